//! `cell sheet` draws its plan (issue 19, item 7): `plan.svg` is well-formed XML (read by
//! xml-rs, which shares no code with the writer), holds one pierce marker and one order number
//! per contour at the plan's pierce points, one red circle per overheat, and the report's
//! figures in its title.

use std::path::{Path, PathBuf};

use cell_msgs::CutPlan;
use xml::reader::{EventReader, XmlEvent};

const CELL: &str = env!("CARGO_BIN_EXE_cell");

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/sheet")
        .join(name)
}

/// What a check needs from `plan.svg`.
#[derive(Debug, Default)]
struct Picture {
    /// The document's `<title>`.
    title: String,
    /// `viewBox`: x, y, width, height (SVG axes: y down).
    view_box: Vec<f64>,
    /// Centres of the circles in the `pierces` group, machine coordinates (y up).
    pierces: Vec<[f64; 2]>,
    /// The texts of the `order` group.
    labels: Vec<String>,
    /// Circles in the `overheats` group.
    overheats: usize,
}

fn attr(attributes: &[xml::attribute::OwnedAttribute], name: &str) -> Option<String> {
    attributes
        .iter()
        .find(|a| a.name.local_name == name)
        .map(|a| a.value.clone())
}

fn number(attributes: &[xml::attribute::OwnedAttribute], name: &str) -> f64 {
    attr(attributes, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("attribute {name} is not a number"))
}

/// Reads `plan.svg`; any XML error fails the test.
fn read_picture(path: &Path) -> Picture {
    let file = std::fs::File::open(path).unwrap();
    let mut picture = Picture::default();
    // The element names and group ids from the root down.
    let mut stack: Vec<(String, Option<String>)> = Vec::new();
    for event in EventReader::new(std::io::BufReader::new(file)) {
        match event.unwrap_or_else(|e| panic!("{}: not well-formed: {e}", path.display())) {
            XmlEvent::StartElement {
                name, attributes, ..
            } => {
                let group = stack.iter().rev().find_map(|(_, id)| id.clone());
                match (name.local_name.as_str(), group.as_deref()) {
                    ("svg", None) => {
                        picture.view_box = attr(&attributes, "viewBox")
                            .expect("a viewBox")
                            .split_whitespace()
                            .map(|v| v.parse().unwrap())
                            .collect();
                    }
                    ("circle", Some("pierces")) => picture
                        .pierces
                        .push([number(&attributes, "cx"), -number(&attributes, "cy")]),
                    ("circle", Some("overheats")) => picture.overheats += 1,
                    _ => {}
                }
                let id = attr(&attributes, "id");
                stack.push((name.local_name, id));
            }
            XmlEvent::EndElement { .. } => {
                stack.pop();
            }
            XmlEvent::Characters(text) => {
                let names: Vec<&str> = stack.iter().map(|(n, _)| n.as_str()).collect();
                let group = stack.iter().rev().find_map(|(_, id)| id.as_deref());
                match (names.as_slice(), group) {
                    (["svg", "title"], _) => picture.title = text.trim().to_string(),
                    ([.., "text"], Some("order")) => picture.labels.push(text.trim().to_string()),
                    _ => {}
                }
            }
            _ => {}
        }
    }
    assert!(stack.is_empty(), "unclosed elements: {stack:?}");
    picture
}

/// Runs `cell sheet` on `layout` with `args`; the plan, the report and the picture.
fn sheet(layout: &Path, args: &[&str]) -> (CutPlan, serde_json::Value, Picture, u64) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = std::process::Command::new(CELL)
        .args(["sheet", "--seed", "1"])
        .args(args)
        .arg("--layout")
        .arg(layout)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("plan.svg"), "{stdout}");
    let plan: CutPlan =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let svg = out.join("plan.svg");
    let size = std::fs::metadata(&svg).unwrap().len();
    (plan, report, read_picture(&svg), size)
}

/// The checks every picture passes (module docs).
fn assert_draws_the_plan(plan: &CutPlan, report: &serde_json::Value, picture: &Picture) {
    let n = report["contours"].as_u64().unwrap() as usize;
    assert_eq!(plan.order.len(), n);
    // One pierce marker per contour, where the plan pierces (machine coordinates, 0.01 mm).
    assert_eq!(picture.pierces.len(), n, "{picture:?}");
    for (k, (drawn, planned)) in picture.pierces.iter().zip(&plan.pierce_points).enumerate() {
        assert!(
            (drawn[0] - planned.x).abs() <= 0.006 && (drawn[1] - planned.y).abs() <= 0.006,
            "cut {}: drawn at {drawn:?}, pierced at ({}, {})",
            k + 1,
            planned.x,
            planned.y
        );
    }
    // The cut order numbered 1..=n.
    let expected: Vec<String> = (1..=n).map(|k| k.to_string()).collect();
    assert_eq!(picture.labels, expected);
    // One red circle per overheat.
    assert_eq!(
        picture.overheats as u64,
        report["overheats"].as_u64().unwrap()
    );
    // The report's figures in the title.
    let figures = format!(
        "{n} contours, idle {:.1} mm, cut {:.1} mm, {} overheats, max {:.0} °C above ambient",
        report["idle_length_mm"].as_f64().unwrap(),
        report["cut_length_mm"].as_f64().unwrap(),
        report["overheats"].as_u64().unwrap(),
        report["max_temperature_c"].as_f64().unwrap(),
    );
    assert!(
        picture.title.contains(&figures),
        "{} vs {figures}",
        picture.title
    );
    // Every pierce is in view.
    let [x, y, w, h] = picture.view_box[..] else {
        panic!("viewBox {:?}", picture.view_box)
    };
    for p in &picture.pierces {
        assert!(
            (x..=x + w).contains(&p[0]) && (y..=y + h).contains(&-p[1]),
            "{p:?}"
        );
    }
}

#[test]
fn cell_sheet_draws_the_example_plan() {
    let (plan, report, picture, _) = sheet(&data("example.json"), &[]);
    assert_eq!(report["contours"], 4);
    assert_draws_the_plan(&plan, &report, &picture);
}

#[test]
fn cell_sheet_marks_the_overheats_of_the_plate() {
    let (plan, report, picture, size) = sheet(&data("plate_holes_nest.json"), &["--no-improve"]);
    assert!(report["overheats"].as_u64().unwrap() > 0, "{report}");
    assert_draws_the_plan(&plan, &report, &picture);
    assert!(size < 200_000, "{size} bytes for 25 contours");
}
