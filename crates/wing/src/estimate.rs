//! Mass and build-time estimates (seed 002 §5 "Estimators", compared against Table 4).

use crate::layers::{Layer, Move};
use crate::marlin::{blocks_from_moves, marlin_time_s, FirmwareMotion};

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

/// Build time of a move list \[s\].
///
/// Without a planner: Σ L/v, E-only moves taking |ΔE|/v (the feeds as asked, no acceleration,
/// no axis limits). With one: the time a Marlin 2 printer with those settings spends
/// ([`crate::marlin::marlin_time_s`]: trapezoids, junction deviation, the 16-block look-ahead,
/// per-axis feed and acceleration limits, E-only retracts and primes, Z-hops).
pub fn build_time_s(moves: &[Move], planner: Option<FirmwareMotion>) -> f64 {
    let blocks = blocks_from_moves(moves);
    match planner {
        Some(m) => marlin_time_s(&blocks, &m),
        None => blocks
            .iter()
            .map(|b| {
                let d = b.delta;
                let xyz = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let l = if xyz > 0.0 { xyz } else { d[3].abs() };
                l / b.feed_mm_s
            })
            .sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layers::MoveKind;

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
        // 100 mm at 10 mm/s, a = 100: 0.1 s up, 0.1 s down, 99 mm cruising.
        let a = FirmwareMotion {
            travel_acceleration_mm_s2: 100.0,
            ..FirmwareMotion::MARLIN_2_DEFAULTS
        };
        let t = build_time_s(&m, Some(a));
        assert!((t - (0.2 + 9.9)).abs() < 1e-3, "{t}");
        // A straight line split in two costs nothing extra; a reversal stops the head.
        let split = [
            mv([0.0; 3], 10.0),
            mv([50.0, 0.0, 0.0], 10.0),
            mv([100.0, 0.0, 0.0], 10.0),
        ];
        assert!((build_time_s(&split, Some(a)) - t).abs() < 1e-6);
        let back = [
            mv([0.0; 3], 10.0),
            mv([50.0, 0.0, 0.0], 10.0),
            mv([0.0, 0.0, 0.0], 10.0),
        ];
        assert!(
            (build_time_s(&back, Some(a)) - (t + 0.1)).abs() < 1e-3,
            "a stop costs v/a = 0.1 s"
        );
        // Short move: triangle, 0.5 mm at a = 100 from rest to rest: 2·sqrt(0.5/100).
        let short = [mv([0.0; 3], 10.0), mv([0.5, 0.0, 0.0], 10.0)];
        assert!((build_time_s(&short, Some(a)) - 2.0 * (0.005f64).sqrt()).abs() < 1e-3);
    }
}
