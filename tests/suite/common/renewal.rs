//! Renewal theory of weak bonds at a kinematic drive (docs/model.md, "Weak bonds at a
//! kinematic drive: renewal theory"): the reference values of the renewal tests, by
//! quadrature with a stated error bound, generic over the force law.
//!
//! A junction with `reattach = "unstretched"` on a plate at `X = V t` alternates between
//! detached periods `T_d ~ Exp(kon)`, `kon = kon0 g(V)`, and attached periods during which
//! `x(s) = V s`, with survival `S(s) = exp(-H(s))`, `H(s) = int_0^s k0 exp(beta dx f(V u)) du`.
//! The periods are independent, so by the renewal-reward theorem the long-run time averages
//! per junction are
//! - attached fraction `n = E[T_a] / (E[T_a] + 1/kon)`, `E[T_a] = int_0^inf S ds`;
//! - tension `<q f> = int_0^inf f(V s) S(s) ds / (E[T_a] + 1/kon)`;
//! - bond force `<q f^x> = int_0^inf f^x(V s) S(s) ds / (E[T_a] + 1/kon)`.
//!
//! [`Discrete`] is the same theory for the fixed-step scheme at step `dt` (exact for the
//! scheme, so a fixed-engine test against it has no discretisation bias).

/// Euler–Mascheroni constant.
pub const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// A value and a bound on its absolute error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounded {
    pub value: f64,
    pub error: f64,
}

/// One weak bond at a kinematic drive: rates and the force law (`tension` = `f`,
/// `force_x` = `f^x`, both functions of the extension `x`).
#[derive(Clone, Copy)]
pub struct Renewal<F: Fn(f64) -> f64, G: Fn(f64) -> f64> {
    pub k0: f64,
    pub beta_dx: f64,
    pub v: f64,
    /// `kon = kon0 g(V)`.
    pub kon: f64,
    pub tension: F,
    pub force_x: G,
}

/// The integrals of one attached period: `E[T_a] = int S`, `int f S`, `int f^x S`.
#[derive(Clone, Copy, Debug)]
pub struct Integrals {
    pub ta: Bounded,
    pub f: Bounded,
    pub fx: Bounded,
    /// Mean cycle `E[T_a] + 1/kon`.
    pub kon: f64,
}

impl Integrals {
    fn cycle(&self) -> f64 {
        self.ta.value + 1.0 / self.kon
    }
    /// `n = E[T_a] / (E[T_a] + 1/kon)`; error `|dn/dE[T_a]| err = (1/kon) err / cycle^2`.
    pub fn attached_fraction(&self) -> Bounded {
        let c = self.cycle();
        Bounded { value: self.ta.value / c, error: self.ta.error / (self.kon * c * c) }
    }
    /// `int phi S / cycle`; error `err_phi / cycle + |int phi S| err_ta / cycle^2`.
    fn per_cycle(&self, b: Bounded) -> Bounded {
        let c = self.cycle();
        Bounded { value: b.value / c, error: b.error / c + b.value.abs() * self.ta.error / (c * c) }
    }
    /// Time average of `q f` per junction.
    pub fn mean_tension(&self) -> Bounded {
        self.per_cycle(self.f)
    }
    /// Time average of `q f^x` per junction.
    pub fn mean_force_x(&self) -> Bounded {
        self.per_cycle(self.fx)
    }
}

/// Gauss–Legendre nodes and weights on [-1, 1], 8 points.
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// `int_a^b h` by 8-point Gauss–Legendre.
fn gl(a: f64, b: f64, h: impl Fn(f64) -> f64) -> f64 {
    let (m, r) = (0.5 * (a + b), 0.5 * (b - a));
    r * GL8.iter().map(|&(x, w)| w * h(m + r * x)).sum::<f64>()
}

impl<F: Fn(f64) -> f64, G: Fn(f64) -> f64> Renewal<F, G> {
    /// Rupture rate after an attached time `s`: `k0 exp(beta dx f(V s))`.
    pub fn hazard(&self, s: f64) -> f64 {
        self.k0 * (self.beta_dx * (self.tension)(self.v * s)).exp()
    }

    /// Where the cumulative hazard first exceeds `h_end`, on panels of width `w`.
    fn truncation(&self, w: f64, h_end: f64) -> f64 {
        let (mut s, mut h) = (0.0, 0.0);
        while h < h_end {
            h += gl(s, s + w, |u| self.hazard(u));
            s += w;
        }
        s
    }

    /// `[int S, int f S, int f^x S]` over `[0, s_max]` on `panels` panels, with `H` at every
    /// node by a nested Gauss–Legendre rule from the panel's start.
    fn composite(&self, s_max: f64, panels: usize) -> [f64; 3] {
        let w = s_max / panels as f64;
        let mut h0 = 0.0;
        let mut acc = [0.0; 3];
        for p in 0..panels {
            let a = p as f64 * w;
            let b = a + w;
            let (m, r) = (0.5 * (a + b), 0.5 * w);
            for &(x, wt) in &GL8 {
                let s = m + r * x;
                let surv = (-(h0 + gl(a, s, |u| self.hazard(u)))).exp();
                let x = self.v * s;
                acc[0] += r * wt * surv;
                acc[1] += r * wt * (self.tension)(x) * surv;
                acc[2] += r * wt * (self.force_x)(x) * surv;
            }
            h0 += gl(a, b, |u| self.hazard(u));
        }
        acc
    }

    /// The three integrals with error bounds.
    ///
    /// Truncation at `s_max` where `H(s_max) >= 60`: the hazard is non-decreasing (the
    /// tension grows with `x = V s`), so for `s > s_max` `S(s) <= S(s_max) e^{-k_m (s - s_max)}`,
    /// `k_m = k(s_max)`; with `|phi(s)| <= A + B s` (`phi` = 1, `f`, `f^x`; both laws have
    /// `|f^x| <= f <= kappa V s`, so `B = slope`) the tail is at most
    /// `S(s_max) ((A + B s_max)/k_m + B/k_m^2)`. Quadrature: composite 8-point Gauss–Legendre
    /// on `n` and `2n` panels; the result is the `2n` one and `|Q_2n - Q_n|` bounds its error
    /// (conservatively: the rule's error falls by `2^16` on halving for a smooth integrand).
    pub fn integrals(&self, slope: f64) -> Integrals {
        let s_max = self.truncation(1e-2 / self.k0.max(1e-300), 60.0);
        let surv = (-60.0f64).exp();
        let k_m = self.hazard(s_max);
        let tail = |a: f64, b: f64| surv * ((a + b * s_max) / k_m + b / (k_m * k_m));
        let n = 256;
        let q1 = self.composite(s_max, n);
        let q2 = self.composite(s_max, 2 * n);
        let b = |i: usize, a: f64, slope: f64| Bounded {
            value: q2[i],
            error: (q2[i] - q1[i]).abs() + tail(a, slope) + 1e-15 * q2[i].abs(),
        };
        Integrals { ta: b(0, 1.0, 0.0), f: b(1, 0.0, slope), fx: b(2, 0.0, slope), kon: self.kon }
    }
}

/// The fixed-step scheme's renewal theory at step `dt` (docs/model.md): a junction formed at
/// step `m` is attached over steps `m .. m+J-1` with extension `V j dt` at step `m + j`;
/// it ruptures at step `m + j`, `j >= 1`, with probability `p_j = rule(k(V j dt) dt)`, so
/// `P(J > j) = prod_{i=1..j} (1 - p_i)`; a detached junction forms at each later step with
/// probability `p_on = rule(kon dt)`, `E[I] = 1/p_on` steps. Time averages: `n = E[J]/(E[J] +
/// E[I])`, `<q phi> = sum_j phi(V j dt) P(J > j) / (E[J] + E[I])`.
pub struct Discrete {
    pub attached_fraction: f64,
    pub mean_tension: f64,
    pub mean_force_x: f64,
}

impl<F: Fn(f64) -> f64, G: Fn(f64) -> f64> Renewal<F, G> {
    /// Discrete-time reference at step `dt`; `rule(k dt)` is the flip probability. The sums
    /// stop where `P(J > j) < 1e-30` (the neglected tail is below `1e-30` times a geometric
    /// factor: `p_j` is non-decreasing).
    pub fn discrete(&self, dt: f64, rule: impl Fn(f64) -> f64) -> Discrete {
        let (mut surv, mut j) = (1.0f64, 0u64);
        let (mut ej, mut sf, mut sfx) = (0.0, 0.0, 0.0);
        while surv > 1e-30 {
            let x = self.v * j as f64 * dt;
            ej += surv;
            sf += (self.tension)(x) * surv;
            sfx += (self.force_x)(x) * surv;
            j += 1;
            surv *= 1.0 - rule(self.hazard(j as f64 * dt) * dt);
        }
        let cycle = ej + 1.0 / rule(self.kon * dt);
        Discrete { attached_fraction: ej / cycle, mean_tension: sf / cycle, mean_force_x: sfx / cycle }
    }
}

/// `E_1(x) = -gamma - ln x - sum_{k>=1} (-x)^k / (k k!)`, for `0 < x <= 10` (the series
/// terms stay below `10^10 / 10!` ~ `3e3`, so about 13 digits remain).
pub fn exp_int_e1(x: f64) -> f64 {
    assert!(x > 0.0 && x <= 10.0);
    let (mut sum, mut term, mut k) = (0.0, 1.0, 1.0);
    loop {
        term *= -x / k;
        let add = term / k;
        sum += add;
        if add.abs() < 1e-17 * sum.abs().max(1e-300) {
            break;
        }
        k += 1.0;
    }
    -EULER_GAMMA - x.ln() - sum
}

/// `G(c) = int_c^inf ln(w/c) e^{-w}/w dw = int_c^inf E_1(w)/w dw`
/// `= (ln c)^2/2 + gamma ln c + gamma^2/2 + pi^2/12 + sum_{k>=1} (-1)^k c^k/(k^2 k!)`
/// (its derivative is `-E_1(c)/c`; the constant is the `s^0` term of the Mellin transform
/// `Gamma(s)/s` of `E_1`). For `0 < c <= 10`.
pub fn gompertz_g(c: f64) -> f64 {
    assert!(c > 0.0 && c <= 10.0);
    let (mut sum, mut term, mut k) = (0.0, 1.0, 1.0);
    loop {
        term *= -c / k;
        let add = term / (k * k);
        sum += add;
        if add.abs() < 1e-17 * sum.abs().max(1e-300) {
            break;
        }
        k += 1.0;
    }
    let l = c.ln();
    0.5 * l * l + EULER_GAMMA * l + 0.5 * EULER_GAMMA * EULER_GAMMA + std::f64::consts::PI.powi(2) / 12.0 + sum
}

/// Closed forms for the `linear` law (Gompertz survival `S = exp(-c (e^{r s} - 1))`,
/// `r = beta dx kappa V`, `c = k0 / r`): substituting `w = c e^{r s}`,
/// `E[T_a] = e^c E_1(c) / r` and `int s S ds = e^c G(c) / r^2`, so `int f S = kappa V e^c G(c) / r^2`.
pub fn linear_closed_form(k0: f64, beta_dx: f64, kappa: f64, v: f64) -> (f64, f64) {
    let r = beta_dx * kappa * v;
    let c = k0 / r;
    (c.exp() * exp_int_e1(c) / r, kappa * v * c.exp() * gompertz_g(c) / (r * r))
}
