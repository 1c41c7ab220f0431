//! Per-layer WAAM toolpaths that cover the layer's part region grown by the machining allowance
//! ([`cover`], issue 20): perimeters (the grown region inset by half the bead width, convex
//! corners pushed out), zig-zag infill at an angle that alternates per layer, thin walls as one
//! bead along the medial axis and pins as a circle per layer ([`thin`]), what is still left
//! filled or reported ([`LayerToolpath::uncovered`]); the thesis's width-driven mid-wall mode,
//! weld starts spread between layers, and interlayer dwell.
//!
//! Every per-point value (speed, width, height, wire feed, arc) holds for the piece from that
//! point to the next, like the rows of seed 004 eq. 7; a segment's last point repeats the values
//! of the one before.

pub mod cover;
pub mod geom;
pub mod infill;
pub mod region;
pub mod thin;
pub mod wall;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::bead;
use crate::cost::{ToolpathTotals, TravelTime};
use crate::process::{WaamProcess, WidthMode};
use cell_geometry::{closed_from_arc_length, point_in_ring_even_odd, signed_area};
use geom::{dist, P2};

/// One slice of the part: closed polygons at height `z_mm`. Plain data so a slicer's output maps
/// onto it directly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerPolygons {
    /// Layer number from the bottom (0-based); drives the infill angle and the start shift.
    pub index: usize,
    /// Height of the toolpath (mm).
    pub z_mm: f64,
    /// Closed, simple rings (mm): outer contours counter-clockwise, holes clockwise, no repeated
    /// last point. The planner re-derives the orientation from nesting (even depth = outer),
    /// so a reversed ring is repaired, not misread.
    pub outers_and_holes: Vec<Vec<[f64; 2]>>,
}

/// Errors of the toolpath planner.
#[derive(Debug, Error)]
pub enum ToolpathError {
    /// A ring of a layer is unusable.
    #[error("layer {layer}: ring {ring}: {message}")]
    BadRing {
        /// Layer index.
        layer: usize,
        /// Ring index within the layer.
        ring: usize,
        /// What is wrong.
        message: String,
    },
    /// The layer's height is not finite.
    #[error("layer {layer}: z_mm = {z_mm} is not finite")]
    BadZ {
        /// Layer index.
        layer: usize,
        /// The value.
        z_mm: f64,
    },
    /// The process profile is invalid.
    #[error(transparent)]
    Process(#[from] crate::process::ProcessError),
    /// A bead-model value out of range (e.g. a wall-driven width outside eq. 14's support).
    #[error(transparent)]
    Bead(#[from] bead::BeadError),
}

/// Whether a segment deposits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SegmentKind {
    /// Arc on, wire feeding.
    Deposit,
    /// Arc off, non-depositing move.
    Travel,
}

/// What a segment is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SegmentRole {
    /// A closed perimeter loop (fixed mode).
    Perimeter,
    /// Zig-zag infill.
    Infill,
    /// A width-driven mid-wall loop (seed 004 B4).
    WallBead,
    /// A travel move.
    Travel,
}

/// One toolpath point; its values hold for the piece to the next point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PathPoint {
    /// X (mm).
    pub x_mm: f64,
    /// Y (mm).
    pub y_mm: f64,
    /// Z (mm).
    pub z_mm: f64,
    /// TCP speed (mm/s): TS when depositing, the travel speed otherwise.
    pub speed_mm_s: f64,
    /// Bead width LW (mm); 0 when not depositing.
    pub bead_width_mm: f64,
    /// Bead height h (mm, eq. 28); 0 when not depositing.
    pub bead_height_mm: f64,
    /// Wire feed speed (m/min); 0 when not depositing.
    pub wire_feed_m_min: f64,
    /// Arc on.
    pub arc_on: bool,
}

/// An ordered run of points of one kind.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Deposit or travel.
    pub kind: SegmentKind,
    /// Perimeter, infill, wall bead or travel.
    pub role: SegmentRole,
    /// At least two points.
    pub points: Vec<PathPoint>,
}

impl Segment {
    /// Path length (mm, 3D).
    pub fn length_mm(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| piece_len(&w[0], &w[1]))
            .sum()
    }

    /// Deposited volume Σ w·h·L over the pieces (mm³); 0 for travel (seed 004 eq. 25).
    pub fn volume_mm3(&self) -> f64 {
        self.points
            .windows(2)
            .filter(|w| w[0].arc_on)
            .map(|w| w[0].bead_width_mm * w[0].bead_height_mm * piece_len(&w[0], &w[1]))
            .sum()
    }

    /// Time to run the segment, Σ L_i / speed_i (s) (seed 004 eq. 18 for deposits).
    pub fn time_s(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| piece_len(&w[0], &w[1]) / w[0].speed_mm_s)
            .sum()
    }
}

fn piece_len(a: &PathPoint, b: &PathPoint) -> f64 {
    ((b.x_mm - a.x_mm).powi(2) + (b.y_mm - a.y_mm).powi(2) + (b.z_mm - a.z_mm).powi(2)).sqrt()
}

/// The toolpath of one layer with its totals.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerToolpath {
    /// Layer index.
    pub index: usize,
    /// Height (mm).
    pub z_mm: f64,
    /// Infill angle used on this layer (degrees from +X).
    pub infill_angle_deg: f64,
    /// Ordered segments.
    pub segments: Vec<Segment>,
    /// Deposited volume Σ w·h·L (mm³).
    pub deposited_volume_mm3: f64,
    /// Arc-on time t_D (s).
    pub deposition_time_s: f64,
    /// Travel time (s): travel moves at the travel speed plus `arc_start_stop_s` per deposit
    /// segment.
    pub travel_time_s: f64,
    /// Interlayer dwell after the layer (s).
    pub dwell_time_s: f64,
    /// Number of arc starts (deposit segments).
    pub arc_starts: usize,
    /// Pieces of the part region grown by the allowance that no bead covers (empty when the
    /// layer is covered; rim slivers thinner than 0.1 mm are not counted).
    #[serde(default)]
    pub uncovered: Vec<UncoveredRegion>,
}

/// A piece of a layer's target region (the part grown by the allowance) no bead covers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UncoveredRegion {
    /// Bounding box minimum (mm).
    pub bbox_min_mm: [f64; 2],
    /// Bounding box maximum (mm).
    pub bbox_max_mm: [f64; 2],
    /// Area (mm²).
    pub area_mm2: f64,
}

impl LayerToolpath {
    /// XY start of the first deposit segment, if any.
    pub fn first_weld_start(&self) -> Option<[f64; 2]> {
        self.segments
            .iter()
            .find(|s| s.kind == SegmentKind::Deposit)
            .map(|s| [s.points[0].x_mm, s.points[0].y_mm])
    }

    /// XY starts of every deposit segment.
    pub fn weld_starts(&self) -> Vec<[f64; 2]> {
        self.segments
            .iter()
            .filter(|s| s.kind == SegmentKind::Deposit)
            .map(|s| [s.points[0].x_mm, s.points[0].y_mm])
            .collect()
    }
}

/// What the cost model needs from a stack of layers (seed 004 eq. 16–18): V_d in m³, t_D, the
/// dwell as t_wait, and the travel time in seconds.
pub fn toolpath_totals(layers: &[LayerToolpath]) -> ToolpathTotals {
    ToolpathTotals {
        deposited_m3: layers.iter().map(|l| l.deposited_volume_mm3).sum::<f64>() * 1e-9,
        deposition_s: layers.iter().map(|l| l.deposition_time_s).sum(),
        wait_s: layers.iter().map(|l| l.dwell_time_s).sum(),
        travel: TravelTime::Seconds(layers.iter().map(|l| l.travel_time_s).sum()),
    }
}

fn check_layer(layer: &LayerPolygons) -> Result<(), ToolpathError> {
    if !layer.z_mm.is_finite() {
        return Err(ToolpathError::BadZ {
            layer: layer.index,
            z_mm: layer.z_mm,
        });
    }
    for (i, r) in layer.outers_and_holes.iter().enumerate() {
        let bad = |message: String| ToolpathError::BadRing {
            layer: layer.index,
            ring: i,
            message,
        };
        if r.len() < 3 {
            return Err(bad(format!("{} points, need at least 3", r.len())));
        }
        if let Some(j) = r
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(bad(format!("point {j} is not finite")));
        }
        if signed_area(r).abs() < 1e-12 {
            return Err(bad("zero area".into()));
        }
    }
    Ok(())
}

/// The rings oriented by nesting: a ring inside an even number of other rings is an outer
/// contour (made CCW), inside an odd number a hole (made CW). The input convention (outer CCW,
/// holes CW) is thereby checked and repaired instead of trusted: a reversed outer would
/// otherwise be offset outwards.
fn oriented_rings(rings: &[Vec<P2>]) -> Vec<Vec<P2>> {
    rings
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let depth = rings
                .iter()
                .enumerate()
                .filter(|&(j, o)| j != i && point_in_ring_even_odd(r[0], o))
                .count();
            let want_ccw = depth % 2 == 0;
            let mut r = r.clone();
            if (signed_area(&r) > 0.0) != want_ccw {
                r.reverse();
            }
            r
        })
        .collect()
}

/// A deposit polyline with per-point (width, speed) before it becomes a [`Segment`].
struct Bead {
    role: SegmentRole,
    pts: Vec<P2>,
    width_speed: Vec<(f64, f64)>,
}

/// Plans one layer. `from` is where the torch is before the layer (the previous layer's end),
/// from which a travel move leads to the first weld start; `None` starts at the first bead.
///
/// The rings are the part's region on this layer (net shape); the beads cover it grown by
/// `process.machining_allowance_mm` (module [`cover`]). Pieces left uncovered (only possible
/// with infill or perimeters off) are listed in [`LayerToolpath::uncovered`].
///
/// # Errors
/// An invalid profile, a degenerate ring (fewer than 3 points, non-finite, zero area), a
/// non-finite `z_mm`.
pub fn plan_layer(
    layer: &LayerPolygons,
    process: &WaamProcess,
    from: Option<[f64; 3]>,
) -> Result<LayerToolpath, ToolpathError> {
    process.check("process")?;
    check_layer(layer)?;
    let rings = &oriented_rings(&layer.outers_and_holes);
    let shift = process.start_shift_mm * layer.index as f64;
    let angle = process.infill_angle_deg + process.infill_layer_rotation_deg * layer.index as f64;
    let tol = process.arc_tolerance_mm;
    let wfs = process.wire_feed_m_min;
    let from_xy = from.map(|p| [p[0], p[1]]);
    let (planned, uncovered) = match process.width_mode {
        WidthMode::Fixed => {
            let c = cover::cover_layer(rings, process);
            let perimeters = c
                .perimeters
                .into_iter()
                .map(|mut b| {
                    b.pts = closed_from_arc_length(&b.pts[..b.pts.len() - 1], shift, geom::NORM);
                    b.widths = vec![b.widths[0]; b.pts.len()];
                    b
                })
                .collect();
            let (mut planned, mut pos) = cover::nearest_first(perimeters, from_xy);
            if process.infill {
                let w = process.fixed_width_mm();
                let spacing = process.infill_spacing_ratio * w;
                for pts in infill::zigzag(
                    &c.infill_region,
                    angle,
                    spacing,
                    process.infill_link_max_ratio * spacing,
                    pos,
                ) {
                    pos = pts.last().copied();
                    planned.push(cover::PlannedBead {
                        role: SegmentRole::Infill,
                        widths: vec![w; pts.len()],
                        pts,
                        closed: false,
                    });
                }
            }
            let mut thin = c.thin;
            let (added, left) = cover::fill_residual(
                &c.target,
                &c.part,
                &planned.iter().chain(&thin).cloned().collect::<Vec<_>>(),
                process,
            );
            thin.extend(added);
            let (thin, _) = cover::nearest_first(thin, pos);
            planned.extend(thin);
            (planned, left)
        }
        WidthMode::WallDriven => {
            let limits = process.width_limits_mm();
            let part = region::union(rings);
            let target = region::grow(&part, process.machining_allowance_mm, tol);
            let target_rings: Vec<Vec<P2>> = target.iter().flatten().cloned().collect();
            let mut planned = Vec::new();
            for samples in wall::mid_wall_loops(&target_rings, limits, process.wall_sample_mm, tol)
            {
                let samples = rotate_samples(&samples, shift);
                let pts: Vec<P2> = samples
                    .iter()
                    .chain(samples.first())
                    .map(|s| s.xy)
                    .collect();
                let widths = samples
                    .iter()
                    .chain(samples.first())
                    .map(|s| s.width_mm)
                    .collect();
                planned.push(cover::PlannedBead {
                    role: SegmentRole::WallBead,
                    pts,
                    widths,
                    closed: true,
                });
            }
            let (added, left) = cover::fill_residual(&target, &part, &planned, process);
            let (added, _) =
                cover::nearest_first(added, planned.last().and_then(|b| b.pts.last().copied()));
            planned.extend(added);
            (planned, left)
        }
    };
    let fixed_w = process.fixed_width_mm();
    let mut beads: Vec<Bead> = Vec::with_capacity(planned.len());
    for b in planned {
        let width_speed = b
            .widths
            .iter()
            .map(|&w| {
                if (w - fixed_w).abs() < 1e-12 {
                    Ok((w, process.travel_speed_mm_s))
                } else {
                    bead::travel_speed_for_width_mm_s(w, wfs).map(|ts| (w, ts))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        beads.push(Bead {
            role: b.role,
            pts: b.pts,
            width_speed,
        });
    }
    let mut tp = assemble(layer, process, angle, beads, from);
    tp.uncovered = uncovered
        .iter()
        .map(|s| {
            let (lo, hi) = region::shape_bbox(s);
            UncoveredRegion {
                bbox_min_mm: lo,
                bbox_max_mm: hi,
                area_mm2: region::shape_area(s),
            }
        })
        .collect();
    Ok(tp)
}

/// The loop of samples started at the sample nearest to arc length `shift_mm` (mod the loop's
/// length) from its lowest-leftmost sample.
fn rotate_samples(samples: &[wall::WallSample], shift_mm: f64) -> Vec<wall::WallSample> {
    let xy: Vec<P2> = samples.iter().map(|s| s.xy).collect();
    let closed = closed_from_arc_length(&xy, shift_mm, geom::NORM);
    let start = closed[0];
    let i = (0..samples.len())
        .min_by(|&a, &b| dist(xy[a], start).total_cmp(&dist(xy[b], start)))
        .unwrap_or(0);
    samples[i..].iter().chain(&samples[..i]).copied().collect()
}

fn assemble(
    layer: &LayerPolygons,
    process: &WaamProcess,
    angle: f64,
    beads: Vec<Bead>,
    from: Option<[f64; 3]>,
) -> LayerToolpath {
    let z = layer.z_mm;
    let wfs = process.wire_feed_m_min;
    let q = bead::deposition_rate_mm3_s(wfs, process.wire_diameter_mm);
    let travel_pt = |x: f64, y: f64, z: f64| PathPoint {
        x_mm: x,
        y_mm: y,
        z_mm: z,
        speed_mm_s: process.travel_move_speed_mm_s,
        bead_width_mm: 0.0,
        bead_height_mm: 0.0,
        wire_feed_m_min: 0.0,
        arc_on: false,
    };
    let mut segments = Vec::new();
    let mut cur = from;
    for b in beads {
        if b.pts.len() < 2 {
            continue;
        }
        let s = b.pts[0];
        if let Some(c) = cur {
            if (c[0] - s[0]).hypot(c[1] - s[1]) > 1e-9 || (c[2] - z).abs() > 1e-9 {
                let lift = process.travel_lift_mm;
                let top = c[2].max(z) + lift;
                let mut points = vec![travel_pt(c[0], c[1], c[2])];
                if lift > 0.0 {
                    points.push(travel_pt(c[0], c[1], top));
                    points.push(travel_pt(s[0], s[1], top));
                }
                points.push(travel_pt(s[0], s[1], z));
                segments.push(Segment {
                    kind: SegmentKind::Travel,
                    role: SegmentRole::Travel,
                    points,
                });
            }
        }
        let n = b.pts.len();
        let points = (0..n)
            .map(|i| {
                // The last point repeats the values of the piece before it.
                let (w, ts) = b.width_speed[i.min(n - 2)];
                PathPoint {
                    x_mm: b.pts[i][0],
                    y_mm: b.pts[i][1],
                    z_mm: z,
                    speed_mm_s: ts,
                    bead_width_mm: w,
                    // Eq. 28: h = WFS·(d_w/2)²·π / (TS·LW).
                    bead_height_mm: q / (ts * w),
                    wire_feed_m_min: wfs,
                    arc_on: true,
                }
            })
            .collect();
        let e = b.pts[n - 1];
        cur = Some([e[0], e[1], z]);
        segments.push(Segment {
            kind: SegmentKind::Deposit,
            role: b.role,
            points,
        });
    }
    let mut deposited_volume_mm3 = 0.0;
    let mut deposition_time_s = 0.0;
    let mut travel_time_s = 0.0;
    let mut arc_starts = 0;
    for s in &segments {
        match s.kind {
            SegmentKind::Deposit => {
                deposited_volume_mm3 += s.volume_mm3();
                deposition_time_s += s.time_s();
                arc_starts += 1;
            }
            SegmentKind::Travel => travel_time_s += s.time_s(),
        }
    }
    travel_time_s += arc_starts as f64 * process.arc_start_stop_s;
    LayerToolpath {
        index: layer.index,
        z_mm: z,
        infill_angle_deg: angle,
        segments,
        deposited_volume_mm3,
        deposition_time_s,
        travel_time_s,
        dwell_time_s: process.dwell_s,
        arc_starts,
        uncovered: Vec::new(),
    }
}

/// Plans a stack of layers in order, each starting from where the previous one ended.
///
/// # Errors
/// As [`plan_layer`], for the first bad layer.
pub fn plan_stack(
    layers: &[LayerPolygons],
    process: &WaamProcess,
) -> Result<Vec<LayerToolpath>, ToolpathError> {
    let mut out: Vec<LayerToolpath> = Vec::with_capacity(layers.len());
    let mut from: Option<[f64; 3]> = None;
    for l in layers {
        let tp = plan_layer(l, process, from)?;
        if let Some(p) = tp.segments.last().and_then(|s| s.points.last()) {
            from = Some([p.x_mm, p.y_mm, p.z_mm]);
        }
        out.push(tp);
    }
    Ok(out)
}
