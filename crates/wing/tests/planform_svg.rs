//! The planform picture (`cell_wing::picture`, seed 002 Fig. 7) draws the design: read back
//! as XML by xml-rs (which shares no code with the writer), through the scale the module
//! documents (SVG x = y mm, SVG y = (x/c − x_h)·c mm), it holds every spar of X_sp where the
//! layout puts it, the main spar at x_τmax, the leading and trailing edges at the design's
//! chord, the section breaks at the sections' bounds, and the design case in its title.

use std::collections::HashMap;

use cell_wing::picture::planform_svg;
use cell_wing::spec::{Wing, WingSpec};
use xml::reader::{EventReader, XmlEvent};

fn wing(spec: &str) -> Wing {
    let path = format!(
        "{}/../../config/wings/{spec}.yaml",
        env!("CARGO_MANIFEST_DIR")
    );
    Wing::design(WingSpec::load(path).unwrap_or_else(|e| panic!("{e}")))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// One element: its name, the ids of it and its ancestors (innermost first), its attributes.
#[derive(Debug)]
struct Element {
    name: String,
    ids: Vec<String>,
    attributes: HashMap<String, String>,
}

impl Element {
    fn in_group(&self, id: &str) -> bool {
        self.ids.iter().any(|i| i == id)
    }

    fn number(&self, name: &str) -> f64 {
        self.attributes
            .get(name)
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{}: {name} is not a number", self.name))
    }

    fn points(&self) -> Vec<[f64; 2]> {
        self.attributes["points"]
            .split_whitespace()
            .map(|p| {
                let (x, y) = p.split_once(',').expect("x,y");
                [x.parse().unwrap(), y.parse().unwrap()]
            })
            .collect()
    }
}

/// Every element and every text (with its element's ids); any XML error fails the test.
fn parse(svg: &str) -> (Vec<Element>, Vec<(Vec<String>, String)>) {
    let mut elements = Vec::new();
    let mut texts = Vec::new();
    let mut ids: Vec<Option<String>> = Vec::new();
    for event in EventReader::new(svg.as_bytes()) {
        match event.unwrap_or_else(|e| panic!("not well-formed: {e}")) {
            XmlEvent::StartElement {
                name, attributes, ..
            } => {
                let attributes: HashMap<String, String> = attributes
                    .into_iter()
                    .map(|a| (a.name.local_name, a.value))
                    .collect();
                ids.push(attributes.get("id").cloned());
                elements.push(Element {
                    name: name.local_name,
                    ids: ids.iter().rev().flatten().cloned().collect(),
                    attributes,
                });
            }
            XmlEvent::EndElement { .. } => {
                ids.pop();
            }
            XmlEvent::Characters(text) => {
                let ids = ids.iter().rev().flatten().cloned().collect();
                texts.push((ids, text.trim().to_string()));
            }
            _ => {}
        }
    }
    assert!(ids.is_empty(), "unclosed elements");
    (elements, texts)
}

/// Drawn to the file's 0.01 mm.
fn near(a: f64, b: f64) -> bool {
    (a - b).abs() <= 0.006
}

fn check(spec: &str) {
    let w = wing(spec);
    let svg = planform_svg(&w, spec);
    let (elements, texts) = parse(&svg);
    let b = w.planform.span_mm;
    let x_h = w.spec.structure.hinge_x_over_c;
    let x_main = w.surfaces.x_max_thickness();
    let chord = &w.planform.chord_mm;
    let y_mm: Vec<f64> = w.spars.y_over_b.iter().map(|y| y * b).collect();
    let at = |j: usize, x_over_c: f64| [y_mm[j], (x_over_c - x_h) * chord[j]];
    let n = y_mm.len();

    // The title names the spec and the design case.
    let title: String = texts
        .iter()
        .filter(|(ids, _)| ids.iter().any(|i| i == "title"))
        .map(|(_, t)| t.as_str())
        .collect();
    assert!(
        title.contains(spec) && title.contains(&format!("design case {}", w.design.case)),
        "{title}"
    );

    // Leading and trailing edges at every station, root included: −x_h·c and (1 − x_h)·c.
    let edge = |id: &str| {
        elements
            .iter()
            .find(|e| e.attributes.get("id").is_some_and(|i| i == id))
            .unwrap_or_else(|| panic!("no {id}"))
            .points()
    };
    let (le, te) = (edge("leading-edge"), edge("trailing-edge"));
    assert_eq!((le.len(), te.len()), (n, n));
    let root = n / 2;
    assert!(y_mm[root].abs() < b / n as f64, "a station at the root");
    assert!(
        near(le[root][0], y_mm[root]) && near(le[root][1], -x_h * chord[root]),
        "root LE drawn at {:?}, chord {} mm",
        le[root],
        chord[root]
    );
    for j in 0..n {
        let (l, t) = (at(j, 0.0), at(j, 1.0));
        assert!(near(le[j][0], l[0]) && near(le[j][1], l[1]), "LE {j}");
        assert!(near(te[j][0], t[0]) && near(te[j][1], t[1]), "TE {j}");
    }

    // The main spar at x_τmax at every station.
    let main: Vec<&Element> = elements
        .iter()
        .filter(|e| e.name == "polyline" && e.in_group("main-spar"))
        .collect();
    assert_eq!(main.len(), 1);
    let main = main[0].points();
    assert_eq!(main.len(), n);
    for (j, p) in main.iter().enumerate() {
        let want = at(j, x_main);
        assert!(near(p[0], want[0]) && near(p[1], want[1]), "main spar {j}");
    }

    // Every other spar of every station, once: each station is crossed by as many spar
    // polylines (and dots) as the layout has spars there besides the main spar, at its x/c.
    let spars: Vec<Vec<[f64; 2]>> = elements
        .iter()
        .filter(|e| e.in_group("spars"))
        .filter_map(|e| match e.name.as_str() {
            "polyline" => Some(e.points()),
            "circle" => Some(vec![[e.number("cx"), e.number("cy")]]),
            _ => None,
        })
        .collect();
    let mut drawn: Vec<Vec<f64>> = vec![Vec::new(); n];
    for trace in &spars {
        let mut stations = Vec::new();
        for p in trace {
            let j = y_mm
                .iter()
                .position(|y| near(*y, p[0]))
                .unwrap_or_else(|| panic!("spar vertex {p:?} off the stations"));
            drawn[j].push(p[1]);
            stations.push(j);
        }
        assert!(
            stations.windows(2).all(|s| s[1] == s[0] + 1),
            "a spar polyline runs station by station: {stations:?}"
        );
    }
    for (j, xs) in w.spars.x_over_c.iter().enumerate() {
        let mut want: Vec<f64> = xs
            .iter()
            .filter(|x| **x != x_main)
            .map(|&x| at(j, x)[1])
            .collect();
        want.sort_by(f64::total_cmp);
        drawn[j].sort_by(f64::total_cmp);
        assert_eq!(drawn[j].len(), want.len(), "station {j}: spar count");
        for (d, s) in drawn[j].iter().zip(&want) {
            assert!(near(*d, *s), "station {j}: spar at {d}, layout {s}");
        }
    }
    // Where the layout's spars move smoothly along the span (the same count, none moving by
    // 1 % of the chord from one station to the next), they are that many unbroken polylines:
    // the longest such stretch.
    let smooth = |j: usize| {
        let (a, b) = (&w.spars.x_over_c[j - 1], &w.spars.x_over_c[j]);
        a.len() == b.len() && a.iter().zip(b).all(|(p, q)| (p - q).abs() < 0.01)
    };
    let (mut best, mut start) = ((0, 0), 0);
    for j in 1..=n {
        if j == n || !smooth(j) {
            if j - start > best.1 - best.0 {
                best = (start, j);
            }
            start = j;
        }
    }
    let count = w.spars.x_over_c[best.0].len() - 1;
    assert!(
        best.1 - best.0 >= 10 && count >= 1,
        "{best:?}, {count} spars"
    );
    let through = spars
        .iter()
        .filter(|t| {
            t.iter().any(|p| near(p[0], y_mm[best.0]))
                && t.iter().any(|p| near(p[0], y_mm[best.1 - 1]))
        })
        .count();
    assert_eq!(
        through, count,
        "stations {best:?} keep {count} spars besides the main spar: {through} polylines"
    );

    // The section breaks: vertical lines at the sections' bounds.
    let mut bounds: Vec<f64> = w
        .sections
        .iter()
        .flat_map(|s| [s.y_bed_mm, s.y_top_mm])
        .collect();
    bounds.sort_by(f64::total_cmp);
    bounds.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let mut breaks: Vec<f64> = elements
        .iter()
        .filter(|e| e.name == "line" && e.in_group("section-breaks"))
        .map(|e| {
            assert!(near(e.number("x1"), e.number("x2")), "vertical");
            e.number("x1")
        })
        .collect();
    breaks.sort_by(f64::total_cmp);
    assert_eq!(breaks.len(), bounds.len(), "{breaks:?} vs {bounds:?}");
    for (d, s) in breaks.iter().zip(&bounds) {
        assert!(near(*d, *s), "break at {d}, section bound {s}");
    }
    // Each section labelled with its index in the section list.
    let labels: Vec<&str> = texts
        .iter()
        .filter(|(ids, _)| ids.iter().any(|i| i == "section-labels"))
        .map(|(_, t)| t.as_str())
        .collect();
    for i in 0..w.sections.len() {
        assert!(labels.contains(&format!("#{i}").as_str()), "{labels:?}");
    }

    // The distributions: one curve each, one point per station, inside the picture.
    let view: Vec<f64> = elements[0].attributes["viewBox"]
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    for id in ["chord", "twist", "lift"] {
        let curves: Vec<_> = elements
            .iter()
            .filter(|e| e.name == "polyline" && e.in_group(id))
            .collect();
        assert_eq!(curves.len(), 1, "{id}");
        let pts = curves[0].points();
        assert_eq!(pts.len(), n, "{id}");
        for p in pts {
            assert!(
                (view[0]..=view[0] + view[2]).contains(&p[0])
                    && (view[1]..=view[1] + view[3]).contains(&p[1]),
                "{id}: {p:?} outside {view:?}"
            );
        }
    }
}

#[test]
fn the_table2_planform_draws_its_spars_edges_and_sections() {
    check("gwing-table2");
}

#[test]
fn a_two_point_design_is_drawn_with_its_case() {
    check("two-point-lift");
}
