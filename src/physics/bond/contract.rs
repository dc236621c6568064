//! The bond-kind contract: [`Bond`], and the numbers a kind is built from ([`BondParams`]).

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::physics::force::ParamError;

/// The scene's numbers a bond kind is built from (plain numbers: physics never reads a scene).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BondParams {
    /// Spontaneous rupture rate `k0` (>= 0).
    pub k0: f64,
    /// Barrier distance `dx` (>= 0) of the weak-bond rate.
    pub dx: f64,
    /// Temperature in units of the reference `kB T` (> 0); `beta = 1/temperature`.
    pub temperature: f64,
}

/// A bond kind, chosen once per run: strong-bond scenes run no weak-bond code.
pub trait Bond: Copy + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned + 'static {
    /// The scene's name of the bond kind (`junctions.bond`).
    const NAME: &'static str;
    /// `true` when the rupture rate depends on the tension.
    const IS_WEAK: bool;
    /// Builds the bond kind from the scene's numbers, or says which one it refuses.
    fn new(p: &BondParams) -> Result<Self, ParamError>;
    /// Rupture rate `k_off(f)` at tension `f >= 0`. May be `+inf`, never NaN.
    fn k_off(&self, tension: f64) -> f64;
    /// `k0 = k_off(0)`, the rate of an unstretched bond.
    fn k0(&self) -> f64;
    /// `s >= 0` with `k_off(f) = k0 exp(s f)` (0 for a force-independent rate). With a law's
    /// thinning slope `c` (`f <= c |x|`), `k0 exp(s c |x|)` bounds a junction's rupture rate:
    /// the exact engine's weak-bond envelope.
    fn force_sensitivity(&self) -> f64;
}

/// `k0 >= 0` and finite.
pub(crate) fn check_k0(p: &BondParams) -> Result<f64, ParamError> {
    if p.k0.is_finite() && p.k0 >= 0.0 {
        Ok(p.k0)
    } else {
        Err(ParamError { field: "k0", value: p.k0, allowed: "must be a finite number >= 0".into() })
    }
}
