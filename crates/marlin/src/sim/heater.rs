//! One heater (hotend or bed): a first-order thermal model driven by a controller, and Marlin's
//! thermal protection (`module/temperature.cpp`).
//!
//! Model: `C dT/dt = P·u − (T − T_amb)/R`, i.e. `dT/dt = (u·(T_max − T_amb) − (T − T_amb)) / τ`
//! with `u ∈ [0, 1]` the heater's duty, `τ = R·C` and `T_max` the temperature full power holds.
//! The controller is feed-forward plus proportional (a stand-in for Marlin's PID: no overshoot,
//! no steady-state error), so `M109` waits are predictable.
//!
//! Protection, with Marlin's stock `Configuration_adv.h` values (per heater kind):
//! - **Heating watch** (`WATCH_TEMP_PERIOD`, `WATCH_TEMP_INCREASE`): after a target is set more
//!   than the increase above the temperature, the temperature must rise by the increase within
//!   the period, else `Heating failed`.
//! - **Thermal runaway** (`THERMAL_PROTECTION_PERIOD`, `THERMAL_PROTECTION_HYSTERESIS`): once the
//!   target was reached, a temperature below target − hysteresis for the period is `Thermal
//!   Runaway`.
//! - **MINTEMP / MAXTEMP**: a reading below `HEATER_0_MINTEMP` (an open thermistor reads far
//!   below ambient) or above `HEATER_0_MAXTEMP`.

/// What a heater is: its physics and protection limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeaterSpec {
    /// `T_amb`, °C.
    pub ambient_c: f64,
    /// Temperature full power holds, °C.
    pub full_power_c: f64,
    /// Time constant τ, s.
    pub tau_s: f64,
    /// `WATCH_TEMP_PERIOD`, s.
    pub watch_period_s: f64,
    /// `WATCH_TEMP_INCREASE`, K.
    pub watch_increase_k: f64,
    /// `THERMAL_PROTECTION_PERIOD`, s.
    pub runaway_period_s: f64,
    /// `THERMAL_PROTECTION_HYSTERESIS`, K.
    pub runaway_hysteresis_k: f64,
    /// `MINTEMP`, °C.
    pub min_c: f64,
    /// `MAXTEMP`, °C.
    pub max_c: f64,
}

impl HeaterSpec {
    /// A 40 W hotend: 20 → 210 °C in about 35 s (Marlin: watch 20 s / 2 K, runaway 40 s / 4 K,
    /// MINTEMP 5, MAXTEMP 275).
    pub const HOTEND: HeaterSpec = HeaterSpec {
        ambient_c: 22.0,
        full_power_c: 300.0,
        tau_s: 30.0,
        watch_period_s: 20.0,
        watch_increase_k: 2.0,
        runaway_period_s: 40.0,
        runaway_hysteresis_k: 4.0,
        min_c: 5.0,
        max_c: 275.0,
    };
    /// A heated bed: 22 → 60 °C in about 30 s (Marlin: watch 60 s / 2 K, runaway 20 s / 2 K,
    /// MINTEMP 5, MAXTEMP 150).
    pub const BED: HeaterSpec = HeaterSpec {
        ambient_c: 22.0,
        full_power_c: 120.0,
        tau_s: 60.0,
        watch_period_s: 60.0,
        watch_increase_k: 2.0,
        runaway_period_s: 20.0,
        runaway_hysteresis_k: 2.0,
        min_c: 5.0,
        max_c: 150.0,
    };
}

/// Why thermal protection stopped the printer (Marlin's `_temp_error` texts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThermalError {
    /// The heating watch expired.
    HeatingFailed,
    /// The temperature fell away from a reached target.
    Runaway,
    /// Reading below MINTEMP.
    MinTemp,
    /// Reading above MAXTEMP.
    MaxTemp,
}

impl ThermalError {
    /// The first part of Marlin's message.
    pub fn text(self) -> &'static str {
        match self {
            ThermalError::HeatingFailed => "Heating failed",
            ThermalError::Runaway => "Thermal Runaway",
            ThermalError::MinTemp => "MINTEMP triggered",
            ThermalError::MaxTemp => "MAXTEMP triggered",
        }
    }
}

/// A heater's state.
#[derive(Debug, Clone, PartialEq)]
pub struct Heater {
    /// Its physics and limits.
    pub spec: HeaterSpec,
    /// True temperature, °C.
    pub temp_c: f64,
    /// Target, °C (0: off).
    pub target_c: f64,
    /// Duty of the last step, 0..1.
    pub duty: f64,
    /// Fault injection: the heater cartridge gets no power (a broken wire).
    pub power_lost: bool,
    /// Fault injection: the thermistor is open (reads −14 °C, as an open 100k NTC does).
    pub sensor_open: bool,
    watch: Option<(f64, f64)>,
    reached: bool,
    below_since: Option<f64>,
}

impl Heater {
    /// A cold heater.
    pub fn new(spec: HeaterSpec) -> Self {
        Heater {
            spec,
            temp_c: spec.ambient_c,
            target_c: 0.0,
            duty: 0.0,
            power_lost: false,
            sensor_open: false,
            watch: None,
            reached: false,
            below_since: None,
        }
    }

    /// What the firmware reads.
    pub fn reading(&self) -> f64 {
        if self.sensor_open {
            -14.0
        } else {
            self.temp_c
        }
    }

    /// Sets the target at simulated time `now_s` (`M104`/`M109`/`M140`/`M190`), starting the
    /// heating watch as `start_watching_heater` does.
    pub fn set_target(&mut self, target_c: f64, now_s: f64) {
        self.target_c = target_c.max(0.0);
        self.reached = false;
        self.below_since = None;
        let r = self.reading();
        self.watch = (self.target_c > r + self.spec.watch_increase_k + 1.0).then_some((
            now_s + self.spec.watch_period_s,
            r + self.spec.watch_increase_k,
        ));
    }

    /// Switches the heater off (`disable_all_heaters`).
    pub fn off(&mut self) {
        self.target_c = 0.0;
        self.duty = 0.0;
        self.watch = None;
        self.reached = false;
        self.below_since = None;
    }

    /// Advances by `dt_s` ending at `now_s`; a thermal error if protection trips.
    pub fn step(&mut self, dt_s: f64, now_s: f64) -> Option<ThermalError> {
        let s = self.spec;
        let span = s.full_power_c - s.ambient_c;
        let r = self.reading();
        self.duty = if self.target_c > 0.0 && !self.sensor_open {
            let feed_forward = (self.target_c - s.ambient_c) / span;
            (feed_forward + 0.5 * (self.target_c - r)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let u = if self.power_lost { 0.0 } else { self.duty };
        // Exact solution over the step for constant u.
        let equilibrium = s.ambient_c + u * span;
        self.temp_c = equilibrium + (self.temp_c - equilibrium) * (-dt_s / s.tau_s).exp();
        let r = self.reading();
        if r < s.min_c {
            return Some(ThermalError::MinTemp);
        }
        if r > s.max_c {
            return Some(ThermalError::MaxTemp);
        }
        if self.target_c <= 0.0 {
            return None;
        }
        if let Some((deadline, need)) = self.watch {
            if r >= need {
                self.watch = None;
            } else if now_s >= deadline {
                return Some(ThermalError::HeatingFailed);
            }
        }
        if r >= self.target_c - s.runaway_hysteresis_k {
            self.reached = true;
            self.below_since = None;
        } else if self.reached {
            let since = *self.below_since.get_or_insert(now_s);
            if now_s - since >= s.runaway_period_s {
                return Some(ThermalError::Runaway);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(h: &mut Heater, from: f64, seconds: f64) -> (f64, Option<ThermalError>) {
        let dt = 0.05;
        let mut t = from;
        while t < from + seconds {
            t += dt;
            if let Some(e) = h.step(dt, t) {
                return (t, Some(e));
            }
        }
        (t, None)
    }

    #[test]
    fn hotend_reaches_its_target_and_holds_it() {
        let mut h = Heater::new(HeaterSpec::HOTEND);
        h.set_target(210.0, 0.0);
        let (_, e) = run(&mut h, 0.0, 60.0);
        assert!(e.is_none());
        assert!((h.temp_c - 210.0).abs() < 0.5, "{}", h.temp_c);
        // Off: it cools toward ambient with τ.
        h.off();
        run(&mut h, 60.0, 30.0);
        let expect = 22.0 + (210.0 - 22.0) * (-1.0f64).exp();
        assert!((h.temp_c - expect).abs() < 3.0, "{} vs {expect}", h.temp_c);
    }

    #[test]
    fn protection_trips_as_marlins_does() {
        let mut h = Heater::new(HeaterSpec::HOTEND);
        h.power_lost = true;
        h.set_target(210.0, 0.0);
        let (t, e) = run(&mut h, 0.0, 60.0);
        assert_eq!(e, Some(ThermalError::HeatingFailed));
        assert!((t - 20.0).abs() < 0.1, "{t}");

        let mut h = Heater::new(HeaterSpec::HOTEND);
        h.set_target(210.0, 0.0);
        run(&mut h, 0.0, 60.0);
        h.power_lost = true;
        let (t, e) = run(&mut h, 60.0, 120.0);
        assert_eq!(e, Some(ThermalError::Runaway));
        assert!(t > 100.0 && t < 110.0, "{t}");

        let mut h = Heater::new(HeaterSpec::BED);
        h.sensor_open = true;
        assert_eq!(run(&mut h, 0.0, 1.0).1, Some(ThermalError::MinTemp));
    }
}
