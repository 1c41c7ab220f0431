//! The wing spec (YAML, `config/wings/*.yaml`) and the G-Wing pipeline: airfoil → lifting line
//! → spars → sections → layers.

use std::path::{Path, PathBuf};

use cell_airfoil::{Airfoil, AirfoilError, SurfaceFunctions};
use cell_config::{Allowed, ParseError, Place, Problem};
use nalgebra::DVector;
use nalgebra::Point2;
use serde::Deserialize;

use crate::layers::{section_layers, BuildParams, Layer, Planform};
use crate::llt::{LiftingLine, LltError, Solution};
use crate::section::{split, Section, SectionError};
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
    /// The design case.
    pub design: Design,
}

/// A chord distribution shape (scaled to the aspect ratio).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum ChordShape {
    /// The discrete ellipse Q⁻¹e.
    Elliptic,
    /// Constant chord.
    Rectangular,
    /// Straight taper, tip/root chord ratio in (0, 1\].
    Tapered {
        /// c_tip / c_root.
        taper_ratio: f64,
    },
}

/// The design case of Table 1 the spec uses (the others are in [`crate::llt`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, tag = "case", rename_all = "snake_case")]
pub enum Design {
    /// Single-point inverse #1: a chord shape and an elliptic lift at `c_l` → twist.
    InverseTwist {
        /// Chord shape.
        chord: ChordShape,
        /// Design wing lift coefficient c_L.
        c_l: f64,
    },
    /// Direct design: a chord shape and linear washout → lift.
    Direct {
        /// Chord shape.
        chord: ChordShape,
        /// Root angle from the zero-lift line \[deg\].
        root_alpha_deg: f64,
        /// Root minus tip angle \[deg\].
        washout_deg: f64,
    },
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

/// Structure (Algorithm 1; defaults: PLA, FS 20, Table 2's 30 mm spacing).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StructureSpec {
    /// σ_y \[MPa\]. Default 26 (PLA, notes).
    pub yield_strength_mpa: f64,
    /// Factor of safety. Default 20 (notes).
    pub safety_factor: f64,
    /// Max spar spacing \[mm\]. Default 30 (Table 2).
    pub max_spar_spacing_mm: f64,
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
            max_spar_spacing_mm: 30.0,
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
            (
                "structure.max_spar_spacing_mm",
                self.structure.max_spar_spacing_mm,
                "mm",
            ),
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
        )
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
    /// The lifting-line result (non-dimensional).
    pub aero: Solution,
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
        let shape = |c: ChordShape| -> Result<DVector<f64>, LltError> {
            let raw = match c {
                ChordShape::Elliptic => ll.elliptic_shape(),
                ChordShape::Rectangular => DVector::repeat(ll.n(), 1.0),
                ChordShape::Tapered { taper_ratio } => {
                    y.map(|y| 1.0 - 2.0 * y.abs() * (1.0 - taper_ratio))
                }
            };
            ll.chord_from_shape(&raw)
        };
        let aero = match &a.design {
            Design::InverseTwist { chord, c_l } => {
                let gamma = ll.gamma_from_shape(&ll.elliptic_shape(), *c_l)?;
                ll.inverse_twist(&shape(*chord)?, &gamma)?
            }
            Design::Direct {
                chord,
                root_alpha_deg,
                washout_deg,
            } => {
                let alpha = y.map(|y| (root_alpha_deg - washout_deg * 2.0 * y.abs()).to_radians());
                ll.direct(&shape(*chord)?, &alpha)?
            }
        };
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
        let lift_n_mm: Vec<f64> = aero.lift_per_span_n_m(lift, b).iter().copied().collect();
        let moment = bending_moment_n_mm(&lift_n_mm, b);
        let bp = spec.build_params();
        let sp = StructureParams {
            extrusion_width_mm: bp.extrusion_width_mm,
            yield_strength_mpa: spec.structure.yield_strength_mpa,
            safety_factor: spec.structure.safety_factor,
            hinge_x_over_c: spec.structure.hinge_x_over_c,
            max_spar_spacing_mm: spec.structure.max_spar_spacing_mm,
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
            planform,
            lift_n_mm,
            spars,
            sections,
        })
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
