//! Surface thermal exposure of a foil cut along a wire path (seed 000 eq. 1–5), integrated in
//! closed form over each straight wire segment.
//!
//! # The model
//! The surface is a closed polyline of N panels and the wire path an open polyline of M
//! segments, both anticlockwise in Selig order from the trailing edge (see
//! `docs/notes/swarmcut-model-notes.md`, "the notes" below). For surface panel i (midpoint
//! sᵢ, unit tangent tᵢ in the direction of travel) and a point r on wire segment j (unit
//! direction wⱼ):
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
//!
//! # Per-segment weights
//! Each wire segment carries a multiplicative weight (default 1, [`WireSegments::set_weights`]):
//! the time the wire dwells on a segment scales its heat, so a segment cut at a local feed f
//! has weight f_nominal / f. Its contribution to every panel is multiplied by the weight.
//!
//! # Two implementations
//! [`ExposureModel::exposure_into`] picks one by the settings:
//!
//! - **fast** (`exposure/fast.rs`), for [`Perspective::UnitTangents`] with [`Causal::Off`] or
//!   [`Causal::CutPoint`] (the defaults), both distance laws: f32 structure of arrays,
//!   branch-free lanes vectorised by the compiler, with one clone of the kernel per instruction
//!   set (AVX-512, AVX2+FMA, SSE4.2, NEON) picked at run time (`multiversion`); whole blocks of
//!   wire on the inner side of a panel's tangent line are skipped; the cut point search is
//!   exact (f64, the same answer as the reference) but visits only the causal window, found by
//!   binary search, and prunes it with bounding boxes. Agrees with the reference to 3e-5 of
//!   max(|Eᵢ|, mean |E|) on real foils (tests hold it to 1e-3 on foils and random, degenerate
//!   paths). Bit-identical run to run on one machine (fixed summation order); clones with
//!   and without FMA may differ in the last bits.
//! - **reference** ([`ExposureModel::exposure_reference_into`]): the f64 scalar loop, for every
//!   setting ([`Perspective::PaperLiteral`], [`Causal::HalfSegment`] only have this one).

use nalgebra::{Point2, Vector2};

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
    /// f32 copies of sx, sy, tx, ty for the fast path.
    f32: [Vec<f32>; 4],
}

impl Panels {
    /// Panels of the closed polygon `points` (mm, anticlockwise, Selig order): panel i runs
    /// `points[i]` → `points[i+1]`, the last one closes back to `points[0]`. A repeated first point at
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
            f32: Default::default(),
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
        p.f32 = [&p.sx, &p.sy, &p.tx, &p.ty].map(|v| v.iter().map(|&x| x as f32).collect());
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

    /// Panel i as an evaluation site; `literal` is the PaperLiteral surface factor ℓᵢ·N.
    #[inline]
    fn site(&self, i: usize) -> Site {
        Site {
            x: self.sx[i],
            y: self.sy[i],
            tx: self.tx[i],
            ty: self.ty[i],
            u: self.u[i],
            surface_factor: self.len[i] * self.len() as f64,
        }
    }
}

/// A point where the exposure is evaluated: a panel midpoint or [`ExposureModel::exposure_at`]'s
/// point, with its unit tangent (visibility half-plane, eq. 2–3) and normalised arc position
/// (causal window).
#[derive(Debug, Clone, Copy)]
struct Site {
    x: f64,
    y: f64,
    tx: f64,
    ty: f64,
    u: f64,
    /// ℓᵢ·N for [`Perspective::PaperLiteral`] (1 for a bare point).
    surface_factor: f64,
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
    /// Per-segment weight (default 1), module docs.
    weight: Vec<f64>,
    total: f64,
    /// f32 copies for the fast path: the M + 1 points' x and y, then the M segments' wx, wy,
    /// len and weight, all zero-padded to M + 1 + [`fast::LANES`].
    f32: [Vec<f32>; 6],
    /// Bounding boxes [xmin, ymin, xmax, ymax] of every [`fast::BLOCK`] consecutive segments,
    /// slightly inflated (cut point pruning).
    blocks: Vec<[f64; 4]>,
    /// The same boxes as four arrays (xmin, ymin, xmax, ymax), padded with empty boxes to
    /// whole groups, for testing a group's blocks in lanes.
    block_lanes: [Vec<f64>; 4],
    /// Bounding boxes of every [`fast::GROUP`] consecutive blocks (cut point pruning,
    /// visibility skipping).
    groups: Vec<[f64; 4]>,
}

impl WireSegments {
    /// Segments of the open polyline `points` (mm): segment j runs `points[j]` → `points[j+1]`, so
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
    /// Every segment weight is reset to 1.
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
        let total = cell_geometry::polyline_length(points, cell_geometry::Norm::Sqrt);
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
            &mut self.weight,
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
            self.weight.push(1.0);
            s += l;
        }
        self.total = s;
        self.refresh_fast(points);
        Ok(())
    }

    /// Sets the per-segment weights (module docs): `weights[j]` multiplies segment j's
    /// contribution. [`WireSegments::set`] resets them to 1.
    ///
    /// # Errors
    /// `weights.len()` ≠ M (named `weights`), or a weight that is not finite and ≥ 0 (named
    /// `weights[j]`); `self` is then unchanged.
    pub fn set_weights(&mut self, weights: &[f64]) -> Result<(), ExposureError> {
        if weights.len() != self.len() {
            return Err(ExposureError::InvalidParameter {
                name: "weights".into(),
                value: weights.len() as f64,
                requirement: "one weight per wire segment",
            });
        }
        if let Some(j) = weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(ExposureError::InvalidParameter {
                name: format!("weights[{j}]"),
                value: weights[j],
                requirement: "finite and >= 0",
            });
        }
        self.weight.copy_from_slice(weights);
        self.f32[5].clear();
        self.f32[5].extend(weights.iter().map(|&w| w as f32));
        self.f32[5].resize(weights.len() + 1 + fast::LANES, 0.0);
        Ok(())
    }

    /// The per-segment weights (all 1 unless [`WireSegments::set_weights`] was called).
    pub fn weights(&self) -> &[f64] {
        &self.weight
    }

    /// Refills the fast path's f32 arrays and bounding boxes from the f64 ones.
    fn refresh_fast(&mut self, points: &[Point2<f64>]) {
        let m = self.len();
        let [px, py, wx, wy, len, wt] = &mut self.f32;
        px.clear();
        px.extend(points.iter().map(|p| p.x as f32));
        py.clear();
        py.extend(points.iter().map(|p| p.y as f32));
        for (dst, src) in
            [wx, wy, len, wt]
                .into_iter()
                .zip([&self.wx, &self.wy, &self.len, &self.weight])
        {
            dst.clear();
            dst.extend(src.iter().map(|&x| x as f32));
        }
        // Zero padding: the kernel reads whole vectors past the last segment (and point).
        for v in &mut self.f32 {
            v.resize(m + 1 + fast::LANES, 0.0);
        }
        // Inflated so that a point a + σw computed in floating point stays inside (1e-9 mm is
        // about 10⁴ times the rounding of mm coordinates below 10 m).
        const PAD: f64 = 1e-9;
        self.blocks.clear();
        for b in 0..m.div_ceil(fast::BLOCK) {
            let pts = &points[b * fast::BLOCK..((b + 1) * fast::BLOCK + 1).min(m + 1)];
            let mut bb = [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY];
            for p in pts {
                bb = [
                    bb[0].min(p.x),
                    bb[1].min(p.y),
                    bb[2].max(p.x),
                    bb[3].max(p.y),
                ];
            }
            self.blocks
                .push([bb[0] - PAD, bb[1] - PAD, bb[2] + PAD, bb[3] + PAD]);
        }
        let padded = self.blocks.len().div_ceil(fast::GROUP) * fast::GROUP;
        for (k, v) in self.block_lanes.iter_mut().enumerate() {
            v.clear();
            v.extend(self.blocks.iter().map(|b| b[k]));
            v.resize(padded, if k < 2 { f64::INFINITY } else { -f64::INFINITY });
        }
        self.groups.clear();
        for g in self.blocks.chunks(fast::GROUP) {
            self.groups.push(g.iter().fold(
                [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY],
                |a, b| {
                    [
                        a[0].min(b[0]),
                        a[1].min(b[1]),
                        a[2].max(b[2]),
                        a[3].max(b[3]),
                    ]
                },
            ));
        }
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

    /// [`ExposureModel::exposure`] into a caller's buffer; allocates nothing. O(N·M) at worst;
    /// uses the fast path when the settings allow (module docs), else the reference.
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
        if self.has_fast_path() {
            fast::exposure(self, surface, wire, out);
        } else {
            self.reference_into(surface, wire, out);
        }
        Ok(())
    }

    /// The f64 scalar reference implementation of [`ExposureModel::exposure_into`], whatever
    /// the settings (for tests and benchmarks; the fast path is checked against it).
    ///
    /// # Errors
    /// As [`ExposureModel::exposure_into`].
    pub fn exposure_reference_into(
        &self,
        surface: &Panels,
        wire: &WireSegments,
        out: &mut [f64],
    ) -> Result<(), ExposureError> {
        self.check(surface, wire, out.len())?;
        self.reference_into(surface, wire, out);
        Ok(())
    }

    /// True when [`ExposureModel::exposure_into`] uses the fast path for these settings:
    /// [`Perspective::UnitTangents`] with [`Causal::Off`] or [`Causal::CutPoint`], either law.
    pub fn has_fast_path(&self) -> bool {
        self.perspective == Perspective::UnitTangents
            && matches!(self.causal, Causal::Off | Causal::CutPoint)
    }

    /// The exposure of an arbitrary `point` (mm) with unit `tangent` (its visibility half-plane,
    /// seed 000 eq. 2–3, the outside on the tangent's right) and normalised arc position
    /// `arc_position` (0 … 1, centre of the causal window): the same formula as a panel
    /// (seed 000 eq. 5, module docs), so at a panel's midpoint, tangent and arc position it
    /// gives exactly that panel's value from [`ExposureModel::exposure_into`]. For CSE
    /// calibration at measured points. With [`Perspective::PaperLiteral`] the surface factor
    /// ℓᵢ·N is left out (a point has no panel): a panel's value is ℓᵢ·N times this.
    ///
    /// # Errors
    /// Invalid settings; an empty `wire`; a non-finite point, tangent or arc position, or a
    /// tangent that is not of unit length (within 1e-6).
    pub fn exposure_at(
        &self,
        wire: &WireSegments,
        point: Point2<f64>,
        tangent: Vector2<f64>,
        arc_position: f64,
    ) -> Result<f64, ExposureError> {
        self.validate()?;
        if wire.is_empty() {
            return Err(ExposureError::Degenerate {
                name: "wire",
                reason: "no segments".into(),
            });
        }
        check_finite("point", &[point])?;
        check_finite("tangent", &[Point2::from(tangent)])?;
        if (tangent.norm() - 1.0).abs() > 1e-6 {
            return Err(ExposureError::InvalidParameter {
                name: "tangent".into(),
                value: tangent.norm(),
                requirement: "a unit vector (norm 1)",
            });
        }
        if !arc_position.is_finite() {
            return Err(ExposureError::InvalidParameter {
                name: "arc_position".into(),
                value: arc_position,
                requirement: "finite",
            });
        }
        let site = Site {
            x: point.x,
            y: point.y,
            tx: tangent.x,
            ty: tangent.y,
            u: arc_position,
            surface_factor: 1.0,
        };
        Ok(if self.has_fast_path() {
            fast::exposure_at(self, wire, &site)
        } else {
            let mut sum = 0.0;
            self.reference_site(wire, &site, |_, v| sum += v);
            sum
        })
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
        self.exposure_matrix_of(surface, &WireSegments::from_points(wire)?)
    }

    /// [`ExposureModel::exposure_matrix`] of prepared wire segments (their weights applied).
    /// Uses the reference implementation.
    ///
    /// # Errors
    /// Invalid settings; an empty `wire`.
    pub fn exposure_matrix_of(
        &self,
        surface: &Panels,
        wire: &WireSegments,
    ) -> Result<(usize, usize, Vec<f32>), ExposureError> {
        let (rows, cols) = (wire.len(), surface.len());
        self.check(surface, wire, cols)?;
        let mut values = vec![0.0f32; rows * cols];
        for i in 0..cols {
            self.reference_site(wire, &surface.site(i), |j, v| {
                values[j * cols + i] = v as f32
            });
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

    fn reference_into(&self, surface: &Panels, wire: &WireSegments, out: &mut [f64]) {
        for (i, e) in out.iter_mut().enumerate() {
            let mut sum = 0.0;
            self.reference_site(wire, &surface.site(i), |_, v| sum += v);
            *e = sum;
        }
    }

    /// Calls `emit(j, contribution)` for every wire segment j with a non-zero contribution to
    /// `site` (seed 000 eq. 1–5, module docs). The reference hot loop.
    #[inline]
    fn reference_site(&self, w: &WireSegments, site: &Site, mut emit: impl FnMut(usize, f64)) {
        // Causal cut: arc position (mm along the wire) beyond which nothing counts, and for
        // HalfSegment the segment containing it.
        let (cut_s, cut_j) = match self.causal {
            Causal::Off => (f64::INFINITY, usize::MAX),
            Causal::CutPoint | Causal::HalfSegment => cut_point(w, site.x, site.y, site.u),
        };
        let last = match self.causal {
            Causal::Off => w.len(),
            _ => (cut_j + 1).min(w.len()),
        };
        for j in 0..last {
            let v = self.segment_value(w, site, j, cut_s, cut_j);
            if v != 0.0 {
                emit(j, v);
            }
        }
    }

    /// Wire segment j's contribution to `site` (seed 000 eq. 5 integrated in closed form over
    /// the segment's visible part, eq. 2–3, up to the cut point `cut_s` mm for
    /// [`Causal::CutPoint`]; halved for j = `cut_j` with [`Causal::HalfSegment`]), times the
    /// segment's weight. f64.
    #[inline]
    fn segment_value(
        &self,
        w: &WireSegments,
        site: &Site,
        j: usize,
        cut_s: f64,
        cut_j: usize,
    ) -> f64 {
        let (sx, sy, tx, ty) = (site.x, site.y, site.tx, site.ty);
        let l = w.len[j];
        if l == 0.0 {
            return 0.0;
        }
        let (wx, wy) = (w.wx[j], w.wy[j]);
        let (rx, ry) = (w.ax[j] - sx, w.ay[j] - sy);
        // C(σ) = t × (a − s) + σ · (t × w), linear (seed 000 eq. 2).
        let c0 = tx * ry - ty * rx;
        let c1 = tx * wy - ty * wx;
        let (mut lo, mut hi) = (0.0f64, l);
        if c1 == 0.0 {
            if c0 > 0.0 {
                return 0.0;
            }
        } else {
            let root = -c0 / c1;
            if c1 > 0.0 {
                hi = hi.min(root);
            } else {
                lo = lo.max(root);
            }
        }
        let mut weight = (tx * wx + ty * wy).abs() * w.weight[j];
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
            return 0.0;
        }
        if self.perspective == Perspective::PaperLiteral {
            weight *= site.surface_factor * w.len() as f64 * l;
        }
        // Foot of the perpendicular: x = (a − s)·w + σ, d = |(a − s) × w|.
        let x0 = rx * wx + ry * wy;
        let d = (rx * wy - ry * wx).abs().max(self.min_distance_mm);
        let v = match self.law {
            DistanceLaw::Paper => asinh_difference(x0 + lo, x0 + hi, d),
            DistanceLaw::AuthorCode => atan_difference(x0 + lo, x0 + hi, d),
        };
        weight * v
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
        if let Some((d2, s)) = nearest_in_window(w, j, sx, sy, lo, hi) {
            if d2 < best {
                (best, best_s, best_j) = (d2, s, j);
            }
        }
    }
    (best_s, best_j)
}

/// The point of wire segment `j` inside the arc window [`lo`, `hi`] (mm) nearest to (sx, sy):
/// (squared distance, its arc position in mm), or `None` if the segment lies outside the
/// window.
#[inline(always)]
fn nearest_in_window(
    w: &WireSegments,
    j: usize,
    sx: f64,
    sy: f64,
    lo: f64,
    hi: f64,
) -> Option<(f64, f64)> {
    let (s0, l) = (w.s0[j], w.len[j]);
    let (p, q) = ((lo - s0).max(0.0), (hi - s0).min(l));
    if p > q {
        return None;
    }
    let (rx, ry) = (w.ax[j] - sx, w.ay[j] - sy);
    let x0 = rx * w.wx[j] + ry * w.wy[j];
    let sigma = (-x0).clamp(p, q);
    let (dx, dy) = (rx + sigma * w.wx[j], ry + sigma * w.wy[j]);
    Some((dx * dx + dy * dy, s0 + sigma))
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

mod fast;

#[cfg(test)]
mod tests;
