//! The weak-bond candidates' exponent caps and their thinning test, shared by the rupture
//! models and the laws' acceptances.

/// Rates whose exponent `a |x|` exceeds this are treated as infinite: the junction
/// ruptures at once (docs/model.md, "Equations", item 6: a rate that overflows means
/// immediate rupture).
pub const EXPONENT_CAP: f64 = 600.0;
/// Re-base the coordinates before `a |y|` exceeds this, so weights stay finite.
pub const FRAME_EXPONENT_LIMIT: f64 = 64.0;
/// Whether the rate of a junction with anchor `c` overflows with the plate at `y`: its
/// exponent `a |y - c|` or its weight's `a |c|` beyond [`EXPONENT_CAP`] (it ruptures at once).
#[inline]
pub fn overflows(a: f64, c: f64, y: f64) -> bool {
    a * (y - c).abs() > EXPONENT_CAP || anchor_overflows(a, c)
}

/// Whether the weights of anchor `c` overflow: `a |c|` beyond [`EXPONENT_CAP`].
#[inline]
pub fn anchor_overflows(a: f64, c: f64) -> bool {
    a * c.abs() > EXPONENT_CAP
}

/// What a candidate's weights `w = [w0, w1]` (`w0 >= exp(-a c)`, `w1 >= exp(a c)`) say of
/// `e^{a |y - c|}` for every plate position `y_lo <= y <= y_hi` (factors `e_hi = exp(a y_hi)`,
/// `e_lo = exp(-a y_lo)`): it lies between `max(w0 / e_lo, w1 / e_hi)` and
/// `max(e_hi w0, e_lo w1)`.
///
/// For weights known only within `w_lo <= w <= w_hi` (each component; `w_lo = w_hi = w` when
/// exact), the lower end is taken from `w_lo` and the upper from `w_hi`.
#[inline]
pub fn bracket(w_lo: [f64; 2], w_hi: [f64; 2], e_hi: f64, e_lo: f64) -> (f64, f64) {
    ((w_lo[0] / e_lo).max(w_lo[1] / e_hi), (e_hi * w_hi[0]).max(e_lo * w_hi[1]))
}

/// Decides a candidate whose rate `r` (units of `k0`) lies in `[lo_r, hi_r]`, with the
/// uniform product `ub = U b`, without the rate itself: `Some(true)` if `ub < lo_r`,
/// `Some(false)` if `ub >= hi_r`, `None` in between. The margins (1e-9 relative, far above
/// the round-off of the bounds and of the rate) make it agree with the exact test `ub < r`.
#[inline]
pub fn squeeze(ub: f64, lo_r: f64, hi_r: f64) -> Option<bool> {
    if ub < SQUEEZE_LO * lo_r {
        Some(true)
    } else if ub >= SQUEEZE_HI * hi_r {
        Some(false)
    } else {
        None
    }
}

/// Relative margins of the acceptance squeeze: `1 -+ 1e-9`.
const SQUEEZE_LO: f64 = 1.0 - 1e-9;
const SQUEEZE_HI: f64 = 1.0 + 1e-9;

/// The thinning test `U b < r` of a candidate with weights `w = [w0, w1]` (`w0 >= exp(-a c)`,
/// `w1 >= exp(a c)` up to round-off, `w0 w1 = 1` for the sum tree's exact weights) under the
/// factors `e_hi = exp(a y_hi)`, `e_lo = exp(-a y_lo)`, given `ub = U b`: `r = e^{a |y - c|}
/// = max(exp(a y) w0, w1 / exp(a y))` (units of `k0`, `ey()` giving `exp(a y)` at the
/// candidate's time). Squeezed first: with `y_lo <= y <= y_hi`, `r` lies between
/// `max(w0 / e_lo, w1 / e_hi)` and `max(e_hi w0, e_lo w1)`, and a uniform outside decides
/// without the plate's position and its exponential (the margins of [`squeeze`]
/// make both tests agree with the exact one). All factors stay finite: `|a y| <=
/// FRAME_EXPONENT_LIMIT` and `|a c| <= EXPONENT_CAP`. The squeeze may take bounds
/// `w_lo <= w <= w_hi` of the weights ([`bracket`]); the exact test asks for the
/// weights themselves (`w()`), only then.
#[inline]
pub fn accept(
    ub: f64,
    [w_lo, w_hi]: [[f64; 2]; 2],
    e_hi: f64,
    e_lo: f64,
    ey: impl FnOnce() -> f64,
    w: impl FnOnce() -> [f64; 2],
) -> bool {
    let (lo, hi) = bracket(w_lo, w_hi, e_hi, e_lo);
    match squeeze(ub, lo, hi) {
        Some(decided) => decided,
        None => {
            let (w, ey) = (w(), ey());
            ub < (ey * w[0]).max(w[1] / ey)
        }
    }
}
