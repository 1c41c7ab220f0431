//! Controller cutter compensation for sheet cutting: `G41`/`G42` with the kerf as the tool's
//! diameter, for profiles with `cutting.compensation: controller` (LinuxCNC only; the profile
//! check refuses it elsewhere).
//!
//! **Side.** The toolpath keeps the nominal contours; the controller offsets the tool by half
//! the kerf to the scrap side. `G41` puts the tool left of the path in the direction of travel,
//! `G42` right of it. A counter-clockwise contour has its inside on the left: a hole (scrap
//! inside) is cut with `G41`, an outer contour (scrap outside) with `G42`; clockwise contours
//! the other way round. The `Toolpath` message carries no contour role, so the role comes from
//! the path itself: the scrap side is where the lead-in starts (the pierce is on the scrap side
//! by construction).
//!
//! **Where it switches.** LinuxCNC offsets the tool on the *entry move*, the first move after
//! `G41`/`G42`, which must be longer than the tool radius (a line) or have a larger radius (an
//! arc), and ends half a kerf off the programmed point. Compensation goes on the lead-in's last
//! move onto the contour that qualifies (its last move, as a rule), else on the rapid to the
//! pierce; `G40` follows the lead-out, before the torch goes up, so the next rapid is the exit
//! move. A contour without a lead-in from the scrap side is an error naming its segment: the
//! entry move would end half a kerf off the rapid's direction at a pierce on the contour, into
//! the part (interpreted, a rapid arriving at a corner of the outline gouged it 0.4 mm deep
//! with a 1.5 mm kerf). So is a contour with neither a qualifying lead-in move nor rapid.
//!
//! **Tool.** The program selects tool 1 (`T1 M6`) after its start lines; the tool table
//! [`TOOL_TABLE_FILE`] written beside the program gives tool 1 the kerf as its diameter
//! (`T1 P1 D1.500`). LinuxCNC reads its tool table from the INI's `[EMCIO]TOOL_TABLE`: point it
//! at this file, or copy the `T1` line into the machine's table. The diameter is in the
//! profile's units, which must be the machine's (`[TRAJ]LINEAR_UNITS`).

use cell_msgs::{Toolpath, ToolpathSegment};
use cell_profiles::{Compensation, MachineProfile};

use crate::{EmitError, EmitOptions};

/// The tool table written beside a program with controller compensation.
pub const TOOL_TABLE_FILE: &str = "tool.tbl";

/// The tool whose diameter is the kerf.
pub const TOOL: u32 = 1;

/// The side of the path the tool is offset to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Left of the path in the direction of travel (`G41`).
    Left,
    /// Right of the path (`G42`).
    Right,
}

impl Side {
    /// The G-code word.
    pub fn word(self) -> &'static str {
        match self {
            Side::Left => "G41",
            Side::Right => "G42",
        }
    }
}

/// What a toolpath segment is to the compensation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Travel, or a segment of no contour.
    Other,
    /// The lead-in onto a contour cut on `side`.
    LeadIn(Side),
    /// A contour cut on `side`, after its lead-in.
    Cut(Side),
    /// A contour without a lead-in from its scrap side.
    Unentered,
    /// The lead-out after a contour.
    LeadOut,
}

impl Role {
    /// True for the first segment of a contour (its lead-in, or a cut without one).
    pub fn starts_contour(self) -> bool {
        matches!(self, Role::LeadIn(_) | Role::Unentered)
    }
}

/// The kerf for `toolpath` on `profile`, mm, when the program compensates on the controller:
/// a sheet-cutting toolpath and a profile with `cutting.compensation: controller`. The material
/// is the options', else the profile's default one.
///
/// # Errors
/// [`EmitError::Kerf`]: no material given or defaulted, or none in the kerf table.
pub fn controller_kerf_mm(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    options: &EmitOptions,
) -> Result<Option<f64>, EmitError> {
    let Some(cutting) = profile
        .cutting
        .as_ref()
        .filter(|c| c.compensation == Compensation::Controller)
    else {
        return Ok(None);
    };
    if toolpath.process != Toolpath::PROCESS_SHEET_CUT {
        return Ok(None);
    }
    let kerf_error = |reason: String| EmitError::Kerf {
        profile: profile.name.clone(),
        reason,
    };
    let material = options
        .material
        .as_ref()
        .or(cutting.default_material.as_ref())
        .ok_or_else(|| {
            kerf_error(
                "no material: give the job's, or set cutting.default_material in the profile"
                    .into(),
            )
        })?;
    cutting
        .kerf_mm(&material.material, material.thickness_mm)
        .map(Some)
        .map_err(kerf_error)
}

/// The tool table for `kerf` (in the program's length unit): tool [`TOOL`] in pocket 1 with the
/// kerf as its diameter, in LinuxCNC's format.
pub fn tool_table(kerf: f64, unit: &str) -> String {
    format!("T{TOOL} P1 D{kerf:.4} ;kerf {kerf:.4} {unit}, written by cellsuite for cutter compensation\n")
}

/// The role of every segment of `toolpath` (module docs).
pub fn roles(toolpath: &Toolpath) -> Vec<Role> {
    let segs = &toolpath.segments;
    let xy = |p: &cell_msgs::geometry_msgs::Point| [p.x, p.y];
    let meets = |a: Option<&cell_msgs::geometry_msgs::Point>,
                 b: Option<&cell_msgs::geometry_msgs::Point>| {
        matches!((a, b), (Some(a), Some(b)) if (a.x - b.x).hypot(a.y - b.y) < 1e-6)
    };
    let mut roles = vec![Role::Other; segs.len()];
    for (i, seg) in segs.iter().enumerate() {
        if seg.kind != ToolpathSegment::KIND_CUT {
            continue;
        }
        let ring: Vec<[f64; 2]> = seg.points.iter().map(xy).collect();
        let lead_in = i
            .checked_sub(1)
            .filter(|&k| {
                segs[k].kind == ToolpathSegment::KIND_LEAD
                    && roles[k] == Role::Other
                    && meets(segs[k].points.last(), seg.points.first())
            })
            // Where it starts is the scrap side, unless it starts on the contour.
            .and_then(|k| Some((k, xy(segs[k].points.first()?))))
            .filter(|&(_, pierce)| ring.len() >= 3 && distance_to_ring(pierce, &ring) > 1e-6);
        let Some((k, pierce)) = lead_in else {
            roles[i] = Role::Unentered;
            continue;
        };
        let ccw = signed_area(&ring) > 0.0;
        let side = if ccw == inside(pierce, &ring) {
            Side::Left
        } else {
            Side::Right
        };
        roles[k] = Role::LeadIn(side);
        roles[i] = Role::Cut(side);
        if let Some(next) = segs.get(i + 1) {
            if next.kind == ToolpathSegment::KIND_LEAD
                && meets(seg.points.last(), next.points.first())
            {
                roles[i + 1] = Role::LeadOut;
            }
        }
    }
    roles
}

/// Twice the signed area of a ring (closed implicitly): > 0 counter-clockwise.
fn signed_area(ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|k| {
            let (a, b) = (ring[k], ring[(k + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// Even-odd point-in-ring test (ray to +x).
fn inside(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let n = ring.len();
    let mut odd = false;
    for k in 0..n {
        let (a, b) = (ring[k], ring[(k + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
}

/// Shortest distance from `p` to the ring's edges.
fn distance_to_ring(p: [f64; 2], ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|k| {
            let (a, b) = (ring[k], ring[(k + 1) % n]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p[0] - a[0] - t * d[0]).hypot(p[1] - a[1] - t * d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// The compensation state of a program being written: the segments' roles, whether `G41`/`G42`
/// is in force, and the moves that could switch it on.
#[derive(Debug, Clone)]
pub(crate) struct Compensator {
    /// Tool radius (half the kerf), mm.
    radius_mm: f64,
    roles: Vec<Role>,
    /// `G41`/`G42` in force.
    active: bool,
    /// The last XY rapid of the current contour: (line index, length in mm).
    rapid: Option<(usize, f64)>,
    /// The feed moves of the current segment.
    moves: Vec<Move>,
    /// The side of the contour being cut.
    side: Side,
}

/// A feed move written into the program.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Move {
    /// Its line index.
    pub line: usize,
    /// The length of a line, or the radius of an arc, mm.
    pub size_mm: f64,
    /// An arc's direction: `Some(true)` counter-clockwise; `None` for a line.
    pub arc_ccw: Option<bool>,
}

impl Compensator {
    /// For `toolpath` with a kerf of `kerf_mm`.
    pub(crate) fn new(toolpath: &Toolpath, kerf_mm: f64) -> Self {
        Self {
            radius_mm: kerf_mm / 2.0,
            roles: roles(toolpath),
            active: false,
            rapid: None,
            moves: Vec::new(),
            side: Side::Left,
        }
    }

    /// A rapid written at line `line`, `length_mm` long in XY.
    pub(crate) fn rapid(&mut self, line: usize, length_mm: f64) {
        self.rapid = Some((line, length_mm));
    }

    /// A feed move written into the program.
    pub(crate) fn feed(&mut self, m: Move) {
        self.moves.push(m);
    }

    /// Before segment `segment` is written: `G40` if a new contour starts while compensation is
    /// still on (a contour reached without a travel move).
    pub(crate) fn before(&mut self, segment: usize) -> Option<&'static str> {
        self.moves.clear();
        let starts = self.roles.get(segment).is_some_and(|r| r.starts_contour());
        (starts && self.active).then(|| {
            self.active = false;
            "G40"
        })
    }

    /// After segment `segment` was written into `lines`: on a lead-in, `G41`/`G42` on its
    /// entry move (module docs); on every segment, the arcs it compensates checked.
    ///
    /// # Errors
    /// [`EmitError::NoLeadIn`] for a contour without a lead-in,
    /// [`EmitError::CompensationEntry`] when no move qualifies, [`EmitError::CompensationArc`]
    /// for an arc the controller cannot compensate.
    pub(crate) fn after(&mut self, segment: usize, lines: &mut [String]) -> Result<(), EmitError> {
        let side = match self.roles.get(segment).copied().unwrap_or(Role::Other) {
            Role::LeadIn(side) => side,
            Role::Unentered => return Err(EmitError::NoLeadIn { segment }),
            Role::Other => return Ok(()),
            Role::Cut(_) | Role::LeadOut => {
                self.rapid = None;
                return if self.active {
                    self.check_arcs(segment, &self.moves)
                } else {
                    Ok(())
                };
            }
        };
        // LinuxCNC compares in the program's rounded numbers: keep a margin of 0.001 mm.
        let qualifies = |size: f64| size > self.radius_mm + 1e-3;
        let on_lead_in = self.moves.iter().rposition(|m| qualifies(m.size_mm));
        let on_rapid = self.rapid.filter(|r| qualifies(r.1)).map(|r| r.0);
        let (entry, compensated) = match (on_lead_in, on_rapid) {
            (Some(k), _) => (self.moves[k].line, &self.moves[k + 1..]),
            (None, Some(line)) => (line, &self.moves[..]),
            (None, None) => {
                return Err(EmitError::CompensationEntry {
                    segment,
                    radius_mm: self.radius_mm,
                })
            }
        };
        self.side = side;
        self.check_arcs(segment, compensated)?;
        lines[entry] = format!("{} {}", side.word(), lines[entry]);
        self.active = true;
        self.rapid = None;
        Ok(())
    }

    /// LinuxCNC refuses to compensate an arc that curves round the tool's side with a radius
    /// no larger than the tool's ("Tool radius not less than arc radius with comp"): a hole or
    /// lead too small for the kerf.
    fn check_arcs(&self, segment: usize, moves: &[Move]) -> Result<(), EmitError> {
        let tool_inside = |ccw: bool| ccw == (self.side == Side::Left);
        match moves
            .iter()
            .find(|m| m.arc_ccw.is_some_and(tool_inside) && m.size_mm <= self.radius_mm + 1e-3)
        {
            Some(m) => Err(EmitError::CompensationArc {
                segment,
                arc_radius_mm: m.size_mm,
                radius_mm: self.radius_mm,
            }),
            None => Ok(()),
        }
    }

    /// At a travel move or the program's end: `G40` if compensation is on.
    pub(crate) fn off(&mut self) -> Option<&'static str> {
        self.rapid = None;
        std::mem::take(&mut self.active).then_some("G40")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_msgs::geometry_msgs::Point;

    fn seg(kind: u8, pts: &[[f64; 2]]) -> ToolpathSegment {
        ToolpathSegment {
            kind,
            points: pts.iter().map(|&[x, y]| Point { x, y, z: 0.0 }).collect(),
            feed_mm_s: vec![10.0; pts.len()],
            ..Default::default()
        }
    }

    fn square(x0: f64, y0: f64, size: f64, ccw: bool) -> Vec<[f64; 2]> {
        let mut s = vec![
            [x0, y0],
            [x0 + size, y0],
            [x0 + size, y0 + size],
            [x0, y0 + size],
            [x0, y0],
        ];
        if !ccw {
            s.reverse();
        }
        s
    }

    fn line(line: usize, size_mm: f64) -> Move {
        Move {
            line,
            size_mm,
            arc_ccw: None,
        }
    }

    const T: u8 = ToolpathSegment::KIND_TRAVEL;
    const C: u8 = ToolpathSegment::KIND_CUT;
    const L: u8 = ToolpathSegment::KIND_LEAD;

    #[test]
    fn the_side_follows_the_winding_and_the_scrap_side() {
        for ccw in [true, false] {
            let hole = square(40.0, 40.0, 20.0, ccw);
            let outer = square(0.0, 0.0, 100.0, ccw);
            let part = square(45.0, 45.0, 10.0, ccw);
            // Leads: into the hole from its middle, onto the outline from below it, onto a
            // part inside the hole from beside it (scrap outside it again).
            let tp = Toolpath {
                process: Toolpath::PROCESS_SHEET_CUT,
                segments: vec![
                    seg(T, &[[0.0, -20.0], [44.0, 44.0]]),
                    seg(L, &[[44.0, 44.0], part[0]]),
                    seg(C, &part),
                    seg(T, &[part[0], [50.0, 42.0]]),
                    seg(L, &[[50.0, 42.0], hole[0]]),
                    seg(C, &hole),
                    seg(L, &[hole[0], [42.0, 41.0]]),
                    seg(T, &[[42.0, 41.0], [0.0, -5.0]]),
                    seg(L, &[[0.0, -5.0], outer[0]]),
                    seg(C, &outer),
                    seg(T, &[outer[0], [0.0, -20.0]]),
                ],
                ..Default::default()
            };
            let (inside, outside) = if ccw {
                (Side::Left, Side::Right)
            } else {
                (Side::Right, Side::Left)
            };
            assert_eq!(
                roles(&tp),
                [
                    Role::Other,
                    Role::LeadIn(outside),
                    Role::Cut(outside),
                    Role::Other,
                    Role::LeadIn(inside),
                    Role::Cut(inside),
                    Role::LeadOut,
                    Role::Other,
                    Role::LeadIn(outside),
                    Role::Cut(outside),
                    Role::Other,
                ],
                "ccw {ccw}"
            );
        }
    }

    #[test]
    fn a_contour_without_a_lead_in_from_off_it_is_unentered() {
        let hole = square(40.0, 40.0, 20.0, true);
        let tp = Toolpath {
            process: Toolpath::PROCESS_SHEET_CUT,
            segments: vec![
                seg(T, &[[0.0, 0.0], hole[0]]),
                seg(C, &hole),
                // A "lead-in" that starts on the contour it enters.
                seg(L, &[[50.0, 40.0], [60.0, 40.0]]),
                seg(C, &square(50.0, 40.0, 10.0, true)),
            ],
            ..Default::default()
        };
        let r = roles(&tp);
        assert_eq!((r[1], r[3]), (Role::Unentered, Role::Unentered));
        let mut comp = Compensator::new(&tp, 1.5);
        comp.rapid(0, 56.0);
        assert_eq!(
            comp.after(1, &mut []),
            Err(EmitError::NoLeadIn { segment: 1 })
        );
    }

    #[test]
    fn the_entry_is_the_last_lead_in_move_longer_than_the_radius_else_the_rapid() {
        let hole = square(40.0, 40.0, 20.0, true);
        let tp = Toolpath {
            process: Toolpath::PROCESS_SHEET_CUT,
            segments: vec![
                seg(T, &[[0.0, 0.0], [50.0, 50.0]]),
                seg(L, &[[50.0, 50.0], hole[0]]),
                seg(C, &hole),
            ],
            ..Default::default()
        };
        let mut lines: Vec<String> = ["G0 X50 Y50", "G1 X45 Y42", "G1 X40 Y40.5", "G1 X40 Y40"]
            .map(String::from)
            .to_vec();
        let mut comp = Compensator::new(&tp, 1.5);
        comp.rapid(0, 70.7);
        assert_eq!(comp.before(1), None);
        comp.feed(line(1, 5.8));
        comp.feed(line(2, 0.6));
        comp.feed(line(3, 0.5));
        comp.after(1, &mut lines).unwrap();
        assert_eq!(lines[1], "G41 G1 X45 Y42");
        // A contour reached without a travel move switches the previous one off first.
        assert_eq!(comp.before(1), Some("G40"));
        assert_eq!(comp.off(), None);
        // No lead-in move long enough: the rapid carries it.
        let mut comp = Compensator::new(&tp, 1.5);
        comp.rapid(0, 70.7);
        comp.before(1);
        comp.feed(line(1, 0.7));
        comp.after(1, &mut lines).unwrap();
        assert_eq!(lines[0], "G41 G0 X50 Y50");
        assert_eq!(comp.off(), Some("G40"));
        // Neither: an error naming the segment.
        let mut comp = Compensator::new(&tp, 1.5);
        comp.rapid(0, 0.5);
        comp.before(1);
        comp.feed(line(1, 0.7));
        assert_eq!(
            comp.after(1, &mut lines),
            Err(EmitError::CompensationEntry {
                segment: 1,
                radius_mm: 0.75
            })
        );
        // An arc inside the tool's path no larger than the tool: the controller refuses it.
        let arc = |line, size_mm, ccw| Move {
            line,
            size_mm,
            arc_ccw: Some(ccw),
        };
        let mut comp = Compensator::new(&tp, 1.5);
        comp.rapid(0, 70.7);
        comp.before(1);
        comp.feed(arc(1, 0.7, true));
        assert_eq!(
            comp.after(1, &mut lines),
            Err(EmitError::CompensationArc {
                segment: 1,
                arc_radius_mm: 0.7,
                radius_mm: 0.75
            })
        );
        // The same arc the other way round has the tool outside it; and before the entry move
        // it is not compensated at all.
        for moves in [
            vec![arc(1, 0.7, false)],
            vec![arc(1, 0.7, true), line(2, 5.0)],
        ] {
            let mut comp = Compensator::new(&tp, 1.5);
            comp.rapid(0, 70.7);
            comp.before(1);
            for m in moves {
                comp.feed(m);
            }
            comp.after(1, &mut lines).unwrap();
            // On the cut that follows (counter-clockwise, tool on the left) it is refused.
            comp.before(2);
            comp.feed(arc(3, 0.7, true));
            assert!(matches!(
                comp.after(2, &mut lines),
                Err(EmitError::CompensationArc { segment: 2, .. })
            ));
        }
    }
}
