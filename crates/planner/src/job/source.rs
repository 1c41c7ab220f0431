//! Where a section comes from: a name from the sections compiled in from `config/airfoils/`, or
//! a UIUC `.dat` file.

use std::path::PathBuf;

use crate::airfoil::Airfoil;

use super::JobError;

/// The UIUC sections shipped in `config/airfoils/`, compiled in: (name, `.dat` text).
pub const EMBEDDED_AIRFOILS: &[(&str, &str)] = &[
    ("ag24", include_str!("../../../../config/airfoils/ag24.dat")),
    (
        "clarky",
        include_str!("../../../../config/airfoils/clarky.dat"),
    ),
    ("e387", include_str!("../../../../config/airfoils/e387.dat")),
    ("mh32", include_str!("../../../../config/airfoils/mh32.dat")),
    (
        "naca0012",
        include_str!("../../../../config/airfoils/naca0012.dat"),
    ),
    (
        "psu94097",
        include_str!("../../../../config/airfoils/psu94097.dat"),
    ),
    ("rg15", include_str!("../../../../config/airfoils/rg15.dat")),
    (
        "s1223",
        include_str!("../../../../config/airfoils/s1223.dat"),
    ),
    (
        "sd7037",
        include_str!("../../../../config/airfoils/sd7037.dat"),
    ),
];

/// Where a section comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AirfoilSource {
    /// A name from [`EMBEDDED_AIRFOILS`] (case-insensitive, e.g. `s1223`).
    Named(String),
    /// A UIUC `.dat` file.
    File(PathBuf),
}

impl AirfoilSource {
    /// Interprets a user's string: a path if it contains a path separator or ends in `.dat`,
    /// or names no embedded section but an existing file; else an embedded name.
    pub fn parse(text: &str) -> Self {
        let looks_like_path = text.contains('/')
            || text.contains(std::path::MAIN_SEPARATOR)
            || text.to_ascii_lowercase().ends_with(".dat");
        if looks_like_path || (embedded(text).is_none() && std::path::Path::new(text).is_file()) {
            Self::File(PathBuf::from(text))
        } else {
            Self::Named(text.to_string())
        }
    }

    /// Reads the section (chord-normalised, as in the file).
    ///
    /// # Errors
    /// [`JobError::UnknownAirfoil`] for a name that is not embedded; [`JobError::Airfoil`]
    /// (naming the file and line) for an unreadable or malformed file.
    pub fn load(&self) -> Result<Airfoil, JobError> {
        match self {
            Self::Named(name) => {
                let (key, text) = embedded(name)
                    .ok_or_else(|| JobError::UnknownAirfoil { name: name.clone() })?;
                Ok(Airfoil::from_dat_str(
                    text,
                    &format!("config/airfoils/{key}.dat"),
                )?)
            }
            Self::File(path) => Ok(Airfoil::load(path)?),
        }
    }
}

impl std::fmt::Display for AirfoilSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Named(n) => f.write_str(n),
            Self::File(p) => write!(f, "{}", p.display()),
        }
    }
}

fn embedded(name: &str) -> Option<(&'static str, &'static str)> {
    EMBEDDED_AIRFOILS
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .copied()
}
