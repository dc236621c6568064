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
//! computed with a real FFT (realfft; Wiener–Khinchin, zero-padded to a power of two of at
//! least `2B`: no wrap-around). A signal `p(t) + e(t)`, with `p` periodic of period `P` and `e` noise
//! uncorrelated with it and with itself over a lag `P`, has `rho(P) = var p / (var p +
//! var e)`: the **coherence** `rho(P)` is the fraction of the variance that repeats after one
//! period. A stationary Gaussian process has, instead, `rho(P) = e^{-gamma P}` for its
//! damped oscillation of rate `gamma`.
//!
//! The **period** is the lag of the highest autocorrelation in its first positive lobe after
//! the first zero crossing (refined by a parabola through the three highest lags). A record
//! whose autocorrelation does not return above zero within a quarter of its length has no
//! period.

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

/// `rho(0..=max_lag)` of `x` (its mean removed here). Empty if `x` has fewer than two
/// values or no variance.
pub fn autocorrelation(x: &[f64], max_lag: usize) -> Vec<f64> {
    let b = x.len();
    if b < 2 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / b as f64;
    let size = (2 * b).next_power_of_two();
    let mut planner = RealFftPlanner::<f64>::new();
    let (forward, inverse) = (planner.plan_fft_forward(size), planner.plan_fft_inverse(size));
    let mut a = forward.make_input_vec();
    a.iter_mut().zip(x).for_each(|(a, &v)| *a = v - mean);
    let mut spectrum = forward.make_output_vec();
    forward.process(&mut a, &mut spectrum).expect("buffers of the planned lengths");
    // |X_k|^2 is real: the inverse's first and last entries have no imaginary part.
    spectrum.iter_mut().for_each(|z| *z = Complex::new(z.norm_sqr(), 0.0));
    inverse.process(&mut spectrum, &mut a).expect("buffers of the planned lengths");
    // a[j] / size = sum_i x_i x_{i+j} (the inverse does not scale).
    let c0 = a[0] / size as f64 / b as f64;
    if c0.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    (0..=max_lag.min(b - 1)).map(|j| a[j] / size as f64 / (b - j) as f64 / c0).collect()
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

/// Half the mean peak-to-trough range over consecutive whole periods of `period` buckets
/// (fractional): periods `[round(k P), round((k+1) P))`, each range the largest bucket maximum
/// less the smallest bucket minimum. With the range of each period also returned. `None` if
/// no whole period fits.
pub fn half_range(buckets: &[(f64, f64, f64)], period: f64) -> Option<(f64, Vec<f64>)> {
    // Also refuses NaN.
    if period.is_nan() || period < 1.0 {
        return None;
    }
    let mut ranges = Vec::new();
    let mut k = 0usize;
    loop {
        let (a, b) = ((k as f64 * period).round() as usize, ((k + 1) as f64 * period).round() as usize);
        if b > buckets.len() || b <= a {
            break;
        }
        let lo = buckets[a..b].iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
        let hi = buckets[a..b].iter().map(|x| x.2).fold(f64::NEG_INFINITY, f64::max);
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

    /// At every length from 2 to 70 and at lengths around powers of two up to 2^13 (the
    /// padded size is `2B` exactly or nearly `4B`), noisy periodic records: the transform's
    /// autocorrelation is the direct sum's to rounding, and so are the period and coherence.
    #[test]
    fn the_real_fft_gives_the_direct_sums_period_at_every_length() {
        let mut s = 7u64;
        let mut noise = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let lengths = (2..=70).chain((4..=13).flat_map(|k| [(1 << k) - 1, 1 << k, (1 << k) + 1]));
        let mut periods = 0;
        for b in lengths {
            let p = 3.0 + (b % 11) as f64;
            let x: Vec<f64> =
                (0..b).map(|i| 1e3 + (std::f64::consts::TAU * i as f64 / p).sin() + 0.8 * noise()).collect();
            let lag = b / 4;
            let (fft, exact) = (autocorrelation(&x, lag), direct(&x, lag));
            assert_eq!(fft.len(), exact.len());
            for (u, v) in fft.iter().zip(&exact) {
                assert!((u - v).abs() < 1e-12, "B = {b}: {u} vs {v}");
            }
            match (period(&fft), period(&exact)) {
                (Some((p1, c1)), Some((p2, c2))) => {
                    assert!((p1 - p2).abs() < 1e-9 && (c1 - c2).abs() < 1e-12, "B = {b}: {p1} {c1} vs {p2} {c2}");
                    periods += 1;
                }
                (None, None) => {}
                (a, e) => panic!("B = {b}: {a:?} vs {e:?}"),
            }
        }
        assert!(periods > 60, "{periods} records had a period");
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
        let buckets: Vec<(f64, f64, f64)> = x.iter().map(|&v| (v, v, v)).collect();
        let (half, ranges) = half_range(&buckets, period).unwrap();
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
        let buckets: Vec<(f64, f64, f64)> = x.iter().map(|&v| (v, v, v)).collect();
        assert_eq!(half_range(&buckets, period).unwrap().0, 9.5);
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
