//! A `Toolpath` as a `nav_msgs/Path`.

use cell_msgs::geometry_msgs::{Pose, PoseStamped};
use cell_msgs::nav_msgs::Path;
use cell_msgs::std_msgs::Header;
use cell_msgs::Toolpath;

use crate::{frames, units};

/// The toolpath's primary points (XY carriage, torch or nozzle tip), every segment in order
/// (travel and leads included), as one path in metres in the toolpath's frame
/// ([`frames::of_header`]) at its stamp. Orientations are the identity: a path shows where the
/// tool goes, the markers show what it does there.
pub fn toolpath_path(toolpath: &Toolpath) -> Path {
    let header = Header {
        stamp: toolpath.header.stamp,
        frame_id: frames::of_header(&toolpath.header),
    };
    let poses = toolpath
        .segments
        .iter()
        .flat_map(|s| &s.points)
        .map(|p| PoseStamped {
            header: header.clone(),
            pose: Pose {
                position: units::point_m(p),
                ..Default::default()
            },
        })
        .collect();
    Path { header, poses }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_msgs::geometry_msgs::Point;
    use cell_msgs::ToolpathSegment;

    #[test]
    fn points_become_poses_in_metres_in_order() {
        let mm = |x, y, z| Point { x, y, z };
        let toolpath = Toolpath {
            header: Header {
                frame_id: "sheet".into(),
                ..Default::default()
            },
            segments: vec![
                ToolpathSegment {
                    kind: ToolpathSegment::KIND_TRAVEL,
                    points: vec![mm(0.0, 0.0, 5.0), mm(100.0, 50.0, 5.0)],
                    ..Default::default()
                },
                ToolpathSegment {
                    kind: ToolpathSegment::KIND_CUT,
                    points: vec![mm(100.0, 50.0, 0.0), mm(250.0, 50.0, 0.0)],
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        let path = toolpath_path(&toolpath);
        assert_eq!(path.header.frame_id, "sheet");
        let xyz: Vec<(f64, f64, f64)> = path
            .poses
            .iter()
            .map(|p| (p.pose.position.x, p.pose.position.y, p.pose.position.z))
            .collect();
        assert_eq!(
            xyz,
            [
                (0.0, 0.0, 0.005),
                (0.1, 0.05, 0.005),
                (0.1, 0.05, 0.0),
                (0.25, 0.05, 0.0)
            ]
        );
        assert!(path.poses.iter().all(|p| p.header.frame_id == "sheet"));
        assert_eq!(path.poses[0].pose.orientation.w, 1.0);
    }
}
