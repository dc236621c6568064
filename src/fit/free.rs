//! The free parameters of a fit: `--free FIELD[=LOW:HIGH][:lin|:log]`, each a scene field
//! holding a number, with its bounds and scale.
//!
//! The optimiser and the profiles work in unit coordinates `y` in `[0, 1]` per parameter:
//! `y = (u - u_low) / (u_high - u_low)` with `u = ln(value)` on a log scale (the default: the
//! scene's numeric fields are rates, stiffnesses, masses, lengths, velocities, all > 0) and
//! `u = value` on a linear one (`:lin`). Default bounds: a decade either side of the scene's
//! value (`value / 10 .. value * 10`); any bound must be a value the field allows (checked by
//! validating the scene with it, at every data point's conditions).

use super::data::{DataSet, check_field};
use crate::scene::Scene;
use crate::scene::error::printable;

/// The factor between the scene's value and each default bound.
pub const DEFAULT_DECADE: f64 = 10.0;

/// One free parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeParam {
    /// The scene field, `section.key`.
    pub field: String,
    /// Bounds, in the field's units.
    pub low: f64,
    pub high: f64,
    /// Log scale (else linear).
    pub log: bool,
    /// The scene's value, where the fit starts (inside the bounds).
    pub start: f64,
}

impl FreeParam {
    fn u(&self, v: f64) -> f64 {
        if self.log { v.ln() } else { v }
    }

    /// The field's value at unit coordinate `y` (clamped to `[0, 1]`); the bounds exactly at
    /// 0 and 1.
    pub fn value(&self, y: f64) -> f64 {
        let y = y.clamp(0.0, 1.0);
        if y == 0.0 {
            return self.low;
        }
        if y == 1.0 {
            return self.high;
        }
        let (a, b) = (self.u(self.low), self.u(self.high));
        let u = a + y * (b - a);
        let v = if self.log { u.exp() } else { u };
        v.clamp(self.low, self.high)
    }

    /// The unit coordinate of `v`.
    pub fn unit(&self, v: f64) -> f64 {
        let (a, b) = (self.u(self.low), self.u(self.high));
        ((self.u(v) - a) / (b - a)).clamp(0.0, 1.0)
    }

    /// `FIELD=LOW:HIGH:scale` as the journal records it (shortest round-trip numbers).
    pub fn describe(&self) -> String {
        format!("{}={:e}:{:e}:{}", self.field, self.low, self.high, if self.log { "log" } else { "lin" })
    }
}

/// `field=value` for `--set`, in a form TOML reads back as the same double.
pub fn assignment(field: &str, value: f64) -> String {
    format!("{field}={value:e}")
}

/// Parses the `--free` arguments (each a comma-separated list) and checks them against
/// `base` and every point of `data`. Errors are one line naming the field.
pub fn parse_free(args: &[String], base: &Scene, data: &DataSet) -> Result<Vec<FreeParam>, String> {
    let table = toml::Table::try_from(base.to_file()).expect("a scene always serializes");
    let mut out: Vec<FreeParam> = Vec::new();
    for item in args.iter().flat_map(|a| a.split(',')).map(str::trim) {
        let fail = |why: String| format!("--free {}: {why}", printable(item));
        let (field, rest) = match item.split_once('=') {
            Some((f, r)) => (f.trim(), Some(r.trim())),
            None => (item, None),
        };
        check_field(base, field).map_err(|why| fail(format!("{} {why}", printable(field))))?;
        let (section, key) = field.split_once('.').expect("checked");
        let Some(value) = table[section][key].as_float() else {
            return Err(fail(format!(
                "{field} is not a real-valued field (a fit varies numbers such as junctions.k0)"
            )));
        };
        if field == "run.seed" || field == "run.t_end" || field == "run.t_warmup" {
            return Err(fail(format!("{field} decides how the model is run, not the model")));
        }
        if data.columns.iter().any(|c| c == field) {
            return Err(fail(format!(
                "{field} is a column of the data (a measured condition), it cannot also be free"
            )));
        }
        if out.iter().any(|p| p.field == field) {
            return Err(fail(format!("{field} is given twice")));
        }
        let mut parts: Vec<&str> = rest.map(|r| r.split(':').map(str::trim).collect()).unwrap_or_default();
        let mut scale = None;
        if let Some(&last) = parts.last() {
            if last == "lin" || last == "log" {
                scale = Some(last == "log");
                parts.pop();
            }
        }
        let number = |s: &str, what: &str| -> Result<f64, String> {
            let v: f64 = s.parse().map_err(|_| fail(format!("{what} '{}' is not a number", printable(s))))?;
            if v.is_finite() { Ok(v) } else { Err(fail(format!("{what} {v} is not finite"))) }
        };
        let (low, high) = match parts.as_slice() {
            [] => {
                if value <= 0.0 {
                    return Err(fail(format!(
                        "{field} = {value} in the scene: give bounds as {field}=LOW:HIGH (the default bounds are the value / {DEFAULT_DECADE} and x {DEFAULT_DECADE})"
                    )));
                }
                (value / DEFAULT_DECADE, value * DEFAULT_DECADE)
            }
            [lo, hi] => (number(lo, "lower bound")?, number(hi, "upper bound")?),
            _ => return Err(fail("expected FIELD, FIELD=LOW:HIGH or FIELD=LOW:HIGH:lin (or :log)".into())),
        };
        if low >= high {
            return Err(fail(format!("the lower bound {low} must be less than the upper bound {high}")));
        }
        let log = scale.unwrap_or(low > 0.0);
        if log && low <= 0.0 {
            return Err(fail(format!("a log scale needs bounds > 0 (lower bound {low}); add :lin for a linear scale")));
        }
        for bound in [low, high] {
            let a = assignment(field, bound);
            base.with_overrides(std::slice::from_ref(&a))
                .map_err(|e| fail(format!("bound outside the allowed range: {e}")))?;
            for i in 0..data.len() {
                let mut o = data.overrides(i);
                o.push(a.clone());
                base.with_overrides(&o).map_err(|e| {
                    fail(format!(
                        "bound outside the allowed range at the conditions of data line {}: {e}",
                        data.points[i].line
                    ))
                })?;
            }
        }
        out.push(FreeParam { field: field.to_string(), low, high, log, start: value.clamp(low, high) });
    }
    if out.is_empty() {
        return Err("--free: no free parameter given (e.g. --free junctions.k0,junctions.kon0)".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data() -> DataSet {
        DataSet::parse("plate.v,friction\n0.5,1\n1,2\n", "d", &crate::test_scenes::fig1(), 1.0).unwrap()
    }

    fn free(a: &str) -> Result<Vec<FreeParam>, String> {
        parse_free(&[a.to_string()], &crate::test_scenes::fig1(), &data())
    }

    #[test]
    fn bounds_scales_and_unit_coordinates() {
        let p = free("junctions.k0,plate.k=100:200:lin,junctions.kon0=0.01:1").unwrap();
        assert_eq!((p[0].low, p[0].high, p[0].log), (0.1 / 10.0, 0.1 * 10.0, true));
        assert_eq!((p[1].low, p[1].high, p[1].log, p[1].start), (100.0, 200.0, false, 150.0));
        assert!(p[2].log);
        assert!((p[0].value(0.5) - 0.1).abs() < 1e-15);
        assert_eq!((p[1].value(0.0), p[1].value(1.0), p[1].value(0.25)), (100.0, 200.0, 125.0));
        assert!((p[2].unit(0.1) - 0.5).abs() < 1e-12);
        assert_eq!(assignment("plate.k", 1e20), "plate.k=1e20");
    }

    #[test]
    fn bad_free_parameters_name_the_field() {
        for (a, mention) in [
            ("junctions.k0=-1:1:lin", "bound outside the allowed range: junctions.k0 = -1"),
            ("junctions.nope", "junctions.nope is not a scene field"),
            ("junctions.n", "not a real-valued field"),
            ("plate.v", "column of the data"),
            ("junctions.k0,junctions.k0", "given twice"),
            ("junctions.k0=1:0.5", "less than"),
            ("junctions.k0=0:1:log", "log scale needs bounds > 0"),
            ("junctions.k0=a:1", "not a number"),
            ("run.seed", "not a real-valued field"),
        ] {
            let e = free(a).unwrap_err();
            assert!(e.contains(mention) && !e.contains('\n') && e.starts_with("--free"), "{a}: {e}");
        }
    }
}
