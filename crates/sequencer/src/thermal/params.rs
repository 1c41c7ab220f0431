//! The raster's constants ([`ThermalParams`]), their checks, and the error a parameter out of
//! range gives ([`SequencerParamError`], shared by the crate's other parameter sets).

use serde::{Deserialize, Serialize};

/// Most cells the thermal raster may have (issue 23: `cell_mm` or a layout's `sheet` set its
/// size). The raster keeps ~17 bytes a cell (temperature and its next step, conductivity,
/// metal fraction, kerf flags), so 1.7 GB at the limit; a 3 × 1.5 m sheet is 2.8·10⁵ cells
/// at the default 4 mm and 1.8·10⁷ at 0.5 mm, a 12 × 3 m plate 3.6·10⁷ at 1 mm.
pub const MAX_RASTER_CELLS: usize = 100_000_000;

/// Most raster steps cutting the contours may take: their perimeters over `cell_mm` (issue
/// 23: a comb of 20 000 points across a 10 m sheet is 2·10⁷ steps, 10⁶ points 10⁹). A step is
/// ~30 µs of raster work (benches README), so the limit is ~5 minutes per raster run; a
/// 12 × 3 m plate's 3 km of cut at 0.5 mm is 6·10⁶, the 1002-contour benchmark ~3·10⁴.
pub const MAX_CUT_STEPS: usize = 10_000_000;

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
    /// every threshold that counts (`t_max − delta` = 200 °C); against 1 °C it updates about a
    /// quarter fewer cells (benches README).
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

/// A sequencer parameter out of range (names the field): of the thermal raster
/// ([`ThermalParams`]), the improvement phase (`ImproveParams`) or the cost model
/// (`CostParams`). Not the node's parameter error (`cell_runtime::NodeParamError`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SequencerParamError {
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
    /// The sheet's raster at `cell_mm` is over [`MAX_RASTER_CELLS`].
    #[error(
        "sheet {w} × {h} mm at cell_mm = {cell_mm} mm is a raster of {cells:.3e} cells: the \
         limit is {MAX_RASTER_CELLS} cells (MAX_RASTER_CELLS)",
        w = .sheet[0],
        h = .sheet[1]
    )]
    RasterTooLarge {
        /// Sheet size, mm.
        sheet: [f64; 2],
        /// Raster cell size, mm.
        cell_mm: f64,
        /// Cells it would take.
        cells: f64,
    },
    /// Cutting the contours would take more than [`MAX_CUT_STEPS`] raster steps.
    #[error(
        "the contours' cut length of {cut_mm:.0} mm at cell_mm = {cell_mm} mm is {steps:.3e} \
         raster steps: the limit is {MAX_CUT_STEPS} steps (MAX_CUT_STEPS)"
    )]
    CutTooLong {
        /// Total perimeter of the contours, mm.
        cut_mm: f64,
        /// Raster cell size, mm.
        cell_mm: f64,
        /// Steps it would take.
        steps: f64,
    },
}

/// Returns a [`SequencerParamError::Invalid`] for `field` unless `ok`.
pub(crate) fn require(
    ok: bool,
    field: &'static str,
    value: impl ToString,
    reason: &'static str,
) -> Result<(), SequencerParamError> {
    if ok {
        Ok(())
    } else {
        Err(SequencerParamError::Invalid {
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
    pub fn validate(&self) -> Result<(), SequencerParamError> {
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

    /// The raster `(width, height)`, cells, of a `sheet[0] × sheet[1]` mm sheet
    /// (`⌈size / cell_mm⌉`, at least 1). Call after [`ThermalParams::validate`].
    ///
    /// # Errors
    /// A sheet size that is not finite and positive (field `sheet`), or a raster over
    /// [`MAX_RASTER_CELLS`] ([`SequencerParamError::RasterTooLarge`]).
    pub fn raster_size(&self, sheet: [f64; 2]) -> Result<(usize, usize), SequencerParamError> {
        require(
            sheet.iter().all(|v| v.is_finite() && *v > 0.0),
            "sheet",
            format!("{sheet:?}"),
            "must be finite and > 0",
        )?;
        let width = (sheet[0] / self.cell_mm).ceil().max(1.0);
        let height = (sheet[1] / self.cell_mm).ceil().max(1.0);
        let cells = width * height;
        // Compared as f64: a 10¹² mm sheet's cells overflow no integer here.
        if cells > MAX_RASTER_CELLS as f64 {
            return Err(SequencerParamError::RasterTooLarge {
                sheet,
                cell_mm: self.cell_mm,
                cells,
            });
        }
        Ok((width as usize, height as usize))
    }

    /// Checks that cutting `cut_mm` of contours, one raster step per `cell_mm`, stays within
    /// [`MAX_CUT_STEPS`]. Call after [`ThermalParams::validate`].
    ///
    /// # Errors
    /// [`SequencerParamError::CutTooLong`].
    pub fn check_cut_steps(&self, cut_mm: f64) -> Result<(), SequencerParamError> {
        let steps = (cut_mm / self.cell_mm).ceil();
        if steps > MAX_CUT_STEPS as f64 || steps.is_nan() {
            return Err(SequencerParamError::CutTooLong {
                cut_mm,
                cell_mm: self.cell_mm,
                steps,
            });
        }
        Ok(())
    }

    /// The time step, s: one cell of cutting (notes §A3 interp).
    pub fn dt_s(&self) -> f64 {
        self.cell_mm / self.cut_speed_mm_s
    }
}
