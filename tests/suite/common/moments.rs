//! The `N -> infinity` moment equations of strong bonds with the linear force law: the
//! oracle the regime criterion and the exact engine's friction statistics are tested against.
//!
//! **Derivation.** Strong bonds: an attached junction ruptures at the constant rate `k0`, a
//! detached one forms at `k_on(t) = kon0 g(|Xd(t)|)`, the same for every junction. Between
//! its own events junction `i` moves as `xd_i = Xd` (attached) or `xd_i = -lambda x_i`
//! (detached). With `n = (1/N) sum q_i` the attached fraction, `m = (1/N) sum_att x_i` and
//! `d = (1/N) sum_det x_i`, the expected change in `dt` given the plate's path is
//!
//! ```text
//! dn = [k_on (1 - n) - k0 n] dt                  formations minus ruptures
//! dm = [Xd n - k0 m + k_on d] dt                 stretching, ruptures carry x_i away,
//!                                                formations bring the residual x_i back
//! dd = [-lambda d + k0 m - k_on d] dt            relaxation, ruptures, formations
//! ```
//!
//! (with `reattach = "unstretched"` a formed junction starts at `x = 0`, so `+ k_on d` drops
//! out of `dm` but `- k_on d` stays in `dd`). Each sum is over `N` junctions whose jumps are
//! independent given the plate, so the noise around these drifts has variance `O(1/N)`; the
//! plate sees only the sums, `F_b = N kappa m`. As `N -> infinity` with the per-junction
//! plate `m_p = M/N`, `e = eta/N`, `k = K/N` held fixed, the fluctuations vanish (law of
//! large numbers) and the plate's equation `M Xdd + eta Xd + F_b + K (X - V t) = 0` divided
//! by `N` closes the system:
//!
//! ```text
//! n' = k_on (1 - n) - k0 n
//! m' = v n - k0 m + k_on d
//! d' = -lambda d + k0 m - k_on d
//! u' = v - V                                      u = X - V t, the lag behind the drive
//! m_p v' = -e v - kappa m - k u                   v = Xd
//! k_on = kon0 g(|v|),  g(s) = 1 for s <= V0, sin(pi V0 / (2 s)) above
//! ```
//!
//! The friction per junction is `f = F/N = -k u`. (This is docs/results.md's mean-field
//! system with `B = m`, `R = d`.) Its fixed point has `v = V`,
//! `n* = k_on / (k_on + k0)`, `d* = k0 m* / (lambda + k_on)`,
//! `m* = (V/k0) n* (1 + k_on/lambda)` (residual; `(V/k0) n*` unstretched) and
//! `f* = e V + kappa m*`, docs/model.md's exact fact 5.
#![allow(dead_code)]

use stickslip::Scene;
use stickslip::ode::Dop853;

/// Parameters of the moment equations, per junction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MomentModel {
    /// `m_p = M / N`.
    pub mass: f64,
    /// `e = eta / N`.
    pub eta: f64,
    /// `k = K / N`.
    pub k: f64,
    pub kappa: f64,
    pub k0: f64,
    pub kon0: f64,
    pub lambda: f64,
    /// `V0 = alpha / tau0`.
    pub v0: f64,
    /// The driving velocity `V`.
    pub v_drive: f64,
    /// `reattach = "residual"`.
    pub residual: bool,
}

/// The state `[n, m, d, u, v]`.
pub type State = [f64; 5];

impl MomentModel {
    /// The moment equations of a scene (strong bonds, linear law, `M > 0`).
    pub fn of(scene: &Scene) -> MomentModel {
        use stickslip::scene::{BondKind, ForceLawKind, Reattach};
        let j = &scene.junctions;
        assert_eq!(j.bond, BondKind::Strong, "the moment equations are for strong bonds");
        assert_eq!(j.force_law, ForceLawKind::Linear, "the moment equations are for the linear law");
        assert!(scene.plate.mass > 0.0, "the moment equations here need an inertial plate");
        let n = j.n as f64;
        MomentModel {
            mass: scene.plate.mass / n,
            eta: scene.plate.eta / n,
            k: scene.plate.k / n,
            kappa: j.kappa,
            k0: j.k0,
            kon0: j.kon0,
            lambda: j.lambda,
            v0: j.alpha / j.tau0,
            v_drive: scene.plate.v,
            residual: j.reattach == Reattach::Residual,
        }
    }

    /// The same model driven at `v`.
    pub fn with_v(&self, v: f64) -> MomentModel {
        MomentModel { v_drive: v, ..*self }
    }

    /// The driving velocities in `[lo, hi]` where the leading eigenvalue of the fixed
    /// point crosses the imaginary axis (Hopf points), found on a grid of `steps` velocities
    /// evenly spaced in `log V` and refined by bisection to a relative `1e-10`.
    pub fn stability_boundaries(&self, lo: f64, hi: f64, steps: usize) -> Vec<f64> {
        let growth = |v: f64| self.with_v(v).eigenvalues()[0].0;
        let at = |k: usize| (lo.ln() + (hi.ln() - lo.ln()) * k as f64 / steps as f64).exp();
        let mut out = Vec::new();
        for k in 0..steps {
            let (mut a, mut b) = (at(k), at(k + 1));
            let (ga, gb) = (growth(a), growth(b));
            if (ga < 0.0) == (gb < 0.0) {
                continue;
            }
            while b - a > 1e-10 * b {
                let m = 0.5 * (a + b);
                if (growth(m) < 0.0) == (ga < 0.0) {
                    a = m;
                } else {
                    b = m;
                }
            }
            out.push(0.5 * (a + b));
        }
        out
    }

    /// `g(|v|)` and its derivative with respect to `v`.
    pub fn g(&self, v: f64) -> (f64, f64) {
        let s = v.abs();
        if s <= self.v0 {
            (1.0, 0.0)
        } else {
            let a = std::f64::consts::FRAC_PI_2 * self.v0 / s;
            (a.sin(), -a.cos() * a / s * v.signum())
        }
    }

    /// The right-hand side.
    pub fn rhs(&self, y: &[f64], dy: &mut [f64]) {
        let (n, m, d, u, v) = (y[0], y[1], y[2], y[3], y[4]);
        let kon = self.kon0 * self.g(v).0;
        dy[0] = kon * (1.0 - n) - self.k0 * n;
        dy[1] = v * n - self.k0 * m + if self.residual { kon * d } else { 0.0 };
        dy[2] = -self.lambda * d + self.k0 * m - kon * d;
        dy[3] = v - self.v_drive;
        dy[4] = (-self.eta * v - self.kappa * m - self.k * u) / self.mass;
    }

    /// The fixed point (steady sliding at `v = V`).
    pub fn fixed_point(&self) -> State {
        let kon = self.kon0 * self.g(self.v_drive).0;
        let n = kon / (kon + self.k0);
        let m = self.v_drive / self.k0 * n * if self.residual { 1.0 + kon / self.lambda } else { 1.0 };
        let d = self.k0 * m / (self.lambda + kon);
        let u = -(self.eta * self.v_drive + self.kappa * m) / self.k;
        [n, m, d, u, self.v_drive]
    }

    /// Steady friction per junction, `f* = e V + kappa m*`.
    pub fn steady_friction(&self) -> f64 {
        -self.k * self.fixed_point()[3]
    }

    /// The Jacobian at `y`, analytically.
    pub fn jacobian(&self, y: &State) -> [[f64; 5]; 5] {
        let (n, _m, d, _u, v) = (y[0], y[1], y[2], y[3], y[4]);
        let (g, dg) = self.g(v);
        let (kon, dkon) = (self.kon0 * g, self.kon0 * dg);
        let r = if self.residual { 1.0 } else { 0.0 };
        let mp = self.mass;
        [
            [-kon - self.k0, 0.0, 0.0, 0.0, dkon * (1.0 - n)],
            [v, -self.k0, r * kon, 0.0, n + r * dkon * d],
            [0.0, self.k0, -self.lambda - kon, 0.0, -dkon * d],
            [0.0, 0.0, 0.0, 0.0, 1.0],
            [0.0, -self.kappa / mp, 0.0, -self.k / mp, -self.eta / mp],
        ]
    }

    /// Eigenvalues `(re, im)` of the Jacobian at the fixed point, largest real part first.
    pub fn eigenvalues(&self) -> Vec<(f64, f64)> {
        let mut ev = eigenvalues(&self.jacobian(&self.fixed_point()));
        ev.sort_by(|a, b| b.0.total_cmp(&a.0));
        ev
    }

    /// Whether steady sliding is linearly stable (every eigenvalue in the left half-plane).
    pub fn stable(&self) -> bool {
        self.eigenvalues()[0].0 < 0.0
    }

    /// The scene's initial state: `detached` (all junctions detached, unstretched),
    /// `attached` (all attached, unstretched) or `stationary` (a fraction
    /// `kon0 / (kon0 + k0)` attached, unstretched); the plate at rest at `X = 0`.
    pub fn initial(&self, scene: &Scene) -> State {
        use stickslip::scene::Initial;
        let n = match scene.junctions.initial {
            Initial::Detached => 0.0,
            Initial::Attached => 1.0,
            Initial::Stationary => self.kon0 / (self.kon0 + self.k0),
        };
        [n, 0.0, 0.0, 0.0, 0.0]
    }

    /// Integrates from `y0` at `t = 0` to `t_end` (relative tolerance `1e-10`), calling
    /// `sample(t, y)` at `t = 0, dt, 2 dt, ..` (dense output) and returning the state at
    /// `t_end`.
    pub fn integrate(&self, y0: State, t_end: f64, dt: f64, mut sample: impl FnMut(f64, &State)) -> State {
        let mut ode = Dop853::new(5, 1e-10, 1e-12).expect("valid tolerances");
        let mut sys = |_t: f64, y: &[f64], dy: &mut [f64]| self.rhs(y, dy);
        let (mut t, mut y) = (0.0, y0);
        let mut k = 0u64;
        sample(0.0, &y);
        k += 1;
        let mut buf = [0.0; 5];
        while t < t_end {
            ode.step(&mut sys, &mut t, &mut y, t_end).expect("the moment equations integrate");
            while (k as f64) * dt <= t {
                let ts = k as f64 * dt;
                ode.dense(ts, &mut buf).expect("inside the step");
                sample(ts, &buf);
                k += 1;
            }
        }
        y
    }

    /// Time-weighted mean and standard deviation of the friction per junction `f = -k u`
    /// over `[t_lo, t_hi]`, from `y0` at `t = 0`: by 64-point Gauss–Legendre-free composite
    /// Simpson quadrature of the dense output on a grid of `h <= 0.01` (the solution is
    /// smooth; the error is far below any sampling error it is compared with).
    pub fn friction_stats(&self, y0: State, t_lo: f64, t_hi: f64) -> (f64, f64) {
        let steps = (((t_hi - t_lo) / 0.01).ceil() as u64).max(2).next_multiple_of(2);
        let h = (t_hi - t_lo) / steps as f64;
        let mut f = Vec::with_capacity(steps as usize + 1);
        // Sample on the grid t_lo + i h by integrating to t_lo first, then in steps of h.
        let mut ode = Dop853::new(5, 1e-11, 1e-13).expect("valid tolerances");
        let mut sys = |_t: f64, y: &[f64], dy: &mut [f64]| self.rhs(y, dy);
        let (mut t, mut y) = (0.0, y0);
        let mut buf = [0.0; 5];
        let mut i = 0u64;
        while i <= steps {
            let ti = t_lo + i as f64 * h;
            while t < ti {
                ode.step(&mut sys, &mut t, &mut y, t_hi).expect("the moment equations integrate");
            }
            if t == ti {
                buf = y;
            } else {
                ode.dense(ti, &mut buf).expect("inside the step");
            }
            f.push(-self.k * buf[3]);
            i += 1;
        }
        let simpson = |g: &dyn Fn(f64) -> f64| -> f64 {
            let s: f64 = f
                .iter()
                .enumerate()
                .map(|(i, &x)| {
                    let w = if i == 0 || i as u64 == steps {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    w * g(x)
                })
                .sum();
            s * h / 3.0
        };
        let t = t_hi - t_lo;
        let mean = simpson(&|x| x) / t;
        let var = simpson(&|x| (x - mean) * (x - mean)) / t;
        (mean, var.sqrt())
    }

    /// The limit cycle reached from `y0` after `t_settle`: its period (time between
    /// successive upward crossings of `v = V`, located by linear interpolation between
    /// points `0.005` apart) and the friction's half-range `(max f - min f) / 2` over the
    /// last full period; `None` if the motion has settled to the fixed point (fewer than
    /// three crossings in 2000 time units, or a half-range below `1e-6 f*`).
    pub fn limit_cycle(&self, y0: State, t_settle: f64) -> Option<(f64, f64)> {
        let dt = 0.005;
        let mut ups = Vec::new();
        let (mut prev, mut fs) = ((f64::NAN, f64::NAN), Vec::new());
        let horizon = t_settle + 2000.0;
        self.integrate(y0, horizon, dt, |t, y| {
            if t >= t_settle {
                let (t0, v0) = prev;
                if v0 < self.v_drive && y[4] >= self.v_drive {
                    ups.push(t0 + (t - t0) * (self.v_drive - v0) / (y[4] - v0));
                }
                fs.push((t, -self.k * y[3]));
            }
            prev = (t, y[4]);
        });
        if ups.len() < 3 {
            return None;
        }
        let (a, b) = (ups[ups.len() - 2], ups[ups.len() - 1]);
        let (lo, hi) = fs
            .iter()
            .filter(|(t, _)| *t >= a && *t <= b)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, f)| (lo.min(f), hi.max(f)));
        let half = 0.5 * (hi - lo);
        (half > 1e-6 * self.steady_friction()).then_some((b - a, half))
    }

    /// The samples a run of `scene` would give at `N -> infinity`: the moment equations
    /// from the scene's initial state, on its output grid (`output.sample_dt`, to
    /// `run.t_end`), scaled to `N = junctions.n` (friction `F = N f`, bond force
    /// `N kappa m`, attached count `round(n N)`).
    pub fn samples(&self, scene: &Scene) -> Vec<stickslip::observe::Sample> {
        let n = scene.junctions.n as f64;
        let mut out = Vec::new();
        self.integrate(self.initial(scene), scene.run.t_end, scene.output.sample_dt, |t, y| {
            out.push(stickslip::observe::Sample {
                t,
                x: y[3] + self.v_drive * t,
                v: y[4],
                friction: -n * self.k * y[3],
                bond_force: n * self.kappa * y[1],
                attached: (y[0] * n).round() as u64,
                n: scene.junctions.n as u64,
            });
        });
        out
    }
}

/// Eigenvalues of a real 5x5 matrix: the roots of its characteristic polynomial
/// (Faddeev–LeVerrier coefficients, Durand–Kerner iteration), as `(re, im)`.
pub fn eigenvalues(a: &[[f64; 5]; 5]) -> Vec<(f64, f64)> {
    const N: usize = 5;
    // Faddeev–LeVerrier: p(z) = z^N + c[1] z^(N-1) + .. + c[N].
    let mut c = [0.0; N + 1];
    c[0] = 1.0;
    let mut mk = [[0.0; N]; N]; // M_0 = 0
    for k in 1..=N {
        // M_k = A M_{k-1} + c_{k-1} I ; c_k = -tr(A M_k) / k
        let mut next = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                next[i][j] = (0..N).map(|l| a[i][l] * mk[l][j]).sum::<f64>() + if i == j { c[k - 1] } else { 0.0 };
            }
        }
        mk = next;
        let tr: f64 = (0..N).map(|i| (0..N).map(|l| a[i][l] * mk[l][i]).sum::<f64>()).sum();
        c[k] = -tr / k as f64;
    }
    // Durand–Kerner on the monic polynomial.
    type C = (f64, f64);
    let mul = |a: C, b: C| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let sub = |a: C, b: C| (a.0 - b.0, a.1 - b.1);
    let div = |a: C, b: C| {
        let d = b.0 * b.0 + b.1 * b.1;
        ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let eval = |z: C| c.iter().fold((0.0, 0.0), |acc, &ck| sub(mul(acc, z), (-ck, 0.0)));
    let scale = 1.0 + c.iter().skip(1).fold(0.0f64, |m, x| m.max(x.abs()));
    let mut roots: Vec<C> = (0..N)
        .map(|i| {
            let (s, co) = (0.4 + 0.9 * i as f64).sin_cos();
            (scale * 0.5 * co, scale * 0.5 * s)
        })
        .collect();
    for _ in 0..2000 {
        let mut delta = 0.0f64;
        for i in 0..N {
            let mut den = (1.0, 0.0);
            for j in 0..N {
                if i != j {
                    den = mul(den, sub(roots[i], roots[j]));
                }
            }
            let step = div(eval(roots[i]), den);
            roots[i] = sub(roots[i], step);
            delta = delta.max(step.0.abs() + step.1.abs());
        }
        if delta < 1e-15 * scale {
            break;
        }
    }
    roots
}
