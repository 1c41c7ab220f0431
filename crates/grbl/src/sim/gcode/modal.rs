//! The parser's modal state (GRBL's `gc_state`): motion mode, plane, units, distance and feed
//! modes, coordinate system and offsets, spindle and coolant, and the `$G` report of it.

/// Millimetres per inch (G20).
pub(super) const MM_PER_INCH: f64 = 25.4;

/// Motion modes (modal group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MotionMode {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
    Cancel,
}

/// Spindle state (M3/M4/M5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Spindle {
    Off,
    Cw,
    Ccw,
}

/// The parser's modal state (GRBL's `gc_state`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Modal {
    pub motion: MotionMode,
    /// 0 = G17 (XY), 1 = G18 (ZX), 2 = G19 (YZ).
    pub plane: u8,
    pub inches: bool,
    pub incremental: bool,
    pub inverse_time: bool,
    /// 0..=5 for G54..G59.
    pub coord: usize,
    /// mm/min; 0 = undefined.
    pub feed_mm_min: f64,
    pub spindle: Spindle,
    pub spindle_speed: f64,
    pub flood: bool,
    pub mist: bool,
    pub tool: u32,
    /// Work coordinate offsets G54..G59 (mm), one per axis.
    pub offsets: [Vec<f64>; 6],
    /// G92 offset (mm).
    pub g92: Vec<f64>,
    /// Where the parser is: the end of the last planned move (mm, machine coordinates).
    pub position: Vec<f64>,
}

impl Modal {
    /// GRBL's power-up / reset state for `n_axes` axes at `position`.
    pub fn new(n_axes: usize, position: Vec<f64>) -> Modal {
        Modal {
            motion: MotionMode::Rapid,
            plane: 0,
            inches: false,
            incremental: false,
            inverse_time: false,
            coord: 0,
            feed_mm_min: 0.0,
            spindle: Spindle::Off,
            spindle_speed: 0.0,
            flood: false,
            mist: false,
            tool: 0,
            offsets: std::array::from_fn(|_| vec![0.0; n_axes]),
            g92: vec![0.0; n_axes],
            position,
        }
    }

    /// After a reset: modal state back to defaults, work offsets kept (they live in EEPROM),
    /// G92 cleared, parser position synced to the machine.
    pub fn reset(&self, position: Vec<f64>) -> Modal {
        let mut m = Modal::new(self.position.len(), position);
        m.offsets = self.offsets.clone();
        m
    }

    /// Work coordinate offset currently in effect (G54..G59 plus G92), mm.
    pub fn wco(&self) -> Vec<f64> {
        self.offsets[self.coord]
            .iter()
            .zip(&self.g92)
            .map(|(a, b)| a + b)
            .collect()
    }

    /// The `$G` report body.
    pub fn gc_report(&self) -> String {
        let motion = match self.motion {
            MotionMode::Rapid => "G0",
            MotionMode::Linear => "G1",
            MotionMode::ArcCw => "G2",
            MotionMode::ArcCcw => "G3",
            MotionMode::Cancel => "G80",
        };
        let spindle = match self.spindle {
            Spindle::Off => "M5",
            Spindle::Cw => "M3",
            Spindle::Ccw => "M4",
        };
        let coolant = match (self.flood, self.mist) {
            (false, false) => "M9".to_string(),
            (true, false) => "M8".to_string(),
            (false, true) => "M7".to_string(),
            (true, true) => "M7 M8".to_string(),
        };
        let feed = if self.inches {
            self.feed_mm_min / MM_PER_INCH
        } else {
            self.feed_mm_min
        };
        format!(
            "{motion} G{} G{} {} {} {} {spindle} {coolant} T{} F{} S{}",
            54 + self.coord,
            17 + self.plane,
            if self.inches { "G20" } else { "G21" },
            if self.incremental { "G91" } else { "G90" },
            if self.inverse_time { "G93" } else { "G94" },
            self.tool,
            fmt_num(feed),
            fmt_num(self.spindle_speed)
        )
    }
}

fn fmt_num(x: f64) -> String {
    if x.fract() == 0.0 {
        format!("{}", x as i64)
    } else {
        format!("{x:.3}")
    }
}
