//! Issue 21's CI check: the default job (swarm, refinement, feed variable, lead-in) with a
//! reduced swarm budget cuts the exposure's coefficient of variation by at least half on three
//! shipped foils, and the result is a path the machine can cut: clear of the foil by the
//! margin (measured here, not with the planner's own test or its geometry crate), feed within the
//! band and the machine's limit. The full figures (24 unseen foils, default budget) are the
//! `uniformity` bench's.

use std::ops::ControlFlow;

use cell_planner::job::{plan, AirfoilSource, HotwireJob};
use cell_planner::pso::{Objective, PsoConfig};

#[test]
fn the_default_job_halves_the_exposure_spread_on_shipped_foils() {
    for name in ["s1223", "e387", "clarky"] {
        let job = HotwireJob {
            root_airfoil: AirfoilSource::Named(name.into()),
            panels: 120,
            pso: PsoConfig {
                particles: 10,
                iterations: 300,
                ..PsoConfig::default()
            },
            ..HotwireJob::default()
        };
        let p = plan(&job, |_| ControlFlow::Continue(())).unwrap();
        let r = &p.root;
        let (before, after) = (r.baseline_stats, r.optimised_stats);
        let cut = 1.0 - after.cv / before.cv;
        eprintln!(
            "{name}: CV {:.3} → {:.3} ({:.0} %), p95 |E − CSE| {:.3} → {:.3}, {} iterations",
            before.cv,
            after.cv,
            100.0 * cut,
            before.p95_abs,
            after.p95_abs,
            p.iterations
        );
        assert!(cut >= 0.5, "{name}: CV cut {cut:.2}");
        assert!(
            after.p95_abs < 0.6 * before.p95_abs,
            "{name}: {after:?} {before:?}"
        );

        // Clearance of lead-in and cut from the foil: least vertex–edge and edge–vertex
        // distance (the two polylines cannot cross while every wire vertex is outside).
        let margin = Objective::default().min_clearance_mm;
        let mut wire = r.lead_in.clone();
        wire.extend_from_slice(&r.optimised);
        let ring = &r.foil;
        let seg_dist =
            |p: nalgebra::Point2<f64>, a: nalgebra::Point2<f64>, b: nalgebra::Point2<f64>| {
                let ab = b - a;
                let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
                (p - (a + ab * t)).norm()
            };
        let n = ring.len();
        let least = wire
            .iter()
            .map(|&w| {
                (0..n)
                    .map(|i| seg_dist(w, ring[i], ring[(i + 1) % n]))
                    .fold(f64::INFINITY, f64::min)
            })
            .chain(ring.iter().map(|&f| {
                wire.windows(2)
                    .map(|s| seg_dist(f, s[0], s[1]))
                    .fold(f64::INFINITY, f64::min)
            }))
            .fold(f64::INFINITY, f64::min);
        assert!(
            wire.iter().all(|&w| !inside(w, ring)),
            "{name}: a wire point inside the foil"
        );
        assert!(
            least >= margin - 1e-9,
            "{name}: clearance {least} < {margin}"
        );

        // The feed stays in its band and under the machine's limit.
        let band = Objective::default().feed.unwrap();
        let limit = job.machine.max_feed_mm_s;
        assert!(r
            .feed_ratio
            .iter()
            .all(|&q| q >= band.min_ratio - 1e-12 && q <= band.max_ratio + 1e-12));
        assert!(p.cut.feed_mm_s.iter().all(|&f| f <= limit + 1e-9));
        assert!(
            r.feed_ratio.iter().any(|&q| (q - 1.0).abs() > 0.05),
            "{name}: the feed never moved"
        );
    }
}

/// Even–odd point in polygon (crossing count of a ray towards +x).
fn inside(p: nalgebra::Point2<f64>, ring: &[nalgebra::Point2<f64>]) -> bool {
    let n = ring.len();
    let mut odd = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            odd = !odd;
        }
    }
    odd
}
