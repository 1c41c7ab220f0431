//! Mass and build-time estimates (seed 002 §5 "Estimators", compared against Table 4).

use crate::layers::{Layer, Move, MoveKind};

/// Deposited volume Σ w·h·L over every stroke \[mm³\].
pub fn deposited_volume_mm3(layers: &[Layer], extrusion_width_mm: f64) -> f64 {
    layers
        .iter()
        .map(|l| {
            l.strokes.iter().map(|s| s.length_mm()).sum::<f64>() * extrusion_width_mm * l.height_mm
        })
        .sum()
}

/// Mass = Σ(w·h·L)·ρ \[g\], with ρ in kg/m³ (1 kg/m³ = 1e-6 g/mm³).
pub fn mass_g(layers: &[Layer], extrusion_width_mm: f64, density_kg_m3: f64) -> f64 {
    deposited_volume_mm3(layers, extrusion_width_mm) * density_kg_m3 * 1e-6
}

/// Acceleration model for [`build_time_s`]: Marlin-style constant acceleration with
/// junction-deviation cornering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Acceleration {
    /// Acceleration \[mm/s²\].
    pub accel_mm_s2: f64,
    /// Junction deviation \[mm\] (Marlin's default is 0.013).
    pub junction_deviation_mm: f64,
}

/// Build time of a move list \[s\].
///
/// Without acceleration: Σ L/v, E-only moves taking |ΔE|/v. With it: each run of XYZ moves is
/// planned like Marlin's look-ahead: the corner speed is capped by junction deviation,
/// v² ≤ a·δ·sin(θ/2)/(1 − sin(θ/2)) (θ the angle between the directions), the run starts and
/// ends at rest (E-only moves stop the head), a forward and a backward pass keep
/// v_exit² ≤ v_entry² + 2aL, and each move is a trapezoid (or triangle) profile.
pub fn build_time_s(moves: &[Move], accel: Option<Acceleration>) -> f64 {
    let mut t = 0.0;
    let mut prev = moves.first().map_or([0.0; 3], |m| m.to);
    let mut prev_e = 0.0;
    // The current run of head moves: (length, feed, unit direction).
    let mut run: Vec<(f64, f64, [f64; 3])> = Vec::new();
    for m in moves {
        let l = cell_geometry::distance3(prev, m.to);
        let de = (m.e_mm - prev_e).abs();
        let e_only = matches!(m.kind, MoveKind::Retract | MoveKind::Prime) && l == 0.0;
        if e_only {
            t += run_time(&run, accel);
            run.clear();
            t += de / m.feed_mm_s;
        } else if l > 0.0 {
            let u = [
                (m.to[0] - prev[0]) / l,
                (m.to[1] - prev[1]) / l,
                (m.to[2] - prev[2]) / l,
            ];
            run.push((l, m.feed_mm_s, u));
        }
        prev = m.to;
        prev_e = m.e_mm;
    }
    t + run_time(&run, accel)
}

fn run_time(run: &[(f64, f64, [f64; 3])], accel: Option<Acceleration>) -> f64 {
    let Some(a) = accel else {
        return run.iter().map(|(l, v, _)| l / v).sum();
    };
    let n = run.len();
    if n == 0 {
        return 0.0;
    }
    let acc = a.accel_mm_s2;
    // Junction speed limits (squared) at the n + 1 boundaries; 0 at both ends.
    let mut v2 = vec![0.0; n + 1];
    for i in 1..n {
        let (ua, ub) = (run[i - 1].2, run[i].2);
        let cos_theta = -(ua[0] * ub[0] + ua[1] * ub[1] + ua[2] * ub[2]);
        let sin_half = (0.5 * (1.0 - cos_theta)).max(0.0).sqrt();
        let cap = run[i - 1].1.min(run[i].1).powi(2);
        v2[i] = if sin_half >= 1.0 - 1e-12 {
            cap
        } else {
            (acc * a.junction_deviation_mm * sin_half / (1.0 - sin_half)).min(cap)
        };
    }
    for i in 0..n {
        v2[i + 1] = v2[i + 1].min(v2[i] + 2.0 * acc * run[i].0);
    }
    for i in (0..n).rev() {
        v2[i] = v2[i].min(v2[i + 1] + 2.0 * acc * run[i].0);
    }
    run.iter()
        .enumerate()
        .map(|(i, &(l, v, _))| trapezoid_time(l, v, v2[i].sqrt(), v2[i + 1].sqrt(), acc))
        .sum()
}

/// Time of a move of length `l` from speed `v0` to `v1` with cruise `v` and acceleration `a`.
fn trapezoid_time(l: f64, v: f64, v0: f64, v1: f64, a: f64) -> f64 {
    let d_acc = (v * v - v0 * v0) / (2.0 * a);
    let d_dec = (v * v - v1 * v1) / (2.0 * a);
    if d_acc + d_dec <= l {
        (v - v0) / a + (v - v1) / a + (l - d_acc - d_dec) / v
    } else {
        // Triangle: the peak speed where accelerating and decelerating meet.
        let vp = ((2.0 * a * l + v0 * v0 + v1 * v1) / 2.0).sqrt();
        (vp - v0) / a + (vp - v1) / a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mv(to: [f64; 3], v: f64) -> Move {
        Move {
            kind: MoveKind::Travel,
            to,
            feed_mm_s: v,
            e_mm: 0.0,
        }
    }

    #[test]
    fn straight_line_times() {
        let m = [mv([0.0; 3], 10.0), mv([100.0, 0.0, 0.0], 10.0)];
        assert!((build_time_s(&m, None) - 10.0).abs() < 1e-12);
        // 100 mm at 10 mm/s, a = 100: 0.1 s up, 0.1 s down, 0.5 mm each, 99 mm cruising.
        let a = Acceleration {
            accel_mm_s2: 100.0,
            junction_deviation_mm: 0.013,
        };
        let t = build_time_s(&m, Some(a));
        assert!((t - (0.2 + 9.9)).abs() < 1e-9, "{t}");
        // A straight line split in two costs nothing extra; a reversal stops the head.
        let split = [
            mv([0.0; 3], 10.0),
            mv([50.0, 0.0, 0.0], 10.0),
            mv([100.0, 0.0, 0.0], 10.0),
        ];
        assert!((build_time_s(&split, Some(a)) - t).abs() < 1e-9);
        let back = [
            mv([0.0; 3], 10.0),
            mv([50.0, 0.0, 0.0], 10.0),
            mv([0.0, 0.0, 0.0], 10.0),
        ];
        assert!(
            (build_time_s(&back, Some(a)) - (t + 0.1)).abs() < 1e-9,
            "a stop costs v/a = 0.1 s"
        );
        // Short move: triangle, 0.5 mm at a = 100 from rest to rest: 2·sqrt(0.5/100).
        let short = [mv([0.0; 3], 10.0), mv([0.5, 0.0, 0.0], 10.0)];
        assert!((build_time_s(&short, Some(a)) - 2.0 * (0.005f64).sqrt()).abs() < 1e-12);
    }
}
