//! Discrete thermal raster of the sheet (seed 003 §A3; notes §A3 give the rule and our reading
//! of it).
//!
//! The sheet `a × b` is a raster of square cells `cell_mm` wide. Each cell stores its
//! temperature as the **excess over ambient** (°C), so the paper's `K_loss` is a plain
//! multiplicative retention factor (1 = no loss).
//!
//! - **Heating** (seed 003 §A3): every cell the tool passes while piercing or cutting is set to
//!   the melting temperature. It conducts as metal for the one spread step in which it is
//!   melted (the molten kerf wall heats the metal around it), then becomes kerf "air" with the
//!   low conductivity `k_air`. Idle moves do not heat.
//! - **Spread** (seed 003 §A3, Fig. 4; notes §A3 interp): one step moves, between every cell
//!   `P` and each of its 8 on-sheet neighbours `S`, the heat `k·(P.T − S.T)` from the hotter to
//!   the colder, where `k = min(k(P), k(S))` is `k_conductivity` for metal and `k_air` for kerf.
//!   For a hot cell among ambient neighbours this is exactly the paper's `ΔT = P.T·K_c` per
//!   neighbour and `P.T − ΔT·count`; then every cell is multiplied by `k_loss`. Off-sheet
//!   neighbours do not count (insulated sheet edge). The update is double-buffered, so it does
//!   not depend on the order cells are visited and the result is bit-for-bit deterministic.
//!   `k_conductivity ≤ 1/8` keeps it stable (no cell can give more than it has).
//! - **Time** (notes §A3 interp): one spread step per tool advance of one cell, i.e. a time
//!   step `dt = cell_mm / cut_speed_mm_s`. Idle moves at `rapid_speed_mm_s` and the pierce
//!   dwell advance time by the matching number of steps.
//! - **Overheat metric** (ours; seed 003 leaves "local overheating" undefined, notes §A3): when
//!   a contour is pierced, before it adds any heat, count one overheat if the hottest cell
//!   within `overheat_radius_cells` of the pierce point is at or above `t_max_c`, and one more
//!   for every cut segment (the cut path split every `segment_mm` from the pierce point) whose
//!   start has such a hot neighbourhood. Kerf cells count: a fresh kerf next to the pierce is
//!   hot sheet.
//! - **Maximum temperature**: the hottest *metal* cell seen during the whole cut (kerf cells are
//!   at melting temperature by definition).
//!
//! Speed (issue 7; none of it changes a bit of the results): only tiles of 8 × 8 cells that
//! hold heat (above `epsilon_c`), and their neighbours across a hot edge, are updated; smaller
//! excesses are rounded to ambient. The rounding, the activity and edge flags and the metal
//! maximum are taken in the same pass as the update, and the two buffers are swapped rather
//! than copied (tiles that drop out of the update are zeroed in the write buffer). Rows of
//! metal cells away from kerf take a plain stencil, other rows the mixed-conductivity one;
//! that choice is made per aligned 16-column block (the earlier tile width, see `BLOCK`). The
//! update is compiled for AVX2 and SSE4.2 and picked at run time (no FMA contraction, so the
//! same bits on every target). 2026-11-22: the 1002-contour generator layout's raster run
//! went from ~2.3 s to ~1.6 s of CPU time (two threads per step did not pay on the shared
//! 2-core machine: the per-step work, ~30 µs, is too small for the hand-over). 2026-11-23:
//! ~1.1 s, by computing, rounding and folding each full tile row (hottest value and metal
//! maximum per lane, kerf as a 0/1 factor) in registers and storing it once: the earlier
//! per-row selects compiled to masked stores and a scalar maximum. About 70 % of the updated
//! cells hold heat; 8 × 4 tiles were slower. Then full tiles off the border are computed from a
//! fixed-size copy of their 10 × 10 neighbourhood (no bounds checks, the same row kernels),
//! ~10–20 % more, and `epsilon_c` 2 °C (its docs) ~0.8 s.

use multiversion::multiversion;
use serde::{Deserialize, Serialize};

use crate::problem::{distance, Contour, Point};

/// Width of the update tiles, cells (divides [`BLOCK`]).
const TW: usize = 8;
/// Height of the update tiles, cells.
const TH: usize = 8;
/// Width of the aligned column blocks that pick a row's arithmetic (the plain metal stencil or
/// the mixed-conductivity one) and whether a tile's cells take the per-cell path. It is the
/// tile width of the first tiled version, kept so the tiling can change without changing a
/// single bit of the results (the two stencils round differently).
const BLOCK: usize = 16;

/// Tile edge flags: heat on the left/right/bottom/top border of a tile, or anywhere.
const LEFT: u8 = 1;
const RIGHT: u8 = 2;
const BOTTOM: u8 = 4;
const TOP: u8 = 8;
const ANY: u8 = 16;

/// Edge flags of cell `(x, y)` in a tile `tw × th`.
fn edge_bits(x: usize, y: usize, tw: usize, th: usize) -> u8 {
    let mut e = ANY;
    if x == 0 {
        e |= LEFT;
    }
    if x + 1 == tw {
        e |= RIGHT;
    }
    if y == 0 {
        e |= BOTTOM;
    }
    if y + 1 == th {
        e |= TOP;
    }
    e
}

/// All constants of the thermal raster (seed 003 §A3). The paper gives no numbers (notes
/// §A0); the defaults are **ours**, for plasma cutting of ~6 mm mild steel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThermalParams {
    /// Raster cell size, mm. Default 4 (about two plasma kerf widths).
    pub cell_mm: f64,
    /// Ambient (initial sheet) temperature, °C. Default 20.
    pub ambient_c: f32,
    /// Melting temperature set in every cell the tool passes, °C. Default 1510 (mild steel).
    pub t_melt_c: f32,
    /// Overheat threshold `t_max`, °C. Default 300 (above this, mild steel parts visibly
    /// distort and lose tolerance).
    pub t_max_c: f32,
    /// Safety margin `delta` below `t_max` used by the thermal policies, °C. Default 100.
    pub delta_c: f32,
    /// `K_conductivity` between metal cells per step, `0 ≤ k ≤ 1/8`. Default 0.1.
    pub k_conductivity: f32,
    /// Conductivity to and from kerf ("air") cells per step, `0 ≤ k_air ≤ k_conductivity`.
    /// Default 0.01.
    pub k_air: f32,
    /// `K_loss` retention per step (1 = no loss), `0 < k ≤ 1`. Default 0.995 (with the
    /// default 0.1 s step: heat halves in about 14 s, convection and radiation from a 6 mm
    /// plate).
    pub k_loss: f32,
    /// Cutting feed, mm/s. Default 40 (2.4 m/min).
    pub cut_speed_mm_s: f64,
    /// Idle (rapid) speed, mm/s. Default 250 (15 m/min).
    pub rapid_speed_mm_s: f64,
    /// Pierce dwell, s; 0 disables it. Default 0.5.
    pub pierce_dwell_s: f64,
    /// Neighbourhood radius of the overheat test, cells (0 = the cell alone). Default 1.
    pub overheat_radius_cells: usize,
    /// Length of the cut segments counted by the overheat metric, mm. Default 20.
    pub segment_mm: f64,
    /// Excess below which a cell is rounded to ambient, °C. Default 2: a truncation far below
    /// every threshold that counts (`t_max − delta` = 200 °C). Against 1 °C on the bench's
    /// 1002-contour layout the nearest order keeps its overheats and cost, its maximum is
    /// 0.9 °C lower and 27 % fewer cells are updated; the 5005-contour one counts 221 overheats
    /// instead of 226 (2026-11-23). 4 °C changes the 1002-contour count (53, not 56).
    pub epsilon_c: f32,
}

impl Default for ThermalParams {
    fn default() -> Self {
        ThermalParams {
            cell_mm: 4.0,
            ambient_c: 20.0,
            t_melt_c: 1510.0,
            t_max_c: 300.0,
            delta_c: 100.0,
            k_conductivity: 0.1,
            k_air: 0.01,
            k_loss: 0.995,
            cut_speed_mm_s: 40.0,
            rapid_speed_mm_s: 250.0,
            pierce_dwell_s: 0.5,
            overheat_radius_cells: 1,
            segment_mm: 20.0,
            epsilon_c: 2.0,
        }
    }
}

/// A parameter out of range (names the field).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The field's value is not allowed.
    #[error("parameter `{field}` = {value}: {reason}")]
    Invalid {
        /// The field, as spelled in the config.
        field: &'static str,
        /// Its value.
        value: String,
        /// What it must be.
        reason: &'static str,
    },
}

/// Returns a [`ParamError::Invalid`] for `field` unless `ok`.
pub(crate) fn require(
    ok: bool,
    field: &'static str,
    value: impl ToString,
    reason: &'static str,
) -> Result<(), ParamError> {
    if ok {
        Ok(())
    } else {
        Err(ParamError::Invalid {
            field,
            value: value.to_string(),
            reason,
        })
    }
}

impl ThermalParams {
    /// Checks every field (seed 003 §A3 ranges; notes §A3 for `k_conductivity ≤ 1/8`).
    ///
    /// # Errors
    /// The first field out of range, by name.
    pub fn validate(&self) -> Result<(), ParamError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        require(
            pos(self.cell_mm),
            "cell_mm",
            self.cell_mm,
            "must be finite and > 0",
        )?;
        require(
            self.ambient_c.is_finite(),
            "ambient_c",
            self.ambient_c,
            "must be finite",
        )?;
        require(
            self.t_melt_c.is_finite() && self.t_melt_c > self.ambient_c,
            "t_melt_c",
            self.t_melt_c,
            "must be finite and above ambient_c",
        )?;
        require(
            self.t_max_c.is_finite()
                && self.t_max_c > self.ambient_c
                && self.t_max_c <= self.t_melt_c,
            "t_max_c",
            self.t_max_c,
            "must lie in (ambient_c, t_melt_c]",
        )?;
        require(
            self.delta_c.is_finite() && self.delta_c >= 0.0,
            "delta_c",
            self.delta_c,
            "must be finite and ≥ 0",
        )?;
        require(
            (0.0..=0.125).contains(&self.k_conductivity),
            "k_conductivity",
            self.k_conductivity,
            "must lie in [0, 1/8] (8 neighbours may not take more than the cell has)",
        )?;
        require(
            self.k_air >= 0.0 && self.k_air <= self.k_conductivity,
            "k_air",
            self.k_air,
            "must lie in [0, k_conductivity]",
        )?;
        require(
            self.k_loss > 0.0 && self.k_loss <= 1.0,
            "k_loss",
            self.k_loss,
            "must lie in (0, 1]",
        )?;
        require(
            pos(self.cut_speed_mm_s),
            "cut_speed_mm_s",
            self.cut_speed_mm_s,
            "must be finite and > 0",
        )?;
        require(
            pos(self.rapid_speed_mm_s),
            "rapid_speed_mm_s",
            self.rapid_speed_mm_s,
            "must be finite and > 0",
        )?;
        require(
            self.pierce_dwell_s.is_finite() && self.pierce_dwell_s >= 0.0,
            "pierce_dwell_s",
            self.pierce_dwell_s,
            "must be finite and ≥ 0",
        )?;
        require(
            self.overheat_radius_cells <= 16,
            "overheat_radius_cells",
            self.overheat_radius_cells,
            "must be ≤ 16",
        )?;
        require(
            pos(self.segment_mm),
            "segment_mm",
            self.segment_mm,
            "must be finite and > 0",
        )?;
        require(
            self.epsilon_c.is_finite() && self.epsilon_c >= 0.0,
            "epsilon_c",
            self.epsilon_c,
            "must be finite and ≥ 0",
        )?;
        Ok(())
    }

    /// The time step, s: one cell of cutting (notes §A3 interp).
    pub fn dt_s(&self) -> f64 {
        self.cell_mm / self.cut_speed_mm_s
    }
}

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
}

/// The live raster while a sheet is cut (seed 003 §A3). Policies query it; the plan evaluator
/// drives it through a whole order.
pub struct ThermalSim<'a> {
    params: ThermalParams,
    width: usize,
    height: usize,
    melt_excess: f32,
    t: Vec<f32>,
    next: Vec<f32>,
    /// Conductivity of each cell (metal or air).
    kc: Vec<f32>,
    /// 1 for metal, 0 for kerf (air from the moment it is melted; the metal maximum skips
    /// it), as `f32` so the maximum is a vector product. Kerf stays 1 when `k_air` equals
    /// `k_conductivity` (no air then).
    metal: Vec<f32>,
    /// Cells melted since the last step: they turn into air after it.
    fresh: Vec<usize>,
    tiles_x: usize,
    tiles_y: usize,
    /// Column and row of every tile (a lookup instead of a division per tile and step).
    tile_xy: Vec<[u32; 2]>,
    active: Vec<bool>,
    /// Edge flags per tile (heat on a border: its neighbour must be updated too).
    edges: Vec<u8>,
    /// Cells next to kerf: they need the mixed-conductivity update.
    slow: Vec<bool>,
    /// Per row and aligned [`BLOCK`] of columns: whether any of its cells is `slow`.
    slow_block: Vec<bool>,
    /// Column blocks per row.
    blocks_x: usize,
    active_list: Vec<usize>,
    stamp: Vec<u64>,
    update_list: Vec<usize>,
    /// The previous step's update list (its tiles may hold stale values in `next`).
    prev_update: Vec<usize>,
    /// New edge flags per entry of `update_list`.
    new_edges: Vec<u8>,
    /// Update every tile every step (the exactness test's reference).
    update_all: bool,
    step: u64,
    cells_updated: u64,
    time_s: f64,
    max_metal_excess: f32,
    tool: Point,
    overheats: usize,
    per_cut: Vec<CutThermal>,
    observer: Option<(u64, FrameObserver<'a>)>,
}

impl<'a> ThermalSim<'a> {
    /// A sheet `sheet[0] × sheet[1]` mm at ambient temperature, tool at `start`.
    ///
    /// # Errors
    /// An invalid parameter, or a sheet size that is not finite and positive (field
    /// `sheet`), or a raster over 10⁸ cells (field `cell_mm`).
    pub fn new(sheet: [f64; 2], start: Point, params: &ThermalParams) -> Result<Self, ParamError> {
        params.validate()?;
        require(
            sheet.iter().all(|v| v.is_finite() && *v > 0.0),
            "sheet",
            format!("{sheet:?}"),
            "must be finite and > 0",
        )?;
        let width = (sheet[0] / params.cell_mm).ceil().max(1.0) as usize;
        let height = (sheet[1] / params.cell_mm).ceil().max(1.0) as usize;
        require(
            (width as f64) * (height as f64) <= 1e8,
            "cell_mm",
            params.cell_mm,
            "gives a raster over 10^8 cells for this sheet",
        )?;
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

    /// One double-buffered spread step (module docs).
    fn spread(&mut self) {
        self.step += 1;
        self.time_s = self.step as f64 * self.params.dt_s();
        // The tiles to update: the active ones, and their neighbours across an edge that
        // holds heat (heat moves one cell per step).
        self.update_list.clear();
        let stamp = self.step;
        let (tiles_x, tiles_y) = (self.tiles_x, self.tiles_y);
        for &tile in &self.active_list {
            let [tx, ty] = self.tile_xy[tile].map(|v| v as usize);
            let e = self.edges[tile];
            let left = e & LEFT != 0 && tx > 0;
            let right = e & RIGHT != 0 && tx + 1 < tiles_x;
            let below = e & BOTTOM != 0 && ty > 0;
            let above = e & TOP != 0 && ty + 1 < tiles_y;
            let candidates = [
                (true, tile),
                (left, tile.wrapping_sub(1)),
                (right, tile + 1),
                (below, tile.wrapping_sub(tiles_x)),
                (above, tile + tiles_x),
                (left && below, tile.wrapping_sub(tiles_x + 1)),
                (right && below, tile.wrapping_sub(tiles_x).wrapping_add(1)),
                (left && above, (tile + tiles_x).wrapping_sub(1)),
                (right && above, tile + tiles_x + 1),
            ];
            for (needed, n) in candidates {
                if needed && self.stamp[n] != stamp {
                    self.stamp[n] = stamp;
                    self.update_list.push(n);
                }
            }
        }
        if self.update_all {
            self.update_list.clear();
            self.update_list.extend(0..self.tiles_x * self.tiles_y);
            self.stamp.fill(stamp);
        }
        // Deterministic order regardless of how tiles were activated (the update itself is
        // double-buffered, so order only matters for the active list).
        self.update_list.sort_unstable();
        let (w, h) = (self.width, self.height);
        self.cells_updated += (self.update_list.len() * TW * TH) as u64;
        let grid = Grid {
            t: &self.t,
            kc: &self.kc,
            slow: &self.slow,
            slow_block: &self.slow_block,
            blocks_x: self.blocks_x,
            metal: &self.metal,
            w,
            h,
            k_metal: self.params.k_conductivity,
            k_loss: self.params.k_loss,
            eps: self.params.epsilon_c,
            tile_xy: &self.tile_xy,
        };
        self.new_edges.clear();
        self.new_edges.resize(self.update_list.len(), 0);
        let max_metal = update_tiles(
            &grid,
            &self.update_list,
            &mut self.next,
            &mut self.new_edges,
        );
        self.max_metal_excess = self.max_metal_excess.max(max_metal);
        // Tiles updated last step but not now hold stale values in the write buffer: they
        // are zero in the current state (inactive, no heat reaching them), so zero them.
        for &tile in &self.prev_update {
            if self.stamp[tile] != stamp {
                let [tx, ty] = self.tile_xy[tile].map(|v| v as usize);
                let (x0, y0) = (tx * TW, ty * TH);
                let (x1, y1) = ((x0 + TW).min(w), (y0 + TH).min(h));
                for y in y0..y1 {
                    self.next[y * w + x0..y * w + x1].fill(0.0);
                }
            }
        }
        // The write buffer now holds the whole new state (see above): swap.
        std::mem::swap(&mut self.t, &mut self.next);
        std::mem::swap(&mut self.prev_update, &mut self.update_list);
        // Fresh kerf turns into air after its one step as molten metal.
        for &i in &self.fresh {
            self.kc[i] = self.params.k_air;
        }
        self.fresh.clear();
        self.active_list.clear();
        for (&tile, &edges) in self.prev_update.iter().zip(&self.new_edges) {
            self.edges[tile] = edges;
            self.active[tile] = edges != 0;
            if edges != 0 {
                self.active_list.push(tile);
            }
        }
        if let Some((every, observer)) = self.observer.as_mut() {
            if self.step.is_multiple_of(*every) {
                let frame = Frame {
                    step: self.step,
                    time_s: self.time_s,
                    width: self.width,
                    height: self.height,
                    cell_mm: self.params.cell_mm,
                    ambient_c: self.params.ambient_c,
                    excess_c: &self.t,
                };
                observer(&frame);
            }
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
        self.travel_to(pierce);
        let path = cut_path(contour, pierce);
        // The overheat test, before this contour adds heat.
        let t_max = self.params.t_max_c;
        let pierce_temp_c = self.hot_near_c(pierce);
        let mut result = CutThermal {
            pierce_temp_c,
            pierce_overheats: usize::from(pierce_temp_c >= t_max),
            segment_overheats: 0,
        };
        let seg = self.params.segment_mm;
        let total: f64 = path.windows(2).map(|w| distance(w[0], w[1])).sum();
        let mut s = seg;
        while s < total {
            if self.hot_near_c(point_along(&path, s)) >= t_max {
                result.segment_overheats += 1;
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
        self.tool = pierce;
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
        }
    }
}

/// Borrowed raster for one spread step (keeps the reads apart from the write buffer).
struct Grid<'g> {
    t: &'g [f32],
    kc: &'g [f32],
    slow: &'g [bool],
    slow_block: &'g [bool],
    blocks_x: usize,
    metal: &'g [f32],
    w: usize,
    h: usize,
    k_metal: f32,
    k_loss: f32,
    eps: f32,
    tile_xy: &'g [[u32; 2]],
}

impl Grid<'_> {
    /// Rounds a freshly computed row to ambient below `epsilon_c` and folds it into the
    /// tile's per-lane accumulators: `hot` the largest value kept (0 if none), `metal_max` the
    /// hottest metal cell. Branch-free so it vectorises (every input is finite and ≥ 0).
    #[inline(always)]
    fn finish_row(&self, out: &mut [f32], metal: &[f32], hot: &mut [f32], metal_max: &mut [f32]) {
        let eps = self.eps;
        let n = out.len();
        let (metal, hot, metal_max) = (&metal[..n], &mut hot[..n], &mut metal_max[..n]);
        for l in 0..n {
            let v = out[l];
            // `v` or 0 as a product (v ≥ 0): a select here becomes masked stores.
            let x = v * f32::from(u8::from(v >= eps));
            out[l] = x;
            hot[l] = hot[l].max(x);
            metal_max[l] = metal_max[l].max(x * metal[l]);
        }
    }

    /// `T + Σ k·(T_S − T)` over on-sheet neighbours (before `k_loss`), any cell.
    #[inline(always)]
    fn generic_cell(&self, x: usize, y: usize) -> f32 {
        let (w, h) = (self.w, self.h);
        let i = y * w + x;
        let (ti, ki) = (self.t[i], self.kc[i]);
        let mut acc = 0.0f32;
        for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
            for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                let j = yy * w + xx;
                if j != i {
                    acc += ki.min(self.kc[j]) * (self.t[j] - ti);
                }
            }
        }
        ti + acc
    }

    /// A run of interior metal cells `a..b` of one row (none next to kerf), written with
    /// `k_loss` applied ([`Grid::metal_row`]).
    #[inline(always)]
    fn metal_run(&self, a: usize, b: usize, out: &mut [f32]) {
        let (w, t) = (self.w, self.t);
        let n = b - a;
        Self::metal_row(
            &t[a - w - 1..b - w + 1],
            &t[a - 1..b + 1],
            &t[a + w - 1..b + w + 1],
            self.k_metal,
            self.k_loss,
            &mut out[..n],
        );
    }

    /// Metal cells of one row from the rows below (`d`), at (`m`) and above (`u`), each one
    /// cell wider on both sides: `(T + k(Σ neighbours − 8·T))·k_loss`, in a form the compiler
    /// vectorises.
    #[inline(always)]
    fn metal_row(u: &[f32], m: &[f32], d: &[f32], k: f32, k_loss: f32, out: &mut [f32]) {
        let n = out.len();
        let (u, m, d) = (&u[..n + 2], &m[..n + 2], &d[..n + 2]);
        for (x, o) in out.iter_mut().enumerate() {
            let ti = m[x + 1];
            let s = u[x] + u[x + 1] + u[x + 2] + m[x] + m[x + 2] + d[x] + d[x + 1] + d[x + 2];
            *o = (ti + k * (s - 8.0 * ti)) * k_loss;
        }
    }

    /// A run of interior cells `a..b` of one row with any mix of metal and kerf, written with
    /// `k_loss` applied ([`Grid::mixed_row`]).
    #[inline(always)]
    fn mixed_run(&self, a: usize, b: usize, out: &mut [f32]) {
        let (w, t, kc) = (self.w, self.t, self.kc);
        let n = b - a;
        Self::mixed_row(
            [
                &t[a - w - 1..b - w + 1],
                &t[a - 1..b + 1],
                &t[a + w - 1..b + w + 1],
            ],
            [
                &kc[a - w - 1..b - w + 1],
                &kc[a - 1..b + 1],
                &kc[a + w - 1..b + w + 1],
            ],
            self.k_loss,
            &mut out[..n],
        );
    }

    /// Cells of one row with any mix of metal and kerf, from the temperatures `t` and
    /// conductivities `k` of the rows below, at and above, each one cell wider on both sides:
    /// `(T + Σ min(k_P, k_S)(T_S − T))·k_loss`, in a form the compiler vectorises.
    #[inline(always)]
    fn mixed_row(t: [&[f32]; 3], k: [&[f32]; 3], k_loss: f32, out: &mut [f32]) {
        let n = out.len();
        // Known lengths let the compiler drop the bounds checks and vectorise.
        let (u, m, d) = (&t[0][..n + 2], &t[1][..n + 2], &t[2][..n + 2]);
        let (ku, km, kd) = (&k[0][..n + 2], &k[1][..n + 2], &k[2][..n + 2]);
        for (x, o) in out.iter_mut().enumerate() {
            let (ti, ki) = (m[x + 1], km[x + 1]);
            let f = |tj: f32, kj: f32| ki.min(kj) * (tj - ti);
            let acc = f(u[x], ku[x])
                + f(u[x + 1], ku[x + 1])
                + f(u[x + 2], ku[x + 2])
                + f(m[x], km[x])
                + f(m[x + 2], km[x + 2])
                + f(d[x], kd[x])
                + f(d[x + 1], kd[x + 1])
                + f(d[x + 2], kd[x + 2]);
            *o = (ti + acc) * k_loss;
        }
    }

    /// A full tile off the sheet border (`x0 ≥ 1`, `y0 ≥ 1`, one cell to spare beyond it):
    /// its neighbourhood copied once into fixed-size arrays, every row computed, rounded and
    /// folded there (the same arithmetic as the per-row path), each row stored once. Returns
    /// the tile's BOTTOM/TOP edge flags.
    #[inline(always)]
    fn interior_tile(
        &self,
        x0: usize,
        y0: usize,
        next: &mut [f32],
        hot: &mut [f32; TW],
        metal_max: &mut [f32; TW],
    ) -> u8 {
        const W: usize = TW + 2;
        let w = self.w;
        let mut t = [[0.0f32; W]; TH + 2];
        let mut k = [[0.0f32; W]; TH + 2];
        for r in 0..TH + 2 {
            let start = (y0 + r - 1) * w + x0 - 1;
            t[r].copy_from_slice(&self.t[start..start + W]);
            k[r].copy_from_slice(&self.kc[start..start + W]);
        }
        let mut e = 0u8;
        for r in 0..TH {
            let y = y0 + r;
            let row = y * w + x0;
            let mut v = [0.0f32; TW];
            if self.slow_block[y * self.blocks_x + x0 / BLOCK] {
                Self::mixed_row(
                    [&t[r], &t[r + 1], &t[r + 2]],
                    [&k[r], &k[r + 1], &k[r + 2]],
                    self.k_loss,
                    &mut v,
                );
            } else {
                Self::metal_row(
                    &t[r],
                    &t[r + 1],
                    &t[r + 2],
                    self.k_metal,
                    self.k_loss,
                    &mut v,
                );
            }
            self.finish_row(&mut v, &self.metal[row..row + TW], hot, metal_max);
            next[row..row + TW].copy_from_slice(&v);
            e |= end_row_flags(r == 0, r + 1 == TH, &v);
        }
        e
    }

    /// Any other tile (at the sheet border, or cut short by it), row by row: interior runs
    /// through the row kernels, border cells through [`Grid::generic_cell`]; rounded and folded
    /// as in [`Grid::interior_tile`]. Returns the tile's BOTTOM/TOP edge flags.
    #[inline(always)]
    fn edge_tile(
        &self,
        [x0, x1]: [usize; 2],
        [y0, y1]: [usize; 2],
        interior_cols: bool,
        next: &mut [f32],
        hot: &mut [f32; TW],
        metal_max: &mut [f32; TW],
    ) -> u8 {
        let (w, h) = (self.w, self.h);
        let mut e = 0u8;
        for y in y0..y1 {
            let border_row = y == 0 || y + 1 == h;
            let row = y * w;
            let out = &mut next[row + x0..row + x1];
            if !border_row && interior_cols {
                if self.slow_block[y * self.blocks_x + x0 / BLOCK] {
                    self.mixed_run(row + x0, row + x1, out);
                } else {
                    self.metal_run(row + x0, row + x1, out);
                }
            } else {
                for (x, o) in (x0..x1).zip(out.iter_mut()) {
                    let v = if border_row || x == 0 || x + 1 == w {
                        self.generic_cell(x, y)
                    } else {
                        self.interior_cell(row + x)
                    };
                    *o = v * self.k_loss;
                }
            }
            self.finish_row(out, &self.metal[row + x0..row + x1], hot, metal_max);
            e |= end_row_flags(y == y0, y + 1 == y1, out);
        }
        e
    }

    /// The same for a cell off the sheet border, unrolled.
    #[inline(always)]
    fn interior_cell(&self, i: usize) -> f32 {
        let w = self.w;
        let t = self.t;
        let ti = t[i];
        let (u, m, d) = (
            &t[i - w - 1..i - w + 2],
            &t[i - 1..i + 2],
            &t[i + w - 1..i + w + 2],
        );
        if !self.slow[i] {
            // Metal among metal: k(Σ neighbours − 8·T).
            let s = u[0] + u[1] + u[2] + m[0] + m[2] + d[0] + d[1] + d[2];
            return ti + self.k_metal * (s - 8.0 * ti);
        }
        let kc = self.kc;
        let ki = kc[i];
        let (ku, km, kd) = (
            &kc[i - w - 1..i - w + 2],
            &kc[i - 1..i + 2],
            &kc[i + w - 1..i + w + 2],
        );
        let acc = ki.min(ku[0]) * (u[0] - ti)
            + ki.min(ku[1]) * (u[1] - ti)
            + ki.min(ku[2]) * (u[2] - ti)
            + ki.min(km[0]) * (m[0] - ti)
            + ki.min(km[2]) * (m[2] - ti)
            + ki.min(kd[0]) * (d[0] - ti)
            + ki.min(kd[1]) * (d[1] - ti)
            + ki.min(kd[2]) * (d[2] - ti);
        ti + acc
    }
}

/// BOTTOM if `first` and TOP if `last` (a tile's first and last row), when the finished row
/// holds heat.
#[inline(always)]
fn end_row_flags(first: bool, last: bool, row: &[f32]) -> u8 {
    if (first || last) && row.iter().any(|&v| v > 0.0) {
        (if first { BOTTOM } else { 0 }) | (if last { TOP } else { 0 })
    } else {
        0
    }
}

/// Updates `tiles` into the write buffer `next`: the new values with `k_loss` applied and excesses below
/// `epsilon_c` rounded to ambient. Writes each tile's new edge flags into `edges` and
/// returns the hottest new metal excess (0 if none). Compiled for AVX2 and SSE4.2 and picked
/// at run time (`multiversion`; no FMA, so every target gives the same bits).
#[multiversion(targets("x86_64+avx2", "x86_64+sse4.2"))]
fn update_tiles(grid: &Grid, tiles: &[usize], next: &mut [f32], edges: &mut [u8]) -> f32 {
    let (w, h) = (grid.w, grid.h);
    let mut max_metal = 0.0f32;
    for (&tile, e_out) in tiles.iter().zip(edges.iter_mut()) {
        let [tx, ty] = grid.tile_xy[tile].map(|v| v as usize);
        let (x0, y0) = (tx * TW, ty * TH);
        let (x1, y1) = ((x0 + TW).min(w), (y0 + TH).min(h));
        // The arithmetic is chosen per aligned BLOCK of columns (see `BLOCK`).
        let bx0 = x0 / BLOCK * BLOCK;
        let bx1 = (bx0 + BLOCK).min(w);
        let interior_cols = bx0 > 0 && bx1 < w;
        let mut hot = [0.0f32; TW];
        let mut metal_max = [0.0f32; TW];
        let mut e = if interior_cols && x1 - x0 == TW && y0 > 0 && y0 + TH < h {
            grid.interior_tile(x0, y0, next, &mut hot, &mut metal_max)
        } else {
            grid.edge_tile(
                [x0, x1],
                [y0, y1],
                interior_cols,
                next,
                &mut hot,
                &mut metal_max,
            )
        };
        let tile_w = x1 - x0;
        if hot[..tile_w].iter().any(|&v| v > 0.0) {
            e |= ANY;
        }
        if hot[0] > 0.0 {
            e |= LEFT;
        }
        if hot[tile_w - 1] > 0.0 {
            e |= RIGHT;
        }
        max_metal = metal_max
            .iter()
            .fold(max_metal, |m, &v| if v > m { v } else { m });
        *e_out = e;
    }
    max_metal
}

/// The closed cut path of `contour` from `pierce` round and back to it: the pierce point is
/// projected onto the nearest polyline edge (seed 003 §A1: a cut starts and ends at its
/// pierce point). Degenerate contours (fewer than 2 points) give `[pierce, pierce]`.
pub fn cut_path(contour: &Contour, pierce: Point) -> Vec<Point> {
    let pts = &contour.points;
    let n = pts.len();
    if n < 2 {
        return vec![pierce, pierce];
    }
    let mut best = (f64::INFINITY, 0usize, pierce);
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let q = project(a, b, pierce);
        let d = distance(q, pierce);
        if d < best.0 {
            best = (d, i, q);
        }
    }
    let (_, i, q) = best;
    let mut path = Vec::with_capacity(n + 3);
    path.push(pierce);
    if distance(q, pierce) > 0.0 {
        path.push(q);
    }
    for k in 1..=n {
        path.push(pts[(i + k) % n]);
    }
    path.push(q);
    if distance(q, pierce) > 0.0 {
        path.push(pierce);
    }
    path
}

/// The point of segment `a–b` nearest to `p` (`a` if the segment is degenerate).
pub(crate) fn project(a: Point, b: Point, p: Point) -> Point {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    if l2 == 0.0 {
        return a;
    }
    let t = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0);
    [a[0] + t * d[0], a[1] + t * d[1]]
}

/// The point at arc length `s` along a polyline (its end if `s` is past it).
pub(crate) fn point_along(path: &[Point], mut s: f64) -> Point {
    for w in path.windows(2) {
        let len = distance(w[0], w[1]);
        if s <= len && len > 0.0 {
            let f = s / len;
            return [
                w[0][0] + f * (w[1][0] - w[0][0]),
                w[0][1] + f * (w[1][1] - w[0][1]),
            ];
        }
        s -= len;
    }
    *path.last().unwrap_or(&[0.0, 0.0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::ContourRole;

    fn square(x: f64, y: f64, s: f64) -> Contour {
        Contour {
            part: 0,
            role: ContourRole::Outer,
            points: vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]],
            pierce_candidates: vec![[x, y]],
        }
    }

    #[test]
    fn bad_params_name_the_field() {
        let p = ThermalParams {
            k_conductivity: 0.2,
            ..Default::default()
        };
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("k_conductivity"), "{e}");
        let p = ThermalParams {
            cut_speed_mm_s: 0.0,
            ..Default::default()
        };
        assert!(p
            .validate()
            .unwrap_err()
            .to_string()
            .contains("cut_speed_mm_s"));
        assert!(ThermalSim::new([0.0, 1.0], [0.0, 0.0], &ThermalParams::default()).is_err());
    }

    /// A lone hot cell among ambient neighbours gives each `ΔT = P.T·K_c` (seed 003 §A3).
    #[test]
    fn spread_matches_the_paper_for_a_hot_cell() {
        let p = ThermalParams {
            k_loss: 1.0,
            epsilon_c: 0.0,
            ..Default::default()
        };
        let mut sim = ThermalSim::new([40.0, 40.0], [0.0, 0.0], &p).unwrap();
        sim.t[5 * 10 + 5] = 1000.0;
        sim.active[0] = true;
        sim.edges[0] = ANY;
        sim.active_list.push(0);
        sim.spread();
        let dt = 1000.0 * p.k_conductivity;
        assert!((sim.t[4 * 10 + 4] - dt).abs() < 1e-3);
        assert!((sim.t[5 * 10 + 5] - (1000.0 - 8.0 * dt)).abs() < 1e-3);
        // Heat is conserved with k_loss = 1.
        let total: f32 = sim.t.iter().sum();
        assert!((total - 1000.0).abs() < 1e-2, "{total}");
    }

    #[test]
    fn cutting_heats_and_is_deterministic() {
        let run = || {
            let mut sim =
                ThermalSim::new([200.0, 200.0], [0.0, 0.0], &ThermalParams::default()).unwrap();
            let a = square(20.0, 75.0, 50.0);
            let b = square(20.0, 20.0, 50.0);
            sim.cut_contour(&a, [20.0, 75.0]);
            let hot = sim.cut_contour(&b, [20.0, 70.0]);
            (sim.frame().excess_c.to_vec(), hot, sim.finish([0.0, 0.0]))
        };
        let (t1, hot, o1) = run();
        let (t2, _, o2) = run();
        assert_eq!(
            t1.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            t2.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(o1, o2);
        assert!(o1.max_temp_c > 300.0, "{}", o1.max_temp_c);
        // The second square is pierced 5 mm from where the first one ended.
        assert!(hot.pierce_overheats + hot.segment_overheats > 0, "{hot:?}");
    }

    /// The tiled, fast-path update agrees with a plain full-grid reference of the rule
    /// (seed 003 §A3, module docs) after kerf cuts and many steps.
    #[test]
    fn tiled_update_matches_the_reference() {
        let p = ThermalParams::default();
        let mut sim = ThermalSim::new([150.0, 120.0], [0.0, 0.0], &p).unwrap();
        sim.cut_contour(&square(2.0, 2.0, 60.0), [2.0, 2.0]);
        sim.cut_contour(&square(70.0, 30.0, 40.0), [70.0, 30.0]);
        let (w, h) = sim.size();
        let mut t = sim.t.clone();
        let kc = sim.kc.clone();
        for _ in 0..40 {
            let mut next = vec![0.0f32; w * h];
            for y in 0..h {
                for x in 0..w {
                    let i = y * w + x;
                    let mut acc = 0.0f32;
                    for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                        for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                            let j = yy * w + xx;
                            if j != i {
                                acc += kc[i].min(kc[j]) * (t[j] - t[i]);
                            }
                        }
                    }
                    let v = (t[i] + acc) * p.k_loss;
                    next[i] = if v < p.epsilon_c { 0.0 } else { v };
                }
            }
            t = next;
            sim.spread();
        }
        let worst = t
            .iter()
            .zip(&sim.t)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 0.01, "tiled vs reference differ by {worst} °C");
        assert!(t.iter().any(|&v| v > 100.0));
    }

    /// Skipping cold tiles, the swapped buffers and the zeroing of tiles that drop out change
    /// no bit against updating every tile every step (module docs, Speed).
    #[test]
    fn sparse_update_is_bit_identical_to_updating_everything() {
        let run = |all: bool| {
            let p = ThermalParams::default();
            // A hash of the whole raster after every step.
            let mut hashes = Vec::new();
            let mut obs = |f: &Frame| {
                let h = f.excess_c.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
                    (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01b3)
                });
                hashes.push(h);
            };
            let mut sim = ThermalSim::new([150.0, 123.0], [0.0, 0.0], &p)
                .unwrap()
                .with_frames(1, &mut obs);
            sim.update_all = all;
            sim.cut_contour(&square(2.0, 2.0, 60.0), [2.0, 2.0]);
            sim.cut_contour(&square(70.0, 30.0, 40.0), [70.0, 30.0]);
            sim.cut_contour(&square(30.0, 80.0, 30.0), [31.0, 80.0]);
            sim.travel_to([149.0, 122.0]);
            // Long enough for kerf to cool below epsilon_c: tiles drop out of the update.
            sim.spread_steps(1200);
            sim.cut_contour(&square(100.0, 90.0, 20.0), [100.0, 90.0]);
            sim.spread_steps(50);
            let t: Vec<u32> = sim.t.iter().map(|v| v.to_bits()).collect();
            let out = sim.finish([0.0, 0.0]);
            (t, out, hashes)
        };
        let (t_sparse, o_sparse, h_sparse) = run(false);
        let (t_all, o_all, h_all) = run(true);
        assert!(t_sparse.iter().any(|&b| f32::from_bits(b) > 100.0));
        assert_eq!(t_sparse, t_all);
        assert_eq!(h_sparse.len() as u64, o_sparse.steps);
        assert_eq!(h_sparse, h_all, "the rasters differ after some step");
        assert_eq!(o_sparse.max_temp_c.to_bits(), o_all.max_temp_c.to_bits());
        assert_eq!(o_sparse.per_cut, o_all.per_cut);
        assert!(o_sparse.cells_updated < o_all.cells_updated);
    }

    #[test]
    fn frames_arrive_every_n_steps() {
        let mut frames = Vec::new();
        let mut obs = |f: &Frame| frames.push(f.step);
        let mut sim = ThermalSim::new([100.0, 100.0], [0.0, 0.0], &ThermalParams::default())
            .unwrap()
            .with_frames(10, &mut obs);
        sim.cut_contour(&square(10.0, 10.0, 20.0), [10.0, 10.0]);
        let out = sim.finish([0.0, 0.0]);
        assert_eq!(frames.len() as u64, out.steps / 10);
        assert!(frames.iter().all(|s| s % 10 == 0));
    }
}
