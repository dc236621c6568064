//! Structured errors of scene reading and validation. Each displays as one line that
//! names the field (or file position), the offending value and what is allowed.

/// Why a scene was refused.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Read {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The text is not valid TOML.
    #[error("{origin}:{line}:{column}: TOML syntax error: {message}")]
    Syntax { origin: String, line: usize, column: usize, message: String },
    /// A key is unknown or a value has the wrong type.
    #[error("{origin}: {path}: {message}")]
    Schema { origin: String, path: String, message: String },
    /// A value is out of its allowed range.
    #[error("{field} = {value}: {allowed}")]
    Invalid { field: &'static str, value: String, allowed: String },
    /// A `--set section.key=value` override is malformed.
    #[error("--set {assignment}: {reason}")]
    Override { assignment: String, reason: String },
}

impl SceneError {
    pub(crate) fn invalid(field: &'static str, value: impl std::fmt::Display, allowed: impl Into<String>) -> Self {
        SceneError::Invalid { field, value: compact(value), allowed: allowed.into() }
    }
}

/// A value as a message shows it: as `{}` writes it (for a number, the shortest text that
/// reads back as the same `f64`), unless that is a number over 20 characters (magnitudes
/// from `1e21`, or small ones with many digits), then in exponent form (`1e300`,
/// `-2.5e-308`). Every integer of up to 20 digits (every `u64`) and every other text stay
/// as they are.
pub fn compact(v: impl std::fmt::Display) -> String {
    let s = v.to_string();
    match s.parse::<f64>() {
        Ok(x) if s.len() > 20 => format!("{x:e}"),
        _ => s,
    }
}

/// `s` with every number in it (a run of digits, with an optional sign, point and
/// fraction) shown as [`compact`] shows it: a message quoting a value by `{}` (serde's type
/// errors, for one) stays short.
pub fn compact_numbers(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let (before, from) = rest.split_at(start);
        let sign = before.ends_with('-') as usize;
        out.push_str(&before[..before.len() - sign]);
        let mut end = from.find(|c: char| !c.is_ascii_digit()).unwrap_or(from.len());
        if from[end..].starts_with('.') && from[end + 1..].starts_with(|c: char| c.is_ascii_digit()) {
            end += 1 + from[end + 1..].find(|c: char| !c.is_ascii_digit()).unwrap_or(from.len() - end - 1);
        }
        out.push_str(&compact(format!("{}{}", &before[before.len() - sign..], &from[..end])));
        rest = &from[end..];
    }
    out.push_str(rest);
    out
}

/// `s` with control characters, line separators and the two code points XML refuses in
/// text (U+FFFE, U+FFFF) escaped (`\n`, `\u{2028}`, `\u{fffe}`), so that a user-supplied
/// key, path or assignment cannot break a one-line message, a comment line or an SVG.
pub fn printable(s: &str) -> String {
    if !s.chars().any(needs_escape) {
        return s.to_string();
    }
    s.chars().fold(String::with_capacity(s.len() + 8), |mut out, c| {
        if needs_escape(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
        out
    })
}

fn needs_escape(c: char) -> bool {
    c.is_control() || matches!(c, '\u{2028}' | '\u{2029}' | '\u{fffe}' | '\u{ffff}')
}

/// Collapses a multi-line message into one line.
pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::{compact, compact_numbers};

    /// Long decimals read back as the same number in exponent form; integers of up to 20
    /// digits, short decimals and other text are kept.
    #[test]
    fn long_numbers_are_shown_in_exponent_form() {
        for x in [1e300, -1e300, 1e-300, 2.5e-308, 1.234_567_890_123_4e21, 1e-7_f64 / 3.0] {
            let s = compact(x);
            assert!(s.len() <= 24 && s.contains('e'), "{x}: {s}");
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        for s in ["18446744073709551615", "-9223372036854775808", "0.000001", "150", "1.5", "nan", "not a number"] {
            assert_eq!(compact(s), s);
        }
        // Inside a message: every number, and only numbers.
        let long = format!("invalid type: floating point `{}`, expected usize; x-2.5 at 1.5e3", 1e300);
        assert_eq!(compact_numbers(&long), "invalid type: floating point `1e300`, expected usize; x-2.5 at 1.5e3");
        let neg = format!("a -{} b 12.", 1e25);
        assert_eq!(compact_numbers(&neg), "a -1e25 b 12.");
        assert_eq!(compact_numbers("no numbers"), "no numbers");
    }
}
