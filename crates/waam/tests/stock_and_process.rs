//! Stock STL boxes and the process profile file.

use std::collections::HashMap;
use std::path::Path;

use cell_waam::stock::{bead_boxes, stock_triangles, write_stock_stl, BeadBox};
use cell_waam::{plan_stack, LayerPolygons, ProcessError, WaamProcess, WidthMode};

fn key(v: &stl_io::Vertex) -> [u32; 3] {
    [v[0].to_bits(), v[1].to_bits(), v[2].to_bits()]
}

/// Signed volume by the divergence theorem (f64 from the f32 vertices).
fn mesh_volume(tris: &[stl_io::Triangle]) -> f64 {
    tris.iter()
        .map(|t| {
            let p: Vec<[f64; 3]> = t
                .vertices
                .iter()
                .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64])
                .collect();
            (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1])
                - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0])
                + p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]))
                / 6.0
        })
        .sum()
}

fn stack() -> Vec<cell_waam::LayerToolpath> {
    let ring =
        |x0: f64, y0: f64, s: f64| vec![[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]];
    let mut hole = ring(20.0, 20.0, 15.0);
    hole.reverse();
    let layers: Vec<LayerPolygons> = (0..3)
        .map(|i| LayerPolygons {
            index: i,
            z_mm: 1.6 * (i + 1) as f64,
            outers_and_holes: vec![ring(0.0, 0.0, 60.0), hole.clone()],
        })
        .collect();
    plan_stack(&layers, &WaamProcess::default()).unwrap()
}

#[test]
fn every_box_is_closed_with_outward_normals() {
    let tps = stack();
    let boxes = bead_boxes(&tps);
    assert!(boxes.len() > 20);
    let tris = stock_triangles(&boxes);
    assert_eq!(tris.len(), 12 * boxes.len(), "12 triangles per box");
    for (bi, chunk) in tris.chunks(12).enumerate() {
        // Every undirected edge of a box is used by exactly two triangles, once each way.
        let mut edges: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
        for t in chunk {
            for i in 0..3 {
                let (a, b) = (key(&t.vertices[i]), key(&t.vertices[(i + 1) % 3]));
                let (k, s) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
                *edges.entry(k).or_default() += s * 1000 + 1;
            }
        }
        for (e, n) in &edges {
            assert_eq!(
                *n, 2,
                "box {bi}: edge {e:?} used {n} (want +1 and −1 direction)"
            );
        }
        assert_eq!(edges.len(), 18, "box {bi}: 12 box edges + 6 face diagonals");
        // Outward: each normal points away from the box centre.
        let c: [f64; 3] = {
            let b = &boxes[bi];
            [
                (b.start[0] + b.end[0]) / 2.0,
                (b.start[1] + b.end[1]) / 2.0,
                (b.start[2] + b.end[2]) / 2.0,
            ]
        };
        for t in chunk {
            let m: Vec<f64> = (0..3)
                .map(|k| t.vertices.iter().map(|v| v[k] as f64).sum::<f64>() / 3.0 - c[k])
                .collect();
            let d =
                m[0] * t.normal[0] as f64 + m[1] * t.normal[1] as f64 + m[2] * t.normal[2] as f64;
            assert!(d > 0.0, "box {bi}: inward normal");
        }
        let v = mesh_volume(chunk);
        let want = boxes[bi].volume_mm3();
        assert!(
            (v - want).abs() < 1e-4 * want.max(1.0),
            "box {bi}: volume {v} vs w·h·L {want}"
        );
    }
}

#[test]
fn stock_volume_is_the_deposited_volume_and_reads_back() {
    let tps = stack();
    let boxes = bead_boxes(&tps);
    let sum_whl: f64 = boxes
        .iter()
        .map(|b| b.width_mm * b.height_mm * b.length_mm())
        .sum();
    let deposited: f64 = tps.iter().map(|l| l.deposited_volume_mm3).sum();
    assert!(
        (sum_whl - deposited).abs() < 1e-9 * deposited,
        "Σ w·h·L of the boxes = the toolpath's volume"
    );
    let mut buf = Vec::new();
    write_stock_stl(&mut buf, &boxes).unwrap();
    assert_eq!(buf.len(), 84 + 50 * 12 * boxes.len(), "binary STL size");
    let mesh = stl_io::read_stl(&mut std::io::Cursor::new(&buf)).unwrap();
    assert_eq!(mesh.faces.len(), 12 * boxes.len());
    let tris: Vec<stl_io::Triangle> = mesh
        .faces
        .iter()
        .map(|f| stl_io::Triangle {
            normal: f.normal,
            vertices: f.vertices.map(|i| mesh.vertices[i]),
        })
        .collect();
    let v = mesh_volume(&tris);
    assert!(
        (v - sum_whl).abs() < 1e-4 * sum_whl,
        "STL volume {v} vs Σ w·h·L {sum_whl}"
    );
}

#[test]
fn degenerate_pieces_give_no_box() {
    let b = BeadBox {
        start: [1.0, 1.0, 0.0],
        end: [1.0, 1.0, 0.0],
        width_mm: 5.0,
        height_mm: 1.0,
    };
    assert!(b.triangles().is_empty());
}

fn config_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/processes/waam.yaml")
}

#[test]
fn default_yaml_loads_and_equals_the_defaults() {
    let p = WaamProcess::from_path(&config_path()).unwrap();
    assert_eq!(
        p,
        WaamProcess::default(),
        "config/processes/waam.yaml documents the defaults"
    );
    assert_eq!(p.wire_diameter_mm, 1.2, "d_w = 1.2 mm (notes B5)");
    assert_eq!(p.cost.waam_sek_h, 400.0, "Chart 3 HR_WAAM");
}

#[test]
fn yaml_errors_name_line_and_field() {
    let text = "wire_feed_m_min: 5.0\ncost:\n  wire_sek_kg: 50\n  bogus: 1\n";
    match WaamProcess::from_yaml_str(text, "t.yaml") {
        Err(ProcessError::Parse(cell_config::ParseError {
            file,
            line: Some(line),
            field: Some(field),
            ..
        })) => {
            assert_eq!(file, "t.yaml");
            assert_eq!(line, 4);
            assert!(field.contains("cost"), "field {field}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    let e = WaamProcess::from_yaml_str("travel_speed_mm_s: 30\n", "t.yaml").unwrap_err();
    assert!(
        matches!(
            e,
            ProcessError::Invalid {
                field: "travel_speed_mm_s",
                ..
            }
        ),
        "{e}"
    );
    let e = WaamProcess::from_yaml_str("infill_spacing_ratio: 1e-9\n", "t.yaml").unwrap_err();
    assert!(
        matches!(
            e,
            ProcessError::Invalid {
                field: "infill_spacing_ratio",
                ..
            }
        ),
        "{e}"
    );
    let e = WaamProcess::from_yaml_str("width_min_mm: 20\n", "t.yaml").unwrap_err();
    assert!(
        matches!(
            e,
            ProcessError::Invalid {
                field: "width_min_mm",
                ..
            }
        ),
        "{e}"
    );
    let e = WaamProcess::from_yaml_str("dwell_s: -1\n", "t.yaml").unwrap_err();
    assert!(
        matches!(
            e,
            ProcessError::Invalid {
                field: "dwell_s",
                ..
            }
        ),
        "{e}"
    );
    let p = WaamProcess::from_yaml_str("width_mode: wall_driven\ndwell_s: 30\n", "t.yaml").unwrap();
    assert_eq!(p.width_mode, WidthMode::WallDriven);
    assert_eq!(p.dwell_s, 30.0);
}
