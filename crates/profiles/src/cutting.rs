//! Sheet cutting settings (the `cutting:` section of a `sheet_cut` profile): kerf compensation,
//! lead-ins and lead-outs, small holes, and the kerf width per material and thickness.
//!
//! ```yaml
//! cutting:
//!   compensation: geometric        # or controller (G41/G42 + tool table; linuxcnc only)
//!   lead_in: {shape: arc, length_mm: 5.0}
//!   lead_out_mm: 2.0
//!   overcut_mm: 0.0
//!   small_hole_diameter_mm: 12.0
//!   too_small_holes: error         # or skip
//!   default_material: {material: mild_steel, thickness_mm: 6.0}
//!   kerf:
//!     - {material: mild_steel, thickness_mm: 3.0, kerf_mm: 1.3}
//!     - {material: mild_steel, thickness_mm: 6.0, kerf_mm: 1.5}
//! ```
//!
//! The sequencer offsets the contours by half the kerf and places the lead-ins
//! (`cell_sequencer`); with `compensation: controller` it leaves the contours nominal and the
//! emitter writes `G41`/`G42` with the kerf in LinuxCNC's tool table instead.

use cell_config::{Allowed, FieldError};

/// Who applies the kerf offset.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Compensation {
    /// The sequencer offsets the path by half the kerf (outer contours outwards, holes
    /// inwards); the program runs on any controller.
    #[default]
    Geometric,
    /// The path stays on the nominal contour; the controller offsets it (`G41`/`G42` with the
    /// kerf as the tool diameter). LinuxCNC dialect only.
    Controller,
}

/// The shape of a lead-in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LeadShape {
    /// A straight line onto the contour.
    Line,
    /// A quarter-circle arc tangent to the contour where it meets it.
    Arc,
}

/// The lead-in: from the pierce on the scrap side onto the contour.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct LeadIn {
    /// Line or arc.
    pub shape: LeadShape,
    /// Length of the lead-in, mm (> half the widest kerf: the pierce clears the part).
    pub length_mm: f64,
}

/// What happens to a hole too small for its kerf offset or its lead-in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TooSmallHoles {
    /// The job fails, naming the hole.
    #[default]
    Error,
    /// The hole is left out with a warning naming it.
    Skip,
}

/// A material and its thickness, as the kerf table names them.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialRef {
    /// Material name, e.g. `mild_steel` (matched without regard to ASCII case).
    pub material: String,
    /// Sheet thickness, mm.
    pub thickness_mm: f64,
}

/// One row of the kerf table.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct KerfEntry {
    /// Material name.
    pub material: String,
    /// Sheet thickness, mm.
    pub thickness_mm: f64,
    /// Kerf width (the width of metal the cut removes), mm.
    pub kerf_mm: f64,
}

/// The `cutting:` section (module docs).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct CuttingSection {
    /// Geometric offset by the sequencer (default) or controller compensation.
    #[serde(default)]
    pub compensation: Compensation,
    /// The lead-in's shape and length.
    pub lead_in: LeadIn,
    /// Lead-out length, mm (0: none).
    #[serde(default)]
    pub lead_out_mm: f64,
    /// Cut past the entry point along the contour, mm (0: none).
    #[serde(default)]
    pub overcut_mm: f64,
    /// Holes whose inscribed diameter is below this get a centre pierce and a shorter arc
    /// lead, mm (0: none).
    #[serde(default)]
    pub small_hole_diameter_mm: f64,
    /// A hole too small for the offset or its lead: an error, or skipped with a warning.
    #[serde(default)]
    pub too_small_holes: TooSmallHoles,
    /// The material a job cuts when it names none.
    #[serde(default)]
    pub default_material: Option<MaterialRef>,
    /// Kerf width per material and thickness.
    pub kerf: Vec<KerfEntry>,
}

impl CuttingSection {
    /// The kerf width for `material` at `thickness_mm`: the table's row at that thickness, or
    /// the straight line between the two nearest thicknesses of that material around it.
    ///
    /// # Errors
    /// An unknown material (listing the table's), or a thickness outside the material's rows
    /// (listing them), one line each.
    ///
    /// ```
    /// # use cell_profiles::MachineProfile;
    /// let cutting = MachineProfile::resolve("linuxcnc-plasma").unwrap().cutting.unwrap();
    /// assert_eq!(cutting.kerf_mm("mild_steel", 6.0), Ok(1.5));
    /// assert!(cutting.kerf_mm("unobtainium", 6.0).unwrap_err().contains("mild_steel"));
    /// ```
    pub fn kerf_mm(&self, material: &str, thickness_mm: f64) -> Result<f64, String> {
        let mut rows: Vec<&KerfEntry> = self
            .kerf
            .iter()
            .filter(|k| k.material.eq_ignore_ascii_case(material))
            .collect();
        if rows.is_empty() {
            let mut known: Vec<&str> = Vec::new();
            for k in &self.kerf {
                if !known.contains(&k.material.as_str()) {
                    known.push(&k.material);
                }
            }
            return Err(format!(
                "no kerf for material {material:?}: the kerf table has {}",
                known.join(", ")
            ));
        }
        rows.sort_by(|a, b| a.thickness_mm.total_cmp(&b.thickness_mm));
        if let Some(exact) = rows
            .iter()
            .find(|k| (k.thickness_mm - thickness_mm).abs() <= 1e-9)
        {
            return Ok(exact.kerf_mm);
        }
        let above = rows.iter().position(|k| k.thickness_mm > thickness_mm);
        match above {
            Some(i) if i > 0 && thickness_mm.is_finite() => {
                let (a, b) = (rows[i - 1], rows[i]);
                let t = (thickness_mm - a.thickness_mm) / (b.thickness_mm - a.thickness_mm);
                Ok(a.kerf_mm + t * (b.kerf_mm - a.kerf_mm))
            }
            _ => Err(format!(
                "no kerf for {material} {thickness_mm} mm: the kerf table has {material} at {} mm",
                rows.iter()
                    .map(|k| k.thickness_mm.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }

    /// The widest kerf of the table, mm (0 for an empty table).
    pub fn widest_kerf_mm(&self) -> f64 {
        self.kerf.iter().map(|k| k.kerf_mm).fold(0.0, f64::max)
    }

    /// Checks the values: lengths ≥ 0, a kerf table of distinct rows with names, thicknesses
    /// and kerfs > 0, a lead-in longer than half the widest kerf, and a default material the
    /// table covers. Fields are named relative to `cutting`. Whether the machine supports
    /// `compensation: controller` is checked by the profile (it needs the G-code dialect).
    ///
    /// # Errors
    /// The first field with a problem.
    pub fn validate(&self) -> Result<(), FieldError> {
        for (field, v) in [
            ("lead_out_mm", self.lead_out_mm),
            ("overcut_mm", self.overcut_mm),
            ("small_hole_diameter_mm", self.small_hole_diameter_mm),
        ] {
            Allowed::NON_NEGATIVE.check_field(field, v, "mm")?;
        }
        self.validate_kerf_table()?;
        let half_kerf = self.widest_kerf_mm() / 2.0;
        Allowed::between(
            cell_config::Bound::Exclusive(half_kerf),
            cell_config::Bound::Unbounded,
        )
        .check(self.lead_in.length_mm, "mm")
        .map_err(|e| {
            e.because("the pierce must clear the part by more than half the widest kerf")
                .at("lead_in.length_mm")
        })?;
        if let Some(m) = &self.default_material {
            self.kerf_mm(&m.material, m.thickness_mm)
                .map_err(|reason| FieldError::new("default_material", reason))?;
        }
        Ok(())
    }

    /// At least one row; each with a material name, thickness and kerf > 0; no two rows for
    /// the same material and thickness.
    fn validate_kerf_table(&self) -> Result<(), FieldError> {
        if self.kerf.is_empty() {
            return Err(FieldError::new("kerf", "at least one row is needed"));
        }
        for (i, row) in self.kerf.iter().enumerate() {
            let field = |name: &str| format!("kerf[{i}].{name}");
            if row.material.trim().is_empty() {
                return Err(FieldError::new(field("material"), "must not be empty"));
            }
            Allowed::POSITIVE.check_field(&field("thickness_mm"), row.thickness_mm, "mm")?;
            Allowed::POSITIVE.check_field(&field("kerf_mm"), row.kerf_mm, "mm")?;
            if let Some(j) = self.kerf[..i].iter().position(|o| {
                o.material.eq_ignore_ascii_case(&row.material) && o.thickness_mm == row.thickness_mm
            }) {
                return Err(FieldError::new(
                    format!("kerf[{i}]"),
                    format!(
                        "{} {} mm is already in kerf[{j}]",
                        row.material, row.thickness_mm
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{MachineProfile, ProfileError, EMBEDDED_PROFILES};

    fn embedded(name: &str) -> String {
        EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap()
            .1
            .to_string()
    }

    fn plasma() -> CuttingSection {
        MachineProfile::resolve("linuxcnc-plasma")
            .unwrap()
            .cutting
            .unwrap()
    }

    #[test]
    fn every_sheet_profile_has_a_cutting_section_that_parses() {
        for (name, _) in EMBEDDED_PROFILES {
            let p = MachineProfile::resolve(name).unwrap();
            assert_eq!(
                p.cutting.is_some(),
                p.process == crate::Process::SheetCut,
                "{name}"
            );
        }
        let c = plasma();
        assert_eq!(c.compensation, Compensation::Geometric);
        assert_eq!(
            c.lead_in,
            LeadIn {
                shape: LeadShape::Arc,
                length_mm: 5.0
            }
        );
        assert_eq!((c.lead_out_mm, c.overcut_mm), (2.0, 0.0));
        assert_eq!(c.too_small_holes, TooSmallHoles::Error);
        let m = c.default_material.as_ref().unwrap();
        assert_eq!((m.material.as_str(), m.thickness_mm), ("mild_steel", 6.0));
        // Optional keys take their defaults.
        let text = "lead_in: {shape: line, length_mm: 3.0}\n\
                    kerf: [{material: mild_steel, thickness_mm: 2.0, kerf_mm: 0.2}]\n";
        let c: CuttingSection = cell_config::from_yaml_str(text, "c.yaml").unwrap();
        assert_eq!(c.compensation, Compensation::Geometric);
        assert_eq!(c.too_small_holes, TooSmallHoles::Error);
        assert_eq!(
            (c.lead_out_mm, c.overcut_mm, c.small_hole_diameter_mm),
            (0.0, 0.0, 0.0)
        );
        assert!(c.default_material.is_none());
        c.validate().unwrap();
    }

    #[test]
    fn kerf_is_the_row_or_the_line_between_the_nearest_rows() {
        let c = plasma();
        assert_eq!(c.kerf_mm("mild_steel", 6.0), Ok(1.5));
        assert_eq!(c.kerf_mm("Mild_Steel", 3.0), Ok(1.3));
        // 7 mm: halfway between 6 mm (1.5) and 8 mm (1.7).
        let k = c.kerf_mm("mild_steel", 7.0).unwrap();
        assert!((k - 1.6).abs() < 1e-12, "{k}");
        // 5 mm: halfway between 4 mm (1.4) and 6 mm (1.5), not between 3 and 10.
        let k = c.kerf_mm("mild_steel", 5.0).unwrap();
        assert!((k - 1.45).abs() < 1e-12, "{k}");
        // Rows in any order.
        let mut shuffled = c.clone();
        shuffled.kerf.reverse();
        assert_eq!(
            shuffled.kerf_mm("mild_steel", 7.0),
            c.kerf_mm("mild_steel", 7.0)
        );
    }

    #[test]
    fn a_thickness_outside_the_table_or_an_unknown_material_lists_the_table() {
        let c = plasma();
        for t in [2.0, 12.0, f64::NAN, f64::INFINITY] {
            let e = c.kerf_mm("mild_steel", t).unwrap_err();
            assert_eq!(
                e,
                format!(
                    "no kerf for mild_steel {t} mm: the kerf table has mild_steel at 3, 4, 6, 8, 10 mm"
                )
            );
        }
        let e = c.kerf_mm("copper", 6.0).unwrap_err();
        assert_eq!(
            e,
            "no kerf for material \"copper\": the kerf table has mild_steel, stainless_steel, aluminium"
        );
    }

    #[test]
    fn bad_values_name_their_field() {
        for (profile, from, to, field) in [
            (
                "linuxcnc-plasma",
                "lead_out_mm: 2.0",
                "lead_out_mm: -2.0",
                "cutting.lead_out_mm",
            ),
            (
                "linuxcnc-plasma",
                "overcut_mm: 0.0",
                "overcut_mm: .nan",
                "cutting.overcut_mm",
            ),
            (
                "linuxcnc-plasma",
                "small_hole_diameter_mm: 12.0",
                "small_hole_diameter_mm: -1",
                "cutting.small_hole_diameter_mm",
            ),
            // Shorter than half the widest kerf (2.0 mm stainless): the pierce is on the part.
            (
                "linuxcnc-plasma",
                "length_mm: 5.0",
                "length_mm: 0.9",
                "cutting.lead_in.length_mm",
            ),
            (
                "linuxcnc-plasma",
                "thickness_mm: 6.0, kerf_mm: 1.5",
                "thickness_mm: 6.0, kerf_mm: 0",
                "cutting.kerf[2].kerf_mm",
            ),
            (
                "linuxcnc-plasma",
                "thickness_mm: 4.0, kerf_mm: 1.4",
                "thickness_mm: -4.0, kerf_mm: 1.4",
                "cutting.kerf[1].thickness_mm",
            ),
            (
                "linuxcnc-plasma",
                "{material: mild_steel, thickness_mm: 3.0",
                "{material: \" \", thickness_mm: 3.0",
                "cutting.kerf[0].material",
            ),
            (
                "linuxcnc-plasma",
                "thickness_mm: 4.0, kerf_mm: 1.4",
                "thickness_mm: 3.0, kerf_mm: 1.4",
                "cutting.kerf[1]",
            ),
            (
                "linuxcnc-plasma",
                "default_material: {material: mild_steel, thickness_mm: 6.0}",
                "default_material: {material: mild_steel, thickness_mm: 25.0}",
                "cutting.default_material",
            ),
            // Controller compensation on GRBL: no G41/G42 there.
            (
                "grbl-laser",
                "compensation: geometric",
                "compensation: controller",
                "cutting.compensation",
            ),
            // A cutting section on a hot-wire machine.
            (
                "grbl-xy",
                "gcode:\n",
                "cutting:\n  lead_in: {shape: arc, length_mm: 5.0}\n  kerf: [{material: a, thickness_mm: 1, kerf_mm: 1}]\ngcode:\n",
                "cutting",
            ),
        ] {
            let text = embedded(profile).replacen(from, to, 1);
            assert_ne!(text, embedded(profile), "{from}");
            let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(&e, ProfileError::Invalid { field: f, .. } if f == field),
                "{profile} {to}: {e}"
            );
            assert!(e.to_string().starts_with("m.yaml: field `"), "{e}");
        }
        // Controller compensation is fine on LinuxCNC.
        let text = embedded("linuxcnc-plasma")
            .replace("compensation: geometric", "compensation: controller");
        let p = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap();
        assert_eq!(p.cutting.unwrap().compensation, Compensation::Controller);
        // An empty kerf table.
        let c = CuttingSection {
            kerf: Vec::new(),
            ..plasma()
        };
        assert_eq!(c.validate().unwrap_err().field, "kerf");
    }

    #[test]
    fn mistyped_keys_and_values_name_the_line() {
        for (from, to, what) in [
            ("lead_out_mm:", "leadout_mm:", "leadout_mm"),
            ("shape: arc", "shape: spiral", "spiral"),
            (
                "too_small_holes: error",
                "too_small_holes: ignore",
                "ignore",
            ),
            ("compensation: geometric", "compensation: g41", "g41"),
            ("kerf_mm: 1.5}", "kerf_mm: 1.5, gas: air}", "gas"),
        ] {
            let text = embedded("linuxcnc-plasma").replacen(from, to, 1);
            let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(
                    &e,
                    ProfileError::Parse(cell_config::ParseError { line: Some(_), .. })
                ),
                "{to}: {e}"
            );
            let msg = e.to_string();
            assert!(msg.contains("cutting") && msg.contains(what), "{msg}");
        }
    }
}
