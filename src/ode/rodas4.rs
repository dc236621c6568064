//! Coefficients of RODAS4 (Hairer & Wanner, *Solving ODEs II*, 2nd ed., Sect. IV.7,
//! Table 7.3 "RODAS"), in the transformed form of Hairer's `rodas.f` (version of 2004,
//! subroutine `ROCOE`, `METH = 1`), digits kept verbatim.
//!
//! With `W = I / (h gamma) - J`, `J = df/dy(t0, y0)`, `f_t = df/dt(t0, y0)`, stage `i`
//! solves
//! ```text
//! W k_i = f(t0 + alpha_i h, y0 + sum_{j<i} a_ij k_j) + sum_{j<i} (c_ij / h) k_j + h d_i f_t
//! ```
//! The method is stiffly accurate: `y1 = y0 + sum_j a_6j k_j + k_6` (the argument of stage
//! 6 plus `k_6`), the embedded order-3 solution is the argument of stage 6 (`y0 + sum_j
//! a_5j k_j + k_5`), so the local error estimate is `k_6` itself. Dense output (order 3):
//! `y(t0 + s h) = (1 - s) y0 + s (y1 + (1 - s) (c2 + s c3))` with `c2 = sum_j h2_j k_j`,
//! `c3 = sum_j h3_j k_j` (`rodas.f`'s `D21..D35`, `CONTRO`).

/// Number of stages.
pub(super) const STAGES: usize = 6;

/// Diagonal `gamma`.
pub(super) const GAMMA: f64 = 0.25;

/// Nodes `alpha_i` (stage times `t0 + alpha_i h`); Hairer's `C2, C3, C4`, and 1 for stages 5, 6.
pub(super) const ALPHA: [f64; STAGES] = [0.0, 0.386, 0.21, 0.63, 1.0, 1.0];

/// `d_i = gamma_i = sum_j gamma_ij` (coefficient of `h f_t`); zero for stages 5, 6.
pub(super) const D: [f64; STAGES] = [0.25, -0.1043, 0.1035, -0.03620000000000023, 0.0, 0.0];

/// `a_ij` (`j < i`), row `i`; row 5 (0-based) is the stage-6 argument, `a_5j` then 1.
pub(super) const A: [[f64; STAGES]; STAGES] = [
    [0.0; STAGES],
    [1.544, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.9466785280815826, 0.2557011698983284, 0.0, 0.0, 0.0, 0.0],
    [3.314825187068521, 2.896124015972201, 0.9986419139977817, 0.0, 0.0, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895, 0.0, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895, 1.0, 0.0],
];

/// `c_ij` (`j < i`), row `i` (Hairer's sign convention: `C = diag(1/gamma) - Gamma^-1`).
pub(super) const C: [[f64; STAGES]; STAGES] = [
    [0.0; STAGES],
    [-5.6688, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0, 0.0],
    [-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0.0, 0.0, 0.0],
    [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.7089089320616, 0.0, 0.0],
    [8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, -6.058818238834054, 0.0],
];

/// Weights of the solution: `y1 = y0 + sum_j M_j k_j` (row 5 of `A` plus `k_6`).
pub(super) const M: [f64; STAGES] =
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687886036105895, 1.0, 1.0];

/// Dense-output coefficients `h2_j`, `h3_j` (stages 1..5; `k_6` does not enter).
pub(super) const H2: [f64; STAGES] =
    [10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823, 1.025137723295662, 0.0];
pub(super) const H3: [f64; STAGES] =
    [-0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386, -6.594389125716872, 0.0];

#[cfg(test)]
mod tests {
    //! Algebraic checks: the classical Rosenbrock order conditions (HW II, Table 7.1) for
    //! `gamma_ii = gamma`, in the original parameters `alpha_ij = (A Gamma)_ij`,
    //! `beta_ij = alpha_ij + gamma_ij`, `b = M Gamma`, recovered from the transformed ones by
    //! `Gamma = (diag(1/gamma) - C)^-1`.
    use super::*;

    const N: usize = STAGES;
    type Mat = [[f64; N]; N];

    /// `Gamma = (I / gamma - C)^-1` (lower triangular, forward substitution column by column).
    fn gamma_matrix() -> Mat {
        let mut g = [[0.0; N]; N];
        for col in 0..N {
            for i in 0..N {
                let rhs = if i == col { 1.0 } else { 0.0 };
                let mut s = rhs;
                for j in 0..i {
                    s += C[i][j] * g[j][col];
                }
                g[i][col] = s * GAMMA;
            }
        }
        g
    }

    fn mat_mul(a: &Mat, b: &Mat) -> Mat {
        let mut c = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                c[i][j] = (0..N).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    fn vec_mat(v: &[f64; N], a: &Mat) -> [f64; N] {
        let mut r = [0.0; N];
        for j in 0..N {
            r[j] = (0..N).map(|k| v[k] * a[k][j]).sum();
        }
        r
    }

    /// The residuals of the order conditions up to `order` for weights `b`.
    fn residuals(b: &[f64; N], order: usize) -> Vec<(&'static str, f64)> {
        let g = gamma_matrix();
        let gam = GAMMA;
        // Original alpha_ij (strictly lower) and beta_ij = alpha_ij + gamma_ij (j < i).
        let alpha = mat_mul(&A, &g);
        let mut beta = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..i {
                beta[i][j] = alpha[i][j] + g[i][j];
            }
        }
        let ai: Vec<f64> = (0..N).map(|i| alpha[i].iter().sum()).collect();
        let bi: Vec<f64> = (0..N).map(|i| beta[i].iter().sum()).collect();
        let sum = |f: &dyn Fn(usize) -> f64| (0..N).map(f).sum::<f64>();
        let mut r = vec![("1", sum(&|i| b[i]) - 1.0)];
        if order >= 2 {
            r.push(("2", sum(&|i| b[i] * bi[i]) - (0.5 - gam)));
        }
        if order >= 3 {
            r.push(("3a", sum(&|i| b[i] * ai[i] * ai[i]) - 1.0 / 3.0));
            r.push(("3b", sum(&|i| b[i] * sum(&|j| beta[i][j] * bi[j])) - (1.0 / 6.0 - gam + gam * gam)));
        }
        if order >= 4 {
            r.push(("4a", sum(&|i| b[i] * ai[i].powi(3)) - 0.25));
            r.push(("4b", sum(&|i| b[i] * ai[i] * sum(&|j| alpha[i][j] * bi[j])) - (1.0 / 8.0 - gam / 3.0)));
            r.push(("4c", sum(&|i| b[i] * sum(&|j| beta[i][j] * ai[j] * ai[j])) - (1.0 / 12.0 - gam / 3.0)));
            r.push((
                "4d",
                sum(&|i| b[i] * sum(&|j| beta[i][j] * sum(&|k| beta[j][k] * bi[k])))
                    - (1.0 / 24.0 - gam / 2.0 + 1.5 * gam * gam - gam.powi(3)),
            ));
        }
        r
    }

    #[test]
    fn nodes_and_time_coefficients_match_the_matrices() {
        let g = gamma_matrix();
        let alpha = mat_mul(&A, &g);
        for i in 0..N {
            let ai: f64 = alpha[i].iter().sum();
            assert!((ai - ALPHA[i]).abs() < 1e-13, "alpha_{i}: {ai} vs {}", ALPHA[i]);
            let gi: f64 = g[i].iter().sum();
            assert!((gi - D[i]).abs() < 1e-13, "gamma_{i}: {gi} vs {}", D[i]);
            assert!((g[i][i] - GAMMA).abs() < 1e-15);
        }
    }

    #[test]
    fn solution_has_order_4_and_embedded_solution_order_3() {
        let g = gamma_matrix();
        let b = vec_mat(&M, &g);
        for (name, r) in residuals(&b, 4) {
            assert!(r.abs() < 1e-12, "order condition {name}: residual {r:e}");
        }
        // Embedded solution: the argument of stage 6, weights row 5 of A (k_6 excluded).
        let b_hat = vec_mat(&A[5], &g);
        for (name, r) in residuals(&b_hat, 3) {
            assert!(r.abs() < 1e-12, "embedded order condition {name}: residual {r:e}");
        }
        // ... and not order 4 (the estimate k_6 = y1 - y_hat would vanish otherwise).
        let worst = residuals(&b_hat, 4).iter().map(|(_, r)| r.abs()).fold(0.0, f64::max);
        assert!(worst > 1e-4, "embedded method unexpectedly of order 4 ({worst:e})");
    }

    /// L-stability: the stability function `R(z) = 1 + z b^T (I - z B)^-1 1`, `B = alpha +
    /// Gamma`, tends to 0 at infinity; stiff accuracy makes `b^T = e_6^T B`, hence `R(inf) =
    /// 1 - e_6^T 1 = 0` exactly. Checked numerically at a large `z`, and `|R(iy)| <= 1`.
    #[test]
    fn stability_function_is_l_stable() {
        let g = gamma_matrix();
        let alpha = mat_mul(&A, &g);
        let mut bm = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                bm[i][j] = alpha[i][j] + g[i][j];
            }
        }
        let b = vec_mat(&M, &g);
        // R(z) for complex z: solve (I - z B) x = 1 by forward substitution (B lower triangular).
        let r = |zr: f64, zi: f64| -> (f64, f64) {
            let mut x = [(0.0, 0.0); N];
            for i in 0..N {
                let (mut sr, mut si) = (1.0, 0.0);
                for j in 0..i {
                    // + z B_ij x_j
                    let (xr, xi) = x[j];
                    sr += bm[i][j] * (zr * xr - zi * xi);
                    si += bm[i][j] * (zr * xi + zi * xr);
                }
                // divide by (1 - z gamma)
                let (dr, di) = (1.0 - zr * bm[i][i], -zi * bm[i][i]);
                let den = dr * dr + di * di;
                x[i] = ((sr * dr + si * di) / den, (si * dr - sr * di) / den);
            }
            let (mut pr, mut pi) = (0.0, 0.0);
            for i in 0..N {
                pr += b[i] * x[i].0;
                pi += b[i] * x[i].1;
            }
            (1.0 + zr * pr - zi * pi, zr * pi + zi * pr)
        };
        let (r_inf, _) = r(-1e12, 0.0);
        assert!(r_inf.abs() < 1e-9, "R(-1e12) = {r_inf}");
        for k in 0..200 {
            let y = 10f64.powf(-3.0 + 9.0 * k as f64 / 199.0);
            let (a, b) = r(0.0, y);
            assert!((a * a + b * b).sqrt() <= 1.0 + 1e-12, "|R({y} i)| > 1");
        }
        for k in 0..200 {
            let x = -(10f64.powf(-3.0 + 9.0 * k as f64 / 199.0));
            let (a, _) = r(x, 0.0);
            assert!(a.abs() <= 1.0, "|R({x})| > 1");
        }
    }
}
