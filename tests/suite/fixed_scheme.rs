//! The fixed-step engine against its scheme (docs/engines.md, "The fixed-step engine"):
//! hand-computed flips, an eager reference implementation (bit for bit), chain invariants
//! over many seeds and every option combination, step/stop semantics, the window force
//! balance, determinism and divergence.

use stickslip::Scene;
use stickslip::engine::{Engine, EngineError, EngineVisitor, fixed};
use stickslip::observe::stats::WindowStats;
use stickslip::observe::{EventKind, JunctionEvent, Nothing, Observer, Recorder, Sample, Segment};
use stickslip::physics::{Bond, ForceLaw, Formation, LawVisitor, Strong, Weak};
use stickslip::rng::{self, ParkMiller, UniformSource};
use stickslip::runner::{Observed, Simulation};
use stickslip::scene::laws::with_force_law;
use stickslip::scene::{BondKind, FlipRule, Initial, IntegratorKind, Reattach, RngKind};
use stickslip_testkit::{BONDS, LAWS, Trace, fixed_fig1 as scene, steps as record};

// ---------------------------------------------------------------------------------------
// Park–Miller draw order, by hand.

/// The Park-Miller sequence by hand: `s <- 16807 s mod (2^31 - 1)`, `xi = s / (2^31 - 1)`.
fn park_miller_uniforms(seed: u64, count: usize) -> Vec<f64> {
    const M: u64 = 2_147_483_647;
    let mut s = seed;
    (0..count)
        .map(|_| {
            s = s * 16_807 % M;
            s as f64 / M as f64
        })
        .collect()
}

fn events_of(trace: &Trace) -> Vec<(f64, u32, EventKind)> {
    trace.events.iter().map(|e| (e.t, e.junction, e.kind)).collect()
}

/// A tiny scene whose junctions exert no force (`kappa = 0`) on a plate at rest (`V = 0`),
/// so `g = 1` and the rates are `kon0` and `k0`; `dt = 1`.
fn tiny(n: usize, kon0: f64, k0: f64, extra: &[&str]) -> Scene {
    let (n, kon0, k0) = (format!("junctions.n={n}"), format!("junctions.kon0={kon0}"), format!("junctions.k0={k0}"));
    let mut o = vec![n.as_str(), &kon0, &k0, "junctions.kappa=0", "plate.v=0", "fixed.dt=1", "run.seed=1"];
    o.extend_from_slice(extra);
    scene(&o)
}

#[test]
fn park_miller_draws_reproduce_hand_computed_flips() {
    use EventKind::{Formation as F, Rupture as R};
    // Seed 1 gives xi_1.. = 7.8e-6, 0.1315, 0.7556, 0.4587, 0.5328, 0.2190, 0.0470,
    // 0.6789, 0.6793, 0.9347, 0.3835, 0.5194: one per junction per step, index order.
    let u = park_miller_uniforms(1, 12);
    assert_eq!(u[0], 16_807.0 / 2_147_483_647.0);
    assert_eq!(u[1], 282_475_249.0 / 2_147_483_647.0);

    // N = 2, linear rule, kon0 dt = 0.5, k0 dt = 0.3, all detached:
    // step 0: j0 xi1 < .5 forms, j1 xi2 < .5 forms; step 1: xi3, xi4 >= .3;
    // step 2: j0 xi5 >= .3, j1 xi6 < .3 ruptures; step 3: j0 xi7 < .3 ruptures, j1 xi8 >= .5;
    // step 4: xi9 >= .5, xi10 >= .3; step 5: j0 xi11 < .5 forms, j1 xi12 >= .3.
    let t = record(&tiny(2, 0.5, 0.3, &[]), 6);
    assert_eq!(events_of(&t), vec![(0.0, 0, F), (0.0, 1, F), (2.0, 1, R), (3.0, 0, R), (5.0, 0, F)]);
    assert_eq!(t.samples.iter().map(|s| s.attached).collect::<Vec<_>>(), vec![0, 2, 2, 1, 0, 0, 1]);

    // The same draws, as-printed rule (flip when xi > k dt):
    // step 0: none; step 1: j0 xi3 > .5 forms; step 2: j0 xi5 > .3 ruptures;
    // step 3: j1 xi8 > .5 forms.
    let t = record(&tiny(2, 0.5, 0.3, &["fixed.flip=as-printed"]), 4);
    assert_eq!(events_of(&t), vec![(1.0, 0, F), (2.0, 0, R), (3.0, 1, F)]);

    // Junctions whose rate is 0 still draw: N = 3, kon0 dt = 0.22, k0 = 0.
    // Step 0: j0, j1 form (xi1, xi2), j2 xi3 = .76 does not; from then on j0 and j1 have
    // rate 0 but draw xi4, xi5, so j2 gets xi6 = .2190 < .22 and forms at t = 1. (Had the
    // zero-rate junctions not drawn, j2 would get xi4, xi5, xi6 and form at t = 3.)
    let t = record(&tiny(3, 0.22, 0.0, &[]), 4);
    assert_eq!(events_of(&t), vec![(0.0, 0, F), (0.0, 1, F), (1.0, 2, F)]);

    // initial = "stationary" draws xi1..xi3 at construction (attached iff xi < kon0/(kon0+k0)
    // = 0.5: j0, j1 attached, j2 not); step 0 then uses xi4..xi6:
    // j0 xi4 < .5 ruptures, j1 xi5 >= .5 stays, j2 xi6 < .5 forms.
    let t = record(&tiny(3, 0.5, 0.5, &["junctions.initial=stationary"]), 1);
    assert_eq!(t.samples[0].attached, 2);
    assert_eq!(events_of(&t), vec![(0.0, 0, R), (0.0, 2, F)]);
}

// ---------------------------------------------------------------------------------------
// An eager, unoptimised reference implementation of the scheme (docs/engines.md, "One step,
// from `t_n` to `t_{n+1} = (n + 1) dt`").

/// The scene's force law, whichever it is (built through the law table, so every law of the
/// table is covered): `f(x)`, `f^x(x)` and whether `f^x = kappa x` (`ForceLaw::IS_LINEAR`).
struct LawFns {
    tension: Box<dyn Fn(f64) -> f64>,
    force_x: Box<dyn Fn(f64) -> f64>,
    is_linear: bool,
}

impl LawVisitor for LawFnsOf {
    type Output = LawFns;
    fn visit<L: ForceLaw>(self, law: L) -> LawFns {
        LawFns {
            tension: Box::new(move |x| law.tension(x)),
            force_x: Box::new(move |x| law.force_x(x)),
            is_linear: L::IS_LINEAR,
        }
    }
}

struct LawFnsOf;

fn law_fns(s: &Scene) -> LawFns {
    with_force_law(&s.junctions, LawFnsOf).unwrap()
}

struct Reference {
    s: Scene,
    law: LawFns,
    rng: Box<dyn UniformSource>,
    q: Vec<bool>,
    x: Vec<f64>,
    plate_x: f64,
    plate_v: f64,
    n: u64,
}

impl Reference {
    fn new(s: &Scene) -> Reference {
        let mut rng: Box<dyn UniformSource> = match s.fixed.rng {
            RngKind::ParkMiller => Box::new(ParkMiller::new(s.run.seed).unwrap()),
            RngKind::Pcg => Box::new(rng::pcg(s.run.seed)),
        };
        let j = &s.junctions;
        let q = (0..j.n)
            .map(|_| match j.initial {
                Initial::Detached => false,
                Initial::Attached => true,
                Initial::Stationary => rng.uniform() < j.kon0 / (j.kon0 + j.k0),
            })
            .collect();
        Reference { s: s.clone(), law: law_fns(s), rng, q, x: vec![0.0; j.n], plate_x: 0.0, plate_v: 0.0, n: 0 }
    }
    fn tension(&self, x: f64) -> f64 {
        (self.law.tension)(x)
    }
    fn force_x(&self, x: f64) -> f64 {
        (self.law.force_x)(x)
    }
    fn k_off(&self, x: f64) -> f64 {
        match self.s.junctions.bond {
            BondKind::Strong => Strong::from_scene(&self.s).k_off(self.tension(x)),
            BondKind::Weak => Weak::from_scene(&self.s).k_off(self.tension(x)),
        }
    }
    /// `F_b` with every attached junction at `x_i + shift`, summed as documented: each
    /// chunk of `CHUNK` junctions in index order, then the chunk sums in chunk order. For a
    /// law with `f^x = kappa x` the engine's documented closed form `f^x(sum_i q_i x_i)` is used.
    fn bond_force(&self, shift: f64) -> f64 {
        let chunk_sum = |(qs, xs): (&[bool], &[f64])| {
            let attached = qs.iter().zip(xs).filter(|(q, _)| **q).map(|(_, x)| x + shift);
            if self.law.is_linear {
                attached.fold(0.0, |a, x| a + x)
            } else {
                attached.fold(0.0, |a, x| a + self.force_x(x))
            }
        };
        let sum = self.q.chunks(fixed::CHUNK).zip(self.x.chunks(fixed::CHUNK)).map(chunk_sum).fold(0.0, |a, c| a + c);
        if self.law.is_linear { self.force_x(sum) } else { sum }
    }
    fn sample(&self) -> Sample {
        let (p, t) = (&self.s.plate, self.n as f64 * self.s.fixed.dt);
        Sample {
            t,
            x: self.plate_x,
            v: self.plate_v,
            friction: p.k * (p.v * t - self.plate_x),
            bond_force: self.bond_force(0.0),
            attached: self.q.iter().filter(|q| **q).count() as u64,
            n: self.q.len() as u64,
        }
    }
    fn step(&mut self, events: &mut Vec<JunctionEvent>) -> Segment {
        let dt = self.s.fixed.dt;
        let t = self.n as f64 * dt;
        let t1 = (self.n + 1) as f64 * dt;
        let j = self.s.junctions.clone();
        let kon = Formation::from_scene(&self.s).k_on(self.plate_v);
        for i in 0..self.q.len() {
            let xi = self.rng.uniform();
            let k = if self.q[i] { self.k_off(self.x[i]) } else { kon };
            let flip = match self.s.fixed.flip {
                FlipRule::Linear => xi < (k * dt).min(1.0),
                FlipRule::Exponential => xi < -(-k * dt).exp_m1(),
                FlipRule::AsPrinted => xi > k * dt,
            };
            if flip {
                let kind = if self.q[i] { EventKind::Rupture } else { EventKind::Formation };
                self.q[i] = !self.q[i];
                if kind == EventKind::Formation && j.reattach == Reattach::Unstretched {
                    self.x[i] = 0.0;
                }
                let x = self.x[i];
                events.push(JunctionEvent { t, junction: i as u32, kind, extension: x, tension: self.tension(x) });
            }
        }
        let fb = self.bond_force(0.0);
        let p = self.s.plate.clone();
        let (x0, v0) = (self.plate_x, self.plate_v);
        let u0 = x0 - p.v * t;
        let a = -(p.eta * v0 + fb + p.k * u0) / p.mass;
        let (x1, v1, visc) = if p.mass == 0.0 {
            let v = -(fb + p.k * u0) / p.eta;
            (x0 + dt * v, v, v)
        } else {
            match self.s.fixed.integrator {
                IntegratorKind::SemiImplicitEuler => {
                    let v = v0 + dt * a;
                    (x0 + dt * v, v, v0)
                }
                IntegratorKind::ExplicitEuler => (x0 + dt * v0, v0 + dt * a, v0),
                IntegratorKind::VelocityVerlet => {
                    let x1 = x0 + dt * v0 + 0.5 * dt * dt * a;
                    let fb1 = self.bond_force(x1 - x0);
                    let rhs = v0 + 0.5 * dt * (a + (-fb1 - p.k * (x1 - p.v * t1)) / p.mass);
                    (x1, rhs / (1.0 + 0.5 * dt * p.eta / p.mass), v0)
                }
            }
        };
        let seg = Segment {
            t0: t,
            t1,
            friction: p.k * (p.v * t - x0),
            friction_m2: 0.0,
            bond_force: fb,
            viscous: p.eta * visc,
            attached: self.q.iter().filter(|q| **q).count() as u64,
        };
        let dx = x1 - x0;
        for i in 0..self.q.len() {
            if self.q[i] {
                self.x[i] += dx;
            } else {
                self.x[i] *= 1.0 - j.lambda * dt;
            }
        }
        self.plate_x = x1;
        self.plate_v = v1;
        self.n += 1;
        seg
    }
}

/// Every option combination, as `--set` overrides.
fn all_combinations() -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for law in LAWS.iter().map(|l| l.name()) {
        for bond in BONDS.iter().map(|b| b.name()) {
            for rng in ["park-miller", "pcg"] {
                for flip in ["linear", "exponential", "as-printed"] {
                    for integ in ["semi-implicit-euler", "explicit-euler", "velocity-verlet", "overdamped"] {
                        for reattach in ["residual", "unstretched"] {
                            for initial in ["detached", "attached", "stationary"] {
                                let (integ, mass) =
                                    if integ == "overdamped" { ("semi-implicit-euler", "0") } else { (integ, "75") };
                                out.push(vec![
                                    format!("junctions.force_law={law}"),
                                    format!("junctions.bond={bond}"),
                                    format!("fixed.rng={rng}"),
                                    format!("fixed.flip={flip}"),
                                    format!("fixed.integrator={integ}"),
                                    format!("plate.mass={mass}"),
                                    format!("junctions.reattach={reattach}"),
                                    format!("junctions.initial={initial}"),
                                ]);
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

/// Small, stable variants of Fig. 1 (`dt = 0.2`, `N = 16`) for option combination `combo`.
fn small(combo: &[String], seed: u64) -> Scene {
    let seed = format!("run.seed={seed}");
    let mut o: Vec<&str> = combo.iter().map(String::as_str).collect();
    o.extend_from_slice(&["junctions.n=16", "fixed.dt=0.2", &seed]);
    scene(&o)
}

fn same(a: f64, b: f64, exact: bool) -> bool {
    if exact { a.to_bits() == b.to_bits() } else { (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs())) }
}

#[test]
fn engine_matches_an_eager_reference_bit_for_bit() {
    let steps = 60;
    for combo in all_combinations() {
        for seed in [3, 77] {
            let s = small(&combo, seed);
            // Velocity Verlet with the linear law uses the closed form
            // F_b' = kappa (sum_i q_i x_i + N_att dX), the reference sums kappa (x_i + dX): round-off apart.
            let exact =
                !(law_fns(&s).is_linear && s.fixed.integrator == IntegratorKind::VelocityVerlet && s.plate.mass > 0.0);
            let got = record(&s, steps);
            assert!(got.error.is_none(), "{combo:?}: {:?}", got.error);
            let mut r = Reference::new(&s);
            let mut events = Vec::new();
            let mut want_samples = vec![r.sample()];
            let mut want_segments = Vec::new();
            for _ in 0..steps {
                want_segments.push(r.step(&mut events));
                want_samples.push(r.sample());
            }
            let ctx = format!("{combo:?} seed {seed}");
            assert_eq!(got.samples.len(), want_samples.len(), "{ctx}");
            for (g, w) in got.samples.iter().zip(&want_samples) {
                assert!(g.t == w.t && g.attached == w.attached && g.n == w.n, "{ctx}: {g:?} vs {w:?}");
                for (a, b) in [(g.x, w.x), (g.v, w.v), (g.friction, w.friction), (g.bond_force, w.bond_force)] {
                    assert!(same(a, b, exact), "{ctx}: sample {g:?} vs {w:?}");
                }
            }
            for (g, w) in got.segments.iter().zip(&want_segments) {
                assert!(g.t0 == w.t0 && g.t1 == w.t1 && g.attached == w.attached && g.friction_m2 == 0.0, "{ctx}");
                for (a, b) in [(g.friction, w.friction), (g.bond_force, w.bond_force), (g.viscous, w.viscous)] {
                    assert!(same(a, b, exact), "{ctx}: segment {g:?} vs {w:?}");
                }
            }
            assert_eq!(got.events.len(), events.len(), "{ctx}");
            for (g, w) in got.events.iter().zip(&events) {
                assert!(g.t == w.t && g.junction == w.junction && g.kind == w.kind, "{ctx}: {g:?} vs {w:?}");
                assert!(
                    same(g.extension, w.extension, exact) && same(g.tension, w.tension, exact),
                    "{ctx}: {g:?} vs {w:?}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Threads: the pass shared by a team, at N above the threshold.

/// A scene large enough for a team (`N > PARALLEL_MIN`, several chunks and a short last
/// one), every law and bond kind, both inertial integrators (velocity Verlet sums `F_b`
/// twice a step) and both generators: after every step the plate, `F_b` and the counters,
/// and at the end every junction's `q_i` and `x_i`, are bit for bit those of the eager
/// reference (one draw at a time, in index order, `F_b` summed chunk by chunk) on 1, 2 and
/// 3 threads.
#[test]
fn threads_give_the_eager_reference_bit_for_bit() {
    use stickslip::physics::{Linear, Tilted};
    let n = fixed::PARALLEL_MIN + 2 * fixed::CHUNK + 123;
    let steps = 6;
    struct Check<'a> {
        s: &'a Scene,
        steps: usize,
    }
    impl Check<'_> {
        fn run<L: ForceLaw, B: Bond, R>(&self, law: L, bond: B, rng: R)
        where
            R: UniformSource
                + Clone
                + std::fmt::Debug
                + serde::Serialize
                + serde::de::DeserializeOwned
                + Send
                + 'static,
        {
            let s = self.s;
            let mut r = Reference::new(s);
            let mut events = Vec::new();
            let mut want = vec![r.sample()];
            for _ in 0..self.steps {
                r.step(&mut events);
                want.push(r.sample());
            }
            for threads in [1, 2, 3] {
                let ctx =
                    format!("{} {} {:?} {:?} on {threads} threads", L::NAME, B::NAME, s.fixed.rng, s.fixed.integrator);
                let mut e = fixed::FixedEngine::new(s, law, bond, rng.clone(), fixed::LinearFlip);
                e.set_threads(threads);
                let mut got = vec![e.sample()];
                for k in 1..=self.steps {
                    e.advance(k as f64 * s.fixed.dt, &mut Nothing).unwrap();
                    got.push(e.sample());
                }
                assert_eq!(got, want, "{ctx}");
                let c = e.counters();
                let ruptures = events.iter().filter(|ev| ev.kind == EventKind::Rupture).count() as u64;
                assert_eq!((c.ruptures, c.formations), (ruptures, events.len() as u64 - ruptures), "{ctx}");
                for i in 0..s.junctions.n {
                    assert_eq!(e.is_attached(i), r.q[i], "{ctx}: junction {i}");
                    assert_eq!(e.extension(i).to_bits(), r.x[i].to_bits(), "{ctx}: junction {i}");
                }
            }
        }
    }
    for extra in [
        &["fixed.integrator=semi-implicit-euler"][..],
        &["fixed.integrator=velocity-verlet"],
        &["fixed.integrator=velocity-verlet", "fixed.rng=pcg"],
    ] {
        let n = format!("junctions.n={n}");
        let mut o = vec![n.as_str(), "fixed.dt=0.1", "junctions.initial=stationary", "junctions.reattach=unstretched"];
        o.extend_from_slice(extra);
        for law in ["linear", "tilted"] {
            for bond in ["strong", "weak"] {
                let (law_o, bond_o) = (format!("junctions.force_law={law}"), format!("junctions.bond={bond}"));
                let mut o = o.clone();
                o.extend_from_slice(&[&law_o, &bond_o]);
                let s = scene(&o);
                // Linear law and velocity Verlet: the engine's closed form for F_b' differs
                // from the reference's sum in rounding; the first-order scheme is compared.
                if law == "linear" && s.fixed.integrator == IntegratorKind::VelocityVerlet {
                    continue;
                }
                let check = Check { s: &s, steps };
                let seed = s.run.seed;
                match (law, bond, s.fixed.rng) {
                    (_, _, RngKind::Pcg) if law == "tilted" && bond == "weak" => {
                        check.run(Tilted::from_scene(&s), Weak::from_scene(&s), rng::pcg(seed))
                    }
                    (_, _, RngKind::Pcg) => continue,
                    ("linear", "strong", _) => {
                        check.run(Linear::from_scene(&s), Strong::from_scene(&s), ParkMiller::new(seed).unwrap())
                    }
                    ("linear", _, _) => {
                        check.run(Linear::from_scene(&s), Weak::from_scene(&s), ParkMiller::new(seed).unwrap())
                    }
                    (_, "strong", _) => {
                        check.run(Tilted::from_scene(&s), Strong::from_scene(&s), ParkMiller::new(seed).unwrap())
                    }
                    _ => check.run(Tilted::from_scene(&s), Weak::from_scene(&s), ParkMiller::new(seed).unwrap()),
                }
            }
        }
    }
}

/// `stickslip run --threads 1, 2, 3` write the same files, byte for byte (`summary.json`
/// apart from `wall_seconds`), at `N` above the threshold; `--threads 0` is refused.
#[test]
fn run_output_does_not_depend_on_threads() {
    const BIN: &str = env!("CARGO_BIN_EXE_stickslip");
    let n = format!("junctions.n={}", fixed::PARALLEL_MIN + fixed::CHUNK / 2);
    let dirs: Vec<tempfile::TempDir> = (0..3).map(|_| tempfile::tempdir().unwrap()).collect();
    for law in ["linear", "tilted"] {
        for (threads, dir) in (1..=3).zip(&dirs) {
            let law = format!("junctions.force_law={law}");
            let mut args = vec!["run", "scenarios/fig1.toml", "--threads"];
            let t = threads.to_string();
            args.push(&t);
            for set in [
                n.as_str(),
                &law,
                "fixed.dt=0.1",
                "run.t_end=5",
                "junctions.initial=stationary",
                "output.sample_dt=0.1",
            ] {
                args.extend(["--set", set]);
            }
            let out = dir.path().join("out");
            let out_s = out.to_str().unwrap();
            args.extend(["--out", out_s]);
            let o =
                std::process::Command::new(BIN).args(&args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        let read = |d: &tempfile::TempDir, f: &str| std::fs::read(d.path().join("out").join(f)).unwrap();
        let summary = |d: &tempfile::TempDir| {
            let mut v: serde_json::Value = serde_json::from_slice(&read(d, "summary.json")).unwrap();
            assert!(v.as_object_mut().unwrap().remove("wall_seconds").is_some());
            v
        };
        for d in &dirs[1..] {
            let trace = read(d, "trace.csv");
            assert!(trace.len() > 1000 && trace == read(&dirs[0], "trace.csv"), "{law}: trace.csv differs");
            assert_eq!(summary(d), summary(&dirs[0]), "{law}");
        }
    }
    let o = std::process::Command::new(BIN)
        .args(["run", "scenarios/fig1.toml", "--threads", "0", "--out"])
        .arg(dirs[0].path().join("refused"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&o.stderr).trim().lines().count(), 1);
    assert!(!dirs[0].path().join("refused").exists());
}

// ---------------------------------------------------------------------------------------
// Chain invariants.

#[test]
fn chain_invariants_hold_for_every_option_and_many_seeds() {
    let steps = 50;
    let combos = all_combinations();
    for seed in 1..=50u64 {
        for combo in &combos {
            let s = small(combo, seed);
            let ctx = format!("{combo:?} seed {seed}");
            let t = record(&s, steps);
            assert!(t.error.is_none(), "{ctx}: {:?}", t.error);
            let (n, dt, p) = (s.junctions.n as u64, s.fixed.dt, &s.plate);
            // Samples: one per step, at t = k dt, finite, 0 <= attached <= N, F = K (V t - X).
            assert_eq!(t.samples.len() as u64, steps + 1, "{ctx}");
            for (k, smp) in t.samples.iter().enumerate() {
                assert_eq!(smp.t, k as f64 * dt, "{ctx}");
                assert!(smp.attached <= n && smp.n == n, "{ctx}");
                assert!([smp.x, smp.v, smp.friction, smp.bond_force].iter().all(|v| v.is_finite()), "{ctx}");
                let f = p.k * (p.v * smp.t - smp.x);
                assert!((smp.friction - f).abs() <= 1e-12 * (p.k * (p.v * smp.t).abs() + p.k * smp.x.abs()), "{ctx}");
            }
            // Segments tile [0, t_end], one per step.
            assert_eq!(t.segments.len() as u64, steps, "{ctx}");
            for (k, seg) in t.segments.iter().enumerate() {
                assert!(seg.t0 == k as f64 * dt && seg.t1 == (k + 1) as f64 * dt, "{ctx}");
                assert!(seg.attached <= n && seg.friction == t.samples[k].friction, "{ctx}");
                // After step k's flips = the count sampled at t_{k+1}.
                assert_eq!(seg.attached, t.samples[k + 1].attached, "{ctx}");
            }
            assert_eq!(t.times, (1..=steps).map(|k| k as f64 * dt).collect::<Vec<_>>(), "{ctx}");
            // Replay the event log: formation only of detached, rupture only of attached.
            let mut state: Vec<Option<bool>> = match s.junctions.initial {
                Initial::Detached => vec![Some(false); n as usize],
                Initial::Attached => vec![Some(true); n as usize],
                Initial::Stationary => vec![None; n as usize],
            };
            let mut attached = t.samples[0].attached as i64;
            let mut last: Option<(f64, u32)> = None;
            let (mut ruptures, mut formations) = (0, 0);
            let mut per_step = vec![0i64; steps as usize];
            for e in &t.events {
                // Times are step starts; within a step, junctions in index order.
                let k = (e.t / dt).round() as usize;
                assert_eq!(e.t, k as f64 * dt, "{ctx}");
                if let Some((lt, lj)) = last {
                    assert!(e.t > lt || (e.t == lt && e.junction > lj), "{ctx}: order");
                }
                last = Some((e.t, e.junction));
                let st = &mut state[e.junction as usize];
                let was_attached = e.kind == EventKind::Rupture;
                assert!(st.is_none_or(|a| a == was_attached), "{ctx}: {e:?} contradicts the junction's state");
                *st = Some(!was_attached);
                if e.kind == EventKind::Rupture {
                    ruptures += 1;
                    per_step[k] -= 1;
                } else {
                    formations += 1;
                    per_step[k] += 1;
                    if s.junctions.reattach == Reattach::Unstretched {
                        assert_eq!(e.extension, 0.0, "{ctx}");
                    }
                }
                assert!(e.extension.is_finite() && e.tension >= 0.0, "{ctx}");
            }
            for (k, (change, seg)) in per_step.iter().zip(&t.segments).enumerate() {
                attached += change;
                assert_eq!(attached as u64, seg.attached, "{ctx}: step {k}");
            }
            assert_eq!(
                (t.counters.ruptures, t.counters.formations, t.counters.steps),
                (ruptures, formations, Some(steps)),
                "{ctx}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Stop semantics.

/// The engine's time after each of a series of stops.
fn stops(s: &Scene) -> Vec<f64> {
    let mut e = Simulation::new(s).unwrap();
    let mut out = vec![e.time()];
    for stop in [0.0, 0.29, 0.3, 0.3 + 1e-12, 0.31, 1.0, 1.0 - 1e-11, 2.55] {
        e.advance(stop).unwrap();
        out.push(e.time());
    }
    assert_eq!(e.time_step(), Some(0.1));
    assert_eq!(e.counters().steps, Some((e.time() / 0.1).round() as u64));
    out
}

#[test]
fn advance_stops_on_the_first_step_boundary_at_or_after_the_stop() {
    let s = scene(&["fixed.dt=0.1"]);
    let t = stops(&s);
    let steps: Vec<u64> = t.iter().map(|t| (t / 0.1).round() as u64).collect();
    // 0.3 is 3 steps although 3 * 0.1 = 0.30000000000000004 > 0.3; 0.3 + 1e-12 too (within 1e-9 dt).
    assert_eq!(steps, vec![0, 0, 3, 3, 3, 4, 10, 10, 26]);
    for (k, t) in steps.iter().zip(&t) {
        assert_eq!(*t, *k as f64 * 0.1, "t = n dt from the integer count");
    }
}

// ---------------------------------------------------------------------------------------
// Window force balance: mean(F) = mean(F_b) + mean(eta Xd) + M (Xd_end - Xd_start) / T.

struct Balance {
    t_warmup: f64,
    t_end: f64,
    mass: f64,
}

struct Sums {
    stats: WindowStats,
    /// `sum_n (F_n - F_b,n - eta v_n) h`.
    residual: f64,
    /// `sum_n (|F_n| + |F_b,n| + |eta v_n|) h`.
    scale: f64,
}

impl Observer for Sums {
    fn segment(&mut self, s: &Segment) {
        self.stats.segment(s);
        let h = s.t1 - s.t0;
        self.residual += (s.friction - s.bond_force - s.viscous) * h;
        self.scale += (s.friction.abs() + s.bond_force.abs() + s.viscous.abs()) * h;
    }
}

impl Balance {
    /// `(Xd at the window start, Xd at its end, sums, sum_n M |Xd_n|)` of a run of `s`.
    fn of(self, s: &Scene) -> (f64, f64, Sums, f64) {
        let mut e = Simulation::new(s).unwrap();
        e.advance(self.t_warmup).unwrap();
        let start = e.sample().v;
        let dt = e.time_step().unwrap();
        let mut sums = Sums { stats: WindowStats::new(self.t_warmup, self.t_end, 1), residual: 0.0, scale: 0.0 };
        let mut momentum_scale = self.mass * start.abs();
        let mut rec = Recorder::default();
        while e.time() < self.t_end - 1e-9 * dt {
            e.advance_observed(e.time() + dt, Observed::Recorder(&mut rec)).unwrap();
            rec.segments.drain(..).for_each(|g| sums.segment(&g));
            rec.events.clear();
            momentum_scale += self.mass * e.sample().v.abs();
        }
        (start, e.sample().v, sums, momentum_scale)
    }
}

/// `(residual, round-off bound, residual of the window means times T)` of the balance.
fn balance(s: &Scene) -> (f64, f64, f64) {
    let (t_warmup, t_end, m) = (s.run.t_warmup, s.run.t_end, s.plate.mass);
    let (v0, v1, sums, momentum_scale) = Balance { t_warmup, t_end, mass: m }.of(s);
    let momentum = m * (v1 - v0);
    let residual = sums.residual - momentum;
    // Per step the identity F_n = F_b,n + eta v_n + M (v_{n+1} - v_n)/dt holds up to a few
    // roundings of each term; summed over the steps (worst case, no cancellation):
    let bound = 8.0 * f64::EPSILON * (sums.scale + momentum_scale);
    let st = &sums.stats;
    let t = t_end - t_warmup;
    let means = (st.friction_mean() - st.bond_force_mean() - st.viscous_mean()) * t - momentum;
    (residual, bound, means)
}

#[test]
fn window_force_balance_is_exact_for_the_euler_integrators() {
    for integ in ["semi-implicit-euler", "explicit-euler"] {
        for extra in [
            &["junctions.force_law=tilted"][..],
            &["junctions.force_law=linear", "junctions.bond=weak"],
            &["plate.mass=0"],
            &["plate.eta=0", "fixed.dt=0.1"],
        ] {
            let integ = format!("fixed.integrator={integ}");
            let mut o = vec![integ.as_str(), "fixed.dt=0.25", "run.t_end=300", "run.t_warmup=100.5", "run.seed=9"];
            o.extend_from_slice(extra);
            let s = scene(&o);
            let (residual, bound, means) = balance(&s);
            assert!(residual.abs() <= bound, "{o:?}: residual {residual} > {bound}");
            // The runner's window statistics (time-weighted means) satisfy it too.
            assert!(means.abs() <= 4.0 * bound, "{o:?}: window means off by {means} (bound {bound})");
        }
    }
    // Velocity Verlet's velocity update is trapezoidal: the left-point identity is not exact
    // for it, and this check is able to tell.
    let s = scene(&["fixed.integrator=velocity-verlet", "fixed.dt=0.25", "run.t_end=300", "run.t_warmup=100.5"]);
    let (residual, bound, _) = balance(&s);
    assert!(residual.abs() > 1e3 * bound, "{residual} vs {bound}");
}

// ---------------------------------------------------------------------------------------
// Determinism.

#[test]
fn same_scene_and_seed_give_identical_output() {
    for extra in [
        &[][..],
        &["fixed.rng=pcg", "run.seed=12345678901", "junctions.bond=weak", "fixed.dt=0.1"],
        &[
            "junctions.force_law=linear",
            "fixed.integrator=velocity-verlet",
            "fixed.dt=0.1",
            "junctions.initial=stationary",
        ],
    ] {
        let mut o = vec!["output.events=true", "run.t_warmup=20"];
        o.extend_from_slice(extra);
        let s = scene(&o);
        let dirs = [tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap()];
        for d in &dirs {
            stickslip::run_scene(&s, Some(d.path())).unwrap();
        }
        for f in ["trace.csv", "events.csv"] {
            let a = std::fs::read(dirs[0].path().join(f)).unwrap();
            let b = std::fs::read(dirs[1].path().join(f)).unwrap();
            assert!(a.len() > 100 && a == b, "{extra:?}: {f} differs");
        }
        let json = |d: &tempfile::TempDir| {
            let mut v: serde_json::Value =
                serde_json::from_slice(&std::fs::read(d.path().join("summary.json")).unwrap()).unwrap();
            assert!(v.as_object_mut().unwrap().remove("wall_seconds").is_some());
            v
        };
        assert_eq!(json(&dirs[0]), json(&dirs[1]), "{extra:?}");
    }
}

/// A checkpoint (serde round trip) resumes to exactly the same run.
struct Checkpoint;
impl EngineVisitor for Checkpoint {
    type Output = ();
    fn visit<E: Engine>(self, mut e: E) {
        e.advance(7.0, &mut Nothing).unwrap();
        // JSON floats read back exactly only with serde_json's `float_roundtrip` feature.
        let json = serde_json::to_string(&e).unwrap();
        let mut resumed: E = serde_json::from_str(&json).unwrap();
        assert_eq!(json, serde_json::to_string(&resumed).unwrap());
        let (mut a, mut b) = (stickslip::observe::Recorder::default(), stickslip::observe::Recorder::default());
        e.advance(20.0, &mut a).unwrap();
        resumed.advance(20.0, &mut b).unwrap();
        assert_eq!(e.sample(), resumed.sample());
        assert!(!a.events.is_empty());
        assert_eq!(a.events, b.events);
        assert_eq!(a.segments, b.segments);
        assert_eq!(e.counters(), resumed.counters());
    }
}

#[test]
fn a_serialized_engine_resumes_identically() {
    for extra in [&["fixed.dt=0.5"][..], &["junctions.bond=weak", "fixed.rng=pcg", "fixed.dt=0.5"]] {
        fixed::dispatch(&scene(extra), Checkpoint).unwrap();
    }
}

// ---------------------------------------------------------------------------------------
// Divergence.

#[test]
fn divergence_is_reported_with_its_step_and_no_nan_is_output() {
    for integ in ["semi-implicit-euler", "explicit-euler", "velocity-verlet"] {
        let integ = format!("fixed.integrator={integ}");
        // omega dt ~ 14 (K = 150, M = 75, dt = 10): far beyond every explicit stability limit.
        let s = scene(&[&integ, "fixed.dt=10", "run.t_end=1e6", "junctions.force_law=linear", "plate.eta=1"]);
        let t = record(&s, 100_000);
        let Some(EngineError::Diverged { step, t: at, quantity, value }) = t.error else {
            panic!("{integ}: expected divergence, got {:?}", t.error)
        };
        assert!(step >= 1 && at == step as f64 * 10.0, "{integ}: step {step} at t = {at}");
        assert!(["X", "Xd", "F_b", "eta Xd", "F"].contains(&quantity), "{quantity}");
        assert!(!value.is_finite() || value.abs() > fixed::DIVERGENCE_LIMIT, "{value}");
        // Steps 1..step-1 were reported, step `step` was not.
        assert_eq!(t.segments.len() as u64, step - 1);
        for smp in &t.samples {
            assert!([smp.x, smp.v, smp.friction, smp.bond_force].iter().all(|v| v.is_finite()));
        }
        for seg in &t.segments {
            assert!([seg.friction, seg.bond_force, seg.viscous].iter().all(|v| v.is_finite()));
        }
        // Through the runner: an error, and no trace or summary left behind.
        let dir = tempfile::tempdir().unwrap();
        let err = stickslip::run_scene(&s, Some(dir.path())).unwrap_err();
        assert!(err.to_string().contains(&format!("step {step}")), "{err}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{integ}: output left behind");
    }
}

/// A stiff drive (`K = 1e9`) turns a plate displacement far below `1e100` into a friction
/// force far above it: `scenarios/stiff.toml`'s plate under velocity Verlet at 1.01 times
/// its limit. The run stops with the divergence error as soon as a force it reports passes
/// `1e100` (here `F = K (V t - X)`, while `|X|` is still about `1e91`), and no sample or
/// segment before holds a force, position or velocity beyond the limit.
#[test]
fn a_force_beyond_the_divergence_limit_stops_the_run() {
    let base = scene(&[
        "plate.mass=1e-6",
        "plate.eta=100",
        "plate.k=1e9",
        "fixed.integrator=velocity-verlet",
        "junctions.initial=stationary",
        "run.t_end=1",
    ]);
    let limit = fixed::stability::analyse(&base).selected().dt_unstable;
    let s = base.with_overrides(&[format!("fixed.dt={}", 1.01 * limit)]).unwrap();
    let t = record(&s, 30_000);
    let Some(EngineError::Diverged { step, quantity, value, .. }) = t.error else {
        panic!("expected divergence, got {:?}", t.error)
    };
    assert_eq!(quantity, "F", "{value:e} at step {step}");
    assert!(value.abs() > fixed::DIVERGENCE_LIMIT);
    let last = t.samples.last().unwrap();
    assert!(last.x.abs() < 1e-6 * fixed::DIVERGENCE_LIMIT, "X = {:e}", last.x);
    let within = |v: f64| v.is_finite() && v.abs() <= fixed::DIVERGENCE_LIMIT;
    for smp in &t.samples {
        assert!([smp.x, smp.v, smp.friction, smp.bond_force].into_iter().all(within), "{smp:?}");
    }
    for seg in &t.segments {
        assert!([seg.friction, seg.bond_force, seg.viscous].into_iter().all(within), "{seg:?}");
    }
    // A kinematic plate has no plate equation to diverge: its large forces are the scene's.
    let kinematic =
        scene(&["plate.kinematic=true", "junctions.kappa=1e200", "fixed.dt=0.5", "junctions.force_law=linear"]);
    let t = record(&kinematic, 40);
    assert!(t.error.is_none(), "{:?}", t.error);
    assert!(t.segments.iter().any(|seg| seg.bond_force > fixed::DIVERGENCE_LIMIT));
}

// ---------------------------------------------------------------------------------------
// The Park–Miller period.

/// A run that draws more numbers than the Park–Miller period `2^31 - 2` is told so: a
/// warning on stderr before it starts and on the summary lines, and `rng_period_exceeded`
/// in `summary.json`. The scene shows why: `N = 99962 = 2 151 331` divides the period, so
/// from step 21483 on every junction draws the numbers of step 0 again; with a kinematic
/// plate, strong bonds, `kon0 dt >= 1` (a detached junction forms surely) and
/// `reattach = "unstretched"`, the junctions' state forgets its past within a few dozen
/// steps, and the trace repeats itself row for row 21483 steps later.
#[test]
fn a_run_beyond_the_park_miller_period_is_warned_about() {
    const BIN: &str = env!("CARGO_BIN_EXE_stickslip");
    const PERIOD: u64 = 2_147_483_646;
    let n: u64 = 99_962;
    let lap = PERIOD / n;
    assert_eq!(lap * n, PERIOD);
    let steps = lap + 200;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (n_set, t_end) = (format!("junctions.n={n}"), format!("run.t_end={steps}"));
    let mut args = vec!["run", "scenarios/fig1.toml", "--out", out.to_str().unwrap()];
    for set in [
        n_set.as_str(),
        &t_end,
        "plate.kinematic=true",
        "junctions.force_law=linear",
        "junctions.reattach=unstretched",
        "junctions.kon0=1000",
        "output.plot=false",
    ] {
        args.extend(["--set", set]);
    }
    let o = std::process::Command::new(BIN).args(&args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{stderr}");
    let draws = n * steps;
    let warning = format!(
        "warning: the run draws {draws} numbers from the Park-Miller generator, 1.009 times its period of 2147483646"
    );
    assert!(stderr.lines().any(|l| l.starts_with(&warning)), "stderr: {stderr}");
    assert!(stdout.lines().any(|l| l.starts_with(&warning)), "stdout: {stdout}");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["rng_period_exceeded"], serde_json::json!({ "draws": draws, "period": PERIOD }));
    // `validate` says so too, as a comment of its scene file.
    args[0] = "validate";
    args.drain(2..4);
    let v = std::process::Command::new(BIN).args(&args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    let report = String::from_utf8_lossy(&v.stdout);
    assert!(v.status.success() && report.lines().any(|l| l.starts_with(&format!("# {warning}"))), "{report}");
    // The stream did repeat: rows 150..200 come back 21483 steps later (t, x apart).
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let rows: Vec<Vec<&str>> = trace.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len() as u64, steps + 1);
    for k in 150..200 {
        assert_eq!(rows[k][3..], rows[k + lap as usize][3..], "row {k}");
    }
}
