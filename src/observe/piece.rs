//! [`Piece`]: the raw time integrals of one piece of a trajectory, as an engine has them
//! (no division), for observers that sum them; [`Piece::segment`] gives the means of a
//! [`Segment`].

use super::report::Segment;

/// The raw time integrals of the observables over one piece `[t0, t1]` of length `h` of
/// the trajectory, about the friction `F0` at its start:
///
/// ```text
///     dev  = int (F - F0) dt,          dev2    = int (F - F0)^2 dt,
///     bond = int F_b dt,               viscous = int eta Xd dt,
/// ```
///
/// each over `[t0, t1]`, with the attached count constant on the piece. An observer that
/// sums moments about a reference `r` needs no division: with `d = F0 - r`,
/// `int (F - r) = h d + dev` and `int (F - r)^2 = h d^2 + 2 d dev + dev2`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Piece {
    /// Absolute start and end times.
    pub t0: f64,
    pub t1: f64,
    /// Length `h` (as the engine measures it, in its own frame; `t1 - t0` to rounding).
    pub h: f64,
    /// Friction `F0` at `t0`.
    pub friction0: f64,
    /// `int (F - F0) dt`.
    pub dev: f64,
    /// `int (F - F0)^2 dt` (>= 0).
    pub dev2: f64,
    /// `int F_b dt`.
    pub bond: f64,
    /// `int eta Xd dt`.
    pub viscous: f64,
    /// Attached count (constant on a piece).
    pub attached: u64,
}

impl Piece {
    /// The piece's means (`h > 0`): `mean F = F0 + dev/h`,
    /// `int (F - mean F)^2 = dev2 - dev^2/h` (clamped at 0), the other means `int/h`.
    #[inline]
    pub fn segment(&self) -> Segment {
        let inv_h = 1.0 / self.h;
        Segment {
            t0: self.t0,
            t1: self.t1,
            friction: self.friction0 + self.dev * inv_h,
            friction_m2: (self.dev2 - self.dev * self.dev * inv_h).max(0.0),
            bond_force: self.bond * inv_h,
            viscous: self.viscous * inv_h,
            attached: self.attached,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `F(s) = F0 + a s` on `[0, h]`: mean `F0 + a h/2`, `int (F - mean)^2 = a^2 h^3 / 12`.
    #[test]
    fn a_linear_piece_has_its_mean_and_second_moment() {
        let (f0, a, h) = (3.0, -2.0, 0.5);
        let p = Piece {
            t0: 1.0,
            t1: 1.5,
            h,
            friction0: f0,
            dev: a * h * h / 2.0,
            dev2: a * a * h * h * h / 3.0,
            bond: 4.0 * h,
            viscous: -h,
            attached: 7,
        };
        let s = p.segment();
        assert!((s.friction - (f0 + a * h / 2.0)).abs() < 1e-15);
        assert!((s.friction_m2 - a * a * h * h * h / 12.0).abs() < 1e-15);
        assert_eq!((s.bond_force, s.viscous, s.attached, s.t0, s.t1), (4.0, -1.0, 7, 1.0, 1.5));
    }
}
