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
    Override { assignment: String, reason: &'static str },
}

impl SceneError {
    pub(crate) fn invalid(field: &'static str, value: impl std::fmt::Display, allowed: impl Into<String>) -> Self {
        SceneError::Invalid { field, value: value.to_string(), allowed: allowed.into() }
    }
}

/// `s` with control characters and line separators escaped (`\n`, `\u{2028}`), so that a
/// user-supplied key, path or assignment cannot break a one-line message.
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
    c.is_control() || matches!(c, '\u{2028}' | '\u{2029}')
}

/// Collapses a multi-line message into one line.
pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}
