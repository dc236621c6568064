//! `--set section.key=value` overrides, applied to the parsed TOML table before the
//! table is deserialized, so an override is checked exactly like the file.

use super::error::SceneError;

/// Applies one `section.key=value` assignment to `table`.
///
/// `value` is read as a TOML value (`0.1`, `true`, `"weak"`, `1e-6`); a bare word that is
/// not a TOML value (`weak`, `park-miller`) is taken as a string. A value that starts as a
/// number (a digit, or a sign or point and a digit) but is not a TOML value (`1e400`, an
/// integer beyond `i64`) is refused as a number, never taken as a string.
pub fn apply(table: &mut toml::Table, assignment: &str) -> Result<(), SceneError> {
    let err = |reason: &str| SceneError::Override {
        assignment: super::error::printable(assignment),
        reason: reason.to_string(),
    };
    let (key, raw) = assignment.split_once('=').ok_or_else(|| err("expected section.key=value"))?;
    let (section, field) = key.trim().split_once('.').ok_or_else(|| err("expected section.key=value"))?;
    if section.is_empty() || field.is_empty() || field.contains('.') {
        return Err(err("expected section.key=value"));
    }
    let value = match parse_value(raw.trim()) {
        Ok(Some(v)) => v,
        Ok(None) => return Err(err("the value is empty")),
        Err(()) => return Err(err(NOT_A_NUMBER)),
    };
    let entry = table.entry(section.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
    match entry {
        toml::Value::Table(t) => {
            t.insert(field.to_string(), value);
            Ok(())
        }
        _ => Err(err("that section is not a table in the scene file")),
    }
}

/// Why a value that starts as a number is refused when TOML cannot read it.
const NOT_A_NUMBER: &str = "not a TOML number (integers from -9223372036854775808 to 9223372036854775807, \
     floats such as 0.5 or 1e-6 of magnitude below about 1.8e308)";

/// The TOML value of `raw`: `Ok(None)` when it is empty, `Err` when it looks like a number
/// and is not one TOML can read.
fn parse_value(raw: &str) -> Result<Option<toml::Value>, ()> {
    if raw.is_empty() {
        return Ok(None);
    }
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => Ok(t.remove("v")),
        Err(_) if looks_numeric(raw) => Err(()),
        Err(_) => Ok(Some(toml::Value::String(raw.to_string()))),
    }
}

/// Whether `raw` starts as a number: a digit, or a sign or a point followed by one.
fn looks_numeric(raw: &str) -> bool {
    let rest = raw.strip_prefix(['+', '-']).unwrap_or(raw);
    let rest = rest.strip_prefix('.').unwrap_or(rest);
    rest.starts_with(|c: char| c.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_words_and_strings() {
        let mut t = toml::Table::new();
        apply(&mut t, "plate.v=0.1").unwrap();
        apply(&mut t, "junctions.bond=weak").unwrap();
        apply(&mut t, "fixed.rng=\"pcg\"").unwrap();
        apply(&mut t, "run.seed = 7").unwrap();
        assert_eq!(t["plate"]["v"].as_float(), Some(0.1));
        assert_eq!(t["junctions"]["bond"].as_str(), Some("weak"));
        assert_eq!(t["fixed"]["rng"].as_str(), Some("pcg"));
        assert_eq!(t["run"]["seed"].as_integer(), Some(7));
    }

    #[test]
    fn malformed_assignments_are_refused() {
        let mut t = toml::Table::new();
        for bad in ["plate.v", "v=1", ".v=1", "plate.=1", "plate.v=", "a.b.c=1"] {
            assert!(apply(&mut t, bad).is_err(), "{bad}");
        }
    }

    /// A number TOML cannot hold is refused as a number, not taken as a string (which the
    /// field would refuse as `invalid type: string "1e400", expected f64`).
    #[test]
    fn numbers_beyond_toml_are_refused_as_numbers() {
        for bad in [
            "plate.v=1e400",
            "plate.v=-1e400",
            "run.seed=9223372036854775808",
            "junctions.n=99999999999999999999",
            "plate.v=.5",
        ] {
            let mut t = toml::Table::new();
            let e = apply(&mut t, bad).unwrap_err().to_string();
            assert_eq!(e, format!("--set {bad}: {NOT_A_NUMBER}"));
        }
        // Words are still strings, numbers still numbers.
        let mut t = toml::Table::new();
        for ok in ["fixed.flip=as-printed", "fixed.rng=park-miller", "plate.v=0.5", "plate.k=+1e300"] {
            apply(&mut t, ok).unwrap();
        }
        assert_eq!(t["fixed"]["flip"].as_str(), Some("as-printed"));
        assert_eq!(t["plate"]["k"].as_float(), Some(1e300));
    }
}
