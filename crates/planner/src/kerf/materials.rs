//! Foam (material) and wire (tool) libraries for the kerf model (seed 001 §4.7: "tool
//! definition library, material definition library"), read from YAML.

use std::collections::BTreeMap;
use std::path::Path;

use cell_config::{Allowed, ParseError, Place, Problem};
use serde::Deserialize;

/// What went wrong reading a library file. `file` is the path or source name.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// Path as given.
        file: String,
        /// Underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// YAML syntax error, unknown or missing key, wrong type, with the line and key path
    /// (`my_foams.yaml:4: field `foams.xps.densty_kg_m3`: unknown field …`).
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A value is out of its domain or inconsistent.
    #[error("{}{reason}", Place::field(file, key))]
    Invalid {
        /// Source name.
        file: String,
        /// Key path, e.g. `foams.xps.density_kg_m3`.
        key: String,
        /// What is wrong: a value out of range, or a rule between keys.
        reason: Problem,
    },
    /// The same foam or wire id is defined twice across the files of a library.
    #[error("{file}: {key} is already defined")]
    Duplicate {
        /// Source name of the second definition.
        file: String,
        /// Key path, e.g. `wires.nichrome_0_36mm`.
        key: String,
    },
}

/// A foam's constants for seed 001 eq. 5–6 (SI).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Foam {
    /// Human-readable name.
    pub description: String,
    /// Density ρ_f (kg/m³).
    pub density_kg_m3: f64,
    /// ^mass Q_eff (J/kg), if given (preferred by [`Foam::mass_energy_j_kg`]).
    #[serde(default)]
    pub mass_specific_energy_j_kg: Option<f64>,
    /// ^vol Q_eff (J/m³), if given.
    #[serde(default)]
    pub volume_specific_energy_j_m3: Option<f64>,
    /// Relative standard deviation of the energy (0.10 for the paper's foams).
    pub sd_fraction: f64,
    /// Other names users call this foam by (e.g. `EPS`), matched case-insensitively.
    #[serde(default)]
    pub aliases: Vec<String>,
}

impl Foam {
    /// ^mass Q_eff (J/kg) for eq. 5: the given value, else ^vol Q_eff / ρ_f (seed 001 eq. 6).
    /// A loaded library guarantees one of them is present and positive.
    pub fn mass_energy_j_kg(&self) -> f64 {
        self.mass_specific_energy_j_kg.unwrap_or_else(|| {
            self.volume_specific_energy_j_m3.unwrap_or(f64::NAN) / self.density_kg_m3
        })
    }
}

/// A hot wire (seed 001 tool library entry).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wire {
    /// Human-readable name.
    pub description: String,
    /// Diameter d (m): the lower bound of the kerf.
    pub diameter_m: f64,
    /// Resistance per metre R' (Ω/m).
    pub resistance_ohm_per_m: f64,
}

/// Foams and wires by id. Both sections of a file are optional; ids must be unique.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialLibrary {
    /// Foams by id (e.g. `xps`, `eps_h_grade`).
    #[serde(default)]
    pub foams: BTreeMap<String, Foam>,
    /// Wires by id (e.g. `nichrome_0_36mm`).
    #[serde(default)]
    pub wires: BTreeMap<String, Wire>,
}

const BUILTIN_FOAMS: &str = include_str!("../../../../config/materials/foams.yaml");
const BUILTIN_WIRES: &str = include_str!("../../../../config/materials/wires.yaml");

impl MaterialLibrary {
    /// The library shipped in `config/materials/` (`foams.yaml` + `wires.yaml`), compiled in so
    /// the planner works without a config directory.
    pub fn builtin() -> Self {
        let parsed =
            Self::from_yaml_str(BUILTIN_FOAMS, "config/materials/foams.yaml").and_then(|foams| {
                foams.merged(
                    Self::from_yaml_str(BUILTIN_WIRES, "config/materials/wires.yaml")?,
                    "config/materials/wires.yaml",
                )
            });
        // The embedded files are tested (`builtin_library_loads`), so this cannot fail at run time.
        parsed.unwrap_or_default()
    }

    /// Parses one library file's text; `source_name` names it in errors.
    ///
    /// # Errors
    /// [`MaterialError::Parse`] for YAML errors and unknown keys (serde `deny_unknown_fields`),
    /// [`MaterialError::Invalid`] for values out of range (see [`MaterialLibrary::validate`]).
    pub fn from_yaml_str(text: &str, source_name: &str) -> Result<Self, MaterialError> {
        let lib: Self = cell_config::from_yaml_str(text, source_name)?;
        lib.validate(source_name)?;
        Ok(lib)
    }

    /// Reads one library file.
    ///
    /// # Errors
    /// As [`MaterialLibrary::from_yaml_str`], plus [`MaterialError::Io`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, MaterialError> {
        let file = path.as_ref().display().to_string();
        let text = std::fs::read_to_string(path.as_ref()).map_err(|source| MaterialError::Io {
            file: file.clone(),
            source,
        })?;
        Self::from_yaml_str(&text, &file)
    }

    /// Reads `foams.yaml` and `wires.yaml` from `dir` (a copy of `config/materials/`) and merges
    /// them.
    ///
    /// # Errors
    /// As [`MaterialLibrary::load`], plus [`MaterialError::Duplicate`] for an id in both.
    pub fn load_dir(dir: impl AsRef<Path>) -> Result<Self, MaterialError> {
        let wires = dir.as_ref().join("wires.yaml");
        Self::load(dir.as_ref().join("foams.yaml"))?
            .merged(Self::load(&wires)?, &wires.display().to_string())
    }

    /// A foam by id.
    pub fn foam(&self, id: &str) -> Option<&Foam> {
        self.foams.get(id)
    }

    /// A wire by id.
    pub fn wire(&self, id: &str) -> Option<&Wire> {
        self.wires.get(id)
    }

    /// A foam by id or alias, case-insensitive (what users type: `EPS`, `xps`, `eps_h_grade`).
    pub fn find_foam(&self, name: &str) -> Option<&Foam> {
        self.foams
            .iter()
            .find(|(id, f)| {
                id.eq_ignore_ascii_case(name)
                    || f.aliases.iter().any(|a| a.eq_ignore_ascii_case(name))
            })
            .map(|(_, f)| f)
    }

    /// A wire by id, case-insensitive.
    pub fn find_wire(&self, name: &str) -> Option<&Wire> {
        self.wires
            .iter()
            .find(|(id, _)| id.eq_ignore_ascii_case(name))
            .map(|(_, w)| w)
    }

    /// Every name [`MaterialLibrary::find_foam`] accepts: ids, then aliases in parentheses.
    pub fn foam_names(&self) -> Vec<String> {
        self.foams
            .iter()
            .map(|(id, f)| {
                if f.aliases.is_empty() {
                    id.clone()
                } else {
                    format!("{id} ({})", f.aliases.join(", "))
                }
            })
            .collect()
    }

    /// Checks every value: densities, energies, diameters and resistances finite and > 0, at
    /// least one energy per foam (both within 1 % of each other by eq. 6 if both are given),
    /// `sd_fraction` in [0, 1).
    ///
    /// # Errors
    /// [`MaterialError::Invalid`] naming `source_name` and the key path.
    pub fn validate(&self, source_name: &str) -> Result<(), MaterialError> {
        let invalid = |key: String, reason: Problem| MaterialError::Invalid {
            file: source_name.into(),
            key,
            reason,
        };
        let in_range = |key: String, v: f64, allowed: Allowed, unit: &'static str| {
            allowed.check(v, unit).map_err(|e| invalid(key, e.into()))
        };
        for (id, f) in &self.foams {
            let key = |field: &str| format!("foams.{id}.{field}");
            let positive = Allowed::POSITIVE;
            in_range(key("density_kg_m3"), f.density_kg_m3, positive, "kg/m³")?;
            if let Some(m) = f.mass_specific_energy_j_kg {
                in_range(key("mass_specific_energy_j_kg"), m, positive, "J/kg")?;
            }
            if let Some(v) = f.volume_specific_energy_j_m3 {
                in_range(key("volume_specific_energy_j_m3"), v, positive, "J/m³")?;
            }
            match (f.mass_specific_energy_j_kg, f.volume_specific_energy_j_m3) {
                (None, None) => {
                    return Err(invalid(
                        format!("foams.{id}"),
                        "needs mass_specific_energy_j_kg or volume_specific_energy_j_m3".into(),
                    ))
                }
                (Some(m), Some(v)) if ((m * f.density_kg_m3 - v) / v).abs() > 0.01 => {
                    return Err(invalid(
                        key("volume_specific_energy_j_m3"),
                        format!(
                            "{v} disagrees with mass_specific_energy_j_kg × density_kg_m3 = {} \
                             by more than 1 % (seed 001 eq. 6)",
                            m * f.density_kg_m3
                        )
                        .into(),
                    ))
                }
                _ => {}
            }
            in_range(
                key("sd_fraction"),
                f.sd_fraction,
                Allowed::half_open(0.0, 1.0),
                "",
            )?;
        }
        let mut names: Vec<(String, String)> = Vec::new();
        for (id, f) in &self.foams {
            for name in std::iter::once(id).chain(&f.aliases) {
                let lower = name.to_ascii_lowercase();
                if let Some((_, owner)) = names.iter().find(|(n, _)| *n == lower) {
                    return Err(invalid(
                        format!("foams.{id}.aliases"),
                        format!("{name:?} already names foams.{owner}").into(),
                    ));
                }
                names.push((lower, id.clone()));
            }
        }
        for (id, w) in &self.wires {
            in_range(
                format!("wires.{id}.diameter_m"),
                w.diameter_m,
                Allowed::POSITIVE,
                "m",
            )?;
            in_range(
                format!("wires.{id}.resistance_ohm_per_m"),
                w.resistance_ohm_per_m,
                Allowed::POSITIVE,
                "Ω/m",
            )?;
        }
        Ok(())
    }

    fn merged(mut self, other: Self, other_name: &str) -> Result<Self, MaterialError> {
        let dup = |key: String| MaterialError::Duplicate {
            file: other_name.into(),
            key,
        };
        for (id, f) in other.foams {
            if self.foams.contains_key(&id) {
                return Err(dup(format!("foams.{id}")));
            }
            self.foams.insert(id, f);
        }
        for (id, w) in other.wires {
            if self.wires.contains_key(&id) {
                return Err(dup(format!("wires.{id}")));
            }
            self.wires.insert(id, w);
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_library_loads() {
        let lib = MaterialLibrary::from_yaml_str(BUILTIN_FOAMS, "foams.yaml")
            .and_then(|f| {
                f.merged(
                    MaterialLibrary::from_yaml_str(BUILTIN_WIRES, "wires.yaml")?,
                    "wires.yaml",
                )
            })
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(lib, MaterialLibrary::builtin());
        assert_eq!(
            lib.foams.keys().collect::<Vec<_>>(),
            ["eps_h_grade", "eps_s_grade", "xps"]
        );
        assert_eq!(lib.wires.keys().collect::<Vec<_>>(), ["nichrome_0_36mm"]);
        let xps = lib.foam("xps").unwrap();
        assert!(
            (xps.mass_energy_j_kg() - 10.1e6 / 30.0).abs() < 1e-6,
            "eq. 6 from 10.1 MJ/m³"
        );
        assert_eq!(lib.foam("eps_s_grade").unwrap().mass_energy_j_kg(), 297e3);
        assert_eq!(
            lib.wire("nichrome_0_36mm").unwrap().resistance_ohm_per_m,
            10.58
        );
        assert!(lib.foam("epp").is_none(), "seed 001 gives no EPP values");
    }

    #[test]
    fn load_dir_reads_config() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/materials");
        assert_eq!(
            MaterialLibrary::load_dir(dir).unwrap(),
            MaterialLibrary::builtin()
        );
    }

    #[test]
    fn unknown_key_names_file_and_key() {
        let text =
            "foams:\n  xps:\n    description: x\n    densty_kg_m3: 30\n    sd_fraction: 0.1\n";
        let e = MaterialLibrary::from_yaml_str(text, "my_foams.yaml").unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("my_foams.yaml:4: "), "{msg}");
        assert!(
            msg.contains("densty_kg_m3") && msg.contains("foams.xps"),
            "{msg}"
        );
        assert!(
            matches!(e, MaterialError::Parse(ParseError { line: Some(4), .. })),
            "{e:?}"
        );
        let e = MaterialLibrary::from_yaml_str("foam: {}\n", "top.yaml").unwrap_err();
        assert!(e.to_string().contains("foam"), "{e}");
    }

    #[test]
    fn invalid_values_name_the_key() {
        let cases = [
            ("foams:\n  f:\n    description: x\n    density_kg_m3: -1\n    mass_specific_energy_j_kg: 1\n    sd_fraction: 0.1\n", "foams.f.density_kg_m3"),
            ("foams:\n  f:\n    description: x\n    density_kg_m3: 20\n    sd_fraction: 0.1\n", "foams.f"),
            ("foams:\n  f:\n    description: x\n    density_kg_m3: 26\n    mass_specific_energy_j_kg: 297000\n    volume_specific_energy_j_m3: 9000000\n    sd_fraction: 0.1\n", "foams.f.volume_specific_energy_j_m3"),
            ("foams:\n  f:\n    description: x\n    density_kg_m3: 26\n    mass_specific_energy_j_kg: 297000\n    sd_fraction: 1.5\n", "foams.f.sd_fraction"),
            ("wires:\n  w:\n    description: x\n    diameter_m: 0\n    resistance_ohm_per_m: 10\n", "wires.w.diameter_m"),
        ];
        for (text, key) in cases {
            let e = MaterialLibrary::from_yaml_str(text, "lib.yaml").unwrap_err();
            assert!(
                matches!(&e, MaterialError::Invalid { key: k, .. } if k == key),
                "{e}"
            );
            assert!(
                e.to_string()
                    .starts_with(&format!("lib.yaml: field `{key}`:")),
                "{e}"
            );
        }
    }

    #[test]
    fn duplicate_ids_are_rejected() {
        let a = MaterialLibrary::builtin();
        let e = a.clone().merged(a, "again.yaml").unwrap_err();
        assert_eq!(
            e.to_string(),
            "again.yaml: foams.eps_h_grade is already defined"
        );
    }
}
