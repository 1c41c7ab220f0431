//! The raster kernel: one double-buffered spread step (module docs) over tiles of `TW × TH`
//! cells, none of it changing a bit of the results against updating every cell.
//!
//! - Only tiles that hold heat (above `epsilon_c`), and their neighbours across a hot edge,
//!   are updated; smaller excesses are rounded to ambient. The rounding, the activity and edge
//!   flags and the metal maximum are taken in the same pass as the update, and the two buffers
//!   are swapped rather than copied (tiles that drop out of the update are zeroed in the write
//!   buffer).
//! - Rows of metal cells away from kerf take a plain stencil, other rows the
//!   mixed-conductivity one; that choice is made per aligned [`BLOCK`] of columns. Each full
//!   tile row is computed, rounded and folded (hottest value and metal maximum per lane, kerf
//!   as a 0/1 factor) in registers and stored once.
//! - Full tiles off the border are computed from a fixed-size copy of their
//!   `(TW + 2) × (TH + 2)` neighbourhood (no bounds checks, the same row kernels).
//! - The update is compiled for AVX2 and SSE4.2 and picked at run time (`multiversion`; no
//!   FMA contraction, so the same bits on every target).

use multiversion::multiversion;

use super::sim::ThermalSim;
use super::Frame;

/// Width of the update tiles, cells (divides [`BLOCK`]).
pub(super) const TW: usize = 8;
/// Height of the update tiles, cells.
pub(super) const TH: usize = 8;
/// Width of the aligned column blocks that pick a row's arithmetic (the plain metal stencil or
/// the mixed-conductivity one) and whether a tile's cells take the per-cell path. It is the
/// tile width of the first tiled version, kept so the tiling can change without changing a
/// single bit of the results (the two stencils round differently).
pub(super) const BLOCK: usize = 16;

/// Tile edge flags: heat on the left/right/bottom/top border of a tile, or anywhere.
pub(super) const LEFT: u8 = 1;
pub(super) const RIGHT: u8 = 2;
pub(super) const BOTTOM: u8 = 4;
pub(super) const TOP: u8 = 8;
pub(super) const ANY: u8 = 16;

/// Edge flags of cell `(x, y)` in a tile `tw × th`.
pub(super) fn edge_bits(x: usize, y: usize, tw: usize, th: usize) -> u8 {
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

impl ThermalSim<'_> {
    /// One double-buffered spread step (module docs).
    pub(super) fn spread(&mut self) {
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
}

/// Borrowed raster for one spread step (keeps the reads apart from the write buffer).
pub(super) struct Grid<'g> {
    pub(super) t: &'g [f32],
    pub(super) kc: &'g [f32],
    pub(super) slow: &'g [bool],
    pub(super) slow_block: &'g [bool],
    pub(super) blocks_x: usize,
    pub(super) metal: &'g [f32],
    pub(super) w: usize,
    pub(super) h: usize,
    pub(super) k_metal: f32,
    pub(super) k_loss: f32,
    pub(super) eps: f32,
    pub(super) tile_xy: &'g [[u32; 2]],
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

/// Updates `tiles` into the write buffer `next`: the new values with `k_loss` applied and
/// excesses below `epsilon_c` rounded to ambient. Writes each tile's new edge flags into
/// `edges` and returns the hottest new metal excess (0 if none). Compiled for AVX2 and SSE4.2 and picked
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
