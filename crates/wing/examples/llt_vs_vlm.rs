//! The lifting line against AeroSandbox's vortex lattice for the six design-case specs
//! (`config/wings/*.yaml`, seed 002 Table 1): writes each wing's AVL file (flat camber, Ainc
//! from the zero-lift line, [`cell_wing::avl`]), solves it with `tests/vlm/compare.py` and prints
//! lift slope, design c_L, span loading, induced drag and span efficiency side by side.
//!
//! `cargo run -p cell_wing --example llt_vs_vlm [-- NCHORD NSPAN]`; `VLM_PYTHON` names a Python
//! with `tests/vlm/requirements.txt` installed (default `python3`): the venv `cargo test --test
//! wing_vlm` makes, `target/tmp/vlm-venv/bin/python`, or
//! `python3 -m venv /tmp/venv-vlm && /tmp/venv-vlm/bin/pip install -r tests/vlm/requirements.txt`.
//! `VLM_OUT=DIR` keeps the AVL files there.

use std::process::Command;

use cell_wing::avl::{geometry, AvlOptions, AvlWing, Camber};
use cell_wing::crosscheck::{pct, Agreement, VlmSolution};
use cell_wing::llt::LiftingLine;
use cell_wing::spec::{Wing, WingSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let defaults = AvlOptions::default();
    let options = AvlOptions {
        chordwise_vortices: args.first().copied().unwrap_or(defaults.chordwise_vortices),
        spanwise_vortices: args.get(1).copied().unwrap_or(defaults.spanwise_vortices),
        camber: Camber::ZeroLiftLine,
        ..defaults
    };
    let python = std::env::var("VLM_PYTHON").unwrap_or_else(|_| "python3".into());
    // `VLM_OUT` keeps the AVL files there; otherwise they go to a temporary directory.
    let keep = std::env::var_os("VLM_OUT").map(std::path::PathBuf::from);
    let dir = keep.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(format!("cell-llt-vs-vlm-{}", std::process::id()))
    });
    std::fs::create_dir_all(&dir)?;
    println!(
        "LLT (each spec's stations) vs AeroSandbox VLM ({} chordwise × {} spanwise per side)",
        options.chordwise_vortices, options.spanwise_vortices
    );
    println!(
        "{:<27} {:>15} {:>7} {:>15} {:>7} {:>20} {:>17} {:>7} {:>13} {:>5}",
        "case",
        "c_Lα LLT/VLM",
        "Δ%",
        "c_L LLT/VLM",
        "Δ%",
        "load Δ% @y/b (tips)",
        "C_Di LLT/VLM",
        "Δ%",
        "e LLT/VLM",
        "s"
    );
    for (name, _) in cell_wing::design::EXAMPLE_SPECS {
        let spec = WingSpec::load(format!("{root}/config/wings/{name}.yaml"))?;
        let wing = Wing::design(spec)?;
        let a = &wing.spec.aero;
        let ll = LiftingLine::new(a.stations, a.aspect_ratio, a.lift_slope_per_rad)?;
        let slope = ll.lift_curve_slope(&wing.aero.chord_over_b)?;
        let file = dir.join(format!("{name}.avl"));
        let text = geometry(
            &AvlWing::of(&wing),
            &AvlOptions {
                title: name.into(),
                ..options.clone()
            },
        )?;
        std::fs::write(&file, text)?;
        let out = Command::new(&python)
            .arg(format!("{root}/tests/vlm/compare.py"))
            .arg(&file)
            .output()?;
        if !out.status.success() {
            return Err(format!("{name}: {}", String::from_utf8_lossy(&out.stderr)).into());
        }
        let json: serde_json::Value = serde_json::from_slice(&out.stdout)?;
        let vlm: VlmSolution = serde_json::from_value(json.clone())?;
        let g = Agreement::of(&wing.aero, slope, &vlm);
        println!(
            "{:<27} {:>7.4}/{:<7.4} {:>+7.2} {:>7.4}/{:<7.4} {:>+7.2} {:>5.2} @{:<5.3} ({:>5.2}) {:>8.5}/{:<8.5} {:>+7.2} \
             {:>6.4}/{:<6.4} {:>5.1}",
            name,
            g.lift_slope.0,
            g.lift_slope.1,
            pct(g.lift_slope),
            g.c_l.0,
            g.c_l.1,
            pct(g.c_l),
            g.span_loading_max_diff_pct,
            g.span_loading_max_diff_at,
            g.span_loading_max_diff_with_tips_pct,
            g.cdi.0,
            g.cdi.1,
            pct(g.cdi),
            g.span_efficiency.0,
            g.span_efficiency.1,
            json["seconds"].as_f64().unwrap_or(f64::NAN),
        );
    }
    if keep.is_none() {
        std::fs::remove_dir_all(&dir)?;
    }
    Ok(())
}
