//! Print time the way a Marlin 2 printer spends it, and Pronterface's estimate beside it
//! (seed 002 Table 4: the paper's 2:10 came from Pronterface).
//!
//! **Marlin's planner** (`Marlin/src/module/planner.cpp`, Marlin 2.x, `_populate_block`,
//! `recalculate`, `calculate_trapezoid_for_block`), with junction deviation (the default since
//! Marlin 2.0: `CLASSIC_JERK` off) and no S-curve:
//!
//! 1. Each G0/G1 is a block of length L = |ΔXYZ|, or |ΔE| for an E-only move. Its nominal
//!    speed is the feed, scaled down so no axis exceeds its `max_feedrate` (M203).
//! 2. Its acceleration is the print acceleration (M204 P) for moves that extrude, the travel
//!    acceleration (M204 T) for XYZ moves without E, the retract acceleration (M204 R) for
//!    E-only moves; then lowered so no axis exceeds its `max_acceleration` (M201):
//!    a ≤ a_max,i·L/|Δ_i|.
//! 3. Junction speed between blocks (unit vectors over XYZE, θ the angle between them):
//!    v_j² = a_j·δ·sin(θ/2)/(1 − sin(θ/2)), a_j the acceleration along the junction vector
//!    (u − u_prev, normalised) within every axis' limit, δ the junction deviation
//!    (`JUNCTION_DEVIATION_MM`); for blocks under 1 mm that turn by less than 45°
//!    (`JD_HANDLE_SMALL_SEGMENTS`) also v_j² ≤ L·a_j/φ, φ the turn (at least 0.033 rad by
//!    Marlin's polynomial acos), the speed of the arc they approximate; a full reversal gets
//!    `MINIMUM_PLANNER_SPEED`; then v_j ≤ both blocks' nominal speeds.
//! 4. Look-ahead over the planner buffer (`BLOCK_BUFFER_SIZE`, one slot kept free): when a
//!    block starts, its entry speed is fixed, and its exit speed is the largest that both the
//!    forward pass (v_exit² ≤ v_entry² + 2aL) and the reverse pass over the blocks then in the
//!    buffer allow, the last buffered block ending at `MINIMUM_PLANNER_SPEED` (the planner
//!    must be able to stop there if nothing more arrives). A printer fed from SD or a fast
//!    host keeps the buffer full, which this assumes.
//! 5. Each block runs a trapezoid: accelerate from entry to nominal, cruise, decelerate to
//!    exit (a triangle when too short to reach nominal).
//!
//! Not modelled: heating and homing (M109, M190, G28: listed apart by [`GcodeRun`]), the
//! slowdown when the buffer drains (`SLOWDOWN`, `MIN_SEGMENT_TIME`), S-curve and linear
//! advance, step rounding.
//!
//! **Pronterface** (Printrun's `printrun/gcoder.py`, `GCode._preprocess`, the duration behind
//! `estimate_duration`): per G0/G1, t = L/F when F did not change; otherwise a fixed
//! acceleration of 2000 mm/s² between the previous and the new F; a move that reverses the XY
//! direction (dx·dx_prev + dy·dy_prev ≤ 0) starts from rest. L is the XY length, or |ΔZ| when
//! XY stays and the line names Z, or |ΔE| when XY stays and it names E but not Z. Z and E
//! speeds are not limited, and G2/G3 are not timed (nor followed: an axis the next G0/G1 names
//! is measured from the last G0/G1 that named it; one it does not name has not moved, so after
//! an arc a retract `G1 E…` takes |ΔE|, not the arc's XY).

use crate::layers::{Move, MoveKind};
/// The printer's motion settings (`Configuration.h` names), from the machine profile;
/// [`FirmwareMotion::MARLIN_2_DEFAULTS`] are Marlin 2's stock values.
pub use cell_profiles::FirmwareMotion;

/// One linear move as a planner sees it: ΔX, ΔY, ΔZ, ΔE \[mm\] at a feed \[mm/s\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Block {
    /// ΔX, ΔY, ΔZ, ΔE \[mm\].
    pub delta: [f64; 4],
    /// Requested feed \[mm/s\].
    pub feed_mm_s: f64,
    /// Written as G0 (Pronterface treats G0 and G1 alike; kept for the record).
    pub rapid: bool,
    /// A segment of a G2/G3 arc (Marlin plans it; Pronterface neither times it nor moves its
    /// idea of the position).
    pub arc: bool,
    /// The line set its feed with an F word (Pronterface inherits F only from G0/G1 lines).
    pub f_word: bool,
    /// The line wrote X, Y, Z, E: Pronterface measures an axis only from lines that name it,
    /// so an arc's travel stays pending until the next G0/G1 naming that axis.
    pub words: [bool; 4],
}

/// The blocks of a move list (E from the absolute `e_mm`), the first move from its own
/// position.
pub fn blocks_from_moves(moves: &[Move]) -> Vec<Block> {
    let mut prev = moves.first().map_or([0.0; 3], |m| m.to);
    let mut prev_e = 0.0;
    moves
        .iter()
        .map(|m| {
            let b = Block {
                delta: [
                    m.to[0] - prev[0],
                    m.to[1] - prev[1],
                    m.to[2] - prev[2],
                    m.e_mm - prev_e,
                ],
                feed_mm_s: m.feed_mm_s,
                rapid: false,
                arc: false,
                f_word: true,
                // The axes the emitter writes for the move.
                words: match m.kind {
                    MoveKind::Retract | MoveKind::Prime => [false, false, false, true],
                    MoveKind::Lift | MoveKind::Lower => [false, false, true, false],
                    MoveKind::Travel => [true, true, true, false],
                    MoveKind::Deposit(_) => [true; 4],
                },
            };
            prev = m.to;
            prev_e = m.e_mm;
            b
        })
        .collect()
}

/// A Marlin G-code program read for timing.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GcodeRun {
    /// Every G0/G1 in order (zero-length ones too: Pronterface counts their feed changes).
    pub blocks: Vec<Block>,
    /// G4 dwell time \[s\].
    pub dwell_s: f64,
    /// Heat-and-wait and homing commands (M109, M190, G28), not timed.
    pub waits: Vec<String>,
}

/// Why a G-code program could not be read for timing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GcodeTimeError {
    /// A word that is not a letter and a number.
    #[error("line {line}: cannot read `{word}`")]
    Word {
        /// 1-based line.
        line: usize,
        /// The word.
        word: String,
    },
    /// A move command this reader does not time (G5 splines, an arc without I/J or with R).
    #[error("line {line}: `{command}` is not timed (G0/G1, and G2/G3 with I and J)")]
    Unsupported {
        /// 1-based line.
        line: usize,
        /// The command.
        command: String,
    },
    /// A move before any feed was set.
    #[error("line {line}: a move with no feed set")]
    NoFeed {
        /// 1-based line.
        line: usize,
    },
}

/// The commands [`read_gcode`] reads; every other line takes no time.
const TIMED: [&str; 14] = [
    "G0", "G1", "G2", "G3", "G5", "G4", "G90", "G91", "M82", "M83", "G92", "M109", "M190", "G28",
];

/// Reads G0/G1 (modal F, which G0 shares with G1 on a Marlin printer outside laser/CNC mode),
/// G2/G3 in the XY plane with centre offsets I, J (cut into chords of at most
/// [`ARC_SEGMENT_MM`], as Marlin's `plan_arc` does, Z and E shared out evenly), G90/G91,
/// M82/M83, G92 and G4 from `text`; M109, M190 and G28 are listed as waits. Other commands
/// (temperatures without wait, fans, messages) take no time here.
///
/// # Errors
/// [`GcodeTimeError`] for an unreadable word, G5 or an arc without I/J, or a move with no feed.
pub fn read_gcode(text: &str) -> Result<GcodeRun, GcodeTimeError> {
    let mut run = GcodeRun::default();
    let mut pos = [0.0f64; 4];
    let (mut relative_xyz, mut relative_e) = (false, false);
    let mut feed: Option<f64> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let code = raw.split(';').next().unwrap_or("").trim();
        let first = code
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_ascii_uppercase();
        if !TIMED.contains(&first.as_str()) {
            // Messages (M117 text), temperatures without wait, fans: no motion, no time.
            continue;
        }
        if ["M109", "M190", "G28"].contains(&first.as_str()) {
            // Heat and wait, homing (G28 X Y takes bare axis letters): listed, not timed.
            run.waits.push(code.to_string());
            continue;
        }
        let mut words = Vec::new();
        for w in code.split_whitespace() {
            let mut chars = w.chars();
            let letter = chars.next().map(|c| c.to_ascii_uppercase());
            let value: Option<f64> = chars.as_str().parse().ok();
            match (letter, value) {
                (Some(l), Some(v)) if l.is_ascii_alphabetic() => words.push((l, v)),
                _ => {
                    return Err(GcodeTimeError::Word {
                        line,
                        word: w.to_string(),
                    })
                }
            }
        }
        let Some(&(letter, number)) = words.first() else {
            continue;
        };
        let axis = |l: char| words.iter().find(|(c, _)| *c == l).map(|(_, v)| *v);
        let command = format!("{letter}{number}");
        match command.as_str() {
            "G0" | "G1" => {
                if let Some(f) = axis('F') {
                    feed = Some(f / 60.0);
                }
                let mut delta = [0.0; 4];
                for (k, l) in ['X', 'Y', 'Z', 'E'].into_iter().enumerate() {
                    if let Some(v) = axis(l) {
                        let relative = if k == 3 { relative_e } else { relative_xyz };
                        let to = if relative { pos[k] + v } else { v };
                        delta[k] = to - pos[k];
                        pos[k] = to;
                    }
                }
                let moves = delta.iter().any(|d| *d != 0.0);
                let Some(f) = feed else {
                    if moves {
                        return Err(GcodeTimeError::NoFeed { line });
                    }
                    continue;
                };
                run.blocks.push(Block {
                    delta,
                    feed_mm_s: f,
                    rapid: letter == 'G' && number == 0.0,
                    arc: false,
                    f_word: axis('F').is_some(),
                    words: ['X', 'Y', 'Z', 'E'].map(|l| axis(l).is_some()),
                });
            }
            "G2" | "G3" => {
                if let Some(f) = axis('F') {
                    feed = Some(f / 60.0);
                }
                let (Some(i), Some(j), Some(f)) = (axis('I'), axis('J'), feed) else {
                    return Err(GcodeTimeError::Unsupported { line, command });
                };
                let from = pos;
                for (k, l) in ['X', 'Y', 'Z', 'E'].into_iter().enumerate() {
                    if let Some(v) = axis(l) {
                        let relative = if k == 3 { relative_e } else { relative_xyz };
                        pos[k] = if relative { pos[k] + v } else { v };
                    }
                }
                let clockwise = number == 2.0;
                run.blocks
                    .extend(arc_blocks(from, pos, [i, j], clockwise, f));
            }
            "G5" => {
                return Err(GcodeTimeError::Unsupported { line, command });
            }
            "G90" => (relative_xyz, relative_e) = (false, false),
            "G91" => (relative_xyz, relative_e) = (true, true),
            "M82" => relative_e = false,
            "M83" => relative_e = true,
            "G92" => {
                for (k, l) in ['X', 'Y', 'Z', 'E'].into_iter().enumerate() {
                    if let Some(v) = axis(l) {
                        pos[k] = v;
                    }
                }
            }
            "G4" => {
                run.dwell_s += axis('S').unwrap_or(0.0) + axis('P').unwrap_or(0.0) / 1000.0;
            }
            _ => {}
        }
    }
    Ok(run)
}

/// Marlin's arc segment length (`MAX_ARC_SEGMENT_MM`, Marlin 2.1 `Configuration_adv.h`) \[mm\].
pub const ARC_SEGMENT_MM: f64 = 1.0;

/// The chords of an arc from `from` to `to` about `from + centre` (XY; Z and E in equal
/// steps): the angle swept clockwise for G2, counter-clockwise for G3, a full turn when the ends
/// meet; ⌊length/[`ARC_SEGMENT_MM`]⌋ chords, at least one (Marlin's `plan_arc`).
fn arc_blocks(
    from: [f64; 4],
    to: [f64; 4],
    centre: [f64; 2],
    clockwise: bool,
    feed_mm_s: f64,
) -> Vec<Block> {
    use std::f64::consts::TAU;
    let c = [from[0] + centre[0], from[1] + centre[1]];
    let (r0, r1) = ([-centre[0], -centre[1]], [to[0] - c[0], to[1] - c[1]]);
    let radius = r0[0].hypot(r0[1]);
    let mut sweep = (r0[0] * r1[1] - r0[1] * r1[0]).atan2(r0[0] * r1[0] + r0[1] * r1[1]);
    if clockwise && sweep >= -1e-9 {
        sweep -= TAU;
    } else if !clockwise && sweep <= 1e-9 {
        sweep += TAU;
    }
    let flat = (sweep * radius).abs();
    let length = flat.hypot(to[2] - from[2]);
    let n = ((length / ARC_SEGMENT_MM).floor() as usize).max(1);
    let start = r0[1].atan2(r0[0]);
    let mut prev = from;
    (1..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            let p = if k == n {
                to
            } else {
                let a = start + sweep * t;
                [
                    c[0] + radius * a.cos(),
                    c[1] + radius * a.sin(),
                    from[2] + (to[2] - from[2]) * t,
                    from[3] + (to[3] - from[3]) * t,
                ]
            };
            let b = Block {
                delta: [
                    p[0] - prev[0],
                    p[1] - prev[1],
                    p[2] - prev[2],
                    p[3] - prev[3],
                ],
                feed_mm_s,
                rapid: false,
                arc: true,
                f_word: false,
                words: [true; 4],
            };
            prev = p;
            b
        })
        .collect()
}

/// One block ready for the look-ahead.
struct Planned {
    length: f64,
    accel: f64,
    nominal: f64,
    /// Largest entry speed² the junction allows.
    max_entry2: f64,
}

/// Motion time \[s\] of `blocks` on a Marlin 2 printer with `m` (the steps in the module doc).
/// Zero-length blocks take no time and leave the junction state as it was.
pub fn marlin_time_s(blocks: &[Block], m: &FirmwareMotion) -> f64 {
    let v_min2 = m.minimum_planner_speed_mm_s.powi(2);
    let mut planned: Vec<Planned> = Vec::with_capacity(blocks.len());
    let mut prev: Option<([f64; 4], f64)> = None;
    for b in blocks {
        let d = b.delta;
        let xyz = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let length = if xyz > 0.0 { xyz } else { d[3].abs() };
        if length <= 0.0 || b.feed_mm_s <= 0.0 {
            continue;
        }
        let unit = d.map(|v| v / length);
        // Step 1: the feed within every axis' max feedrate.
        let mut nominal = b.feed_mm_s;
        for (u, max) in unit.iter().zip(m.max_feedrate_mm_s) {
            if u.abs() * nominal > max {
                nominal = max / u.abs();
            }
        }
        // Step 2: the acceleration by kind, within every axis' max acceleration.
        let base = if xyz == 0.0 {
            m.retract_acceleration_mm_s2
        } else if d[3] != 0.0 {
            m.print_acceleration_mm_s2
        } else {
            m.travel_acceleration_mm_s2
        };
        let accel = limit_by_axes(base, &unit, &m.max_acceleration_mm_s2);
        // Step 3: the junction with the previous block.
        let max_entry2 = match prev {
            None => 0.0,
            Some((u_prev, nominal_prev)) => {
                let cos_theta = -(0..4).map(|k| u_prev[k] * unit[k]).sum::<f64>();
                let v2 = if cos_theta > 0.999_999 {
                    v_min2
                } else {
                    let cos_theta = cos_theta.max(-0.999_999);
                    let mut j = [0.0; 4];
                    for k in 0..4 {
                        j[k] = unit[k] - u_prev[k];
                    }
                    let norm = j.iter().map(|v| v * v).sum::<f64>().sqrt();
                    let j = j.map(|v| v / norm);
                    let a_j = limit_by_axes(accel, &j, &m.max_acceleration_mm_s2);
                    let sin_half = (0.5 * (1.0 - cos_theta)).sqrt();
                    let mut v2 = a_j * m.junction_deviation_mm * sin_half / (1.0 - sin_half);
                    if length < 1.0 && cos_theta < -std::f64::consts::FRAC_1_SQRT_2 {
                        // A short block turning by less than 45°: a curve of radius ≈ L/turn
                        // (JD_HANDLE_SMALL_SEGMENTS), the turn by Marlin's polynomial acos,
                        // which bottoms out at 0.033 rad on a straight line.
                        let turn = std::f64::consts::FRAC_PI_2 - asin_approx(-cos_theta);
                        v2 = v2.min(length * a_j / turn);
                    }
                    v2
                };
                v2.min(nominal * nominal).min(nominal_prev * nominal_prev)
            }
        };
        planned.push(Planned {
            length,
            accel,
            nominal,
            max_entry2,
        });
        prev = Some((unit, nominal));
    }
    // Steps 4–5: each block's exit from the buffer it starts with, then its trapezoid.
    let ahead = m.block_buffer_size.saturating_sub(1).max(1);
    let n = planned.len();
    let mut entry2 = 0.0;
    let mut t = 0.0;
    for i in 0..n {
        let end = (i + ahead).min(n);
        let mut exit2 = v_min2;
        for k in (i + 1..end).rev() {
            let p = &planned[k];
            exit2 = p.max_entry2.min(exit2 + 2.0 * p.accel * p.length);
        }
        let p = &planned[i];
        exit2 = exit2.min(entry2 + 2.0 * p.accel * p.length);
        if i + 1 == n {
            exit2 = exit2.min(v_min2);
        }
        t += trapezoid_time(p.length, p.nominal, entry2.sqrt(), exit2.sqrt(), p.accel);
        entry2 = exit2;
    }
    t
}

/// Marlin's MinMax polynomial for asin(t), t in \[0, 1\] (error ±0.033 rad).
fn asin_approx(t: f64) -> f64 {
    0.032843707
        + t * (-1.451838349
            + t * (29.66153956
                + t * (-131.1123477 + t * (262.8130562 + t * (-242.7199627 + t * 84.31466202)))))
}

/// `accel` lowered so that no axis of the unit vector `u` exceeds its limit.
fn limit_by_axes(accel: f64, u: &[f64; 4], max: &[f64; 4]) -> f64 {
    u.iter()
        .zip(max)
        .filter(|(c, _)| c.abs() > 1e-12)
        .fold(accel, |a, (c, m)| a.min(m / c.abs()))
}

/// Time of a move of length `l` from speed `v0` to `v1`, cruising at `v`, accelerating at `a`.
pub(crate) fn trapezoid_time(l: f64, v: f64, v0: f64, v1: f64, a: f64) -> f64 {
    let d_acc = (v * v - v0 * v0) / (2.0 * a);
    let d_dec = (v * v - v1 * v1) / (2.0 * a);
    if d_acc + d_dec <= l {
        (v - v0) / a + (v - v1) / a + (l - d_acc - d_dec) / v
    } else {
        // Triangle: the peak speed where accelerating and decelerating meet.
        let vp = ((2.0 * a * l + v0 * v0 + v1 * v1) / 2.0).sqrt();
        (vp - v0).max(0.0) / a + (vp - v1).max(0.0) / a
    }
}

/// Pronterface's duration \[s\] of `blocks` (Printrun `gcoder.py`, see the module doc), before
/// its truncation to whole seconds.
pub fn pronterface_time_s(blocks: &[Block]) -> f64 {
    const ACCELERATION: f64 = 2000.0;
    let (mut last_f, mut last_dx, mut last_dy) = (0.0f64, 0.0, 0.0);
    let mut total = 0.0;
    // gcoder neither times G2/G3 nor moves its position or feed for them: the next G0/G1 is
    // measured from where the last G0/G1 naming each axis ended and, without an F word, runs
    // at its feed.
    let mut skipped = [0.0; 4];
    let mut inherited_f = 0.0;
    for b in blocks {
        if b.arc {
            for (s, d) in skipped.iter_mut().zip(b.delta) {
                *s += d;
            }
            continue;
        }
        // An axis the line names is measured from where gcoder last saw it (before any arcs
        // since); one it does not name has not moved.
        let [dx, dy, dz, de] = [0, 1, 2, 3].map(|k| {
            if b.words[k] {
                b.delta[k] + std::mem::take(&mut skipped[k])
            } else {
                b.delta[k]
            }
        });
        let f = if b.f_word { b.feed_mm_s } else { inherited_f };
        inherited_f = f;
        if dx * last_dx + dy * last_dy <= 0.0 {
            last_f = 0.0;
        }
        let mut travel = dx.hypot(dy);
        if travel == 0.0 {
            travel = if b.words[2] {
                dz.abs()
            } else if b.words[3] {
                de.abs()
            } else {
                0.0
            };
        }
        total += if f == last_f {
            if f != 0.0 {
                travel / f
            } else {
                0.0
            }
        } else {
            let distance = 2.0 * ((last_f + f) * (f - last_f) * 0.5 / ACCELERATION).abs();
            if distance <= travel && last_f + f != 0.0 && f != 0.0 {
                2.0 * distance / (last_f + f) + (travel - distance) / f
            } else {
                2.0 * travel / (last_f + f)
            }
        };
        (last_dx, last_dy, last_f) = (dx, dy, f);
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(dx: f64, dy: f64, f: f64) -> Block {
        Block {
            delta: [dx, dy, 0.0, 0.0],
            feed_mm_s: f,
            rapid: false,
            arc: false,
            f_word: true,
            words: [true; 4],
        }
    }

    const M: FirmwareMotion = FirmwareMotion {
        travel_acceleration_mm_s2: 100.0,
        print_acceleration_mm_s2: 100.0,
        ..FirmwareMotion::MARLIN_2_DEFAULTS
    };

    #[test]
    fn a_straight_line_is_one_trapezoid_however_it_is_split() {
        // 100 mm at 10 mm/s, a = 100: 0.1 s up, 0.1 s down, 99 mm cruising.
        let one = marlin_time_s(&[line(100.0, 0.0, 10.0)], &M);
        assert!((one - 10.1).abs() < 1e-3, "{one}");
        let split: Vec<Block> = (0..10).map(|_| line(10.0, 0.0, 10.0)).collect();
        assert!((marlin_time_s(&split, &M) - one).abs() < 1e-3);
        // A reversal stops the head: one more stop and start, v/a = 0.1 s.
        let back = [line(50.0, 0.0, 10.0), line(-50.0, 0.0, 10.0)];
        assert!((marlin_time_s(&back, &M) - (one + 0.1)).abs() < 1e-3);
    }

    #[test]
    fn the_buffer_limits_the_look_ahead() {
        // 100 moves of 2 mm in a line at 100 mm/s, a = 100: with the whole line planned, one
        // trapezoid (1 s up, 1 s down, 100 mm cruising: 3 s). The 16-block buffer sees 14
        // blocks (28 mm) past the running one and must be able to stop there, so the head
        // never passes v = sqrt(2·100·28) ≈ 75 mm/s.
        let blocks: Vec<Block> = (0..100).map(|_| line(2.0, 0.0, 100.0)).collect();
        let big = FirmwareMotion {
            block_buffer_size: 1000,
            ..M
        };
        assert!((marlin_time_s(&blocks, &big) - 3.0).abs() < 1e-3);
        let t = marlin_time_s(&blocks, &M);
        let v = (2.0f64 * 100.0 * 28.0).sqrt();
        let capped = trapezoid_time(200.0, v, 0.0, 0.0, 100.0);
        assert!(t > 3.1 && (t - capped).abs() < 0.05, "{t} vs {capped}");
        // Short straight blocks: the arc rule caps them at v² = L·a/0.033.
        let short: Vec<Block> = (0..400).map(|_| line(0.5, 0.0, 100.0)).collect();
        let t = marlin_time_s(&short, &big);
        let v = (0.5 * 100.0 / (std::f64::consts::FRAC_PI_2 - asin_approx(1.0))).sqrt();
        assert!(v < 40.0 && (t - trapezoid_time(200.0, v, 0.0, 0.0, 100.0)).abs() < 0.05);
    }

    #[test]
    fn axis_limits_slow_z_and_e() {
        // A 0.4 mm Z-hop asked at 80 mm/s runs at Z's 5 mm/s under Z's 100 mm/s²: 0.125 mm up,
        // 0.125 mm down, 0.15 mm cruising: 2·0.05 + 0.03 s.
        let hop = Block {
            delta: [0.0, 0.0, 0.4, 0.0],
            feed_mm_s: 80.0,
            rapid: true,
            arc: false,
            f_word: true,
            words: [false, false, true, false],
        };
        let t = marlin_time_s(&[hop], &FirmwareMotion::MARLIN_2_DEFAULTS);
        assert!((t - 0.13).abs() < 1e-3, "{t}");
        // A 0.8 mm retract at 35 mm/s is held to E's 25 mm/s at the retract acceleration.
        let retract = Block {
            delta: [0.0, 0.0, 0.0, -0.8],
            feed_mm_s: 35.0,
            rapid: false,
            arc: false,
            f_word: true,
            words: [false, false, false, true],
        };
        let t = marlin_time_s(&[retract], &FirmwareMotion::MARLIN_2_DEFAULTS);
        let expect = 2.0 * 25.0 / 3000.0 + (0.8 - 625.0 / 3000.0) / 25.0;
        assert!((t - expect).abs() < 1e-4, "{t} vs {expect}");
    }

    #[test]
    fn junction_deviation_sets_the_corner_speed() {
        // A 90° corner: v² = a·δ·sin45°/(1 − sin45°) = 100 · 0.013 · 2.414 → 1.77 mm/s.
        let corner = [line(50.0, 0.0, 10.0), line(0.0, 50.0, 10.0)];
        let v = (100.0 * 0.013 * (0.5f64).sqrt() / (1.0 - (0.5f64).sqrt())).sqrt();
        let one_leg = trapezoid_time(50.0, 10.0, 0.0, v, 100.0);
        let t = marlin_time_s(&corner, &M);
        // (Both ends stop at the minimum planner speed, 0.05 mm/s, not 0.)
        assert!((t - 2.0 * one_leg).abs() < 1e-3, "{t}");
    }

    #[test]
    fn pronterface_port_follows_gcoder() {
        // Same feed, same direction: L/F; a feed change accelerates at 2000 mm/s².
        let t = pronterface_time_s(&[line(10.0, 0.0, 10.0), line(10.0, 0.0, 10.0)]);
        // First move starts from rest (last_f = 0): distance = 2·(10·10/2)/2000 = 0.05 mm.
        let first = 2.0 * 0.05 / 10.0 + (10.0 - 0.05) / 10.0;
        assert!((t - (first + 1.0)).abs() < 1e-12, "{t}");
        // A reversal restarts from rest.
        let back = pronterface_time_s(&[line(10.0, 0.0, 10.0), line(-10.0, 0.0, 10.0)]);
        assert!((back - 2.0 * first).abs() < 1e-12);
    }

    #[test]
    fn arcs_become_chords_of_at_most_a_millimetre() {
        // A half circle of radius 10 counter-clockwise from (10, 0) to (-10, 0) about the
        // origin, E 3 mm: 31.4 mm in 31 chords; Pronterface skips it and measures the next
        // G1 from (10, 0).
        let run = read_gcode("G1 X10 Y0 F600\nG3 X-10 Y0 I-10 J0 E3\nG1 X-10 Y5\n").unwrap();
        let arc: Vec<&Block> = run.blocks.iter().filter(|b| b.arc).collect();
        assert_eq!(arc.len(), 31);
        let sum = |k: usize| arc.iter().map(|b| b.delta[k]).sum::<f64>();
        assert!((sum(0) + 20.0).abs() < 1e-9 && sum(1).abs() < 1e-9 && (sum(3) - 3.0).abs() < 1e-9);
        let length: f64 = arc.iter().map(|b| b.delta[0].hypot(b.delta[1])).sum();
        assert!(
            (length - 10.0 * std::f64::consts::PI).abs() < 0.02,
            "{length}"
        );
        // Upper half (y ≥ 0) for counter-clockwise; clockwise would go through y < 0.
        let mut y = 0.0;
        for b in &arc {
            y += b.delta[1];
            assert!(y >= -1e-9);
        }
        let cw = read_gcode("G1 X10 Y0 F600\nG2 X-10 Y0 I-10 J0\n").unwrap();
        assert!(cw.blocks[1].delta[1] < 0.0);
        let full = read_gcode("G1 X10 Y0 F600\nG2 X10 Y0 I-10 J0\n").unwrap();
        assert_eq!(full.blocks.len(), 1 + 62, "a full turn: 62.8 mm");
        let p = pronterface_time_s(&run.blocks) - pronterface_time_s(&run.blocks[..1]);
        let after = line(-20.0, 5.0, 10.0);
        let expect =
            pronterface_time_s(&[run.blocks[0], after]) - pronterface_time_s(&run.blocks[..1]);
        assert!((p - expect).abs() < 1e-9, "{p} vs {expect}");
        // A retract right after the arc names no X/Y: gcoder times it by E alone (2.2 mm from
        // the last E it saw, before the arc; 35 mm/s from rest), not by the arc's 20 mm of XY,
        // which waits for the next line that names X or Y.
        let text = "G1 X10 Y0 F600\nG3 X-10 Y0 I-10 J0 E3\nG1 E2.2 F2100\nG1 X-10 Y5 F600\n";
        let run = read_gcode(text).unwrap();
        let from_rest = |l: f64, f: f64| {
            let d = f * f / 2000.0;
            2.0 * d / f + (l - d) / f
        };
        let first = pronterface_time_s(&run.blocks[..1]);
        let retract = pronterface_time_s(&run.blocks[..33]) - first;
        assert!((retract - from_rest(2.2, 35.0)).abs() < 1e-9, "{retract}");
        let rest = pronterface_time_s(&run.blocks) - first - retract;
        let expect = from_rest(20.0f64.hypot(5.0), 10.0);
        assert!((rest - expect).abs() < 1e-9, "{rest} vs {expect}");
    }

    #[test]
    fn gcode_reader_tracks_modes_and_feeds() {
        let text = "G90\nM82\nG92 E0\nM117 job x.y\nM109 S210\nG1 X10 Y0 F600 ; comment\nG0 X20\n\
                    G1 E-0.8 F2100\nM83\nG1 X30 E1.5\nG91\nG1 X5\nG4 P500\nG28 X Y\n";
        let run = read_gcode(text).unwrap();
        let d: Vec<[f64; 4]> = run.blocks.iter().map(|b| b.delta).collect();
        assert_eq!(
            d,
            vec![
                [10.0, 0.0, 0.0, 0.0],
                [10.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, -0.8],
                [10.0, 0.0, 0.0, 1.5],
                [5.0, 0.0, 0.0, 0.0],
            ]
        );
        assert_eq!(run.blocks[1].feed_mm_s, 10.0, "G0 keeps the modal F");
        assert!(run.blocks[1].rapid);
        assert_eq!(run.blocks[3].feed_mm_s, 35.0);
        assert_eq!(
            run.waits,
            vec!["M109 S210".to_string(), "G28 X Y".to_string()]
        );
        assert_eq!(run.dwell_s, 0.5);
        assert!(matches!(
            read_gcode("G1 X1 F60\nG2 X2 R1\n"),
            Err(GcodeTimeError::Unsupported { line: 2, .. })
        ));
        assert!(matches!(
            read_gcode("G1 X1\n"),
            Err(GcodeTimeError::NoFeed { line: 1 })
        ));
        assert!(matches!(
            read_gcode("G1 X1..2 F60\n"),
            Err(GcodeTimeError::Word { line: 1, .. })
        ));
    }
}
