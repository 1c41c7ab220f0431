//! Machine health as a `diagnostic_msgs/DiagnosticArray`.

use cell_msgs::builtin_interfaces::Time;
use cell_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use cell_msgs::std_msgs::Header;
use cell_msgs::MachineStatus;

use crate::HeaterReading;

/// The diagnostic level of a machine state: idle, running and done are OK; hold and unknown
/// are WARN (someone should look); alarm and disconnected are ERROR.
pub fn level(state: u8) -> u8 {
    match state {
        MachineStatus::STATE_IDLE | MachineStatus::STATE_RUNNING | MachineStatus::STATE_DONE => {
            DiagnosticStatus::OK
        }
        MachineStatus::STATE_ALARM | MachineStatus::STATE_DISCONNECTED => DiagnosticStatus::ERROR,
        _ => DiagnosticStatus::WARN,
    }
}

/// The name of a machine state, as the diagnostic message says it.
pub fn state_name(state: u8) -> &'static str {
    match state {
        MachineStatus::STATE_DISCONNECTED => "disconnected",
        MachineStatus::STATE_IDLE => "idle",
        MachineStatus::STATE_RUNNING => "running",
        MachineStatus::STATE_HOLD => "hold",
        MachineStatus::STATE_ALARM => "alarm",
        MachineStatus::STATE_DONE => "done",
        _ => "unknown",
    }
}

/// One status per machine, named `<reporter>: <machine_id>` (the `node: component` convention
/// of `diagnostic_updater`), hardware id the machine id, level by [`level`], message the state
/// (and the alarm text, if any), and values `state`, `job_id`, `acked_line`, `total_lines`,
/// `buffer_fill`, `feed_mm_s`, each axis (`axis/<name>` in mm or deg, as reported) and each of
/// the machine's heaters in `heaters` (`heater/<name>/current_c` and `heater/<name>/target_c`,
/// °C; target 0: off).
pub fn diagnostics(
    reporter: &str,
    statuses: &[MachineStatus],
    heaters: &[HeaterReading],
    stamp: Time,
) -> DiagnosticArray {
    let status = statuses
        .iter()
        .map(|s| {
            let kv = |key: &str, value: String| KeyValue {
                key: key.to_owned(),
                value,
            };
            let mut message = state_name(s.state).to_owned();
            if !s.alarm.is_empty() {
                message = format!("{message}: {}", s.alarm);
            }
            let mut values = vec![
                kv("state", state_name(s.state).to_owned()),
                kv("job_id", s.job_id.clone()),
                kv("acked_line", s.acked_line.to_string()),
                kv("total_lines", s.total_lines.to_string()),
                kv("buffer_fill", s.buffer_fill.to_string()),
                kv("feed_mm_s", s.feed_mm_s.to_string()),
            ];
            values.extend(
                s.axis_names
                    .iter()
                    .zip(&s.axis_positions)
                    .map(|(a, p)| kv(&format!("axis/{a}"), p.to_string())),
            );
            for h in heaters.iter().filter(|h| h.machine_id == s.machine_id) {
                values.push(kv(
                    &format!("heater/{}/current_c", h.heater),
                    h.current_c.to_string(),
                ));
                values.push(kv(
                    &format!("heater/{}/target_c", h.heater),
                    h.target_c.to_string(),
                ));
            }
            DiagnosticStatus {
                level: level(s.state),
                name: format!("{reporter}: {}", s.machine_id),
                message,
                hardware_id: s.machine_id.clone(),
                values,
            }
        })
        .collect();
    DiagnosticArray {
        header: Header {
            stamp,
            frame_id: String::new(),
        },
        status,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_machine_reports_its_state_and_values() {
        let statuses = [
            MachineStatus {
                machine_id: "grbl-sim".into(),
                state: MachineStatus::STATE_RUNNING,
                job_id: "sheet-1".into(),
                acked_line: 12,
                total_lines: 40,
                axis_names: vec!["X".into()],
                axis_positions: vec![12.5],
                ..Default::default()
            },
            MachineStatus {
                machine_id: "abb".into(),
                state: MachineStatus::STATE_ALARM,
                alarm: "ALARM:1 hard limit".into(),
                ..Default::default()
            },
        ];
        let heaters = [
            HeaterReading {
                machine_id: "grbl-sim".into(),
                heater: "hotend".into(),
                current_c: 187.5,
                target_c: 210.0,
            },
            HeaterReading {
                machine_id: "other".into(),
                heater: "bed".into(),
                current_c: 60.0,
                target_c: 60.0,
            },
        ];
        let array = diagnostics(
            "machine_bridge",
            &statuses,
            &heaters,
            Time { sec: 5, nanosec: 0 },
        );
        assert_eq!(array.header.stamp.sec, 5);
        let [grbl, abb] = &array.status[..] else {
            panic!("two statuses")
        };
        assert_eq!(grbl.name, "machine_bridge: grbl-sim");
        assert_eq!(
            (grbl.level, grbl.message.as_str()),
            (DiagnosticStatus::OK, "running")
        );
        let value = |key: &str| {
            grbl.values
                .iter()
                .find(|kv| kv.key == key)
                .map(|kv| kv.value.as_str())
        };
        assert_eq!(value("acked_line"), Some("12"));
        assert_eq!(value("axis/X"), Some("12.5"));
        assert_eq!(value("heater/hotend/current_c"), Some("187.5"));
        assert_eq!(value("heater/hotend/target_c"), Some("210"));
        assert_eq!(
            value("heater/bed/current_c"),
            None,
            "another machine's heater"
        );
        assert!(!abb.values.iter().any(|kv| kv.key.starts_with("heater/")));
        assert_eq!(abb.level, DiagnosticStatus::ERROR);
        assert_eq!(abb.message, "alarm: ALARM:1 hard limit");
        assert_eq!(level(MachineStatus::STATE_HOLD), DiagnosticStatus::WARN);
    }
}
