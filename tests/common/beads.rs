//! The deposited beads of a WAAM robot program, rebuilt from its moves with the bead model
//! written out here again from seed 004 (no code shared with `cell_waam`), and questions about
//! their union: is a point inside, and how far can one go from it in a direction before leaving
//! the deposit.
//!
//! A bead is the bead model's rectangular cross-section (seed 004 eq. 25: width LW, height h)
//! swept along one straight move of an arc-on run, with round ends (the weld pool is round, so
//! consecutive moves join without a notch): in plan the set of points within LW/2 of the move,
//! in height a slab of thickness h placed by [`ToolPoint`]. The substrate plate is the
//! half-space below `z = 0` of the work object (the part is built on it).
#![allow(dead_code)] // each test binary uses a different subset

use super::rapid_reader::{MoveKind, Run};

/// External bead width LW (mm) for travel speed `ts_mm_s` (mm/s) and wire feed `wfs_m_min`
/// (m/min), seed 004 eq. 14: `LW = 1.5 + Re((TS − 14.1)^1.55) + Re((WFS − 2.9)^1.52)`, where
/// `Re(x^p)` of a negative x is `|x|^p·cos(pπ)`.
pub fn bead_width_mm(ts_mm_s: f64, wfs_m_min: f64) -> f64 {
    let re_pow = |x: f64, p: f64| {
        if x >= 0.0 {
            x.powf(p)
        } else {
            (-x).powf(p) * (p * std::f64::consts::PI).cos()
        }
    };
    1.5 + re_pow(ts_mm_s - 14.1, 1.55) + re_pow(wfs_m_min - 2.9, 1.52)
}

/// Bead height h (mm), seed 004 eq. 28: `h = WFS·(d_w/2)²·π / (TS·LW)`, WFS in mm/s, the
/// rectangular cross-section that holds the wire fed per unit length of bead.
pub fn bead_height_mm(ts_mm_s: f64, wfs_m_min: f64, wire_diameter_mm: f64) -> f64 {
    let wfs_mm_s = wfs_m_min * 1000.0 / 60.0;
    let wire_area = std::f64::consts::PI * (wire_diameter_mm / 2.0).powi(2);
    wfs_mm_s * wire_area / (ts_mm_s * bead_width_mm(ts_mm_s, wfs_m_min))
}

/// Where the program's tool point sits relative to the bead it lays: the checker's one
/// assumption about the emitter's convention (its README and `cell_waam::to_msg`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ToolPoint {
    /// Halfway up the bead (the slicing plane at mid-layer).
    MidBead,
    /// At the bead's top (the wire tip on the surface being built).
    BeadTop,
    /// This far (mm) above the bead's top (a contact-tip-to-work distance).
    AboveBeadTop(f64),
}

impl ToolPoint {
    /// Height of the tool point above the bead's base for a bead of height `h`.
    pub fn above_base(self, h: f64) -> f64 {
        match self {
            ToolPoint::MidBead => 0.5 * h,
            ToolPoint::BeadTop => h,
            ToolPoint::AboveBeadTop(d) => h + d,
        }
    }
}

/// What the program does not say and the process file used does.
#[derive(Debug, Clone, Copy)]
pub struct ProcessFacts {
    /// Wire feed (m/min) when the weld data does not carry one.
    pub wire_feed_m_min: f64,
    /// Wire diameter d_w (mm).
    pub wire_diameter_mm: f64,
}

/// One bead: a move of an arc-on run.
#[derive(Debug, Clone, Copy)]
pub struct Bead {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub half_width: f64,
    pub z_base: f64,
    pub z_top: f64,
    pub travel_speed_mm_s: f64,
    pub wire_feed_m_min: f64,
    /// Where the move is in the program.
    pub line: usize,
}

impl Bead {
    fn length(&self) -> f64 {
        (self.b[0] - self.a[0]).hypot(self.b[1] - self.a[1])
    }

    /// Distance in plan from `p` to the move.
    fn plan_distance(&self, p: [f64; 2]) -> f64 {
        let (dx, dy) = (self.b[0] - self.a[0], self.b[1] - self.a[1]);
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 {
            (((p[0] - self.a[0]) * dx + (p[1] - self.a[1]) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p[0] - self.a[0] - t * dx).hypot(p[1] - self.a[1] - t * dy)
    }

    /// `p` inside or within `eps` of the bead.
    pub fn contains(&self, p: [f64; 3], eps: f64) -> bool {
        p[2] >= self.z_base - eps
            && p[2] <= self.z_top + eps
            && self.plan_distance([p[0], p[1]]) <= self.half_width + eps
    }

    /// How far from `p` (inside) along unit `d` the ray stays in the bead.
    fn exit(&self, p: [f64; 3], d: [f64; 3]) -> f64 {
        let slab = if d[2] > 1e-12 {
            (self.z_top - p[2]) / d[2]
        } else if d[2] < -1e-12 {
            (self.z_base - p[2]) / d[2]
        } else {
            f64::INFINITY
        };
        let plan = if d[0].abs() < 1e-12 && d[1].abs() < 1e-12 {
            f64::INFINITY
        } else {
            // The plan shape is convex, the union of a rectangle and two discs: the ray stays
            // inside up to the largest end of its intervals in the three.
            let r = self.half_width;
            let mut end = disc_end([p[0], p[1]], [d[0], d[1]], self.a, r);
            end = end.max(disc_end([p[0], p[1]], [d[0], d[1]], self.b, r));
            let l = self.length();
            if l > 0.0 {
                let u = [(self.b[0] - self.a[0]) / l, (self.b[1] - self.a[1]) / l];
                let n = [-u[1], u[0]];
                let rel = [p[0] - self.a[0], p[1] - self.a[1]];
                let (s0, ds) = (rel[0] * u[0] + rel[1] * u[1], d[0] * u[0] + d[1] * u[1]);
                let (q0, dq) = (rel[0] * n[0] + rel[1] * n[1], d[0] * n[0] + d[1] * n[1]);
                let a = slab_interval(s0, ds, 0.0, l);
                let b = slab_interval(q0, dq, -r, r);
                let (lo, hi) = (a.0.max(b.0), a.1.min(b.1));
                if lo <= hi {
                    end = end.max(hi);
                }
            }
            end
        };
        slab.min(plan).max(0.0)
    }
}

/// The end of the ray's interval inside the disc (−∞ when it misses).
fn disc_end(p: [f64; 2], d: [f64; 2], c: [f64; 2], r: f64) -> f64 {
    let (fx, fy) = (p[0] - c[0], p[1] - c[1]);
    let a = d[0] * d[0] + d[1] * d[1];
    let b = fx * d[0] + fy * d[1];
    let cc = fx * fx + fy * fy - r * r;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        f64::NEG_INFINITY
    } else {
        (-b + disc.sqrt()) / a
    }
}

/// The ray's interval `x0 + t·dx ∈ [lo, hi]`.
fn slab_interval(x0: f64, dx: f64, lo: f64, hi: f64) -> (f64, f64) {
    if dx.abs() < 1e-12 {
        if x0 >= lo - 1e-9 && x0 <= hi + 1e-9 {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        }
    } else {
        let (t0, t1) = ((lo - x0) / dx, (hi - x0) / dx);
        (t0.min(t1), t0.max(t1))
    }
}

/// The beads of a program run: one per `ArcL`/`ArcLEnd` move of an arc-on run (from its
/// `ArcLStart` target), at the weld data's weld speed when it sets one (in arc mode the
/// controller welds at that speed, not the speeddata's), with the weld data's wire feed or else
/// the process file's.
///
/// # Errors
/// An `ArcL`/`ArcLEnd` outside a run, a run left open, or a speed ≤ 0.
pub fn beads_of(
    run: &Run,
    facts: ProcessFacts,
    tool_point: ToolPoint,
) -> Result<Vec<Bead>, String> {
    let mut beads = Vec::new();
    let mut previous: Option<[f64; 3]> = None;
    let mut arc_on = false;
    for m in &run.motions {
        let at = format!("{}:{}", m.file, m.line);
        match m.kind {
            MoveKind::ArcLStart => {
                if arc_on {
                    return Err(format!("{at}: ArcLStart inside an arc-on run"));
                }
                arc_on = true;
            }
            MoveKind::ArcL | MoveKind::ArcLEnd => {
                let from = previous
                    .filter(|_| arc_on)
                    .ok_or(format!("{at}: {:?} with no arc on", m.kind))?;
                let weld = m.weld.filter(|w| w.weld_speed_mm_s > 0.0);
                let ts = weld.map_or(m.speed_mm_s, |w| w.weld_speed_mm_s);
                let wfs = m
                    .weld
                    .and_then(|w| w.wire_feed_m_min)
                    .unwrap_or(facts.wire_feed_m_min);
                if !(ts > 0.0 && wfs > 0.0) {
                    return Err(format!(
                        "{at}: travel speed {ts} mm/s, wire feed {wfs} m/min"
                    ));
                }
                let w = bead_width_mm(ts, wfs);
                let h = bead_height_mm(ts, wfs, facts.wire_diameter_mm);
                let to = m.target.pos;
                // A move that climbs within a run lays its bead at the higher end's layer.
                let z_tool = from[2].max(to[2]);
                let z_base = z_tool - tool_point.above_base(h);
                beads.push(Bead {
                    a: [from[0], from[1]],
                    b: [to[0], to[1]],
                    half_width: w / 2.0 + JOIN_MM,
                    z_base,
                    z_top: z_base + h,
                    travel_speed_mm_s: ts,
                    wire_feed_m_min: wfs,
                    line: m.line,
                });
                if m.kind == MoveKind::ArcLEnd {
                    arc_on = false;
                }
            }
            MoveKind::MoveL | MoveKind::MoveJ => {
                if arc_on {
                    return Err(format!("{at}: {:?} inside an arc-on run", m.kind));
                }
            }
        }
        previous = Some(m.target.pos);
    }
    if arc_on {
        return Err("the program ends with the arc on (no ArcLEnd)".into());
    }
    Ok(beads)
}

/// The union of the beads and the substrate below `z = 0`, with a grid to find the beads near
/// a point.
pub struct Deposit {
    pub beads: Vec<Bead>,
    origin: [f64; 3],
    cell: [f64; 3],
    dims: [usize; 3],
    cells: Vec<Vec<u32>>,
}

/// Tolerance of "on the boundary" (mm).
const EPS: f64 = 1e-6;
/// The program's position resolution, mm (RAPID targets are written to 0.001 mm). Each bead is
/// modelled this much wider on either side: infill beads laid exactly a bead width apart would
/// otherwise show slits of up to a micrometre wherever rounding moved them apart, which no
/// weld pool leaves.
const JOIN_MM: f64 = 1e-3;

impl Deposit {
    pub fn new(beads: Vec<Bead>) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for b in &beads {
            for (i, (l, h)) in bead_box(b).into_iter().enumerate() {
                lo[i] = lo[i].min(l);
                hi[i] = hi[i].max(h);
            }
        }
        if beads.is_empty() {
            lo = [0.0; 3];
            hi = [1.0; 3];
        }
        let max_w = beads.iter().map(|b| 2.0 * b.half_width).fold(1.0, f64::max);
        let max_h = beads.iter().map(|b| b.z_top - b.z_base).fold(0.5, f64::max);
        let cell = [max_w / 2.0, max_w / 2.0, max_h];
        let dims: [usize; 3] =
            std::array::from_fn(|i| (((hi[i] - lo[i]) / cell[i]).ceil() as usize).max(1));
        let mut cells = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        for (n, b) in beads.iter().enumerate() {
            let bx = bead_box(b);
            let range = |i: usize| {
                let a = ((bx[i].0 - lo[i]) / cell[i]).floor().max(0.0) as usize;
                let z = (((bx[i].1 - lo[i]) / cell[i]).floor().max(0.0) as usize).min(dims[i] - 1);
                a.min(dims[i] - 1)..=z
            };
            for k in range(2) {
                for j in range(1) {
                    for i in range(0) {
                        cells[(k * dims[1] + j) * dims[0] + i].push(n as u32);
                    }
                }
            }
        }
        Deposit {
            beads,
            origin: lo,
            cell,
            dims,
            cells,
        }
    }

    fn candidates(&self, p: [f64; 3]) -> &[u32] {
        let mut idx = [0usize; 3];
        for i in 0..3 {
            let f = ((p[i] - self.origin[i]) / self.cell[i]).floor();
            if f < 0.0 || f >= self.dims[i] as f64 {
                return &[];
            }
            idx[i] = f as usize;
        }
        &self.cells[(idx[2] * self.dims[1] + idx[1]) * self.dims[0] + idx[0]]
    }

    /// `p` in a bead (or on one) or in the substrate.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        p[2] <= EPS
            || self
                .candidates(p)
                .iter()
                .any(|&n| self.beads[n as usize].contains(p, EPS))
    }

    /// How far from `p` along unit `d` the ray stays inside the deposit, up to `cap`; 0 when
    /// `p` is outside.
    pub fn exit_distance(&self, p: [f64; 3], d: [f64; 3], cap: f64) -> f64 {
        let mut t = 0.0;
        loop {
            let q = [p[0] + t * d[0], p[1] + t * d[1], p[2] + t * d[2]];
            let mut best = t;
            if q[2] <= EPS {
                best = if d[2] < 1e-12 {
                    f64::INFINITY
                } else {
                    t + (0.0 - q[2]) / d[2]
                };
            }
            for &n in self.candidates(q) {
                let b = &self.beads[n as usize];
                if b.contains(q, EPS) {
                    best = best.max(t + b.exit(q, d));
                }
            }
            if best >= cap {
                return cap;
            }
            if best <= t + EPS {
                return t;
            }
            t = best;
        }
    }

    /// The bounding box of the beads: (min, max).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for b in &self.beads {
            for (i, (l, h)) in bead_box(b).into_iter().enumerate() {
                lo[i] = lo[i].min(l);
                hi[i] = hi[i].max(h);
            }
        }
        (lo, hi)
    }

    /// Sum of the beads' own volumes, LW·h·length (seed 004 eq. 25), overlaps counted twice.
    pub fn swept_volume_mm3(&self) -> f64 {
        self.beads
            .iter()
            .map(|b| 2.0 * b.half_width * (b.z_top - b.z_base) * b.length())
            .sum()
    }
}

fn bead_box(b: &Bead) -> [(f64, f64); 3] {
    let r = b.half_width;
    [
        (b.a[0].min(b.b[0]) - r, b.a[0].max(b.b[0]) + r),
        (b.a[1].min(b.b[1]) - r, b.a[1].max(b.b[1]) + r),
        (b.z_base, b.z_top),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bead_model_reproduces_the_seed_fixtures() {
        // seed 004 notes B5: eq. 14 at Chart 2 condition 10 and 1, eq. 28 at condition 10.
        assert!((bead_width_mm(7.0, 5.53) - 9.113).abs() < 0.002);
        assert!((bead_width_mm(2.2, 3.56) - 9.300).abs() < 0.002);
        // eq. 28 with the model's width (the seed's 1.622 mm uses the measured 9.18 mm).
        let h = bead_height_mm(7.0, 5.53, 1.2);
        assert!((h - 1.634).abs() < 0.001, "{h}");
    }
}
