//! The series' local cubic ([`super::SeriesSum::taylor_at`]): evaluated by the plate's
//! steps instead of the series when their excursion is small.

/// The cubic Taylor polynomial of the series about a point `at`,
/// `S(z) ~ c0 + c1 e + c2 e^2 + c3 e^3`, `e = z - at` ([`super::SeriesSum::taylor_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalCubic {
    pub at: f64,
    pub c: [f64; 4],
}

impl LocalCubic {
    /// `c0 + c1 e + c2 e^2 + c3 e^3`, `e = z - at`, as `(c0 + c1 e) + e^2 (c2 + c3 e)`
    /// (Estrin's scheme: the two halves and `e^2` are independent, so the value is ready
    /// two roundings sooner than by Horner's; the rounding error has the same bound,
    /// `3 eps sum |c_j| |e|^j` to first order).
    #[inline]
    pub fn force(&self, z: f64) -> f64 {
        let e = z - self.at;
        let [c0, c1, c2, c3] = self.c;
        (c0 + c1 * e) + (e * e) * (c2 + c3 * e)
    }

    /// The cubic and its derivative `c1 + 2 c2 e + 3 c3 e^2`, both by Estrin's scheme.
    #[inline]
    pub fn force_and_stiffness(&self, z: f64) -> (f64, f64) {
        let e = z - self.at;
        let e2 = e * e;
        let [c0, c1, c2, c3] = self.c;
        ((c0 + c1 * e) + e2 * (c2 + c3 * e), (c1 + 2.0 * c2 * e) + e2 * (3.0 * c3))
    }
}
