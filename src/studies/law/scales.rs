//! Physical units of a friction law: the scales that turn the model's numbers into SI.
//!
//! The model's units (docs/model.md): length `l0`, time `t0 = M / eta`, velocity `l0 / t0`,
//! temperature `T_ref` (the `kB T_ref` of `junctions.temperature = 1`), force
//! `kB T_ref / l0`. So
//!
//! ```text
//! slip rate [m/s] = V l0 / t0,    temperature [K] = T T_ref,
//! friction [N]    = F f0,  f0 = the force unit (given, or kB T_ref / l0),
//! mu              = F f0 / L,  L = the normal load [N].
//! ```

use serde::Serialize;

/// Boltzmann's constant in J/K (exact in the SI since 2019).
pub const BOLTZMANN: f64 = 1.380_649e-23;

/// The scales as given (`None`: not given).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScaleArgs {
    /// `--l0`: the length unit in metres.
    pub l0: Option<f64>,
    /// `--t0`: the time unit `M / eta` in seconds.
    pub t0: Option<f64>,
    /// `--t-ref`: the reference temperature in kelvin.
    pub t_ref: Option<f64>,
    /// `--normal-load`: the normal load in newtons.
    pub normal_load: Option<f64>,
    /// `--force-unit`: the force unit in newtons (default `kB T_ref / l0`).
    pub force_unit: Option<f64>,
}

/// The scales in force.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Scales {
    /// Length unit, m.
    pub l0: f64,
    /// Time unit `M / eta`, s.
    pub t0: f64,
    /// Reference temperature, K.
    pub t_ref: f64,
    /// Normal load, N.
    pub normal_load: f64,
    /// Force unit, N.
    pub force_unit: f64,
    /// Whether the force unit is `kB T_ref / l0` (not given).
    pub force_unit_derived: bool,
}

/// A scale missing or out of range: one line naming the option.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ScaleError {
    #[error("{option}: missing; {why} (give {example})")]
    Missing { option: &'static str, why: &'static str, example: &'static str },
    #[error("{option} {}: must be a number from 1e-150 to 1e150 ({unit})", crate::scene::error::compact(value))]
    OutOfRange { option: &'static str, value: f64, unit: &'static str },
    /// A unit made of the scales (the force unit `kB T_ref / l0`, the velocity unit `l0 /
    /// t0`, the friction coefficient's `force unit / normal load`) outside the same window.
    #[error("{options}: make {what} = {value:e}, outside 1e-150 to 1e150 (every law value would be scaled by it)")]
    Derived { options: &'static str, what: &'static str, value: f64 },
}

/// Widest factor a scale, or a unit made of them, may be: within `[1/SCALE_MAX, SCALE_MAX]`
/// the model's values, scaled, stay finite and normal numbers.
const SCALE_MAX: f64 = 1e150;

impl ScaleArgs {
    /// The scales, each checked: the first missing or bad one is the error.
    pub fn resolve(&self) -> Result<Scales, ScaleError> {
        let need = |v: Option<f64>, option, why, example, unit| match v {
            None => Err(ScaleError::Missing { option, why, example }),
            Some(value) => in_range(value, option, unit),
        };
        let l0 = need(
            self.l0,
            "--l0",
            "slip rates in m/s are V * l0 / t0",
            "the length unit in metres, e.g. --l0 1e-9",
            "metres",
        )?;
        let t0 = need(
            self.t0,
            "--t0",
            "slip rates in m/s are V * l0 / t0",
            "the time unit M/eta in seconds, e.g. --t0 1e-6",
            "seconds",
        )?;
        let t_ref = need(
            self.t_ref,
            "--t-ref",
            "temperatures in kelvin are T * T_ref",
            "the reference temperature in kelvin, e.g. --t-ref 300",
            "kelvin",
        )?;
        let normal_load = need(
            self.normal_load,
            "--normal-load",
            "the friction coefficient is mu = friction / normal load",
            "the normal load in newtons, e.g. --normal-load 1e-6",
            "newtons",
        )?;
        let (force_unit, derived) = match self.force_unit {
            Some(f) => (in_range(f, "--force-unit", "newtons")?, false),
            None => (derived_unit(BOLTZMANN * t_ref / l0, "--t-ref and --l0", "the force unit kB T_ref / l0")?, true),
        };
        derived_unit(l0 / t0, "--l0 and --t0", "the velocity unit l0 / t0")?;
        let options = if derived { "--t-ref, --l0 and --normal-load" } else { "--force-unit and --normal-load" };
        derived_unit(force_unit / normal_load, options, "the friction coefficient's unit (force unit / normal load)")?;
        Ok(Scales { l0, t0, t_ref, normal_load, force_unit, force_unit_derived: derived })
    }
}

fn within(value: f64) -> bool {
    (1.0 / SCALE_MAX..=SCALE_MAX).contains(&value)
}

/// `value` if within the window ([`SCALE_MAX`]), else the option named.
fn in_range(value: f64, option: &'static str, unit: &'static str) -> Result<f64, ScaleError> {
    if within(value) { Ok(value) } else { Err(ScaleError::OutOfRange { option, value, unit }) }
}

fn derived_unit(value: f64, options: &'static str, what: &'static str) -> Result<f64, ScaleError> {
    if within(value) { Ok(value) } else { Err(ScaleError::Derived { options, what, value }) }
}

impl Scales {
    /// Slip rate in m/s of the model's velocity `v`.
    pub fn slip_rate(&self, v: f64) -> f64 {
        v * self.l0 / self.t0
    }
    /// Temperature in kelvin of the model's temperature `t`.
    pub fn kelvin(&self, t: f64) -> f64 {
        t * self.t_ref
    }
    /// The velocity unit `l0 / t0` in m/s.
    pub fn velocity_unit(&self) -> f64 {
        self.l0 / self.t0
    }
    /// A force of the model in newtons.
    pub fn newtons(&self, f: f64) -> f64 {
        f * self.force_unit
    }
    /// The friction coefficient of a total friction `f` of the model.
    pub fn mu(&self, f: f64) -> f64 {
        self.newtons(f) / self.normal_load
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full() -> ScaleArgs {
        ScaleArgs { l0: Some(1e-9), t0: Some(1e-6), t_ref: Some(300.0), normal_load: Some(1e-9), force_unit: None }
    }

    #[test]
    fn the_first_missing_scale_is_named() {
        let mut a = full();
        a.t_ref = None;
        a.normal_load = None;
        let e = a.resolve().unwrap_err().to_string();
        assert!(e.starts_with("--t-ref: missing;") && !e.contains('\n'), "{e}");
        let mut a = full();
        a.l0 = Some(-1.0);
        assert!(a.resolve().unwrap_err().to_string().starts_with("--l0 -1: must be"));
        let mut a = full();
        a.force_unit = Some(f64::NAN);
        assert!(a.resolve().unwrap_err().to_string().starts_with("--force-unit NaN"));
        // A scale beyond the window, and units made of scales within it that are not.
        let mut a = full();
        a.t_ref = Some(1e308);
        assert_eq!(
            a.resolve().unwrap_err().to_string(),
            "--t-ref 1e308: must be a number from 1e-150 to 1e150 (kelvin)"
        );
        let mut a = full();
        (a.l0, a.t0) = (Some(1e100), Some(1e-100));
        assert!(
            a.resolve().unwrap_err().to_string().starts_with("--l0 and --t0: make the velocity unit l0 / t0 = 1e200")
        );
        let mut a = full();
        (a.t_ref, a.normal_load) = (Some(1e149), Some(1e-20));
        let e = a.resolve().unwrap_err().to_string();
        assert!(e.starts_with("--t-ref, --l0 and --normal-load: make the friction coefficient's unit"), "{e}");
        let mut a = full();
        (a.force_unit, a.normal_load) = (Some(1e100), Some(1e-100));
        assert!(a.resolve().unwrap_err().to_string().starts_with("--force-unit and --normal-load: make"));
        let mut a = full();
        (a.t_ref, a.l0) = (Some(1e-140), Some(1e100));
        assert!(a.resolve().unwrap_err().to_string().starts_with("--t-ref and --l0: make the force unit"));
    }

    #[test]
    fn conversions() {
        let s = full().resolve().unwrap();
        assert!(s.force_unit_derived);
        assert_eq!(s.force_unit, BOLTZMANN * 300.0 / 1e-9);
        assert_eq!(s.slip_rate(2.0), 2.0 * 1e-9 / 1e-6);
        assert_eq!(s.kelvin(0.5), 150.0);
        assert_eq!(s.mu(1.0), s.force_unit / 1e-9);
    }
}
