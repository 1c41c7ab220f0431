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
//! Files: `params` (the constants and their checks), `sim` (the model: heating, time, the
//! overheat metric), `kernel` (the tiled spread step and its SIMD dispatch; none of it changes
//! a bit of the results), `path` (the cut path round a contour).

mod kernel;
mod params;
mod path;
mod sim;

pub(crate) use params::require;
pub use params::{SequencerParamError, ThermalParams, MAX_CUT_STEPS, MAX_RASTER_CELLS};
pub use path::cut_path;
pub(crate) use path::point_along;
pub use sim::{CutThermal, Frame, FrameObserver, ThermalOutcome, ThermalSim};

#[cfg(test)]
mod tests;
