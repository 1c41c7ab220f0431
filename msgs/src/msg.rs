//! `cell_msgs/msg/*` types, mirroring `msgs/msg/*.msg` field by field.

use serde::{Deserialize, Serialize};

use crate::geometry_msgs::{Point, Vector3};
use crate::std_msgs::Header;

/// A planned toolpath for one job: what the planner, sequencer and slicer publish and what the
/// emitter turns into a [`MachineProgram`]. Units: millimetres.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Toolpath {
    /// Frame and time of the path.
    pub header: Header,
    /// Job this toolpath belongs to; carried through to the MachineProgram.
    pub job_id: String,
    /// Which cell process this path is for (one of `PROCESS_*`).
    pub process: u8,
    /// Unit of every segment's `power` values (one of `POWER_*`).
    pub power_unit: u8,
    /// Distance between the primary and secondary planes \[mm\] (hot-wire tower separation);
    /// 0 if unused.
    pub plane_separation_mm: f64,
    /// The path's continuous runs, in order.
    pub segments: Vec<ToolpathSegment>,
}

impl Toolpath {
    /// Process: hot-wire foam cutting.
    pub const PROCESS_HOTWIRE: u8 = 0;
    /// Process: sheet cutting (laser, plasma, ...).
    pub const PROCESS_SHEET_CUT: u8 = 1;
    /// Process: wire-arc additive manufacturing.
    pub const PROCESS_WAAM: u8 = 2;
    /// Process: extrusion printing.
    pub const PROCESS_EXTRUSION: u8 = 3;
    /// Power unit: no power values.
    pub const POWER_NONE: u8 = 0;
    /// Power unit: hot-wire current \[A\].
    pub const POWER_WIRE_CURRENT_A: u8 = 1;
    /// Power unit: laser power \[%\].
    pub const POWER_LASER_PERCENT: u8 = 2;
    /// Power unit: arc on (1) / off (0).
    pub const POWER_ARC_ON: u8 = 3;
    /// Power unit: extrusion rate \[mm³/s\].
    pub const POWER_EXTRUSION_MM3_S: u8 = 4;
    /// Power unit: arc welding wire feed speed \[m/min\] (0: arc off).
    pub const POWER_WIRE_FEED_M_MIN: u8 = 5;
}

/// One continuous run of a toolpath: the tool moves through `points` in order. Units:
/// millimetres, millimetres per second. Frame: the parent Toolpath's `header.frame_id`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct ToolpathSegment {
    /// What the tool does along this segment (one of `KIND_*`).
    pub kind: u8,
    /// Layer index for layered processes (WAAM, extrusion); 0 otherwise.
    pub layer: u32,
    /// Primary-plane points: hot-wire root / XY carriage, laser or torch tip, nozzle tip.
    pub points: Vec<Point>,
    /// Secondary-plane points, empty or one per primary point: hot-wire tip / UV carriage.
    pub secondary_points: Vec<Point>,
    /// Tool axis direction per point, empty or one per point (robot orientation for WAAM and
    /// RAPID).
    pub normals: Vec<Vector3>,
    /// Feed along the path at each point \[mm/s\], one per point.
    pub feed_mm_s: Vec<f32>,
    /// Process power at each point, one per point, in the parent Toolpath's `power_unit`.
    pub power: Vec<f32>,
    /// WAAM bead width per point \[mm\]; empty for other processes.
    pub bead_width_mm: Vec<f32>,
    /// WAAM bead height per point \[mm\]; empty for other processes.
    pub bead_height_mm: Vec<f32>,
}

impl ToolpathSegment {
    /// The tool cuts along the segment.
    pub const KIND_CUT: u8 = 0;
    /// Rapid move with the tool inactive.
    pub const KIND_TRAVEL: u8 = 1;
    /// The tool deposits material (WAAM, extrusion).
    pub const KIND_DEPOSIT: u8 = 2;
    /// Lead-in or lead-out move.
    pub const KIND_LEAD: u8 = 3;
}

/// A scalar raster: sheet temperature, wire/surface exposure matrix, or a 1-row exposure
/// profile along a foil. Row-major, `height` rows of `width` cells.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct HeatMap {
    /// Frame and time of the raster.
    pub header: Header,
    /// What the raster shows, e.g. "sheet_temperature", "wire_exposure", "exposure_profile".
    pub quantity: String,
    /// Unit of `data` and `threshold`, e.g. "K", "J/mm^2", "1" for normalised values.
    pub unit: String,
    /// Number of columns.
    pub width: u32,
    /// Number of rows.
    pub height: u32,
    /// Cell pitch along columns (x) \[mm\]; 1 for index-space rasters.
    pub cell_width_mm: f64,
    /// Cell pitch along rows (y) \[mm\]; 1 for index-space rasters.
    pub cell_height_mm: f64,
    /// Position of the centre of cell (row 0, column 0) in `header.frame_id` \[mm\].
    pub origin: Point,
    /// Value of interest (overheat temperature, critical specific energy); NaN when none.
    pub threshold: f32,
    /// `height * width` values, row-major.
    pub data: Vec<f32>,
}

/// `HeatMap::new` got data whose length is not `width * height`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("heat map of {width}x{height} cells needs {} values, got {len}", u64::from(*.width) * u64::from(*.height))]
pub struct HeatMapSizeError {
    /// Requested width.
    pub width: u32,
    /// Requested height.
    pub height: u32,
    /// Length of the data given.
    pub len: usize,
}

/// A [`HeatMap`]'s fields before `data`, then the length of `data`: exactly the CDR that
/// precedes the floats (a sequence length is a 4-aligned `u32`, like any other).
#[derive(Serialize)]
struct HeatMapHeadRef<'a> {
    header: &'a Header,
    quantity: &'a str,
    unit: &'a str,
    width: u32,
    height: u32,
    cell_width_mm: f64,
    cell_height_mm: f64,
    origin: &'a Point,
    threshold: f32,
    data_len: u32,
}

/// The owned counterpart of [`HeatMapHeadRef`], for reading.
#[derive(Deserialize)]
struct HeatMapHead {
    header: Header,
    quantity: String,
    unit: String,
    width: u32,
    height: u32,
    cell_width_mm: f64,
    cell_height_mm: f64,
    origin: Point,
    threshold: f32,
    data_len: u32,
}

impl HeatMap {
    /// [`crate::to_cdr`] of this heat map, with `data` copied as one block (serde writes a
    /// float at a time: about 8 ms for a 1024×1024 frame). Same bytes.
    pub fn to_cdr_bulk(&self) -> Result<Vec<u8>, crate::CdrError> {
        let Ok(data_len) = u32::try_from(self.data.len()) else {
            return crate::to_cdr(self); // let the serializer report it
        };
        let head = HeatMapHeadRef {
            header: &self.header,
            quantity: &self.quantity,
            unit: &self.unit,
            width: self.width,
            height: self.height,
            cell_width_mm: self.cell_width_mm,
            cell_height_mm: self.cell_height_mm,
            origin: &self.origin,
            threshold: self.threshold,
            data_len,
        };
        let mut bytes = crate::to_cdr(&head)?;
        bytes.reserve(4 * self.data.len());
        for value in &self.data {
            bytes.extend_from_slice(&value.to_le_bytes());
        }
        Ok(bytes)
    }

    /// [`crate::from_cdr`] for a heat map, reading `data` as one block. Same result, same
    /// errors on short or malformed input.
    pub fn from_cdr_bulk(bytes: &[u8]) -> Result<Self, crate::CdrError> {
        use crate::cdr::{check_trailing, split_header, Endianness};
        let (endianness, body) = split_header(bytes)?;
        if endianness == Endianness::Big {
            return crate::from_cdr(bytes);
        }
        let (head, used) = cdr_encoding::from_bytes::<HeatMapHead, byteorder::LittleEndian>(body)?;
        let floats = body.get(used..).unwrap_or_default();
        let wanted = head.data_len as usize * 4;
        if floats.len() < wanted {
            // Let the serde path produce its usual "too short" error.
            return crate::from_cdr(bytes);
        }
        check_trailing(floats.len() - wanted)?;
        let data = floats[..wanted]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        Ok(Self {
            header: head.header,
            quantity: head.quantity,
            unit: head.unit,
            width: head.width,
            height: head.height,
            cell_width_mm: head.cell_width_mm,
            cell_height_mm: head.cell_height_mm,
            origin: head.origin,
            threshold: head.threshold,
            data,
        })
    }

    /// An index-space raster (1 mm cells at the origin, no threshold) after checking
    /// `data.len() == width * height`.
    pub fn new(
        quantity: impl Into<String>,
        unit: impl Into<String>,
        width: u32,
        height: u32,
        data: Vec<f32>,
    ) -> Result<Self, HeatMapSizeError> {
        if u64::from(width) * u64::from(height) != data.len() as u64 {
            return Err(HeatMapSizeError {
                width,
                height,
                len: data.len(),
            });
        }
        Ok(Self {
            quantity: quantity.into(),
            unit: unit.into(),
            width,
            height,
            cell_width_mm: 1.0,
            cell_height_mm: 1.0,
            threshold: f32::NAN,
            data,
            ..Default::default()
        })
    }
}

/// One file of a machine program: a G-code file, a RAPID module (.mod) or a program file (.pgf).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct ProgramFile {
    /// File name without directories, e.g. "job42.ngc", "MainModule.mod".
    pub name: String,
    /// File contents.
    pub text: String,
}

/// A complete program for one machine, produced by the emitter and streamed by machine_bridge.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct MachineProgram {
    /// Time of emission.
    pub header: Header,
    /// Job the program was emitted for.
    pub job_id: String,
    /// Output dialect: "grbl", "linuxcnc", "mach3", "marlin" or "rapid" (ABB RAPID).
    pub dialect: String,
    /// Machine profile (a name under config/machines) the program was emitted for.
    pub machine_profile: String,
    /// Program files; the first one is the entry point (the G-code file, or the RAPID main
    /// module).
    pub files: Vec<ProgramFile>,
    /// Total number of lines over all files.
    pub line_count: u32,
    /// Lower-case hex SHA-256 over the files' texts, concatenated in order.
    pub sha256: String,
}

/// State of one machine controller as seen by machine_bridge.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct MachineStatus {
    /// Time of the observation.
    pub header: Header,
    /// Which machine this is (machine profile name or controller address).
    pub machine_id: String,
    /// One of `STATE_*`.
    pub state: u8,
    /// Job being executed; empty when idle.
    pub job_id: String,
    /// Last program line the controller acknowledged, 1-based; 0 before the first.
    pub acked_line: u32,
    /// Lines in the program being executed.
    pub total_lines: u32,
    /// Axis names, e.g. X Y U V, in the order of `axis_positions`.
    pub axis_names: Vec<String>,
    /// Machine positions \[mm or deg\], one per axis name.
    pub axis_positions: Vec<f64>,
    /// Fill of the controller's receive or planner buffer, 0..1.
    pub buffer_fill: f32,
    /// Current feed \[mm/s\].
    pub feed_mm_s: f32,
    /// Alarm or error text from the controller; empty when none.
    pub alarm: String,
}

/// An operator command for one controller, acted on at once (within one status cycle).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq, Default)]
pub struct MachineCommand {
    /// Controller id; empty = every controller of the bridge.
    pub machine_id: String,
    /// One of `COMMAND_*`.
    pub command: u8,
    /// Percent for the overrides (10..200); unused otherwise.
    pub value: u16,
}

impl MachineCommand {
    /// Feed hold.
    pub const COMMAND_HOLD: u8 = 1;
    /// Resume after a hold.
    pub const COMMAND_RESUME: u8 = 2;
    /// Safe stop: hold, reset, heat off; a running program ends as aborted.
    pub const COMMAND_ABORT: u8 = 3;
    /// Feed override to `value` percent.
    pub const COMMAND_FEED_OVERRIDE: u8 = 4;
    /// Spindle (heat) override to `value` percent.
    pub const COMMAND_SPINDLE_OVERRIDE: u8 = 5;
}

impl MachineStatus {
    /// State not known yet.
    pub const STATE_UNKNOWN: u8 = 0;
    /// No connection to the controller.
    pub const STATE_DISCONNECTED: u8 = 1;
    /// Connected and idle.
    pub const STATE_IDLE: u8 = 2;
    /// Executing a program.
    pub const STATE_RUNNING: u8 = 3;
    /// Feed hold.
    pub const STATE_HOLD: u8 = 4;
    /// In alarm; see `alarm`.
    pub const STATE_ALARM: u8 = 5;
    /// Finished the program.
    pub const STATE_DONE: u8 = 6;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_map_new_checks_size() {
        let map = HeatMap::new("sheet_temperature", "K", 3, 2, vec![0.0; 6]).expect("6 = 3 x 2");
        assert_eq!((map.width, map.height, map.cell_width_mm), (3, 2, 1.0));
        assert!(map.threshold.is_nan());
        let err = HeatMap::new("t", "K", 3, 2, vec![0.0; 5]).expect_err("5 != 6");
        assert_eq!(
            err.to_string(),
            "heat map of 3x2 cells needs 6 values, got 5"
        );
    }
}

#[cfg(test)]
mod bulk_tests {
    use super::*;
    use crate::{from_cdr, to_cdr, RosMessage};

    fn sample(quantity: &str, width: u32, height: u32) -> HeatMap {
        let data = (0..width * height).map(|i| i as f32 * 0.5 - 3.0).collect();
        let mut h = HeatMap::new(quantity, "K", width, height, data).expect("sized");
        h.header.frame_id = "sheet".into();
        h.origin = Point {
            x: 1.0,
            y: -2.0,
            z: 0.25,
        };
        h.threshold = 573.0;
        h
    }

    #[test]
    fn bulk_codec_writes_and_reads_exactly_the_serde_bytes() {
        // Quantity lengths vary the padding before the 8-aligned doubles.
        for (quantity, w, h) in [
            ("", 0, 0),
            ("t", 3, 1),
            ("temp", 2, 5),
            ("sheet_temperature", 64, 32),
        ] {
            let hm = sample(quantity, w, h);
            let serde_bytes = to_cdr(&hm).unwrap();
            assert_eq!(
                hm.to_cdr_bulk().unwrap(),
                serde_bytes,
                "{quantity:?} {w}x{h}"
            );
            assert_eq!(hm.encode().unwrap(), serde_bytes);
            assert_eq!(HeatMap::from_cdr_bulk(&serde_bytes).unwrap(), hm);
            assert_eq!(
                HeatMap::decode(&serde_bytes).unwrap(),
                from_cdr::<HeatMap>(&serde_bytes).unwrap()
            );
        }
    }

    #[test]
    fn bulk_decoder_rejects_what_serde_rejects() {
        let bytes = sample("temp", 4, 4).to_cdr_bulk().unwrap();
        for cut in 0..bytes.len() {
            assert!(
                HeatMap::from_cdr_bulk(&bytes[..cut]).is_err(),
                "accepted {cut} of {} bytes",
                bytes.len()
            );
        }
        let mut long = bytes.clone();
        long.extend([0; 8]);
        assert!(
            HeatMap::from_cdr_bulk(&long).is_err(),
            "accepted 8 trailing bytes"
        );
    }
}

/// The order a nested sheet is cut in (seed 003): what the sequencer's `SequenceSheet` action
/// returns beside the [`Toolpath`]. Units: millimetres, degrees Celsius above ambient.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct CutPlan {
    /// Frame and time of the plan.
    pub header: Header,
    /// Job this plan belongs to; carried into the Toolpath.
    pub job_id: String,
    /// Contours in cut order, as indices into the layout's contour list.
    pub order: Vec<u32>,
    /// The part each cut contour belongs to, one per entry of `order`.
    pub parts: Vec<u32>,
    /// Where each cut pierces, one per entry of `order` (z = 0); with leads, the lead-in's
    /// start on the scrap side.
    pub pierce_points: Vec<Point>,
    /// The policy that built the order (nearest, min_overheat, random, path_overheat).
    pub policy: String,
    /// Whether the improvement phase ran.
    pub improved: bool,
    /// Rapid (idle) travel from the start point through every pierce point and back (with
    /// leads: from each cut's lead-out end to the next pierce).
    pub idle_length_mm: f64,
    /// Length cut, the sum of the contour perimeters (with leads: the cut paths and the leads).
    pub cut_length_mm: f64,
    /// Pierces and cut segments that started in an overheated cell.
    pub overheats: u32,
    /// Hottest cell over the whole simulated cut.
    pub max_temperature_c: f64,
    /// The objective: idle length + w · overheats + lead-in penalties.
    pub cost: f64,
    /// Kerf width, mm (0: cut on the drawn contours, no leads).
    pub kerf_mm: f64,
    /// How far the cut path lies off the drawn contour, mm (half the kerf; 0 when the
    /// controller compensates).
    pub path_offset_mm: f64,
    /// Lead-in length asked for, mm: the pierce's distance from the cut path (less where a
    /// lead had to be shortened).
    pub lead_in_mm: f64,
    /// Lead-out length, mm.
    pub lead_out_mm: f64,
}

/// One closed planar polygon of a slice, in the layer's plane (z from the parent
/// [`SliceLayer`]). Units: millimetres. Vertices in order, the last not repeating the first;
/// outer contours run counter-clockwise, holes clockwise.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct Polygon2 {
    /// Vertex x coordinates (one per vertex).
    pub x_mm: Vec<f64>,
    /// Vertex y coordinates (same length as `x_mm`).
    pub y_mm: Vec<f64>,
    /// True for a hole (odd nesting depth).
    pub is_hole: bool,
}

/// One layer of a sliced part: the closed contours the plane `z = z_mm` cuts from the mesh.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct SliceLayer {
    /// Layer number from the bottom (0-based).
    pub index: u32,
    /// Height of the slicing plane (and of the layer's toolpath) \[mm\].
    pub z_mm: f64,
    /// Closed contours: outer contours and holes.
    pub contours: Vec<Polygon2>,
    /// Chains the slicer could not close (an open mesh); they are not in `contours`.
    pub open_chains: u32,
}

/// The layers a part was sliced into (seed 004): what the slicer's `Slice` action returns
/// beside the [`Toolpath`] and publishes on `layer_stack`. Units: millimetres.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
pub struct LayerStack {
    /// Frame and time of the stack.
    pub header: Header,
    /// Job this stack belongs to; carried into the Toolpath.
    pub job_id: String,
    /// Distance between consecutive slicing planes \[mm\].
    pub layer_height_mm: f64,
    /// Height of the first plane \[mm\].
    pub first_z_mm: f64,
    /// The layers, bottom to top.
    pub layers: Vec<SliceLayer>,
}
