//! The force laws and bond kinds to loop over, taken from the library: a law or bond kind
//! added to `ForceLawKind::ALL` or `BondKind::ALL` is covered by every loop over these.

use stickslip::scene::{BondKind, ForceLawKind};

/// Every force law the library has.
pub const LAWS: &[ForceLawKind] = &ForceLawKind::ALL;

/// Every bond kind the library has.
pub const BONDS: &[BondKind] = &BondKind::ALL;

/// Every (law, bond) pair, laws outermost.
pub fn law_bond_pairs() -> impl Iterator<Item = (ForceLawKind, BondKind)> {
    LAWS.iter().flat_map(|&l| BONDS.iter().map(move |&b| (l, b)))
}
