//! The one shape of "value out of range": the value, the range it must lie in, its unit.

use std::fmt;

use crate::FieldError;

/// One end of an [`Allowed`] range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// No limit on this side (only finiteness).
    Unbounded,
    /// The limit itself is allowed (`≥ min`, `≤ max`).
    Inclusive(f64),
    /// The limit itself is not allowed (`> min`, `< max`).
    Exclusive(f64),
}

/// The values a number may take: finite, at or above `min`, at or below `max`. NaN and the
/// infinities are never allowed.
///
/// ```
/// use cell_config::Allowed;
/// assert!(Allowed::POSITIVE.contains(0.1) && !Allowed::POSITIVE.contains(0.0));
/// assert!(!Allowed::NON_NEGATIVE.contains(f64::INFINITY));
/// assert!(!Allowed::half_open(0.0, 1.0).contains(1.0));
/// assert_eq!(Allowed::half_open(0.0, 1.0).to_string(), "in [0, 1)");
/// assert_eq!(Allowed::POSITIVE.to_string(), "finite and > 0");
/// assert_eq!(Allowed::at_most(6.0).whole().to_string(), "≤ 6");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Allowed {
    /// Lower end.
    pub min: Bound,
    /// Upper end.
    pub max: Bound,
    /// A count (decimals, targets): written without "finite and".
    pub whole: bool,
}

impl Allowed {
    /// Any finite number.
    pub const FINITE: Self = Self::between(Bound::Unbounded, Bound::Unbounded);
    /// Finite and > 0.
    pub const POSITIVE: Self = Self::between(Bound::Exclusive(0.0), Bound::Unbounded);
    /// Finite and ≥ 0.
    pub const NON_NEGATIVE: Self = Self::between(Bound::Inclusive(0.0), Bound::Unbounded);

    /// From its two ends.
    pub const fn between(min: Bound, max: Bound) -> Self {
        Self {
            min,
            max,
            whole: false,
        }
    }

    /// Finite and ≥ `min`.
    pub const fn at_least(min: f64) -> Self {
        Self::between(Bound::Inclusive(min), Bound::Unbounded)
    }

    /// Finite and ≤ `max`.
    pub const fn at_most(max: f64) -> Self {
        Self::between(Bound::Unbounded, Bound::Inclusive(max))
    }

    /// `[min, max]`.
    pub const fn closed(min: f64, max: f64) -> Self {
        Self::between(Bound::Inclusive(min), Bound::Inclusive(max))
    }

    /// `[min, max)`.
    pub const fn half_open(min: f64, max: f64) -> Self {
        Self::between(Bound::Inclusive(min), Bound::Exclusive(max))
    }

    /// The same range for a count, written without "finite and".
    pub const fn whole(self) -> Self {
        Self {
            whole: true,
            ..self
        }
    }

    /// True if `value` is finite and within both ends.
    pub fn contains(&self, value: f64) -> bool {
        let above = match self.min {
            Bound::Unbounded => true,
            Bound::Inclusive(m) => value >= m,
            Bound::Exclusive(m) => value > m,
        };
        let below = match self.max {
            Bound::Unbounded => true,
            Bound::Inclusive(m) => value <= m,
            Bound::Exclusive(m) => value < m,
        };
        value.is_finite() && above && below
    }

    /// `Ok` if `value` (in `unit`, `""` for none) is allowed.
    ///
    /// # Errors
    /// [`OutOfRange`] with the value, this range and the unit.
    pub fn check(&self, value: f64, unit: &'static str) -> Result<(), OutOfRange> {
        if self.contains(value) {
            Ok(())
        } else {
            Err(OutOfRange::new(value, *self, unit))
        }
    }

    /// As [`Allowed::check`], naming `field`.
    ///
    /// # Errors
    /// [`FieldError`] holding the [`OutOfRange`].
    pub fn check_field(
        &self,
        field: &str,
        value: f64,
        unit: &'static str,
    ) -> Result<(), FieldError> {
        self.check(value, unit).map_err(|e| e.at(field))
    }
}

impl fmt::Display for Allowed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let finite = if self.whole { "" } else { "finite and " };
        match (self.min, self.max) {
            (Bound::Unbounded, Bound::Unbounded) => f.write_str("finite"),
            (Bound::Inclusive(m), Bound::Unbounded) => write!(f, "{finite}≥ {m}"),
            (Bound::Exclusive(m), Bound::Unbounded) => write!(f, "{finite}> {m}"),
            (Bound::Unbounded, Bound::Inclusive(m)) => write!(f, "{finite}≤ {m}"),
            (Bound::Unbounded, Bound::Exclusive(m)) => write!(f, "{finite}< {m}"),
            (lo, hi) => {
                let (open, a) = match lo {
                    Bound::Inclusive(a) => ('[', a),
                    Bound::Exclusive(a) => ('(', a),
                    Bound::Unbounded => unreachable!("matched above"),
                };
                let (close, b) = match hi {
                    Bound::Inclusive(b) => (']', b),
                    Bound::Exclusive(b) => (')', b),
                    Bound::Unbounded => unreachable!("matched above"),
                };
                write!(f, "in {open}{a}, {b}{close}")
            }
        }
    }
}

/// A number outside what its field allows: `1200 mm is out of range: must be in [0, 1000)
/// (the tower separation)`. The field is named by the [`FieldError`] that carries it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{value}{}{unit} is out of range: must be {allowed}{}",
    if unit.is_empty() { "" } else { " " },
    note.as_ref().map(|n| format!(" ({n})")).unwrap_or_default()
)]
pub struct OutOfRange {
    /// The value given.
    pub value: f64,
    /// What the field allows.
    pub allowed: Allowed,
    /// Its unit (`mm`, `mm/s`, `s`; empty for a ratio or a count).
    pub unit: &'static str,
    /// Where a limit comes from, when it is another field (`tower_separation_mm`).
    pub note: Option<String>,
}

impl OutOfRange {
    /// `value` (in `unit`) is not in `allowed`.
    pub fn new(value: f64, allowed: Allowed, unit: &'static str) -> Self {
        Self {
            value,
            allowed,
            unit,
            note: None,
        }
    }

    /// With a note on where a limit comes from.
    #[must_use]
    pub fn because(mut self, note: impl Into<String>) -> Self {
        self.note = Some(note.into());
        self
    }

    /// This problem in `field`.
    pub fn at(self, field: impl Into<String>) -> FieldError {
        FieldError::new(field, self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_reject_nan_and_infinities_and_respect_open_ends() {
        for allowed in [
            Allowed::FINITE,
            Allowed::POSITIVE,
            Allowed::NON_NEGATIVE,
            Allowed::closed(0.0, 1.0),
        ] {
            assert!(!allowed.contains(f64::NAN), "{allowed}");
            assert!(!allowed.contains(f64::INFINITY), "{allowed}");
            assert!(!allowed.contains(f64::NEG_INFINITY), "{allowed}");
        }
        assert!(Allowed::NON_NEGATIVE.contains(0.0) && !Allowed::POSITIVE.contains(0.0));
        assert!(Allowed::closed(0.0, 1.0).contains(1.0));
        assert!(!Allowed::half_open(0.0, 1.0).contains(1.0));
        assert!(Allowed::at_least(0.1).contains(0.1) && !Allowed::at_least(0.1).contains(0.09));
        assert!(Allowed::at_most(3.0).contains(-5.0) && !Allowed::at_most(3.0).contains(3.5));
    }

    #[test]
    fn messages_name_value_unit_range_and_note() {
        let e = Allowed::POSITIVE.check(-1.0, "mm").unwrap_err();
        assert_eq!(
            e.to_string(),
            "-1 mm is out of range: must be finite and > 0"
        );
        let e = Allowed::half_open(0.0, 1000.0)
            .check(1200.0, "mm")
            .unwrap_err()
            .because("tower_separation_mm");
        assert_eq!(
            e.to_string(),
            "1200 mm is out of range: must be in [0, 1000) (tower_separation_mm)"
        );
        let e = Allowed::at_most(6.0).whole().check(7.0, "").unwrap_err();
        assert_eq!(e.to_string(), "7 is out of range: must be ≤ 6");
        assert_eq!(
            Allowed::between(Bound::Exclusive(0.0), Bound::Inclusive(25.0)).to_string(),
            "in (0, 25]"
        );
        assert_eq!(
            Allowed::FINITE
                .check(f64::NAN, "°")
                .unwrap_err()
                .to_string(),
            "NaN ° is out of range: must be finite"
        );
    }
}
