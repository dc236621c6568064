//! `stickslip validate`: checks a scene and prints every resolved parameter.

use std::fmt::Write as _;
use std::process::ExitCode;

use super::args::SceneArgs;
use super::args::load_scene;
use super::stdout::emit;

pub(crate) fn validate(args: &SceneArgs) -> ExitCode {
    let scene = match load_scene(args, &[]) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let toml = toml::to_string(&scene.to_file()).expect("a scene always serializes");
    let mut text = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(text, "# scene {} is valid; resolved parameters:", crate::scene::error::printable(&scene.name));
    text.push_str(&short_numbers(&toml));
    let j = &scene.junctions;
    let p = &scene.plate;
    let short = crate::scene::error::compact_numbers;
    let _ = writeln!(text, "{}", short(&format!("# derived: V0 = alpha/tau0 = {}, beta dx = {}", j.v0(), j.beta_dx())));
    let _ = writeln!(text, "{}", short(&in_force_line(&scene)));
    if p.mass > 0.0 {
        let k_tot = p.k;
        let omega = (k_tot / p.mass).sqrt();
        let zeta = if k_tot > 0.0 { p.eta / (2.0 * (k_tot * p.mass).sqrt()) } else { f64::INFINITY };
        let line = format!("# plate (no junctions attached): omega = sqrt(K/M) = {omega}, damping ratio = {zeta}");
        let _ = writeln!(text, "{}", short(&line));
    }
    for line in super::stability::validate_block(&crate::engine::fixed::stability::analyse(&scene), scene.run.engine) {
        let _ = writeln!(text, "{line}");
    }
    if let Some(w) = crate::engine::fixed::period_warning(&scene) {
        let _ = writeln!(text, "# {w}");
    }
    let out = std::path::Path::new("out").join(&scene.name);
    for line in crate::estimate::Estimate::of(&scene, false).report(&out) {
        let _ = writeln!(text, "{line}");
    }
    emit(&text)
}

/// The scene file `toml` with each long number shown in exponent form
/// ([`compact`](crate::scene::error::compact): `k_slope = 1e300`, not 301 digits). Only a
/// whole value (`key = number`) is rewritten, so a string is never touched; a long number is
/// always a float (an integer field has at most 20 digits), and the exponent form is a TOML
/// float of the same value, so the file reads back to the same scene.
fn short_numbers(toml: &str) -> String {
    let mut out = String::with_capacity(toml.len());
    for line in toml.lines() {
        match line.split_once(" = ") {
            Some((key, value)) if value.parse::<f64>().is_ok() => {
                let _ = writeln!(out, "{key} = {}", crate::scene::error::compact(value));
            }
            _ => {
                let _ = writeln!(out, "{line}");
            }
        }
    }
    out
}

/// The temperature-dependent parameters in force at the scene's temperature (the file above
/// gives them at `T = 1`; docs/model.md, "Temperature").
fn in_force_line(scene: &crate::scene::Scene) -> String {
    let f = scene.in_force();
    let how = if scene.reference.is_some() { "" } else { " (no temperature dependence: the values above)" };
    format!(
        "# in force at junctions.temperature = {}{how}: k0 = {}, kon0 = {}, kappa = {}, K = {}, eta = {}",
        scene.junctions.temperature, f.k0, f.kon0, f.kappa, f.k, f.eta
    )
}
