//! Periodicity of a record: its autocorrelation, the period of its oscillation and how
//! much of its variance repeats after one period.
//!
//! For a record `x_0 .. x_{B-1}` (deviations from its mean) the autocorrelation at lag `j`
//! is the unbiased estimate
//!
//! ```text
//! rho(j) = [ (1/(B-j)) sum_{i<B-j} x_i x_{i+j} ] / [ (1/B) sum_i x_i^2 ],
//! ```
//!
//! computed with a radix-2 FFT (Wiener–Khinchin, zero-padded to at least `2B`: no
//! wrap-around). A signal `p(t) + e(t)`, with `p` periodic of period `P` and `e` noise
//! uncorrelated with it and with itself over a lag `P`, has `rho(P) = var p / (var p +
//! var e)`: the **coherence** `rho(P)` is the fraction of the variance that repeats after one
//! period. A stationary Gaussian process has, instead, `rho(P) = e^{-gamma P}` for its
//! damped oscillation of rate `gamma`.
//!
//! The **period** is the lag of the highest autocorrelation in its first positive lobe after
//! the first zero crossing (refined by a parabola through the three highest lags). A record
//! whose autocorrelation does not return above zero within a quarter of its length has no
//! period.

/// Complex numbers as `(re, im)`.
type C = (f64, f64);

/// In-place iterative radix-2 FFT of `a` (length a power of two); `inverse` uses `e^{+i..}`
/// and does not scale. The twiddles `e^{-+2 pi i m/n}`, `m < n/2`, are computed once per
/// call (`n/2` `sin_cos`, not `n/2` per stage): stage `len` uses `m = k n/len`, whose angle
/// `(2 pi/n) (k n/len)` is the same `f64` as `(2 pi/len) k` (the two differ by powers of two
/// only), so the transform is the one that computes every twiddle in its stage, bit for bit
/// (unit test `fft_is_the_per_stage_fft`).
fn fft(a: &mut [C], inverse: bool) {
    let n = a.len();
    debug_assert!(n.is_power_of_two());
    bit_reverse(a);
    let sign = if inverse { 1.0 } else { -1.0 };
    let ang = sign * 2.0 * std::f64::consts::PI / n as f64;
    let twiddles: Vec<C> = (0..n / 2)
        .map(|m| {
            let (s, c) = (ang * m as f64).sin_cos();
            (c, s)
        })
        .collect();
    let mut len = 2;
    while len <= n {
        let stride = n / len;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (c, s) = twiddles[k * stride];
                let (u, v) = (a[start + k], a[start + k + len / 2]);
                let t = (v.0 * c - v.1 * s, v.0 * s + v.1 * c);
                a[start + k] = (u.0 + t.0, u.1 + t.1);
                a[start + k + len / 2] = (u.0 - t.0, u.1 - t.1);
            }
        }
        len <<= 1;
    }
}

/// The FFT's bit-reversal permutation.
fn bit_reverse(a: &mut [C]) {
    let n = a.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            a.swap(i, j);
        }
    }
}

/// `rho(0..=max_lag)` of `x` (its mean removed here). Empty if `x` has fewer than two
/// values or no variance.
pub fn autocorrelation(x: &[f64], max_lag: usize) -> Vec<f64> {
    let b = x.len();
    if b < 2 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / b as f64;
    let size = (2 * b).next_power_of_two();
    let mut a: Vec<C> = x.iter().map(|&v| (v - mean, 0.0)).collect();
    a.resize(size, (0.0, 0.0));
    fft(&mut a, false);
    a.iter_mut().for_each(|z| *z = (z.0 * z.0 + z.1 * z.1, 0.0));
    fft(&mut a, true);
    // a[j].0 / size = sum_i x_i x_{i+j}.
    let c0 = a[0].0 / size as f64 / b as f64;
    if c0.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    (0..=max_lag.min(b - 1)).map(|j| a[j].0 / size as f64 / (b - j) as f64 / c0).collect()
}

/// The period (in lags, fractional) and the coherence `rho(P)` of `rho` (from
/// [`autocorrelation`]), or `None` if it has no first positive lobe after its first zero
/// crossing.
pub fn period(rho: &[f64]) -> Option<(f64, f64)> {
    let first_negative = rho.iter().position(|&r| r < 0.0)?;
    let lobe_start = first_negative + rho[first_negative..].iter().position(|&r| r > 0.0)?;
    let lobe_len = rho[lobe_start..].iter().position(|&r| r <= 0.0).unwrap_or(rho.len() - lobe_start);
    let lobe = &rho[lobe_start..lobe_start + lobe_len];
    let (k, &peak) = lobe.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).expect("a lobe is not empty");
    let j = lobe_start + k;
    // Parabola through (j-1, j, j+1): vertex offset in (-1/2, 1/2) at a strict maximum.
    let offset = if j >= 1 && j + 1 < rho.len() {
        let (l, r) = (rho[j - 1], rho[j + 1]);
        let curv = l - 2.0 * peak + r;
        if curv < 0.0 { (0.5 * (l - r) / curv).clamp(-0.5, 0.5) } else { 0.0 }
    } else {
        0.0
    };
    Some((j as f64 + offset, peak))
}

/// Half the mean peak-to-trough range over consecutive whole periods of `period` bins
/// (fractional): periods `[round(k P), round((k+1) P))`, each range the largest bin maximum
/// less the smallest bin minimum. With the range of each period also returned. `None` if
/// no whole period fits.
pub fn half_range(bins: &[(f64, f64, f64)], period: f64) -> Option<(f64, Vec<f64>)> {
    // Also refuses NaN.
    if period.is_nan() || period < 1.0 {
        return None;
    }
    let mut ranges = Vec::new();
    let mut k = 0usize;
    loop {
        let (a, b) = ((k as f64 * period).round() as usize, ((k + 1) as f64 * period).round() as usize);
        if b > bins.len() || b <= a {
            break;
        }
        let lo = bins[a..b].iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
        let hi = bins[a..b].iter().map(|x| x.2).fold(f64::NEG_INFINITY, f64::max);
        ranges.push(hi - lo);
        k += 1;
    }
    if ranges.is_empty() {
        return None;
    }
    let mean = ranges.iter().sum::<f64>() / ranges.len() as f64;
    Some((0.5 * mean, ranges))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direct O(B^2) estimate.
    fn direct(x: &[f64], max_lag: usize) -> Vec<f64> {
        let b = x.len();
        let m = x.iter().sum::<f64>() / b as f64;
        let c0 = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / b as f64;
        (0..=max_lag)
            .map(|j| (0..b - j).map(|i| (x[i] - m) * (x[i + j] - m)).sum::<f64>() / (b - j) as f64 / c0)
            .collect()
    }

    /// The transform with each twiddle computed in its stage, `(2 pi/len) k`.
    fn per_stage_fft(a: &mut [C], inverse: bool) {
        let n = a.len();
        bit_reverse(a);
        let sign = if inverse { 1.0 } else { -1.0 };
        let mut len = 2;
        while len <= n {
            let ang = sign * 2.0 * std::f64::consts::PI / len as f64;
            for start in (0..n).step_by(len) {
                for k in 0..len / 2 {
                    let (s, c) = (ang * k as f64).sin_cos();
                    let (u, v) = (a[start + k], a[start + k + len / 2]);
                    let t = (v.0 * c - v.1 * s, v.0 * s + v.1 * c);
                    a[start + k] = (u.0 + t.0, u.1 + t.1);
                    a[start + k + len / 2] = (u.0 - t.0, u.1 - t.1);
                }
            }
            len <<= 1;
        }
    }

    /// The shared twiddle table gives the per-stage transform bit for bit, both ways, at
    /// every size from 1 to 2^14.
    #[test]
    fn fft_is_the_per_stage_fft() {
        for bits in 0..=14 {
            let n = 1usize << bits;
            let x: Vec<C> =
                (0..n).map(|i| (((i * 7919) % 1013) as f64 * 0.37 - 100.0, (i % 13) as f64 - 6.0)).collect();
            for inverse in [false, true] {
                let (mut a, mut b) = (x.clone(), x.clone());
                fft(&mut a, inverse);
                per_stage_fft(&mut b, inverse);
                let bits_of = |v: &[C]| v.iter().flat_map(|z| [z.0.to_bits(), z.1.to_bits()]).collect::<Vec<_>>();
                assert!(bits_of(&a) == bits_of(&b), "n = {n}, inverse = {inverse}");
            }
        }
    }

    #[test]
    fn fft_autocorrelation_equals_the_direct_sum() {
        let x: Vec<f64> = (0..777).map(|i| ((i as f64) * 0.37).sin() + 0.3 * ((i * i % 17) as f64 - 8.0)).collect();
        let a = autocorrelation(&x, 300);
        let b = direct(&x, 300);
        assert_eq!(a.len(), 301);
        for (u, v) in a.iter().zip(&b) {
            assert!((u - v).abs() < 1e-12, "{u} vs {v}");
        }
        assert!(autocorrelation(&[1.0; 10], 5).is_empty());
        assert!(autocorrelation(&[1.0], 5).is_empty());
    }

    #[test]
    fn a_sine_has_its_period_and_full_coherence() {
        // Period 25.3 samples, 40 periods.
        let p = 25.3;
        let x: Vec<f64> = (0..1020).map(|i| 3.0 + 2.0 * (std::f64::consts::TAU * i as f64 / p).sin()).collect();
        let rho = autocorrelation(&x, x.len() / 4);
        let (period, coherence) = period(&rho).unwrap();
        assert!((period - p).abs() < 0.05, "{period}");
        assert!(coherence > 0.99, "{coherence}");
        let bins: Vec<(f64, f64, f64)> = x.iter().map(|&v| (v, v, v)).collect();
        let (half, ranges) = half_range(&bins, period).unwrap();
        assert_eq!(ranges.len(), 40);
        assert!((half - 2.0).abs() < 0.01, "{half}");
    }

    #[test]
    fn a_sawtooth_has_its_period_and_its_drop() {
        // Rises by 1 per sample for 19 samples, drops by 19 at once: period 20.
        let x: Vec<f64> = (0..2000).map(|i| (i % 20) as f64).collect();
        let (period, coherence) = period(&autocorrelation(&x, 500)).unwrap();
        // The peak is a cusp: the parabola places it within a hundredth of a lag.
        assert!((period - 20.0).abs() < 0.01 && coherence > 0.99, "{period} {coherence}");
        let bins: Vec<(f64, f64, f64)> = x.iter().map(|&v| (v, v, v)).collect();
        assert_eq!(half_range(&bins, period).unwrap().0, 9.5);
    }

    #[test]
    fn a_decaying_record_has_no_period() {
        // An AR(1) record with positive correlation: rho(j) = 0.9^j never turns negative.
        let mut x = vec![0.0];
        let mut s = 12345u64;
        for _ in 0..5000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            x.push(0.9 * x.last().unwrap() + u);
        }
        let rho = autocorrelation(&x, 50);
        assert!(rho[..20].iter().all(|&r| r > 0.0));
        assert!(period(&rho[..20]).is_none());
    }
}
