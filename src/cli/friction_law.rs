//! `stickslip friction-law`: a friction law for continuum codes from a
//! velocity-temperature map (library: [`crate::studies::law`]).
//!
//! Either runs the map (`SCENE --param plate.v .. --param junctions.temperature ..`, a
//! sweep with its journal and files in the output directory) or reads a finished sweep's
//! directory (`--from DIR`). The physical scales are checked before anything runs or is
//! written: a missing one is one line naming its option, exit 2.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::args::{EXIT_BAD_INPUT, EXIT_RUN_FAILED, SceneArgs, fail};
use super::sweep::{AxisArgs, Finished, SweepArgs, run_study};
use crate::studies::format::fixed;
use crate::studies::law::{
    self, DEFAULT_DEGREE, FrictionLaw, LawInput, PointRuns, ScaleArgs, Scales, T_FIELD, V_FIELD, from_outcome,
    read_sweep_dir, vt_axes,
};

#[derive(clap::Args, Debug)]
pub struct FrictionLawArgs {
    /// Scene file (TOML) of the map to run (not with --from).
    #[arg(required_unless_present = "from", conflicts_with = "from")]
    pub scene: Option<PathBuf>,
    /// Override a scene field, e.g. `--set run.t_end=1000` (repeatable; checked like the file).
    #[arg(long = "set", value_name = "SECTION.KEY=VALUE", conflicts_with = "from")]
    pub set: Vec<String>,
    #[command(flatten)]
    pub axes: AxisArgs,
    /// Runs per grid point, each with its own seed (two or more give intervals and a weighted fit).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000), conflicts_with = "from")]
    pub replicas: u32,
    /// Worker threads for the map's runs (default: all cores). The results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096), conflicts_with = "from")]
    pub threads: Option<u32>,
    /// Read a finished sweep over plate.v and junctions.temperature from its output directory instead of running one.
    #[arg(long, value_name = "SWEEPDIR")]
    pub from: Option<PathBuf>,
    /// Output directory (default: the --from directory, or out/<scene file stem>-friction-law/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Length unit l0 in metres (slip rate in m/s = V l0 / t0).
    #[arg(long, value_name = "METRES", allow_hyphen_values = true)]
    pub l0: Option<f64>,
    /// Time unit M/eta in seconds.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub t0: Option<f64>,
    /// Reference temperature in kelvin (temperature in K = T T_ref).
    #[arg(long, value_name = "KELVIN", allow_hyphen_values = true)]
    pub t_ref: Option<f64>,
    /// Normal load in newtons (mu = friction / normal load).
    #[arg(long, value_name = "NEWTONS", allow_hyphen_values = true)]
    pub normal_load: Option<f64>,
    /// Force unit in newtons (default kB T_ref / l0).
    #[arg(long, value_name = "NEWTONS", allow_hyphen_values = true)]
    pub force_unit: Option<f64>,
    /// Total degree of the fitted polynomial in ln(V/V0) and T_ref/T - 1.
    #[arg(long, default_value_t = DEFAULT_DEGREE, value_parser = clap::value_parser!(u32).range(1..=2))]
    pub fit_degree: u32,
}

impl FrictionLawArgs {
    fn scales(&self) -> ScaleArgs {
        ScaleArgs {
            l0: self.l0,
            t0: self.t0,
            t_ref: self.t_ref,
            normal_load: self.normal_load,
            force_unit: self.force_unit,
        }
    }
}

/// The grid of a prepared sweep, checked as a law checks it in `scales`
/// ([`law::source::checked_points`]).
fn check_grid(sweep: &crate::studies::sweep::Sweep, scales: &Scales) -> Result<(), String> {
    let params: Vec<&str> = sweep.axes.iter().map(|a| a.param.as_str()).collect();
    let (iv, it) = vt_axes(&params, "--param").map_err(|e| e.to_string())?;
    let points =
        sweep.points.iter().map(|p| PointRuns { v: p.values[iv].x, t: p.values[it].x, runs: Vec::new() }).collect();
    let input = LawInput { scene: sweep.base.name.clone(), replicas: sweep.replicas, points };
    law::source::checked_points(&input, scales).map(|_| ()).map_err(|e| e.to_string())
}

pub(crate) fn friction_law(args: &FrictionLawArgs) -> ExitCode {
    let scales = match args.scales().resolve() {
        Ok(s) => s,
        Err(e) => return fail(EXIT_BAD_INPUT, e),
    };
    let (input, out, _held) = match &args.from {
        Some(dir) => {
            if !args.axes.params.is_empty() || !args.axes.lists.is_empty() {
                return fail(
                    EXIT_BAD_INPUT,
                    "--param: not with --from (the sweep's directory says what was swept; give either a scene with its fields, or --from)",
                );
            }
            let input = match read_sweep_dir(dir) {
                Ok(i) => i,
                Err(e) => return fail(EXIT_BAD_INPUT, e),
            };
            let out = args.out.clone().unwrap_or_else(|| dir.clone());
            let held = match super::out_dir::prepare_out_dir(&out) {
                Ok(h) => h,
                Err(m) => return fail(EXIT_BAD_INPUT, m),
            };
            (input, out, held)
        }
        None => {
            let Some(scene) = args.scene.clone() else {
                return fail(EXIT_BAD_INPUT, "SCENE: give a scene file, or --from SWEEPDIR");
            };
            let sweep_args = SweepArgs {
                scene: SceneArgs { scene, set: args.set.clone() },
                axes: args.axes.clone(),
                replicas: args.replicas,
                log_x: false,
                log_y: false,
                out: args.out.clone(),
                threads: args.threads,
            };
            let default_out =
                |s: &crate::studies::sweep::Sweep| Path::new("out").join(format!("{}-friction-law", s.base.name));
            let Finished { sweep, outcome, out, held } =
                match run_study(&sweep_args, default_out, |s| check_grid(s, &scales)) {
                    Ok(f) => f,
                    Err(code) => return code,
                };
            match from_outcome(&sweep, &outcome) {
                Ok(i) => (i, out, held),
                Err(e) => return fail(EXIT_BAD_INPUT, e),
            }
        }
    };
    let law = match FrictionLaw::new(&input, scales, args.fit_degree) {
        Ok(l) => l,
        Err(e) => return fail(EXIT_BAD_INPUT, e),
    };
    if let Err(e) = law.write(&out) {
        return fail(EXIT_RUN_FAILED, e);
    }
    report(&law, &out);
    ExitCode::SUCCESS
}

/// What the command prints: the table in short, the fit, the files.
fn report(law: &FrictionLaw, out: &Path) {
    let steady = law.steady().count();
    println!(
        "friction law of scene {} over {V_FIELD} x {T_FIELD}: {} points, {steady} steady, {} replica(s) each",
        crate::scene::error::printable(&law.scene),
        law.points.len(),
        law.replicas
    );
    for p in &law.points {
        let mu = match p.mu {
            Some(m) if m.ci95.is_finite() => format!("mu = {} +- {}", fixed(m.mean, 6), fixed(m.ci95, 6)),
            Some(m) => format!("mu = {}", fixed(m.mean, 6)),
            None => format!("no steady mu ({}: left out of abaqus.inp and ansys.mac)", p.regime.as_str()),
        };
        println!(
            "  V = {:<10} T = {:<8} {:.4e} m/s {:>8.2} K  F/N = {}  {mu}",
            format!("{}", p.v),
            format!("{}", p.t),
            p.slip_rate,
            p.kelvin,
            fixed(p.friction_per_junction.mean, 6)
        );
    }
    match &law.fit {
        Ok(f) => {
            let gof = match (f.chi_square, f.p_value) {
                (Some(c), Some(pv)) => format!("chi-square {c:.4} on {} dof (p = {pv:.3})", f.dof),
                (Some(c), None) => format!("chi-square {c:.4} on {} dof", f.dof),
                (None, _) => format!("unweighted, rms residual {:.3e}", f.rms_residual),
            };
            let lowered = if f.degree < f.degree_requested {
                format!(" (degree {} asked; the steady points determine degree {})", f.degree_requested, f.degree)
            } else {
                String::new()
            };
            println!("fit: degree {}{lowered}, {} terms, {gof} (law.json)", f.degree, f.terms.len());
        }
        Err(e) => println!("fit: none ({e}); the tables hold what the map gives"),
    }
    println!(
        "output in {} (law.csv, abaqus.inp, ansys.mac, law.json)",
        crate::scene::error::printable(&out.display().to_string())
    );
}
