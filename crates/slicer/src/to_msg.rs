//! The sliced layers as a `cell_msgs::LayerStack` (kept apart from the job, which knows nothing
//! of message types). The toolpath message comes from [`cell_waam::to_msg::toolpath_msg`].

use cell_msgs::std_msgs::Header;
use cell_msgs::{LayerStack, Polygon2, SliceLayer};

/// The stack as a message: one `SliceLayer` per layer, one `Polygon2` per closed contour
/// (open chains only counted).
pub fn layer_stack_msg(stack: &cell_mesh::LayerStack, job_id: &str, frame_id: &str) -> LayerStack {
    LayerStack {
        header: Header {
            stamp: cell_msgs::builtin_interfaces::Time::now(),
            frame_id: frame_id.into(),
        },
        job_id: job_id.into(),
        layer_height_mm: stack.layer_height_mm,
        first_z_mm: stack.first_z_mm,
        layers: stack
            .layers
            .iter()
            .map(|l| SliceLayer {
                index: l.index as u32,
                z_mm: l.z_mm,
                contours: l
                    .contours
                    .iter()
                    .map(|c| Polygon2 {
                        x_mm: c.points.iter().map(|p| p[0]).collect(),
                        y_mm: c.points.iter().map(|p| p[1]).collect(),
                        is_hole: c.is_hole,
                    })
                    .collect(),
                open_chains: l.open_chains.len() as u32,
            })
            .collect(),
    }
}
