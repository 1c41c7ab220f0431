//! G-code from a `Toolpath` for a profile's dialect.
//!
//! The program is: a header comment, the profile's start lines, a rapid (G0) to the first
//! point, power on with the first point's value and the pre-heat dwell, one G1 per point that
//! moves (zero-length moves where segments meet are dropped), power off, the end lines and M2.
//!
//! **Feeds.** G94: F = feed × 60 (mm/min). G93 (inverse time): F = 1 / duration in minutes,
//! with the duration max(‖ΔXY‖, ‖ΔUV‖) / feed: the `Toolpath` feed of a 4-axis hot-wire point is
//! the speed of the carriage that moves farther, so both carriages finish the move together.
//!
//! **Power.** `S` = power × `s_per_unit`, written on the power-on line and again on any G1 whose
//! rounded value differs from the last one written.
//!
//! **Axes.** Primary x, y (and z where the profile maps it) and secondary x, y as the profile's
//! u, v letters. A toolpath without secondary points on a 4-axis profile is a straight cut:
//! both carriages follow the primary points. Secondary points on a profile without u, v are
//! accepted only when they equal the primary ones.
//!
//! **User text** (the job id) goes only into the header comment, reduced to a safe character
//! set, so no text can close the comment and inject a command.

use std::fmt::Write as _;

use cell_msgs::{Toolpath, ToolpathSegment};
use cell_profiles::{Dialect, FeedMode, GcodeSettings, MachineProfile, Units};

use crate::EmitError;

/// One checked point of the program.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pose {
    primary: [f64; 3],
    secondary: [f64; 2],
    feed_mm_s: f64,
    power: f64,
    travel: bool,
    segment: usize,
    point: usize,
}

/// The G-code program for `toolpath` on `profile` (module docs). `job_id` goes into the header
/// comment, sanitised.
///
/// # Errors
/// A profile without a `gcode` section; a non-finite value, a feed ≤ 0 or a per-point array of
/// the wrong length (naming segment and point); an axis the profile does not map; a position
/// outside the machine's travel.
pub fn emit(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    job_id: &str,
) -> Result<String, EmitError> {
    let g = profile
        .gcode
        .as_ref()
        .ok_or_else(|| EmitError::MissingSection {
            profile: profile.name.clone(),
            section: "gcode",
        })?;
    let poses = poses(toolpath, profile, g)?;
    let mut out = String::new();
    let comment = |text: &str| match g.dialect {
        Dialect::Marlin => format!("; {text}"),
        _ => format!("({text})"),
    };
    let _ = writeln!(
        out,
        "{}",
        comment(&format!(
            "cellsuite emitter: job {}, profile {}",
            sanitise(job_id),
            sanitise(&profile.name)
        ))
    );
    let _ = writeln!(out, "{}", modal_line(g));
    for line in &g.program_start {
        let _ = writeln!(out, "{}", fill_template(line, job_id, &profile.name));
    }
    let Some(first) = poses.first() else {
        let _ = writeln!(out, "M2");
        return Ok(out);
    };
    let _ = writeln!(out, "G0 {}", axes(g, first));
    let mut last_s = None;
    if let Some(p) = &g.power {
        let s = s_value(g, first.power);
        let _ = writeln!(out, "{} S{s}", p.on);
        last_s = Some(s);
        if g.preheat_dwell_s > 0.0 {
            let _ = writeln!(out, "{}", dwell(g.dialect, g.preheat_dwell_s));
        }
    }
    let mut at = *first;
    for pose in &poses[1..] {
        if same_place(&at, pose, g.decimals) {
            continue;
        }
        let mut line = format!(
            "{} {}",
            if pose.travel { "G0" } else { "G1" },
            axes(g, pose)
        );
        if !pose.travel {
            let _ = write!(line, " F{}", feed_word(g, &at, pose));
        }
        if g.power.is_some() {
            let s = s_value(g, pose.power);
            if last_s.as_ref() != Some(&s) {
                let _ = write!(line, " S{s}");
                last_s = Some(s);
            }
        }
        let _ = writeln!(out, "{line}");
        at = *pose;
    }
    if let Some(p) = &g.power {
        let _ = writeln!(out, "{}", p.off);
    }
    if g.feed_mode == FeedMode::InverseTime {
        // Leave the controller in the usual mode for whatever is run next.
        let _ = writeln!(out, "G94");
    }
    for line in &g.program_end {
        let _ = writeln!(out, "{}", fill_template(line, job_id, &profile.name));
    }
    if g.dialect != Dialect::Marlin {
        let _ = writeln!(out, "M2");
    }
    Ok(out)
}

/// Checks every segment and flattens it into poses.
fn poses(
    toolpath: &Toolpath,
    profile: &MachineProfile,
    g: &GcodeSettings,
) -> Result<Vec<Pose>, EmitError> {
    let w = &g.axis_words;
    let mut out = Vec::new();
    for (si, seg) in toolpath.segments.iter().enumerate() {
        let n = seg.points.len();
        for (what, len, may_be_empty) in [
            ("secondary_points", seg.secondary_points.len(), true),
            ("feed_mm_s", seg.feed_mm_s.len(), false),
            ("power", seg.power.len(), true),
        ] {
            if len != n && !(may_be_empty && len == 0) {
                return Err(EmitError::Length {
                    segment: si,
                    what,
                    expected: n,
                    found: len,
                });
            }
        }
        for (pi, p) in seg.points.iter().enumerate() {
            let s = seg.secondary_points.get(pi).copied().unwrap_or(*p);
            let feed = f64::from(seg.feed_mm_s[pi]);
            let power = seg.power.get(pi).map_or(0.0, |&v| f64::from(v));
            for (what, v) in [
                ("x", p.x),
                ("y", p.y),
                ("z", p.z),
                ("secondary x", s.x),
                ("secondary y", s.y),
                ("feed", feed),
                ("power", power),
            ] {
                if !v.is_finite() {
                    return Err(EmitError::NonFinite {
                        segment: si,
                        point: pi,
                        what,
                    });
                }
            }
            if feed <= 0.0 {
                return Err(EmitError::Feed {
                    segment: si,
                    point: pi,
                    feed_mm_s: seg.feed_mm_s[pi],
                });
            }
            if w.u.is_none() && (s.x != p.x || s.y != p.y) {
                return Err(EmitError::NoAxis {
                    profile: profile.name.clone(),
                    what: "the secondary (UV) carriage",
                });
            }
            let pose = Pose {
                primary: [p.x, p.y, p.z],
                secondary: [s.x, s.y],
                feed_mm_s: feed,
                power,
                travel: seg.kind == ToolpathSegment::KIND_TRAVEL,
                segment: si,
                point: pi,
            };
            profile
                .check_position(&positions(g, &pose))
                .map_err(|violation| EmitError::Envelope {
                    segment: si,
                    point: pi,
                    violation,
                })?;
            out.push(pose);
        }
    }
    Ok(out)
}

/// (axis letter, value) pairs a pose writes.
fn positions(g: &GcodeSettings, p: &Pose) -> Vec<(char, f64)> {
    let w = &g.axis_words;
    let mut out = vec![(w.x, p.primary[0]), (w.y, p.primary[1])];
    if let Some(z) = w.z {
        out.push((z, p.primary[2]));
    }
    if let (Some(u), Some(v)) = (w.u, w.v) {
        out.push((u, p.secondary[0]));
        out.push((v, p.secondary[1]));
    }
    out
}

fn axes(g: &GcodeSettings, p: &Pose) -> String {
    positions(g, p)
        .iter()
        .map(|(letter, v)| format!("{letter}{}", number(*v, g.decimals)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// True if `b` writes the same coordinates as `a` (a zero-length move once rounded).
fn same_place(a: &Pose, b: &Pose, decimals: usize) -> bool {
    let r = |v: f64| number(v, decimals);
    a.primary
        .iter()
        .zip(&b.primary)
        .all(|(x, y)| r(*x) == r(*y))
        && a.secondary
            .iter()
            .zip(&b.secondary)
            .all(|(x, y)| r(*x) == r(*y))
}

/// The F word for the move from `a` to `b` (module docs).
fn feed_word(g: &GcodeSettings, a: &Pose, b: &Pose) -> String {
    match g.feed_mode {
        FeedMode::UnitsPerMinute => number(b.feed_mm_s * 60.0, 3),
        FeedMode::InverseTime => {
            let dp = ((b.primary[0] - a.primary[0]).powi(2)
                + (b.primary[1] - a.primary[1]).powi(2)
                + (b.primary[2] - a.primary[2]).powi(2))
            .sqrt();
            let ds = if g.axis_words.u.is_some() {
                ((b.secondary[0] - a.secondary[0]).powi(2)
                    + (b.secondary[1] - a.secondary[1]).powi(2))
                .sqrt()
            } else {
                0.0
            };
            let minutes = dp.max(ds) / b.feed_mm_s / 60.0;
            // Enough significant digits that F × duration stays 1 to 1e-6 for short moves.
            number(1.0 / minutes, 4)
        }
    }
}

/// The modal words the program relies on, from the settings (never from a template).
fn modal_line(g: &GcodeSettings) -> String {
    let units = match g.units {
        Units::Mm => "G21",
        Units::Inch => "G20",
    };
    let feed = match g.feed_mode {
        FeedMode::UnitsPerMinute => "G94",
        FeedMode::InverseTime => "G93",
    };
    match g.dialect {
        Dialect::Marlin => format!("{units} G90"),
        Dialect::Grbl => format!("G17 {units} G90 {feed}"),
        // Arc centres incremental (I, J from the start point), as the fitter writes them.
        Dialect::Linuxcnc | Dialect::Mach3 => format!("G17 {units} G90 G91.1 {feed}"),
    }
}

/// A start/end template line with `{job}` and `{profile}` filled in, sanitised.
fn fill_template(line: &str, job_id: &str, profile: &str) -> String {
    line.replace("{job}", &sanitise(job_id))
        .replace("{profile}", &sanitise(profile))
}

fn s_value(g: &GcodeSettings, power: f64) -> String {
    let p = g.power.as_ref().map_or(1.0, |p| p.s_per_unit);
    number(power * p, g.power.as_ref().map_or(0, |p| p.s_decimals))
}

fn dwell(dialect: Dialect, seconds: f64) -> String {
    match dialect {
        // Marlin: P is milliseconds, S seconds.
        Dialect::Marlin => format!("G4 S{}", number(seconds, 3)),
        // GRBL, LinuxCNC and Mach3 (default setting): P in seconds.
        _ => format!("G4 P{}", number(seconds, 3)),
    }
}

/// `v` with `decimals` places, never `-0`.
fn number(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// User text reduced to letters, digits, space and `_ - . : /`, at most 64 characters: it
/// cannot end a comment or start a command in any dialect.
pub fn sanitise(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || " _-.:/".contains(c) {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_msgs::geometry_msgs::Point;

    fn seg(kind: u8, pts: &[(f64, f64)], feed: f32, power: f32) -> ToolpathSegment {
        ToolpathSegment {
            kind,
            points: pts.iter().map(|&(x, y)| Point { x, y, z: 0.0 }).collect(),
            feed_mm_s: vec![feed; pts.len()],
            power: vec![power; pts.len()],
            ..Default::default()
        }
    }

    fn toolpath(segments: Vec<ToolpathSegment>) -> Toolpath {
        Toolpath {
            segments,
            ..Default::default()
        }
    }

    #[test]
    fn straight_cut_on_the_four_axis_profile_in_inverse_time() {
        let profile = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        let tp = toolpath(vec![
            seg(
                ToolpathSegment::KIND_LEAD,
                &[(100.0, 50.0), (90.0, 50.0)],
                10.0,
                3.0,
            ),
            seg(
                ToolpathSegment::KIND_CUT,
                &[(90.0, 50.0), (90.0, 60.0)],
                5.0,
                2.5,
            ),
        ]);
        let text = emit(&tp, &profile, "job (1); M2").unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            [
                "(cellsuite emitter: job job _1__ M2, profile linuxcnc-xyuv)",
                "G17 G21 G90 G91.1 G93",
                "G0 X100.000 Y50.000 U100.000 V50.000",
                "M3 S300",
                "G4 P2.000",
                "G1 X90.000 Y50.000 U90.000 V50.000 F60.0000",
                "G1 X90.000 Y60.000 U90.000 V60.000 F30.0000 S250",
                "M5",
                "G94",
                "M2",
            ]
        );
    }

    #[test]
    fn bad_input_is_named_and_gives_no_program() {
        let profile = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        let mut tp = toolpath(vec![seg(0, &[(10.0, 10.0), (20.0, 10.0)], 5.0, 3.0)]);
        tp.segments[0].points[1].y = f64::NAN;
        let e = emit(&tp, &profile, "j").unwrap_err();
        assert_eq!(e.to_string(), "segment 0 point 1: y is not finite");
        let mut tp = toolpath(vec![seg(0, &[(10.0, 10.0), (20.0, 10.0)], 5.0, 3.0)]);
        tp.segments[0].feed_mm_s[1] = 0.0;
        assert!(matches!(
            emit(&tp, &profile, "j"),
            Err(EmitError::Feed {
                segment: 0,
                point: 1,
                ..
            })
        ));
        let tp = toolpath(vec![seg(0, &[(10.0, 10.0), (700.0, 10.0)], 5.0, 3.0)]);
        let e = emit(&tp, &profile, "j").unwrap_err();
        assert!(
            e.to_string().starts_with("segment 0 point 1: X = 700.000"),
            "{e}"
        );
        let two_axis = MachineProfile::resolve("grbl-xy").unwrap();
        let mut tp = toolpath(vec![seg(0, &[(10.0, 10.0), (20.0, 10.0)], 5.0, 3.0)]);
        tp.segments[0].secondary_points = tp.segments[0].points.clone();
        tp.segments[0].secondary_points[1].x = 15.0;
        assert!(matches!(
            emit(&tp, &two_axis, "j"),
            Err(EmitError::NoAxis { .. })
        ));
    }

    #[test]
    fn numbers_never_print_negative_zero_and_text_is_sanitised() {
        assert_eq!(number(-0.0001, 3), "0.000");
        assert_eq!(number(-1.5, 1), "-1.5");
        assert_eq!(sanitise("a(b)c;d\nM3 S9000"), "a_b_c_d_M3 S9000");
        assert_eq!(sanitise(&"x".repeat(100)).len(), 64);
    }
}
