//! The series engine for the tilted law (`exact.tilted = "series"`): event-log invariants
//! over many seeds (strong and weak bonds, dynamic and kinematic plate), stiff plates at a
//! bounded cost, and agreement with the direct (O(N), DOP853) engine.

mod common;

use common::*;
use stickslip::Scene;
use stickslip::engine::{Counters, Engine, EngineVisitor, with_engine};
use stickslip::observe::{EventKind, Recorder};
use stickslip::runner::{OutputGrid, drive};

fn record(scene: &Scene) -> (Recorder, Counters) {
    struct V<'a>(&'a Scene);
    impl EngineVisitor for V<'_> {
        type Output = (Recorder, Counters);
        fn visit<E: Engine>(self, mut e: E) -> Self::Output {
            let mut r = Recorder::default();
            let grid = OutputGrid::new(self.0, e.time_step());
            drive(&mut e, &grid, &mut r).unwrap();
            (r, e.counters())
        }
    }
    with_engine(scene, V(scene)).unwrap()
}

/// The event log replays to the sampled attached counts, each junction alternates,
/// times strictly increase, segments tile `[0, t_end]`; friction is `K (V t - X)` for a
/// dynamic plate and the bond force with `X = V t` for a kinematic one.
fn check(s: &Scene, r: &Recorder, c: &Counters) {
    let n = s.junctions.n;
    let ruptures = r.events.iter().filter(|e| e.kind == EventKind::Rupture).count() as u64;
    assert_eq!(ruptures, c.ruptures);
    assert_eq!(r.events.len() as u64 - ruptures, c.formations);
    assert_eq!(c.events, Some(c.ruptures + c.formations));
    let mut attached = vec![None::<bool>; n];
    let mut count = r.samples[0].attached as i64;
    let mut last_t = f64::NEG_INFINITY;
    for e in &r.events {
        assert!(e.t >= last_t, "event times increase: {} after {}", e.t, last_t);
        last_t = e.t;
        let j = e.junction as usize;
        let now = e.kind == EventKind::Formation;
        if let Some(was) = attached[j] {
            assert_ne!(was, now, "junction {j} {:?} twice in a row at t = {}", e.kind, e.t);
        }
        attached[j] = Some(now);
        count += if now { 1 } else { -1 };
        assert!((0..=n as i64).contains(&count));
        assert!(e.tension >= 0.0 && e.extension.is_finite());
    }
    assert_eq!(count, r.samples.last().unwrap().attached as i64, "replayed count equals the final sample");
    let (k, v) = (s.plate.k, s.plate.v);
    for smp in &r.samples {
        assert!(smp.attached <= n as u64);
        if s.plate.kinematic {
            assert!((smp.x - v * smp.t).abs() <= 1e-9 * (1.0 + v * smp.t), "X = V t: {} vs {}", smp.x, v * smp.t);
            assert_eq!(smp.friction, smp.bond_force);
            assert_eq!(smp.v, v);
        } else {
            let f = k * (v * smp.t - smp.x);
            assert!((smp.friction - f).abs() <= 1e-9 * k * (smp.x.abs() + v * smp.t + 1.0), "{} vs {f}", smp.friction);
        }
    }
    let mut t = 0.0;
    for seg in &r.segments {
        assert!((seg.t0 - t).abs() <= 1e-12 * (1.0 + t), "segments tile time");
        assert!(seg.t1 >= seg.t0 && seg.friction_m2 >= 0.0 && seg.friction.is_finite());
        if s.plate.kinematic {
            assert_eq!(seg.viscous, 0.0);
            assert_eq!(seg.friction, seg.bond_force);
        }
        t = seg.t1;
    }
    assert!((t - s.run.t_end).abs() < 1e-9);
    assert!(c.series_rebases.is_some() && c.series_error.is_some());
}

#[test]
fn event_log_and_samples_are_consistent() {
    let mut runs = 0;
    for bond in ["strong", "weak"] {
        for kinematic in [false, true] {
            for reattach in ["residual", "unstretched"] {
                for seed in 1..=5u64 {
                    let s = scene(
                        stickslip::testkit::FIG1,
                        &[
                            "run.engine=exact",
                            "junctions.force_law=tilted",
                            "junctions.n=40",
                            "junctions.initial=stationary",
                            &format!("junctions.bond={bond}"),
                            &format!("junctions.reattach={reattach}"),
                            &format!("plate.kinematic={kinematic}"),
                            &format!("run.seed={seed}"),
                            "run.t_end=60",
                            "output.sample_dt=0.5",
                        ],
                    );
                    let (r, c) = record(&s);
                    assert!(c.events.unwrap() > 50, "{bond} kinematic={kinematic}: {:?} events", c.events);
                    check(&s, &r, &c);
                    runs += 1;
                }
            }
        }
    }
    assert_eq!(runs, 40);
}
