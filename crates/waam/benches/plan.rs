//! Planning speed and totals for a stack of plate layers with holes (prints figures; no
//! criterion dependency needed for these few numbers).
//!
//! `cargo bench -p cell_waam --bench plan`

use std::time::Instant;

use cell_waam::cost::{post_toolpath_cost, PartVolumes};
use cell_waam::stock::{bead_boxes, write_stock_stl};
use cell_waam::toolpath::toolpath_totals;
use cell_waam::{plan_stack, LayerPolygons, WaamProcess, WidthMode};

fn rect(x0: f64, y0: f64, w: f64, h: f64) -> Vec<[f64; 2]> {
    vec![[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]
}

fn circle_cw(cx: f64, cy: f64, r: f64, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let a = -(i as f64) / n as f64 * std::f64::consts::TAU;
            [cx + r * a.cos(), cy + r * a.sin()]
        })
        .collect()
}

fn run(name: &str, layers: &[LayerPolygons], p: &WaamProcess) {
    let t0 = Instant::now();
    let tps = plan_stack(layers, p).expect("plan");
    let dt = t0.elapsed().as_secs_f64();
    let totals = toolpath_totals(&tps);
    let starts: usize = tps.iter().map(|l| l.arc_starts).sum();
    let points: usize = tps
        .iter()
        .flat_map(|l| &l.segments)
        .map(|s| s.points.len())
        .sum();
    let t1 = Instant::now();
    let boxes = bead_boxes(&tps);
    let mut stl = Vec::new();
    write_stock_stl(&mut stl, &boxes).expect("stl");
    let dt_stl = t1.elapsed().as_secs_f64();
    let cost = post_toolpath_cost(&p.cost, &PartVolumes::default(), &totals);
    println!(
        "{name}: {} layers, {points} points, {starts} arc starts",
        tps.len()
    );
    println!(
        "  plan {:.1} ms ({:.2} ms/layer); stock {} boxes, {:.1} MB STL in {:.1} ms",
        dt * 1e3,
        dt * 1e3 / tps.len() as f64,
        boxes.len(),
        stl.len() as f64 / 1e6,
        dt_stl * 1e3
    );
    println!(
        "  V_d {:.4e} m³, t_D {:.0} s, t_trav {:.0} s, C_i^AM {:.1} SEK (wire {:.1}, time {:.1})",
        totals.deposited_m3,
        totals.deposition_s,
        totals.travel.seconds(),
        cost.deposition_sek,
        cost.wire_sek,
        cost.waam_time_sek
    );
}

fn main() {
    let plate: Vec<LayerPolygons> = (0..40)
        .map(|i| LayerPolygons {
            index: i,
            z_mm: 1.6 * (i + 1) as f64,
            outers_and_holes: vec![
                rect(0.0, 0.0, 200.0, 150.0),
                {
                    let mut h = rect(30.0, 40.0, 40.0, 30.0);
                    h.reverse();
                    h
                },
                circle_cw(140.0, 75.0, 25.0, 96),
            ],
        })
        .collect();
    run(
        "plate 200x150 mm, 2 holes, fixed width",
        &plate,
        &WaamProcess::default(),
    );
    let tube: Vec<LayerPolygons> = (0..40)
        .map(|i| LayerPolygons {
            index: i,
            z_mm: 1.6 * (i + 1) as f64,
            outers_and_holes: vec![
                {
                    let mut o = circle_cw(0.0, 0.0, 100.0, 256);
                    o.reverse();
                    o
                },
                circle_cw(0.0, 0.0, 91.0, 256),
            ],
        })
        .collect();
    let p = WaamProcess {
        width_mode: WidthMode::WallDriven,
        ..WaamProcess::default()
    };
    run("tube r 100/91 mm, wall-driven", &tube, &p);
}
