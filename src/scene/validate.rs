//! Validation: [`SceneFile`] (what the user wrote) to [`Scene`] (typed, checked parameters).
//! Defaults and allowed ranges here are the ones documented in `docs/scenes.md`.

use super::error::{SceneError, compact};
use super::file::SceneFile;
use super::params::*;
use super::thermal::{Coefficients, Reference, in_force};
use crate::physics::ExactMethod;

/// Largest Park–Miller seed: the state must lie in `[1, 2^31 - 2]`.
pub const PARK_MILLER_SEED_MAX: u64 = (1 << 31) - 2;
/// Largest number of junctions (junction indices are stored as `u32`).
pub const N_MAX: usize = u32::MAX as usize;
/// Largest number of output samples a run may ask for.
pub const SAMPLES_MAX: f64 = 1e9;
/// Largest number of fixed steps a run may ask for.
pub const STEPS_MAX: f64 = 1e15;
/// Largest number of junction events a run may be expected to take
/// ([`crate::estimate::work::expected`]; at 1e7 events per second, three years).
pub const EVENTS_MAX: f64 = 1e15;
/// Largest lower bound on the exact engine's plate-integrator steps (tilted law) a run may
/// need: beyond it the run would take days (docs/scenes.md).
pub const TILTED_STEPS_MAX: f64 = 1e9;

/// A lower bound on the steps the exact engine's explicit plate integrator (DOP853, tilted
/// law) takes over `[0, t_end]`, whatever the events: its step is capped at
/// `2 sqrt(M / (K + kappa N))` (`2 eta / (K + kappa N)` when `M = 0`) and, on a stiff plate,
/// limited by stability to about `6 M / eta` (DOP853's stability interval on the negative
/// real axis is about `[-6, 0]`, and the plate's fast eigenvalue is `-eta/M`).
pub fn tilted_min_steps(plate: &PlateParams, kappa_n: f64, t_end: f64) -> f64 {
    let k = plate.k + kappa_n;
    let mut h = f64::INFINITY;
    if plate.mass > 0.0 {
        if plate.eta > 0.0 {
            h = h.min(6.0 * plate.mass / plate.eta);
        }
        if k > 0.0 {
            h = h.min(2.0 * (plate.mass / k).sqrt());
        }
    } else if k > 0.0 {
        h = 2.0 * plate.eta / k;
    }
    t_end / h
}

fn finite_ge(field: &'static str, v: f64, lo: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v >= lo {
        Ok(v)
    } else {
        Err(SceneError::invalid(field, v, format!("must be a finite number >= {lo}")))
    }
}

fn finite_gt(field: &'static str, v: f64, lo: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > lo {
        Ok(v)
    } else {
        Err(SceneError::invalid(field, v, format!("must be a finite number > {lo}")))
    }
}

impl SceneFile {
    /// Checks every field, fills in defaults and returns the typed scene.
    pub fn validate(&self, name: &str) -> Result<Scene, SceneError> {
        let j = &self.junctions;
        let n = j.n.unwrap_or(300);
        if n == 0 || n > N_MAX {
            return Err(SceneError::invalid("junctions.n", n, format!("must be a whole number from 1 to {N_MAX}")));
        }
        let mut junctions = JunctionParams {
            n,
            bond: j.bond.unwrap_or(BondKind::Strong),
            force_law: j.force_law.unwrap_or(ForceLawKind::Tilted),
            kappa: finite_ge("junctions.kappa", j.kappa.unwrap_or(0.1), 0.0)?,
            l0: finite_gt("junctions.l0", j.l0.unwrap_or(1.0), 0.0)?,
            lambda: finite_ge("junctions.lambda", j.lambda.unwrap_or(0.1), 0.0)?,
            reattach: j.reattach.unwrap_or(Reattach::Residual),
            k0: finite_ge("junctions.k0", j.k0.unwrap_or(0.1), 0.0)?,
            kon0: finite_ge("junctions.kon0", j.kon0.unwrap_or(0.1), 0.0)?,
            tau0: finite_gt("junctions.tau0", j.tau0.unwrap_or(2.0), 0.0)?,
            alpha: finite_gt("junctions.alpha", j.alpha.unwrap_or(1.0), 0.0)?,
            dx: finite_ge("junctions.dx", j.dx.unwrap_or(1.0), 0.0)?,
            temperature: finite_gt("junctions.temperature", j.temperature.unwrap_or(1.0), 0.0)?,
            initial: j.initial.unwrap_or(Initial::Detached),
            e_off: j.e_off.unwrap_or(0.0),
            e_on: j.e_on.unwrap_or(0.0),
            kappa_slope: j.kappa_slope.unwrap_or(0.0),
        };
        let p = &self.plate;
        let mut plate = PlateParams {
            mass: finite_ge("plate.mass", p.mass.unwrap_or(75.0), 0.0)?,
            eta: finite_ge("plate.eta", p.eta.unwrap_or(75.0), 0.0)?,
            k: finite_ge("plate.k", p.k.unwrap_or(150.0), 0.0)?,
            v: finite_ge("plate.v", p.v.unwrap_or(0.5), 0.0)?,
            kinematic: p.kinematic.unwrap_or(false),
            k_slope: p.k_slope.unwrap_or(0.0),
            eta_slope: p.eta_slope.unwrap_or(0.0),
        };
        // The temperature map (scene::thermal), once: from here on `junctions` and `plate`
        // hold the values in force at the scene's temperature, the ones every check below
        // and every engine sees.
        let reference = thermal_map(&mut junctions, &mut plate)?;
        // The law's and the bond kind's own checks (scene::laws), after the common ones above.
        let law =
            super::laws::check(&junctions).map_err(|(field, e)| SceneError::invalid(field, e.value, e.allowed))?;
        if junctions.initial == Initial::Stationary && junctions.k0 + junctions.kon0 == 0.0 {
            return Err(SceneError::invalid(
                "junctions.initial",
                "stationary",
                "needs junctions.k0 + junctions.kon0 > 0 (the stationary attached probability is kon0/(kon0+k0))",
            ));
        }

        if !plate.kinematic && plate.mass == 0.0 && plate.eta == 0.0 {
            return Err(SceneError::invalid(
                "plate.eta",
                0,
                "must be > 0 when plate.mass = 0 (an overdamped plate needs damping)",
            ));
        }

        // The plate's stiffness with every junction attached, `K + kappa N`, is a number.
        let kappa_n = junctions.kappa * n as f64;
        if !(plate.k + kappa_n).is_finite() {
            let (field, value) =
                if kappa_n.is_finite() { ("plate.k", plate.k) } else { ("junctions.kappa", junctions.kappa) };
            return Err(SceneError::invalid(
                field,
                value,
                format!(
                    "makes plate.k + junctions.kappa N overflow (N = {n}; {:e} + {:e}): the plate's stiffness with every junction attached must be a finite number",
                    plate.k, kappa_n
                ),
            ));
        }

        let r = &self.run;
        let t_end = finite_gt("run.t_end", r.t_end.unwrap_or(150.0), 0.0)?;
        let t_warmup = finite_ge("run.t_warmup", r.t_warmup.unwrap_or(0.0), 0.0)?;
        if t_warmup >= t_end {
            return Err(SceneError::invalid(
                "run.t_warmup",
                t_warmup,
                format!("must be less than run.t_end ({})", compact(t_end)),
            ));
        }
        let run =
            RunParams { engine: r.engine.unwrap_or(EngineKind::Exact), t_end, t_warmup, seed: r.seed.unwrap_or(1) };

        let f = &self.fixed;
        let fixed = FixedParams {
            dt: finite_gt("fixed.dt", f.dt.unwrap_or(1.0), 0.0)?,
            rng: f.rng.unwrap_or(RngKind::ParkMiller),
            flip: f.flip.unwrap_or(FlipRule::Linear),
            integrator: f.integrator.unwrap_or(IntegratorKind::SemiImplicitEuler),
        };
        if run.engine == EngineKind::Fixed {
            if t_end / fixed.dt > STEPS_MAX {
                return Err(SceneError::invalid(
                    "fixed.dt",
                    fixed.dt,
                    format!("gives more than {STEPS_MAX:e} steps over run.t_end ({})", compact(t_end)),
                ));
            }
            // The engine steps up to `t_end - STEP_SLACK dt` (`FixedParams::step_limit`): a
            // window that ends before its first step, or starts after its last, holds no
            // step, and its averages would be 0 / 0.
            let limit = FixedParams::step_limit(fixed.dt, t_end);
            if limit <= 0.0 {
                return Err(SceneError::invalid(
                    "run.t_end",
                    t_end,
                    format!(
                        "must be more than {:e} fixed.dt = {} with run.engine = \"fixed\" (the engine steps up to run.t_end less that, so a shorter run takes no step)",
                        FixedParams::STEP_SLACK,
                        compact(FixedParams::STEP_SLACK * fixed.dt)
                    ),
                ));
            }
            if t_warmup >= limit {
                return Err(SceneError::invalid(
                    "run.t_warmup",
                    t_warmup,
                    format!(
                        "must be less than run.t_end - {:e} fixed.dt = {} with run.engine = \"fixed\" (the engine steps up to that time, so a later window holds no step)",
                        FixedParams::STEP_SLACK,
                        compact(limit)
                    ),
                ));
            }
            // The relaxation step `x *= 1 - lambda dt` of detached junctions amplifies their
            // extensions by |1 - lambda dt| > 1 per step beyond this: refused, never run
            // (docs/stability.md; docs/scenes.md, "Errors").
            if junctions.lambda * fixed.dt > 2.0 {
                return Err(SceneError::invalid(
                    "fixed.dt",
                    fixed.dt,
                    format!(
                        "must be <= 2 / junctions.lambda = {:e} with run.engine = \"fixed\" (junctions.lambda * fixed.dt = {:e} > 2 makes the relaxation step x *= 1 - lambda dt of detached junctions unstable)",
                        2.0 / junctions.lambda,
                        junctions.lambda * fixed.dt
                    ),
                ));
            }
            if fixed.rng == RngKind::ParkMiller && !(1..=PARK_MILLER_SEED_MAX).contains(&run.seed) {
                return Err(SceneError::invalid(
                    "run.seed",
                    run.seed,
                    format!(
                        "must be in [1, {PARK_MILLER_SEED_MAX}] for the Park-Miller generator (fixed.rng = \"park-miller\")"
                    ),
                ));
            }
        }

        let e = &self.exact;
        let exact = ExactParams {
            rtol: e.rtol.unwrap_or(1e-10),
            atol: e.atol.unwrap_or(1e-12),
            tilted: e.tilted.unwrap_or_default(),
        };
        if !(exact.rtol.is_finite() && (1e-14..=1e-2).contains(&exact.rtol)) {
            return Err(SceneError::invalid("exact.rtol", exact.rtol, "must be a number from 1e-14 to 1e-2"));
        }
        finite_gt("exact.atol", exact.atol, 0.0)?;

        let o = &self.output;
        let sample_dt = match o.sample_dt {
            Some(s) => finite_gt("output.sample_dt", s, 0.0)?,
            None => default_sample_dt(t_end, run.engine, fixed.dt),
        };
        if t_end / sample_dt > SAMPLES_MAX {
            return Err(SceneError::invalid(
                "output.sample_dt",
                sample_dt,
                format!("gives more than {SAMPLES_MAX:e} samples over run.t_end ({})", compact(t_end)),
            ));
        }
        // Last: a cost check across sections (plate, junctions, run), after every field is
        // checked on its own.
        let exact_engine = run.engine == EngineKind::Exact;
        let by_choice = law.exact == ExactMethod::Series && exact.tilted == TiltedMethod::Direct;
        let direct = exact_engine && (by_choice || law.exact == ExactMethod::Direct);
        if direct && plate.kinematic && !by_choice {
            return Err(SceneError::invalid(
                "plate.kinematic",
                true,
                format!(
                    "cannot be true with junctions.force_law = \"{}\" on the exact engine (its direct method integrates the plate equation)",
                    law.name
                ),
            ));
        }
        if direct && plate.kinematic {
            return Err(SceneError::invalid(
                "exact.tilted",
                "direct",
                "cannot run plate.kinematic = true (the direct method integrates the plate equation); use exact.tilted = \"series\"",
            ));
        }
        if direct {
            let (lo, hi) = law.stiffness;
            let steps = tilted_min_steps(&plate, hi.max(-lo) * junctions.n as f64, t_end);
            if steps > TILTED_STEPS_MAX {
                return Err(SceneError::invalid(
                    "run.t_end",
                    t_end,
                    format!(
                        "needs at least {steps:.1e} steps of the exact engine's explicit plate integrator ({} law; more than {TILTED_STEPS_MAX:e}): its step is bounded by 6 M/eta and 2 sqrt(M/(K + kappa N)) (2 eta/(K + kappa N) when M = 0); shorten the run, use plate.mass = 0 for the limit M/eta -> 0, or junctions.force_law = \"linear\" (closed form)",
                        law.name
                    ),
                ));
            }
        }

        let trace = o.trace.unwrap_or(true);
        // trace.svg by default whenever trace.csv is written: a run shows its picture.
        let output =
            OutputParams { sample_dt, trace, events: o.events.unwrap_or(false), plot: o.plot.unwrap_or(trace) };
        if output.plot && !output.trace {
            return Err(SceneError::invalid(
                "output.plot",
                true,
                "needs output.trace = true (trace.svg is drawn from trace.csv after the run)",
            ));
        }
        let scene = Scene { name: name.to_string(), junctions, plate, run, fixed, exact, output, reference };
        // A run of more junction events than `EVENTS_MAX` would take years (docs/scenes.md).
        let events = crate::estimate::work::expected(&scene).events;
        if events.is_nan() || events > EVENTS_MAX {
            return Err(SceneError::invalid(
                "run.t_end",
                scene.run.t_end,
                format!(
                    "expects about {events:.1e} junction events (N = {n} at the rates k0 = {:e}, kon0 g(V) at zero force; more than {EVENTS_MAX:e}, years of run time): shorten the run or lower the rates",
                    scene.junctions.k0
                ),
            ));
        }
        Ok(scene)
    }
}

/// Applies the temperature map to the reference values in `j` and `p` (replaced by the
/// values in force at `j.temperature`); returns the reference values when the scene has a
/// temperature dependence, `None` (and leaves `j` and `p` untouched) when it has none.
fn thermal_map(j: &mut JunctionParams, p: &mut PlateParams) -> Result<Option<Reference>, SceneError> {
    let c = Coefficients {
        e_off: j.e_off,
        e_on: j.e_on,
        kappa_slope: j.kappa_slope,
        k_slope: p.k_slope,
        eta_slope: p.eta_slope,
    };
    c.check()?;
    if c.is_zero() {
        return Ok(None);
    }
    let reference = Reference { k0: j.k0, kon0: j.kon0, kappa: j.kappa, k: p.k, eta: p.eta };
    let now = in_force(&reference, &c, j.temperature)?;
    (j.k0, j.kon0, j.kappa, p.k, p.eta) = (now.k0, now.kon0, now.kappa, now.k, now.eta);
    Ok(Some(reference))
}

/// Default output interval: `t_end / 1000`, rounded up to whole steps for the fixed engine.
pub fn default_sample_dt(t_end: f64, engine: EngineKind, dt: f64) -> f64 {
    let s = t_end / 1000.0;
    match engine {
        EngineKind::Exact => s,
        EngineKind::Fixed => (s / dt).ceil().max(1.0) * dt,
    }
}
