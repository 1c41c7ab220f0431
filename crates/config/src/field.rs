//! What a validator reports: which field, and what is wrong with it.

use crate::OutOfRange;

/// What is wrong with a field's value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Problem {
    /// A number outside its range (the one shape for every such check); boxed to keep the
    /// errors that carry a problem small.
    #[error(transparent)]
    OutOfRange(Box<OutOfRange>),
    /// Any other rule: sections that need each other, names that clash, `min < max`.
    #[error("{0}")]
    Rule(String),
}

impl From<OutOfRange> for Problem {
    fn from(e: OutOfRange) -> Self {
        Self::OutOfRange(Box::new(e))
    }
}

impl From<String> for Problem {
    fn from(rule: String) -> Self {
        Self::Rule(rule)
    }
}

impl From<&str> for Problem {
    fn from(rule: &str) -> Self {
        Self::Rule(rule.into())
    }
}

/// A field a validator rejects: its dotted path and the [`Problem`]. The loader adds the file
/// (written as [`crate::Place::field`] then the problem).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("field `{field}`: {problem}")]
pub struct FieldError {
    /// Dotted path, e.g. `hotwire.tower_separation_mm` or `gcode.program_start[1]`.
    pub field: String,
    /// What is wrong.
    pub problem: Problem,
}

impl FieldError {
    /// `field` has `problem`.
    pub fn new(field: impl Into<String>, problem: impl Into<Problem>) -> Self {
        Self {
            field: field.into(),
            problem: problem.into(),
        }
    }

    /// The same problem one section down: `field` becomes `section.field` (an empty field, the
    /// section itself, becomes `section`). Section validators name fields relative to their
    /// section; the caller that knows where the section sits adds it.
    ///
    /// ```
    /// let e = cell_config::FieldError::new("dwell_s", "bad").within("pierce").within("gcode");
    /// assert_eq!(e.field, "gcode.pierce.dwell_s");
    /// assert_eq!(cell_config::FieldError::new("", "bad").within("pierce").field, "pierce");
    /// ```
    #[must_use]
    pub fn within(mut self, section: &str) -> Self {
        self.field = if self.field.is_empty() {
            section.to_owned()
        } else {
            format!("{section}.{}", self.field)
        };
        self
    }
}
