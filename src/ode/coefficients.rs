//! Coefficients of DOP853, the Dormand–Prince 8(5,3) pair with its 7th-order dense output.
//!
//! Source: E. Hairer and G. Wanner, `dop853.f` ("version of April 25, 1996, small corrections
//! on March 4, 2002"), subroutine `DP86CO`, the `PARAMETER` blocks `c*`, `b*`, `bhh*`, `er*`,
//! `a*`, `d*` (distributed at <https://www.unige.ch/~hairer/software.html>; read from the copy
//! in `cpmech/hwode/dop853.f`). Cross-checked digit for digit against SciPy's
//! `scipy/integrate/_ivp/dop853_coefficients.py`, which publishes the same numbers as arrays.
//! Method: Hairer, Nørsett, Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
//! Springer 1993, Sect. II.5 and II.6.
//!
//! The published 30-digit literals are kept verbatim (they round correctly to `f64`), so that
//! the table can be audited against the source line by line.
//!
//! Indexing: stage `j` (0-based) is Hairer's stage `j + 1`. Stages 0..=11 are the twelve
//! stages of a step (stage 11 is at `t + h`); stage 12 is `f(t + h, y_new)` (the FSAL
//! derivative, Hairer's `K4` after acceptance); stages 13..=15 are the three extra stages
//! used only by the dense output (Hairer's `c14`, `c15`, `c16`).
//! Zero entries are omitted: each row lists `(stage, coefficient)` pairs.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

/// Nodes `c_j` of stages 0..=15 (`c_12 = 1` is the FSAL stage at `t + h`).
pub const C: [f64; 16] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
    1.0,
    0.1e+00,
    0.2e+00,
    0.777777777777777777777777777778e+00,
];

/// Runge–Kutta matrix, row `i` = stage `i` (1..=11 for the step, 13..=15 for dense output;
/// stage 13 uses the FSAL stage 12). Row 0 and row 12 are empty (row 12 is [`B`]).
pub const A: [&[(usize, f64)]; 16] = [
    &[],
    &[(0, 5.26001519587677318785587544488e-2)],
    &[(0, 1.97250569845378994544595329183e-2), (1, 5.91751709536136983633785987549e-2)],
    &[(0, 2.95875854768068491816892993775e-2), (2, 8.87627564304205475450678981324e-2)],
    &[
        (0, 2.41365134159266685502369798665e-1),
        (2, -8.84549479328286085344864962717e-1),
        (3, 9.24834003261792003115737966543e-1),
    ],
    &[
        (0, 3.7037037037037037037037037037e-2),
        (3, 1.70828608729473871279604482173e-1),
        (4, 1.25467687566822425016691814123e-1),
    ],
    &[
        (0, 3.7109375e-2),
        (3, 1.70252211019544039314978060272e-1),
        (4, 6.02165389804559606850219397283e-2),
        (5, -1.7578125e-2),
    ],
    &[
        (0, 3.70920001185047927108779319836e-2),
        (3, 1.70383925712239993810214054705e-1),
        (4, 1.07262030446373284651809199168e-1),
        (5, -1.53194377486244017527936158236e-2),
        (6, 8.27378916381402288758473766002e-3),
    ],
    &[
        (0, 6.24110958716075717114429577812e-1),
        (3, -3.36089262944694129406857109825e0),
        (4, -8.68219346841726006818189891453e-1),
        (5, 2.75920996994467083049415600797e1),
        (6, 2.01540675504778934086186788979e1),
        (7, -4.34898841810699588477366255144e1),
    ],
    &[
        (0, 4.77662536438264365890433908527e-1),
        (3, -2.48811461997166764192642586468e0),
        (4, -5.90290826836842996371446475743e-1),
        (5, 2.12300514481811942347288949897e1),
        (6, 1.52792336328824235832596922938e1),
        (7, -3.32882109689848629194453265587e1),
        (8, -2.03312017085086261358222928593e-2),
    ],
    &[
        (0, -9.3714243008598732571704021658e-1),
        (3, 5.18637242884406370830023853209e0),
        (4, 1.09143734899672957818500254654e0),
        (5, -8.14978701074692612513997267357e0),
        (6, -1.85200656599969598641566180701e1),
        (7, 2.27394870993505042818970056734e1),
        (8, 2.49360555267965238987089396762e0),
        (9, -3.0467644718982195003823669022e0),
    ],
    &[
        (0, 2.27331014751653820792359768449e0),
        (3, -1.05344954667372501984066689879e1),
        (4, -2.00087205822486249909675718444e0),
        (5, -1.79589318631187989172765950534e1),
        (6, 2.79488845294199600508499808837e1),
        (7, -2.85899827713502369474065508674e0),
        (8, -8.87285693353062954433549289258e0),
        (9, 1.23605671757943030647266201528e1),
        (10, 6.43392746015763530355970484046e-1),
    ],
    &[],
    &[
        (0, 5.61675022830479523392909219681e-2),
        (6, 2.53500210216624811088794765333e-1),
        (7, -2.46239037470802489917441475441e-1),
        (8, -1.24191423263816360469010140626e-1),
        (9, 1.5329179827876569731206322685e-1),
        (10, 8.20105229563468988491666602057e-3),
        (11, 7.56789766054569976138603589584e-3),
        (12, -8.298e-3),
    ],
    &[
        (0, 3.18346481635021405060768473261e-2),
        (5, 2.83009096723667755288322961402e-2),
        (6, 5.35419883074385676223797384372e-2),
        (7, -5.49237485713909884646569340306e-2),
        (10, -1.08347328697249322858509316994e-4),
        (11, 3.82571090835658412954920192323e-4),
        (12, -3.40465008687404560802977114492e-4),
        (13, 1.41312443674632500278074618366e-1),
    ],
    &[
        (0, -4.28896301583791923408573538692e-1),
        (5, -4.69762141536116384314449447206e0),
        (6, 7.68342119606259904184240953878e0),
        (7, 4.06898981839711007970213554331e0),
        (8, 3.56727187455281109270669543021e-1),
        (12, -1.39902416515901462129418009734e-3),
        (13, 2.9475147891527723389556272149e0),
        (14, -9.15095847217987001081870187138e0),
    ],
];

/// Weights of the 8th-order solution (Hairer's `b1, b6..b12`).
pub const B: [(usize, f64); 8] = [
    (0, 5.42937341165687622380535766363e-2),
    (5, 4.45031289275240888144113950566e0),
    (6, 1.89151789931450038304281599044e0),
    (7, -5.8012039600105847814672114227e0),
    (8, 3.1116436695781989440891606237e-1),
    (9, -1.52160949662516078556178806805e-1),
    (10, 2.01365400804030348374776537501e-1),
    (11, 4.47106157277725905176885569043e-2),
];

/// Weights of the embedded 3rd-order solution (Hairer's `bhh1..bhh3`): the 3rd-order error
/// estimate is `sum(B k) - BHH k`.
pub const BHH: [(usize, f64); 3] = [
    (0, 0.244094488188976377952755905512e+00),
    (8, 0.733846688281611857341361741547e+00),
    (11, 0.220588235294117647058823529412e-01),
];

/// Coefficients of the 5th-order error estimate (Hairer's `er1, er6..er12`).
pub const ER: [(usize, f64); 8] = [
    (0, 0.1312004499419488073250102996e-01),
    (5, -0.1225156446376204440720569753e+01),
    (6, -0.4957589496572501915214079952e+00),
    (7, 0.1664377182454986536961530415e+01),
    (8, -0.3503288487499736816886487290e+00),
    (9, 0.3341791187130174790297318841e+00),
    (10, 0.8192320648511571246570742613e-01),
    (11, -0.2235530786388629525884427845e-01),
];

/// Dense-output coefficients (Hairer's `d4*..d7*`) over stages 0, 5..=15: row `r` gives the
/// dense coefficient vector `cont[4 + r] = h * sum_j D[r][j] k_j`.
pub const D: [[(usize, f64); 12]; 4] = [
    [
        (0, -0.84289382761090128651353491142e+01),
        (5, 0.56671495351937776962531783590e+00),
        (6, -0.30689499459498916912797304727e+01),
        (7, 0.23846676565120698287728149680e+01),
        (8, 0.21170345824450282767155149946e+01),
        (9, -0.87139158377797299206789907490e+00),
        (10, 0.22404374302607882758541771650e+01),
        (11, 0.63157877876946881815570249290e+00),
        (12, -0.88990336451333310820698117400e-01),
        (13, 0.18148505520854727256656404962e+02),
        (14, -0.91946323924783554000451984436e+01),
        (15, -0.44360363875948939664310572000e+01),
    ],
    [
        (0, 0.10427508642579134603413151009e+02),
        (5, 0.24228349177525818288430175319e+03),
        (6, 0.16520045171727028198505394887e+03),
        (7, -0.37454675472269020279518312152e+03),
        (8, -0.22113666853125306036270938578e+02),
        (9, 0.77334326684722638389603898808e+01),
        (10, -0.30674084731089398182061213626e+02),
        (11, -0.93321305264302278729567221706e+01),
        (12, 0.15697238121770843886131091075e+02),
        (13, -0.31139403219565177677282850411e+02),
        (14, -0.93529243588444783865713862664e+01),
        (15, 0.35816841486394083752465898540e+02),
    ],
    [
        (0, 0.19985053242002433820987653617e+02),
        (5, -0.38703730874935176555105901742e+03),
        (6, -0.18917813819516756882830838328e+03),
        (7, 0.52780815920542364900561016686e+03),
        (8, -0.11573902539959630126141871134e+02),
        (9, 0.68812326946963000169666922661e+01),
        (10, -0.10006050966910838403183860980e+01),
        (11, 0.77771377980534432092869265740e+00),
        (12, -0.27782057523535084065932004339e+01),
        (13, -0.60196695231264120758267380846e+02),
        (14, 0.84320405506677161018159903784e+02),
        (15, 0.11992291136182789328035130030e+02),
    ],
    [
        (0, -0.25693933462703749003312586129e+02),
        (5, -0.15418974869023643374053993627e+03),
        (6, -0.23152937917604549567536039109e+03),
        (7, 0.35763911791061412378285349910e+03),
        (8, 0.93405324183624310003907691704e+02),
        (9, -0.37458323136451633156875139351e+02),
        (10, 0.10409964950896230045147246184e+03),
        (11, 0.29840293426660503123344363579e+02),
        (12, -0.43533456590011143754432175058e+02),
        (13, 0.96324553959188282948394950600e+02),
        (14, -0.39177261675615439165231486172e+02),
        (15, -0.14972683625798562581422125276e+03),
    ],
];

/// Number of stages evaluated per step attempt (stage 0 is the FSAL derivative of the
/// previous step, so an attempt costs `STAGES - 1` evaluations).
pub const STAGES: usize = 12;
/// Stages stored per step: the twelve, the FSAL stage and the three dense-output stages.
pub const STAGES_EXT: usize = 16;

#[cfg(test)]
mod tests {
    //! Algebraic checks of the table: the order conditions of every rooted tree (Butcher
    //! series), for the 8th-order solution, the 5th- and 3rd-order error estimators and the
    //! 7th-order continuous extension. A typo in any coefficient beyond the 14th digit or so
    //! breaks at least one of them.
    use super::*;

    /// A rooted tree: (order, children as indices into the list of smaller trees).
    type Tree = (usize, Vec<usize>);

    /// Rooted trees up to order `max`.
    fn trees(max: usize) -> Vec<(usize, Vec<usize>)> {
        fn multisets(
            trees: &[(usize, Vec<usize>)],
            remaining: usize,
            max_idx: usize,
            cur: &mut Vec<usize>,
            out: &mut Vec<Vec<usize>>,
        ) {
            if remaining == 0 {
                out.push(cur.clone());
                return;
            }
            for idx in (0..=max_idx).rev() {
                if idx < trees.len() && trees[idx].0 <= remaining {
                    cur.push(idx);
                    multisets(trees, remaining - trees[idx].0, idx, cur, out);
                    cur.pop();
                }
            }
        }
        let mut list: Vec<Tree> = vec![(1, vec![])];
        for order in 2..=max {
            let mut out = Vec::new();
            multisets(&list, order - 1, list.len() - 1, &mut Vec::new(), &mut out);
            for ch in out {
                list.push((order, ch));
            }
        }
        list
    }

    /// Dense 16x16 matrix of the extended tableau, row 12 (the FSAL stage) = B.
    fn full_a() -> [[f64; 16]; 16] {
        let mut a = [[0.0; 16]; 16];
        for (i, row) in A.iter().enumerate() {
            for &(j, v) in row.iter() {
                a[i][j] = v;
            }
        }
        for &(j, v) in B.iter() {
            a[12][j] = v;
        }
        a
    }

    /// `Phi_i(t)` for every tree and every stage, and `gamma(t)`.
    fn elementary(max: usize) -> (Vec<Tree>, Vec<[f64; 16]>, Vec<f64>) {
        let a = full_a();
        let ts = trees(max);
        let mut phi: Vec<[f64; 16]> = Vec::new();
        let mut gamma: Vec<f64> = Vec::new();
        for (order, ch) in &ts {
            let mut p = [1.0; 16];
            let mut g = *order as f64;
            for &u in ch {
                for (i, pi) in p.iter_mut().enumerate() {
                    let s: f64 = (0..16).map(|j| a[i][j] * phi[u][j]).sum();
                    *pi *= s;
                }
                g *= gamma[u];
            }
            phi.push(p);
            gamma.push(g);
        }
        (ts, phi, gamma)
    }

    fn weights(sparse: &[(usize, f64)]) -> [f64; 16] {
        let mut w = [0.0; 16];
        for &(j, v) in sparse {
            w[j] += v;
        }
        w
    }

    #[test]
    fn tree_counts() {
        let ts = trees(8);
        let counts: Vec<usize> = (1..=8).map(|o| ts.iter().filter(|t| t.0 == o).count()).collect();
        assert_eq!(counts, vec![1, 1, 2, 4, 9, 20, 48, 115]);
    }

    #[test]
    fn row_sums_equal_nodes() {
        for (i, row) in A.iter().enumerate() {
            if i == 0 || i == 12 {
                continue;
            }
            let s: f64 = row.iter().map(|&(_, a)| a).sum();
            assert!((s - C[i]).abs() < 5e-14, "row {i}: sum {s} vs c {}", C[i]);
        }
        let s: f64 = B.iter().map(|&(_, b)| b).sum();
        assert!((s - 1.0).abs() < 5e-15);
    }

    #[test]
    fn order_8_solution_and_embedded_5_and_3() {
        let (ts, phi, gamma) = elementary(8);
        let b = weights(&B);
        let er = weights(&ER);
        let bhh = weights(&BHH);
        let dot = |w: &[f64; 16], p: &[f64; 16]| -> f64 { (0..16).map(|j| w[j] * p[j]).sum() };
        let mut worst: f64 = 0.0;
        for (k, (order, _)) in ts.iter().enumerate() {
            let exact = 1.0 / gamma[k];
            let e8 = dot(&b, &phi[k]) - exact;
            worst = worst.max(e8.abs());
            assert!(e8.abs() < 1e-13, "8th-order condition fails for tree {k} (order {order}): {e8:e}");
            if *order <= 5 {
                // er = b - b5: the 5th-order weights satisfy the conditions up to order 5.
                let e5 = dot(&er, &phi[k]);
                assert!(e5.abs() < 1e-12, "5th-order estimator fails for tree {k} (order {order}): {e5:e}");
            }
            if *order <= 3 {
                let e3 = dot(&bhh, &phi[k]) - exact;
                assert!(e3.abs() < 1e-12, "3rd-order estimator fails for tree {k} (order {order}): {e3:e}");
            }
        }
        // The estimators are not of higher order than claimed (they do estimate something).
        let e5_order6: f64 =
            ts.iter().enumerate().filter(|(_, t)| t.0 == 6).map(|(k, _)| dot(&er, &phi[k]).abs()).fold(0.0, f64::max);
        assert!(e5_order6 > 1e-6, "{e5_order6:e}");
        assert!(worst < 1e-13, "{worst:e}");
    }

    /// The continuous extension: `y(t0 + s h) = y0 + h sum_j b_j(s) k_j` with the `b_j(s)`
    /// implied by `CONTD8` must satisfy `sum_j b_j(s) Phi_j(t) = s^|t| / gamma(t)` for every
    /// tree of order <= 7.
    #[test]
    fn dense_output_order_7() {
        let (ts, phi, gamma) = elementary(8);
        let b = weights(&B);
        let mut e0 = [0.0; 16];
        e0[0] = 1.0;
        let mut e12 = [0.0; 16];
        e12[12] = 1.0;
        let d: Vec<[f64; 16]> = D.iter().map(|row| weights(row)).collect();
        let mut worst8: f64 = 0.0;
        for &s in &[0.1, 0.25, 0.5, 0.7, 0.93] {
            let s1 = 1.0 - s;
            let mut w = [0.0; 16];
            for j in 0..16 {
                let cont1 = b[j];
                let cont2 = e0[j] - cont1;
                let cont3 = cont1 - e12[j] - cont2;
                let conpar = d[0][j] + s * (d[1][j] + s1 * (d[2][j] + s * d[3][j]));
                w[j] = s * (cont1 + s1 * (cont2 + s * (cont3 + s1 * conpar)));
            }
            for (k, (order, _)) in ts.iter().enumerate() {
                let got: f64 = (0..16).map(|j| w[j] * phi[k][j]).sum();
                let exact = s.powi(*order as i32) / gamma[k];
                if *order <= 7 {
                    assert!(
                        (got - exact).abs() < 1e-13,
                        "dense condition fails: s = {s}, tree {k} (order {order}): {:e}",
                        got - exact
                    );
                } else {
                    worst8 = worst8.max((got - exact).abs());
                }
            }
        }
        // Order exactly 7: some order-8 condition fails inside the step.
        assert!(worst8 > 1e-8, "{worst8:e}");
    }
}
