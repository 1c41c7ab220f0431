//! The wing spec (YAML, `config/wings/*.yaml`) and the G-Wing pipeline: airfoil → lifting line
//! → spars → sections → layers.

use std::path::{Path, PathBuf};

use cell_airfoil::{Airfoil, AirfoilError, SurfaceFunctions};
use cell_config::{Allowed, OutOfRange, ParseError, Place, Problem};
use nalgebra::Point2;
use serde::Deserialize;

pub use crate::design::{ChordShape, Design};
use crate::design::{DesignError, DesignReport, Designed};
use crate::layers::{section_layers, BuildParams, Layer, Planform};
use crate::llt::{LiftingLine, LltError, Solution};
use crate::section::{split, Section, SectionError};
use crate::spacing::SpacingRule;
use crate::structure::{bending_moment_n_mm, place_spars, SparLayout, StructureParams};

/// What went wrong loading a spec or designing the wing.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The spec file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// Path as given.
        file: String,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The YAML did not parse or has a wrong or unknown field (with its line and path).
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A field is out of its domain.
    #[error("{}{reason}", Place::field(file, field))]
    Invalid {
        /// Spec file.
        file: String,
        /// Field path, e.g. `build.layer_height_mm`.
        field: &'static str,
        /// The value, its unit and the accepted range.
        reason: Problem,
    },
    /// The airfoil file.
    #[error(transparent)]
    Airfoil(#[from] AirfoilError),
    /// The lifting-line design.
    #[error(transparent)]
    Llt(#[from] LltError),
    /// A design-case field (`aero.design.…`, [`crate::design`]) is invalid; `file` is empty
    /// when the error comes from [`Wing::design`], whose callers name the file.
    #[error("{}{error}", if file.is_empty() { String::new() } else { format!("{file}: ") })]
    Design {
        /// Spec file, or empty.
        file: String,
        /// The field, from `aero.design`, and its problem.
        error: cell_config::FieldError,
    },
    /// The section split.
    #[error(transparent)]
    Section(#[from] SectionError),
}

/// A G-Wing design: aerodynamics, loads, structure and build settings.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WingSpec {
    /// Selig/Lednicer `.dat` airfoil, relative to the spec file.
    pub airfoil: PathBuf,
    /// Aerodynamic design.
    pub aero: AeroSpec,
    /// Flight loads for the structure.
    pub loads: LoadSpec,
    /// Structure (Algorithm 1).
    #[serde(default)]
    pub structure: StructureSpec,
    /// Build settings (Table 3 and the printer).
    #[serde(default)]
    pub build: BuildSpec,
}

/// Aerodynamic design (seed 002 Table 1).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AeroSpec {
    /// Span b \[mm\].
    pub span_mm: f64,
    /// Aspect ratio AR = b²/S.
    pub aspect_ratio: f64,
    /// LLT stations n. Default 400 (the paper's example).
    #[serde(default = "default_stations")]
    pub stations: usize,
    /// 2-D lift slope a \[1/rad\]. Default 2π.
    #[serde(default = "default_lift_slope")]
    pub lift_slope_per_rad: f64,
    /// Airfoil zero-lift angle α_L0 \[deg\]; added to the LLT α for the built twist. Default 0.
    #[serde(default)]
    pub alpha_l0_deg: f64,
    /// The design case ([`crate::design`]).
    pub design: Design,
}

/// Flight loads.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Aircraft gross weight W_G \[N\], carried as a point load at the centre.
    pub gross_weight_n: f64,
    /// Load factor applied to the lift. Default 1.
    #[serde(default = "one")]
    pub load_factor: f64,
}

/// Structure (Algorithm 1; defaults: PLA, FS 20, the G-Wing example's AM spacing rule, whose
/// floor r*·w_e is Table 2's 30 mm at w_e = 0.5 mm).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StructureSpec {
    /// σ_y \[MPa\]. Default 26 (PLA, notes).
    pub yield_strength_mpa: f64,
    /// Factor of safety. Default 20 (notes).
    pub safety_factor: f64,
    /// η* of the AM spar spacing rule Δx_max = max(min(κ_US, κ_LS)·w_e²/η*, r*·w_e)
    /// ([`crate::spacing`], Alg. 1 step 5, ref. \[8\]). Default 2e-5 (the G-Wing example).
    pub am_eta_star: f64,
    /// r* of the same rule: the floor r*·w_e. Default 60 (30 mm at w_e = 0.5 mm, Table 2).
    pub am_r_star: f64,
    /// Optional hard cap on every spar gap \[mm\], applied over the rule (none by default: the
    /// rule alone; set it to hold a spacing no curvature may widen).
    pub max_spar_spacing_mm: Option<f64>,
    /// Hinge line chord fraction. Default 0.8 (Fig. 5).
    pub hinge_x_over_c: f64,
    /// Hinge height in local thickness above the lower surface. Default 1 (upper surface).
    pub hinge_z_over_t: f64,
}

impl Default for StructureSpec {
    fn default() -> Self {
        Self {
            yield_strength_mpa: 26.0,
            safety_factor: 20.0,
            am_eta_star: 2e-5,
            am_r_star: 60.0,
            max_spar_spacing_mm: None,
            hinge_x_over_c: 0.8,
            hinge_z_over_t: 1.0,
        }
    }
}

/// Build settings; defaults are Table 3 and a 220 × 220 mm Marlin bed.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BuildSpec {
    /// Nozzle diameter \[mm\]. Default 0.4 (Table 3; informational).
    pub nozzle_diameter_mm: f64,
    /// Layer height \[mm\]. Default 0.2.
    pub layer_height_mm: f64,
    /// First layer height \[mm\]. Default 0.2.
    pub first_layer_height_mm: f64,
    /// Extrusion width \[mm\]. Default 0.5.
    pub extrusion_width_mm: f64,
    /// Filament diameter \[mm\]. Default 1.75.
    pub filament_diameter_mm: f64,
    /// Material density \[kg/m³\]. Default 1240 (PLA).
    pub density_kg_m3: f64,
    /// Perimeter speed \[mm/s\]. Default 40.
    pub perimeter_speed_mm_s: f64,
    /// Infill (spar) speed \[mm/s\]. Default 40.
    pub infill_speed_mm_s: f64,
    /// Solid infill (rib) speed \[mm/s\]. Default 60.
    pub solid_infill_speed_mm_s: f64,
    /// First layer speed \[mm/s\]. Default 30.
    pub first_layer_speed_mm_s: f64,
    /// Travel speed \[mm/s\]. Default 80.
    pub travel_speed_mm_s: f64,
    /// Retract length \[mm\]. Default 0.8.
    pub retract_mm: f64,
    /// Retract speed \[mm/s\]. Default 35.
    pub retract_speed_mm_s: f64,
    /// Z-hop \[mm\]. Default 0.4.
    pub z_hop_mm: f64,
    /// Spar ends inset, in bead widths. Default 0.6.
    pub spar_overlap: f64,
    /// Max build height z_max \[mm\]. Default 150.
    pub z_max_mm: f64,
    /// Centre section width w_c \[mm\]. Default 50.
    pub centre_width_mm: f64,
    /// Bed X \[mm\]. Default 220.
    pub bed_x_mm: f64,
    /// Bed Y \[mm\]. Default 220.
    pub bed_y_mm: f64,
}

impl Default for BuildSpec {
    fn default() -> Self {
        Self {
            nozzle_diameter_mm: 0.4,
            layer_height_mm: 0.2,
            first_layer_height_mm: 0.2,
            extrusion_width_mm: 0.5,
            filament_diameter_mm: 1.75,
            density_kg_m3: 1240.0,
            perimeter_speed_mm_s: 40.0,
            infill_speed_mm_s: 40.0,
            solid_infill_speed_mm_s: 60.0,
            first_layer_speed_mm_s: 30.0,
            travel_speed_mm_s: 80.0,
            retract_mm: 0.8,
            retract_speed_mm_s: 35.0,
            z_hop_mm: 0.4,
            spar_overlap: 0.6,
            z_max_mm: 150.0,
            centre_width_mm: 50.0,
            bed_x_mm: 220.0,
            bed_y_mm: 220.0,
        }
    }
}

/// Most lifting-line stations (issue 23: the solve builds two n × n matrices, 8n² bytes each,
/// and factors them in O(n³); 200 000 stations would take 640 GB). 5× the paper's 400: 32 MB
/// matrices and a factorisation of a few seconds.
pub const MAX_STATIONS: usize = 2_000;

/// Most printable sections, `2·⌈(span − centre)/2 / z_max⌉ + 1` (issue 23). A 1.5 m span in
/// 150 mm sections is 11; the limit is ~20× that.
pub const MAX_SECTIONS: usize = 201;

/// Most layers in one section, `z_max / layer_height` (issue 23: a 1e-9 mm layer height). The
/// defaults give 750 (150 mm at 0.2 mm); the limit is 10× a 150 mm section at 0.1 mm.
pub const MAX_LAYERS_PER_SECTION: usize = 15_000;

/// Most layers over the whole wing, `span / layer_height` (issue 23). A 1.5 m wing at 0.2 mm
/// is 7 500; the limit is ~13× that.
pub const MAX_WING_LAYERS: usize = 100_000;

/// Most spar gaps or rib lines across one chord: `c_max / max_spar_spacing` and
/// `c_max / extrusion_width`, with `c_max = 2·span/AR` bounding every chord the planform can
/// have (a taper's root chord is `2/(1 + λ)` times the mean `span/AR`, an ellipse's 4/π)
/// (issue 23). Table 2's wing has ~5 spars and ~300 rib lines per chord.
pub const MAX_LINES_PER_CHORD: usize = 5_000;

fn default_stations() -> usize {
    400
}
fn default_lift_slope() -> f64 {
    2.0 * std::f64::consts::PI
}
fn one() -> f64 {
    1.0
}

impl WingSpec {
    /// Parses spec YAML; `file` names the source in errors.
    pub fn from_yaml_str(text: &str, file: &str) -> Result<Self, SpecError> {
        let spec: Self = cell_config::from_yaml_str(text, file)?;
        spec.validate(file)?;
        Ok(spec)
    }

    /// Reads a spec file; the airfoil path is resolved against the file's directory.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SpecError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SpecError::Io {
            file: file.clone(),
            source,
        })?;
        let mut spec = Self::from_yaml_str(&text, &file)?;
        if spec.airfoil.is_relative() {
            spec.airfoil = path.parent().unwrap_or(Path::new(".")).join(&spec.airfoil);
        }
        Ok(spec)
    }

    /// Checks every number: sizes, loads, strengths and speeds > 0; retract, Z-hop and spar
    /// overlap ≥ 0; hinge fractions in [0, 1]; a finite zero-lift angle.
    fn validate(&self, file: &str) -> Result<(), SpecError> {
        let b = &self.build;
        let check = |field: &'static str, value: f64, allowed: Allowed, unit: &'static str| {
            allowed.check(value, unit).map_err(|e| SpecError::Invalid {
                file: file.into(),
                field,
                reason: e.into(),
            })
        };
        for (field, value, unit) in [
            ("aero.span_mm", self.aero.span_mm, "mm"),
            ("loads.gross_weight_n", self.loads.gross_weight_n, "N"),
            ("loads.load_factor", self.loads.load_factor, ""),
            (
                "structure.yield_strength_mpa",
                self.structure.yield_strength_mpa,
                "MPa",
            ),
            ("structure.safety_factor", self.structure.safety_factor, ""),
            ("structure.am_eta_star", self.structure.am_eta_star, ""),
            ("structure.am_r_star", self.structure.am_r_star, ""),
            ("build.layer_height_mm", b.layer_height_mm, "mm"),
            ("build.first_layer_height_mm", b.first_layer_height_mm, "mm"),
            ("build.extrusion_width_mm", b.extrusion_width_mm, "mm"),
            ("build.filament_diameter_mm", b.filament_diameter_mm, "mm"),
            ("build.density_kg_m3", b.density_kg_m3, "kg/m³"),
            ("build.perimeter_speed_mm_s", b.perimeter_speed_mm_s, "mm/s"),
            ("build.infill_speed_mm_s", b.infill_speed_mm_s, "mm/s"),
            (
                "build.solid_infill_speed_mm_s",
                b.solid_infill_speed_mm_s,
                "mm/s",
            ),
            (
                "build.first_layer_speed_mm_s",
                b.first_layer_speed_mm_s,
                "mm/s",
            ),
            ("build.travel_speed_mm_s", b.travel_speed_mm_s, "mm/s"),
            ("build.retract_speed_mm_s", b.retract_speed_mm_s, "mm/s"),
            ("build.bed_x_mm", b.bed_x_mm, "mm"),
            ("build.bed_y_mm", b.bed_y_mm, "mm"),
        ] {
            check(field, value, Allowed::POSITIVE, unit)?;
        }
        for (field, value, unit) in [
            ("build.retract_mm", b.retract_mm, "mm"),
            ("build.z_hop_mm", b.z_hop_mm, "mm"),
            ("build.spar_overlap", b.spar_overlap, ""),
        ] {
            check(field, value, Allowed::NON_NEGATIVE, unit)?;
        }
        for (field, value) in [
            ("structure.hinge_x_over_c", self.structure.hinge_x_over_c),
            ("structure.hinge_z_over_t", self.structure.hinge_z_over_t),
        ] {
            check(field, value, Allowed::closed(0.0, 1.0), "")?;
        }
        check(
            "aero.alpha_l0_deg",
            self.aero.alpha_l0_deg,
            Allowed::FINITE,
            "deg",
        )?;
        check(
            "aero.aspect_ratio",
            self.aero.aspect_ratio,
            Allowed::POSITIVE,
            "",
        )?;
        self.aero.design.validate().map_err(|e| SpecError::Design {
            file: file.into(),
            error: e.within("aero.design"),
        })?;
        self.check_sizes(file)
    }

    /// The limits on what the spec makes (issue 23): stations, sections, layers, spars and
    /// rib lines ([`MAX_STATIONS`] and the others); each error names the field and the limit.
    fn check_sizes(&self, file: &str) -> Result<(), SpecError> {
        let fail = |field: &'static str, e: OutOfRange| SpecError::Invalid {
            file: file.into(),
            field,
            reason: e.into(),
        };
        let (a, b) = (&self.aero, &self.build);
        Allowed::closed(2.0, MAX_STATIONS as f64)
            .whole()
            .check(a.stations as f64, "")
            .map_err(|e| fail("aero.stations", e.because("MAX_STATIONS")))?;
        // Counts from a ratio of two fields: the smaller one has a least value.
        let at_least = |field, value: f64, total: f64, most: usize, why: String| {
            Allowed::at_least(total / most as f64)
                .check(value, "mm")
                .map_err(|e| fail(field, e.because(why)))
        };
        let semi = 0.5 * (a.span_mm - b.centre_width_mm);
        let sides = (MAX_SECTIONS - 1) / 2;
        at_least(
            "build.z_max_mm",
            b.z_max_mm,
            semi,
            sides,
            format!(
                "at most {MAX_SECTIONS} sections (MAX_SECTIONS): {sides} per side over \
                 (aero.span_mm − build.centre_width_mm)/2 = {semi} mm"
            ),
        )?;
        at_least(
            "build.layer_height_mm",
            b.layer_height_mm,
            b.z_max_mm,
            MAX_LAYERS_PER_SECTION,
            format!(
                "at most {MAX_LAYERS_PER_SECTION} layers per section \
                 (MAX_LAYERS_PER_SECTION) over build.z_max_mm = {} mm",
                b.z_max_mm
            ),
        )?;
        at_least(
            "build.layer_height_mm",
            b.layer_height_mm,
            a.span_mm,
            MAX_WING_LAYERS,
            format!(
                "at most {MAX_WING_LAYERS} layers (MAX_WING_LAYERS) over aero.span_mm = {} mm",
                a.span_mm
            ),
        )?;
        let c_max = 2.0 * a.span_mm / a.aspect_ratio;
        let lines = || {
            format!(
                "at most {MAX_LINES_PER_CHORD} lines (MAX_LINES_PER_CHORD) across the \
                 largest chord, 2·aero.span_mm/aero.aspect_ratio = {c_max} mm"
            )
        };
        // The least spar gap is the rule's floor r*·w_e, or the cap if lower.
        let caps = self
            .structure
            .max_spar_spacing_mm
            .map(|cap| ("structure.max_spar_spacing_mm", cap, c_max));
        for (field, value, total) in [
            (
                "structure.am_r_star",
                self.structure.am_r_star,
                c_max / b.extrusion_width_mm,
            ),
            ("build.extrusion_width_mm", b.extrusion_width_mm, c_max),
        ]
        .into_iter()
        .chain(caps)
        {
            at_least(field, value, total, MAX_LINES_PER_CHORD, lines())?;
        }
        Ok(())
    }

    /// The [`BuildParams`] of this spec.
    pub fn build_params(&self) -> BuildParams {
        let b = &self.build;
        BuildParams {
            extrusion_width_mm: b.extrusion_width_mm,
            layer_height_mm: b.layer_height_mm,
            first_layer_height_mm: b.first_layer_height_mm,
            filament_diameter_mm: b.filament_diameter_mm,
            perimeter_speed_mm_s: b.perimeter_speed_mm_s,
            infill_speed_mm_s: b.infill_speed_mm_s,
            solid_infill_speed_mm_s: b.solid_infill_speed_mm_s,
            first_layer_speed_mm_s: b.first_layer_speed_mm_s,
            travel_speed_mm_s: b.travel_speed_mm_s,
            retract_mm: b.retract_mm,
            retract_speed_mm_s: b.retract_speed_mm_s,
            z_hop_mm: b.z_hop_mm,
            spar_overlap: b.spar_overlap,
            bed_x_mm: b.bed_x_mm,
            bed_y_mm: b.bed_y_mm,
            hinge_x_over_c: self.structure.hinge_x_over_c,
            hinge_z_over_t: self.structure.hinge_z_over_t,
        }
    }
}

/// A designed wing: everything Algorithm 2 needs.
#[derive(Debug, Clone)]
pub struct Wing {
    /// The spec it came from.
    pub spec: WingSpec,
    /// The airfoil, normalised.
    pub airfoil: Airfoil,
    /// Its surface functions.
    pub surfaces: SurfaceFunctions,
    /// The lifting-line result (non-dimensional): condition 1 of the design (the only one in
    /// single-point cases), whose α is the built twist.
    pub aero: Solution,
    /// The design case's solve: every condition, targets and Δα.
    pub design: Designed,
    /// The condition (0-based index into `design.conditions`) whose lift loads the spars.
    pub structure_condition: usize,
    /// Chord and built twist per station.
    pub planform: Planform,
    /// Lift per span at the design load \[N/mm\].
    pub lift_n_mm: Vec<f64>,
    /// Spar locations X_sp.
    pub spars: SparLayout,
    /// The printable sections.
    pub sections: Vec<Section>,
}

impl Wing {
    /// Runs the design: airfoil → LLT (the spec's case) → loads → spars → sections.
    pub fn design(spec: WingSpec) -> Result<Self, SpecError> {
        let airfoil = Airfoil::load(&spec.airfoil)?.normalised();
        let surfaces = SurfaceFunctions::new(&airfoil)?;
        let a = &spec.aero;
        let ll = LiftingLine::new(a.stations, a.aspect_ratio, a.lift_slope_per_rad)?;
        let y = ll.stations();
        let design = a.design.solve(&ll).map_err(|e| match e {
            DesignError::Field(error) => SpecError::Design {
                file: String::new(),
                error: error.within("aero.design"),
            },
            DesignError::Llt(e) => SpecError::Llt(e),
        })?;
        let aero = design.conditions[0].clone();
        let structure_condition = design.structure_condition(&y);
        let b = a.span_mm;
        let planform = Planform {
            span_mm: b,
            chord_mm: aero.chord_over_b.iter().map(|c| c * b).collect(),
            twist_rad: aero
                .geometric_alpha_rad(a.alpha_l0_deg.to_radians())
                .iter()
                .copied()
                .collect(),
        };
        let lift = spec.loads.gross_weight_n * spec.loads.load_factor;
        let lift_n_mm: Vec<f64> = design.conditions[structure_condition]
            .lift_per_span_n_m(lift, b)
            .iter()
            .copied()
            .collect();
        let moment = bending_moment_n_mm(&lift_n_mm, b);
        let bp = spec.build_params();
        let sp = StructureParams {
            extrusion_width_mm: bp.extrusion_width_mm,
            yield_strength_mpa: spec.structure.yield_strength_mpa,
            safety_factor: spec.structure.safety_factor,
            hinge_x_over_c: spec.structure.hinge_x_over_c,
            spacing: SpacingRule {
                extrusion_width_mm: bp.extrusion_width_mm,
                eta_star: spec.structure.am_eta_star,
                r_star: spec.structure.am_r_star,
                max_mm: spec.structure.max_spar_spacing_mm,
            },
            min_spar_height_mm: (2.0 * bp.spar_overlap + 1.0) * bp.extrusion_width_mm,
        };
        let yb: Vec<f64> = y.iter().copied().collect();
        let spars = place_spars(&surfaces, &yb, &planform.chord_mm, &moment, &sp);
        let sections = split(b, spec.build.centre_width_mm, spec.build.z_max_mm)?;
        Ok(Self {
            spec,
            airfoil,
            surfaces,
            aero,
            design,
            structure_condition,
            planform,
            lift_n_mm,
            spars,
            sections,
        })
    }

    /// The design case's report: the solved planform and each condition, requested against
    /// achieved.
    pub fn design_report(&self) -> DesignReport {
        self.design
            .report(self.spec.aero.span_mm, self.structure_condition)
    }

    /// The layers of section `i` (index into [`Wing::sections`]), or None if out of range.
    pub fn layers(&self, i: usize) -> Option<Vec<Layer>> {
        let section = self.sections.get(i)?;
        let perimeter: Vec<Point2<f64>> = self.airfoil.points().to_vec();
        Some(section_layers(
            &perimeter,
            &self.surfaces,
            &self.planform,
            &self.spars,
            section,
            &self.spec.build_params(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped Table 2 spec with `edits` (`(key line prefix, replacement line)`) applied.
    fn table2(edits: &[(&str, &str)]) -> String {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../config/wings/gwing-table2.yaml"
        );
        let mut text = std::fs::read_to_string(path).unwrap();
        for (key, line) in edits {
            let old = text
                .lines()
                .find(|l| l.trim_start().starts_with(key))
                .unwrap_or_else(|| panic!("{key} in the spec"))
                .to_owned();
            text = text.replace(&old, line);
        }
        text
    }

    fn error(edits: &[(&str, &str)]) -> Option<String> {
        WingSpec::from_yaml_str(&table2(edits), "w.yaml")
            .err()
            .map(|e| e.to_string())
    }

    #[test]
    fn stations_at_the_limit_pass_and_one_more_is_refused() {
        assert_eq!(error(&[("stations:", "  stations: 2000")]), None);
        let e = error(&[("stations:", "  stations: 2001")]).unwrap();
        assert_eq!(
            e,
            "w.yaml: field `aero.stations`: 2001 is out of range: must be in [2, 2000] \
             (MAX_STATIONS)"
        );
        assert!(error(&[("stations:", "  stations: 200000")]).is_some());
    }

    #[test]
    fn layer_height_section_and_chord_counts_are_capped() {
        // Per section: 300 mm sections over at most 15000 layers: 0.02 mm.
        let z = ("z_max_mm:", "  z_max_mm: 300");
        let h = |h: f64| format!("  layer_height_mm: {h}");
        let least = 300.0 / MAX_LAYERS_PER_SECTION as f64;
        assert_eq!(error(&[z, ("layer_height_mm:", h(least).as_str())]), None);
        let e = error(&[z, ("layer_height_mm:", h(0.0199).as_str())]).unwrap();
        assert!(
            e.starts_with("w.yaml: field `build.layer_height_mm`: 0.0199 mm is out of range")
                && e.ends_with(
                    "(at most 15000 layers per section (MAX_LAYERS_PER_SECTION) over \
                     build.z_max_mm = 300 mm)"
                ),
            "{e}"
        );
        // Over the wing: 1090 mm in at most 100000 layers.
        let least = 1090.0 / MAX_WING_LAYERS as f64;
        assert_eq!(error(&[("layer_height_mm:", h(least).as_str())]), None);
        let e = error(&[("layer_height_mm:", h(0.0108).as_str())]).unwrap();
        assert!(
            e.ends_with("(MAX_WING_LAYERS) over aero.span_mm = 1090 mm)"),
            "{e}"
        );
        let e = error(&[("layer_height_mm:", "  layer_height_mm: 1e-9")]).unwrap();
        assert!(e.contains("`build.layer_height_mm`: 0.000000001 mm"), "{e}");
        // Sections: (1090 − 50)/2 = 520 mm per side in at most 100 sections.
        let z = |z: f64| format!("  z_max_mm: {z}");
        assert_eq!(error(&[("z_max_mm:", z(5.2).as_str())]), None);
        let e = error(&[("z_max_mm:", z(5.19).as_str())]).unwrap();
        assert!(
            e.contains("`build.z_max_mm`: 5.19 mm is out of range: must be finite and ≥ 5.2")
                && e.contains("MAX_SECTIONS"),
            "{e}"
        );
        // Spar spacing: the largest chord is 2·1090/8 = 272.5 mm, over 5000 lines: the rule's
        // floor r*·w_e (w_e = 0.5 mm) and the optional cap at least 0.0545 mm.
        let r_star = |r: f64| format!("  am_r_star: {r}");
        assert_eq!(error(&[("am_r_star:", r_star(0.109).as_str())]), None);
        let e = error(&[("am_r_star:", r_star(0.1089).as_str())]).unwrap();
        assert!(
            e.contains("`structure.am_r_star`") && e.contains("MAX_LINES_PER_CHORD"),
            "{e}"
        );
        let cap = |s: f64| format!("  am_r_star: 60\n  max_spar_spacing_mm: {s}");
        assert_eq!(error(&[("am_r_star:", cap(0.0545).as_str())]), None);
        let e = error(&[("am_r_star:", cap(0.0544).as_str())]).unwrap();
        assert!(
            e.contains("`structure.max_spar_spacing_mm`") && e.contains("MAX_LINES_PER_CHORD"),
            "{e}"
        );
        let e = error(&[("am_r_star:", cap(0.0).as_str())]).unwrap();
        assert!(e.contains("`structure.max_spar_spacing_mm`"), "{e}");
    }
}
