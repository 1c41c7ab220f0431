//! The AVL geometry file of a designed wing (seed 002: "G-Wing can optionally call AVL … output
//! the wing geometry to AVL" for vortex-lattice verification).
//!
//! AVL (Athena Vortex Lattice, M. Drela and H. Youngren) reads a plain-text `xxx.avl` file; the
//! fields written here are those of its user guide, `avl_doc.txt`, "Geometry Input File":
//!
//! - the header: title, `Mach` (Prandtl–Glauert), `iYsym iZsym Zsym` (0 0 0: no image planes,
//!   the whole wing is modelled; `YDUPLICATE` needs iYsym = 0), `Sref Cref Bref` (reference area,
//!   chord for Cm, span for Cl/Cn), `Xref Yref Zref` (moment reference) and `CDp` (0: the
//!   lifting-line design has no profile drag);
//! - one `SURFACE` with `Nchord Cspace Nspan Sspace`: chordwise vortices with cosine spacing
//!   (Cspace = 1) and spanwise vortices with −sine spacing from root to tip (Sspace = −2),
//!   which the guide recommends for straight and elliptic wings ("equivalent to a cosine
//!   distribution across the whole span");
//! - `YDUPLICATE 0.0`: the right wing is defined and mirrored about y = 0 for the left;
//! - one `SECTION` per spanwise vortex edge, `Xle Yle Zle Chord Ainc`: AVL interpolates chord
//!   and incidence linearly between sections, so the sections sit at the same −sine points
//!   as the vortices (one strip between neighbours);
//! - after each section either `AFILE` (the airfoil's `.dat`, whose camber line AVL splines)
//!   or nothing (a flat camber line), and `CLAF` = a/2π when the 2-D lift slope a is not
//!   the thin-airfoil 2π ("dcl/da = 2 pi CLaf").
//!
//! Axes are AVL's: X downstream, Y out the right wing, Z up; lengths in metres (AVL's Lunit is
//! arbitrary; coefficients do not depend on it). The planform is G-Wing's: every section is
//! placed so that the hinge line at `hinge_x_over_c` is straight, here the line x = 0, z = 0
//! (Xle = −x_h·c). The chord lies in the x-y plane and the twist enters only as Ainc: AVL's
//! Ainc "is used only to modify the flow tangency boundary condition … and does not rotate the
//! geometry of the airfoil section itself" (linearised theory).
//!
//! The incidence depends on the camber the file gives AVL ([`Camber`]): with the airfoil's
//! camber line, Ainc is the built (geometric) section angle, LLT α + α_L0 (notes, "Planform
//! assembly"); with a flat camber line, whose zero-lift line is its chord, Ainc is the LLT α
//! itself, measured from the zero-lift line. The flat form compares the lifting line with a
//! vortex lattice on equal terms: both then use the design's own zero-lift angle.
//!
//! AVL's array limits (`src/AVL.INC`: NSMAX = 400 strips, NVMAX = 6000 horseshoe vortices, both
//! halves counted) bound the vortex counts.

use std::f64::consts::PI;
use std::fmt::Write;

use cell_airfoil::Airfoil;

use crate::layers::Planform;
use crate::llt::Solution;
use crate::spec::Wing;

/// Most chordwise strips AVL holds (AVL 3.x `src/AVL.INC`, NSMAX), both halves together.
pub const AVL_MAX_STRIPS: usize = 400;
/// Most horseshoe vortices AVL holds (AVL 3.x `src/AVL.INC`, NVMAX).
pub const AVL_MAX_VORTICES: usize = 6000;

/// What is wrong with the AVL request.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AvlError {
    /// A count or value is outside what the file or AVL accepts.
    #[error("AVL output: invalid {name} = {value}: {reason}")]
    Invalid {
        /// Option or field name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range.
        reason: String,
    },
}

/// The camber line the file gives every section.
#[derive(Debug, Clone, PartialEq)]
pub enum Camber {
    /// The airfoil's: `AFILE <file>` after each section; Ainc = LLT α + α_L0 (as built).
    Airfoil {
        /// The `.dat` file name as AVL should open it (relative to where AVL runs).
        afile: String,
    },
    /// A flat camber line; Ainc = LLT α (from the zero-lift line).
    ZeroLiftLine,
}

/// How the file discretises the wing.
#[derive(Debug, Clone, PartialEq)]
pub struct AvlOptions {
    /// The case title (first line).
    pub title: String,
    /// Default Mach number. 0: incompressible, as the lifting line.
    pub mach: f64,
    /// Chordwise vortices per strip (Nchord). Default 12.
    pub chordwise_vortices: usize,
    /// Spanwise vortices on the right half (Nspan; AVL mirrors them). Default 40.
    pub spanwise_vortices: usize,
    /// Camber line and incidence convention.
    pub camber: Camber,
}

impl Default for AvlOptions {
    fn default() -> Self {
        Self {
            title: "G-Wing".into(),
            mach: 0.0,
            chordwise_vortices: 12,
            spanwise_vortices: 40,
            camber: Camber::ZeroLiftLine,
        }
    }
}

/// The design data the file is made of.
#[derive(Debug, Clone, PartialEq)]
pub struct AvlWing {
    /// Span, chord and built twist (LLT α + α_L0) per station.
    pub planform: Planform,
    /// The airfoil's zero-lift angle α_L0 \[rad\] the twist includes.
    pub alpha_l0_rad: f64,
    /// 2-D lift slope a \[1/rad\].
    pub lift_slope_per_rad: f64,
    /// Hinge line chord fraction x_h.
    pub hinge_x_over_c: f64,
}

impl AvlWing {
    /// From a lifting-line solution of a wing of span `span_mm`.
    pub fn from_solution(
        aero: &Solution,
        span_mm: f64,
        alpha_l0_rad: f64,
        lift_slope_per_rad: f64,
        hinge_x_over_c: f64,
    ) -> Self {
        Self {
            planform: Planform {
                span_mm,
                chord_mm: aero.chord_over_b.iter().map(|c| c * span_mm).collect(),
                twist_rad: aero
                    .geometric_alpha_rad(alpha_l0_rad)
                    .iter()
                    .copied()
                    .collect(),
            },
            alpha_l0_rad,
            lift_slope_per_rad,
            hinge_x_over_c,
        }
    }

    /// From a designed wing (its planform, α_L0, lift slope and hinge line).
    pub fn of(wing: &Wing) -> Self {
        Self {
            planform: wing.planform.clone(),
            alpha_l0_rad: wing.spec.aero.alpha_l0_deg.to_radians(),
            lift_slope_per_rad: wing.spec.aero.lift_slope_per_rad,
            hinge_x_over_c: wing.spec.structure.hinge_x_over_c,
        }
    }
}

/// The airfoil as the XFOIL-type coordinate file `AFILE` reads (avl_doc.txt: a name line,
/// then x/c y/c pairs from the TE round the LE back to the TE): the section's points, already
/// normalised and in Selig order, one pair a line.
pub fn afile_dat(airfoil: &Airfoil) -> String {
    let mut f = format!("{}\n", airfoil.name().replace('\n', " "));
    for p in airfoil.points() {
        let _ = writeln!(f, "{:.7} {:.7}", p.x, p.y);
    }
    f
}

/// The −sine spanwise points of AVL's Sspace = −2 from root to tip, y_k = (b/2)·sin(πk/2K),
/// k = 0..=K, as fractions of the semispan.
pub fn minus_sine_points(k_max: usize) -> Vec<f64> {
    (0..=k_max)
        .map(|k| (0.5 * PI * k as f64 / k_max as f64).sin())
        .collect()
}

/// The AVL geometry file (`xxx.avl`) of `wing`.
///
/// # Errors
/// [`AvlError::Invalid`] for zero vortex counts, more strips or vortices than AVL holds, a
/// non-finite Mach number or one ≥ 1 (Prandtl–Glauert), an empty planform or a non-positive
/// chord.
pub fn geometry(wing: &AvlWing, options: &AvlOptions) -> Result<String, AvlError> {
    let invalid = |name, value: f64, reason: String| {
        Err(AvlError::Invalid {
            name,
            value,
            reason,
        })
    };
    let (nc, ns) = (options.chordwise_vortices, options.spanwise_vortices);
    if nc == 0 || ns == 0 {
        return invalid(
            "vortex count",
            nc.min(ns) as f64,
            "Nchord and Nspan must be ≥ 1".into(),
        );
    }
    if 2 * ns > AVL_MAX_STRIPS {
        return invalid(
            "spanwise_vortices",
            ns as f64,
            format!("AVL holds {AVL_MAX_STRIPS} strips over both halves (NSMAX)"),
        );
    }
    if 2 * ns * nc > AVL_MAX_VORTICES {
        return invalid(
            "chordwise_vortices",
            nc as f64,
            format!(
                "2·Nspan·Nchord = {} > {AVL_MAX_VORTICES} vortices (AVL's NVMAX)",
                2 * ns * nc
            ),
        );
    }
    if !(options.mach.is_finite() && (0.0..1.0).contains(&options.mach)) {
        return invalid("mach", options.mach, "must be in [0, 1)".into());
    }
    let p = &wing.planform;
    if p.chord_mm.is_empty() || p.chord_mm.len() != p.twist_rad.len() {
        return invalid(
            "planform",
            p.chord_mm.len() as f64,
            "needs one chord and twist per station".into(),
        );
    }
    if let Some(c) = p.chord_mm.iter().find(|c| !(c.is_finite() && **c > 0.0)) {
        return invalid("chord_mm", *c, "every chord must be finite and > 0".into());
    }
    if !(p.span_mm.is_finite() && p.span_mm > 0.0) {
        return invalid("span_mm", p.span_mm, "must be finite and > 0".into());
    }
    let m = 1e-3;
    let b = p.span_mm * m;
    let n = p.chord_mm.len() as f64;
    let s_ref = p.chord_mm.iter().sum::<f64>() * m * b / n;
    // Mean aerodynamic chord (2/S)∫₀^{b/2} c² dy over the stations.
    let c_ref = p.chord_mm.iter().map(|c| (c * m).powi(2)).sum::<f64>() * (b / n) / s_ref;
    let xh = wing.hinge_x_over_c;
    let (ainc_offset, afile) = match &options.camber {
        Camber::Airfoil { afile } => (0.0, Some(afile.as_str())),
        Camber::ZeroLiftLine => (-wing.alpha_l0_rad, None),
    };
    let claf = wing.lift_slope_per_rad / (2.0 * PI);
    let mut f = String::new();
    // Writing to a String cannot fail.
    let mut line = |s: String| {
        let _ = writeln!(f, "{s}");
    };
    line(options.title.replace('\n', " "));
    line("#Mach".into());
    line(format!("{:.4}", options.mach));
    line("#IYsym IZsym Zsym".into());
    line("0 0 0.0".into());
    line("#Sref Cref Bref  [m², m, m]".into());
    line(format!("{s_ref:.6} {c_ref:.6} {b:.6}"));
    line("#Xref Yref Zref  (quarter chord of Cref, hinge line at x = 0)".into());
    line(format!("{:.6} 0.0 0.0", (0.25 - xh) * c_ref));
    line("#CDp".into());
    line("0.0".into());
    line("#".into());
    line("SURFACE".into());
    line("Wing".into());
    line("#Nchord Cspace Nspan Sspace".into());
    line(format!("{nc} 1.0 {ns} -2.0"));
    line("YDUPLICATE".into());
    line("0.0".into());
    match &options.camber {
        Camber::Airfoil { .. } => {
            line("# Ainc = LLT alpha + alpha_L0 (built), airfoil camber".into())
        }
        Camber::ZeroLiftLine => {
            line("# Ainc = LLT alpha (from the zero-lift line), flat camber".into())
        }
    }
    for eta in minus_sine_points(ns) {
        let y_mm = 0.5 * p.span_mm * eta;
        let (c_mm, twist) = p.at(y_mm);
        let c = c_mm * m;
        line("SECTION".into());
        line("#Xle Yle Zle Chord Ainc".into());
        line(format!(
            "{:.6} {:.6} 0.0 {c:.6} {:.5}",
            -xh * c,
            y_mm * m,
            (twist + ainc_offset).to_degrees()
        ));
        if let Some(afile) = afile {
            line("AFILE".into());
            line(if afile.contains(char::is_whitespace) {
                format!("\"{afile}\"")
            } else {
                afile.to_owned()
            });
        }
        if (claf - 1.0).abs() > 1e-12 {
            line("CLAF".into());
            line(format!("{claf:.6}"));
        }
    }
    Ok(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::llt::LiftingLine;

    fn numbers(line: &str) -> Vec<f64> {
        line.split_whitespace()
            .map(|t| t.parse().unwrap())
            .collect()
    }

    /// A tapered, washed-out wing, span 1 m, AR 8, hinge at 80 %.
    fn tapered() -> AvlWing {
        let ll = LiftingLine::new(100, 8.0, 2.0 * PI).unwrap();
        let y = ll.stations();
        let c = ll.chord_from_shape(&y.map(|y| 1.0 - y.abs())).unwrap();
        let s = ll.direct(&c, &y.map(|y| 0.1 - 0.1 * y.abs())).unwrap();
        AvlWing::from_solution(&s, 1000.0, (-2f64).to_radians(), 2.0 * PI, 0.8)
    }

    #[test]
    fn header_and_sections_follow_the_design() {
        let w = tapered();
        let text = geometry(&w, &AvlOptions::default()).unwrap();
        let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(lines[0], "G-Wing");
        assert_eq!(numbers(lines[1]), [0.0]);
        assert_eq!(numbers(lines[2]), [0.0, 0.0, 0.0]);
        let refs = numbers(lines[3]);
        assert!((refs[0] - 1.0 / 8.0).abs() < 1e-6, "S = b²/AR, {refs:?}");
        assert!((refs[2] - 1.0).abs() < 1e-9);
        assert_eq!(numbers(lines[8]), [12.0, 1.0, 40.0, -2.0]);
        let sections: Vec<Vec<f64>> = lines
            .windows(2)
            .filter(|l| l[0] == "SECTION")
            .map(|l| numbers(l[1]))
            .collect();
        assert_eq!(
            sections.len(),
            41,
            "one section per vortex edge, root to tip"
        );
        assert_eq!(sections[0][1], 0.0);
        assert!((sections[40][1] - 0.5).abs() < 1e-9, "tip at b/2");
        for s in &sections {
            // Straight hinge at x = 0: Xle = −0.8·c.
            assert!((s[0] + 0.8 * s[3]).abs() < 2e-6, "{s:?}");
            let (c, twist) = w.planform.at(s[1] * 1000.0);
            assert!((s[3] - c / 1000.0).abs() < 1e-6);
            // Zero-lift-line convention: Ainc = built twist − α_L0 = LLT α.
            assert!((s[4] - (twist.to_degrees() + 2.0)).abs() < 1e-4);
        }
        assert!(!text.contains("AFILE") && !text.contains("CLAF"));
    }

    #[test]
    fn airfoil_camber_writes_afile_and_the_built_twist() {
        let w = tapered();
        let o = AvlOptions {
            camber: Camber::Airfoil {
                afile: "ag 24.dat".into(),
            },
            ..AvlOptions::default()
        };
        let text = geometry(&w, &o).unwrap();
        assert_eq!(text.matches("AFILE\n\"ag 24.dat\"").count(), 41);
        let root = text.lines().skip_while(|l| *l != "SECTION").nth(2).unwrap();
        let (_, twist) = w.planform.at(0.0);
        assert!((numbers(root)[4] - twist.to_degrees()).abs() < 1e-4);
        let mut steep = w.clone();
        steep.lift_slope_per_rad = 1.1 * 2.0 * PI;
        assert!(geometry(&steep, &o).unwrap().contains("CLAF\n1.100000"));
    }

    #[test]
    fn counts_beyond_avl_are_refused() {
        let w = tapered();
        let with = |nc, ns| AvlOptions {
            chordwise_vortices: nc,
            spanwise_vortices: ns,
            ..AvlOptions::default()
        };
        assert!(
            geometry(&w, &with(15, 200)).is_ok(),
            "400 strips, 6000 vortices"
        );
        assert!(geometry(&w, &with(1, 201)).is_err(), "402 strips");
        assert!(geometry(&w, &with(16, 200)).is_err(), "6400 vortices");
        assert!(geometry(&w, &with(0, 10)).is_err());
        let mut bad = w.clone();
        bad.planform.chord_mm[3] = 0.0;
        assert!(geometry(&bad, &AvlOptions::default()).is_err());
        let mach = AvlOptions {
            mach: 1.0,
            ..AvlOptions::default()
        };
        assert!(geometry(&w, &mach).is_err());
    }
}
