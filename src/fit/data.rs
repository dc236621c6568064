//! The measured curve of a fit: `DATA.csv`, one row per measured point. Columns named by
//! scene fields (`section.key`) are the point's conditions, `friction` its measured mean
//! friction per junction (model units), `sigma` (optional) its standard error. Lines that
//! are blank or start with `#` are skipped; fields are separated by commas, without quoting.

use crate::scene::Scene;
use crate::scene::error::printable;

/// The column of measured friction.
pub const FRICTION: &str = "friction";
/// The optional column of standard errors.
pub const SIGMA: &str = "sigma";

/// One measured point.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The line of `DATA.csv` it came from (1-based; the header is line 1 or later).
    pub line: usize,
    /// The value of each condition column, as written (a TOML value for `--set`).
    pub text: Vec<String>,
    /// The same values as numbers.
    pub conditions: Vec<f64>,
    /// Measured mean friction per junction, model units (after `--friction-scale`).
    pub friction: f64,
    /// Its standard error (after `--friction-scale`), if the data give one.
    pub sigma: Option<f64>,
}

/// A measured curve, checked against a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct DataSet {
    /// The condition columns, in file order: scene fields `section.key`.
    pub columns: Vec<String>,
    pub points: Vec<Point>,
    /// Whether a `sigma` column was given.
    pub has_sigma: bool,
}

/// Why a data file was refused: one line naming the file, the line or column, the value
/// and what is allowed.
#[derive(Debug, thiserror::Error)]
#[error("{origin}: {message}")]
pub struct DataError {
    pub origin: String,
    pub message: String,
}

/// Whether `field` (`section.key`) names a field of `scene`, as its complete scene file
/// lists them; `Err` names the sections or fields there are.
pub fn check_field(scene: &Scene, field: &str) -> Result<(), String> {
    let table = toml::Table::try_from(scene.to_file()).expect("a scene always serializes");
    let keys = |t: &toml::Table| t.keys().cloned().collect::<Vec<_>>().join(", ");
    let Some((section, key)) = field.split_once('.').filter(|(s, k)| !s.is_empty() && !k.contains('.')) else {
        return Err(format!("is not a scene field SECTION.KEY (sections: {})", keys(&table)));
    };
    match table.get(section).and_then(|s| s.as_table()) {
        None => Err(format!("is not a scene field: no section [{section}] (sections: {})", keys(&table))),
        Some(t) if !t.contains_key(key) => {
            Err(format!("is not a scene field: [{section}] has no field '{key}' (fields: {})", keys(t)))
        }
        Some(_) => Ok(()),
    }
}

/// Widest magnitude of a friction or a sigma as read (times `--friction-scale`), of a
/// friction over its sigma, and of the scale itself; `1 / VALUE_MAX` is the smallest sigma
/// and scale. Within these the data's part of the misfit's terms `((F_sim - F) / sigma)^2`
/// stays finite (a simulated friction that overflows them is refused at its evaluation).
pub const VALUE_MAX: f64 = 1e100;

/// Whether `v` (`--friction-scale`, or a scaled sigma) is within `[1 / VALUE_MAX, VALUE_MAX]`.
pub fn in_window(v: f64) -> bool {
    (1.0 / VALUE_MAX..=VALUE_MAX).contains(&v)
}

impl DataSet {
    /// Reads `text` (the contents of the file `origin`), each friction and sigma multiplied
    /// by `scale`, and checks every condition against `base`: each row's conditions applied
    /// to `base` must validate like a scene file.
    pub fn parse(text: &str, origin: &str, base: &Scene, scale: f64) -> Result<DataSet, DataError> {
        let origin = printable(origin);
        let fail = |message: String| DataError { origin: origin.clone(), message };
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(k, l)| (k + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let Some((_, header)) = lines.next() else {
            return Err(fail(format!("no header line (expected columns such as plate.v,{FRICTION},{SIGMA})")));
        };
        let names: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        let find = |name: &str| names.iter().position(|c| c == name);
        let friction = find(FRICTION).ok_or_else(|| {
            fail(format!(
                "no '{FRICTION}' column (columns: {}); it holds the measured mean friction per junction",
                printable(header)
            ))
        })?;
        let sigma = find(SIGMA);
        let mut columns = Vec::new();
        let mut condition_at = Vec::new();
        for (c, name) in names.iter().enumerate() {
            if c == friction || Some(c) == sigma {
                continue;
            }
            if names[..c].contains(name) {
                return Err(fail(format!("column '{}' is given twice", printable(name))));
            }
            check_field(base, name).map_err(|why| fail(format!("column '{}' {why}", printable(name))))?;
            if name == "run.seed" {
                return Err(fail(
                    "column 'run.seed': the seeds of a fit's runs are derived from run.seed, not measured conditions"
                        .into(),
                ));
            }
            columns.push(name.clone());
            condition_at.push(c);
        }
        let mut points = Vec::new();
        for (line, row) in lines {
            let cells: Vec<&str> = row.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                return Err(fail(format!("line {line}: {} fields, the header has {}", cells.len(), names.len())));
            }
            let number = |c: usize| -> Result<f64, DataError> {
                let v: f64 = cells[c].parse().map_err(|_| {
                    fail(format!("line {line}: {} = '{}' is not a number", printable(&names[c]), printable(cells[c])))
                })?;
                if !v.is_finite() {
                    return Err(fail(format!(
                        "line {line}: {} = {}: must be a finite number",
                        printable(&names[c]),
                        cells[c]
                    )));
                }
                Ok(v)
            };
            let f = number(friction)? * scale;
            let s = match sigma {
                Some(c) => {
                    let s = number(c)? * scale;
                    if !(s > 0.0 && s.is_finite()) {
                        return Err(fail(format!(
                            "line {line}: {SIGMA} = {}: must be > 0 (a standard error)",
                            cells[c]
                        )));
                    }
                    if !in_window(s) {
                        return Err(fail(format!(
                            "line {line}: {SIGMA} = {} (times --friction-scale {scale}): must be from 1e-100 to 1e100",
                            cells[c]
                        )));
                    }
                    Some(s)
                }
                None => None,
            };
            if f.abs() > VALUE_MAX {
                return Err(fail(format!(
                    "line {line}: {FRICTION} = {} (times --friction-scale {scale}): must be from -1e100 to 1e100",
                    cells[friction]
                )));
            }
            if let Some(s) = s.filter(|s| f.abs() / s > VALUE_MAX) {
                return Err(fail(format!(
                    "line {line}: {FRICTION} / {SIGMA} = {}: must be from -1e100 to 1e100 (the misfit's terms ((F_sim - F) / sigma)^2 must stay finite)",
                    crate::scene::error::compact(f / s)
                )));
            }
            let mut text = Vec::new();
            let mut conditions = Vec::new();
            for &c in &condition_at {
                conditions.push(number(c)?);
                text.push(cells[c].to_string());
            }
            let overrides: Vec<String> = columns.iter().zip(&text).map(|(k, v)| format!("{k}={v}")).collect();
            base.with_overrides(&overrides).map_err(|e| fail(format!("line {line}: {e}")))?;
            points.push(Point { line, text, conditions, friction: f, sigma: s });
        }
        if points.is_empty() {
            return Err(fail("no data rows after the header".into()));
        }
        Ok(DataSet { columns, points, has_sigma: sigma.is_some() })
    }

    /// The `--set` overrides of point `i`'s conditions.
    pub fn overrides(&self, i: usize) -> Vec<String> {
        self.columns.iter().zip(&self.points[i].text).map(|(k, v)| format!("{k}={v}")).collect()
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<DataSet, DataError> {
        DataSet::parse(text, "d.csv", &crate::test_scenes::fig1(), 1.0)
    }

    #[test]
    fn a_curve_reads_with_its_conditions() {
        let d = parse("# measured\nplate.v,friction,sigma\n0.1, 0.5, 0.01\n\n1,0.7,0.02\n").unwrap();
        assert_eq!(d.columns, vec!["plate.v"]);
        assert_eq!(d.points.len(), 2);
        assert_eq!((d.points[1].line, d.points[1].conditions[0], d.points[1].sigma), (5, 1.0, Some(0.02)));
        assert_eq!(d.overrides(0), vec!["plate.v=0.1"]);
        assert!(d.has_sigma);
    }

    #[test]
    fn bad_data_is_one_line_naming_the_line_or_column() {
        for (text, mention) in [
            ("plate.v,f\n1,2\n", "no 'friction' column"),
            ("plate.vv,friction\n1,2\n", "column 'plate.vv'"),
            ("nope,friction\n1,2\n", "column 'nope'"),
            ("plate.v,friction\n1,NaN\n", "line 2: friction = NaN"),
            ("plate.v,friction\n1,inf\n", "line 2"),
            ("plate.v,friction\n-1,2\n", "line 2: plate.v = -1"),
            ("plate.v,friction\n1\n", "line 2: 1 fields"),
            ("plate.v,friction,sigma\n1,2,0\n", "line 2: sigma = 0"),
            ("plate.v,friction,sigma\n1,2,1e-320\n", "line 2: sigma = 1e-320 (times --friction-scale 1): must be from"),
            ("plate.v,friction,sigma\n1,2,1e101\n", "line 2: sigma = 1e101"),
            ("plate.v,friction\n1,-1e300\n", "line 2: friction = -1e300 (times --friction-scale 1): must be from"),
            ("plate.v,friction\n", "no data rows"),
            ("", "no header"),
        ] {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.contains(mention) && !e.contains('\n') && e.starts_with("d.csv: "), "{e}");
        }
    }
}
