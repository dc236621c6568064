//! The observers of a run: the core observers every run has, the writers (`trace.csv` and
//! `events.csv` are observers that write), the event observers chosen once per run, and
//! `RunObservers`, all of them together.

use std::path::Path;

use super::error::{RunError, output_error};
use super::progress::Probe;
use crate::observe::regime::RegimeDetector;
use crate::observe::stats::{RuptureForces, WindowStats};
use crate::observe::{JunctionEvent, Nothing, Observer, Piece, Sample, Segment, Stretch};
use crate::output::csv::{CsvFile, EventWriter, FilePos, TraceWriter};
use crate::scene::Scene;

/// The observers every run has: window statistics and the regime detector.
pub type CoreObservers = (WindowStats, RegimeDetector);

/// Builds the core observers for a scene.
pub fn core_observers(scene: &Scene) -> CoreObservers {
    (WindowStats::new(scene.run.t_warmup, scene.run.t_end, scene.junctions.n as u64), RegimeDetector::for_scene(scene))
}

/// The observers of junction events a run may have: none, the rupture-force statistics
/// (weak bonds), the event writer (`output.events`), or both. The type is chosen once per
/// run, so a run that logs no events and has no weak bonds compiles the event path out of
/// the engine.
pub trait EventObservers: Observer {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        None
    }
    fn event_writer(&mut self) -> Option<&mut EventWriter> {
        None
    }
    fn into_event_writer(self) -> Option<EventWriter>;
}

impl EventObservers for Nothing {
    fn into_event_writer(self) -> Option<EventWriter> {
        None
    }
}

impl EventObservers for RuptureForces {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        Some(self)
    }
    fn into_event_writer(self) -> Option<EventWriter> {
        None
    }
}

impl EventObservers for EventWriter {
    fn event_writer(&mut self) -> Option<&mut EventWriter> {
        Some(self)
    }
    fn into_event_writer(self) -> Option<EventWriter> {
        Some(self)
    }
}

impl EventObservers for (EventWriter, RuptureForces) {
    fn rupture_forces(&self) -> Option<&RuptureForces> {
        Some(&self.1)
    }
    fn event_writer(&mut self) -> Option<&mut EventWriter> {
        Some(&mut self.0)
    }
    fn into_event_writer(self) -> Option<EventWriter> {
        Some(self.0)
    }
}

/// The CSV writers a scene asks for.
pub(super) struct Writers {
    pub trace: Option<TraceWriter>,
    pub events: Option<EventWriter>,
}

impl Writers {
    /// No files (a run without an output directory).
    pub fn none() -> Self {
        Writers { trace: None, events: None }
    }

    /// Creates `trace.csv.part` and `events.csv.part` in `dir` as the scene asks (none, or
    /// both, are left on error).
    pub fn create(scene: &Scene, dir: &Path) -> Result<Self, RunError> {
        let trace = match scene.output.trace {
            true => Some(TraceWriter::create(dir).map_err(output_error(dir, TraceWriter::NAME))?),
            false => None,
        };
        let events = match scene.output.events {
            true => match EventWriter::create(dir) {
                Ok(ev) => Some(ev),
                Err(e) => {
                    if let Some(t) = trace {
                        t.0.discard();
                    }
                    return Err(output_error(dir, EventWriter::NAME)(e));
                }
            },
            false => None,
        };
        Ok(Writers { trace, events })
    }

    /// Reopens the partial files of a checkpointed run at the positions it recorded (check
    /// them with [`CsvFile::check_resume`] first).
    pub fn reopen(dir: &Path, trace: Option<&FilePos>, events: Option<&FilePos>) -> Result<Self, RunError> {
        let reopen = |name: &str, pos: &FilePos| CsvFile::resume(dir, name, pos).map_err(output_error(dir, name));
        let trace = match trace {
            Some(p) => Some(TraceWriter(reopen(TraceWriter::NAME, p)?)),
            None => None,
        };
        let events = match events {
            Some(p) => Some(EventWriter(reopen(EventWriter::NAME, p)?)),
            None => None,
        };
        Ok(Writers { trace, events })
    }
}

/// Every observer of a run.
pub(super) struct RunObservers<X> {
    pub core: CoreObservers,
    pub trace: Option<TraceWriter>,
    /// The event observers (which may hold the event writer).
    pub events: X,
    /// Lets the progress display see the simulated time.
    pub probe: Probe,
}

impl<X: EventObservers> Observer for RunObservers<X> {
    // The trace writer and the probe want no events.
    const EVENTS: bool = CoreObservers::EVENTS || X::EVENTS;
    const FORMATIONS: bool = (CoreObservers::EVENTS && CoreObservers::FORMATIONS) || (X::EVENTS && X::FORMATIONS);
    const STRETCHES: bool = CoreObservers::STRETCHES && X::STRETCHES;
    #[inline]
    fn event(&mut self, e: &JunctionEvent) {
        if CoreObservers::EVENTS {
            self.core.event(e);
        }
        if X::EVENTS {
            self.events.event(e);
        }
    }
    #[inline]
    fn segment(&mut self, s: &Segment) {
        self.core.segment(s);
        self.trace.segment(s);
        self.events.segment(s);
        self.probe.segment(s);
    }
    #[inline]
    fn piece(&mut self, p: &Piece) {
        self.core.piece(p);
        self.trace.piece(p);
        self.events.piece(p);
        self.probe.piece(p);
    }
    #[inline]
    fn integrals_after(&self) -> f64 {
        let writers = self.trace.integrals_after().min(self.events.integrals_after());
        self.core.integrals_after().min(writers).min(self.probe.integrals_after())
    }
    #[inline]
    fn stretch_until(&self) -> f64 {
        let writers = self.trace.stretch_until().min(self.events.stretch_until());
        self.core.stretch_until().min(writers).min(self.probe.stretch_until())
    }
    #[inline]
    fn stretch(&mut self, s: &Stretch) {
        self.core.stretch(s);
        self.trace.stretch(s);
        self.events.stretch(s);
        self.probe.stretch(s);
    }
    #[inline]
    fn stop(&mut self) {
        self.core.stop();
        self.trace.stop();
        self.events.stop();
        self.probe.stop();
    }
    fn sample(&mut self, s: &Sample) {
        self.core.sample(s);
        self.trace.sample(s);
        self.events.sample(s);
        self.probe.sample(s);
    }
}

impl<X: EventObservers> RunObservers<X> {
    /// Flushes the writers to the operating system (files stay under their `.part` names).
    pub fn flush(&mut self, dir: &Path) -> Result<(), RunError> {
        if let Some(t) = self.trace.as_mut() {
            t.0.flush().map_err(output_error(dir, TraceWriter::NAME))?;
        }
        if let Some(ev) = self.events.event_writer() {
            ev.0.flush().map_err(output_error(dir, EventWriter::NAME))?;
        }
        Ok(())
    }

    /// Flushes and syncs the writers, and returns how far each file is written.
    pub fn file_positions(&mut self, dir: &Path) -> Result<(Option<FilePos>, Option<FilePos>), RunError> {
        let trace = match self.trace.as_mut() {
            Some(t) => Some(t.0.position().map_err(output_error(dir, TraceWriter::NAME))?),
            None => None,
        };
        let events = match self.events.event_writer() {
            Some(ev) => Some(ev.0.position().map_err(output_error(dir, EventWriter::NAME))?),
            None => None,
        };
        Ok((trace, events))
    }

    /// Renames the files into place (or reports the first write error).
    pub fn commit_files(self, dir: &Path) -> Result<(), RunError> {
        if let Some(t) = self.trace {
            t.0.finish().map_err(output_error(dir, TraceWriter::NAME))?;
        }
        if let Some(ev) = self.events.into_event_writer() {
            ev.0.finish().map_err(output_error(dir, EventWriter::NAME))?;
        }
        Ok(())
    }

    /// Removes the partial files.
    pub fn discard_files(self) {
        if let Some(t) = self.trace {
            t.0.discard();
        }
        if let Some(ev) = self.events.into_event_writer() {
            ev.0.discard();
        }
    }
}
