//! Scenes: the problem definition. A TOML file ([`file::SceneFile`]) is read, optionally
//! overridden with `--set section.key=value`, and validated into a [`Scene`].

pub mod error;
pub mod file;
pub mod laws;
pub mod overrides;
pub mod params;
pub mod thermal;
pub mod validate;

pub use error::SceneError;
pub use file::SceneFile;
pub use params::*;

use std::path::Path;

impl Scene {
    /// Parses TOML text, applies overrides and validates. `origin` names the text in errors.
    pub fn from_toml_str(text: &str, origin: &str, name: &str, overrides: &[String]) -> Result<Scene, SceneError> {
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, column) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
            SceneError::Syntax { origin: origin.to_string(), line, column, message: error::one_line(e.message()) }
        })?;
        for a in overrides {
            overrides::apply(&mut table, a)?;
        }
        let file: SceneFile = serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let path = e.path().to_string();
            SceneError::Schema {
                origin: origin.to_string(),
                path: if path == "." { "scene".to_string() } else { error::printable(&path) },
                message: error::compact_numbers(&error::one_line(&e.into_inner().to_string())),
            }
        })?;
        file.validate(name)
    }

    /// Reads, overrides and validates a scene file; the scene's name is the file stem.
    pub fn from_file(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
        let origin = error::printable(&path.display().to_string());
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read { path: origin.clone(), source })?;
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
        Self::from_toml_str(&text, &origin, &name, overrides)
    }

    /// The scene with overrides applied to its already-validated values (used by sweeps).
    pub fn with_overrides(&self, overrides: &[String]) -> Result<Scene, SceneError> {
        let text = toml::to_string(&self.to_file()).expect("a scene always serializes");
        Self::from_toml_str(&text, &self.name, &self.name, overrides)
    }

    /// The scene written back as a complete scene file (every field explicit).
    pub fn to_file(&self) -> SceneFile {
        let (j, p, r, f, e, o) = (&self.junctions, &self.plate, &self.run, &self.fixed, &self.exact, &self.output);
        // The file holds the reference values; validation maps them to `T` again.
        let reference = self.reference_values();
        SceneFile {
            junctions: file::JunctionsSection {
                n: Some(j.n),
                bond: Some(j.bond),
                force_law: Some(j.force_law),
                kappa: Some(reference.kappa),
                l0: Some(j.l0),
                lambda: Some(j.lambda),
                reattach: Some(j.reattach),
                k0: Some(reference.k0),
                kon0: Some(reference.kon0),
                tau0: Some(j.tau0),
                alpha: Some(j.alpha),
                dx: Some(j.dx),
                temperature: Some(j.temperature),
                initial: Some(j.initial),
                e_off: Some(j.e_off),
                e_on: Some(j.e_on),
                kappa_slope: Some(j.kappa_slope),
            },
            plate: file::PlateSection {
                mass: Some(p.mass),
                eta: Some(reference.eta),
                k: Some(reference.k),
                v: Some(p.v),
                kinematic: Some(p.kinematic),
                k_slope: Some(p.k_slope),
                eta_slope: Some(p.eta_slope),
            },
            run: file::RunSection {
                engine: Some(r.engine),
                t_end: Some(r.t_end),
                t_warmup: Some(r.t_warmup),
                seed: Some(r.seed),
            },
            fixed: file::FixedSection {
                dt: Some(f.dt),
                rng: Some(f.rng),
                flip: Some(f.flip),
                integrator: Some(f.integrator),
            },
            exact: file::ExactSection { rtol: Some(e.rtol), atol: Some(e.atol), tilted: Some(e.tilted) },
            output: file::OutputSection {
                sample_dt: Some(o.sample_dt),
                trace: Some(o.trace),
                events: Some(o.events),
                plot: Some(o.plot),
            },
        }
    }
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}
