//! The estimate of one run: its memory, work and output files, and their text.

use std::path::Path;

use super::memory::{self, BASELINE_BYTES, Method, Part};
use super::outputs::{self, OutputFile};
use super::system::{available_memory, free_disk};
use super::work::{self, Work};
use crate::scene::Scene;

/// What a run of a scene is expected to need.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub n: usize,
    pub method: Method,
    /// The engine's buffers that grow with `N`.
    pub parts: Vec<Part>,
    /// Buffers of the run that do not grow with `N`, beyond [`BASELINE_BYTES`].
    pub buffer_bytes: u64,
    pub work: Work,
    pub files: Vec<OutputFile>,
}

impl Estimate {
    /// The estimate for a run of `scene` (with checkpoints when `checkpoints`).
    pub fn of(scene: &Scene, checkpoints: bool) -> Estimate {
        let work = work::expected(scene);
        Estimate {
            n: scene.junctions.n,
            method: Method::of(scene),
            parts: memory::engine_parts(scene),
            buffer_bytes: memory::fixed_buffers(scene, checkpoints),
            files: outputs::files(scene, &work, checkpoints),
            work,
        }
    }
    /// Bytes of the engine's state.
    pub fn engine_bytes(&self) -> u64 {
        self.parts.iter().map(|p| p.bytes).sum()
    }
    /// Bytes one run adds to the program: engine state and buffers.
    pub fn run_bytes(&self) -> u64 {
        self.engine_bytes().saturating_add(self.buffer_bytes)
    }
    /// Peak memory of a process running it: [`BASELINE_BYTES`] and [`Estimate::run_bytes`].
    pub fn peak_bytes(&self) -> u64 {
        BASELINE_BYTES.saturating_add(self.run_bytes())
    }
    /// Bytes of all output files.
    pub fn output_bytes(&self) -> u64 {
        self.files.iter().fold(0u64, |a, f| a.saturating_add(f.bytes))
    }
    /// The per-junction breakdown, e.g. `40 B per junction (attached and detached bags)`.
    pub fn per_junction(&self) -> String {
        let total: f64 = self.parts.iter().map(|p| p.per_junction).sum();
        let each = self.parts.iter().map(|p| format!("{} {:.1} B", p.what, p.per_junction)).collect::<Vec<_>>();
        format!("{total:.1} B per junction: {}", each.join(", "))
    }
    /// The block `stickslip validate` prints, as `#` comment lines; `out` is the output
    /// directory a run would write to.
    pub fn report(&self, out: &Path) -> Vec<String> {
        let mut lines = vec![format!(
            "# estimate: peak memory {} = engine {} ({}, N = {}; {}) + buffers {} + program {}",
            bytes(self.peak_bytes()),
            bytes(self.engine_bytes()),
            self.method.name(),
            self.n,
            self.per_junction(),
            bytes(self.buffer_bytes),
            bytes(BASELINE_BYTES),
        )];
        lines.push(match available_memory() {
            Some(a) => format!("# estimate: memory available {} ({})", bytes(a.bytes), a.source),
            None => "# estimate: memory available: unknown".to_string(),
        });
        let w = &self.work;
        let steps = w.steps.map(|s| format!("{s} steps, ")).unwrap_or_default();
        lines.push(format!(
            "# estimate: work {steps}{:.3e} junction events expected (rates at zero force and the drive velocity), {} output samples",
            w.events, w.samples
        ));
        let files = self.files.iter().map(|f| format!("{} {}", f.name, bytes(f.bytes))).collect::<Vec<_>>();
        let free = free_disk(out).map(bytes).unwrap_or_else(|| "unknown".to_string());
        lines.push(format!(
            "# estimate: outputs {} = {}; free on the disk of {}: {free}",
            bytes(self.output_bytes()),
            files.join(", "),
            crate::scene::error::printable(&out.display().to_string())
        ));
        lines
    }
}

/// `bytes` in binary units, 3 significant figures (`512 B`, `40.0 MiB`, `1.50 TiB`).
pub fn bytes(b: u64) -> String {
    const UNITS: [&str; 7] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    match (u, v) {
        (0, _) => format!("{b} B"),
        (_, v) if v < 10.0 => format!("{v:.2} {}", UNITS[u]),
        (_, v) if v < 100.0 => format!("{v:.1} {}", UNITS[u]),
        _ => format!("{v:.0} {}", UNITS[u]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_are_written_in_binary_units() {
        assert_eq!(bytes(512), "512 B");
        assert_eq!(bytes(40 << 20), "40.0 MiB");
        assert_eq!(bytes(3 << 29), "1.50 GiB");
        assert_eq!(bytes(u64::MAX), "16.0 EiB");
    }
}
