//! The thermal model of a sheet being cut (module docs): heating where the tool passes, time
//! advancing with the tool, the overheat metric and the maximum temperature. The spread step
//! itself is the raster kernel's (`kernel`).

use cell_geometry::{polyline_length, Norm};
use serde::{Deserialize, Serialize};

use crate::problem::{distance, Contour, Point};

use super::kernel::{edge_bits, BLOCK, TH, TW};
use super::params::{SequencerParamError, ThermalParams};
use super::path::{cut_path, point_along};

/// One frame of the raster (for the `HeatMap` stream), seed 003 §A3.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// Spread steps since the start.
    pub step: u64,
    /// Simulated time, s.
    pub time_s: f64,
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    /// Cell size, mm.
    pub cell_mm: f64,
    /// Ambient temperature, °C; add it to `excess_c` for absolute values.
    pub ambient_c: f32,
    /// Row-major (`y * width + x`, y up from the sheet origin) excess over ambient, °C.
    pub excess_c: &'a [f32],
}

/// A callback receiving raster frames (seed 003 §A3 snapshots for the `HeatMap` stream).
pub type FrameObserver<'a> = &'a mut dyn FnMut(&Frame);

/// What cutting one contour did (seed 003 §A3, our overheat metric).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct CutThermal {
    /// Hottest temperature round the pierce point when it was pierced, °C.
    pub pierce_temp_c: f32,
    /// 1 if the pierce was an overheat.
    pub pierce_overheats: usize,
    /// Cut segments that started hot.
    pub segment_overheats: usize,
}

/// Totals of a simulated cut (seed 003 §A3).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ThermalOutcome {
    /// Overheats (pierces plus cut segments, see the module docs).
    pub overheats: usize,
    /// Hottest metal cell over the whole cut, °C.
    pub max_temp_c: f32,
    /// Simulated time including idle moves and the return to start, s.
    pub time_s: f64,
    /// Spread steps.
    pub steps: u64,
    /// Cell updates (the simulation's work; tiles updated × tile area).
    pub cells_updated: u64,
    /// Per contour, in cutting order.
    pub per_cut: Vec<CutThermal>,
    /// Where each overheat was counted, in cutting order: the pierce point or the start of a
    /// hot cut segment (for pictures of the plan, e.g. `plan.svg`).
    pub overheat_points: Vec<Point>,
}

/// The live raster while a sheet is cut (seed 003 §A3). Policies query it; the plan evaluator
/// drives it through a whole order.
pub struct ThermalSim<'a> {
    pub(super) params: ThermalParams,
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) melt_excess: f32,
    pub(super) t: Vec<f32>,
    pub(super) next: Vec<f32>,
    /// Conductivity of each cell (metal or air).
    pub(super) kc: Vec<f32>,
    /// 1 for metal, 0 for kerf (air from the moment it is melted; the metal maximum skips
    /// it), as `f32` so the maximum is a vector product. Kerf stays 1 when `k_air` equals
    /// `k_conductivity` (no air then).
    pub(super) metal: Vec<f32>,
    /// Cells melted since the last step: they turn into air after it.
    pub(super) fresh: Vec<usize>,
    pub(super) tiles_x: usize,
    pub(super) tiles_y: usize,
    /// Column and row of every tile (a lookup instead of a division per tile and step).
    pub(super) tile_xy: Vec<[u32; 2]>,
    pub(super) active: Vec<bool>,
    /// Edge flags per tile (heat on a border: its neighbour must be updated too).
    pub(super) edges: Vec<u8>,
    /// Cells next to kerf: they need the mixed-conductivity update.
    pub(super) slow: Vec<bool>,
    /// Per row and aligned [`BLOCK`] of columns: whether any of its cells is `slow`.
    pub(super) slow_block: Vec<bool>,
    /// Column blocks per row.
    pub(super) blocks_x: usize,
    pub(super) active_list: Vec<usize>,
    pub(super) stamp: Vec<u64>,
    pub(super) update_list: Vec<usize>,
    /// The previous step's update list (its tiles may hold stale values in `next`).
    pub(super) prev_update: Vec<usize>,
    /// New edge flags per entry of `update_list`.
    pub(super) new_edges: Vec<u8>,
    /// Update every tile every step (the exactness test's reference).
    pub(super) update_all: bool,
    pub(super) step: u64,
    pub(super) cells_updated: u64,
    pub(super) time_s: f64,
    pub(super) max_metal_excess: f32,
    pub(super) tool: Point,
    pub(super) overheats: usize,
    pub(super) per_cut: Vec<CutThermal>,
    pub(super) overheat_points: Vec<Point>,
    pub(super) observer: Option<(u64, FrameObserver<'a>)>,
}

impl<'a> ThermalSim<'a> {
    /// A sheet `sheet[0] × sheet[1]` mm at ambient temperature, tool at `start`.
    ///
    /// # Errors
    /// An invalid parameter, or a sheet size that is not finite and positive (field
    /// `sheet`), or a raster over [`super::MAX_RASTER_CELLS`] ([`ThermalParams::raster_size`]).
    pub fn new(
        sheet: [f64; 2],
        start: Point,
        params: &ThermalParams,
    ) -> Result<Self, SequencerParamError> {
        params.validate()?;
        let (width, height) = params.raster_size(sheet)?;
        let n = width * height;
        let tiles_x = width.div_ceil(TW);
        let tiles_y = height.div_ceil(TH);
        Ok(ThermalSim {
            params: params.clone(),
            width,
            height,
            melt_excess: params.t_melt_c - params.ambient_c,
            t: vec![0.0; n],
            next: vec![0.0; n],
            kc: vec![params.k_conductivity; n],
            metal: vec![1.0; n],
            fresh: Vec::new(),
            tiles_x,
            tiles_y,
            tile_xy: (0..tiles_x * tiles_y)
                .map(|t| [(t % tiles_x) as u32, (t / tiles_x) as u32])
                .collect(),
            active: vec![false; tiles_x * tiles_y],
            edges: vec![0; tiles_x * tiles_y],
            slow: vec![false; n],
            slow_block: vec![false; width.div_ceil(BLOCK) * height],
            blocks_x: width.div_ceil(BLOCK),
            active_list: Vec::new(),
            stamp: vec![0; tiles_x * tiles_y],
            update_list: Vec::new(),
            prev_update: Vec::new(),
            new_edges: Vec::new(),
            update_all: false,
            step: 0,
            cells_updated: 0,
            time_s: 0.0,
            max_metal_excess: 0.0,
            tool: start,
            overheats: 0,
            per_cut: Vec::new(),
            overheat_points: Vec::new(),
            observer: None,
        })
    }

    /// Calls `observer` with a [`Frame`] every `every` spread steps (`every ≥ 1`; 0 is
    /// treated as 1).
    pub fn with_frames(mut self, every: u64, observer: FrameObserver<'a>) -> Self {
        self.observer = Some((every.max(1), observer));
        self
    }

    /// Raster size `(width, height)`, cells.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The current raster as a frame.
    pub fn frame(&self) -> Frame<'_> {
        Frame {
            step: self.step,
            time_s: self.time_s,
            width: self.width,
            height: self.height,
            cell_mm: self.params.cell_mm,
            ambient_c: self.params.ambient_c,
            excess_c: &self.t,
        }
    }

    /// The parameters.
    pub fn params(&self) -> &ThermalParams {
        &self.params
    }

    /// Where the tool is.
    pub fn tool(&self) -> Point {
        self.tool
    }

    /// The cell holding `p` (clamped onto the sheet).
    fn cell(&self, p: Point) -> (usize, usize) {
        let c = |v: f64, n: usize| ((v / self.params.cell_mm).floor().max(0.0) as usize).min(n - 1);
        (c(p[0], self.width), c(p[1], self.height))
    }

    /// Temperature of the cell holding `p`, °C.
    pub fn temp_at_c(&self, p: Point) -> f32 {
        let (x, y) = self.cell(p);
        self.params.ambient_c + self.t[y * self.width + x]
    }

    /// Hottest cell within `overheat_radius_cells` of `p`, °C (the overheat test, module
    /// docs).
    pub fn hot_near_c(&self, p: Point) -> f32 {
        let (x, y) = self.cell(p);
        let r = self.params.overheat_radius_cells;
        let mut m = 0.0f32;
        for yy in y.saturating_sub(r)..=(y + r).min(self.height - 1) {
            let row = yy * self.width;
            for xx in x.saturating_sub(r)..=(x + r).min(self.width - 1) {
                m = m.max(self.t[row + xx]);
            }
        }
        self.params.ambient_c + m
    }

    /// Hottest metal cell so far, °C.
    pub fn max_temp_c(&self) -> f32 {
        self.params.ambient_c + self.max_metal_excess
    }

    /// Cell updates so far (tiles updated × tile area; the cost of the simulation).
    pub fn cells_updated(&self) -> u64 {
        self.cells_updated
    }

    /// Overheats so far.
    pub fn overheats(&self) -> usize {
        self.overheats
    }

    /// Simulated time so far, s.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    fn melt(&mut self, x: usize, y: usize) {
        let (w, h) = (self.width, self.height);
        let i = y * w + x;
        self.t[i] = self.melt_excess;
        self.fresh.push(i);
        if self.params.k_air != self.params.k_conductivity {
            self.metal[i] = 0.0;
        }
        // Cells next to kerf take the slow (mixed-conductivity) path from now on.
        for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
            for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                self.slow[yy * w + xx] = true;
                self.slow_block[yy * self.blocks_x + xx / BLOCK] = true;
            }
        }
        let tile = (y / TH) * self.tiles_x + x / TW;
        self.edges[tile] |= edge_bits(
            x % TW,
            y % TH,
            TW.min(w - x / TW * TW),
            TH.min(h - y / TH * TH),
        );
        if !self.active[tile] {
            self.active[tile] = true;
            self.active_list.push(tile);
        }
    }

    /// Advances time by `n` spread steps.
    pub fn spread_steps(&mut self, n: u64) {
        for _ in 0..n {
            self.spread();
        }
    }

    /// Spread steps for an idle move of `mm` (at least 0; rounded to the nearest step).
    pub fn idle_steps(&self, mm: f64) -> u64 {
        (mm / self.params.rapid_speed_mm_s / self.params.dt_s()).round() as u64
    }

    /// Idle move of the tool to `p`: no heating, time advances (seed 003 §A3).
    pub fn travel_to(&mut self, p: Point) {
        let steps = self.idle_steps(distance(self.tool, p));
        self.spread_steps(steps);
        self.tool = p;
    }

    /// Pierces `contour` at `pierce` (after an idle move there) and cuts once round it,
    /// returning what the overheat metric counted (module docs).
    pub fn cut_contour(&mut self, contour: &Contour, pierce: Point) -> CutThermal {
        self.cut_path_from(&cut_path(contour, pierce), false)
    }

    /// Cuts `contour` from its pierce candidate `k`: with leads ([`Contour::cut_path`]) the
    /// whole path, lead-in and lead-out heated too, one spread step per `cell_mm` of path
    /// (the flattened arcs of the cut path and the leads are much shorter than a cell);
    /// without, [`ThermalSim::cut_contour`] from the pierce point.
    pub fn cut(&mut self, contour: &Contour, k: usize) -> CutThermal {
        if contour.leads.is_empty() {
            self.cut_contour(contour, contour.pierce_candidates[k])
        } else {
            self.cut_path_from(&contour.cut_path(k), true)
        }
    }

    /// Pierces at `path[0]` (after an idle move there), cuts along `path` and leaves the tool
    /// at its end. `by_length`: one spread step per `cell_mm` of path; else per edge, at
    /// least one step per edge.
    fn cut_path_from(&mut self, path: &[Point], by_length: bool) -> CutThermal {
        let pierce = path[0];
        self.travel_to(pierce);
        // The overheat test, before this contour adds heat.
        let t_max = self.params.t_max_c;
        let pierce_temp_c = self.hot_near_c(pierce);
        let mut result = CutThermal {
            pierce_temp_c,
            pierce_overheats: usize::from(pierce_temp_c >= t_max),
            segment_overheats: 0,
        };
        if result.pierce_overheats > 0 {
            self.overheat_points.push(pierce);
        }
        let seg = self.params.segment_mm;
        let total = polyline_length(path, Norm::Hypot);
        let mut s = seg;
        while s < total {
            let at = point_along(path, s);
            if self.hot_near_c(at) >= t_max {
                result.segment_overheats += 1;
                self.overheat_points.push(at);
            }
            s += seg;
        }
        self.overheats += result.pierce_overheats + result.segment_overheats;
        // Pierce: melt and dwell.
        let (x, y) = self.cell(pierce);
        self.melt(x, y);
        let dwell = (self.params.pierce_dwell_s / self.params.dt_s()).round() as u64;
        self.spread_steps(dwell);
        // Cut: one cell per step along the path.
        let step_mm = self.params.cell_mm;
        if by_length {
            // Steps at every `step_mm` of path length, and one at its end.
            let mut next = step_mm;
            let mut at = 0.0;
            for w in path.windows(2) {
                let len = distance(w[0], w[1]);
                while next <= at + len && len > 0.0 {
                    let f = (next - at) / len;
                    let p = [
                        w[0][0] + f * (w[1][0] - w[0][0]),
                        w[0][1] + f * (w[1][1] - w[0][1]),
                    ];
                    let (x, y) = self.cell(p);
                    self.melt(x, y);
                    self.spread();
                    next += step_mm;
                }
                at += len;
            }
            if next - step_mm < at {
                let (x, y) = self.cell(path[path.len() - 1]);
                self.melt(x, y);
                self.spread();
            }
        } else {
            for w in path.windows(2) {
                let len = distance(w[0], w[1]);
                let n = (len / step_mm).ceil() as usize;
                for k in 1..=n {
                    let f = k as f64 / n as f64;
                    let p = [
                        w[0][0] + f * (w[1][0] - w[0][0]),
                        w[0][1] + f * (w[1][1] - w[0][1]),
                    ];
                    let (x, y) = self.cell(p);
                    self.melt(x, y);
                    self.spread();
                }
            }
        }
        self.tool = path[path.len() - 1];
        self.per_cut.push(result);
        result
    }

    /// Ends the cut: idle return to `end` and the totals.
    pub fn finish(mut self, end: Point) -> ThermalOutcome {
        self.travel_to(end);
        if std::env::var_os("SEQ_DEBUG_CELLS").is_some() {
            eprintln!(
                "steps {} cells/step {}",
                self.step,
                self.cells_updated / self.step.max(1)
            );
        }
        ThermalOutcome {
            overheats: self.overheats,
            max_temp_c: self.max_temp_c(),
            time_s: self.time_s,
            steps: self.step,
            cells_updated: self.cells_updated,
            per_cut: std::mem::take(&mut self.per_cut),
            overheat_points: std::mem::take(&mut self.overheat_points),
        }
    }
}
