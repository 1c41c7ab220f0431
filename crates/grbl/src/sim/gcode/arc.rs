//! G2/G3 arcs: the centre from the R word or the I/J/K offsets (GRBL's checks and `error:N`
//! codes), and the arc's length for the move's timing.
//!
//! In the arc plane (G17 XY, G18 ZX, G19 YZ) with (x, y) the chord from start to target:
//! - radius form: the centre lies on the chord's perpendicular bisector,
//!   o = ½ (x − y·h, y + x·h) with h = ∓√(4r² − x² − y²) / ‖(x, y)‖, the sign chosen by the
//!   direction and flipped for r < 0 (the longer arc); 4r² < x² + y² is `error:34`.
//! - offset form: the centre is (I, J) (or the plane's pair) from the start; start and end
//!   radii differing by more than 0.005 mm and more than 0.5 mm or 0.1 % is `error:33`.
//! - the swept angle θ is atan2 of the start and end radius vectors, taken clockwise for G2
//!   and anticlockwise for G3 (a full circle when start and end coincide, within 5 × 10⁻⁷ rad);
//!   the length is √((|θ|·r)² + Δlinear² + Σ Δother²), a helix through the other axes.

use std::f64::consts::PI;

use super::apply::Line;
use super::code::*;
use super::MotionMode;

/// Length (mm) of the arc from `start` to `target` in `plane` (0 = G17, 1 = G18, 2 = G19),
/// clockwise for [`MotionMode::ArcCw`]; marks the R or offset words used.
pub(super) fn arc_length(
    line: &mut Line<'_>,
    motion: MotionMode,
    plane: u8,
    start: &[f64],
    target: &[f64],
) -> Result<f64, u8> {
    let axes = line.axes;
    let unit = line.unit;
    let (a0, a1, lin) = match plane {
        0 => ('X', 'Y', 'Z'),
        1 => ('Z', 'X', 'Y'),
        _ => ('Y', 'Z', 'X'),
    };
    let idx = |c: char| axes.iter().position(|&a| a == c);
    let (Some(i0), Some(i1)) = (idx(a0), idx(a1)) else {
        return Err(UNSUPPORTED_COMMAND);
    };
    if line.axis_words[i0].is_none() && line.axis_words[i1].is_none() {
        return Err(NO_AXIS_WORDS_IN_PLANE);
    }
    let off_letter = |c: char| match c {
        'X' => 'I',
        'Y' => 'J',
        _ => 'K',
    };
    let x = target[i0] - start[i0];
    let y = target[i1] - start[i1];
    let (o0, o1);
    if let Some(r_word) = line.value('R') {
        line.use_word('R');
        if x == 0.0 && y == 0.0 {
            return Err(INVALID_TARGET);
        }
        let r = r_word * unit;
        let mut h = 4.0 * r * r - x * x - y * y;
        if h < 0.0 {
            return Err(ARC_RADIUS_ERROR);
        }
        h = -h.sqrt() / x.hypot(y);
        if motion == MotionMode::ArcCcw {
            h = -h;
        }
        if r < 0.0 {
            h = -h;
        }
        o0 = 0.5 * (x - y * h);
        o1 = 0.5 * (y + x * h);
    } else {
        let (w0, w1) = (line.value(off_letter(a0)), line.value(off_letter(a1)));
        if w0.is_none() && w1.is_none() {
            return Err(NO_OFFSETS_IN_PLANE);
        }
        line.use_word(off_letter(a0));
        line.use_word(off_letter(a1));
        o0 = w0.unwrap_or(0.0) * unit;
        o1 = w1.unwrap_or(0.0) * unit;
        let r_start = o0.hypot(o1);
        let r_end = (x - o0).hypot(y - o1);
        let delta = (r_end - r_start).abs();
        if delta > 0.005 && (delta > 0.5 || delta > 0.001 * r_start) {
            return Err(INVALID_TARGET);
        }
    }
    let radius = o0.hypot(o1);
    let (rs0, rs1) = (-o0, -o1);
    let (rt0, rt1) = (x - o0, y - o1);
    let mut travel = (rs0 * rt1 - rs1 * rt0).atan2(rs0 * rt0 + rs1 * rt1);
    const EPS: f64 = 5e-7;
    if motion == MotionMode::ArcCw {
        if travel >= -EPS {
            travel -= 2.0 * PI;
        }
    } else if travel <= EPS {
        travel += 2.0 * PI;
    }
    let linear = idx(lin).map_or(0.0, |k| target[k] - start[k]);
    let others: f64 = (0..axes.len())
        .filter(|&k| k != i0 && k != i1 && Some(k) != idx(lin))
        .map(|k| (target[k] - start[k]).powi(2))
        .sum();
    Ok(((travel.abs() * radius).powi(2) + linear * linear + others).sqrt())
}
