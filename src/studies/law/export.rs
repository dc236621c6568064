//! The law as tables for continuum codes, steady points only, in SI units (slip rate in
//! m/s, temperature in K):
//!
//! - Abaqus (`abaqus.inp`): a `*FRICTION` block for a `*SURFACE INTERACTION`, one data
//!   line per point, `friction coefficient, slip rate, contact pressure, temperature`
//!   (the isotropic data line's first four fields; temperature is a column of its own, so
//!   no `DEPENDENCIES` parameter, which counts field variables besides temperature).
//!   Contact pressure is `0.0` on every line: the law does not depend on it. Lines are
//!   ordered with slip rate varying fastest, then temperature, both ascending.
//! - Ansys (`ansys.mac`): `TB,FRIC,1,,,ISO`, then per temperature `TBFIELD,TEMP,T` and per
//!   slip rate `TBFIELD,SLRV,V` followed by `TBDATA,1,mu`, fields ascending. The material
//!   number `1` is the contact pair's (change it to yours).
//!
//! Points that are not steady are left out ([`super::tables::LEFT_OUT`]) and listed in
//! the comments, which escape control characters ([`printable`]). Numbers are written in
//! the shortest form that reads back to the same double, the same text as `law.csv`.

use std::fmt::Write as _;

use super::FrictionLaw;
use super::tables::LEFT_OUT;
use crate::output::csv::push_f64;
use crate::scene::error::printable;

fn num(x: f64) -> String {
    let mut s = String::new();
    push_f64(&mut s, x);
    s
}

/// `line` cut at spaces into pieces of at most `width` characters (a longer word stays
/// whole), the pieces after the first indented: input lines of the codes are limited in
/// length (Abaqus: 256 characters).
fn wrap(line: &str, width: usize) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    for word in line.split(' ') {
        if !cur.is_empty() && cur.len() + 1 + word.len() > width {
            out.push(std::mem::take(&mut cur));
            cur.push_str("  ");
        } else if !cur.is_empty() && !cur.ends_with("  ") {
            cur.push(' ');
        }
        cur.push_str(word);
    }
    out.push(cur);
    out
}

impl FrictionLaw {
    /// The comment lines both exports start with, each after `mark`. Every line is
    /// escaped ([`printable`]): a control character in the scene's name cannot start a
    /// line that the code would read as input.
    fn preamble(&self, mark: &str, what: &str) -> String {
        let sc = &self.scales;
        let steady = self.steady().count();
        let mut lines = vec![
            format!("stickslip friction-law: {what}"),
            format!(
                "scene {}, {} replica(s) per point; {} of {} (V, T) points steady (every replica smooth)",
                self.scene,
                self.replicas,
                steady,
                self.points.len()
            ),
            format!(
                "slip rate in m/s = V * l0 / t0 (l0 = {} m, t0 = {} s); temperature in K = T * T_ref (T_ref = {} K)",
                num(sc.l0),
                num(sc.t0),
                num(sc.t_ref)
            ),
            format!(
                "mu = friction * force unit / normal load (force unit {} N{}, normal load {} N)",
                num(sc.force_unit),
                if sc.force_unit_derived { " = kB T_ref / l0" } else { "" },
                num(sc.normal_load)
            ),
            LEFT_OUT.to_string(),
        ];
        for p in self.points.iter().filter(|p| !p.steady) {
            lines.push(format!(
                "left out: V = {} ({} m/s), T = {} ({} K): {} ({} of the replicas in stick-slip)",
                num(p.v),
                num(p.slip_rate),
                num(p.t),
                num(p.kelvin),
                p.regime.as_str(),
                num(p.stick_slip_fraction)
            ));
        }
        if steady == 0 {
            lines.push("no steady point: no table is given".to_string());
        }
        lines.iter().flat_map(|l| wrap(&printable(l), 96)).map(|l| format!("{mark} {l}\n")).collect()
    }

    /// The steady points as `(mu, slip rate in m/s, temperature in K)`, in table order.
    fn table_rows(&self) -> Vec<(f64, f64, f64)> {
        self.steady().map(|p| (p.mu.expect("a steady point has a coefficient").mean, p.slip_rate, p.kelvin)).collect()
    }

    /// `abaqus.inp`: the `*FRICTION` block.
    pub fn abaqus_inp(&self) -> String {
        let mut s = self.preamble(
            "**",
            "Abaqus *FRICTION table (friction coefficient, slip rate, contact pressure, temperature); place it under a *SURFACE INTERACTION",
        );
        let rows = self.table_rows();
        if !rows.is_empty() {
            s.push_str("*FRICTION\n");
        }
        for (mu, v, t) in rows {
            let _ = writeln!(s, "{}, {}, 0.0, {}", num(mu), num(v), num(t));
        }
        s
    }

    /// `ansys.mac`: `TB,FRIC` with `TBFIELD` temperature and sliding velocity.
    pub fn ansys_mac(&self) -> String {
        let mut s = self.preamble(
            "!",
            "Ansys TB,FRIC table over TBFIELD TEMP (K) and SLRV (m/s); material 1 is the contact pair's",
        );
        let rows = self.table_rows();
        if !rows.is_empty() {
            s.push_str("TB,FRIC,1,,,ISO\n");
        }
        let mut temperature = None;
        for (mu, v, t) in rows {
            if temperature != Some(t) {
                let _ = writeln!(s, "TBFIELD,TEMP,{}", num(t));
                temperature = Some(t);
            }
            let _ = writeln!(s, "TBFIELD,SLRV,{}\nTBDATA,1,{}", num(v), num(mu));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::super::{LawInput, PointRuns, RunRecord, ScaleArgs};
    use super::*;
    use crate::observe::regime::Regime;

    /// A law of a scene named `scene`: one steady point and one in stick-slip.
    fn law(scene: &str) -> FrictionLaw {
        let scales =
            ScaleArgs { l0: Some(1e-9), t0: Some(1e-6), t_ref: Some(300.0), normal_load: Some(1e-9), force_unit: None };
        let run = |regime| RunRecord { friction_mean: 3.0, friction_per_junction: 0.1, regime };
        let points = vec![
            PointRuns { v: 0.1, t: 1.0, runs: vec![run(Regime::Smooth)] },
            PointRuns { v: 1.0, t: 1.0, runs: vec![run(Regime::StickSlip)] },
        ];
        let input = LawInput { scene: scene.into(), replicas: 1, points };
        FrictionLaw::new(&input, scales.resolve().unwrap(), 1).unwrap()
    }

    #[test]
    fn control_characters_in_the_scene_name_stay_inside_comments() {
        let law = law("nl\nTBDATA,1,9\r*FRICTION\u{b}\u{2028}x");
        for (mark, text) in [("**", law.abaqus_inp()), ("!", law.ansys_mac())] {
            let preamble = law.preamble(mark, "test");
            for line in preamble.split_terminator('\n') {
                assert!(line.starts_with(mark), "{line:?}");
                assert!(!line.chars().any(|c| c.is_control() || matches!(c, '\u{2028}' | '\u{2029}')), "{line:?}");
            }
            assert!(preamble.contains(r"scene nl\nTBDATA,1,9\r*FRICTION\u{b}\u{2028}x,"), "{preamble}");
            // Past the comments: the table's header and its one steady row only.
            let input: Vec<&str> = text.lines().filter(|l| !l.starts_with(mark)).collect();
            assert_eq!(input.len(), if mark == "**" { 2 } else { 4 }, "{input:?}");
        }
    }
}
