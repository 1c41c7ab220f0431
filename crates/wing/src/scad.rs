//! OpenSCAD model of the designed wing (seed 002 §CAD File Generation: "fully independent of the
//! G-Code generation process"): the outer mould line (OML) and the spar walls, built from the
//! design results only (chord and twist per LLT station, the hinge line, the airfoil, the spar
//! locations X_sp and the section breaks), never from [`crate::layers`].
//!
//! **Wing frame** (origin on the hinge line at y = 0; X aft along the chord, Y spanwise towards
//! the right tip, Z up; right-handed). The section at span y has chord c(y) and angle
//! α(y) = LLT α + α_L0 (nose up positive), both linear between LLT stations and held beyond the
//! end stations ([`crate::layers::Planform`]). A unit-chord airfoil point (x, z) goes to
//! u = (x − x_h)·c, v = (z − z_h)·c with the hinge x_h = `hinge_x_over_c` and
//! z_h = z_lower(x_h) + p_z·τ(x_h), then X = u cos α + v sin α, Z = −u sin α + v cos α: every
//! section is twisted about its hinge point, which stays at X = Z = 0, so the hinge line is
//! straight.
//!
//! **Solids.** The OML is the airfoil polygon (the `.dat` points, closed) lofted with straight
//! rulings between rings at every LLT station and at the section breaks: a closed polyhedron per
//! section whose slice at any span is the polygon the printed perimeter's bead centre follows
//! (no offset), so its volume is ∫A·c(y)² dy with A the unit airfoil's area. A spar at x/c = s
//! is a wall w wide (the extrusion width) along the chord normal, from z_lower(s) to z_upper(s)
//! each inset by `spar_overlap`·w (the spar line's ends), lofted the same way; where the spar
//! count changes between stations the walls switch at the midpoint, as [`SparLayout::at`]
//! does. The model shows the OML solid, not a shell: the skin is one bead on the OML, which a
//! CAD solid of width w would only approximate near the sharp trailing edge.
//!
//! **Files.** `part = "oml"` (default) renders the OML, `"spars"` the spar walls, `"preview"`
//! both with the OML translucent (OpenSCAD's `%`, preview only). Each part is one `polyhedron`
//! (one closed shell per section or spar run), so rendering needs no CSG and is quick.
//! [`wing_scad`] writes the whole wing in the wing frame, one shell per printable section;
//! [`section_scad`] one section in its **build orientation**, the machine frame of its G-code:
//! spanwise distance from the bed face up as Z, the chord along X (mirrored on the right wing)
//! and the airfoil's Z along machine Y, with the hinge line vertical at X = X_bed/2 ∓
//! c_max(½ − x_h), Y = Y_bed/2 (c_max the section's largest chord). The centre section is built
//! from its left face up, which is its mirror image (the same solid for a symmetric wing).
//! Numbers are written in mm with 4 decimals; the text is deterministic.

use std::fmt::Write as _;

use cell_airfoil::SurfaceFunctions;

use crate::section::{Section, Side};
use crate::spec::Wing;
use crate::structure::SparLayout;

/// Which part of the wing a file holds.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Extent<'a> {
    Wing,
    Section(&'a Section),
}

/// Points and faces of one `polyhedron`: faces listed clockwise seen from outside (OpenSCAD's
/// rule).
#[derive(Debug, Default)]
struct Polyhedron {
    points: Vec<[f64; 3]>,
    faces: Vec<Vec<usize>>,
}

impl Polyhedron {
    /// A closed loft through `rings` (equal lengths, in increasing wing Y, each anticlockwise
    /// seen from −Y, i.e. in the airfoil's (x, z) sense): side quads as two triangles, and the
    /// two end caps as polygons.
    fn add_loft(&mut self, rings: &[Vec<[f64; 3]>]) {
        let Some(n) = rings.first().map(Vec::len) else {
            return;
        };
        if rings.len() < 2 || n < 3 {
            return;
        }
        let base = self.points.len();
        for r in rings {
            self.points.extend_from_slice(r);
        }
        let at = |k: usize, i: usize| base + k * n + i % n;
        for k in 0..rings.len() - 1 {
            for i in 0..n {
                // Ring direction × +Y points inwards: this order is clockwise from outside.
                self.faces
                    .push(vec![at(k, i), at(k, i + 1), at(k + 1, i + 1)]);
                self.faces
                    .push(vec![at(k, i), at(k + 1, i + 1), at(k + 1, i)]);
            }
        }
        // The −Y cap is seen from −Y, where the ring runs anticlockwise: reverse it.
        self.faces.push((0..n).rev().map(|i| at(0, i)).collect());
        self.faces
            .push((0..n).map(|i| at(rings.len() - 1, i)).collect());
    }

    /// Applies the rigid map `f`; `mirror` when it reverses orientation (then every face is
    /// reversed, so faces stay clockwise from outside).
    fn map(&mut self, f: impl Fn([f64; 3]) -> [f64; 3], mirror: bool) {
        for p in &mut self.points {
            *p = f(*p);
        }
        if mirror {
            for face in &mut self.faces {
                face.reverse();
            }
        }
    }

    fn write(&self, out: &mut String, module: &str) {
        let _ = writeln!(out, "module {module}() polyhedron(\n  points = [");
        for p in &self.points {
            let _ = writeln!(out, "    [{}, {}, {}],", num(p[0]), num(p[1]), num(p[2]));
        }
        out.push_str("  ],\n  faces = [\n");
        for f in &self.faces {
            let ids: Vec<String> = f.iter().map(usize::to_string).collect();
            let _ = writeln!(out, "    [{}],", ids.join(", "));
        }
        out.push_str("  ],\n  convexity = 10);\n\n");
    }
}

/// `v` in mm with 4 decimals, trailing zeros trimmed, no `-0`.
fn num(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// The design quantities the model needs, and the section geometry of the module docs.
struct Shape<'a> {
    wing: &'a Wing,
    surf: &'a SurfaceFunctions,
    /// Unit-chord OML ring (the airfoil points, the repeated closing point dropped).
    ring: Vec<[f64; 2]>,
    x_h: f64,
    z_h: f64,
}

impl<'a> Shape<'a> {
    fn new(wing: &'a Wing) -> Self {
        let surf = &wing.surfaces;
        let mut ring: Vec<[f64; 2]> = wing.airfoil.points().iter().map(|p| [p.x, p.y]).collect();
        if ring.len() > 3 && ring.first() == ring.last() {
            ring.pop();
        }
        let x_h = wing.spec.structure.hinge_x_over_c;
        let z_h = surf.z_lower(x_h) + wing.spec.structure.hinge_z_over_t * surf.thickness(x_h);
        Self {
            wing,
            surf,
            ring,
            x_h,
            z_h,
        }
    }

    /// Unit-chord airfoil point (x, z) of the section at span y → wing frame.
    fn to_wing(&self, y: f64, x: f64, z: f64) -> [f64; 3] {
        let (c, alpha) = self.wing.planform.at(y);
        let (sin, cos) = alpha.sin_cos();
        let (u, v) = ((x - self.x_h) * c, (z - self.z_h) * c);
        [u * cos + v * sin, y, -u * sin + v * cos]
    }

    /// Span levels of one solid from `y0` to `y1` (y0 < y1): both ends, every LLT station
    /// between, and the midpoints between stations whose spar counts differ (where the walls
    /// switch).
    fn levels(&self, y0: f64, y1: f64) -> Vec<f64> {
        let b = self.wing.spec.aero.span_mm;
        let sp = &self.wing.spars;
        let mut ys = vec![y0, y1];
        for (j, &yb) in sp.y_over_b.iter().enumerate() {
            ys.push(yb * b);
            if let Some(next) = sp.y_over_b.get(j + 1) {
                if sp.x_over_c[j].len() != sp.x_over_c[j + 1].len() {
                    ys.push(0.5 * (yb + next) * b);
                }
            }
        }
        ys.retain(|&y| y >= y0 && y <= y1);
        ys.sort_by(f64::total_cmp);
        ys.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        ys
    }

    /// The OML loft between `levels`.
    fn oml(&self, levels: &[f64], out: &mut Polyhedron) {
        let rings: Vec<Vec<[f64; 3]>> = levels
            .iter()
            .map(|&y| {
                self.ring
                    .iter()
                    .map(|p| self.to_wing(y, p[0], p[1]))
                    .collect()
            })
            .collect();
        out.add_loft(&rings);
    }

    /// The spar walls between `levels`: per interval the spars of [`spars_over`], joined into
    /// one loft per spar while the count stays the same. An interval in which a spar moves
    /// more than w along the chord is split into pieces that move it at most w, so the ruled
    /// wall's ends stay within c·|z''|·(w/c)²/8 of the skins (z'' the surface's curvature).
    fn spars(&self, levels: &[f64], out: &mut Polyhedron) {
        let b = self.wing.spec.aero.span_mm;
        let w = self.wing.spec.build.extrusion_width_mm;
        let overlap = self.wing.spec.build.spar_overlap;
        // One wall's 4-corner ring at span y and x/c s, or None where the section is too thin.
        let wall = |y: f64, s: f64| -> Option<Vec<[f64; 3]>> {
            let (c, _) = self.wing.planform.at(y);
            let inset = overlap * w / c;
            let (top, bottom) = (self.surf.z_upper(s) - inset, self.surf.z_lower(s) + inset);
            let dw = 0.5 * w / c;
            (top - bottom > 1e-9).then(|| {
                [
                    (s - dw, bottom),
                    (s + dw, bottom),
                    (s + dw, top),
                    (s - dw, top),
                ]
                .iter()
                .map(|&(x, z)| self.to_wing(y, x, z))
                .collect()
            })
        };
        let mut runs: Vec<Option<Vec<Vec<[f64; 3]>>>> = Vec::new();
        let close = |runs: &mut Vec<Option<Vec<Vec<[f64; 3]>>>>, out: &mut Polyhedron| {
            for run in runs.drain(..).flatten() {
                out.add_loft(&run);
            }
        };
        for pair in levels.windows(2) {
            let mid = 0.5 * (pair[0] + pair[1]) / b;
            let at = |y: f64| spars_over(&self.wing.spars, y / b, mid);
            // Split the interval so no spar moves more than w along the chord in one piece.
            let (c, _) = self.wing.planform.at(pair[0]);
            let moved = at(pair[0])
                .iter()
                .zip(at(pair[1]))
                .map(|(p, q)| (q - p).abs() * c)
                .fold(0.0, f64::max);
            let pieces = (moved / w).ceil().max(1.0) as usize;
            let y_at = |i: usize| pair[0] + (pair[1] - pair[0]) * i as f64 / pieces as f64;
            for i in 0..pieces {
                let (y0, y1) = (y_at(i), y_at(i + 1));
                let (s0, s1) = (at(y0), at(y1));
                if s0.len() != runs.len() {
                    close(&mut runs, out);
                    runs.resize(s0.len(), None);
                }
                for (k, (&a, &e)) in s0.iter().zip(&s1).enumerate() {
                    match (wall(y0, a), wall(y1, e)) {
                        (Some(r0), Some(r1)) => match &mut runs[k] {
                            Some(run) => run.push(r1),
                            None => runs[k] = Some(vec![r0, r1]),
                        },
                        _ => {
                            if let Some(run) = runs[k].take() {
                                out.add_loft(&run);
                            }
                        }
                    }
                }
            }
        }
        close(&mut runs, out);
    }
}

/// Spar x/c at span y/b for the interval whose midpoint is `mid` (y/b): linear between the two
/// stations around `mid` when their spar counts agree, else the spars of the station on
/// `mid`'s side of their midpoint; the end stations' spars beyond them ([`SparLayout::at`]'s
/// rule, taken per interval so both ends of a wall use the same stations).
fn spars_over(layout: &SparLayout, y_over_b: f64, mid: f64) -> Vec<f64> {
    let ys = &layout.y_over_b;
    let i = ys.partition_point(|v| *v < mid);
    if i == 0 {
        return layout.x_over_c[0].clone();
    }
    if i == ys.len() {
        return layout.x_over_c[ys.len() - 1].clone();
    }
    let (a, b) = (&layout.x_over_c[i - 1], &layout.x_over_c[i]);
    let t = |y: f64| (y - ys[i - 1]) / (ys[i] - ys[i - 1]);
    if a.len() == b.len() {
        let t = t(y_over_b);
        a.iter().zip(b).map(|(p, q)| p + (q - p) * t).collect()
    } else if t(mid) < 0.5 {
        a.clone()
    } else {
        b.clone()
    }
}

/// The two parts of one extent, in the wing frame.
fn parts(shape: &Shape, extent: Extent) -> (Polyhedron, Polyhedron) {
    let (mut oml, mut spars) = (Polyhedron::default(), Polyhedron::default());
    let bounds: Vec<(f64, f64)> = match extent {
        Extent::Wing => shape
            .wing
            .sections
            .iter()
            .map(|s| (s.y_bed_mm.min(s.y_top_mm), s.y_bed_mm.max(s.y_top_mm)))
            .collect(),
        Extent::Section(s) => vec![(s.y_bed_mm.min(s.y_top_mm), s.y_bed_mm.max(s.y_top_mm))],
    };
    for (y0, y1) in bounds {
        let levels = shape.levels(y0, y1);
        shape.oml(&levels, &mut oml);
        shape.spars(&levels, &mut spars);
    }
    (oml, spars)
}

fn header(wing: &Wing, title: &str, frame: &str) -> String {
    let a = &wing.spec.aero;
    let mut out = String::new();
    let _ = writeln!(out, "// {title}");
    let _ = writeln!(
        out,
        "// G-Wing (seed 002) OpenSCAD model, written by cell_wing::scad from the design (chord,\n\
         // twist, hinge line, airfoil, spar locations X_sp, section breaks), independently of\n\
         // the G-code. Units mm.\n\
         // Airfoil: {}\n\
         // Span {} mm, AR {}, c_L {:.4}; hinge at x/c = {}; spar walls {} mm wide.",
        wing.airfoil.name().replace(['\n', '\r'], " "),
        num(a.span_mm),
        num(a.aspect_ratio),
        wing.aero.c_l,
        num(wing.spec.structure.hinge_x_over_c),
        num(wing.spec.build.extrusion_width_mm),
    );
    let _ = writeln!(out, "// {frame}");
    out.push_str(
        "// part: \"oml\" the outer mould line (solid, the printed perimeter's bead centre),\n\
         // \"spars\" the spar walls, \"preview\" both (OML translucent). E.g.\n\
         // openscad -D 'part=\"spars\"' -o spars.stl this.scad\n\
         part = \"oml\";\n\n",
    );
    out
}

fn footer(out: &mut String) {
    out.push_str(
        "if (part == \"oml\") oml();\n\
         else if (part == \"spars\") spars();\n\
         else if (part == \"preview\") { %oml(); spars(); }\n\
         else assert(false, \"part must be \\\"oml\\\", \\\"spars\\\" or \\\"preview\\\"\");\n",
    );
}

/// The whole wing in the wing frame (module docs): one OML shell and one set of spar walls
/// per printable section, so the section breaks show as faces.
pub fn wing_scad(wing: &Wing) -> String {
    let shape = Shape::new(wing);
    let (oml, spars) = parts(&shape, Extent::Wing);
    let mut out = header(
        wing,
        "whole wing",
        "Wing frame: origin on the hinge line at mid-span, X aft, Y towards the right tip, Z up.",
    );
    oml.write(&mut out, "oml");
    spars.write(&mut out, "spars");
    footer(&mut out);
    out
}

/// Section `index` (into [`Wing::sections`]) in its build orientation (module docs), or None
/// when there is no such section.
pub fn section_scad(wing: &Wing, index: usize) -> Option<String> {
    let section = wing.sections.get(index)?;
    let shape = Shape::new(wing);
    let (mut oml, mut spars) = parts(&shape, Extent::Section(section));
    let b = &wing.spec.build;
    let (lo, hi) = (
        section.y_bed_mm.min(section.y_top_mm),
        section.y_bed_mm.max(section.y_top_mm),
    );
    let c_max = shape
        .levels(lo, hi)
        .iter()
        .map(|&y| wing.planform.at(y).0)
        .fold(0.0, f64::max);
    // Chord sign s (the right wing mirrored in X) and build direction d (the left wing grows
    // towards −y); the map (X, Y, Z) → (s·X, Z, d·(Y − y_bed)) has determinant −s·d.
    let s = if section.side == Side::Right {
        -1.0
    } else {
        1.0
    };
    let d = section.direction();
    let x_h = wing.spec.structure.hinge_x_over_c;
    let hinge = [0.5 * b.bed_x_mm - s * c_max * (0.5 - x_h), 0.5 * b.bed_y_mm];
    let to_machine = |p: [f64; 3]| {
        [
            hinge[0] + s * p[0],
            hinge[1] + p[2],
            d * (p[1] - section.y_bed_mm),
        ]
    };
    let mirror = -s * d < 0.0;
    oml.map(to_machine, mirror);
    spars.map(to_machine, mirror);
    let mut out = header(
        wing,
        &format!(
            "section {index}: {:?} {}, y from {} to {} mm",
            section.side,
            section.index,
            num(section.y_bed_mm),
            num(section.y_top_mm)
        ),
        &format!(
            "Build orientation (the section's G-code frame): Z = |y - ({})| up from the bed,\n\
             // hinge line vertical at X = {}, Y = {}.",
            num(section.y_bed_mm),
            num(hinge[0]),
            num(hinge[1])
        ),
    );
    oml.write(&mut out, "oml");
    spars.write(&mut out, "spars");
    footer(&mut out);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_trimmed_and_never_negative_zero() {
        assert_eq!(num(1.5), "1.5");
        assert_eq!(num(2.0), "2");
        assert_eq!(num(-0.00001), "0");
        assert_eq!(num(-12.34567), "-12.3457");
    }

    /// A closed loft has every edge in exactly two faces, traversed once each way.
    #[test]
    fn a_loft_is_closed_and_consistently_oriented() {
        let ring = |y: f64| vec![[0.0, y, 0.0], [1.0, y, 0.0], [1.0, y, 1.0], [0.0, y, 1.0]];
        let mut p = Polyhedron::default();
        p.add_loft(&[ring(0.0), ring(1.0), ring(3.0)]);
        let mut edges = std::collections::HashMap::new();
        for f in &p.faces {
            for i in 0..f.len() {
                *edges.entry((f[i], f[(i + 1) % f.len()])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} once");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} both ways");
        }
        // Clockwise from outside: the right-hand normal points inwards, so the divergence
        // theorem over the faces gives minus the volume (1 × 3 × 1).
        let v: f64 = p
            .faces
            .iter()
            .flat_map(|f| (1..f.len() - 1).map(move |i| [f[0], f[i], f[i + 1]]))
            .map(|[a, b, c]| {
                let (a, b, c) = (p.points[a], p.points[b], p.points[c]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum();
        assert!((v + 3.0).abs() < 1e-12, "volume {v}");
    }
}
