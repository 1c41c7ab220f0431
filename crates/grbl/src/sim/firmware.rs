//! Which firmware the simulator speaks as: GRBL 1.1h (an Arduino), grblHAL or FluidNC. The
//! flavour sets what the controller says (reset banner, `$I`, `[MSG:…]` style, help) and the
//! defaults [`SimConfig::for_firmware`](super::SimConfig::for_firmware) takes (RX buffer,
//! planner blocks, what a new connection sees); the machine underneath is the same.
//!
//! The texts are the firmwares' own (sources read: gnea/grbl 1.1h `report.c`, grblHAL core
//! `report.c`/`stream.c`/`messages.c`, FluidNC v3.7.8 `Report.cpp`/`Logging.h`/
//! `TelnetServer.cpp`):
//!
//! - **GRBL 1.1h** (Arduino): banner `Grbl 1.1h ['$' for help]`; `$I` answers
//!   `[VER:1.1h.20190830:…]` and `[OPT:V,15,128]` (options, planner blocks, RX bytes); RX buffer
//!   128, planner 15, line buffer 80 (`error:11` past it); messages `[MSG:text]`; the board
//!   resets when its port opens (DTR).
//! - **grblHAL**: banner `GrblHAL 1.1f ['$' or '$HELP' for help]`; `$I` answers
//!   `[VER:1.1f.20260817:…]`, `[OPT:VNMSL,100,1024,3,0]` (… axes, tools), `[AXS:3:XYZ]`,
//!   `[NEWOPT:…]`, `[FIRMWARE:grblHAL]`; RX buffer 1024, planner 100, line buffer 257
//!   (`error:11`); messages `[MSG:text]`; a new host (USB DTR, telnet) gets the banner, no reset.
//! - **FluidNC v3.7.8** (ESP32, telnet): banner `Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for
//!   help]`; `$I` answers `[VER:3.7 FluidNC v3.7.8:…]`, `[OPT:PHS]` (no sizes) and
//!   `[MSG: Machine: …]`; RX buffer 1200 (a telnet client's), planner 15, line buffer 255 raw
//!   bytes with the rest dropped without an error; messages `[MSG:INFO: text]`; a new telnet
//!   client gets nothing (since 2022 FluidNC greets no one), no reset.
//!
//! A real Arduino resets when the port opens; [`OnConnect::Banner`] is the GRBL default here so
//! that a reconnect finds the machine as the link left it (a board with its auto-reset
//! disabled, or behind a serial-to-TCP bridge); [`OnConnect::Reset`] gives the Arduino.

use super::config::OnConnect;

/// GRBL 1.1h's reset banner (`report_init_message`).
pub const GRBL_BANNER: &str = "Grbl 1.1h ['$' for help]";
/// grblHAL's reset banner (`COMPATIBILITY_LEVEL` 0, the default).
pub const GRBLHAL_BANNER: &str = "GrblHAL 1.1f ['$' or '$HELP' for help]";
/// FluidNC v3.7.8's reset banner (its default `Start/Message`, `Grbl \V [FluidNC \B (\R) \H]`,
/// on a WiFi build).
pub const FLUIDNC_BANNER: &str = "Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for help]";

/// The build-info text `$I` shows after `VER:` (GRBL stores it with `$I=text`).
pub const BUILD_INFO: &str = "cellsuite grbl_sim";

/// GRBL 1.1h's `$I` answer on an Arduino (before `ok`).
pub const GRBL_BUILD_INFO: [&str; 2] = ["[VER:1.1h.20190830:cellsuite grbl_sim]", "[OPT:V,15,128]"];
/// grblHAL's `$I` answer for three axes (before `ok`).
pub const GRBLHAL_BUILD_INFO: [&str; 5] = [
    "[VER:1.1f.20260817:cellsuite grbl_sim]",
    "[OPT:VNMSL,100,1024,3,0]",
    "[AXS:3:XYZ]",
    "[NEWOPT:ENUMS,RT+,SED]",
    "[FIRMWARE:grblHAL]",
];
/// FluidNC v3.7.8's `$I` answer (before `ok`): its `OPT` carries no buffer sizes.
pub const FLUIDNC_BUILD_INFO: [&str; 3] = [
    "[VER:3.7 FluidNC v3.7.8:cellsuite grbl_sim]",
    "[OPT:PHS]",
    "[MSG: Machine: cellsuite grbl_sim]",
];

/// The firmware the simulator speaks as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SimFirmware {
    /// GRBL 1.1h on an Arduino (ATmega328p).
    #[default]
    Grbl11h,
    /// grblHAL (32-bit boards, e.g. the `grbl-xyuv` hot-wire controller).
    GrblHal,
    /// FluidNC on an ESP32, over telnet.
    FluidNc,
}

impl SimFirmware {
    /// The reset banner (without the empty line printed before it).
    pub fn banner(self) -> &'static str {
        match self {
            SimFirmware::Grbl11h => GRBL_BANNER,
            SimFirmware::GrblHal => GRBLHAL_BANNER,
            SimFirmware::FluidNc => FLUIDNC_BANNER,
        }
    }

    /// The firmware's RX buffer (bytes) as `Bf:` reports it when empty.
    pub fn rx_buffer_bytes(self) -> usize {
        match self {
            SimFirmware::Grbl11h => 128,
            SimFirmware::GrblHal => 1024,
            SimFirmware::FluidNc => 1200,
        }
    }

    /// Usable planner blocks.
    pub fn planner_blocks(self) -> usize {
        match self {
            SimFirmware::Grbl11h | SimFirmware::FluidNc => 15,
            SimFirmware::GrblHal => 100,
        }
    }

    /// The line buffer (bytes, terminator included): GRBL keeps 79 characters after removing
    /// spaces and comments, grblHAL 256; FluidNC keeps 254 bytes as received.
    pub fn line_buffer_size(self) -> usize {
        match self {
            SimFirmware::Grbl11h => crate::protocol::LINE_BUFFER_SIZE,
            SimFirmware::GrblHal => 257,
            SimFirmware::FluidNc => 255,
        }
    }

    /// True when a line past the line buffer is answered `error:11`; FluidNC drops the excess
    /// bytes and runs what it kept.
    pub fn overflow_is_error(self) -> bool {
        self != SimFirmware::FluidNc
    }

    /// What a new host sees.
    pub fn on_connect(self) -> OnConnect {
        match self {
            SimFirmware::Grbl11h | SimFirmware::GrblHal => OnConnect::Banner,
            SimFirmware::FluidNc => OnConnect::Silent,
        }
    }

    /// A feedback message as the firmware prints it: `[MSG:text]`, FluidNC `[MSG:INFO: text]`.
    pub fn message(self, text: &str) -> String {
        match self {
            SimFirmware::FluidNc => format!("[MSG:INFO: {text}]"),
            _ => format!("[MSG:{text}]"),
        }
    }

    /// The `$` help line.
    pub fn help(self) -> &'static str {
        match self {
            SimFirmware::GrblHal => {
                "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H $B ~ ! ? ctrl-x]"
            }
            _ => "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]",
        }
    }

    /// The lines `$I` prints before `ok`, for `planner_blocks`, `rx_buffer_bytes` and `axes`.
    pub fn build_info(
        self,
        planner_blocks: usize,
        rx_buffer_bytes: usize,
        axes: &[char],
    ) -> Vec<String> {
        match self {
            SimFirmware::Grbl11h => vec![
                format!("[VER:1.1h.20190830:{BUILD_INFO}]"),
                format!("[OPT:V,{planner_blocks},{rx_buffer_bytes}]"),
            ],
            SimFirmware::GrblHal => {
                let letters: String = axes.iter().collect();
                vec![
                    format!("[VER:1.1f.20260817:{BUILD_INFO}]"),
                    // Options, planner blocks, RX buffer, axes, tools.
                    format!(
                        "[OPT:VNMSL,{planner_blocks},{rx_buffer_bytes},{},0]",
                        axes.len()
                    ),
                    format!("[AXS:{}:{letters}]", axes.len()),
                    "[NEWOPT:ENUMS,RT+,SED]".into(),
                    "[FIRMWARE:grblHAL]".into(),
                ]
            }
            SimFirmware::FluidNc => vec![
                format!("[VER:3.7 FluidNC v3.7.8:{BUILD_INFO}]"),
                "[OPT:PHS]".into(),
                format!("[MSG: Machine: {BUILD_INFO}]"),
            ],
        }
    }

    /// True when status reports refresh `WCO:`/`Ov:` less often while busy (Run, Hold, Jog):
    /// GRBL and grblHAL every 30/20 reports; FluidNC v3.7.8's `switch` falls through to the
    /// idle counts (every 10) in every state.
    pub(super) fn slow_refresh_when_busy(self) -> bool {
        self != SimFirmware::FluidNc
    }

    /// True when `A:` shows the spindle only while its PWM output is enabled: GRBL 1.1 turns the
    /// PWM off at `S0` (and in laser mode between moves), so `M3 S0` prints no `A:S`. grblHAL
    /// and FluidNC show the enable state they set.
    pub(super) fn accessory_follows_pwm(self) -> bool {
        self == SimFirmware::Grbl11h
    }

    /// The grblHAL rule for `Ov:`/`A:`/`WCO:` (see `report`) instead of GRBL's.
    pub(super) fn grblhal_reporting(self) -> bool {
        self == SimFirmware::GrblHal
    }
}

impl std::fmt::Display for SimFirmware {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SimFirmware::Grbl11h => "GRBL 1.1h",
            SimFirmware::GrblHal => "grblHAL 1.1f",
            SimFirmware::FluidNc => "FluidNC v3.7.8",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn build_info_constants_are_what_the_simulator_prints() {
        let xyz = ['X', 'Y', 'Z'];
        for (f, expected) in [
            (SimFirmware::Grbl11h, GRBL_BUILD_INFO.as_slice()),
            (SimFirmware::GrblHal, GRBLHAL_BUILD_INFO.as_slice()),
            (SimFirmware::FluidNc, FLUIDNC_BUILD_INFO.as_slice()),
        ] {
            let got = f.build_info(f.planner_blocks(), f.rx_buffer_bytes(), &xyz);
            assert_eq!(got, expected, "{f}");
        }
    }

    #[test]
    fn messages_in_each_firmwares_style() {
        assert_eq!(SimFirmware::Grbl11h.message("Pgm End"), "[MSG:Pgm End]");
        assert_eq!(SimFirmware::GrblHal.message("Pgm End"), "[MSG:Pgm End]");
        assert_eq!(
            SimFirmware::FluidNc.message("Pgm End"),
            "[MSG:INFO: Pgm End]"
        );
    }
}
