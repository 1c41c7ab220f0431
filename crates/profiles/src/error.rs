//! What goes wrong reading a profile: one line naming the file (and the line and field).

use cell_config::{FieldError, ParseError, Place, Problem};

use crate::EMBEDDED_PROFILES;

/// A rejected or unreadable profile. Messages are one line and name the file.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The path.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// YAML syntax, a missing or unknown key, or a value of the wrong type (with its line and
    /// field).
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A value out of its domain.
    #[error("{}{reason}", Place::field(file, field))]
    Invalid {
        /// The file.
        file: String,
        /// Dotted key path, e.g. `hotwire.tower_separation_mm`.
        field: String,
        /// What is wrong: a value out of range, or a rule between sections.
        reason: Problem,
    },
    /// A name that is neither an embedded profile nor a file.
    #[error(
        "machine profile {name:?} is not a known name (known: {}) nor a .yaml path",
        EMBEDDED_PROFILES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
    )]
    Unknown {
        /// The name given.
        name: String,
    },
}

impl ProfileError {
    /// `error` found in the profile `file`.
    pub fn invalid(file: &str, error: FieldError) -> Self {
        Self::Invalid {
            file: file.into(),
            field: error.field,
            reason: error.problem,
        }
    }
}
