//! What a controller says about itself: which firmware printed the reset banner, the build
//! options `$I` reports (planner blocks, RX buffer) and the spindle word of the parser state
//! `$G` reports.
//!
//! Banners as the firmwares print them:
//! - GRBL 1.1: `Grbl 1.1h ['$' for help]`;
//! - grblHAL: `GrblHAL 1.1f ['$' or '$HELP' for help]` (with `COMPATIBILITY_LEVEL` > 0 it calls
//!   itself `Grbl`, like GRBL 1.1);
//! - FluidNC: `Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for help]` (GRBL's prefix, so senders keep
//!   working, with the real name in the brackets).
//!
//! `$I` answers `[VER:…]` and `[OPT:flags,planner_blocks,rx_buffer_bytes…]` on GRBL 1.1 and
//! grblHAL; a firmware whose `OPT` carries no numbers leaves the sizes unknown (the controller
//! file's value is used then).

/// Which firmware a banner came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Firmware {
    /// GRBL 1.1 (or a fork that prints its banner).
    Grbl,
    /// grblHAL.
    GrblHal,
    /// FluidNC (ESP32).
    FluidNc,
}

impl std::fmt::Display for Firmware {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Firmware::Grbl => "GRBL",
            Firmware::GrblHal => "grblHAL",
            Firmware::FluidNc => "FluidNC",
        })
    }
}

/// A reset banner: the firmware and the version it printed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Banner {
    /// Which firmware.
    pub firmware: Firmware,
    /// The version as printed: `1.1h` (GRBL), `1.1f` (grblHAL), `v3.7.8` (FluidNC).
    pub version: String,
}

impl std::fmt::Display for Banner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.firmware, self.version)
    }
}

/// The banner in `line`, if it is one.
pub fn parse_banner(line: &str) -> Option<Banner> {
    let (firmware, rest) = if let Some(rest) = strip_prefix_ignore_case(line, "GrblHAL ") {
        (Firmware::GrblHal, rest)
    } else if let Some(rest) = line.strip_prefix("Grbl ") {
        (Firmware::Grbl, rest)
    } else {
        return None;
    };
    let first = rest.split_whitespace().next()?;
    // `Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for help]`.
    if let Some(after) = rest.split_once("[FluidNC ").map(|(_, a)| a) {
        let version = after.split_whitespace().next().unwrap_or(first);
        return Some(Banner {
            firmware: Firmware::FluidNc,
            version: version.to_string(),
        });
    }
    Some(Banner {
        firmware,
        version: first.to_string(),
    })
}

fn strip_prefix_ignore_case<'a>(line: &'a str, prefix: &str) -> Option<&'a str> {
    let head = line.get(..prefix.len())?;
    head.eq_ignore_ascii_case(prefix)
        .then(|| &line[prefix.len()..])
}

/// Sizes from a `[OPT:…]` build-options line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuildOptions {
    /// Planner blocks.
    pub planner_blocks: u16,
    /// Serial RX buffer (bytes).
    pub rx_buffer_bytes: usize,
}

/// Parses the body of `[OPT:V,15,128]` (after `OPT:`): option letters, planner blocks, RX
/// buffer bytes, then anything a firmware adds. `None` when the two numbers are not there.
pub fn parse_build_options(body: &str) -> Option<BuildOptions> {
    let mut fields = body.split(',').skip(1).map(str::trim);
    let planner_blocks = fields.next()?.parse().ok()?;
    let rx_buffer_bytes = fields.next()?.parse().ok()?;
    Some(BuildOptions {
        planner_blocks,
        rx_buffer_bytes,
    })
}

/// The spindle (heat) word of the parser state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpindleWord {
    /// `M3`: on, clockwise (hot wire, plasma torch, constant-power laser).
    M3,
    /// `M4`: on, counter-clockwise (dynamic-power laser in laser mode).
    M4,
    /// `M5`: off.
    M5,
}

/// The spindle word in the body of `[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]`.
pub fn gc_spindle(body: &str) -> Option<SpindleWord> {
    body.split_whitespace().find_map(|w| match w {
        "M3" => Some(SpindleWord::M3),
        "M4" => Some(SpindleWord::M4),
        "M5" => Some(SpindleWord::M5),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn banners_of_the_three_firmwares() {
        let b = parse_banner("Grbl 1.1h ['$' for help]").unwrap();
        assert_eq!((b.firmware, b.version.as_str()), (Firmware::Grbl, "1.1h"));
        let b = parse_banner("GrblHAL 1.1f ['$' or '$HELP' for help]").unwrap();
        assert_eq!(
            (b.firmware, b.version.as_str()),
            (Firmware::GrblHal, "1.1f")
        );
        let b = parse_banner("Grbl 3.7 [FluidNC v3.7.8 (wifi) '$' for help]").unwrap();
        assert_eq!(
            (b.firmware, b.version.as_str()),
            (Firmware::FluidNc, "v3.7.8")
        );
        assert_eq!(b.to_string(), "FluidNC v3.7.8");
        assert!(parse_banner("Grbl").is_none());
        assert!(parse_banner("[MSG:Grbl 1.1h]").is_none());
        assert!(parse_banner("ok").is_none());
    }

    #[test]
    fn build_options_give_the_buffer_sizes() {
        assert_eq!(
            parse_build_options("V,15,128"),
            Some(BuildOptions {
                planner_blocks: 15,
                rx_buffer_bytes: 128
            })
        );
        assert_eq!(
            parse_build_options("VNMSL,35,1024,3,0").map(|o| o.rx_buffer_bytes),
            Some(1024)
        );
        assert_eq!(parse_build_options("PHS"), None);
        assert_eq!(parse_build_options("V,x,128"), None);
    }

    #[test]
    fn the_spindle_word_of_the_parser_state() {
        assert_eq!(
            gc_spindle("G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0"),
            Some(SpindleWord::M5)
        );
        assert_eq!(
            gc_spindle("G1 G54 G17 G21 G90 G93 M3 M9 T0 F300 S1000"),
            Some(SpindleWord::M3)
        );
        assert_eq!(gc_spindle("G1 M4 S200"), Some(SpindleWord::M4));
        assert_eq!(gc_spindle("G0 G54"), None);
    }
}
