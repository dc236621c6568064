//! A prepared sweep: the swept fields and their values, the grid of points, and the scene of
//! every run with its derived seed. Preparing validates everything and runs nothing.

use serde::Serialize;

use super::values::SweepValue;
use crate::scene::error::printable;
use crate::scene::{EngineKind, RngKind, Scene, SceneError};
use crate::studies::seeds;

/// Most runs (grid points x replicas) a sweep may have.
pub const MAX_RUNS: usize = 1_000_000;
/// Most fields a sweep varies together (a 2-D map).
pub const MAX_AXES: usize = 2;

/// One swept field and its values.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepAxis {
    /// The scene field, `section.key`.
    pub param: String,
    pub values: Vec<SweepValue>,
    /// Draw this axis of `sweep.svg` on a log scale.
    pub log: bool,
}

/// What to sweep: one or two axes (the first varies slowest), replicas per grid point, and
/// the `--set` overrides already applied to the base scene (for the record).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    pub axes: Vec<SweepAxis>,
    pub replicas: usize,
    pub set: Vec<String>,
}

/// One point of the grid: its index, one value per axis, and the scenes of its replicas.
#[derive(Clone, Debug)]
pub struct GridPoint {
    /// `i` for a 1-D sweep; `i * len(values of axis 2) + j` for value `i` of the first axis and
    /// `j` of the second (row-major).
    pub index: usize,
    /// The value of each axis at this point.
    pub values: Vec<SweepValue>,
    /// `scenes[r]`: the scene of replica `r`, its seed set.
    pub scenes: Vec<Scene>,
}

/// One run of a sweep, in the order [`Sweep::runs`] lists them.
#[derive(Clone, Copy, Debug)]
pub struct RunSpec<'a> {
    /// Grid point index.
    pub point: usize,
    pub replica: usize,
    /// The scene to run, with its derived seed.
    pub scene: &'a Scene,
}

/// A sweep ready to run.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The scene with the `--set` overrides, before the swept values.
    pub base: Scene,
    pub axes: Vec<SweepAxis>,
    pub replicas: usize,
    /// The `--set` overrides, for the record.
    pub set: Vec<String>,
    /// The grid, row-major (the last axis varies fastest).
    pub points: Vec<GridPoint>,
}

/// Why a sweep cannot be prepared: one line naming the argument, the value and what is
/// allowed.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    #[error(
        "--param: no field to sweep (give --param SECTION.KEY with its values, e.g. --param plate.v --values 0.1,1)"
    )]
    NoAxes,
    #[error("--param: {count} fields given, at most {MAX_AXES} (a 2-D sweep)")]
    TooManyAxes { count: usize },
    #[error("--param {param}: expected a scene field as SECTION.KEY, e.g. plate.v")]
    NotAField { param: String },
    #[error("--param {param}: no section [{section}] in a scene (sections: {sections})")]
    NoSection { param: String, section: String, sections: String },
    #[error("--param {param}: [{section}] has no field '{key}' (fields: {fields})")]
    NoField { param: String, section: String, key: String, fields: String },
    #[error(
        "--param run.seed: cannot be swept: each run's seed is derived from run.seed, the grid point and the replica (use --replicas, or --set run.seed=...)"
    )]
    SeedSwept,
    #[error("--param {param}: given twice (a 2-D sweep varies two different fields)")]
    SameField { param: String },
    #[error("--values: no values given for {param}")]
    NoValues { param: String },
    #[error(
        "--replicas {replicas}: must be at least 1, with grid points x replicas at most {MAX_RUNS} ({points} grid points)"
    )]
    Replicas { replicas: usize, points: usize },
    #[error("{flag}: value {value} of {param} is not > 0 (a log axis needs positive values)")]
    LogAxis { flag: &'static str, param: String, value: String },
    #[error("--replicas {replicas}: at {point} {}", seeds::blocks_do_not_fit(*replicas, *draws))]
    ParkMillerPeriod {
        /// `plate.v = 0.5` (each swept field).
        point: String,
        replicas: usize,
        /// Draws one replica can use, `N (steps + 1)`.
        draws: u64,
    },
    #[error("{point}: {source}")]
    Value {
        /// `value V for P` (1-D) or `values P1 = V1, P2 = V2` (2-D).
        point: String,
        #[source]
        source: SceneError,
    },
}

/// Checks that `param` names a field of a scene.
fn check_field(base: &Scene, param: &str) -> Result<(), SpecError> {
    let (section, key) = param
        .split_once('.')
        .filter(|(s, k)| !s.is_empty() && !k.is_empty() && !k.contains('.') && !param.contains('='))
        .ok_or_else(|| SpecError::NotAField { param: printable(param) })?;
    let table = toml::Table::try_from(base.to_file()).expect("a scene always serializes");
    let fields = |t: &toml::Table| t.keys().cloned().collect::<Vec<_>>().join(", ");
    match table.get(section).and_then(|s| s.as_table()) {
        None => {
            Err(SpecError::NoSection { param: printable(param), section: printable(section), sections: fields(&table) })
        }
        Some(t) if !t.contains_key(key) => Err(SpecError::NoField {
            param: printable(param),
            section: section.to_string(),
            key: printable(key),
            fields: fields(t),
        }),
        _ if param == "run.seed" => Err(SpecError::SeedSwept),
        _ => Ok(()),
    }
}

impl Sweep {
    /// Checks the fields and every grid point (its values applied to `base` and validated
    /// like the scene file) and derives every run's seed ([`crate::studies::seeds`], grid
    /// point index and replica; with the Park–Miller generator, disjoint blocks of its cycle
    /// for the replicas of a point, refused when they do not fit). Nothing runs.
    pub fn prepare(base: Scene, spec: SweepSpec) -> Result<Sweep, SpecError> {
        let SweepSpec { axes, replicas, set } = spec;
        match axes.len() {
            0 => return Err(SpecError::NoAxes),
            n if n > MAX_AXES => return Err(SpecError::TooManyAxes { count: n }),
            _ => {}
        }
        for (k, a) in axes.iter().enumerate() {
            check_field(&base, &a.param)?;
            if axes[..k].iter().any(|b| b.param == a.param) {
                return Err(SpecError::SameField { param: a.param.clone() });
            }
            if a.values.is_empty() {
                return Err(SpecError::NoValues { param: a.param.clone() });
            }
            if let Some(v) = a.values.iter().find(|v| a.log && v.x <= 0.0) {
                let flag = if k == 0 { "--log-x" } else { "--log-y" };
                return Err(SpecError::LogAxis { flag, param: a.param.clone(), value: printable(&v.text) });
            }
        }
        let points = axes.iter().map(|a| a.values.len()).product::<usize>();
        if replicas == 0 || points.saturating_mul(replicas) > MAX_RUNS {
            return Err(SpecError::Replicas { replicas, points });
        }
        // Row-major grid of value indices.
        let grid: Vec<Vec<usize>> = match axes.len() {
            1 => (0..axes[0].values.len()).map(|i| vec![i]).collect(),
            _ => (0..axes[0].values.len()).flat_map(|i| (0..axes[1].values.len()).map(move |j| vec![i, j])).collect(),
        };
        let mut scenes = Vec::with_capacity(grid.len());
        for idx in &grid {
            let values: Vec<SweepValue> = idx.iter().zip(&axes).map(|(&i, a)| a.values[i].clone()).collect();
            let overrides: Vec<String> =
                values.iter().zip(&axes).map(|(v, a)| format!("{}={}", a.param, v.text)).collect();
            let scene = base.with_overrides(&overrides).map_err(|source| {
                let point = match axes.len() {
                    1 => format!("value {} for {}", printable(&values[0].text), axes[0].param),
                    _ => format!(
                        "values {} = {}, {} = {}",
                        axes[0].param,
                        printable(&values[0].text),
                        axes[1].param,
                        printable(&values[1].text)
                    ),
                };
                SpecError::Value { point, source }
            })?;
            scenes.push((values, scene));
        }
        let mut seeds = seeds::derive_all(base.run.seed, grid.len(), replicas);
        for (g, (values, scene)) in scenes.iter().enumerate() {
            if scene.run.engine == EngineKind::Fixed && scene.fixed.rng == RngKind::ParkMiller {
                let draws = seeds::replica_draws(scene);
                seeds[g] =
                    seeds::sweep_park_miller_seeds(base.run.seed, g as u64, replicas, draws).ok_or_else(|| {
                        let point =
                            axes.iter().zip(values).map(|(a, v)| format!("{} = {}", a.param, printable(&v.text)));
                        SpecError::ParkMillerPeriod { point: point.collect::<Vec<_>>().join(", "), replicas, draws }
                    })?;
            }
        }
        let points = scenes
            .into_iter()
            .zip(seeds)
            .enumerate()
            .map(|(index, ((values, scene), row))| GridPoint {
                index,
                values,
                scenes: row
                    .into_iter()
                    .map(|seed| {
                        let mut r = scene.clone();
                        r.run.seed = seed;
                        r
                    })
                    .collect(),
            })
            .collect();
        Ok(Sweep { base, axes, replicas, set, points })
    }

    /// Every run, grid point by grid point (replicas in order within a point): the order in
    /// which [`Sweep::outcome`] takes the runs' summaries.
    pub fn runs(&self) -> impl Iterator<Item = RunSpec<'_>> + '_ {
        self.points.iter().flat_map(|p| {
            p.scenes.iter().enumerate().map(move |(replica, scene)| RunSpec { point: p.index, replica, scene })
        })
    }

    /// Number of runs.
    pub fn len(&self) -> usize {
        self.points.len() * self.replicas
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the sweep varies two fields (a map).
    pub fn is_map(&self) -> bool {
        self.axes.len() == 2
    }

    /// The swept fields joined by `-` (for the default output directory).
    pub fn name(&self) -> String {
        self.axes.iter().map(|a| a.param.as_str()).collect::<Vec<_>>().join("-")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::studies::sweep::{ValueSpec, parse_values};

    fn spec(param: &str, values: &str, replicas: usize) -> SweepSpec {
        let values = parse_values(ValueSpec::List(values)).unwrap();
        SweepSpec { axes: vec![SweepAxis { param: param.into(), values, log: false }], replicas, set: vec![] }
    }

    fn seeds_of(s: &Sweep) -> Vec<Vec<u64>> {
        s.points.iter().map(|p| p.scenes.iter().map(|s| s.run.seed).collect()).collect()
    }

    /// The replicas of a Park–Miller point follow each other on the generator's cycle, each
    /// `N (steps + 1)` draws after the one before (the draws a replica can use at that
    /// point's step), from the point's hashed state.
    #[test]
    fn park_miller_replicas_take_consecutive_disjoint_blocks() {
        let sweep = Sweep::prepare(crate::test_scenes::fig1(), spec("fixed.dt", "1,0.5", 3)).unwrap();
        // fig1: N = 300, t_end = 150.
        for (g, (row, draws)) in seeds_of(&sweep).iter().zip([300 * 151, 300 * 301]).enumerate() {
            seeds::assert_consecutive_blocks(row, draws, Some(g as u64));
        }
    }

    /// A Park–Miller point whose replicas need more draws than the cycle holds is refused in
    /// one line naming the replicas, the point and the ways out; PCG seeds are the hashed
    /// ones whatever the draws.
    #[test]
    fn park_miller_points_whose_replicas_do_not_fit_are_refused() {
        // dt = 1e-4: 1.5e6 steps of 300 junctions, 450_000_300 draws a replica; 4 fit.
        assert!(Sweep::prepare(crate::test_scenes::fig1(), spec("fixed.dt", "1,1e-4", 4)).is_ok());
        let e = Sweep::prepare(crate::test_scenes::fig1(), spec("fixed.dt", "1,1e-4", 5)).unwrap_err().to_string();
        assert_eq!(
            e,
            "--replicas 5: at fixed.dt = 1e-4 the replicas need 5 x 450000300 Park-Miller draws, more than the \
             generator's period 2147483646; use fewer replicas, a larger fixed.dt or --set fixed.rng=pcg"
        );
        // One replica that alone would go round the cycle.
        let e = Sweep::prepare(crate::test_scenes::fig1(), spec("fixed.dt", "1e-5", 1)).unwrap_err().to_string();
        assert!(e.starts_with("--replicas 1: at fixed.dt = 1e-5 ") && !e.contains("fewer"), "{e}");
        assert!(e.ends_with("use a larger fixed.dt or --set fixed.rng=pcg"), "{e}");
        let pcg = crate::test_scenes::fig1_with(&["fixed.rng=pcg"]);
        let sweep = Sweep::prepare(pcg, spec("fixed.dt", "1,1e-4", 5)).unwrap();
        assert_eq!(seeds_of(&sweep), seeds::derive_all(1, 2, 5));
    }
}
