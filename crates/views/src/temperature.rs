//! A printer's heaters (hotend, bed) as `sensor_msgs/Temperature`, one message per heater.
//!
//! `sensor_msgs/msg/Temperature` (ROS 2 `common_interfaces`): `temperature` in degrees
//! Celsius, `variance` 0 for "unknown", the header's stamp the time of the measurement and its
//! frame id where it was taken. The controller's reading is what the printer reported
//! (Marlin's `M105`/`ok T:` report, `T:210.00 /210.00 B:60.00 /60.00`); Marlin gives no
//! variance, so it is 0.

use cell_msgs::builtin_interfaces::Time;
use cell_msgs::sensor_msgs::Temperature;
use cell_msgs::std_msgs::Header;

use crate::frames;

/// One heater's last reading on one machine, °C.
#[derive(Debug, Clone, PartialEq)]
pub struct HeaterReading {
    /// The machine (controller) id.
    pub machine_id: String,
    /// The heater: `hotend` or `bed`.
    pub heater: String,
    /// Measured temperature.
    pub current_c: f64,
    /// Target (0: off).
    pub target_c: f64,
}

/// The measured temperature as a `sensor_msgs/Temperature` stamped `stamp`, in the heater's
/// frame ([`frames::heater`], e.g. `marlin-sim/hotend`), variance 0 (unknown). The target has
/// no field in this type: it is in the diagnostics.
pub fn temperature(reading: &HeaterReading, stamp: Time) -> Temperature {
    Temperature {
        header: Header {
            stamp,
            frame_id: frames::heater(&reading.machine_id, &reading.heater),
        },
        temperature: reading.current_c,
        variance: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_becomes_a_temperature_in_the_heaters_frame() {
        let reading = HeaterReading {
            machine_id: "marlin-sim".into(),
            heater: "hotend".into(),
            current_c: 187.25,
            target_c: 210.0,
        };
        let t = temperature(&reading, Time { sec: 7, nanosec: 5 });
        assert_eq!(t.header.frame_id, "marlin-sim/hotend");
        assert_eq!((t.header.stamp.sec, t.header.stamp.nanosec), (7, 5));
        assert_eq!((t.temperature, t.variance), (187.25, 0.0));
    }
}
