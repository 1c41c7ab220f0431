//! `cell slice` draws the slice (issue 20, item 6): `slice.svg` is well-formed XML (read by
//! xml-rs, which shares no code with the writer), shows the chosen layer (`--picture-layer`,
//! default the middle one) and a side section with the part, the beads and the allowance, and a
//! layer past the last is a usage error naming the range.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use xml::reader::{EventReader, XmlEvent};

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// What a check needs from `slice.svg`: per group id, its `rect`s (x, y, width, height) and
/// how many `path`s it holds; and every text.
#[derive(Debug, Default)]
struct Picture {
    rects: HashMap<String, Vec<[f64; 4]>>,
    paths: HashMap<String, usize>,
    groups: Vec<String>,
    texts: Vec<String>,
}

fn read_picture(path: &Path) -> Picture {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut p = Picture::default();
    let mut stack: Vec<Option<String>> = Vec::new();
    for event in EventReader::new(std::io::BufReader::new(file)) {
        match event.unwrap_or_else(|e| panic!("{}: not well-formed: {e}", path.display())) {
            XmlEvent::StartElement {
                name, attributes, ..
            } => {
                let attr = |n: &str| {
                    attributes
                        .iter()
                        .find(|a| a.name.local_name == n)
                        .map(|a| a.value.clone())
                };
                let num = |n: &str| attr(n).and_then(|v| v.parse::<f64>().ok()).unwrap();
                let id = attr("id");
                if let Some(id) = &id {
                    p.groups.push(id.clone());
                }
                let group = stack
                    .iter()
                    .rev()
                    .find_map(|g| g.clone())
                    .unwrap_or_default();
                match name.local_name.as_str() {
                    "rect" => p.rects.entry(group).or_default().push([
                        num("x"),
                        num("y"),
                        num("width"),
                        num("height"),
                    ]),
                    "path" => *p.paths.entry(group).or_default() += 1,
                    _ => {}
                }
                stack.push(id);
            }
            XmlEvent::EndElement { .. } => {
                stack.pop();
            }
            XmlEvent::Characters(t) => p.texts.push(t),
            _ => {}
        }
    }
    p
}

fn slice(stl: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "slice".to_string(),
        "--stl".into(),
        stl.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    std::process::Command::new(CELL)
        .args(&args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run cell")
}

#[test]
fn slice_svg_shows_a_layer_and_a_side_section_with_part_beads_and_allowance() {
    let dir = tempfile::tempdir().unwrap();
    let cube = repo("tests/data/stl/20mm-xyz-cube.stl");
    let out = slice(&cube, &dir.path().join("mid"), &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("mid/report.json")).unwrap())
            .unwrap();
    let layers = report["layers"].as_u64().unwrap() as usize;
    let allowance = report["machining_allowance_mm"].as_f64().unwrap();
    let p = read_picture(&dir.path().join("mid/slice.svg"));
    for id in [
        "title",
        "legend",
        "layer",
        "layer-allowance",
        "layer-beads",
        "layer-part",
        "layer-paths",
        "layer-travel",
        "cut-line",
        "section",
        "section-allowance",
        "section-beads",
        "section-part",
    ] {
        assert!(
            p.groups.iter().any(|g| g == id),
            "group {id} missing: {:?}",
            p.groups
        );
    }
    let title = p.texts.join(" ");
    assert!(
        title.contains(&format!("layer {} of {layers}", layers / 2)),
        "{title}"
    );
    assert!(p.paths["layer-beads"] >= 1 && p.paths["layer-part"] == 1);

    // The cube's section: 20 mm wide in every layer clear of the engraved letters, the
    // allowance reaching exactly the allowance beyond it on either side, beads crossing it.
    let part = &p.rects["section-part"];
    assert!(part.len() >= layers.min(12), "{part:?}");
    let widest = part.iter().map(|r| r[2]).fold(0.0, f64::max);
    assert!((widest - 20.0).abs() < 0.05, "{widest}");
    let (left, right) = part
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, r), q| {
            (l.min(q[0]), r.max(q[0] + q[2]))
        });
    let allowed = &p.rects["section-allowance"];
    let a_left = allowed.iter().map(|r| r[0]).fold(f64::INFINITY, f64::min);
    let a_right = allowed
        .iter()
        .map(|r| r[0] + r[2])
        .fold(f64::NEG_INFINITY, f64::max);
    assert!((left - a_left - allowance).abs() < 0.02, "{left} {a_left}");
    assert!(
        (a_right - right - allowance).abs() < 0.02,
        "{right} {a_right}"
    );
    let beads = &p.rects["section-beads"];
    assert!(!beads.is_empty());
    assert!(
        beads.iter().all(|b| b[2] > 0.0 && b[3] > 0.5 && b[3] < 3.0),
        "{beads:?}"
    );

    // Another layer, and one past the last.
    let out = slice(&cube, &dir.path().join("l2"), &["--picture-layer", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let p = read_picture(&dir.path().join("l2/slice.svg"));
    assert!(p.texts.join(" ").contains(&format!("layer 2 of {layers}")));
    let out = slice(&cube, &dir.path().join("far"), &["--picture-layer", "999"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(64), "{err}");
    assert!(
        err.contains("--picture-layer 999") && err.contains(&format!("0..={}", layers - 1)),
        "{err}"
    );
    assert!(!dir.path().join("far/slice.svg").exists());
}
