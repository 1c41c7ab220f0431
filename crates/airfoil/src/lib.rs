//! `cell_airfoil`: airfoil sections: UIUC `.dat` input, the 2-D geometry a hot wire follows,
//! and the thickness and surface functions a printed wing needs ([`SurfaceFunctions`],
//! seed 002 notes §5 "Airfoil I/O", `docs/notes/seed-notes-hotwire-gwing.md`).
//!
//! An [`Airfoil`] is a closed polygon stored **anticlockwise in Selig order**: trailing edge →
//! upper surface → leading edge → lower surface → trailing edge (the wire runs the same way, see
//! `docs/notes/swarmcut-model-notes.md`). The closing segment last → first point is implied; a
//! sharp trailing edge repeats the TE point at both ends, a blunt one leaves a gap
//! ([`Airfoil::trailing_edge_gap`]).
//!
//! Conventions used throughout:
//! - **Leading edge (LE)**: the point with the smallest x (the first one on a tie). It is a
//!   vertex, never interpolated, so it is frame dependent: after a large twist another vertex
//!   may become the LE.
//! - **Trailing edge (TE)**: the midpoint of the first and last point.
//! - **Chord**: the distance LE → TE.
//! - **Upper surface**: points TE → LE (indices `0..=le`); **lower surface**: LE → TE
//!   (indices `le..`). Both share the LE vertex.
//!
//! Coordinates are either chord-normalised (files) or millimetres (after
//! [`Airfoil::scaled`]); the type does not care.

#![warn(missing_docs)]

use std::path::Path;

use cell_geometry::{cumulative_lengths, sample_at_arc_fractions, signed_area, Norm};
use nalgebra::{Point2, Rotation2, Vector2};

mod dat;
mod surface;

pub use surface::SurfaceFunctions;

/// Fewest distinct points a section may have.
pub const MIN_POINTS: usize = 5;

/// Most coordinate lines a `.dat` file may hold (issue 23: every size from a file has a
/// limit). UIUC files hold 35–400 points, high-resolution exports ~2 000; the limit is 10×
/// that, far above what the resampling and the surface functions need.
pub const MAX_POINTS: usize = 20_000;

/// What went wrong reading or building an airfoil. `file` is the source name given to the
/// parser (or the airfoil's name for in-memory geometry); `line` is 1-based.
#[derive(Debug, thiserror::Error)]
pub enum AirfoilError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// Path as given.
        file: String,
        /// Underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A coordinate did not parse as a number.
    #[error("{file}:{line}: {field} coordinate `{text}` is not a number")]
    NotANumber {
        /// Source name.
        file: String,
        /// 1-based line.
        line: usize,
        /// `"x"` or `"y"`.
        field: &'static str,
        /// The offending token.
        text: String,
    },
    /// A coordinate line did not have exactly two columns.
    #[error("{file}:{line}: expected 2 columns (x y), found {found}")]
    ColumnCount {
        /// Source name.
        file: String,
        /// 1-based line.
        line: usize,
        /// Number of whitespace-separated columns found.
        found: usize,
    },
    /// A coordinate was NaN or infinite.
    #[error("{file}:{line}: {field} = {value} is not finite")]
    NonFinite {
        /// Source name.
        file: String,
        /// 1-based line.
        line: usize,
        /// `"x"` or `"y"`.
        field: &'static str,
        /// The value read.
        value: f64,
    },
    /// A coordinate is outside the sane range of a chord-normalised file.
    #[error(
        "{file}:{line}: {field} = {value} is outside ±{limit} (a .dat file is chord-normalised)"
    )]
    OutOfRange {
        /// Source name.
        file: String,
        /// 1-based line.
        line: usize,
        /// `"x"` or `"y"`.
        field: &'static str,
        /// The value read.
        value: f64,
        /// The accepted magnitude.
        limit: f64,
    },
    /// A Lednicer file's point counts do not match its data.
    #[error(
        "{file}:{line}: Lednicer header declares {upper} upper + {lower} lower points, \
         the file has {found_upper} + {found_lower}"
    )]
    LednicerCount {
        /// Source name.
        file: String,
        /// 1-based line of the counts header.
        line: usize,
        /// Declared upper-surface count.
        upper: usize,
        /// Declared lower-surface count.
        lower: usize,
        /// Upper-surface points found (first blank-separated block, or by count).
        found_upper: usize,
        /// Lower-surface points found.
        found_lower: usize,
    },
    /// More than [`MAX_POINTS`] coordinate lines.
    #[error("{file}:{line}: more than {MAX_POINTS} coordinate lines: the limit is {MAX_POINTS} points (MAX_POINTS)")]
    TooManyPoints {
        /// Source name.
        file: String,
        /// 1-based line of the first coordinate over the limit.
        line: usize,
    },
    /// Fewer than [`MIN_POINTS`] distinct points.
    #[error("{file}:{line}: only {found} distinct points, need at least {MIN_POINTS}")]
    TooFewPoints {
        /// Source name.
        file: String,
        /// 1-based line of the last coordinate read (or of the end of the file).
        line: usize,
        /// Distinct points found.
        found: usize,
    },
    /// The points do not form a usable section (zero area, zero chord, LE at an end point…).
    #[error("{file}: degenerate section: {reason}")]
    Degenerate {
        /// Source or airfoil name.
        file: String,
        /// What is degenerate.
        reason: String,
    },
    /// A geometry parameter was out of its domain.
    #[error("{file}: invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Airfoil name.
        file: String,
        /// Parameter name, e.g. `chord_mm`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted domain.
        reason: &'static str,
    },
}

/// A closed airfoil section, anticlockwise in Selig order (see the module docs).
///
/// Invariants, upheld by every constructor: at least [`MIN_POINTS`] finite points, no two
/// consecutive points equal, positive signed area, non-zero chord, and the LE strictly inside
/// the point list (both surfaces have at least two points).
#[derive(Debug, Clone, PartialEq)]
pub struct Airfoil {
    name: String,
    points: Vec<Point2<f64>>,
}

/// Why a point list is not a valid section (mapped to an [`AirfoilError`] by the caller).
enum Problem {
    NonFinite(usize),
    TooFew(usize),
    Degenerate(&'static str),
}

impl Airfoil {
    /// Builds a section from points in either rotational order.
    ///
    /// Drops exact duplicate consecutive points, then reverses the list if its signed area is
    /// negative (clockwise), so the result is anticlockwise. The first point stays the first
    /// point, so a Selig-style list (starting at the TE) stays in Selig order.
    ///
    /// # Errors
    /// [`AirfoilError::Degenerate`] for non-finite points, fewer than [`MIN_POINTS`] distinct
    /// points, zero area, zero chord or a leading edge (min x) at either end of the list.
    pub fn new(name: impl Into<String>, points: Vec<Point2<f64>>) -> Result<Self, AirfoilError> {
        let name = name.into();
        match validate(points) {
            Ok(points) => Ok(Self { name, points }),
            Err(problem) => {
                let reason = match problem {
                    Problem::NonFinite(i) => format!("point {i} is not finite"),
                    Problem::TooFew(n) => {
                        format!("only {n} distinct points, need at least {MIN_POINTS}")
                    }
                    Problem::Degenerate(why) => why.to_string(),
                };
                Err(AirfoilError::Degenerate { file: name, reason })
            }
        }
    }

    /// Parses UIUC `.dat` text; `source_name` names the source in errors and, when the file has
    /// no name line, becomes the airfoil name (its file stem).
    ///
    /// Both layouts are detected automatically:
    /// - **Selig**: a name line, then `x y` from the TE over the upper surface to the LE and back
    ///   over the lower surface.
    /// - **Lednicer**: a name line, then the point counts (`61.  61.`), then the upper surface
    ///   LE → TE, a blank line, and the lower surface LE → TE. Recognised by a first numeric row
    ///   whose two values are whole numbers ≥ 2 (impossible as normalised coordinates).
    ///
    /// Tolerates blank lines, tabs, trailing spaces, CRLF and a UTF-8 BOM. After a blank line,
    /// a line that does not start with a number ends the data: the rest is taken as notes
    /// (UIUC's `ag24.dat` has such a trailer). Clockwise files are flipped and duplicate
    /// consecutive points (Lednicer's shared LE) dropped, as in [`Airfoil::new`].
    ///
    /// # Errors
    /// Non-numeric coordinates, wrong column counts, NaN/∞, |x| or |y| > 2, Lednicer counts
    /// that do not match, fewer than [`MIN_POINTS`] points (all with file and 1-based line),
    /// and the degenerate cases of [`Airfoil::new`].
    pub fn from_dat_str(text: &str, source_name: &str) -> Result<Self, AirfoilError> {
        let parsed = dat::parse(text, source_name)?;
        let name = parsed.name.unwrap_or_else(|| {
            Path::new(source_name)
                .file_stem()
                .map_or_else(|| source_name.to_string(), |s| s.to_string_lossy().into())
        });
        let file = source_name.to_string();
        match validate(parsed.points) {
            Ok(points) => Ok(Self { name, points }),
            Err(Problem::TooFew(found)) => Err(AirfoilError::TooFewPoints {
                file,
                line: parsed.last_line,
                found,
            }),
            // The parser already rejected non-finite values with their line.
            Err(Problem::NonFinite(i)) => Err(AirfoilError::Degenerate {
                file,
                reason: format!("point {i} is not finite"),
            }),
            Err(Problem::Degenerate(why)) => Err(AirfoilError::Degenerate {
                file,
                reason: why.into(),
            }),
        }
    }

    /// Reads and parses a UIUC `.dat` file (see [`Airfoil::from_dat_str`]); errors name `path`.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, AirfoilError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| AirfoilError::Io {
            file: file.clone(),
            source,
        })?;
        Self::from_dat_str(&text, &file)
    }

    /// The section's name (the `.dat` name line).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The points, anticlockwise in Selig order.
    pub fn points(&self) -> &[Point2<f64>] {
        &self.points
    }

    /// Index of the leading edge: the first point with the smallest x.
    pub fn leading_edge_index(&self) -> usize {
        le_index(&self.points)
    }

    /// The leading-edge vertex (smallest x).
    pub fn leading_edge(&self) -> Point2<f64> {
        self.points[self.leading_edge_index()]
    }

    /// The trailing edge: midpoint of the first and last point.
    pub fn trailing_edge(&self) -> Point2<f64> {
        nalgebra::center(&self.points[0], &self.points[self.points.len() - 1])
    }

    /// Upper surface, TE → LE (indices `0..=le`).
    pub fn upper_surface(&self) -> &[Point2<f64>] {
        &self.points[..=self.leading_edge_index()]
    }

    /// Lower surface, LE → TE (indices `le..`).
    pub fn lower_surface(&self) -> &[Point2<f64>] {
        &self.points[self.leading_edge_index()..]
    }

    /// Chord length ‖TE − LE‖, in the section's units.
    pub fn chord(&self) -> f64 {
        nalgebra::distance(&self.leading_edge(), &self.trailing_edge())
    }

    /// Signed area by the shoelace formula over the closed polygon,
    /// ½ Σ (xᵢ yᵢ₊₁ − xᵢ₊₁ yᵢ); positive for anticlockwise order.
    pub fn signed_area(&self) -> f64 {
        signed_area(&self.points)
    }

    /// Distance between the first and last point: 0 for a sharp trailing edge.
    pub fn trailing_edge_gap(&self) -> f64 {
        nalgebra::distance(&self.points[0], &self.points[self.points.len() - 1])
    }

    /// The section moved so the LE is at the origin and the TE at (1, 0): translate by −LE,
    /// rotate by −atan2(TE − LE), scale by 1/chord.
    ///
    /// Rotating can make a neighbouring vertex the new min-x LE; the transform is repeated
    /// (at most 4 times) until the LE vertex is stable, so for any real section the result has
    /// LE exactly at the origin and chord 1 up to rounding.
    pub fn normalised(&self) -> Airfoil {
        let mut out = self.clone();
        for _ in 0..4 {
            let le_i = out.leading_edge_index();
            let (le, te) = (out.leading_edge(), out.trailing_edge());
            let d = te - le;
            let rot = Rotation2::new(-d.y.atan2(d.x));
            let k = 1.0 / d.norm();
            let points: Vec<_> = out
                .points
                .iter()
                .map(|p| Point2::from(rot * (p - le) * k))
                .collect();
            // Similarity transforms keep the orientation, so no re-validation is needed.
            out = Airfoil {
                name: out.name,
                points,
            };
            if out.leading_edge_index() == le_i {
                break;
            }
        }
        out
    }

    /// The section scaled uniformly about its LE so that its chord becomes `chord_mm`
    /// (any unit; mm by convention). Scaling about the LE keeps the same LE vertex.
    ///
    /// # Errors
    /// [`AirfoilError::InvalidParameter`] unless `chord_mm` is finite and > 0.
    pub fn scaled(&self, chord_mm: f64) -> Result<Airfoil, AirfoilError> {
        if !(chord_mm.is_finite() && chord_mm > 0.0) {
            return Err(self.invalid("chord_mm", chord_mm, "must be finite and > 0"));
        }
        let le = self.leading_edge();
        let k = chord_mm / self.chord();
        self.mapped(|p| le + (p - le) * k)
    }

    /// The section rotated by `angle_deg` about `pivot`. **Positive is nose up**: the LE (at
    /// smaller x than the TE) rises and the TE drops, i.e. a *clockwise* rotation by
    /// `angle_deg` in the usual x-right, y-up frame (the G-Wing convention). The LE is then the
    /// new min-x vertex.
    ///
    /// # Errors
    /// [`AirfoilError::InvalidParameter`] for a non-finite angle or pivot;
    /// [`AirfoilError::Degenerate`] if the rotated section has its min-x vertex at an end of
    /// the list (rotations of roughly ±90° or more).
    pub fn twisted(&self, angle_deg: f64, pivot: Point2<f64>) -> Result<Airfoil, AirfoilError> {
        if !angle_deg.is_finite() {
            return Err(self.invalid("angle_deg", angle_deg, "must be finite"));
        }
        if !(pivot.x.is_finite() && pivot.y.is_finite()) {
            return Err(self.invalid("pivot", f64::NAN, "must be finite"));
        }
        let rot = Rotation2::new(-angle_deg.to_radians());
        self.mapped(|p| pivot + rot * (p - pivot))
    }

    /// The section translated by `by`.
    ///
    /// # Errors
    /// [`AirfoilError::InvalidParameter`] for a non-finite offset.
    pub fn translated(&self, by: Vector2<f64>) -> Result<Airfoil, AirfoilError> {
        if !(by.x.is_finite() && by.y.is_finite()) {
            return Err(self.invalid("by", f64::NAN, "must be finite"));
        }
        self.mapped(|p| p + by)
    }

    /// The section with a closed (zero-gap) trailing edge.
    ///
    /// Method: the TE midpoint M is **added at both ends** of the point list, so the list runs
    /// M → upper → LE → lower → M. M lies on the old implied closing segment, so the enclosed
    /// shape, the LE, the TE and every original point are unchanged; the blunt base simply
    /// becomes an explicit part of the path (the wire cuts across it from its midpoint).
    /// A section whose gap is already 0 is returned unchanged.
    pub fn closed_trailing_edge(&self) -> Airfoil {
        if self.trailing_edge_gap() == 0.0 {
            return self.clone();
        }
        let m = self.trailing_edge();
        let mut points = Vec::with_capacity(self.points.len() + 2);
        points.push(m);
        points.extend_from_slice(&self.points);
        points.push(m);
        Airfoil {
            name: self.name.clone(),
            points,
        }
    }

    /// Resampled to `n` points with **cosine spacing in x** on each surface.
    ///
    /// In the chord frame (origin at the LE, x along LE → TE) the upper surface gets
    /// `n/2 + 1` points and the lower `⌈n/2⌉` (sharing the LE), at
    /// xₖ = x_end·(1 − cos(πk/(m−1)))/2, where x_end is the chord-frame x of that surface's
    /// end point. y is interpolated linearly on the first crossing of xₖ walking from the LE,
    /// so x is strictly monotone on each surface. The LE vertex and both end points are kept
    /// exactly. Surfaces that double back in x (unusual) follow their first crossing.
    ///
    /// # Errors
    /// `n < MIN_POINTS`; a surface whose end is not aft of the LE in the chord frame.
    pub fn resampled_cosine(&self, n: usize) -> Result<Airfoil, AirfoilError> {
        self.check_count(n)?;
        let (m_upper, m_lower) = surface_counts(n);
        let le = self.leading_edge();
        let u = (self.trailing_edge() - le) / self.chord();
        let v = Vector2::new(-u.y, u.x);
        let to_local = |p: &Point2<f64>| Point2::new((p - le).dot(&u), (p - le).dot(&v));
        let from_local = |q: Point2<f64>| le + u * q.x + v * q.y;

        let resample = |surface_from_le: Vec<Point2<f64>>, m: usize| {
            let local: Vec<_> = surface_from_le.iter().map(to_local).collect();
            let x_end = local[local.len() - 1].x;
            if x_end <= 0.0 {
                return Err(AirfoilError::Degenerate {
                    file: self.name.clone(),
                    reason: "a surface does not end aft of the leading edge".into(),
                });
            }
            let xs: Vec<f64> = cosine_fractions(m).iter().map(|f| f * x_end).collect();
            let mut out: Vec<_> = sample_by_x(&local, &xs)
                .into_iter()
                .map(from_local)
                .collect();
            // Keep the LE and the surface end exactly, free of frame round-trip rounding.
            out[0] = surface_from_le[0];
            out[m - 1] = surface_from_le[surface_from_le.len() - 1];
            Ok(out)
        };
        let mut upper = resample(
            self.upper_surface().iter().rev().copied().collect(),
            m_upper,
        )?;
        let lower = resample(self.lower_surface().to_vec(), m_lower)?;
        upper.reverse();
        upper.extend_from_slice(&lower[1..]);
        Airfoil::new(self.name.clone(), upper)
    }

    /// Cumulative arc length along the point list (first → last, without the implied closing
    /// segment), normalised to 0 … 1: sᵢ = Σ_{j<i} ‖pⱼ₊₁ − pⱼ‖ / L.
    pub fn arc_length_params(&self) -> Vec<f64> {
        let cum = cumulative_lengths(&self.points, Norm::Sqrt);
        let total = cum[cum.len() - 1];
        cum.iter().map(|s| s / total).collect()
    }

    /// Resampled to `n` points evenly spaced in arc length along the point list, first and last
    /// point kept exactly. The LE is generally *not* one of the new points; use
    /// [`Airfoil::resampled_cosine`] or [`synchronise`] when it must be.
    ///
    /// # Errors
    /// `n < MIN_POINTS`.
    pub fn resample_by_arc_length(&self, n: usize) -> Result<Airfoil, AirfoilError> {
        self.check_count(n)?;
        let fractions: Vec<f64> = (0..n).map(|k| k as f64 / (n - 1) as f64).collect();
        Airfoil::new(
            self.name.clone(),
            sample_at_arc_fractions(&self.points, &fractions, Norm::Sqrt),
        )
    }

    fn mapped(&self, f: impl Fn(&Point2<f64>) -> Point2<f64>) -> Result<Airfoil, AirfoilError> {
        Airfoil::new(self.name.clone(), self.points.iter().map(f).collect())
    }

    fn invalid(&self, name: &'static str, value: f64, reason: &'static str) -> AirfoilError {
        AirfoilError::InvalidParameter {
            file: self.name.clone(),
            name,
            value,
            reason,
        }
    }

    fn check_count(&self, n: usize) -> Result<(), AirfoilError> {
        if n < MIN_POINTS {
            return Err(self.invalid("n", n as f64, "need at least MIN_POINTS (5) points"));
        }
        Ok(())
    }
}

/// Root and tip points of [`synchronise`], index-matched.
pub type SyncedPoints = (Vec<Point2<f64>>, Vec<Point2<f64>>);

/// Resamples `root` and `tip` to `n` points each that correspond one to one, for a hot wire
/// whose two ends must pass matching points at the same time.
///
/// Each section is split at its LE; the upper surfaces get `n/2 + 1` points and the lower
/// `⌈n/2⌉` (sharing the LE). On every surface, point k sits at the same **normalised arc
/// length** sₖ = (1 − cos(πk/(m−1)))/2 of that surface on both sections (cosine clustering puts
/// more points near the LE and TE, where curvature is high). Hence index `n/2` is the LE on
/// both, index 0 and n−1 are each section's first and last point, and the output keeps
/// Selig order. Neither section needs the same point count or spacing as the other.
///
/// # Errors
/// [`AirfoilError::InvalidParameter`] for `n < MIN_POINTS`.
pub fn synchronise(root: &Airfoil, tip: &Airfoil, n: usize) -> Result<SyncedPoints, AirfoilError> {
    root.check_count(n)?;
    let (m_upper, m_lower) = surface_counts(n);
    let (f_upper, f_lower) = (cosine_fractions(m_upper), cosine_fractions(m_lower));
    let sync = |foil: &Airfoil| {
        let mut pts = sample_at_arc_fractions(foil.upper_surface(), &f_upper, Norm::Sqrt);
        let lower = sample_at_arc_fractions(foil.lower_surface(), &f_lower, Norm::Sqrt);
        pts.extend_from_slice(&lower[1..]);
        pts
    };
    Ok((sync(root), sync(tip)))
}

/// Point counts (upper, lower) for `n` points in total sharing the LE.
fn surface_counts(n: usize) -> (usize, usize) {
    (n / 2 + 1, n - n / 2)
}

/// m fractions 0 … 1 with cosine clustering at both ends; exactly 0 and 1 at the ends.
fn cosine_fractions(m: usize) -> Vec<f64> {
    let last = (m.max(2) - 1) as f64;
    (0..m)
        .map(|k| 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / last).cos()))
        .collect()
}

fn le_index(points: &[Point2<f64>]) -> usize {
    let mut best = 0;
    for (i, p) in points.iter().enumerate() {
        if p.x < points[best].x {
            best = i;
        }
    }
    best
}

fn validate(mut points: Vec<Point2<f64>>) -> Result<Vec<Point2<f64>>, Problem> {
    if let Some(i) = points
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(Problem::NonFinite(i));
    }
    points.dedup();
    if points.len() < MIN_POINTS {
        return Err(Problem::TooFew(points.len()));
    }
    let area = signed_area(&points);
    if !(area.is_finite() && area != 0.0) {
        return Err(Problem::Degenerate("zero (or non-finite) enclosed area"));
    }
    if area < 0.0 {
        points.reverse();
    }
    let le = le_index(&points);
    if le == 0 || le == points.len() - 1 {
        return Err(Problem::Degenerate(
            "the leading edge (min x) is an end point, so one surface is empty",
        ));
    }
    let te = nalgebra::center(&points[0], &points[points.len() - 1]);
    if nalgebra::distance(&points[le], &te) == 0.0 {
        return Err(Problem::Degenerate("zero chord"));
    }
    Ok(points)
}

/// Points on the polyline `local` at ascending `xs`, each on the first segment (from the start,
/// never moving back) whose x-range contains it; beyond the polyline the last segment is used.
fn sample_by_x(local: &[Point2<f64>], xs: &[f64]) -> Vec<Point2<f64>> {
    let mut seg = 0;
    xs.iter()
        .map(|&x| {
            while seg + 2 < local.len() {
                let (a, b) = (local[seg].x, local[seg + 1].x);
                if a.min(b) <= x && x <= a.max(b) {
                    break;
                }
                seg += 1;
            }
            let (a, b) = (local[seg], local[seg + 1]);
            let t = if b.x != a.x {
                ((x - a.x) / (b.x - a.x)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            Point2::new(x, a.y + (b.y - a.y) * t)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config_foil(name: &str) -> Airfoil {
        let path = format!(
            "{}/../../config/airfoils/{name}.dat",
            env!("CARGO_MANIFEST_DIR")
        );
        Airfoil::load(&path).unwrap_or_else(|e| panic!("{e}"))
    }

    /// A symmetric diamond-ish section with a blunt TE, anticlockwise in Selig order.
    fn blunt() -> Airfoil {
        let pts = [
            (1.0, 0.01),
            (0.5, 0.06),
            (0.1, 0.04),
            (0.0, 0.0),
            (0.1, -0.04),
            (0.5, -0.06),
            (1.0, -0.01),
        ];
        Airfoil::new(
            "blunt",
            pts.iter().map(|&(x, y)| Point2::new(x, y)).collect(),
        )
        .unwrap()
    }

    #[test]
    fn chord_le_te_and_gap() {
        let f = blunt();
        assert_eq!(f.leading_edge_index(), 3);
        assert_eq!(f.trailing_edge(), Point2::new(1.0, 0.0));
        assert!((f.chord() - 1.0).abs() < 1e-15);
        assert!((f.trailing_edge_gap() - 0.02).abs() < 1e-15);
        assert!(f.signed_area() > 0.0);
    }

    #[test]
    fn new_flips_clockwise_and_rejects_degenerate() {
        let mut pts = blunt().points().to_vec();
        pts.reverse();
        let f = Airfoil::new("cw", pts).unwrap();
        assert_eq!(f.points(), blunt().points());
        let line: Vec<_> = (0..6).map(|i| Point2::new(i as f64, 0.0)).collect();
        assert!(matches!(
            Airfoil::new("line", line),
            Err(AirfoilError::Degenerate { .. })
        ));
        let nan = vec![Point2::new(f64::NAN, 0.0); 6];
        assert!(Airfoil::new("nan", nan).is_err());
    }

    #[test]
    fn normalised_scaled_translated() {
        let f = config_foil("clarky")
            .scaled(200.0)
            .unwrap()
            .twisted(7.0, Point2::new(50.0, 0.0))
            .unwrap()
            .translated(Vector2::new(-30.0, 12.0))
            .unwrap();
        assert!(
            (f.chord() - 200.0).abs() < 0.5,
            "twist may move the min-x vertex slightly"
        );
        let n = f.normalised();
        assert!(n.leading_edge().coords.norm() < 1e-12);
        assert!((n.chord() - 1.0).abs() < 1e-12);
        assert!(n.trailing_edge().y.abs() < 1e-12);
        assert!(n.signed_area() > 0.0);
        let s = n.scaled(150.0).unwrap();
        assert!((s.chord() - 150.0).abs() < 1e-9);
        assert!(n.scaled(0.0).is_err() && n.scaled(f64::NAN).is_err());
        assert!(n.translated(Vector2::new(f64::INFINITY, 0.0)).is_err());
    }

    #[test]
    fn positive_twist_is_nose_up() {
        let f = config_foil("naca0012").normalised();
        let t = f.twisted(5.0, Point2::new(0.25, 0.0)).unwrap();
        let le = t.points()[f.leading_edge_index()];
        assert!(le.y > 0.02, "LE rises: {le}");
        assert!(t.trailing_edge().y < -0.06, "TE drops");
        assert!(t.signed_area() > 0.0);
        assert!(f.twisted(f64::NAN, Point2::origin()).is_err());
    }

    #[test]
    fn closed_trailing_edge_adds_midpoint_only() {
        let f = blunt();
        let c = f.closed_trailing_edge();
        assert_eq!(c.trailing_edge_gap(), 0.0);
        assert_eq!(&c.points()[1..c.points().len() - 1], f.points());
        assert_eq!(c.trailing_edge(), f.trailing_edge());
        assert!((c.signed_area() - f.signed_area()).abs() < 1e-15);
        assert_eq!(c.closed_trailing_edge(), c, "already closed: unchanged");
    }

    #[test]
    fn resampled_cosine_keeps_le_te_and_monotone_x() {
        for name in ["s1223", "clarky", "ag24"] {
            let f = config_foil(name).normalised();
            for n in [5, 40, 81] {
                let r = f.resampled_cosine(n).unwrap();
                let p = r.points();
                assert_eq!(p.len(), n, "{name} n={n}");
                assert_eq!(p[0], f.points()[0]);
                assert_eq!(p[n - 1], f.points()[f.points().len() - 1]);
                let le = r.leading_edge_index();
                assert_eq!(le, n / 2);
                assert_eq!(p[le], f.leading_edge());
                assert!(
                    p[..=le].windows(2).all(|w| w[0].x > w[1].x),
                    "{name}: upper"
                );
                assert!(p[le..].windows(2).all(|w| w[0].x < w[1].x), "{name}: lower");
                assert!(r.signed_area() > 0.0);
            }
            assert!(f.resampled_cosine(4).is_err());
        }
    }

    #[test]
    fn resampled_cosine_tracks_the_shape() {
        let f = config_foil("s1223").normalised();
        let r = f.resampled_cosine(200).unwrap();
        assert!((r.signed_area() - f.signed_area()).abs() < 1e-3 * f.signed_area());
    }

    #[test]
    fn arc_length_params_and_resample() {
        let f = config_foil("e387");
        let s = f.arc_length_params();
        assert_eq!(s.len(), f.points().len());
        assert_eq!((s[0], s[s.len() - 1]), (0.0, 1.0));
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        let r = f.resample_by_arc_length(50).unwrap();
        assert_eq!(r.points().len(), 50);
        assert_eq!(r.points()[0], f.points()[0]);
        assert_eq!(r.points()[49], f.points()[f.points().len() - 1]);
        let rs = r.arc_length_params();
        for (k, s) in rs.iter().enumerate() {
            // Chords are shorter than arcs, so the spacing is only near-uniform.
            assert!((s - k as f64 / 49.0).abs() < 0.01, "k={k} s={s}");
        }
    }

    #[test]
    fn synchronise_matches_le_and_te() {
        let root = config_foil("s1223").scaled(250.0).unwrap();
        let tip = config_foil("clarky").scaled(150.0).unwrap();
        for n in [5, 100, 101] {
            let (r, t) = synchronise(&root, &tip, n).unwrap();
            assert_eq!((r.len(), t.len()), (n, n));
            assert_eq!(r[n / 2], root.leading_edge(), "root LE at n/2");
            assert_eq!(t[n / 2], tip.leading_edge(), "tip LE at n/2");
            assert_eq!(
                (r[0], r[n - 1]),
                (root.points()[0], *root.points().last().unwrap())
            );
            assert_eq!(
                (t[0], t[n - 1]),
                (tip.points()[0], *tip.points().last().unwrap())
            );
            let rf = Airfoil::new("r", r).unwrap();
            let tf = Airfoil::new("t", t).unwrap();
            assert_eq!(rf.leading_edge_index(), n / 2);
            assert_eq!(tf.leading_edge_index(), n / 2);
        }
        assert!(synchronise(&root, &tip, 3).is_err());
    }
}
