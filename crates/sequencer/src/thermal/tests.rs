use super::kernel::ANY;
use super::*;
use crate::problem::{Contour, ContourRole};

fn square(x: f64, y: f64, s: f64) -> Contour {
    Contour {
        part: 0,
        role: ContourRole::Outer,
        points: vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]],
        pierce_candidates: vec![[x, y]],
        leads: Vec::new(),
        drawn: Vec::new(),
    }
}

#[test]
fn bad_params_name_the_field() {
    let p = ThermalParams {
        k_conductivity: 0.2,
        ..Default::default()
    };
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("k_conductivity"), "{e}");
    let p = ThermalParams {
        cut_speed_mm_s: 0.0,
        ..Default::default()
    };
    assert!(p
        .validate()
        .unwrap_err()
        .to_string()
        .contains("cut_speed_mm_s"));
    assert!(ThermalSim::new([0.0, 1.0], [0.0, 0.0], &ThermalParams::default()).is_err());
}

#[test]
fn the_raster_is_capped() {
    let p = ThermalParams {
        cell_mm: 1.0,
        ..Default::default()
    };
    // 10 000 × 10 000 cells is the limit; one more row is over it.
    assert_eq!(p.raster_size([1e4, 1e4]), Ok((10_000, 10_000)));
    assert_eq!(10_000 * 10_000, MAX_RASTER_CELLS);
    let e = p.raster_size([1e4, 1e4 + 0.5]).unwrap_err().to_string();
    assert_eq!(
        e,
        "sheet 10000 × 10000.5 mm at cell_mm = 1 mm is a raster of 1.000e8 cells: the limit \
         is 100000000 cells (MAX_RASTER_CELLS)"
    );
    // A sheet of 10¹² mm at the default 4 mm: 6·10²² cells, refused without overflow.
    let e = ThermalParams::default()
        .raster_size([1e12, 1e12])
        .unwrap_err()
        .to_string();
    assert!(e.contains("a raster of 6.250e22 cells"), "{e}");
    assert!(ThermalSim::new([1e12, 1e12], [0.0, 0.0], &ThermalParams::default()).is_err());
}

#[test]
fn the_cut_steps_are_capped() {
    let p = ThermalParams::default();
    let at = p.cell_mm * MAX_CUT_STEPS as f64;
    assert_eq!(p.check_cut_steps(at), Ok(()));
    let e = p.check_cut_steps(at + 1.0).unwrap_err().to_string();
    assert_eq!(
        e,
        "the contours' cut length of 40000001 mm at cell_mm = 4 mm is 1.000e7 raster steps: \
         the limit is 10000000 steps (MAX_CUT_STEPS)"
    );
}

/// A lone hot cell among ambient neighbours gives each `ΔT = P.T·K_c` (seed 003 §A3).
#[test]
fn spread_matches_the_paper_for_a_hot_cell() {
    let p = ThermalParams {
        k_loss: 1.0,
        epsilon_c: 0.0,
        ..Default::default()
    };
    let mut sim = ThermalSim::new([40.0, 40.0], [0.0, 0.0], &p).unwrap();
    sim.t[5 * 10 + 5] = 1000.0;
    sim.active[0] = true;
    sim.edges[0] = ANY;
    sim.active_list.push(0);
    sim.spread();
    let dt = 1000.0 * p.k_conductivity;
    assert!((sim.t[4 * 10 + 4] - dt).abs() < 1e-3);
    assert!((sim.t[5 * 10 + 5] - (1000.0 - 8.0 * dt)).abs() < 1e-3);
    // Heat is conserved with k_loss = 1.
    let total: f32 = sim.t.iter().sum();
    assert!((total - 1000.0).abs() < 1e-2, "{total}");
}

#[test]
fn cutting_heats_and_is_deterministic() {
    let run = || {
        let mut sim =
            ThermalSim::new([200.0, 200.0], [0.0, 0.0], &ThermalParams::default()).unwrap();
        let a = square(20.0, 75.0, 50.0);
        let b = square(20.0, 20.0, 50.0);
        sim.cut_contour(&a, [20.0, 75.0]);
        let hot = sim.cut_contour(&b, [20.0, 70.0]);
        (sim.frame().excess_c.to_vec(), hot, sim.finish([0.0, 0.0]))
    };
    let (t1, hot, o1) = run();
    let (t2, _, o2) = run();
    assert_eq!(
        t1.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        t2.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    assert_eq!(o1, o2);
    assert!(o1.max_temp_c > 300.0, "{}", o1.max_temp_c);
    // The second square is pierced 5 mm from where the first one ended.
    assert!(hot.pierce_overheats + hot.segment_overheats > 0, "{hot:?}");
}

/// The tiled, fast-path update agrees with a plain full-grid reference of the rule
/// (seed 003 §A3, module docs) after kerf cuts and many steps.
#[test]
fn tiled_update_matches_the_reference() {
    let p = ThermalParams::default();
    let mut sim = ThermalSim::new([150.0, 120.0], [0.0, 0.0], &p).unwrap();
    sim.cut_contour(&square(2.0, 2.0, 60.0), [2.0, 2.0]);
    sim.cut_contour(&square(70.0, 30.0, 40.0), [70.0, 30.0]);
    let (w, h) = sim.size();
    let mut t = sim.t.clone();
    let kc = sim.kc.clone();
    for _ in 0..40 {
        let mut next = vec![0.0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let mut acc = 0.0f32;
                for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                    for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                        let j = yy * w + xx;
                        if j != i {
                            acc += kc[i].min(kc[j]) * (t[j] - t[i]);
                        }
                    }
                }
                let v = (t[i] + acc) * p.k_loss;
                next[i] = if v < p.epsilon_c { 0.0 } else { v };
            }
        }
        t = next;
        sim.spread();
    }
    let worst = t
        .iter()
        .zip(&sim.t)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 0.01, "tiled vs reference differ by {worst} °C");
    assert!(t.iter().any(|&v| v > 100.0));
}

/// Skipping cold tiles, the swapped buffers and the zeroing of tiles that drop out change
/// no bit against updating every tile every step (kernel docs).
#[test]
fn sparse_update_is_bit_identical_to_updating_everything() {
    let run = |all: bool| {
        let p = ThermalParams::default();
        // A hash of the whole raster after every step.
        let mut hashes = Vec::new();
        let mut obs = |f: &Frame| {
            let h = f.excess_c.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
                (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01b3)
            });
            hashes.push(h);
        };
        let mut sim = ThermalSim::new([150.0, 123.0], [0.0, 0.0], &p)
            .unwrap()
            .with_frames(1, &mut obs);
        sim.update_all = all;
        sim.cut_contour(&square(2.0, 2.0, 60.0), [2.0, 2.0]);
        sim.cut_contour(&square(70.0, 30.0, 40.0), [70.0, 30.0]);
        sim.cut_contour(&square(30.0, 80.0, 30.0), [31.0, 80.0]);
        sim.travel_to([149.0, 122.0]);
        // Long enough for kerf to cool below epsilon_c: tiles drop out of the update.
        sim.spread_steps(1200);
        sim.cut_contour(&square(100.0, 90.0, 20.0), [100.0, 90.0]);
        sim.spread_steps(50);
        let t: Vec<u32> = sim.t.iter().map(|v| v.to_bits()).collect();
        let out = sim.finish([0.0, 0.0]);
        (t, out, hashes)
    };
    let (t_sparse, o_sparse, h_sparse) = run(false);
    let (t_all, o_all, h_all) = run(true);
    assert!(t_sparse.iter().any(|&b| f32::from_bits(b) > 100.0));
    assert_eq!(t_sparse, t_all);
    assert_eq!(h_sparse.len() as u64, o_sparse.steps);
    assert_eq!(h_sparse, h_all, "the rasters differ after some step");
    assert_eq!(o_sparse.max_temp_c.to_bits(), o_all.max_temp_c.to_bits());
    assert_eq!(o_sparse.per_cut, o_all.per_cut);
    assert!(o_sparse.cells_updated < o_all.cells_updated);
}

#[test]
fn frames_arrive_every_n_steps() {
    let mut frames = Vec::new();
    let mut obs = |f: &Frame| frames.push(f.step);
    let mut sim = ThermalSim::new([100.0, 100.0], [0.0, 0.0], &ThermalParams::default())
        .unwrap()
        .with_frames(10, &mut obs);
    sim.cut_contour(&square(10.0, 10.0, 20.0), [10.0, 10.0]);
    let out = sim.finish([0.0, 0.0]);
    assert_eq!(frames.len() as u64, out.steps / 10);
    assert!(frames.iter().all(|s| s % 10 == 0));
}
