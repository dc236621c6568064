//! `--set section.key=value` overrides, applied to the parsed TOML table before the
//! table is deserialized, so an override is checked exactly like the file.

use super::error::SceneError;

/// Applies one `section.key=value` assignment to `table`.
///
/// `value` is read as a TOML value (`0.1`, `true`, `"weak"`, `1e-6`); a bare word that is
/// not a TOML value (`weak`, `park-miller`) is taken as a string.
pub fn apply(table: &mut toml::Table, assignment: &str) -> Result<(), SceneError> {
    let err = |reason| SceneError::Override { assignment: super::error::printable(assignment), reason };
    let (key, raw) = assignment.split_once('=').ok_or_else(|| err("expected section.key=value"))?;
    let (section, field) = key.trim().split_once('.').ok_or_else(|| err("expected section.key=value"))?;
    if section.is_empty() || field.is_empty() || field.contains('.') {
        return Err(err("expected section.key=value"));
    }
    let value = parse_value(raw.trim()).ok_or_else(|| err("the value is empty"))?;
    let entry = table.entry(section.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
    match entry {
        toml::Value::Table(t) => {
            t.insert(field.to_string(), value);
            Ok(())
        }
        _ => Err(err("that section is not a table in the scene file")),
    }
}

fn parse_value(raw: &str) -> Option<toml::Value> {
    if raw.is_empty() {
        return None;
    }
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => t.remove("v"),
        Err(_) => Some(toml::Value::String(raw.to_string())),
    }
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
}
