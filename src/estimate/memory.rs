//! Memory of a run: the engine's state per junction (from the sizes of the types it stores,
//! so the figures follow the structs) and the buffers that do not grow with `N`.

use std::mem::size_of;

use crate::engine::exact::core::bags::{Attached, Detached};
use crate::engine::exact::rupture::sumtree::SumTree2;
use crate::engine::exact::{self};
use crate::engine::exact::{BinnedRupture, uses_bins};
use crate::physics::ExactMethod;
use crate::scene::laws::{LawVisitor, with_force_law};
use crate::scene::{BondKind, EngineKind, Scene};

/// Resident memory of the program itself before it allocates for a scene: code, libraries,
/// stacks, the allocator's arenas and the runner's fixed buffers (part-file buffers,
/// regime detector, progress). Measured as the peak resident set of a run at `N = 10`
/// (`tests/suite/estimate.rs` measures it again and bounds the difference).
pub const BASELINE_BYTES: u64 = 7 << 20;

/// Buffer of a checkpoint being written (`output::checkpoint`).
const CHECKPOINT_BUFFER: u64 = 1 << 20;
/// The tilted law's series engine: its anchor bins and their O(1) lookup table
/// (`engine::exact::stepper::series::sum`): they cover the spread of the anchors, not `N`; typically well
/// under this allowance (the lookup table alone is capped at 4 MiB).
const SERIES_BINS: u64 = 1 << 20;

/// One buffer of the engine's state: what it holds and its bytes per junction.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub what: &'static str,
    /// Bytes for the whole scene.
    pub bytes: u64,
    /// Bytes per junction (for the sum tree, its bytes over `N`).
    pub per_junction: f64,
}

/// Which method of which engine advances the scene (docs/runs.md, "Memory per junction").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Fixed,
    /// Closed form (linear law).
    ClosedForm,
    /// The tilted law's series engine.
    Series,
    /// Direct summation with DOP853.
    Direct,
}

impl Method {
    pub fn of(scene: &Scene) -> Method {
        struct Which<'a>(&'a Scene);
        impl LawVisitor for Which<'_> {
            type Output = ExactMethod;
            fn visit<L: crate::physics::ForceLaw>(self, _law: L) -> ExactMethod {
                exact::method::<L>(self.0)
            }
        }
        match scene.run.engine {
            EngineKind::Fixed => Method::Fixed,
            EngineKind::Exact => match with_force_law(&scene.junctions, Which(scene)) {
                Ok(ExactMethod::ClosedForm) => Method::ClosedForm,
                Ok(ExactMethod::Series) => Method::Series,
                Ok(ExactMethod::Direct) | Err(_) => Method::Direct,
            },
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Method::Fixed => "fixed-step engine",
            Method::ClosedForm => "exact engine, closed form",
            Method::Series => "exact engine, series",
            Method::Direct => "exact engine, direct sum",
        }
    }
}

/// Bytes per junction of the fixed engine: a state byte `q_i` and an extension `x_i`.
pub const FIXED_PER_JUNCTION: usize = size_of::<u8>() + size_of::<f64>();
/// Bytes per junction of the exact engines' bags: each junction has a slot reserved in the
/// attached bag and in the detached bag.
pub const BAGS_PER_JUNCTION: usize = size_of::<Attached>() + size_of::<Detached>();

/// The engine's buffers that grow with `N`, for `scene`.
pub fn engine_parts(scene: &Scene) -> Vec<Part> {
    let n = scene.junctions.n;
    let part = |what, per: usize| Part { what, bytes: n as u64 * per as u64, per_junction: per as f64 };
    let method = Method::of(scene);
    if method == Method::Fixed {
        return vec![part("junction states and extensions", FIXED_PER_JUNCTION)];
    }
    let mut parts = vec![part("attached and detached bags", BAGS_PER_JUNCTION)];
    if method == Method::Series {
        parts.push(part("series handles", size_of::<u32>()));
    }
    if let Some(store) = RuptureStore::of(scene) {
        let bytes = store.bytes(n);
        parts.push(Part { what: store.name(), bytes, per_junction: bytes as f64 / n.max(1) as f64 });
    }
    parts
}

/// The weak-bond rupture model's store in the exact engine: the closed form and the series
/// thin against bins of anchors from [`BINNED_FROM`](crate::engine::exact::BINNED_FROM)
/// junctions on, against a sum tree below; the direct method, and strong bonds, need none.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RuptureStore {
    Tree,
    Bins,
}

impl RuptureStore {
    fn of(scene: &Scene) -> Option<RuptureStore> {
        if scene.junctions.bond != BondKind::Weak {
            return None;
        }
        match Method::of(scene) {
            Method::ClosedForm | Method::Series if uses_bins(scene.junctions.n) => Some(RuptureStore::Bins),
            Method::ClosedForm | Method::Series => Some(RuptureStore::Tree),
            Method::Fixed | Method::Direct => None,
        }
    }
    fn name(self) -> &'static str {
        match self {
            RuptureStore::Tree => "rupture sum tree",
            RuptureStore::Bins => "rupture bins",
        }
    }
    /// Bytes in memory for `n` junctions.
    fn bytes(self, n: usize) -> u64 {
        match self {
            RuptureStore::Tree => SumTree2::bytes_for(n),
            RuptureStore::Bins => BinnedRupture::bytes_for(n),
        }
    }
    /// Bytes in a checkpoint for `n` junctions: a sum tree node is 77 bytes per 64-byte node.
    fn encoded_bytes(self, n: usize) -> u64 {
        match self {
            RuptureStore::Tree => SumTree2::bytes_for(n) / 64 * 77,
            RuptureStore::Bins => BinnedRupture::encoded_bytes_for(n),
        }
    }
}

/// Buffers that do not grow with `N`, beyond [`BASELINE_BYTES`]: the series engine's bins
/// and a checkpoint's write buffer.
pub fn fixed_buffers(scene: &Scene, checkpoints: bool) -> u64 {
    let series = if Method::of(scene) == Method::Series { SERIES_BINS } else { 0 };
    series + if checkpoints { CHECKPOINT_BUFFER } else { 0 }
}

/// Bytes of `checkpoint.bin` (MessagePack, structs as maps): per junction at most a bag
/// entry with its field names (31 bytes; the series adds a handle, at most 5), the fixed
/// engine's state byte and extension (10), and a sum tree node (77 bytes per 64-byte node) or the rupture bins
/// ([`BinnedRupture::encoded_bytes_for`]); plus 4 KiB of header and plate state.
pub fn checkpoint_bytes(scene: &Scene) -> u64 {
    let n = scene.junctions.n as u64;
    let junctions = match Method::of(scene) {
        Method::Fixed => 10 * n,
        Method::Series => 36 * n,
        _ => 31 * n,
    };
    let rupture = RuptureStore::of(scene).map_or(0, |s| s.encoded_bytes(scene.junctions.n));
    junctions + rupture + 4096
}
