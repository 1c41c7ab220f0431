//! Where a configuration problem is: the prefix every configuration message starts with.

use std::fmt;

/// `FILE[:LINE]: [field `PATH`: ]`: the file, the line when known and the dotted path of the
/// field when known. Every configuration error writes this, then what is wrong, so all of them
/// read alike and an editor can jump to `FILE:LINE`.
///
/// ```
/// use cell_config::Place;
/// let at = Place { file: "m.yaml", line: Some(4), field: Some("axes.X") };
/// assert_eq!(format!("{at}bad"), "m.yaml:4: field `axes.X`: bad");
/// assert_eq!(format!("{}bad", Place::file("m.yaml")), "m.yaml: bad");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Place<'a> {
    /// The file, or a name for text that has none (e.g. `<layout_json>`).
    pub file: &'a str,
    /// 1-based line, when known.
    pub line: Option<u32>,
    /// Dotted path of the field (`hotwire.supply_a`, `parts[2].outer`), when known.
    pub field: Option<&'a str>,
}

impl<'a> Place<'a> {
    /// A whole file.
    pub fn file(file: &'a str) -> Self {
        Self {
            file,
            line: None,
            field: None,
        }
    }

    /// One field of a file, without a line (what a validator knows).
    pub fn field(file: &'a str, field: &'a str) -> Self {
        Self {
            file,
            line: None,
            field: Some(field),
        }
    }
}

impl fmt::Display for Place<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        f.write_str(": ")?;
        if let Some(field) = self.field {
            write!(f, "field `{field}`: ")?;
        }
        Ok(())
    }
}
