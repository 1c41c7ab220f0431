//! One exposure evaluation (seed 000 eq. 5, closed form) on S1223, chord 200 mm, 0.5 mm fixed
//! offset, at N ≈ M = 100, 200, 400. Prints µs per evaluation next to the notes' NumPy figures.
//!
//! `CARGO_TARGET_DIR=/tmp/target-planner cargo bench -p cell_planner --bench exposure`

use std::time::Instant;

use cell_planner::airfoil::Airfoil;
use cell_planner::exposure::{
    coefficient_of_variation, DistanceLaw, ExposureModel, Panels, WireSegments,
};
use cell_planner::trajectory::Baseline;

fn main() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../config/airfoils/s1223.dat"
    );
    let foil = Airfoil::load(path)
        .and_then(|f| f.scaled(200.0))
        .expect("s1223");
    let numpy = [(100, "0.2–0.3 ms"), (200, "0.6–0.9 ms"), (400, "2–4 ms")];
    for (n, peer) in numpy {
        let surface = Panels::from_points(foil.resampled_cosine(n).expect("resample").points())
            .expect("panels");
        let wire = Baseline::fixed_offset(&foil, 0.5, n).expect("baseline");
        let wire = WireSegments::from_points(wire.points()).expect("wire");
        for law in [DistanceLaw::Paper, DistanceLaw::AuthorCode] {
            let model = ExposureModel {
                law,
                ..ExposureModel::default()
            };
            let mut out = vec![0.0; surface.len()];
            model
                .exposure_into(&surface, &wire, &mut out)
                .expect("exposure");
            let reps = (2_000_000 / (n * n)).max(20);
            let t = Instant::now();
            for _ in 0..reps {
                model
                    .exposure_into(&surface, &wire, &mut out)
                    .expect("exposure");
                std::hint::black_box(&out);
            }
            let us = t.elapsed().as_secs_f64() * 1e6 / reps as f64;
            println!(
                "N={n:3} M={:3} {law:?}: {us:8.1} µs/evaluation (CV {:.4}); NumPy (notes): {peer}",
                wire.len(),
                coefficient_of_variation(&out)
            );
        }
    }
}
