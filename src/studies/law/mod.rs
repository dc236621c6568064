//! A friction law for continuum codes from a velocity-temperature map
//! (`stickslip friction-law`).
//!
//! A 2-D sweep over `plate.v` and `junctions.temperature` ([`source`]: run here, or read
//! from a finished sweep's directory) becomes, in the physical units of [`scales`]:
//!
//! - `law.csv`: a row per `(V, T)` point, `T` then `V` ascending: slip rate and temperature
//!   in SI, friction per junction and in newtons with 95 % Student-t intervals across
//!   replicas, `mu = friction / normal load` with its interval (steady points only), the
//!   regime and the `steady` flag ([`points`]);
//! - `abaqus.inp` (a `*FRICTION` block) and `ansys.mac` (`TB,FRIC` with `TBFIELD`), the
//!   steady points only: a point in stick-slip has no steady coefficient, so it is left
//!   out of the tables (and listed in their comments) and the codes interpolate across it
//!   from the steady points around it ([`export`]);
//! - `law.json`: the scales, the smooth form fitted to the steady points ([`fit`]) with
//!   its parameters, standard errors, residuals and chi-square, and what was left out.
//!
//! The files are written as one set, whole or not at all ([`crate::output::atomic::write_files`]).

pub mod export;
pub mod fit;
pub mod points;
pub mod scales;
pub mod source;
pub mod tables;

use std::path::Path;

pub use fit::{Fit, FitError, FitPoint, Term};
pub use points::{Estimate, LawPoint, PointRuns, RunRecord};
pub use scales::{BOLTZMANN, ScaleArgs, ScaleError, Scales};
pub use source::{LawInput, SourceError, T_FIELD, V_FIELD, from_outcome, read_sweep_dir, vt_axes};

use crate::output::atomic::{WriteFileError, write_files};

/// The files a law writes, in the order they are written.
pub const FILES: [&str; 4] = ["law.csv", "abaqus.inp", "ansys.mac", "law.json"];

/// The degree of the fitted form unless another is asked for.
pub const DEFAULT_DEGREE: u32 = 2;

/// A friction law: the points of the map in physical units, and the fitted form.
#[derive(Clone, Debug)]
pub struct FrictionLaw {
    pub scene: String,
    pub replicas: usize,
    pub scales: Scales,
    /// Sorted by `T`, then `V`.
    pub points: Vec<LawPoint>,
    /// The form fitted to the steady points, or why none could be.
    pub fit: Result<Fit, FitError>,
    /// Indices into `points` of the steady points the fit used, in its order.
    pub fitted: Vec<usize>,
}

/// `x = ln(V / V0)` and `y = T_ref / T - 1` of a point (`V`, `T` in the model's units).
pub fn fit_coordinates(v: f64, t: f64) -> (f64, f64) {
    (v.ln(), 1.0 / t - 1.0)
}

impl FrictionLaw {
    /// The law of `input` in the units of `scales`, its form fitted at degree `degree`
    /// (1 or 2). Refuses what [`source::checked_points`] refuses.
    pub fn new(input: &LawInput, scales: Scales, degree: u32) -> Result<FrictionLaw, SourceError> {
        let sorted = source::checked_points(input, &scales)?;
        let points: Vec<LawPoint> = sorted.iter().map(|p| LawPoint::new(p, &scales)).collect();
        let fitted: Vec<usize> = (0..points.len()).filter(|&k| points[k].steady).collect();
        let data: Vec<FitPoint> = fitted
            .iter()
            .map(|&k| {
                let p = &points[k];
                let (x, y) = fit_coordinates(p.v, p.t);
                let mu = p.mu.expect("a steady point has a coefficient");
                FitPoint { x, y, z: mu.mean, sigma: Some(mu.se) }
            })
            .collect();
        let fit = fit::fit(&data, degree);
        Ok(FrictionLaw { scene: input.scene.clone(), replicas: input.replicas, scales, points, fit, fitted })
    }

    /// The steady points (those the tables of the continuum codes hold).
    pub fn steady(&self) -> impl Iterator<Item = &LawPoint> {
        self.points.iter().filter(|p| p.steady)
    }

    /// Writes [`FILES`] into `dir` as one set: a failed write replaces none of them.
    pub fn write(&self, dir: &Path) -> Result<(), WriteFileError> {
        let files = [
            (FILES[0], self.law_csv()),
            (FILES[1], self.abaqus_inp()),
            (FILES[2], self.ansys_mac()),
            (FILES[3], self.law_json()),
        ];
        write_files(dir, &files)
    }
}
