//! Message views of a plan: the hot-wire `Toolpath` in machine coordinates and the exposure
//! `HeatMap`s, with their frame ids.

use cell_msgs::{
    builtin_interfaces::Time, geometry_msgs::Point, std_msgs::Header, HeatMap, Toolpath,
    ToolpathSegment,
};
use nalgebra::Point2;

use crate::exposure::{DistanceLaw, ExposureModel, Panels};

use super::{HotwirePlan, JobError, Motion};

/// Frame id of the planner's toolpaths: the hot-wire machine's coordinates (XY carriage plane
/// at z = 0, UV at z = tower separation).
pub const FRAME_ID: &str = "hotwire_machine";

/// Frame id of the planner's root-section exposure heat maps (LE at the origin).
pub const SECTION_FRAME_ID: &str = "hotwire_root";

/// Frame id of the tip-section exposure heat maps of a tapered panel.
pub const TIP_FRAME_ID: &str = "hotwire_tip";

impl HotwirePlan {
    /// The plan as a hot-wire `Toolpath` in machine coordinates (frame [`FRAME_ID`], wire
    /// current in A): LEAD in, CUT (closed), LEAD out. `points` are the XY carriage at z = 0;
    /// on a 4-axis machine `secondary_points` are the UV carriage at z = tower separation and
    /// `plane_separation_mm` is that separation. Feeds follow [`Motion`]'s convention.
    pub fn to_toolpath(&self, job_id: &str) -> Toolpath {
        let w = self.towers.separation_mm;
        let at = |p: &Point2<f64>, z: f64| Point { x: p.x, y: p.y, z };
        let segment = |kind, m: &Motion| ToolpathSegment {
            kind,
            points: m.xy.iter().map(|p| at(p, 0.0)).collect(),
            secondary_points: if self.four_axis {
                m.uv.iter().map(|p| at(p, w)).collect()
            } else {
                Vec::new()
            },
            feed_mm_s: m.feed_mm_s.iter().map(|&f| f as f32).collect(),
            power: m.current_a.iter().map(|&a| a as f32).collect(),
            ..Default::default()
        };
        Toolpath {
            header: Header {
                stamp: Time::now(),
                frame_id: FRAME_ID.into(),
            },
            job_id: job_id.into(),
            process: Toolpath::PROCESS_HOTWIRE,
            power_unit: Toolpath::POWER_WIRE_CURRENT_A,
            plane_separation_mm: w,
            segments: vec![
                segment(ToolpathSegment::KIND_LEAD, &self.lead_in),
                segment(ToolpathSegment::KIND_CUT, &self.cut),
                segment(ToolpathSegment::KIND_LEAD, &self.lead_out),
            ],
        }
    }

    /// The optimised exposure along the foil as a 1 × N raster (`exposure_profile`, one cell
    /// per panel from the TE, index space), threshold = CSE.
    pub fn exposure_heat_map(&self) -> HeatMap {
        profile_map(self.model, self.root.cse, &self.root.optimised_exposure)
    }

    /// The baseline exposure profile, as [`HotwirePlan::exposure_heat_map`].
    pub fn baseline_heat_map(&self) -> HeatMap {
        profile_map(self.model, self.root.cse, &self.root.baseline_exposure)
    }

    /// Every optimised wire segment's contribution to every panel: M × N (`wire_exposure`,
    /// rows = wire segments, columns = panels), threshold = CSE.
    ///
    /// # Errors
    /// The exposure model's (a degenerate path); not expected for a plan from
    /// [`plan`](super::plan).
    pub fn exposure_matrix_heat_map(&self) -> Result<HeatMap, JobError> {
        let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
            airfoil: self.root.airfoil.clone(),
            source: e.into(),
        };
        let panels = Panels::from_points(&self.root.surface).map_err(wrap)?;
        let (rows, cols, values) = self
            .model
            .exposure_matrix(&panels, &self.root.optimised)
            .map_err(wrap)?;
        Ok(heat_map(
            self.model,
            self.root.cse,
            "wire_exposure",
            cols,
            rows,
            values,
        ))
    }
}

pub(super) fn heat_map(
    model: ExposureModel,
    cse: f64,
    quantity: &str,
    width: usize,
    height: usize,
    data: Vec<f32>,
) -> HeatMap {
    HeatMap {
        header: Header {
            stamp: Time::now(),
            frame_id: SECTION_FRAME_ID.into(),
        },
        quantity: quantity.into(),
        unit: match model.law {
            DistanceLaw::Paper => "1",
            DistanceLaw::AuthorCode => "1/mm",
        }
        .into(),
        width: width as u32,
        height: height as u32,
        cell_width_mm: 1.0,
        cell_height_mm: 1.0,
        origin: Point::default(),
        threshold: cse as f32,
        data,
    }
}

/// A 1 × N `exposure_profile` raster of `exposure`, threshold = `cse`.
pub(super) fn profile_map(model: ExposureModel, cse: f64, exposure: &[f64]) -> HeatMap {
    heat_map(
        model,
        cse,
        "exposure_profile",
        exposure.len(),
        1,
        exposure.iter().map(|&e| e as f32).collect(),
    )
}
