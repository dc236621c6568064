//! Small dense LU factorisation with partial pivoting, for the linearly implicit stages of
//! [`super::Rosenbrock`] (dimension at most its capacity `N`, [`MAX_DIM`] for the general
//! integrator; fixed arrays, no allocation).
//!
//! `P A = L U` (Doolittle, `L` unit lower triangular), stored in place row-major with stride
//! `n`; `solve` does the permutation, forward and back substitution (Golub & Van Loan,
//! *Matrix Computations*, Alg. 3.4.1).
//!
//! For `n = 2` (the plate of the series engine) the factors are turned into the inverse
//! `A^-1 = U^-1 L^-1 P` once per factorisation, and `solve` is a product with it: two
//! independent dot products instead of a chain of substitutions, which matters because a
//! Rosenbrock step's six solves are on its critical path. Error: each entry of `U^-1 L^-1`
//! is formed from the factors with at most 3 roundings, so the solution's error is at most
//! about `4 eps |U^-1| |L^-1| |b|` componentwise, the same form (and order) as the
//! substitutions' forward error bound (Higham, *Accuracy and Stability*, Sect. 8.1 and
//! 14.1); `the_2x2_path_matches_the_general_algorithm` checks it.

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
    /// `n = 2`: the inverse `A^-1`, row-major (the permutation folded in).
    inv2: [f64; 4],
    /// `1 / U_kk` (the solve multiplies: no division per solve).
    inv: [f64; N],
}

impl<const N: usize> Default for Lu<N> {
    fn default() -> Self {
        Self { n: 0, a: [[0.0; N]; N], piv: [0; N], inv: [0.0; N], inv2: [0.0; 4] }
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
        let inv1 = 1.0 / u11;
        self.inv[0] = inv0;
        self.inv[1] = inv1;
        self.a.as_flattened_mut()[..4].copy_from_slice(&[r0[0], r0[1], l, u11]);
        // U^-1 L^-1 = [[inv0 (1 + u01 l inv1), -u01 inv0 inv1], [-l inv1, inv1]] acts on
        // (b[piv0], b[piv1]); its columns go to columns piv0 and piv1 of A^-1.
        let w = r0[1] * inv0 * inv1;
        let cols = [[inv0 + w * l, -l * inv1], [-w, inv1]];
        let (p0, p1) = (self.piv[0], self.piv[1]);
        self.inv2 = [cols[p0][0], cols[p1][0], cols[p0][1], cols[p1][1]];
        r0[1].is_finite() && l.is_finite() && self.inv2.iter().all(|v| v.is_finite())
    }

    /// Solves `(fac I - J) x = b` with the stored factors; `b` is overwritten by `x`.
    #[inline(always)]
    pub(super) fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        if n == 2 {
            let m = &self.inv2;
            let (b0, b1) = (b[0], b[1]);
            b[0] = m[0] * b0 + m[1] * b1;
            b[1] = m[2] * b0 + m[3] * b1;
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

    /// The 2x2 path (factors, then the explicit inverse) against the general algorithm on
    /// the same matrix embedded in a 3x3 block-diagonal system (which takes the general
    /// path), with and without a row swap, and for ill-conditioned matrices: the solutions
    /// agree within `8 eps (|U^-1| |L^-1| |b|)`, the forward error bound of both (module
    /// doc), and the residual of the 2x2 solution is at round-off level.
    #[test]
    fn the_2x2_path_matches_the_general_algorithm() {
        let cases = [
            [0.3, -1.7, 2.5, 0.9],
            [2.0, 1.0, -3.0, 0.5],
            [1.0, 0.0, 0.0, -2.0],
            // Nearly singular `fac I - J` (cancellation in the inverse's entries).
            [0.25, 1.0, 1.0, 1.0 / (1.0 - 1e-9)],
            // Badly scaled rows (a stiff plate: 1e9 against 1).
            [0.0, 1.0, -1e9, -1e4],
        ];
        for jac in cases {
            let fac = 1.25;
            let mut lu2 = Lu::<2>::default();
            assert!(lu2.factor_shifted(2, fac, &jac));
            let j3 = [jac[0], jac[1], 0.0, jac[2], jac[3], 0.0, 0.0, 0.0, 0.0];
            let mut lu3 = Lu::<MAX_DIM>::default();
            assert!(lu3.factor_shifted(3, fac, &j3));
            // The factors themselves are the general algorithm's, bit for bit.
            let (a2, a3) = (lu2.a.as_flattened(), lu3.a.as_flattened());
            assert_eq!([a2[0], a2[1], a2[2], a2[3]], [a3[0], a3[1], a3[3], a3[4]], "jac {jac:?}");
            for b in [[0.7, -1.3], [1.0, 0.0], [0.0, 1.0], [1e-3, 5e8]] {
                let (mut b2, mut b3) = (b, [b[0], b[1], 1.0]);
                lu2.solve(&mut b2);
                lu3.solve(&mut b3);
                // |U^-1| |L^-1| |P b| from the stored factors.
                let (u01, l, inv0, inv1) = (a2[1], a2[2], lu2.inv[0], lu2.inv[1]);
                let pb = [b[lu2.piv[0]].abs(), b[lu2.piv[1]].abs()];
                let z = [pb[0], pb[1] + l.abs() * pb[0]];
                let bound1 = inv1.abs() * z[1];
                let bound0 = inv0.abs() * (z[0] + u01.abs() * bound1);
                for (i, bound) in [bound0, bound1].into_iter().enumerate() {
                    let tol = 8.0 * f64::EPSILON * bound;
                    assert!((b2[i] - b3[i]).abs() <= tol, "jac {jac:?} b {b:?}: x{i} {} vs {}", b2[i], b3[i]);
                }
                // (fac I - J) x = b. An explicit inverse is not backward stable: its residual
                // is bounded by `eps cond(A) |A| |x|` (rows), `cond` in the infinity norm.
                let a = [fac - jac[0], -jac[1], -jac[2], fac - jac[3]];
                let m = &lu2.inv2;
                let norm = |v: &[f64; 4]| (v[0].abs() + v[1].abs()).max(v[2].abs() + v[3].abs());
                let cond = norm(&a) * norm(m);
                for i in 0..2 {
                    let r = a[2 * i] * b2[0] + a[2 * i + 1] * b2[1];
                    let scale = a[2 * i].abs() * b2[0].abs() + a[2 * i + 1].abs() * b2[1].abs();
                    let tol = 8.0 * f64::EPSILON * cond * scale.max(b[i].abs());
                    assert!((r - b[i]).abs() <= tol, "jac {jac:?} b {b:?}: row {i} {r} vs {}", b[i]);
                }
            }
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
