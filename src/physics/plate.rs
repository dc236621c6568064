//! The plate's equation of motion (docs/model.md, "Equations", item 1):
//! `M Xdd + eta Xd + F_b + K (X - V t) = 0`.

use serde::{Deserialize, Serialize};

/// Plate parameters in the form engines use.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plate {
    pub mass: f64,
    pub eta: f64,
    pub k: f64,
    pub v: f64,
}

impl Plate {
    /// Net force on the plate `-(eta Xd + F_b + K u)`, with `u = X - V t`: the plate
    /// equation is `M Xdd = ` this (and `0 = ` this with `M = 0`).
    #[inline]
    pub fn net_force(&self, lag: f64, xd: f64, bond_force: f64) -> f64 {
        -(self.eta * xd + bond_force + self.k * lag)
    }
    /// Acceleration `Xdd = -(eta Xd + F_b + K u) / M` for `M > 0`, with `u = X - V t`.
    #[inline]
    pub fn acceleration(&self, lag: f64, xd: f64, bond_force: f64) -> f64 {
        self.net_force(lag, xd, bond_force) / self.mass
    }
    /// Overdamped velocity `Xd = -(F_b + K u) / eta` for `M = 0`.
    #[inline]
    pub fn overdamped_velocity(&self, lag: f64, bond_force: f64) -> f64 {
        -(bond_force + self.k * lag) / self.eta
    }
}
