//! Small dense LU factorisation with partial pivoting, for the linearly implicit stages of
//! [`super::Rosenbrock`] (dimension at most its capacity `N`, [`MAX_DIM`] for the general
//! integrator; fixed arrays, no allocation).
//!
//! `P A = L U` (Doolittle, `L` unit lower triangular), stored in place row-major with stride
//! `n`; `solve` does the permutation, forward and back substitution (Golub & Van Loan,
//! *Matrix Computations*, Alg. 3.4.1).

/// Largest system dimension of the Rosenbrock integrator.
pub const MAX_DIM: usize = 8;

/// An `n x n` matrix factorised in place, `n <= N`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Lu<const N: usize> {
    n: usize,
    /// `L` (strictly lower, unit diagonal implied) and `U`, row-major, stride `n`, in the
    /// first `n * n` entries of the flattened array.
    a: [[f64; N]; N],
    /// Row `i` of `P A` is row `piv[i]` of `A`.
    piv: [usize; N],
    /// `1 / U_kk` (the solve multiplies: no division per solve).
    inv: [f64; N],
}

impl<const N: usize> Default for Lu<N> {
    fn default() -> Self {
        Self { n: 0, a: [[0.0; N]; N], piv: [0; N], inv: [0.0; N] }
    }
}

impl<const N: usize> Lu<N> {
    /// Factorises `fac I - J` (`jac` row-major `n x n`) in place. Returns `false` if a pivot
    /// is zero or any entry non-finite (the matrix is then unusable).
    #[inline]
    pub(super) fn factor_shifted(&mut self, n: usize, fac: f64, jac: &[f64]) -> bool {
        debug_assert!(n <= N && jac.len() >= n * n);
        self.n = n;
        if n == 2 {
            return self.factor_2x2(fac, jac);
        }
        let a = self.a.as_flattened_mut();
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = -jac[i * n + j];
            }
            a[i * n + i] += fac;
            self.piv[i] = i;
        }
        for k in 0..n {
            // Partial pivoting: the largest |a[i][k]|, i >= k.
            let mut p = k;
            let mut best = a[k * n + k].abs();
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if !(best > 0.0 && best.is_finite()) {
                return false;
            }
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
                self.piv.swap(k, p);
            }
            let inv = 1.0 / a[k * n + k];
            self.inv[k] = inv;
            for i in k + 1..n {
                let l = a[i * n + k] * inv;
                a[i * n + k] = l;
                if l != 0.0 {
                    for j in k + 1..n {
                        a[i * n + j] -= l * a[k * n + j];
                    }
                }
            }
        }
        a[..n * n].iter().all(|v| v.is_finite())
    }

    /// `factor_shifted` for `n = 2`, unrolled: the same operations in the same order (the
    /// same factors, bit for bit), without the loops.
    #[inline]
    fn factor_2x2(&mut self, fac: f64, jac: &[f64]) -> bool {
        let (mut r0, mut r1) = ([fac - jac[0], -jac[1]], [-jac[2], fac - jac[3]]);
        self.piv[..2].copy_from_slice(&[0, 1]);
        let best = r0[0].abs().max(r1[0].abs());
        if !(best > 0.0 && best.is_finite()) {
            return false;
        }
        if r1[0].abs() > r0[0].abs() {
            std::mem::swap(&mut r0, &mut r1);
            self.piv[..2].copy_from_slice(&[1, 0]);
        }
        let inv0 = 1.0 / r0[0];
        let l = r1[0] * inv0;
        let u11 = if l != 0.0 { r1[1] - l * r0[1] } else { r1[1] };
        if !(u11.abs() > 0.0 && u11.is_finite()) {
            return false;
        }
        self.inv[0] = inv0;
        self.inv[1] = 1.0 / u11;
        self.a.as_flattened_mut()[..4].copy_from_slice(&[r0[0], r0[1], l, u11]);
        r0[1].is_finite() && l.is_finite()
    }

    /// Solves `(fac I - J) x = b` with the stored factors; `b` is overwritten by `x`.
    #[inline(always)]
    pub(super) fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        if n == 2 {
            let a = self.a.as_flattened();
            let x0 = b[self.piv[0]];
            let x1 = (b[self.piv[1]] - a[2] * x0) * self.inv[1];
            b[0] = (x0 - a[1] * x1) * self.inv[0];
            b[1] = x1;
            return;
        }
        let a = self.a.as_flattened();
        let mut x = [0.0; N];
        for i in 0..n {
            let mut s = b[self.piv[i]];
            for j in 0..i {
                s -= a[i * n + j] * x[j];
            }
            x[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for j in i + 1..n {
                s -= a[i * n + j] * x[j];
            }
            x[i] = s * self.inv[i];
        }
        b[..n].copy_from_slice(&x[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(fac I - J) x = b` recovered for a matrix that needs pivoting (zero leading entry).
    #[test]
    fn solves_a_system_that_needs_pivoting() {
        // fac I - J = [[0, 2, 1], [1, 1, 0], [3, 0, 5]] with fac = 1.
        let m = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 5.0]];
        let mut jac = [0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                jac[i * 3 + j] = if i == j { 1.0 } else { 0.0 } - m[i][j];
            }
        }
        let mut lu = Lu::<MAX_DIM>::default();
        assert!(lu.factor_shifted(3, 1.0, &jac));
        let x = [1.5, -2.0, 0.25];
        let mut b = [0.0; 3];
        for i in 0..3 {
            b[i] = (0..3).map(|j| m[i][j] * x[j]).sum();
        }
        lu.solve(&mut b);
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14, "{b:?}");
        }
    }

    /// The unrolled 2x2 factorisation gives the general algorithm's factors and solutions
    /// bit for bit (with and without a row swap), checked against the same matrix embedded
    /// in a 3x3 block-diagonal system, which takes the general path.
    #[test]
    fn the_2x2_path_is_the_general_algorithm() {
        for jac in [[0.3, -1.7, 2.5, 0.9], [2.0, 1.0, -3.0, 0.5], [1.0, 0.0, 0.0, -2.0]] {
            let fac = 1.25;
            let mut lu2 = Lu::<2>::default();
            assert!(lu2.factor_shifted(2, fac, &jac));
            let j3 = [jac[0], jac[1], 0.0, jac[2], jac[3], 0.0, 0.0, 0.0, 0.0];
            let mut lu3 = Lu::<MAX_DIM>::default();
            assert!(lu3.factor_shifted(3, fac, &j3));
            let (mut b2, mut b3) = ([0.7, -1.3], [0.7, -1.3, 1.0]);
            lu2.solve(&mut b2);
            lu3.solve(&mut b3);
            assert_eq!(b2, [b3[0], b3[1]], "jac {jac:?}");
            // (fac I - J) x = b.
            let r0 = (fac - jac[0]) * b2[0] - jac[1] * b2[1];
            let r1 = -jac[2] * b2[0] + (fac - jac[3]) * b2[1];
            assert!((r0 - 0.7).abs() < 1e-14 && (r1 + 1.3).abs() < 1e-14, "{r0} {r1}");
        }
        let mut lu2 = Lu::<2>::default();
        assert!(!lu2.factor_shifted(2, 1.0, &[1.0, 0.0, 0.0, 1.0]));
        assert!(!lu2.factor_shifted(2, 1.0, &[0.0, 1.0, 1.0, 0.0 + f64::NAN]));
    }

    #[test]
    fn singular_and_non_finite_matrices_are_refused() {
        let mut lu = Lu::<MAX_DIM>::default();
        // fac I - J = 0.
        assert!(!lu.factor_shifted(2, 1.0, &[1.0, 0.0, 0.0, 1.0]));
        assert!(!lu.factor_shifted(1, 1.0, &[f64::NAN]));
        assert!(!lu.factor_shifted(1, f64::INFINITY, &[0.0]));
    }
}
