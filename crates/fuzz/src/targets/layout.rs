//! Sheet layouts: DXF drawings (`cell_sequencer::dxf::read_dxf`) and the JSON layout format
//! (`Layout::from_json_str`), each followed by the nesting check the sequence job runs first.

use cell_sequencer::dxf::{read_dxf, DxfOptions};
use cell_sequencer::layout::Layout;

use crate::{scratch_dir, seed_files, text, Target};

const DXF_TOKENS: &[&str] = &[
    "  0\nSECTION\n",
    "  2\nENTITIES\n",
    "  2\nHEADER\n",
    "  0\nENDSEC\n",
    "  0\nEOF\n",
    "  0\nLWPOLYLINE\n",
    "  0\nPOLYLINE\n",
    "  0\nVERTEX\n",
    "  0\nSEQEND\n",
    "  0\nLINE\n",
    "  0\nARC\n",
    "  0\nCIRCLE\n",
    "  0\nSPLINE\n",
    "  0\nELLIPSE\n",
    "  0\nINSERT\n",
    "  8\nSHEET\n",
    " 90\n",
    " 70\n1\n",
    " 10\n",
    " 20\n",
    " 40\n",
    " 42\n",
    " 50\n",
    " 51\n",
    "$EXTMIN",
    "$INSUNITS",
    "1e308",
    "NaN",
];

const JSON_TOKENS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "\"sheet\"",
    "\"parts\"",
    "\"contours\"",
    "\"points\"",
    "\"holes\"",
    "\"size_mm\"",
    "\"name\"",
    "[0,0]",
    "[1e308,1e308]",
    "[-1,-1]",
    "null",
    "true",
    "1e999",
    "-0.0",
];

fn dxf(data: &[u8]) {
    let path = scratch_dir("dxf").join("input.dxf");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(layout) = read_dxf(&path, &DxfOptions::default()) {
        let _ = layout.contour_count();
        let _ = layout.nesting();
        let _ = layout.to_json();
    }
}

fn json(data: &[u8]) {
    if let Ok(layout) = Layout::from_json_str(&text(data), "input.json") {
        let _ = layout.contour_count();
        let _ = layout.nesting();
        let _ = Layout::from_json_str(&layout.to_json(), "again.json");
    }
}

fn dxf_seeds() -> Vec<Vec<u8>> {
    seed_files("tests/data/sheet", &[".dxf"], 1 << 20)
}

fn json_seeds() -> Vec<Vec<u8>> {
    let mut s = seed_files("tests/data/sheet", &[".json"], 1 << 20);
    s.extend(seed_files("config/sheets", &[".json"], 1 << 20));
    s
}

/// The layout targets.
pub fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "layout_dxf",
            about: "DXF sheet drawings (read_dxf), then nesting",
            run: dxf,
            seeds: dxf_seeds,
            tokens: DXF_TOKENS,
            max_len: 1 << 16,
        },
        Target {
            name: "layout_json",
            about: "JSON sheet layouts (Layout::from_json_str), then nesting",
            run: json,
            seeds: json_seeds,
            tokens: JSON_TOKENS,
            max_len: 1 << 16,
        },
    ]
}
