//! The fast exposure path (module docs of [`super`]): seed 000 eq. 1–5 in closed form per wire
//! segment, as the reference, but f32, branch-free and vectorised, with work skipped where it
//! provably contributes nothing.
//!
//! Per evaluation site (panel midpoint):
//! 1. the causal cut point ([`cut_point_from`]): exact f64, the same answer as the reference's
//!    scan, but only over the window (its ends carried on from the previous panel, binary
//!    search otherwise), starting from the previous panel's cut, and pruned with the wire's
//!    group and block bounding boxes (a group's blocks tested in lanes);
//! 2. the segments before the cut (all of them with [`Causal::Off`]), skipping groups of
//!    [`GROUP`]·[`BLOCK`] segments whose bounding box lies wholly on the inner side of the
//!    site's tangent line (χ = 0, eq. 3), through the f32 lane kernel ([`run_sum`]), which
//!    also skips lane groups that are wholly inside and leaves out the visibility clip where
//!    no lane needs it;
//! 3. the cut segment itself in f64 through the reference's own segment formula (scalar work
//!    that overlaps the vector kernel's: folding it into the f32 lanes was no faster).
//!
//! Where f32 is not enough: a segment that crosses the site's tangent line at a grazing angle
//! close to the site. The crossing (the visibility clip, eq. 3) moves along the segment by the
//! f32 rounding of the coordinates divided by the sine of that angle, and the integrand there is
//! up to 1/d²; a random path grazing a panel midpoint at 0.6° was 2e-3 off. The kernel bounds
//! that error per lane and hands a lane whose bound exceeds [`CLIP_TOLERANCE`] of the lane's
//! own value to the reference's f64 formula instead (rare: it needs a wire within about
//! ε·|coordinates|/[`CLIP_TOLERANCE`] of the site's tangent line, crossing it).
//!
//! Written by hand rather than with a SIMD crate's math functions: the kernel is plain f32
//! arithmetic on fixed-length lane arrays that LLVM vectorises for whichever instruction set
//! `multiversion` compiled the clone for; `ln` and `atan2` are small polynomial approximations
//! here ([`ln`], [`atan2_over`]) because the standard library's are scalar calls that stop the
//! vectoriser. Clones for CPUs with FMA use fused multiply-adds (`FMA` = true: half the
//! latency in the polynomials), the others plain multiply and add (`mul_add` would be a slow
//! library call there), so results are bit-identical run to run on one machine, and may
//! differ in the last bits between machines with and without FMA.

use multiversion::multiversion;
use multiversion::target::selected_target;

use super::{Causal, DistanceLaw, ExposureModel, Panels, Site, WireSegments, CAUSAL_WINDOW};

/// Wire segments per bounding-box block.
pub(super) const BLOCK: usize = 8;
/// Blocks per bounding-box group.
pub(super) const GROUP: usize = 8;
/// Largest relative error of a lane's value allowed from the f32 visibility clip (module docs);
/// lanes above it are computed in f64.
const CLIP_TOLERANCE: f32 = 1e-5;

/// f32 lanes of the summation (fixed, whatever the vector width, so that every clone adds in
/// the same order).
pub(super) const LANES: usize = 16;

/// A site's constants in f32.
#[derive(Debug, Clone, Copy)]
struct Site32 {
    x: f32,
    y: f32,
    tx: f32,
    ty: f32,
    dmin: f32,
}

/// Fast [`ExposureModel::exposure_into`]: `model` has a fast path, inputs are checked.
#[multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "x86_64+sse4.2",
    "aarch64+neon"
))]
pub(super) fn exposure(
    model: &ExposureModel,
    surface: &Panels,
    wire: &WireSegments,
    out: &mut [f64],
) {
    if selected_target!().supports_feature_str("fma") {
        exposure_with::<true>(model, surface, wire, out)
    } else {
        exposure_with::<false>(model, surface, wire, out)
    }
}

#[inline(always)]
fn exposure_with<const FMA: bool>(
    model: &ExposureModel,
    surface: &Panels,
    wire: &WireSegments,
    out: &mut [f64],
) {
    let [sx, sy, tx, ty] = &surface.f32;
    let dmin = model.min_distance_mm as f32;
    let mut cursor = Cursor::default();
    for (i, e) in out.iter_mut().enumerate() {
        let s32 = Site32 {
            x: sx[i],
            y: sy[i],
            tx: tx[i],
            ty: ty[i],
            dmin,
        };
        *e = site_value::<FMA>(model, wire, &surface.site(i), &s32, &mut cursor);
    }
}

/// Fast [`ExposureModel::exposure_at`].
#[multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "x86_64+sse4.2",
    "aarch64+neon"
))]
pub(super) fn exposure_at(model: &ExposureModel, wire: &WireSegments, site: &Site) -> f64 {
    // The same f64 → f32 conversions as `Panels::from_points`, so a panel's own midpoint gives
    // its value bit for bit.
    let s32 = Site32 {
        x: site.x as f32,
        y: site.y as f32,
        tx: site.tx as f32,
        ty: site.ty as f32,
        dmin: model.min_distance_mm as f32,
    };
    if selected_target!().supports_feature_str("fma") {
        site_value::<true>(model, wire, site, &s32, &mut Cursor::default())
    } else {
        site_value::<false>(model, wire, site, &s32, &mut Cursor::default())
    }
}

/// Exposure of one site (steps 1–3 of the module docs).
#[inline(always)]
fn site_value<const FMA: bool>(
    model: &ExposureModel,
    w: &WireSegments,
    site: &Site,
    s32: &Site32,
    cursor: &mut Cursor,
) -> f64 {
    let m = w.len();
    let (end, cut) = match model.causal {
        Causal::CutPoint => {
            let (cut_s, cut_j) = cut_point_from(w, site.x, site.y, site.u, cursor);
            (cut_j, Some((cut_s, cut_j)))
        }
        _ => (m, None),
    };
    let mut total = 0.0f64;
    // Runs of groups not wholly on the inner side of the tangent line (testing single blocks
    // too cost more than it saved). No closure here: a closure would not inherit the clone's
    // target features.
    let nblocks = end.div_ceil(BLOCK);
    let mut run: Option<usize> = None;
    for g in 0..nblocks.div_ceil(GROUP) {
        if inner_side(&w.groups[g], site) {
            total += flush::<FMA>(model, w, site, &mut run, g * GROUP * BLOCK, end, s32);
            continue;
        }
        if run.is_none() {
            run = Some(g * GROUP * BLOCK);
        }
    }
    total += flush::<FMA>(model, w, site, &mut run, end, end, s32);
    if let Some((cut_s, cut_j)) = cut {
        total += model.segment_value(w, site, cut_j, cut_s, cut_j);
    }
    total
}

/// Ends the open run (if any) at `stop` (≤ `end`) and returns its sum.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn flush<const FMA: bool>(
    model: &ExposureModel,
    w: &WireSegments,
    site: &Site,
    run: &mut Option<usize>,
    stop: usize,
    end: usize,
    s32: &Site32,
) -> f64 {
    match run.take() {
        Some(start) if stop.min(end) > start => {
            run_sum::<FMA>(model, w, site, start, stop.min(end), s32)
        }
        _ => 0.0,
    }
}

/// True when the box lies wholly where C = t × (p − s) > 0 (seed 000 eq. 2–3: χ = 0), so no
/// segment inside it heats the site. C is linear, so its minimum over the box is at a corner.
#[inline(always)]
fn inner_side(bb: &[f64; 4], s: &Site) -> bool {
    let y = if s.tx >= 0.0 { bb[1] } else { bb[3] };
    let x = if s.ty >= 0.0 { bb[2] } else { bb[0] };
    s.tx * (y - s.y) - s.ty * (x - s.x) > 0.0
}

/// Σ over segments `j0..j1` of their f32 contributions to the site, ignoring the causal cut
/// (the caller stops before the cut segment). Works in blocks of [`LANES`] segments, each a
/// fixed-length loop LLVM turns into whole vectors (no scalar remainder): the f32 arrays are
/// padded with [`LANES`] zero-length segments, and lanes past `j1` get length 0, which makes
/// them contribute 0. Lanes whose f32 clip is too inexact ([`pair`]) are added in f64 by the
/// reference's formula.
#[inline(always)]
fn run_sum<const FMA: bool>(
    model: &ExposureModel,
    w: &WireSegments,
    site: &Site,
    j0: usize,
    j1: usize,
    s: &Site32,
) -> f64 {
    let author = model.law == DistanceLaw::AuthorCode;
    let [px, py, wx, wy, len, wt] = &w.f32;
    let mut acc = [0.0f32; LANES];
    let mut exact = 0.0f64;
    let mut j = j0;
    while j < j1 {
        let live = j1 - j;
        let lanes = |v: &[f32], j: usize| -> [f32; LANES] { v[j..j + LANES].try_into().unwrap() };
        let (ax, ay, bx, by) = (
            lanes(px, j),
            lanes(py, j),
            lanes(px, j + 1),
            lanes(py, j + 1),
        );
        let (wx, wy, wt) = (lanes(wx, j), lanes(wy, j), lanes(wt, j));
        let mut l = lanes(len, j);
        for (k, l) in l.iter_mut().enumerate() {
            if k >= live {
                *l = 0.0;
            }
        }
        // Does any lane cross the tangent line or lie inside it (C > 0 at an end, eq. 2–3)?
        // Usually not: then the kernel without the visibility clip does.
        // And are all of them inside (or padding)? Then they contribute nothing.
        let (mut clipped, mut inner) = (false, true);
        for k in 0..LANES {
            let ca = s.tx * (ay[k] - s.y) - s.ty * (ax[k] - s.x);
            let cb = s.tx * (by[k] - s.y) - s.ty * (bx[k] - s.x);
            clipped |= (ca > 0.0) | (cb > 0.0);
            inner &= ((ca > 0.0) & (cb > 0.0)) | (l[k] == 0.0);
        }
        if inner {
            j += LANES;
            continue;
        }
        let mut redo = [false; LANES];
        macro_rules! lanes_of {
            ($author:literal, $clip:literal) => {
                for k in 0..LANES {
                    let (v, r) = pair::<$author, $clip, FMA>(
                        ax[k], ay[k], bx[k], by[k], wx[k], wy[k], l[k], wt[k], s,
                    );
                    acc[k] += v;
                    redo[k] = r;
                }
            };
        }
        match (author, clipped) {
            (true, true) => lanes_of!(true, true),
            (true, false) => lanes_of!(true, false),
            (false, true) => lanes_of!(false, true),
            (false, false) => lanes_of!(false, false),
        }
        if redo.iter().any(|&r| r) {
            for (k, _) in redo.iter().enumerate().filter(|(_, &r)| r) {
                // Before the cut segment: the cut does not clip it.
                exact += model.segment_value(w, site, j + k, f64::INFINITY, usize::MAX);
            }
        }
        j += LANES;
    }
    // Pairwise, fixed order.
    let mut width = LANES;
    while width > 1 {
        width /= 2;
        for k in 0..width {
            acc[k] += acc[k + width];
        }
    }
    f64::from(acc[0]) + exact
}

/// One wire segment's contribution to the site without the causal cut (seed 000 eq. 1–5 in
/// closed form, module docs of [`super`]), f32, branch-free. The segment runs from a to b with
/// unit direction w and length l (0 for padding and masked lanes): visibility clips the segment to
/// σ ∈ [lo, hi] where C(σ) ≤ 0 (eq. 2–3); P = |t · w| (eq. 4, unit tangents) times the
/// segment weight; then ∫ dσ/‖R‖ = ln(g(x₁)/g(x₀)) (`AUTHOR` = false, eq. 5 as printed) or
/// ∫ dσ/‖R‖² = atan2(d(x₁ − x₀), d² + x₀x₁)/d (`AUTHOR`, the author's code).
///
/// Returns (value, redo): with `CLIP`, redo is set (and the value 0) when the f32 clip's error
/// bound exceeds [`CLIP_TOLERANCE`] of the value: the coordinates' rounding, about
/// ε·(|a| + |b| + 2|s|) in C, moves the root by l/|C(b) − C(a)| times that, and the integral by
/// that times the integrand at the root, 1/r² or 1/r with r² = x_root² + d².
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pair<const AUTHOR: bool, const CLIP: bool, const FMA: bool>(
    ax: f32,
    ay: f32,
    bx: f32,
    by: f32,
    wx: f32,
    wy: f32,
    l: f32,
    wt: f32,
    s: &Site32,
) -> (f32, bool) {
    let (rx, ry) = (ax - s.x, ay - s.y);
    // C at the segment's start a and end b (eq. 2), linear in between; from the points
    // themselves, so a segment that starts or ends exactly on the tangent line (a wire vertex
    // at the site, say) clips exactly there.
    // Without `CLIP` the caller knows C ≤ 0 at both ends: all of it is visible.
    let (ca, cb) = if CLIP {
        (s.tx * ry - s.ty * rx, s.tx * (by - s.y) - s.ty * (bx - s.x))
    } else {
        (0.0, 0.0)
    };
    let den = ca - cb;
    let (lo, hi) = if CLIP {
        let root = l * (ca / if den == 0.0 { 1.0 } else { den });
        (
            if ca > 0.0 { root } else { 0.0 },
            if cb > 0.0 { root } else { l },
        )
    } else {
        (0.0, l)
    };
    // Both ends inside: lo = hi = root. Zero length: lo = hi.
    let visible = hi > lo;
    let weight = (s.tx * wx + s.ty * wy).abs() * wt;
    let x0 = rx * wx + ry * wy;
    let d = (rx * wy - ry * wx).abs().max(s.dmin);
    let d2 = d * d;
    let (xl, xh) = (x0 + lo, x0 + hi);
    // r² at the clipped end (the root), for the error bound.
    let xr = if ca > 0.0 { xl } else { xh };
    let rr = fma::<FMA>(xr, xr, d2);
    let v = if AUTHOR {
        atan2_over::<FMA>(d * (hi - lo), fma::<FMA>(xl, xh, d2), d)
    } else {
        // g(x) = x + √(x² + d²) = n/q, as d²/(√(x² + d²) − x) for x < 0 (no cancellation).
        let (rl, rh) = (fma::<FMA>(xl, xl, d2).sqrt(), fma::<FMA>(xh, xh, d2).sqrt());
        let (nl, ql) = if xl >= 0.0 {
            (xl + rl, 1.0)
        } else {
            (d2, rl - xl)
        };
        let (nh, qh) = if xh >= 0.0 {
            (xh + rh, 1.0)
        } else {
            (d2, rh - xh)
        };
        ln::<FMA>(((nh * ql) / (qh * nl)).max(1.0))
    };
    let redo = CLIP && visible && ((ca > 0.0) != (cb > 0.0)) && {
        let eps = f32::EPSILON
            * (ax.abs() + ay.abs() + bx.abs() + by.abs() + 2.0 * (s.x.abs() + s.y.abs()));
        // l·eps/|den| · (1/r² or 1/r) > tolerance · v, without divisions.
        let scale = if AUTHOR { rr } else { rr.sqrt() };
        l * eps > CLIP_TOLERANCE * v * den.abs() * scale
    };
    if visible && !redo {
        (weight * v, false)
    } else {
        (0.0, redo)
    }
}

/// Natural logarithm for finite x ≥ 1 (the ratio g(x₁)/g(x₀) ≥ 1), branch-free: x = 2ᵉ·m with
/// m ∈ [√½, √2), ln x = e·ln 2 + ln m, ln m by the Cephes `logf` polynomial in m − 1.
/// Max relative error 8e-8 over [1, 1e30], with or without FMA (test `ln_and_atan2_accuracy`).
#[inline(always)]
pub(super) fn ln<const FMA: bool>(x: f32) -> f32 {
    let bits = x.to_bits();
    // Exponent for m ∈ [0.5, 1), then shift m into [√½, √2).
    let e = ((bits >> 23) & 0xff) as i32 - 126;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
    let small = m < std::f32::consts::FRAC_1_SQRT_2;
    let e = (if small { e - 1 } else { e }) as f32;
    let f = if small { m + m - 1.0 } else { m - 1.0 };
    let z = f * f;
    let mut p = 7.037_683_6e-2f32;
    for c in [
        -1.151_461e-1,
        1.167_699_9e-1,
        -1.242_014_1e-1,
        1.424_932_3e-1,
        -1.666_805_8e-1,
        2.000_071_4e-1,
        -2.499_999_4e-1,
        3.333_333e-1,
    ] {
        p = fma::<FMA>(p, f, c);
    }
    let y = fma::<FMA>(p * f, z, fma::<FMA>(-2.121_944_4e-4, e, -0.5 * z));
    fma::<FMA>(0.693_359_4, e, f + y)
}

/// atan a for a ∈ [0, 1] (SLEEF `atanf` polynomial).
#[inline(always)]
fn atan_unit<const FMA: bool>(a: f32) -> f32 {
    let t = a * a;
    let mut u = 2.823_639e-3f32;
    for c in [
        -1.595_690_3e-2,
        4.250_499e-2,
        -7.489_009e-2,
        1.063_479_3e-1,
        -1.420_273_6e-1,
        1.999_269_6e-1,
        -3.333_310_2e-1,
    ] {
        u = fma::<FMA>(u, t, c);
    }
    fma::<FMA>(a, t * u, a)
}

/// atan2(y, x)/d for y ≥ 0 (the angle lies in [0, π]) and d > 0, branch-free, with a single
/// division: atan of min(|x|, y)/max(|x|, y) ∈ [0, 1] ([`atan_unit`]), then reflected; with
/// q = 1/(max(|x|, y)·d), min/max = min·q·d and 1/d = max·q. Max absolute error of the angle
/// 4.3e-7 rad, max relative error of the result 2.8e-7 (test `ln_and_atan2_accuracy`); 0 for
/// y = x = 0.
#[inline(always)]
pub(super) fn atan2_over<const FMA: bool>(y: f32, x: f32, d: f32) -> f32 {
    let ax = x.abs();
    let (lo, hi) = (ax.min(y), ax.max(y));
    let q = 1.0 / (if hi > 0.0 { hi } else { 1.0 } * d);
    let r = atan_unit::<FMA>(lo * (q * d));
    let r = if y > ax {
        std::f32::consts::FRAC_PI_2 - r
    } else {
        r
    };
    let r = if x < 0.0 { std::f32::consts::PI - r } else { r };
    r * (hi * q)
}

/// a·b + c, fused (one rounding) when `FMA`.
#[inline(always)]
fn fma<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// The causal cut point (as the reference `super::cut_point`, bit for bit): the nearest wire
/// point to (sx, sy) within ±[`CAUSAL_WINDOW`] of normalised wire arc length around `u`, as its
/// arc position in mm and segment; ties keep the earlier segment.
#[cfg(test)]
pub(super) fn cut_point(w: &WireSegments, sx: f64, sy: f64, u: f64) -> (f64, usize) {
    cut_point_from(w, sx, sy, u, &mut Cursor::default())
}

/// Search state carried from one panel to the next (they come in order of arc position, so
/// the window and the cut point move forward a little each time).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Cursor {
    /// The previous panel's cut segment.
    pub(super) cut: Option<usize>,
    /// The previous window's first segment and end (0 before the first panel).
    pub(super) j0: usize,
    pub(super) j1: usize,
}

/// [`cut_point`], carrying `cursor` on: finds the window's segments by moving the previous
/// window's ends forward (binary search if they would have to move back), scans the block
/// holding the previous cut segment if it lies in the window (else the one at arc position
/// u), then visits only groups and blocks whose bounding box could hold a nearer point.
/// Whole blocks are scanned in f64 lanes.
#[inline(always)]
pub(super) fn cut_point_from(
    w: &WireSegments,
    sx: f64,
    sy: f64,
    u: f64,
    cursor: &mut Cursor,
) -> (f64, usize) {
    let lo = (u - CAUSAL_WINDOW).max(0.0) * w.total;
    let hi = (u + CAUSAL_WINDOW).min(1.0) * w.total;
    let m = w.len();
    // A superset of the segments the reference accepts (p ≤ q below): slack for rounding.
    let slack = 1e-9 * w.total;
    let j0 = advance(m, |j| w.s0[j] + w.len[j] < lo - slack, cursor.j0);
    let j1 = advance(m, |j| w.s0[j] <= hi + slack, cursor.j1);
    (cursor.j0, cursor.j1) = (j0, j1);
    if j0 >= j1 {
        return (lo, 0);
    }
    let hint = cursor.cut;
    let win = Window {
        lo,
        hi,
        j0,
        j1,
        sx,
        sy,
    };
    let mut best = (f64::INFINITY, lo, 0usize);
    let box_d2 = |bb: &[f64; 4]| {
        let dx = (bb[0] - sx).max(sx - bb[2]).max(0.0);
        let dy = (bb[1] - sy).max(sy - bb[3]).max(0.0);
        dx * dx + dy * dy
    };
    let guess = match hint {
        Some(j) if (j0..j1).contains(&j) => j,
        _ => (partition(m, |j| w.s0[j] <= u * w.total).saturating_sub(1)).clamp(j0, j1 - 1),
    };
    let first = guess / BLOCK;
    scan_block(w, first, &win, &mut best);
    let (b0, b1) = (j0 / BLOCK, (j1 - 1) / BLOCK + 1);
    for g in b0 / GROUP..(b1 - 1) / GROUP + 1 {
        if box_d2(&w.groups[g]) > best.0 {
            continue;
        }
        // The group's blocks' boxes in lanes, then a scan of each that could hold a nearer
        // point (padding boxes are empty: infinitely far).
        let [x0, y0, x1, y1] = &w.block_lanes;
        let at = g * GROUP;
        let lanes = |v: &[f64]| -> [f64; GROUP] { v[at..at + GROUP].try_into().unwrap() };
        let (x0, y0, x1, y1) = (lanes(x0), lanes(y0), lanes(x1), lanes(y1));
        let mut near = [false; GROUP];
        for k in 0..GROUP {
            let dx = (x0[k] - sx).max(sx - x1[k]).max(0.0);
            let dy = (y0[k] - sy).max(sy - y1[k]).max(0.0);
            near[k] = dx * dx + dy * dy <= best.0;
        }
        for (k, &near) in near.iter().enumerate() {
            let b = at + k;
            if near && b != first && (b0..b1).contains(&b) {
                scan_block(w, b, &win, &mut best);
            }
        }
    }
    cursor.cut = Some(best.2);
    (best.1, best.2)
}

/// [`partition`] when it is known to be at least `from` (`pred(from − 1)` holds): steps forward
/// from there; otherwise a binary search.
#[inline(always)]
fn advance(n: usize, pred: impl Fn(usize) -> bool, from: usize) -> usize {
    if from > n || (from > 0 && !pred(from - 1)) {
        return partition(n, pred);
    }
    let mut j = from;
    while j < n && pred(j) {
        j += 1;
    }
    j
}

/// The causal window of one cut point search: arc positions `lo..=hi` (mm), segments
/// `j0..j1` that may touch it, and the site.
struct Window {
    lo: f64,
    hi: f64,
    j0: usize,
    j1: usize,
    sx: f64,
    sy: f64,
}

/// Offers every segment of block `b` in the window to `best` = (d², arc position, segment):
/// the reference's per-segment formula, in [`BLOCK`] f64 lanes for a whole block.
#[inline(always)]
fn scan_block(w: &WireSegments, b: usize, win: &Window, best: &mut (f64, f64, usize)) {
    let start = b * BLOCK;
    let (lo, hi, sx, sy) = (win.lo, win.hi, win.sx, win.sy);
    if start >= win.j0 && start + BLOCK <= win.j1 {
        let lanes = |v: &[f64]| -> [f64; BLOCK] { v[start..start + BLOCK].try_into().unwrap() };
        let (ax, ay, wx, wy) = (lanes(&w.ax), lanes(&w.ay), lanes(&w.wx), lanes(&w.wy));
        let (len, s0) = (lanes(&w.len), lanes(&w.s0));
        let (mut d2, mut at) = ([0.0; BLOCK], [0.0; BLOCK]);
        for k in 0..BLOCK {
            let (p, q) = ((lo - s0[k]).max(0.0), (hi - s0[k]).min(len[k]));
            let (rx, ry) = (ax[k] - sx, ay[k] - sy);
            let x0 = rx * wx[k] + ry * wy[k];
            // = clamp(−x0, p, q) where p ≤ q; lanes with p > q are out of the window.
            let sigma = (-x0).max(p).min(q);
            let (dx, dy) = (rx + sigma * wx[k], ry + sigma * wy[k]);
            d2[k] = if p > q {
                f64::INFINITY
            } else {
                dx * dx + dy * dy
            };
            at[k] = s0[k] + sigma;
        }
        // Most blocks scanned hold no nearer point: one lane-wise minimum decides.
        let mut min = d2;
        let mut width = BLOCK;
        while width > 1 {
            width /= 2;
            for k in 0..width {
                min[k] = min[k].min(min[k + width]);
            }
        }
        if min[0] > best.0 {
            return;
        }
        for k in 0..BLOCK {
            offer(best, d2[k], at[k], start + k);
        }
    } else {
        for j in start.max(win.j0)..(start + BLOCK).min(win.j1) {
            if let Some((d2, s)) = super::nearest_in_window(w, j, sx, sy, lo, hi) {
                offer(best, d2, s, j);
            }
        }
    }
}

/// Takes (d², arc position, segment) as the best if nearer, or as near and earlier.
#[inline(always)]
fn offer(best: &mut (f64, f64, usize), d2: f64, s: f64, j: usize) {
    if d2 < best.0 || (d2 == best.0 && j < best.2) {
        *best = (d2, s, j);
    }
}

/// The first index in 0..n where `pred` turns false (`pred` true on a prefix).
#[inline(always)]
fn partition(n: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}
