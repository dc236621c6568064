//! The model's physics as pure functions of state and parameters: no randomness, no
//! clock, no I/O. Engines own time and randomness and call these.

pub mod force;
pub mod plate;
pub mod rates;
pub mod series;

pub use force::{ForceLaw, Linear, Tilted};
pub use plate::Plate;
pub use rates::{Bond, Formation, Strong, Weak};
pub use series::{SeriesSum, tilted_taylor};

use crate::scene::Scene;

impl Plate {
    pub fn from_scene(s: &Scene) -> Plate {
        Plate { mass: s.plate.mass, eta: s.plate.eta, k: s.plate.k, v: s.plate.v }
    }
}

impl Formation {
    pub fn from_scene(s: &Scene) -> Formation {
        Formation { kon0: s.junctions.kon0, v0: s.junctions.v0() }
    }
}

impl Linear {
    pub fn from_scene(s: &Scene) -> Linear {
        Linear { kappa: s.junctions.kappa }
    }
}

impl Tilted {
    pub fn from_scene(s: &Scene) -> Tilted {
        Tilted { kappa: s.junctions.kappa, l0: s.junctions.l0 }
    }
}

impl Strong {
    pub fn from_scene(s: &Scene) -> Strong {
        Strong { k0: s.junctions.k0 }
    }
}

impl Weak {
    pub fn from_scene(s: &Scene) -> Weak {
        Weak { k0: s.junctions.k0, beta_dx: s.junctions.beta_dx() }
    }
}
