//! Temperature as a physical input: the map from a scene's reference parameters (their
//! values at the reference temperature `T = 1` of the units) to the parameters in force at
//! the scene's temperature `T = junctions.temperature` (docs/model.md, "Temperature").
//!
//! ```text
//! k0(T)    = k0    exp(-e_off (1/T - 1))       rupture, thermally activated (Arrhenius)
//! kon0(T)  = kon0  exp(-e_on  (1/T - 1))       formation, thermally activated
//! kappa(T) = kappa (1 + kappa_slope (T - 1))   junction stiffness
//! K(T)     = K     (1 + k_slope (T - 1))       driving spring
//! eta(T)   = eta   (1 + eta_slope (T - 1))     viscous damping
//! ```
//!
//! `e_off` and `e_on` are activation energies in units of `kB T_ref` (`>= 0`), the slopes
//! relative changes per unit of `T` (any sign, as long as the factor stays `> 0`). The
//! weak bonds' force sensitivity `exp(f dx / T)` is not part of the map: it has always read
//! `T` itself. With it, a weak bond's rupture rate is Bell's
//! `k0 e^{e_off} exp(-(e_off - f dx) / T)`.
//!
//! A coefficient of 0 leaves its parameter as it is (the reference value itself, with no
//! factor applied), so a scene whose five coefficients are 0 has exactly its reference
//! values, bit for bit. At `T = 1` every factor is exactly 1 (`1/1 - 1 = 0`, `exp(0) = 1`,
//! `1 + s 0 = 1`) and so every value is again the reference one.
//!
//! Pure (no I/O, no state): validation applies it once per scene, and the engines read only
//! the values in force.

use serde::{Deserialize, Serialize};

use super::error::SceneError;

/// The temperature-dependent parameters: at `T = 1` (the scene file's values, the
/// *reference* values) or at the scene's temperature (the values *in force*).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// Spontaneous rupture rate `k0` (1/time).
    pub k0: f64,
    /// Formation rate `kon0` (1/time).
    pub kon0: f64,
    /// Junction spring constant `kappa` (force/length).
    pub kappa: f64,
    /// Driving spring constant `K` (force/length).
    pub k: f64,
    /// Viscous damping `eta` (force/velocity).
    pub eta: f64,
}

/// The five coefficients of the map: activation energies and relative slopes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coefficients {
    /// `junctions.e_off`: activation energy of rupture (units of `kB T_ref`).
    pub e_off: f64,
    /// `junctions.e_on`: activation energy of formation (units of `kB T_ref`).
    pub e_on: f64,
    /// `junctions.kappa_slope`: relative slope of `kappa` per unit of `T`.
    pub kappa_slope: f64,
    /// `plate.k_slope`: relative slope of `K` per unit of `T`.
    pub k_slope: f64,
    /// `plate.eta_slope`: relative slope of `eta` per unit of `T`.
    pub eta_slope: f64,
}

impl Coefficients {
    /// Every coefficient 0: the map is the identity whatever `T`.
    pub fn is_zero(&self) -> bool {
        [self.e_off, self.e_on, self.kappa_slope, self.k_slope, self.eta_slope].iter().all(|&c| c == 0.0)
    }

    /// Each coefficient finite, and each activation energy `>= 0` (a barrier is never
    /// negative: a negative energy would make a rate *fall* as the temperature rises).
    pub fn check(&self) -> Result<(), SceneError> {
        for (field, e) in [("junctions.e_off", self.e_off), ("junctions.e_on", self.e_on)] {
            if !(e.is_finite() && e >= 0.0) {
                return Err(SceneError::invalid(
                    field,
                    e,
                    "must be a finite number >= 0 (an activation energy in units of kB T_ref: a barrier is never negative)",
                ));
            }
        }
        for (field, s) in [
            ("junctions.kappa_slope", self.kappa_slope),
            ("plate.k_slope", self.k_slope),
            ("plate.eta_slope", self.eta_slope),
        ] {
            if !s.is_finite() {
                return Err(SceneError::invalid(field, s, "must be a finite number"));
            }
        }
        Ok(())
    }
}

/// The Arrhenius factor's exponent `-e (1/T - 1)`.
pub fn arrhenius_exponent(e: f64, t: f64) -> f64 {
    -e * (1.0 / t - 1.0)
}

/// The elastic factor `1 + s (T - 1)`.
pub fn slope_factor(s: f64, t: f64) -> f64 {
    1.0 + s * (t - 1.0)
}

/// `rate exp(-e (1/T - 1))`, or `rate` itself when `e = 0`; refused when it leaves the
/// floating-point range (overflow, or a positive rate underflowing below the smallest
/// normal number).
fn activated(field: &'static str, name: &str, rate: f64, e: f64, t: f64) -> Result<f64, SceneError> {
    if e == 0.0 {
        return Ok(rate);
    }
    let exponent = arrhenius_exponent(e, t);
    let value = rate * exponent.exp();
    let out_of_range = if !value.is_finite() {
        Some("overflows")
    } else if rate > 0.0 && value < f64::MIN_POSITIVE {
        Some("underflows")
    } else {
        None
    };
    match out_of_range {
        None => Ok(value),
        Some(how) => Err(SceneError::invalid(
            field,
            e,
            format!(
                "at junctions.temperature = {t} the {name} in force, {rate} exp(-e (1/T - 1)) = {rate} exp({exponent}), {how} the floating-point range; lower the energy or move the temperature toward 1"
            ),
        )),
    }
}

/// `value (1 + s (T - 1))`, or `value` itself when `s = 0`; refused when the factor is not
/// `> 0` (the constant would be `<= 0` at `T`) or the product is not finite.
fn sloped(field: &'static str, name: &str, value: f64, s: f64, t: f64) -> Result<f64, SceneError> {
    if s == 0.0 {
        return Ok(value);
    }
    let factor = slope_factor(s, t);
    let out = value * factor;
    if !(factor.is_finite() && factor > 0.0) {
        let shown = if factor.is_finite() { format!("{factor}") } else { "not a finite number".to_string() };
        return Err(SceneError::invalid(
            field,
            s,
            format!(
                "makes {name} <= 0 or unbounded at junctions.temperature = {t}: the factor 1 + slope (T - 1) is {shown}, and must be a finite number > 0"
            ),
        ));
    }
    if !out.is_finite() {
        return Err(SceneError::invalid(
            field,
            s,
            format!(
                "makes {name} overflow at junctions.temperature = {t} ({value} times {factor} is not a finite number)"
            ),
        ));
    }
    Ok(out)
}

/// The parameters in force at temperature `t` (`> 0`, checked by the caller), from the
/// reference values and checked coefficients ([`Coefficients::check`]). Errors name the
/// coefficient's field and the temperature.
pub fn in_force(reference: &Reference, c: &Coefficients, t: f64) -> Result<Reference, SceneError> {
    Ok(Reference {
        k0: activated("junctions.e_off", "rupture rate k0", reference.k0, c.e_off, t)?,
        kon0: activated("junctions.e_on", "formation rate kon0", reference.kon0, c.e_on, t)?,
        kappa: sloped("junctions.kappa_slope", "junctions.kappa", reference.kappa, c.kappa_slope, t)?,
        k: sloped("plate.k_slope", "plate.k", reference.k, c.k_slope, t)?,
        eta: sloped("plate.eta_slope", "plate.eta", reference.eta, c.eta_slope, t)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const REF: Reference = Reference { k0: 0.7, kon0: 1.3, kappa: 0.1, k: 15.0, eta: 25.0 };

    fn all(e_off: f64, e_on: f64, s: f64) -> Coefficients {
        Coefficients { e_off, e_on, kappa_slope: s, k_slope: s / 2.0, eta_slope: -s / 4.0 }
    }

    /// Zero coefficients: the reference values, bit for bit, at any temperature.
    #[test]
    fn zero_coefficients_are_the_identity() {
        for t in [1e-3, 0.1, 0.5, 1.0, 2.0, 17.0, 1e6] {
            let out = in_force(&REF, &Coefficients::default(), t).unwrap();
            assert_eq!(out, REF, "T = {t}");
        }
        assert!(Coefficients::default().is_zero());
        assert!(!all(0.0, 0.0, 1e-300).is_zero());
    }

    /// `T = 1`: the reference values exactly, whatever the coefficients.
    #[test]
    fn reference_temperature_gives_the_reference_values() {
        for c in [all(3.0, 5.0, 0.4), all(700.0, 0.5, -0.9), all(1e-9, 1e3, 123.0)] {
            let out = in_force(&REF, &c, 1.0).unwrap();
            assert_eq!(out, REF, "{c:?}");
        }
    }

    /// The formulas, against independently written expressions (Bell's form for the rates:
    /// `k0 e^{e} exp(-e / T)`).
    #[test]
    fn values_follow_the_formulas() {
        let c = all(4.0, 2.5, 0.3);
        for t in [0.25, 0.5, 0.8, 1.5, 2.0, 4.0] {
            let out = in_force(&REF, &c, t).unwrap();
            let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * b.abs();
            assert!(close(out.k0, REF.k0 * (4.0f64).exp() * (-4.0 / t).exp()), "k0 at {t}: {}", out.k0);
            assert!(close(out.kon0, REF.kon0 * (2.5f64).exp() * (-2.5 / t).exp()), "kon0 at {t}");
            assert_eq!(out.kappa, REF.kappa * (1.0 + 0.3 * (t - 1.0)), "kappa at {t}");
            assert_eq!(out.k, REF.k * (1.0 + 0.15 * (t - 1.0)), "K at {t}");
            assert_eq!(out.eta, REF.eta * (1.0 - 0.075 * (t - 1.0)), "eta at {t}");
            // Rates rise with T (a barrier is crossed more easily when hot).
            assert_eq!(out.k0 > REF.k0, t > 1.0);
        }
        // One value by hand: k0 = 0.7 e^{-4 (1/2 - 1)} = 0.7 e^2 at T = 2.
        let out = in_force(&REF, &all(4.0, 0.0, 0.0), 2.0).unwrap();
        assert!((out.k0 - 0.7 * std::f64::consts::E.powi(2)).abs() < 1e-14);
        assert_eq!(out.kon0, REF.kon0);
    }

    /// Bad coefficients: one-line errors naming the field (and the temperature).
    #[test]
    fn bad_coefficients_are_refused() {
        let field = |r: Result<(), SceneError>| match r.unwrap_err() {
            SceneError::Invalid { field, .. } => field,
            e => panic!("{e}"),
        };
        assert_eq!(field(all(-0.1, 0.0, 0.0).check()), "junctions.e_off");
        assert_eq!(field(all(0.0, -1.0, 0.0).check()), "junctions.e_on");
        assert_eq!(field(all(f64::INFINITY, 0.0, 0.0).check()), "junctions.e_off");
        assert_eq!(field(all(0.0, 0.0, f64::NAN).check()), "junctions.kappa_slope");
        assert!(all(0.0, 0.0, -5.0).check().is_ok());

        let err = |c: Coefficients, t: f64| in_force(&REF, &c, t).unwrap_err().to_string();
        // kappa (1 + 2 (0.4 - 1)) = kappa (-0.2) at T = 0.4.
        let e = err(Coefficients { kappa_slope: 2.0, ..Default::default() }, 0.4);
        assert!(e.starts_with("junctions.kappa_slope = 2: makes junctions.kappa <= 0"), "{e}");
        assert!(e.contains("junctions.temperature = 0.4") && e.contains("-0.19999"), "{e}");
        // Exactly 0 is refused too.
        let e = err(Coefficients { k_slope: -1.0, ..Default::default() }, 2.0);
        assert!(e.starts_with("plate.k_slope = -1: makes plate.k <= 0"), "{e}");
        let e = err(Coefficients { eta_slope: 1e300, ..Default::default() }, 1e10);
        assert!(e.starts_with("plate.eta_slope = 1e300:") && e.contains("not a finite number"), "{e}");
        // Overflow and underflow of the Arrhenius factor.
        let e = err(Coefficients { e_off: 800.0, ..Default::default() }, 1e9);
        assert!(e.starts_with("junctions.e_off = 800:") && e.contains("overflows"), "{e}");
        let e = err(Coefficients { e_on: 800.0, ..Default::default() }, 0.5);
        assert!(e.starts_with("junctions.e_on = 800:") && e.contains("underflows"), "{e}");
        assert!(!e.contains("inf") && !e.contains("NaN"), "{e}");
        // A rate of 0 stays 0 (nothing to underflow).
        let zero = Reference { k0: 0.0, ..REF };
        assert_eq!(in_force(&zero, &Coefficients { e_off: 800.0, ..Default::default() }, 0.5).unwrap().k0, 0.0);
    }
}
