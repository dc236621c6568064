//! Sizes of the files a run writes, from its expected work ([`super::work`]).

use super::memory::checkpoint_bytes;
use super::work::Work;
use crate::scene::Scene;

/// Bytes of a `trace.csv` row: six numbers in their shortest round-trip form (about 16 to
/// 20 characters each when not round) and separators.
pub const TRACE_ROW_BYTES: u64 = 100;
/// Bytes of an `events.csv` row: time, junction index, kind and two numbers.
pub const EVENT_ROW_BYTES: u64 = 72;
/// Bytes of `summary.json` (at most).
const SUMMARY_BYTES: u64 = 4096;

/// One output file and its expected size.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputFile {
    pub name: &'static str,
    pub bytes: u64,
    /// The scene field (or flag) that asks for the file.
    pub field: &'static str,
}

/// The files a run of `scene` writes with their expected sizes (`checkpoint.bin` twice when
/// `checkpoints`: the new one is written beside the old before it replaces it).
pub fn files(scene: &Scene, work: &Work, checkpoints: bool) -> Vec<OutputFile> {
    let o = &scene.output;
    let mut files = vec![OutputFile { name: "summary.json", bytes: SUMMARY_BYTES, field: "summary" }];
    if o.trace {
        let bytes = TRACE_ROW_BYTES.saturating_mul(work.samples + 1);
        files.push(OutputFile { name: "trace.csv", bytes, field: "output.trace" });
    }
    if o.events {
        let bytes = (EVENT_ROW_BYTES as f64 * work.events).min(u64::MAX as f64) as u64 + 64;
        files.push(OutputFile { name: "events.csv", bytes, field: "output.events" });
    }
    if o.plot {
        // Drawn from at most 2 points per bucket of the time axis.
        let points = work.samples.min(2 * crate::output::TRACE_SVG_BUCKETS as u64);
        files.push(OutputFile { name: "trace.svg", bytes: 30_000 + 120 * points, field: "output.plot" });
    }
    if checkpoints {
        files.push(OutputFile {
            name: "checkpoint.bin",
            bytes: 2 * checkpoint_bytes(scene),
            field: "--checkpoint-every",
        });
    }
    files
}
