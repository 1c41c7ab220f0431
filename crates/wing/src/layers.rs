//! Per-layer toolpaths of a section (seed 002 Algorithm 2): the transformed airfoil as a
//! closed perimeter, then the spars (or, on a section's first layer, a solid rib), and the
//! flattened move list with absolute E, retracts and Z-hops.

use cell_airfoil::SurfaceFunctions;
use nalgebra::Point2;

use crate::section::{Section, Side};
use crate::structure::SparLayout;

/// Process settings (seed 002 Table 3 and the notes' G-code details).
#[derive(Debug, Clone, PartialEq)]
pub struct BuildParams {
    /// Bead width w \[mm\].
    pub extrusion_width_mm: f64,
    /// Layer height h \[mm\].
    pub layer_height_mm: f64,
    /// First layer height h₀ \[mm\].
    pub first_layer_height_mm: f64,
    /// Filament diameter d_f \[mm\].
    pub filament_diameter_mm: f64,
    /// Perimeter speed \[mm/s\].
    pub perimeter_speed_mm_s: f64,
    /// Infill (spar) speed \[mm/s\].
    pub infill_speed_mm_s: f64,
    /// Solid infill (rib) speed \[mm/s\].
    pub solid_infill_speed_mm_s: f64,
    /// First layer speed cap \[mm/s\]: layer 0 runs at min(role speed, this).
    pub first_layer_speed_mm_s: f64,
    /// Travel speed \[mm/s\].
    pub travel_speed_mm_s: f64,
    /// Filament pulled back for each travel \[mm\].
    pub retract_mm: f64,
    /// Retract and prime speed \[mm/s\].
    pub retract_speed_mm_s: f64,
    /// Nozzle lift for each travel \[mm\].
    pub z_hop_mm: f64,
    /// Spar ends stop this many bead widths inside the skin (notes: infillOverlap k = 0.6).
    pub spar_overlap: f64,
    /// Bed size in X \[mm\]; the section is centred on the bed.
    pub bed_x_mm: f64,
    /// Bed size in Y \[mm\].
    pub bed_y_mm: f64,
    /// Hinge line chord fraction x_h (Fig. 5: 0.8).
    pub hinge_x_over_c: f64,
    /// Hinge height as a fraction of the local thickness above the lower surface (notes:
    /// p_z = 1, the upper surface).
    pub hinge_z_over_t: f64,
}

/// What a stroke builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The airfoil outline (skin).
    Perimeter,
    /// One spar: a chord-normal line between the skins.
    Spar,
    /// The first-layer solid infill (rib).
    Rib,
}

/// One continuous deposit polyline at one feed.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    /// What it builds.
    pub role: Role,
    /// Machine points (X, Y, Z) \[mm\].
    pub points: Vec<[f64; 3]>,
    /// Feed \[mm/s\].
    pub feed_mm_s: f64,
}

impl Stroke {
    /// Polyline length \[mm\].
    pub fn length_mm(&self) -> f64 {
        cell_geometry::polyline_length3(&self.points)
    }
}

/// One layer of a section.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Layer index within the section (0 is on the bed).
    pub index: u32,
    /// Nozzle height (top of this layer) \[mm\].
    pub z_mm: f64,
    /// Bead height of this layer \[mm\].
    pub height_mm: f64,
    /// Spanwise y of the layer \[mm\].
    pub y_mm: f64,
    /// Strokes in print order: perimeter first.
    pub strokes: Vec<Stroke>,
}

/// The wing geometry the layers are cut from: chord and geometric twist per LLT station.
#[derive(Debug, Clone, PartialEq)]
pub struct Planform {
    /// Span b \[mm\].
    pub span_mm: f64,
    /// Chord per station \[mm\] (stations at y/b = −½ + (j + ½)/n).
    pub chord_mm: Vec<f64>,
    /// Geometric section angle per station, nose up positive \[rad\] (LLT α + α_L0).
    pub twist_rad: Vec<f64>,
}

impl Planform {
    /// Chord and twist at spanwise y (linear between stations, ends held).
    pub fn at(&self, y_mm: f64) -> (f64, f64) {
        let n = self.chord_mm.len();
        let s = (y_mm / self.span_mm + 0.5) * n as f64 - 0.5;
        if s <= 0.0 {
            return (self.chord_mm[0], self.twist_rad[0]);
        }
        if s >= (n - 1) as f64 {
            return (self.chord_mm[n - 1], self.twist_rad[n - 1]);
        }
        let i = s.floor() as usize;
        let t = s - i as f64;
        let lerp = |v: &[f64]| v[i] + (v[i + 1] - v[i]) * t;
        (lerp(&self.chord_mm), lerp(&self.twist_rad))
    }
}

/// The layers of one section (Algorithm 2 lines 4–15).
///
/// Layer count n = ⌈(b_sect − h₀)/h⌉ + 1 (notes); layer k sits at Z = h₀ + k·h (the last may
/// overshoot the section top by less than h) and takes chord, twist and spars at y = y_bed ±
/// Z. Each layer: the perimeter (the transformed airfoil points, no offset, in the direction
/// TE → lower → LE → upper → TE, closed), then on layer 0 a serpentine rib of chord-normal
/// lines at pitch w, TE → LE (deposit links instead of the repo's G0 links: one continuous
/// stroke, no retracts), on the others one stroke per spar, alternating the end they start
/// from. Spar and rib lines stop `spar_overlap`·w inside each skin and are left out where that
/// leaves no line.
///
/// **Order (fewer travel moves).** Layer 0's perimeter starts at the TE. Every later layer
/// starts where the one below ended: its perimeter starts (and closes) at the outline point
/// nearest the previous layer's last point (the seam: a point inserted on the outline's edge,
/// so the outline is unchanged), and its spars run from the end of the spar row (TE-most or
/// LE-most spar, upper or lower end) nearest that seam to the other. So layers alternate
/// TE → LE and LE → TE, the seam sits at the front or rear spar's junction with the skin, and
/// no layer travels back a chord to a fixed start (the repo's and our first order did: on the
/// Table 2 root section 317 mm of travel a layer).
///
/// Section transform (notes, per-layer transform): x' = x − x_h, z' = z − z_LS(x_h) −
/// p_z·τ(x_h); scale by c; rotate nose up by the twist; mirror x on the right wing; the hinge
/// goes to X = X_bed/2 ∓ c_max(½ − x_h), Y = Y_bed/2, with c_max the section's largest chord,
/// so the hinge line is one vertical line.
pub fn section_layers(
    perimeter: &[Point2<f64>],
    surf: &SurfaceFunctions,
    planform: &Planform,
    spars: &SparLayout,
    section: &Section,
    p: &BuildParams,
) -> Vec<Layer> {
    let h0 = p.first_layer_height_mm;
    let height = section.height_mm();
    let n_layers = ((height - h0) / p.layer_height_mm).ceil().max(0.0) as usize + 1;
    let zs: Vec<f64> = (0..n_layers)
        .map(|k| h0 + k as f64 * p.layer_height_mm)
        .collect();
    let y_of = |z: f64| section.y_bed_mm + section.direction() * z;
    let c_max = zs
        .iter()
        .map(|&z| planform.at(y_of(z)).0)
        .fold(0.0, f64::max);
    let mirror = section.side == Side::Right;
    let sign = if mirror { -1.0 } else { 1.0 };
    let hinge = Point2::new(
        0.5 * p.bed_x_mm - sign * c_max * (0.5 - p.hinge_x_over_c),
        0.5 * p.bed_y_mm,
    );
    let xh = p.hinge_x_over_c;
    let zh = surf.z_lower(xh) + p.hinge_z_over_t * surf.thickness(xh);
    let w = p.extrusion_width_mm;
    let mut previous_end: Option<[f64; 3]> = None;
    zs.iter()
        .enumerate()
        .map(|(k, &z)| {
            let y = y_of(z);
            let (c, twist) = planform.at(y);
            let (sin, cos) = twist.sin_cos();
            let to_machine = |x: f64, zz: f64| {
                let (u, v) = ((x - xh) * c, (zz - zh) * c);
                let (u, v) = (u * cos + v * sin, -u * sin + v * cos);
                [hinge.x + sign * u, hinge.y + v, z]
            };
            let first = k == 0;
            let speed = |s: f64| {
                if first {
                    s.min(p.first_layer_speed_mm_s)
                } else {
                    s
                }
            };
            let mut strokes = Vec::new();
            let mut outline: Vec<[f64; 3]> = perimeter
                .iter()
                .rev()
                .map(|q| to_machine(q.x, q.y))
                .collect();
            if let Some(end) = previous_end {
                outline = seam_nearest(&outline, end);
            }
            outline.push(outline[0]);
            let seam = outline[0];
            strokes.push(Stroke {
                role: Role::Perimeter,
                points: outline,
                feed_mm_s: speed(p.perimeter_speed_mm_s),
            });
            // A chord-normal line at x between the skins, or None if the section is too thin.
            let inset = p.spar_overlap * w / c;
            let line = |x: f64, from_upper: bool| {
                let (top, bottom) = (surf.z_upper(x) - inset, surf.z_lower(x) + inset);
                (top - bottom > 1e-9).then(|| {
                    let (a, b) = (to_machine(x, top), to_machine(x, bottom));
                    if from_upper {
                        [a, b]
                    } else {
                        [b, a]
                    }
                })
            };
            if first {
                let pitch = w / c;
                let mut rib = Vec::new();
                let mut x = 1.0 - 0.5 * pitch;
                let mut upper = true;
                while x > 0.0 {
                    if let Some(l) = line(x, upper) {
                        rib.extend(l);
                        upper = !upper;
                    }
                    x -= pitch;
                }
                if rib.len() >= 2 {
                    strokes.push(Stroke {
                        role: Role::Rib,
                        points: rib,
                        feed_mm_s: speed(p.solid_infill_speed_mm_s),
                    });
                }
            } else {
                let mut xs = spars.at(y / planform.span_mm);
                xs.sort_by(|a, b| b.total_cmp(a));
                // Each spar as (upper end, lower end), TE → LE; then the row walked from the
                // end nearest the seam (ties keep TE → LE from the upper skin).
                let mut row: Vec<[[f64; 3]; 2]> =
                    xs.into_iter().filter_map(|x| line(x, true)).collect();
                let gap = |q: [f64; 3]| cell_geometry::distance3(q, seam);
                let (te_first, upper_first) =
                    [(true, true), (true, false), (false, true), (false, false)]
                        .into_iter()
                        .filter(|_| !row.is_empty())
                        .min_by(|a, b| {
                            let first = |(te, up): (bool, bool)| {
                                let s = if te { row[0] } else { row[row.len() - 1] };
                                gap(s[usize::from(!up)])
                            };
                            first(*a).total_cmp(&first(*b))
                        })
                        .unwrap_or((true, true));
                if !te_first {
                    row.reverse();
                }
                let mut upper = upper_first;
                for [a, b] in row {
                    strokes.push(Stroke {
                        role: Role::Spar,
                        points: if upper { vec![a, b] } else { vec![b, a] },
                        feed_mm_s: speed(p.infill_speed_mm_s),
                    });
                    upper = !upper;
                }
            }
            previous_end = strokes
                .last()
                .and_then(|s: &Stroke| s.points.last().copied());
            Layer {
                index: k as u32,
                z_mm: z,
                height_mm: if first { h0 } else { p.layer_height_mm },
                y_mm: y,
                strokes,
            }
        })
        .collect()
}

/// `ring` (vertices, closing edge implied) started at the point of its boundary nearest to
/// `near` in XY: that point inserted on its edge (unless it is a vertex) and the vertices
/// rotated to follow it, in the same direction (an empty ring stays empty).
fn seam_nearest(ring: &[[f64; 3]], near: [f64; 3]) -> Vec<[f64; 3]> {
    let n = ring.len();
    let xy = |q: [f64; 3]| [q[0], q[1]];
    let Some((edge, foot)) = (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let f = cell_geometry::closest_point_on_segment(xy(near), xy(a), xy(b));
            (i, [f.x, f.y, a[2]])
        })
        .min_by(|a, b| {
            let d = |f: [f64; 3]| (f[0] - near[0]).hypot(f[1] - near[1]);
            d(a.1).total_cmp(&d(b.1))
        })
    else {
        return Vec::new();
    };
    let same = |a: [f64; 3], b: [f64; 3]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9;
    let after = (edge + 1) % n;
    let (start, insert) = if same(foot, ring[edge]) {
        (edge, false)
    } else if same(foot, ring[after]) {
        (after, false)
    } else {
        (after, true)
    };
    let mut out = Vec::with_capacity(n + 1);
    if insert {
        out.push(foot);
    }
    out.extend((0..n).map(|j| ring[(start + j) % n]));
    out
}

/// What a [`Move`] does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveKind {
    /// Extruding along a stroke of this role.
    Deposit(Role),
    /// A rapid between strokes (filament retracted; nozzle lifted where it crosses a wall).
    Travel,
    /// Filament pulled back (E only).
    Retract,
    /// Filament pushed back (E only).
    Prime,
    /// Nozzle lifted by the Z-hop (Z only).
    Lift,
    /// Nozzle lowered back (Z only).
    Lower,
}

/// One machine move: where it ends, at what feed, and the absolute filament position E.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// What the move does.
    pub kind: MoveKind,
    /// End point (X, Y, Z) \[mm\].
    pub to: [f64; 3],
    /// Feed \[mm/s\] (filament speed for retract/prime).
    pub feed_mm_s: f64,
    /// Absolute E after the move \[mm of filament\].
    pub e_mm: f64,
}

/// Filament cross-section π d_f²/4 \[mm²\].
pub fn filament_area_mm2(p: &BuildParams) -> f64 {
    std::f64::consts::PI * p.filament_diameter_mm.powi(2) / 4.0
}

/// The layers as machine moves with absolute E (Algorithm 2 lines 8–15, notes' G-code
/// details): each deposit move pushes ΔE = w·h·L/(π d_f²/4) (the notes' FlowMult 1.25 ≈ 4/π
/// over d_f² is the same thing with the π/4 written out); between strokes the filament is
/// retracted, moved at travel speed and primed. The nozzle is lifted by the Z-hop (and lowered
/// after) only where the travel crosses a stroke already printed in its layer
/// ([`cell_geometry::travel_crosses_polylines`], the emitter's `z_hop_only_when_crossing`
/// rule): a travel between spar ends inside the skin passes over nothing, and the climb to the
/// next layer passes above everything printed (its walls are those of the layer it climbs
/// to). Each lift and lower costs Marlin ≈ 0.25 s (Z at 5 mm/s, 100 mm/s²).
pub fn moves(layers: &[Layer], p: &BuildParams) -> Vec<Move> {
    let area = filament_area_mm2(p);
    let mut out: Vec<Move> = Vec::new();
    let mut e = 0.0;
    let xy = |q: &[f64; 3]| [q[0], q[1]];
    // The strokes printed so far in this layer: the walls at the nozzle's height (the climb
    // from the layer below passes above all of that layer's walls).
    let mut walls: Vec<Vec<[f64; 2]>> = Vec::new();
    for layer in layers {
        walls.clear();
        for s in &layer.strokes {
            let start = s.points[0];
            if let Some(last) = out.last().map(|m| m.to) {
                if last != start {
                    let lift = p.z_hop_mm > 0.0
                        && cell_geometry::travel_crosses_polylines(xy(&last), xy(&start), &walls);
                    e -= p.retract_mm;
                    out.push(Move {
                        kind: MoveKind::Retract,
                        to: last,
                        feed_mm_s: p.retract_speed_mm_s,
                        e_mm: e,
                    });
                    let up = |q: [f64; 3]| [q[0], q[1], q[2] + p.z_hop_mm];
                    if lift {
                        out.push(Move {
                            kind: MoveKind::Lift,
                            to: up(last),
                            feed_mm_s: p.travel_speed_mm_s,
                            e_mm: e,
                        });
                    }
                    out.push(Move {
                        kind: MoveKind::Travel,
                        to: if lift { up(start) } else { start },
                        feed_mm_s: p.travel_speed_mm_s,
                        e_mm: e,
                    });
                    if lift {
                        out.push(Move {
                            kind: MoveKind::Lower,
                            to: start,
                            feed_mm_s: p.travel_speed_mm_s,
                            e_mm: e,
                        });
                    }
                    e += p.retract_mm;
                    out.push(Move {
                        kind: MoveKind::Prime,
                        to: start,
                        feed_mm_s: p.retract_speed_mm_s,
                        e_mm: e,
                    });
                }
            } else {
                out.push(Move {
                    kind: MoveKind::Travel,
                    to: start,
                    feed_mm_s: p.travel_speed_mm_s,
                    e_mm: e,
                });
            }
            walls.push(s.points.iter().map(xy).collect());
            for w in s.points.windows(2) {
                e += p.extrusion_width_mm * layer.height_mm * cell_geometry::distance3(w[0], w[1])
                    / area;
                out.push(Move {
                    kind: MoveKind::Deposit(s.role),
                    to: w[1],
                    feed_mm_s: s.feed_mm_s,
                    e_mm: e,
                });
            }
        }
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::section::split;
    use cell_airfoil::Airfoil;

    fn setup() -> (Vec<Point2<f64>>, SurfaceFunctions, Planform, SparLayout) {
        let path = format!(
            "{}/../../config/airfoils/ag24.dat",
            env!("CARGO_MANIFEST_DIR")
        );
        let foil = Airfoil::load(path).unwrap().normalised();
        let surf = SurfaceFunctions::new(&foil).unwrap();
        // A tapered wing, 150 → 100 mm, 6° → 0° washout, spars at 0.1, x_τ, 0.6.
        let n = 20;
        let ys: Vec<f64> = (0..n).map(|j| -0.5 + (j as f64 + 0.5) / n as f64).collect();
        let planform = Planform {
            span_mm: 400.0,
            chord_mm: ys.iter().map(|y| 150.0 - 100.0 * y.abs()).collect(),
            twist_rad: ys
                .iter()
                .map(|y| (6.0 - 12.0 * y.abs()).to_radians())
                .collect(),
        };
        let x_tau = surf.x_max_thickness();
        let spars = SparLayout {
            y_over_b: ys.clone(),
            x_over_c: vec![vec![0.1, x_tau, 0.6]; n],
            m: vec![0.0; n],
            required_inertia_mm4: vec![0.0; n],
            provided_inertia_mm4: vec![0.0; n],
        };
        (foil.points().to_vec(), surf, planform, spars)
    }

    /// The build parameters the crate's unit tests share.
    pub(crate) fn params() -> BuildParams {
        BuildParams {
            extrusion_width_mm: 0.5,
            layer_height_mm: 0.2,
            first_layer_height_mm: 0.3,
            filament_diameter_mm: 1.75,
            perimeter_speed_mm_s: 40.0,
            infill_speed_mm_s: 40.0,
            solid_infill_speed_mm_s: 60.0,
            first_layer_speed_mm_s: 30.0,
            travel_speed_mm_s: 80.0,
            retract_mm: 0.8,
            retract_speed_mm_s: 35.0,
            z_hop_mm: 0.4,
            spar_overlap: 0.6,
            bed_x_mm: 220.0,
            bed_y_mm: 220.0,
            hinge_x_over_c: 0.8,
            hinge_z_over_t: 1.0,
        }
    }

    /// Point-in-polygon (even-odd) in XY of the closed perimeter (its repeated closing point
    /// adds a zero-length edge, which crosses nothing).
    fn inside(poly: &[[f64; 3]], q: [f64; 3]) -> bool {
        cell_geometry::point_in_ring_even_odd([q[0], q[1]], poly.iter().map(|p| [p[0], p[1]]))
    }

    #[test]
    fn layers_follow_the_planform_and_keep_the_hinge_line_straight() {
        let (perimeter, surf, planform, spars) = setup();
        let p = params();
        for section in split(400.0, 0.0, 100.0).unwrap() {
            let layers = section_layers(&perimeter, &surf, &planform, &spars, &section, &p);
            assert_eq!(layers.len(), ((100.0f64 - 0.3) / 0.2).ceil() as usize + 1);
            assert!((layers[0].z_mm - 0.3).abs() < 1e-12 && layers[0].height_mm == 0.3);
            // The hinge (x_h on the upper surface) lands on the same machine point every layer.
            let xh = p.hinge_x_over_c;
            let hinge: Vec<[f64; 2]> = layers
                .iter()
                .map(|l| {
                    let per = &l.strokes[0];
                    assert_eq!(per.role, Role::Perimeter);
                    assert_eq!(per.points.first(), per.points.last(), "closed perimeter");
                    assert!(per.points.iter().all(|q| q[2] == l.z_mm));
                    // The upper-surface vertex nearest to x_h (Selig index i; reversed in the
                    // ring, at n − 1 − i).
                    let n = perimeter.len();
                    let i = perimeter
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| *i <= n / 2)
                        .min_by(|a, b| (a.1.x - xh).abs().total_cmp(&(b.1.x - xh).abs()))
                        .unwrap()
                        .0;
                    // The stroke is that ring started at the seam (after an inserted seam
                    // point, if any); the open TE's gap, the edge farthest from the vertices'
                    // mean (they crowd the LE), runs from ring vertex n − 1 to ring vertex 0,
                    // which gives the rotation.
                    let ring = &per.points[per.points.len() - 1 - n..per.points.len() - 1];
                    let mean = ring.iter().fold([0.0; 3], |m, q| {
                        [m[0] + q[0] / n as f64, m[1] + q[1] / n as f64, m[2]]
                    });
                    let far = |m: usize| {
                        let (a, b) = (ring[m], ring[(m + 1) % n]);
                        cell_geometry::distance3(
                            [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, a[2]],
                            mean,
                        )
                    };
                    let gap = (0..n).max_by(|a, b| far(*a).total_cmp(&far(*b))).unwrap();
                    let q = ring[(n - 1 - i + gap + 1) % n];
                    [q[0], q[1]]
                })
                .collect();
            // Chord 150 → 100 mm: aligned on the LE instead, x_h would move by 0.8 × 50 = 40 mm.
            for k in 0..2 {
                let spread = hinge
                    .iter()
                    .map(|h| (h[k] - hinge[0][k]).abs())
                    .fold(0.0, f64::max);
                assert!(spread < 2.0, "hinge coordinate {k} varies by {spread} mm");
            }
            for l in &layers[1..] {
                let spar_count = l.strokes.iter().filter(|s| s.role == Role::Spar).count();
                assert_eq!(spar_count, 3, "layer {}", l.index);
                for s in &l.strokes[1..] {
                    assert!(
                        s.points.iter().all(|q| inside(&l.strokes[0].points, *q)),
                        "spar inside the skin"
                    );
                    assert!(s.feed_mm_s == 40.0);
                }
            }
            let rib = &layers[0].strokes[1];
            assert_eq!(rib.role, Role::Rib);
            assert!(rib.feed_mm_s == 30.0, "first layer speed");
            assert!(rib
                .points
                .iter()
                .all(|q| inside(&layers[0].strokes[0].points, *q)));
            // The rib fills the section: its length × w ≈ the airfoil area.
            let (c, _) = planform.at(layers[0].y_mm);
            let area = Airfoil::new("a", perimeter.clone()).unwrap().signed_area() * c * c;
            let filled = rib.length_mm() * p.extrusion_width_mm;
            assert!(
                (filled / area - 1.0).abs() < 0.15,
                "rib {filled} vs area {area}"
            );
        }
    }

    #[test]
    fn right_wing_is_mirrored_and_twist_raises_the_nose() {
        let (perimeter, surf, planform, spars) = setup();
        let p = params();
        let secs = split(400.0, 0.0, 100.0).unwrap();
        let right = secs.iter().find(|s| s.side == Side::Right).unwrap();
        let left = secs.iter().find(|s| s.side == Side::Left).unwrap();
        let rl = section_layers(&perimeter, &surf, &planform, &spars, right, &p);
        let ll = section_layers(&perimeter, &surf, &planform, &spars, left, &p);
        let (r, l) = (&rl[0].strokes[0].points, &ll[0].strokes[0].points);
        let le = perimeter.len()
            - 1
            - perimeter
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.x.total_cmp(&b.1.x))
                .unwrap()
                .0;
        // LE is at +X on the right wing, −X on the left; both are centred on the bed.
        assert!(r[le][0] > r[0][0] && l[le][0] < l[0][0]);
        assert!(((r[le][0] + r[0][0]) * 0.5 - 110.0).abs() < 20.0);
        // 6° nose up at the root: the LE sits above the TE.
        assert!(r[le][1] > r[0][1] && l[le][1] > l[0][1]);
    }

    #[test]
    fn each_layer_starts_where_the_last_ended_and_lifts_only_over_walls() {
        let (perimeter, surf, planform, spars) = setup();
        let p = params();
        let section = split(400.0, 0.0, 100.0).unwrap().remove(1);
        let layers = section_layers(&perimeter, &surf, &planform, &spars, &section, &p);
        let mv = moves(&layers, &p);
        for pair in layers.windows(2) {
            let end = *pair[0].strokes.last().unwrap().points.last().unwrap();
            let seam = pair[1].strokes[0].points[0];
            let first_spar = pair[1].strokes[1].points[0];
            // Spar ends sit 0.6 w = 0.3 mm inside the skin: a step up, not a trip back.
            let xy = |a: [f64; 3], b: [f64; 3]| (a[0] - b[0]).hypot(a[1] - b[1]);
            assert!(xy(end, seam) < 0.5, "layer {}", pair[1].index);
            // (Layer 0's rib ends at the LE, in front of every spar.)
            if pair[0].index > 0 {
                assert!(xy(seam, first_spar) < 0.5, "layer {}", pair[1].index);
            }
        }
        // Travel per layer: the spar row (0.1 c → 0.6 c) and the skin between its ends, not the
        // chord back to a fixed start (≈ 1.4 c a layer before).
        let mut travel = vec![0.0; layers.len()];
        let mut prev = mv[0].to;
        let mut layer = 0;
        for m in &mv {
            if let Some(k) = layers.iter().position(|l| l.z_mm == m.to[2]) {
                layer = k;
            }
            if m.kind == MoveKind::Travel {
                travel[layer] += (m.to[0] - prev[0]).hypot(m.to[1] - prev[1]);
            }
            prev = m.to;
        }
        for (l, t) in layers.iter().zip(&travel).skip(1) {
            let (c, _) = planform.at(l.y_mm);
            assert!(
                *t < 0.7 * c,
                "layer {}: {t:.1} mm of travel, chord {c:.1}",
                l.index
            );
        }
        // Every travel that is not lifted stays inside its layer's outline (sampled, by
        // point-in-ring: not the crossing test the moves use); this wing needs no lift.
        let outline_at = |z: f64| &layers.iter().find(|l| l.z_mm == z).unwrap().strokes[0];
        let mut lifted = 0;
        for w in mv.windows(2) {
            if w[1].kind == MoveKind::Lift {
                lifted += 1;
            }
            if w[1].kind != MoveKind::Travel || w[0].to[2] != w[1].to[2] {
                continue;
            }
            let (a, b) = (w[0].to, w[1].to);
            let outline = &outline_at(b[2]).points;
            for k in 1..100 {
                let t = f64::from(k) / 100.0;
                let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), b[2]];
                assert!(
                    inside(outline, q),
                    "travel {a:?} → {b:?} leaves the outline"
                );
            }
        }
        assert_eq!(lifted, 0);
    }

    #[test]
    fn a_travel_over_a_printed_stroke_is_lifted_and_the_others_are_not() {
        let p = params();
        let z = 0.5;
        let stroke = |role, points: &[[f64; 2]]| Stroke {
            role,
            points: points.iter().map(|q| [q[0], q[1], z]).collect(),
            feed_mm_s: 40.0,
        };
        // A square skin, a spar at x = 5, then one at x = 8 (its travel leaves the first spar's
        // end: no crossing), then one at x = 2 (its travel from x = 8 crosses the spar at 5).
        let layers = [Layer {
            index: 1,
            z_mm: z,
            height_mm: 0.2,
            y_mm: 0.0,
            strokes: vec![
                stroke(
                    Role::Perimeter,
                    &[
                        [0.0, 0.0],
                        [10.0, 0.0],
                        [10.0, 10.0],
                        [0.0, 10.0],
                        [0.0, 0.0],
                    ],
                ),
                stroke(Role::Spar, &[[5.0, 1.0], [5.0, 9.0]]),
                stroke(Role::Spar, &[[8.0, 9.0], [8.0, 1.0]]),
                stroke(Role::Spar, &[[2.0, 5.0], [2.0, 9.0]]),
            ],
        }];
        let mv = moves(&layers, &p);
        let kinds: Vec<MoveKind> = mv
            .iter()
            .map(|m| m.kind)
            .filter(|k| !matches!(k, MoveKind::Deposit(_)))
            .collect();
        use MoveKind::{Lift, Lower, Prime, Retract, Travel};
        assert_eq!(
            kinds,
            [
                vec![Travel],
                vec![Retract, Travel, Prime],
                vec![Retract, Travel, Prime],
                vec![Retract, Lift, Travel, Lower, Prime],
            ]
            .concat()
        );
        let travel = mv.iter().rfind(|m| m.kind == MoveKind::Travel).unwrap();
        assert_eq!(travel.to, [2.0, 5.0, z + p.z_hop_mm]);
        // Retracts and primes stay balanced: E ends at the deposited volume.
        let deposited: f64 = layers[0].strokes.iter().map(Stroke::length_mm).sum();
        let e = deposited * 0.5 * 0.2 / filament_area_mm2(&p);
        assert!((mv.last().unwrap().e_mm - e).abs() < 1e-12);
    }
}
