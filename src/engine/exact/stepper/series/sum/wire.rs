//! The series' serialised form (checkpoints): [`Wire`], and the conversions that drop and
//! rebuild what is derived (the grid-index cache, direct mode's position table and orders).

use serde::{Deserialize, Serialize};

use super::SeriesSum;
use super::bins::{Bin, Dense};
use super::bound::{Q_D, Q_NARROW, Q_WIDE, tails};
use super::coefficients::PMAX;
use super::direct::{Direct, DirectWire};
use super::graded::Grades;
use crate::physics::Tilted;

/// Serialized form of `SeriesSum`. `n_rb` and `resid` are absent from checkpoints written
/// before the O(p) update: such a state is read as re-based with every present junction
/// counted through the bins (`n_rb = n`, `resid = 0`), which is what it was. Direct mode
/// writes `direct` and no `bins`, `free`, `index` (a reader that knows only the bins then
/// refuses the state instead of misreading it). Bins mode names its bins' ratio only for
/// narrow bins: a state that names none has wide ones (`q = 1/4`); a ratio that is neither
/// is refused.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Wire {
    law: Tilted,
    p: usize,
    base: f64,
    origin: f64,
    base_off: f64,
    n: u64,
    x0: [f64; 2],
    a: [f64; PMAX],
    al: [f64; PMAX],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bins: Option<Vec<Bin>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    free: Option<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    index: Option<Vec<(i64, u32)>>,
    roff: f64,
    spread: f64,
    #[serde(default)]
    n_rb: Option<u64>,
    #[serde(default)]
    resid: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    direct: Option<DirectWire>,
    /// Direct mode's series holds each junction to its own order (graded orders). Absent
    /// from checkpoints written before them, whose series is then rebuilt on reading.
    #[serde(default)]
    graded: bool,
    /// The bins' ratio `q`, written for narrow bins only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ratio: Option<f64>,
}

/// A checkpoint's series whose bins' ratio is not one the series knows.
#[derive(Debug, thiserror::Error)]
#[error("series bins' ratio {0} is not {Q_WIDE} or {Q_NARROW}")]
pub(super) struct RatioError(f64);

impl TryFrom<Wire> for SeriesSum {
    type Error = RatioError;
    fn try_from(w: Wire) -> Result<SeriesSum, RatioError> {
        let q = match (w.direct.is_some(), w.ratio) {
            (true, _) => Q_D,
            (false, None) => Q_WIDE,
            (false, Some(q)) if q == Q_NARROW || q == Q_WIDE => q,
            (false, Some(q)) => return Err(RatioError(q)),
        };
        let p = w.p.min(PMAX - 1);
        let mut s = SeriesSum {
            law: w.law,
            p,
            q,
            tails: tails(q, p),
            base: w.base,
            origin: w.origin,
            base_off: w.base_off,
            n: w.n,
            x0: w.x0,
            a: w.a,
            al: w.al,
            bins: w.bins.unwrap_or_default(),
            free: w.free.unwrap_or_default(),
            index: w.index.unwrap_or_default(),
            roff: w.roff,
            spread: w.spread,
            n_rb: w.n_rb.unwrap_or(w.n),
            resid: w.resid,
            dense: Dense::default(),
            direct: w.direct.map(|d| Direct::from_wire(d, Grades::new(w.law.l0, w.p.min(PMAX - 1)))),
        };
        if s.direct.is_some() && !w.graded {
            // Written with every junction to order `p`: rebuilt at its base with graded
            // orders, so that a removal subtracts what the series holds.
            s.rebase_direct(s.base);
        }
        if let Some(&(j, slot)) = s.index.last() {
            let index = std::mem::take(&mut s.index);
            s.dense.set(j, slot, &index);
            s.index = index;
        }
        Ok(s)
    }
}

impl From<SeriesSum> for Wire {
    fn from(s: SeriesSum) -> Wire {
        let bins_mode = s.direct.is_none();
        Wire {
            law: s.law,
            p: s.p,
            base: s.base,
            origin: s.origin,
            base_off: s.base_off,
            n: s.n,
            x0: s.x0,
            a: s.a,
            al: s.al,
            bins: bins_mode.then_some(s.bins),
            free: bins_mode.then_some(s.free),
            index: bins_mode.then_some(s.index),
            roff: s.roff,
            spread: s.spread,
            n_rb: Some(s.n_rb),
            resid: s.resid,
            direct: s.direct.map(|d| DirectWire { e: d.e, handle: d.handle, free: d.free }),
            graded: !bins_mode,
            ratio: (bins_mode && s.q != Q_WIDE).then_some(s.q),
        }
    }
}
