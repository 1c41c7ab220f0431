//! Marlin 2 for cellsuite's machine bridge, with no ROS in it: the host side of Marlin's serial
//! protocol and a protocol simulator that answers as Marlin 2.1 does.
//!
//! - [`protocol`]: numbered lines with checksums (`N<n> <cmd>*<cs>`), the answers a host sees
//!   (`ok`, `ok T:…`, `Resend:`, `Error:`, `echo:busy: processing`, wait reports, `start`) and
//!   temperature reports.
//! - [`client`]: a ping-pong streaming client (one line in flight, resend on request), status
//!   queries (`M105`, `M114`) and the safe stop that switches the heaters off and reads the
//!   targets back from `M105`.
//! - [`sim`]: the simulator: command queue, heaters, planner, thermal protection, kill.
//!
//! Sources: Marlin 2.1 `gcode/queue.cpp` (line numbers, checksums, `gcode_line_error`,
//! `flush_and_request_resend`), `gcode/temp/M104_M109.cpp`, `M140_M190.cpp`, `M105.cpp`,
//! `module/temperature.cpp` (`print_heater_states`, `wait_for_hotend`, thermal protection,
//! `_temp_error`), `feature/e_parser.h` (EMERGENCY_PARSER: M108, M112, M410),
//! `gcode/gcode.cpp` (host keepalive), `MarlinCore.cpp` (`kill`).

#![warn(missing_docs)]

pub mod client;
pub mod protocol;
pub mod sim;
