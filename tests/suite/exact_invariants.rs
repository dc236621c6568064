//! Invariants of the exact engine over many seeds and every option combination.

use stickslip::engine::Engine;
use stickslip::observe::{EventKind, Recorder};
use stickslip::runner::Recording;
use stickslip::scene::{BondKind, ForceLawKind};
use stickslip_testkit::{BONDS, LAWS, scene};

fn record(scene: &stickslip::Scene) -> Recording {
    let r = stickslip::runner::record(scene);
    assert!(r.completed(), "{:?}", r.error);
    let c = r.counters.clone();
    let ruptures = r.events.iter().filter(|e| e.kind == EventKind::Rupture).count() as u64;
    assert_eq!(ruptures, c.ruptures);
    assert_eq!(r.events.len() as u64 - ruptures, c.formations);
    assert_eq!(c.events, Some(c.ruptures + c.formations));
    if scene.run.t_end >= 3000.0 {
        assert!(c.rebases.unwrap() >= 1, "the run re-based {:?} times", c.rebases);
    }
    r
}

#[test]
fn event_log_and_samples_are_consistent() {
    let mut runs = 0;
    for bond in BONDS.iter().map(|b| b.name()) {
        for reattach in ["residual", "unstretched"] {
            for initial in ["detached", "attached", "stationary"] {
                for seed in 1..=6u64 {
                    let s = scene(
                        stickslip_testkit::FIG1,
                        &[
                            "run.engine=exact",
                            "junctions.force_law=linear",
                            "junctions.n=60",
                            &format!("junctions.bond={bond}"),
                            &format!("junctions.reattach={reattach}"),
                            &format!("junctions.initial={initial}"),
                            &format!("run.seed={seed}"),
                            "run.t_end=60",
                            "output.sample_dt=0.5",
                        ],
                    );
                    check(&s, &record(&s));
                    runs += 1;
                }
            }
        }
    }
    assert_eq!(runs, 36 * BONDS.len());
}

fn check(s: &stickslip::Scene, r: &Recording) {
    let n = s.junctions.n;
    // Replay the event log from the initial state given by the first sample.
    let mut attached = vec![None::<bool>; n];
    let mut count = r.samples[0].attached as i64;
    let mut last_t = f64::NEG_INFINITY;
    for e in &r.events {
        assert!(e.t > last_t, "event times strictly increase: {} after {}", e.t, last_t);
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
        if now && s.junctions.reattach == stickslip::scene::Reattach::Unstretched {
            assert_eq!(e.extension, 0.0);
        }
    }
    assert_eq!(count, r.samples.last().unwrap().attached as i64, "replayed count equals the final sample");
    // Samples: counts in range, friction = K (V t - X), times on the grid.
    let (k, v) = (s.plate.k, s.plate.v);
    for (i, smp) in r.samples.iter().enumerate() {
        assert!(smp.attached <= n as u64);
        let f = k * (v * smp.t - smp.x);
        assert!((smp.friction - f).abs() <= 1e-9 * k * (smp.x.abs() + v * smp.t + 1.0), "{} vs {f}", smp.friction);
        if i + 1 < r.samples.len() {
            assert!((smp.t - i as f64 * s.output.sample_dt).abs() < 1e-12);
        }
    }
    // Segments tile [0, t_end].
    let mut t = 0.0;
    for seg in &r.segments {
        assert!((seg.t0 - t).abs() <= 1e-12 * (1.0 + t), "segments tile time");
        assert!(seg.t1 >= seg.t0 && seg.friction_m2 >= 0.0);
        t = seg.t1;
    }
    assert!((t - s.run.t_end).abs() < 1e-9);
}

/// The time average of the friction equals that of bond plus viscous force, up to the
/// change of momentum `M (Xd_end - Xd_start) / T` (exact integrals of the exact trajectory).
#[test]
fn window_force_balance() {
    for bond in BONDS.iter().map(|b| b.name()) {
        let s = scene(
            stickslip_testkit::FIG1,
            &["run.engine=exact", "junctions.force_law=linear", &format!("junctions.bond={bond}"), "run.t_end=200"],
        );
        let r = record(&s);
        let t = s.run.t_end;
        let (mut f, mut fb, mut visc) = (0.0, 0.0, 0.0);
        for seg in &r.segments {
            let h = seg.t1 - seg.t0;
            f += seg.friction * h;
            fb += seg.bond_force * h;
            visc += seg.viscous * h;
        }
        let dp = s.plate.mass * (r.samples.last().unwrap().v - r.samples[0].v);
        let residual = (f - fb - visc - dp) / t;
        assert!(residual.abs() < 1e-8 * (f / t).abs().max(1.0), "{bond}: residual {residual}");
    }
}

/// Weak bonds force a re-basing whenever `beta dx kappa |y| > 64`: a long run re-bases many
/// times, and time, samples, segments and the event log must come through intact.
#[test]
fn many_rebasings_keep_every_invariant() {
    for &law in LAWS {
        let t_end = if law == ForceLawKind::Linear { 20_000.0 } else { 12_000.0 };
        let law = law.name();
        let s = scene(
            stickslip_testkit::FIG1,
            &[
                "run.engine=exact",
                &format!("junctions.force_law={law}"),
                "junctions.bond=weak",
                "junctions.n=40",
                &format!("run.t_end={t_end}"),
                "output.sample_dt=10",
            ],
        );
        let r = record(&s);
        check(&s, &r);
        assert_eq!(r.samples.last().unwrap().t, t_end);
    }
}

/// The two event queues (a scan and the `priority-queue` crate) order the same channels the
/// same way, so a run gives the same events and the same final state with either.
#[test]
fn both_event_queues_give_the_same_run() {
    use stickslip::engine::exact::{ArrayQueue, PqQueue, strong_linear, weak_linear};
    for &kind in BONDS {
        let bond = kind.name();
        let s = stickslip_testkit::scaled(2000, ForceLawKind::Linear, kind);
        let (mut a, mut b) = (Recorder::default(), Recorder::default());
        let (sa, sb, ca, cb) = match kind {
            BondKind::Strong => {
                let (mut ea, mut eb) = (strong_linear::<ArrayQueue>(&s), strong_linear::<PqQueue>(&s));
                ea.advance(30.0, &mut a).unwrap();
                eb.advance(30.0, &mut b).unwrap();
                (ea.sample(), eb.sample(), ea.counters(), eb.counters())
            }
            BondKind::Weak => {
                let (mut ea, mut eb) = (weak_linear::<ArrayQueue>(&s), weak_linear::<PqQueue>(&s));
                ea.advance(30.0, &mut a).unwrap();
                eb.advance(30.0, &mut b).unwrap();
                (ea.sample(), eb.sample(), ea.counters(), eb.counters())
            }
        };
        assert!(ca.events.unwrap() > 1000, "{bond}: too few events to compare ({:?})", ca.events);
        assert_eq!(ca, cb, "{bond}: counters differ");
        assert_eq!(format!("{sa:?}"), format!("{sb:?}"), "{bond}: final state differs");
        assert_eq!(a.events.len(), b.events.len());
        for (x, y) in a.events.iter().zip(&b.events) {
            assert_eq!((x.t, x.junction, x.kind), (y.t, y.junction, y.kind), "{bond}: event logs differ");
        }
    }
}
