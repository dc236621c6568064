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

/// Collapses a multi-line message into one line.
pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}
