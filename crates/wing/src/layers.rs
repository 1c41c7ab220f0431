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
/// Z. Each layer: the perimeter (the transformed airfoil points, no offset, TE → lower → LE →
/// upper → TE, closed), then on layer 0 a serpentine rib of chord-normal lines at pitch w
/// (deposit links instead of the repo's G0 links: one continuous stroke, no retracts), on the
/// others one stroke per spar, TE → LE, alternating the end they start from. Spar and rib lines
/// stop `spar_overlap`·w inside each skin and are left out where that leaves no line.
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
            outline.push(outline[0]);
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
                let mut upper = true;
                for x in xs {
                    if let Some(l) = line(x, upper) {
                        strokes.push(Stroke {
                            role: Role::Spar,
                            points: l.to_vec(),
                            feed_mm_s: speed(p.infill_speed_mm_s),
                        });
                        upper = !upper;
                    }
                }
            }
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

/// What a [`Move`] does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveKind {
    /// Extruding along a stroke of this role.
    Deposit(Role),
    /// A rapid between strokes (nozzle lifted, filament retracted).
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
/// retracted, the nozzle lifted by the Z-hop, moved at travel speed, lowered and primed.
pub fn moves(layers: &[Layer], p: &BuildParams) -> Vec<Move> {
    let area = filament_area_mm2(p);
    let mut out: Vec<Move> = Vec::new();
    let mut e = 0.0;
    for layer in layers {
        for s in &layer.strokes {
            let start = s.points[0];
            if let Some(last) = out.last().map(|m| m.to) {
                if last != start {
                    e -= p.retract_mm;
                    out.push(Move {
                        kind: MoveKind::Retract,
                        to: last,
                        feed_mm_s: p.retract_speed_mm_s,
                        e_mm: e,
                    });
                    let up = |q: [f64; 3]| [q[0], q[1], q[2] + p.z_hop_mm];
                    out.push(Move {
                        kind: MoveKind::Lift,
                        to: up(last),
                        feed_mm_s: p.travel_speed_mm_s,
                        e_mm: e,
                    });
                    out.push(Move {
                        kind: MoveKind::Travel,
                        to: up(start),
                        feed_mm_s: p.travel_speed_mm_s,
                        e_mm: e,
                    });
                    out.push(Move {
                        kind: MoveKind::Lower,
                        to: start,
                        feed_mm_s: p.travel_speed_mm_s,
                        e_mm: e,
                    });
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
                    // The upper-surface vertex nearest to x_h (Selig index i; reversed in the stroke).
                    let i = perimeter
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| *i <= perimeter.len() / 2)
                        .min_by(|a, b| (a.1.x - xh).abs().total_cmp(&(b.1.x - xh).abs()))
                        .unwrap()
                        .0;
                    let q = per.points[perimeter.len() - 1 - i];
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
}
