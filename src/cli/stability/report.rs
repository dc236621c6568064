//! The text of the fixed-step stability analysis ([`crate::engine::fixed::stability`]):
//! the table `stickslip stability` prints, the block of `stickslip validate`, the warning a
//! fixed-step run prints before it starts, and the number format they share.

use crate::engine::fixed::Integrator;
use crate::engine::fixed::stability::{Analysis, PlateLimit, Verdict, analyse};
use crate::scene::{EngineKind, FlipRule, Scene};

/// The scene-file name of an integrator.
pub fn integrator_name(i: Integrator) -> &'static str {
    match i {
        Integrator::SemiImplicitEuler => "semi-implicit-euler",
        Integrator::ExplicitEuler => "explicit-euler",
        Integrator::VelocityVerlet => "velocity-verlet",
        Integrator::Overdamped => "overdamped-euler",
        Integrator::Kinematic => "kinematic",
    }
}

fn rule_name(r: FlipRule) -> &'static str {
    match r {
        FlipRule::Linear => "linear",
        FlipRule::Exponential => "exponential",
        FlipRule::AsPrinted => "as-printed",
    }
}

/// A number in at most 6 significant digits (`inf` for an unbounded limit).
pub fn num(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if x.is_nan() {
        // Parameters at the edge of the floating-point range (e.g. a subnormal mass) can
        // leave a limit undefined; say so rather than print a number.
        return "undefined".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let s = format!("{:.*}", (5 - a.log10().floor() as i32).max(0) as usize, x);
        if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
    } else {
        let s = format!("{x:.5e}");
        let (m, e) = s.split_once('e').expect("exponent form");
        let m = if m.contains('.') { m.trim_end_matches('0').trim_end_matches('.') } else { m };
        format!("{m}e{e}")
    }
}

/// What "all attached" means for the scene's force law.
fn stiffest(a: &Analysis) -> String {
    format!("K + kappa N = {} with all {} junctions attached ({})", num(a.k_all), a.n, a.stiffness_note)
}

/// The verdict of one row in words.
pub fn explain(a: &Analysis, r: &PlateLimit) -> String {
    if r.integrator == Integrator::Kinematic {
        return "no plate equation (plate.kinematic: X = V t): no limit".into();
    }
    let neutral = if a.eta == 0.0 && r.integrator != Integrator::ExplicitEuler {
        " (undamped: oscillations keep their amplitude, as in the exact solution)"
    } else {
        ""
    };
    match r.verdict {
        Verdict::Stable => format!("stable for every attached count{neutral}"),
        Verdict::Unstable => {
            if r.dt_stable == 0.0 && r.dt_unstable == 0.0 {
                "unstable at every dt (explicit Euler amplifies an undamped oscillation each step)".into()
            } else {
                "unstable for every attached count: oscillations grow until the run fails".into()
            }
        }
        Verdict::AtLimit => {
            "at the limit: |eig| = 1 with the most favourable attached count (an oscillation that never \
             decays), > 1 with the others"
                .into()
        }
        Verdict::Conditional => {
            let which = match (a.dt < r.dt_none, a.dt < r.dt_all) {
                (true, false) => "few",
                (false, true) => "many",
                _ => "some but not too many",
            };
            format!("conditional: stable only while {which} junctions are attached")
        }
    }
}

/// The table printed by `stickslip stability`.
pub fn table(a: &Analysis, scene_name: &str) -> String {
    let mut out = String::new();
    let push = |out: &mut String, s: String| {
        out.push_str(&s);
        out.push('\n');
    };
    push(&mut out, format!("# stability of the fixed-step scheme: scene {scene_name}, fixed.dt = {}", num(a.dt)));
    if a.kinematic() {
        push(
            &mut out,
            "# plate.kinematic = true: the plate follows its drive (X = V t), there is no plate equation and so \
             no plate stability limit"
                .into(),
        );
    } else {
        push(
            &mut out,
            format!(
                "# plate linearised as M Xdd + eta Xd + k X = 0 with M = {}, eta = {}, k from K = {} (no junction attached) to {}",
                num(a.mass),
                num(a.eta),
                num(a.k_none),
                stiffest(a)
            ),
        );
    }
    push(
        &mut out,
        "# dt limit: stable below it whatever the attached count; unstable above: unstable beyond it whatever \
         the attached count; |eig| none / all: spectral radius of one step at the scene's dt with no / all \
         junctions attached"
            .into(),
    );
    let header = ["integrator", "dt limit", "unstable above", "scene dt", "|eig| none", "|eig| all", "verdict"];
    let rows: Vec<[String; 7]> = a
        .plate
        .iter()
        .map(|r| {
            [
                format!("{}{}", integrator_name(r.integrator), if r.selected { " *" } else { "" }),
                num(r.dt_stable),
                num(r.dt_unstable),
                num(a.dt),
                num(r.radius_none),
                num(r.radius_all),
                explain(a, r),
            ]
        })
        .collect();
    let mut widths = header.map(str::len);
    for row in &rows {
        for (w, c) in widths.iter_mut().zip(row.iter()) {
            *w = (*w).max(c.len());
        }
    }
    let line = |cells: &[&str]| -> String {
        let mut s = String::new();
        for (i, c) in cells.iter().enumerate() {
            if i + 1 == cells.len() {
                s.push_str(c);
            } else {
                s.push_str(&format!("{c:<w$}  ", w = widths[i]));
            }
        }
        s
    };
    push(&mut out, line(&header));
    for row in &rows {
        push(&mut out, line(&row.iter().map(String::as_str).collect::<Vec<_>>()));
    }
    push(
        &mut out,
        "(* = the integrator this scene uses; plate.mass = 0 always takes the overdamped Euler step)".into(),
    );
    push(&mut out, relaxation_line(a));
    push(&mut out, flips_line(a));
    out
}

/// The relaxation step in one line.
pub fn relaxation_line(a: &Analysis) -> String {
    let r = &a.relaxation;
    let verdict = if !r.stable {
        "UNSTABLE: detached extensions grow as |1 - lambda dt|^n"
    } else if !r.monotone {
        "stable but not monotone: detached extensions change sign every step"
    } else {
        "stable and monotone"
    };
    format!(
        "relaxation x *= 1 - lambda dt: lambda dt = {} (stable up to 2, monotone up to 1): {verdict}",
        num(r.lambda_dt)
    )
}

/// The flip probabilities in one line.
pub fn flips_line(a: &Analysis) -> String {
    let f = &a.flips;
    let mut s = format!("flips ({} rule): k0 dt = {}, kon0 dt = {}", rule_name(f.rule), num(f.k0_dt), num(f.kon0_dt));
    s.push_str(match f.rule {
        FlipRule::Linear if f.saturated() => ": SATURATED, k dt >= 1 flips surely (rates above 1/dt are cut to 1/dt)",
        FlipRule::Linear => ": below saturation (k dt < 1)",
        FlipRule::AsPrinted if f.saturated() => ": k dt >= 1 NEVER flips under the as-printed rule",
        FlipRule::AsPrinted => ": the as-printed rule flips with probability 1 - k dt",
        FlipRule::Exponential => ": the exponential rule never saturates (probability 1 - exp(-k dt))",
    });
    if let Some(f_sat) = f.weak_saturation_tension {
        s.push_str(&format!("; weak bonds reach k_off dt = 1 at tension {}", num(f_sat)));
    }
    s
}

/// The problems worth a warning before a fixed-step run, in words (empty if none).
pub fn issues(a: &Analysis) -> Vec<String> {
    let mut issues = Vec::new();
    let r = a.selected();
    if r.verdict != Verdict::Stable {
        let limit = if r.dt_unstable == 0.0 {
            "no dt is stable for an undamped plate".to_string()
        } else {
            format!(
                "stable for every attached count only below dt = {} (K + kappa N = {}), unstable for all above {}",
                num(r.dt_stable),
                num(a.k_all),
                num(r.dt_unstable)
            )
        };
        issues.push(format!(
            "fixed.dt = {} is {} for the {} plate step: {limit}; the plate oscillation may grow until the run fails",
            num(a.dt),
            match r.verdict {
                Verdict::Unstable => "beyond the stability limit",
                Verdict::AtLimit => "at the stability limit",
                _ => "beyond the stability limit with junctions attached",
            },
            integrator_name(r.integrator),
        ));
    }
    if !a.relaxation.monotone {
        issues.push(format!(
            "junctions.lambda * fixed.dt = {} > 1: detached extensions change sign every step",
            num(a.relaxation.lambda_dt)
        ));
    }
    if a.flips.saturated() {
        issues.push(format!(
            "k0 dt = {}, kon0 dt = {}: a rate with k dt >= 1 {} under the {} flip rule",
            num(a.flips.k0_dt),
            num(a.flips.kon0_dt),
            if a.flips.rule == FlipRule::AsPrinted { "never flips" } else { "flips surely" },
            rule_name(a.flips.rule)
        ));
    }
    issues
}

/// The short block `stickslip validate` prints (comment lines).
pub fn validate_block(a: &Analysis, engine: EngineKind) -> Vec<String> {
    let mut lines = vec![format!(
        "# fixed-step stability{} (fixed.dt = {}; `stickslip stability` shows the table):",
        if engine == EngineKind::Fixed { "" } else { " (used only with run.engine = \"fixed\")" },
        num(a.dt)
    )];
    for r in &a.plate {
        lines.push(format!(
            "#   {}{}: dt limit {} (unstable above {}): {}",
            integrator_name(r.integrator),
            if r.selected { " (this scene)" } else { "" },
            num(r.dt_stable),
            num(r.dt_unstable),
            r.verdict.as_str()
        ));
    }
    lines.push(format!("#   {}", relaxation_line(a)));
    lines.push(format!("#   {}", flips_line(a)));
    lines
}

/// The one warning line a fixed-step run of `scene` prints before it starts, if any.
pub fn warning(scene: &Scene) -> Option<String> {
    if scene.run.engine != EngineKind::Fixed {
        return None;
    }
    let issues = issues(&analyse(scene));
    (!issues.is_empty()).then(|| format!("warning: {} (see `stickslip stability`)", issues.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes as testkit;

    /// A kinematic plate: the table says there is no plate limit, and no warning is about
    /// the plate step.
    #[test]
    fn kinematic_plate_has_no_limit() {
        let s = testkit::fig1_with(&["plate.kinematic=true", "run.engine=fixed", "fixed.dt=5"]);
        let a = analyse(&s);
        let table = table(&a, "k");
        assert!(table.contains("no plate stability limit") && table.contains("kinematic *"), "{table}");
        assert!(issues(&a).iter().all(|i| !i.contains("plate step")), "{:?}", issues(&a));
        assert!(warning(&testkit::fig1_with(&["plate.kinematic=true", "run.engine=fixed"])).is_none());
    }

    /// The letter's Fig. 1 at `dt = 1` is warned about; at `dt = 0.5`, or on the exact
    /// engine, it is not.
    #[test]
    fn fig1_warnings() {
        assert!(warning(&testkit::fig1()).is_some());
        assert!(warning(&testkit::fig1_with(&["fixed.dt=0.5"])).is_none());
        assert!(warning(&testkit::fig1_with(&["run.engine=exact"])).is_none());
    }

    #[test]
    fn numbers_print_short() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(0.9399209), "0.939921");
        assert_eq!(num(1.2909944487), "1.29099");
        assert_eq!(num(2.7e-14), "2.7e-14");
        assert_eq!(num(f64::INFINITY), "inf");
        assert_eq!(num(150.0), "150");
        assert_eq!(num(1e9), "1e9");
    }
}
