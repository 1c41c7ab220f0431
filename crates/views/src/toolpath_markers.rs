//! A `Toolpath` as a `visualization_msgs/MarkerArray`: what the tool does where, by colour.

use cell_msgs::geometry_msgs::{Point, Vector3};
use cell_msgs::std_msgs::Header;
use cell_msgs::visualization_msgs::{Marker, MarkerArray};
use cell_msgs::Toolpath;

use crate::kind_style::kind_style;
use crate::{frames, units, ViewError};

/// The toolpath as markers, in metres in its frame ([`frames::of_header`]) at its stamp:
///
/// 1. a `DELETEALL`, so the previous toolpath's markers on the topic go;
/// 2. one `LINE_LIST` per (segment kind, layer), in order of first appearance: namespace the
///    kind (`cut`, `travel`, `deposit`, `lead`; [`kind_style`]), id the layer (WAAM and wing
///    layers are separate markers, so a viewer can show or hide each), its colour and width
///    the kind's, each segment's consecutive points as line pairs;
/// 3. for hot-wire toolpaths with secondary points (the UV carriage), the same per kind and
///    layer in namespace `<kind>/secondary`, half transparent.
///
/// Segments of fewer than two points draw nothing.
///
/// # Errors
/// [`ViewError::SecondaryPoints`] when a segment has secondary points but not one per point.
pub fn toolpath_markers(toolpath: &Toolpath) -> Result<MarkerArray, ViewError> {
    let header = Header {
        stamp: toolpath.header.stamp,
        frame_id: frames::of_header(&toolpath.header),
    };
    // (kind, layer, secondary) → index into `lines`, in order of first appearance.
    let mut groups: Vec<((u8, u32, bool), Vec<Point>)> = Vec::new();
    let mut add = |key: (u8, u32, bool), points: &[Point]| {
        let index = match groups.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                groups.push((key, Vec::new()));
                groups.len() - 1
            }
        };
        let lines = &mut groups[index].1;
        for pair in points.windows(2) {
            lines.push(units::point_m(&pair[0]));
            lines.push(units::point_m(&pair[1]));
        }
    };
    for (i, s) in toolpath.segments.iter().enumerate() {
        if !s.secondary_points.is_empty() && s.secondary_points.len() != s.points.len() {
            return Err(ViewError::SecondaryPoints {
                job_id: toolpath.job_id.clone(),
                segment: i,
                primary: s.points.len(),
                secondary: s.secondary_points.len(),
            });
        }
        add((s.kind, s.layer, false), &s.points);
        if !s.secondary_points.is_empty() {
            add((s.kind, s.layer, true), &s.secondary_points);
        }
    }
    let mut markers = vec![Marker {
        header: header.clone(),
        action: Marker::DELETEALL,
        ..Default::default()
    }];
    markers.extend(
        groups
            .into_iter()
            .filter(|(_, lines)| !lines.is_empty())
            .map(|((kind, layer, secondary), points)| {
                let style = kind_style(kind);
                let mut color = style.color;
                let mut ns = style.namespace;
                if secondary {
                    color.a *= 0.5;
                    ns.push_str("/secondary");
                }
                Marker {
                    header: header.clone(),
                    ns,
                    id: i32::try_from(layer).unwrap_or(i32::MAX),
                    type_: Marker::LINE_LIST,
                    action: Marker::ADD,
                    scale: Vector3 {
                        x: style.width_m,
                        ..Default::default()
                    },
                    color,
                    points,
                    ..Default::default()
                }
            }),
    );
    Ok(MarkerArray { markers })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kind_style;
    use cell_msgs::ToolpathSegment;

    fn mm(x: f64, y: f64, z: f64) -> Point {
        Point { x, y, z }
    }

    fn segment(kind: u8, layer: u32, points: Vec<Point>) -> ToolpathSegment {
        ToolpathSegment {
            kind,
            layer,
            points,
            ..Default::default()
        }
    }

    /// A two-layer WAAM toolpath: deposit, travel, deposit per layer.
    fn waam() -> Toolpath {
        let (d, t) = (ToolpathSegment::KIND_DEPOSIT, ToolpathSegment::KIND_TRAVEL);
        Toolpath {
            header: Header {
                frame_id: "work_object".into(),
                ..Default::default()
            },
            process: Toolpath::PROCESS_WAAM,
            segments: vec![
                segment(
                    d,
                    0,
                    vec![mm(0.0, 0.0, 2.0), mm(100.0, 0.0, 2.0), mm(100.0, 20.0, 2.0)],
                ),
                segment(t, 0, vec![mm(100.0, 20.0, 2.0), mm(0.0, 40.0, 2.0)]),
                segment(d, 0, vec![mm(0.0, 40.0, 2.0), mm(50.0, 40.0, 2.0)]),
                segment(d, 1, vec![mm(0.0, 0.0, 4.0), mm(100.0, 0.0, 4.0)]),
                segment(t, 1, vec![mm(7.0, 7.0, 4.0)]),
            ],
            ..Default::default()
        }
    }

    #[test]
    fn one_marker_per_kind_and_layer_coloured_by_kind() {
        let array = toolpath_markers(&waam()).expect("valid");
        let m = &array.markers;
        assert_eq!(m[0].action, Marker::DELETEALL);
        let keys: Vec<(&str, i32)> = m[1..].iter().map(|m| (m.ns.as_str(), m.id)).collect();
        // Layer 1's travel has one point: no marker.
        assert_eq!(keys, [("deposit", 0), ("travel", 0), ("deposit", 1)]);
        assert!(m[1..]
            .iter()
            .all(|m| m.type_ == Marker::LINE_LIST && m.header.frame_id == "work_object"));
        assert_eq!(m[1].color, kind_style::DEPOSIT);
        assert_eq!(m[2].color, kind_style::TRAVEL);
        // Layer 0 deposits: 2 + 1 line pairs, in metres.
        let xyz: Vec<(f64, f64, f64)> = m[1].points.iter().map(|p| (p.x, p.y, p.z)).collect();
        assert_eq!(
            xyz,
            [
                (0.0, 0.0, 0.002),
                (0.1, 0.0, 0.002),
                (0.1, 0.0, 0.002),
                (0.1, 0.02, 0.002),
                (0.0, 0.04, 0.002),
                (0.05, 0.04, 0.002),
            ]
        );
        assert_eq!(m[3].points[1].x, 0.1);
        assert_eq!(m[3].points[1].z, 0.004);
    }

    #[test]
    fn secondary_points_get_their_own_namespace_and_bad_ones_are_refused() {
        let cut = ToolpathSegment {
            kind: ToolpathSegment::KIND_CUT,
            points: vec![mm(0.0, 0.0, 0.0), mm(10.0, 0.0, 0.0)],
            secondary_points: vec![mm(0.0, 0.0, 600.0), mm(12.0, 0.0, 600.0)],
            ..Default::default()
        };
        let mut toolpath = Toolpath {
            job_id: "wing".into(),
            segments: vec![cut],
            ..Default::default()
        };
        let array = toolpath_markers(&toolpath).expect("valid");
        let ns: Vec<&str> = array.markers.iter().map(|m| m.ns.as_str()).collect();
        assert_eq!(ns, ["", "cut", "cut/secondary"]);
        assert_eq!(array.markers[0].header.frame_id, frames::CELL);
        assert_eq!(array.markers[2].points[1].z, 0.6);
        assert_eq!(array.markers[2].color.a, kind_style::CUT.a * 0.5);
        toolpath.segments[0].secondary_points.pop();
        let e = toolpath_markers(&toolpath).unwrap_err();
        assert!(
            e.to_string()
                .contains("segment 0 has 1 secondary points for 2"),
            "{e}"
        );
    }
}
