//! Thinning over one step of a stepped plate (the series stepper): on `[s0, s1]` the plate
//! is proven within `y_lo <= y <= y_hi`, so any weak-bond rupture model's bound under those
//! bounds ([`RuptureModel::bound`]) holds, candidates arrive at its constant rate and each is
//! picked and accepted by the model and the law ([`RuptureRate`]), as on a closed-form
//! plate's channel (docs/engines.md, "Plate between events (tilted law): a series, Taylor
//! steps and a stiff integrator").

use rand_distr::{Distribution, Exp1};

use super::contract::RuptureModel;
use super::rate::RuptureRate;
use crate::engine::EngineError;
use crate::engine::exact::core::bags::Attached;
use crate::rng::Pcg64;

/// Candidates drawn beyond which a run is stalled, whatever its events ([`stalled`]) ...
pub const STALL_CANDIDATES: u64 = 100_000_000;
/// ... plus this many per event.
pub const STALL_PER_EVENT: u64 = 100_000;

/// Whether a run that has drawn `candidates` thinning candidates for `events` events is
/// stalled: more than [`STALL_CANDIDATES`] plus [`STALL_PER_EVENT`] per event. A scene the
/// envelope fits draws about one candidate per event; the tilted law's envelope
/// `exp(a |x|)` exceeds its rate `exp(a (sqrt(x^2 + l0^2) - l0))` by up to `exp(a l0)`,
/// which at a low temperature (`a l0 >> 1`) leaves the acceptance near zero.
pub fn stalled(candidates: u64, events: u64) -> bool {
    candidates > STALL_CANDIDATES.saturating_add(STALL_PER_EVENT.saturating_mul(events))
}

/// The first accepted candidate `(time, slot)` of `model` over the step `[s0, s1]` with bounds
/// `[y_lo, y_hi]`, if any; `y_at(s)` is the plate's position inside the step. The acceptance
/// `r_i / b_i` is at most 1 only while the plate is within the bounds: checked wherever the
/// position is computed (and at an accepted candidate), so that thinning is exact or the run
/// stops. Rates beyond any representable bound within the step rupture a junction at once
/// (docs/model.md, "Equations", item 6), one per call. `candidates` counts the candidates.
#[allow(clippy::too_many_arguments)]
pub fn thin<R: RuptureModel, L: RuptureRate>(
    model: &mut R,
    rng: &mut Pcg64,
    (s0, s1): (f64, f64),
    (y_lo, y_hi): (f64, f64),
    attached: &[Attached],
    law: &L,
    mut y_at: impl FnMut(f64) -> Result<f64, EngineError>,
    candidates: &mut u64,
) -> Result<Option<(f64, usize)>, EngineError> {
    let n_att = attached.len();
    if n_att == 0 || s1 <= s0 {
        return Ok(None);
    }
    let rate = model.bound(y_lo, y_hi);
    if rate.is_nan() {
        return Err(EngineError::NonFinite { t: s0, quantity: "weak-bond thinning envelope", value: rate });
    }
    if rate == f64::INFINITY {
        *candidates += 1;
        return Ok(Some((s0, n_att - 1)));
    }
    if rate == 0.0 {
        return Ok(None);
    }
    let mut position = |s: f64| -> Result<f64, EngineError> {
        let y = y_at(s)?;
        if !(y_lo <= y && y <= y_hi) {
            return Err(EngineError::EnvelopeViolated { t: s, y, lo: y_lo, hi: y_hi });
        }
        Ok(y)
    };
    let mut s = s0;
    loop {
        let e: f64 = Exp1.sample(rng);
        s += e / rate;
        if s >= s1 {
            return Ok(None);
        }
        *candidates += 1;
        let mut seen = None;
        let hit = model.pick(rng, attached, law, || match position(s) {
            Ok(y) => {
                seen = Some(Ok(y));
                y
            }
            Err(e) => {
                seen = Some(Err(e));
                f64::NAN
            }
        });
        let seen = match seen {
            Some(seen) => seen,
            None if hit.is_some() => position(s),
            None => continue,
        };
        seen?;
        if let Some(slot) = hit {
            return Ok(Some((s, slot)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::exact::rupture::binned::BinnedRupture;
    use crate::engine::exact::rupture::rate::TiltedRate;
    use crate::engine::exact::rupture::tree::TreeRupture;
    use crate::physics::{ForceLaw, Tilted};
    use crate::rng::pcg;

    /// Thinning with a single junction at a frozen plate reproduces its tilted rate, with the
    /// tree and with the bins: the number of steps with an accepted event matches the
    /// binomial count of `1 - exp(-r h)` within 4 standard deviations.
    #[test]
    fn thinning_rate_matches_the_tilted_rate() {
        let law = Tilted { kappa: 0.5, l0: 1.0 };
        let rate = TiltedRate::new(law, 2.0);
        let a = 2.0 * law.kappa;
        let mut rng = pcg(7);
        let tree = TreeRupture::new(0.3, a, 4);
        let bins = BinnedRupture::try_new(0.3, a, 4, &mut rng).unwrap();
        check_rate(tree, &rate, &mut rng);
        check_rate(bins, &rate, &mut rng);
    }

    fn check_rate<R: RuptureModel>(mut model: R, rate: &TiltedRate, rng: &mut Pcg64) {
        let mut att = [Attached { c: -0.7, id: 0, bin: 0 }];
        assert!(model.attached(&mut att, 0, -0.7, 0.0));
        let (y, mut cand) = (0.2, 0u64);
        let expected_rate = 0.3 * (rate.beta_dx * rate.law.tension(y - att[0].c)).exp();
        let steps = 200_000;
        let mut count = 0u64;
        for i in 0..steps {
            let s0 = i as f64 * 0.05;
            let span = (s0, s0 + 0.05);
            if thin(&mut model, rng, span, (y - 0.1, y + 0.3), &att, rate, |_| Ok(y), &mut cand).unwrap().is_some() {
                count += 1;
            }
        }
        let p = 1.0 - (-expected_rate * 0.05).exp();
        let (mean, sd) = (p * steps as f64, (steps as f64 * p * (1.0 - p)).sqrt());
        assert!((count as f64 - mean).abs() < 4.0 * sd, "count {count}, expected {mean} +- {sd}");
        assert!(cand >= count);
    }

    /// A plate outside its step's bounds would make the acceptance exceed 1: the thinning
    /// refuses it rather than sample a wrong law.
    #[test]
    fn a_plate_outside_its_bounds_is_refused() {
        let rate = TiltedRate::new(Tilted { kappa: 0.5, l0: 1.0 }, 2.0);
        let mut model = TreeRupture::new(5.0, 1.0, 4);
        let mut att = [Attached { c: -0.7, id: 0, bin: 0 }];
        assert!(model.attached(&mut att, 0, -0.7, 0.0));
        let r = thin(&mut model, &mut pcg(3), (0.0, 10.0), (0.0, 0.1), &att, &rate, |_| Ok(0.2), &mut 0);
        assert!(matches!(r, Err(EngineError::EnvelopeViolated { .. })), "{r:?}");
    }
}
