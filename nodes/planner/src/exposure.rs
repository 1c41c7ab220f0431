//! Surface thermal exposure of a foil cut along a wire path (seed 000 eq. 1–5), integrated in
//! closed form over each straight wire segment.
//!
//! # The model
//! The surface is a closed polyline of N panels and the wire path an open polyline of M
//! segments, both anticlockwise in Selig order from the trailing edge (see
//! `swarmcut-model-notes.md`). For surface panel i (midpoint sᵢ, unit tangent tᵢ in the
//! direction of travel) and a point r on wire segment j (unit direction wⱼ):
//!
//! - R = r − sᵢ (seed 000 eq. 1);
//! - C = tᵢ × R, z component (seed 000 eq. 2);
//! - χ = 1 where C ≤ 0, i.e. the wire is on the outer side of the panel's tangent line, else 0
//!   (seed 000 eq. 3; eq. 5 calls it V). Only a half-plane test: the foil never shadows the wire.
//! - P = |tᵢ · wⱼ| (seed 000 eq. 4 with **unit** tangents, ambiguity 2 of the notes; the
//!   paper-literal form is [`Perspective::PaperLiteral`]);
//! - Eᵢ = Σⱼ ∫ χ · P / ‖R‖ᵖ dσ over the wire arc length σ in mm (seed 000 eq. 5), with p = 1
//!   ([`DistanceLaw::Paper`]) or p = 2 ([`DistanceLaw::AuthorCode`]).
//!
//! # Closed-form integration
//! Along a straight segment C is linear in σ, so χ clips the segment to one exact sub-interval.
//! With d the perpendicular distance from sᵢ to the segment's line and x the signed position
//! along the line from the foot of that perpendicular, ‖R‖² = x² + d² and
//!
//! - ∫ dx / √(x² + d²) = asinh(x/d), evaluated as ln(g(x₁)/g(x₀)) with g(x) = x + √(x²+d²)
//!   (or d²/(√(x²+d²) − x) for x < 0, free of cancellation);
//! - ∫ dx / (x² + d²) = atan(x/d)/d, evaluated as atan2(d(x₁ − x₀), d² + x₀x₁)/d.
//!
//! So E does not depend on how finely a given geometric path is split into segments, and it
//! does not depend on N either: there is no panel-length factor (ambiguity 4).
//!
//! **Unit.** Eᵢ is a line integral over the wire path of |cos θ|/‖R‖ᵖ: with
//! [`DistanceLaw::Paper`] it is mm/mm, i.e. **dimensionless**; with [`DistanceLaw::AuthorCode`]
//! it is **mm⁻¹**. It is a property of the point sᵢ (a panel midpoint), not of the panel.
//!
//! **Degenerate distance.** d is replaced by max(d, `min_distance_mm`) (default 0.05 mm, about a
//! 0.1 mm wire's radius: the wire centre can never be closer to the surface than that), so a
//! wire passing through sᵢ gives a large but finite value.
//!
//! # Causal mask (not in the paper)
//! A surface point stops being heated once the wire has cut past it. Its *cut point* is the
//! point of the wire path nearest to sᵢ, searched only within ±[`CAUSAL_WINDOW`] (25 %) of
//! normalised wire arc length around sᵢ's own normalised arc position on the surface (no wrap
//! round: the wire path is open and runs once), so a trailing-edge panel does not pick the
//! wire's other pass. See [`Causal`] for how the cut point masks the wire.

use nalgebra::Point2;

/// Half-width of the causal search window in normalised arc length (notes: "about ±25 %").
pub const CAUSAL_WINDOW: f64 = 0.25;

/// A rejected exposure-model input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExposureError {
    /// A parameter is NaN, infinite or out of its domain; `name` names it.
    #[error("{name} = {value} is invalid: must be {requirement}")]
    InvalidParameter {
        /// Parameter name, e.g. `min_distance_mm` or `wire[3]`.
        name: String,
        /// The value given.
        value: f64,
        /// The accepted domain.
        requirement: &'static str,
    },
    /// A polyline has too few distinct points or zero length.
    #[error("{name}: {reason}")]
    Degenerate {
        /// Which input (`surface` or `wire`).
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// An output buffer has the wrong length.
    #[error("output has {found} entries, the surface has {expected} panels")]
    OutputLength {
        /// Surface panel count.
        expected: usize,
        /// Buffer length given.
        found: usize,
    },
}

/// Distance exponent of seed 000 eq. 5 (ambiguity 3 of the notes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DistanceLaw {
    /// 1/‖R‖, as printed in seed 000 eq. 5 (default). E is dimensionless.
    #[default]
    Paper,
    /// 1/‖R‖², as in the author's public code. E is in mm⁻¹.
    AuthorCode,
}

/// Perspective factor of seed 000 eq. 4 (ambiguity 2 of the notes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Perspective {
    /// P = |t · w| with unit tangents, times the wire arc-length element dσ (default): the
    /// "angle and panel size" the paper's text describes.
    #[default]
    UnitTangents,
    /// The literal eq. 4–5 with unnormalised derivatives, the polylines parameterised
    /// uniformly per panel/segment (Δv = 1/N, Δu = 1/M): each pair is weighted by an extra
    /// (ℓᵢ·N)·(Lⱼ·M). Depends on N, M and the spacing; for comparison only.
    PaperLiteral,
}

/// How the causal cut point (module docs) masks the wire path for a surface point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Causal {
    /// No mask: the whole path heats every point (what seed 000 eq. 5 literally integrates).
    Off,
    /// The path up to the cut point counts, the rest not at all (default). This is the
    /// continuum limit of [`Causal::HalfSegment`] (a wire parallel to a flat surface heats a
    /// point exactly half as much as with no mask) and, unlike it, independent of M.
    #[default]
    CutPoint,
    /// The notes' discrete rule: segments before the one containing the cut point count fully,
    /// that segment half, later ones not at all. Depends on the wire discretisation.
    HalfSegment,
}

/// Exposure-model settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExposureModel {
    /// Distance exponent (default [`DistanceLaw::Paper`]).
    pub law: DistanceLaw,
    /// Perspective factor (default [`Perspective::UnitTangents`]).
    pub perspective: Perspective,
    /// Causal mask (default [`Causal::CutPoint`]).
    pub causal: Causal,
    /// Floor on the perpendicular distance d in the closed forms, mm (default 0.05).
    pub min_distance_mm: f64,
}

impl Default for ExposureModel {
    fn default() -> Self {
        Self {
            law: DistanceLaw::Paper,
            perspective: Perspective::UnitTangents,
            causal: Causal::CutPoint,
            min_distance_mm: 0.05,
        }
    }
}

/// A closed surface polyline as panels, structure of arrays, precomputed once.
#[derive(Debug, Clone, PartialEq)]
pub struct Panels {
    sx: Vec<f64>,
    sy: Vec<f64>,
    tx: Vec<f64>,
    ty: Vec<f64>,
    len: Vec<f64>,
    /// Normalised arc position of each midpoint, 0 … 1 from points[0].
    u: Vec<f64>,
    perimeter: f64,
}

impl Panels {
    /// Panels of the closed polygon `points` (mm, anticlockwise, Selig order): panel i runs
    /// points[i] → points[i+1], the last one closes back to points[0]. A repeated first point at
    /// the end and exact duplicate consecutive points are dropped first, so there are no
    /// zero-length panels; N = number of distinct points.
    ///
    /// # Errors
    /// A non-finite point (named `surface[i]`), fewer than 3 distinct points.
    pub fn from_points(points: &[Point2<f64>]) -> Result<Self, ExposureError> {
        check_finite("surface", points)?;
        let mut ring = points.to_vec();
        ring.dedup();
        if ring.len() > 1 && ring.first() == ring.last() {
            ring.pop();
        }
        let n = ring.len();
        if n < 3 {
            return Err(ExposureError::Degenerate {
                name: "surface",
                reason: format!("{n} distinct points, need at least 3"),
            });
        }
        let mut p = Self {
            sx: Vec::with_capacity(n),
            sy: Vec::with_capacity(n),
            tx: Vec::with_capacity(n),
            ty: Vec::with_capacity(n),
            len: Vec::with_capacity(n),
            u: Vec::with_capacity(n),
            perimeter: 0.0,
        };
        let mut s = 0.0;
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let d = b - a;
            let l = d.norm();
            p.sx.push(0.5 * (a.x + b.x));
            p.sy.push(0.5 * (a.y + b.y));
            p.tx.push(d.x / l);
            p.ty.push(d.y / l);
            p.len.push(l);
            p.u.push(s + 0.5 * l);
            s += l;
        }
        p.perimeter = s;
        for u in &mut p.u {
            *u /= s;
        }
        Ok(p)
    }

    /// Number of panels N.
    pub fn len(&self) -> usize {
        self.len.len()
    }

    /// Always false: a surface has at least 3 panels.
    pub fn is_empty(&self) -> bool {
        self.len.is_empty()
    }

    /// Midpoint sᵢ of panel `i`, mm.
    pub fn midpoint(&self, i: usize) -> Point2<f64> {
        Point2::new(self.sx[i], self.sy[i])
    }

    /// Unit tangent tᵢ of panel `i` (direction of travel).
    pub fn tangent(&self, i: usize) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::new(self.tx[i], self.ty[i])
    }

    /// Length ℓᵢ of panel `i`, mm.
    pub fn length_mm(&self, i: usize) -> f64 {
        self.len[i]
    }

    /// Normalised arc position (0 … 1 from the first point) of panel `i`'s midpoint.
    pub fn arc_position(&self, i: usize) -> f64 {
        self.u[i]
    }

    /// Perimeter of the closed polygon, mm.
    pub fn perimeter_mm(&self) -> f64 {
        self.perimeter
    }
}

/// An open wire polyline as segments, structure of arrays. Reusable: [`WireSegments::set`]
/// refills it without allocating once its capacity suffices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WireSegments {
    ax: Vec<f64>,
    ay: Vec<f64>,
    wx: Vec<f64>,
    wy: Vec<f64>,
    len: Vec<f64>,
    /// Arc length at each segment start, mm.
    s0: Vec<f64>,
    total: f64,
}

impl WireSegments {
    /// Segments of the open polyline `points` (mm): segment j runs points[j] → points[j+1], so
    /// M = points.len() − 1 (a closed path repeats its first point at the end). Zero-length
    /// segments are kept (they contribute nothing) so row j of [`ExposureModel::exposure_matrix`]
    /// is always segment j.
    ///
    /// # Errors
    /// A non-finite point (named `wire[j]`), fewer than 2 points, zero total length.
    pub fn from_points(points: &[Point2<f64>]) -> Result<Self, ExposureError> {
        let mut w = Self::default();
        w.set(points)?;
        Ok(w)
    }

    /// Refills from `points`, as [`WireSegments::from_points`]; on error `self` is unchanged.
    ///
    /// # Errors
    /// As [`WireSegments::from_points`].
    pub fn set(&mut self, points: &[Point2<f64>]) -> Result<(), ExposureError> {
        check_finite("wire", points)?;
        if points.len() < 2 {
            return Err(ExposureError::Degenerate {
                name: "wire",
                reason: format!("{} points, need at least 2", points.len()),
            });
        }
        let total: f64 = points.windows(2).map(|p| (p[1] - p[0]).norm()).sum();
        if total.is_nan() || total <= 0.0 {
            return Err(ExposureError::Degenerate {
                name: "wire",
                reason: "zero total length".into(),
            });
        }
        for v in [
            &mut self.ax,
            &mut self.ay,
            &mut self.wx,
            &mut self.wy,
            &mut self.len,
            &mut self.s0,
        ] {
            v.clear();
        }
        let mut s = 0.0;
        for p in points.windows(2) {
            let d = p[1] - p[0];
            let l = d.norm();
            let (wx, wy) = if l > 0.0 {
                (d.x / l, d.y / l)
            } else {
                (0.0, 0.0)
            };
            self.ax.push(p[0].x);
            self.ay.push(p[0].y);
            self.wx.push(wx);
            self.wy.push(wy);
            self.len.push(l);
            self.s0.push(s);
            s += l;
        }
        self.total = s;
        Ok(())
    }

    /// Number of segments M.
    pub fn len(&self) -> usize {
        self.len.len()
    }

    /// True before the first successful [`WireSegments::set`].
    pub fn is_empty(&self) -> bool {
        self.len.is_empty()
    }

    /// Total path length, mm.
    pub fn length_mm(&self) -> f64 {
        self.total
    }
}

impl ExposureModel {
    /// Checks the settings.
    ///
    /// # Errors
    /// `min_distance_mm` not finite and > 0.
    pub fn validate(&self) -> Result<(), ExposureError> {
        if !(self.min_distance_mm.is_finite() && self.min_distance_mm > 0.0) {
            return Err(ExposureError::InvalidParameter {
                name: "min_distance_mm".into(),
                value: self.min_distance_mm,
                requirement: "finite and > 0",
            });
        }
        Ok(())
    }

    /// Total exposure Eᵢ of every surface panel (seed 000 eq. 5 integrated over the wire path,
    /// module docs), one value per panel, in the unit stated in the module docs.
    ///
    /// # Errors
    /// Invalid settings ([`ExposureModel::validate`]) or wire points ([`WireSegments::set`]).
    pub fn exposure(
        &self,
        surface: &Panels,
        wire: &[Point2<f64>],
    ) -> Result<Vec<f64>, ExposureError> {
        let wire = WireSegments::from_points(wire)?;
        let mut out = vec![0.0; surface.len()];
        self.exposure_into(surface, &wire, &mut out)?;
        Ok(out)
    }

    /// [`ExposureModel::exposure`] into a caller's buffer; allocates nothing. O(N·M).
    ///
    /// # Errors
    /// Invalid settings; `out.len()` ≠ N; an empty `wire`.
    pub fn exposure_into(
        &self,
        surface: &Panels,
        wire: &WireSegments,
        out: &mut [f64],
    ) -> Result<(), ExposureError> {
        self.check(surface, wire, out.len())?;
        for (i, e) in out.iter_mut().enumerate() {
            let mut sum = 0.0;
            self.panel(surface, wire, i, |_, v| sum += v);
            *e = sum;
        }
        Ok(())
    }

    /// Every wire segment's contribution to every panel's exposure: `(rows, cols, values)` with
    /// rows = M wire segments, cols = N surface panels, row-major (`values[j * cols + i]`), in
    /// f32 for display (the heat map). Column sums equal [`ExposureModel::exposure`] up to f32
    /// rounding; the causal mask is applied.
    ///
    /// # Errors
    /// As [`ExposureModel::exposure`].
    pub fn exposure_matrix(
        &self,
        surface: &Panels,
        wire: &[Point2<f64>],
    ) -> Result<(usize, usize, Vec<f32>), ExposureError> {
        let wire = WireSegments::from_points(wire)?;
        let (rows, cols) = (wire.len(), surface.len());
        self.check(surface, &wire, cols)?;
        let mut values = vec![0.0f32; rows * cols];
        for i in 0..cols {
            self.panel(surface, &wire, i, |j, v| values[j * cols + i] = v as f32);
        }
        Ok((rows, cols, values))
    }

    fn check(
        &self,
        surface: &Panels,
        wire: &WireSegments,
        out_len: usize,
    ) -> Result<(), ExposureError> {
        self.validate()?;
        if out_len != surface.len() {
            return Err(ExposureError::OutputLength {
                expected: surface.len(),
                found: out_len,
            });
        }
        if wire.is_empty() {
            return Err(ExposureError::Degenerate {
                name: "wire",
                reason: "no segments".into(),
            });
        }
        Ok(())
    }

    /// Calls `emit(j, contribution)` for every wire segment j with a non-zero contribution to
    /// panel i. The hot loop.
    #[inline]
    fn panel(&self, sf: &Panels, w: &WireSegments, i: usize, mut emit: impl FnMut(usize, f64)) {
        let (sx, sy, tx, ty) = (sf.sx[i], sf.sy[i], sf.tx[i], sf.ty[i]);
        let dmin = self.min_distance_mm;
        // Causal cut: arc position (mm along the wire) beyond which nothing counts, and for
        // HalfSegment the segment containing it.
        let (cut_s, cut_j) = match self.causal {
            Causal::Off => (f64::INFINITY, usize::MAX),
            Causal::CutPoint | Causal::HalfSegment => cut_point(w, sx, sy, sf.u[i]),
        };
        let literal = match self.perspective {
            Perspective::UnitTangents => None,
            Perspective::PaperLiteral => Some(sf.len[i] * sf.len() as f64 * w.len() as f64),
        };
        let last = match self.causal {
            Causal::Off => w.len(),
            _ => (cut_j + 1).min(w.len()),
        };
        for j in 0..last {
            let l = w.len[j];
            if l == 0.0 {
                continue;
            }
            let (wx, wy) = (w.wx[j], w.wy[j]);
            let (rx, ry) = (w.ax[j] - sx, w.ay[j] - sy);
            // C(σ) = t × (a − s) + σ · (t × w), linear (seed 000 eq. 2).
            let c0 = tx * ry - ty * rx;
            let c1 = tx * wy - ty * wx;
            let (mut lo, mut hi) = (0.0f64, l);
            if c1 == 0.0 {
                if c0 > 0.0 {
                    continue;
                }
            } else {
                let root = -c0 / c1;
                if c1 > 0.0 {
                    hi = hi.min(root);
                } else {
                    lo = lo.max(root);
                }
            }
            let mut weight = (tx * wx + ty * wy).abs();
            match self.causal {
                Causal::Off => {}
                Causal::CutPoint => hi = hi.min(cut_s - w.s0[j]),
                Causal::HalfSegment => {
                    if j == cut_j {
                        weight *= 0.5;
                    }
                }
            }
            if hi <= lo || weight == 0.0 {
                continue;
            }
            if let Some(k) = literal {
                weight *= k * l;
            }
            // Foot of the perpendicular: x = (a − s)·w + σ, d = |(a − s) × w|.
            let x0 = rx * wx + ry * wy;
            let d = (rx * wy - ry * wx).abs().max(dmin);
            let v = match self.law {
                DistanceLaw::Paper => asinh_difference(x0 + lo, x0 + hi, d),
                DistanceLaw::AuthorCode => atan_difference(x0 + lo, x0 + hi, d),
            };
            emit(j, weight * v);
        }
    }
}

/// The causal cut point for a surface point (sx, sy) at normalised surface position `u`: the
/// nearest wire point within ±[`CAUSAL_WINDOW`] of normalised wire arc length, returned as its
/// arc position in mm and the segment containing it. Ties keep the earlier point.
fn cut_point(w: &WireSegments, sx: f64, sy: f64, u: f64) -> (f64, usize) {
    let lo = (u - CAUSAL_WINDOW).max(0.0) * w.total;
    let hi = (u + CAUSAL_WINDOW).min(1.0) * w.total;
    let (mut best, mut best_s, mut best_j) = (f64::INFINITY, lo, 0);
    for j in 0..w.len() {
        let (s0, l) = (w.s0[j], w.len[j]);
        let (p, q) = ((lo - s0).max(0.0), (hi - s0).min(l));
        if p > q {
            continue;
        }
        let (rx, ry) = (w.ax[j] - sx, w.ay[j] - sy);
        let x0 = rx * w.wx[j] + ry * w.wy[j];
        let sigma = (-x0).clamp(p, q);
        let (dx, dy) = (rx + sigma * w.wx[j], ry + sigma * w.wy[j]);
        let d2 = dx * dx + dy * dy;
        if d2 < best {
            (best, best_s, best_j) = (d2, s0 + sigma, j);
        }
    }
    (best_s, best_j)
}

/// asinh(x₁/d) − asinh(x₀/d) = ∫_{x₀}^{x₁} dx/√(x² + d²), for x₀ ≤ x₁, d > 0, without the
/// cancellation of subtracting two asinh values on the same side.
#[inline]
fn asinh_difference(x0: f64, x1: f64, d: f64) -> f64 {
    let d2 = d * d;
    let g = |x: f64| {
        let r = (x * x + d2).sqrt();
        if x >= 0.0 {
            x + r
        } else {
            d2 / (r - x)
        }
    };
    (g(x1) / g(x0)).ln()
}

/// (atan(x₁/d) − atan(x₀/d))/d = ∫_{x₀}^{x₁} dx/(x² + d²), for x₀ ≤ x₁, d > 0. The difference of
/// the two angles lies in [0, π), so one atan2 gives it exactly.
#[inline]
fn atan_difference(x0: f64, x1: f64, d: f64) -> f64 {
    (d * (x1 - x0)).atan2(d * d + x0 * x1) / d
}

/// Coefficient of variation (population standard deviation / mean) of `values`; NaN for an
/// empty slice or a zero mean.
pub fn coefficient_of_variation(values: &[f64]) -> f64 {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    if mean == 0.0 {
        f64::NAN
    } else {
        var.sqrt() / mean
    }
}

fn check_finite(name: &'static str, points: &[Point2<f64>]) -> Result<(), ExposureError> {
    match points
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        None => Ok(()),
        Some(i) => Err(ExposureError::InvalidParameter {
            name: format!("{name}[{i}]"),
            value: if points[i].x.is_finite() {
                points[i].y
            } else {
                points[i].x
            },
            requirement: "finite",
        }),
    }
}

#[cfg(test)]
mod tests;
