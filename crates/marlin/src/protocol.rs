//! Marlin's serial protocol as a host sees it (Marlin 2.1, `gcode/queue.cpp`,
//! `module/temperature.cpp`).
//!
//! A host line is `N<n> <command>*<checksum>`: the checksum is the XOR of every byte before `*`,
//! written in decimal. Marlin checks that `n` is its last line number + 1 (`M110 N<n>` sets it)
//! and the checksum; on a mismatch it answers `Error:<why>, Last Line: <last>`, empties its RX
//! buffer and asks `Resend: <last + 1>` followed by `ok`.

/// Marlin's line checksum: XOR of every byte of `text` (the part before `*`).
pub fn checksum(text: &str) -> u8 {
    text.bytes().fold(0, |cs, b| cs ^ b)
}

/// `N<n> <command>*<checksum>` (without the line end).
pub fn numbered(n: u64, command: &str) -> String {
    let body = format!("N{n} {command}");
    let cs = checksum(&body);
    format!("{body}*{cs}")
}

/// A line as Marlin's queue reads it: the N word, the command and the checksum check.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HostLine<'a> {
    /// The `N` word, if the line starts with one.
    pub number: Option<i64>,
    /// The command without `N…` and `*…`, trimmed.
    pub command: &'a str,
    /// With a number: whether the checksum was there and right; `None` without a checksum.
    pub checksum_ok: Option<bool>,
}

/// Splits a received line (no line end) the way `get_serial_commands` reads it.
pub fn parse_host_line(line: &str) -> HostLine<'_> {
    let line = line.trim_start_matches(' ');
    let (body, star) = match line.rfind('*') {
        Some(i) => (&line[..i], Some(&line[i + 1..])),
        None => (line, None),
    };
    let checksum_ok = star.map(|cs| cs.trim().parse::<u16>().ok() == Some(checksum(body).into()));
    if let Some(rest) = body.strip_prefix('N') {
        let digits = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '-'))
            .unwrap_or(rest.len());
        let number = rest[..digits].parse::<i64>().ok();
        HostLine {
            number,
            command: rest[digits..].trim(),
            checksum_ok,
        }
    } else {
        HostLine {
            number: None,
            command: body.trim(),
            checksum_ok,
        }
    }
}

/// The G/M code of a command: (`'G'|'M'`, number), e.g. `M109 S210` → `('M', 109)`.
pub fn code_of(command: &str) -> Option<(char, u32)> {
    let mut chars = command.trim_start().chars();
    let letter = chars.next()?.to_ascii_uppercase();
    if letter != 'G' && letter != 'M' {
        return None;
    }
    let rest = chars.as_str();
    let end = rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len());
    // `G1.5`-style subcodes are not used here; a code without digits is no code.
    rest[..end].parse().ok().map(|n| (letter, n))
}

/// The value of word `letter` in a command (`S210` → 210), ignoring the code itself.
pub fn word(command: &str, letter: char) -> Option<f64> {
    let up = letter.to_ascii_uppercase();
    let mut words = command.split_whitespace();
    words.next();
    for w in words {
        let mut cs = w.chars();
        if cs.next().map(|c| c.to_ascii_uppercase()) == Some(up) {
            if let Ok(v) = cs.as_str().parse::<f64>() {
                return Some(v);
            }
        }
    }
    None
}

/// One heater's reading: current temperature and target, °C.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeaterReading {
    /// Measured temperature.
    pub current: f64,
    /// Target (0: off).
    pub target: f64,
}

/// A temperature report (`T:210.00 /210.00 B:60.00 /60.00 @:64 B@:0`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Temps {
    /// The hotend (`T:`).
    pub hotend: HeaterReading,
    /// The bed (`B:`), if the printer has one.
    pub bed: Option<HeaterReading>,
}

impl Temps {
    /// Both targets are 0: the firmware is not heating.
    pub fn targets_off(&self) -> bool {
        self.hotend.target == 0.0 && self.bed.is_none_or(|b| b.target == 0.0)
    }
}

impl std::fmt::Display for Temps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "T:{:.1} /{:.0}", self.hotend.current, self.hotend.target)?;
        if let Some(b) = self.bed {
            write!(f, " B:{:.1} /{:.0}", b.current, b.target)?;
        }
        Ok(())
    }
}

/// Parses the `T:` and `B:` pairs of a report; `None` without a `T:` pair.
pub fn parse_temps(text: &str) -> Option<Temps> {
    let pair = |key: &str| -> Option<HeaterReading> {
        let mut words = text.split_whitespace();
        while let Some(w) = words.next() {
            if let Some(v) = w.strip_prefix(key) {
                let current = v.parse().ok()?;
                let target = words.next()?.strip_prefix('/')?.parse().ok()?;
                return Some(HeaterReading { current, target });
            }
        }
        None
    };
    Some(Temps {
        hotend: pair("T:")?,
        bed: pair("B:"),
    })
}

/// What a line from Marlin means to the host.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// `ok`, with the temperatures when it answers `M105`.
    Ok(Option<Temps>),
    /// `Resend: <n>` (also the older `rs <n>`).
    Resend(u64),
    /// `Error:…` about a line (checksum, line number): a `Resend:` follows.
    LineError(String),
    /// `Error:Printer halted. kill() called!`: the firmware stopped; only a reset brings it back.
    Killed,
    /// Any other `Error:…` (thermal errors come before the kill).
    Error(String),
    /// `echo:busy: processing` (host keepalive): a long command is still running.
    Busy,
    /// A wait report of `M109`/`M190` (` T:… /… B:… /… @:… W:…`).
    WaitReport(Temps),
    /// `start`: the firmware (re)booted.
    Start,
    /// `echo:Unknown command: "…"`.
    Unknown(String),
    /// `X:… Y:… Z:… E:… Count …` (`M114`).
    Position(Vec<(char, f64)>),
    /// Anything else (`echo:…`, `//action:…`, `FIRMWARE_NAME:…`).
    Other(String),
}

/// The answer to the kill: `SERIAL_ERROR_MSG(STR_ERR_KILLED)`.
pub const KILLED: &str = "Printer halted. kill() called!";

/// Classifies one received line (line end stripped).
pub fn parse_response(line: &str) -> Response {
    let t = line.trim_end_matches(['\r', '\n']);
    let trimmed = t.trim();
    if trimmed == "ok" || trimmed.starts_with("ok ") {
        return Response::Ok(parse_temps(trimmed));
    }
    if let Some(n) = trimmed
        .strip_prefix("Resend:")
        .or_else(|| trimmed.strip_prefix("rs "))
    {
        if let Ok(n) = n.trim().parse() {
            return Response::Resend(n);
        }
    }
    if let Some(e) = trimmed.strip_prefix("Error:") {
        let e = e.trim();
        if e == KILLED {
            return Response::Killed;
        }
        if e.contains("Last Line") {
            return Response::LineError(e.to_owned());
        }
        return Response::Error(e.to_owned());
    }
    if trimmed == "start" {
        return Response::Start;
    }
    if trimmed == "echo:busy: processing" || trimmed == "echo:busy: paused for user" {
        return Response::Busy;
    }
    if let Some(u) = trimmed.strip_prefix("echo:Unknown command:") {
        return Response::Unknown(u.trim().trim_matches('"').to_owned());
    }
    if trimmed.starts_with("T:") && trimmed.contains(" W:") {
        if let Some(temps) = parse_temps(trimmed) {
            return Response::WaitReport(temps);
        }
    }
    if trimmed.starts_with("X:") && trimmed.contains(" Y:") {
        let head = trimmed.split(" Count").next().unwrap_or(trimmed);
        let axes: Vec<(char, f64)> = head
            .split_whitespace()
            .filter_map(|w| {
                let (k, v) = w.split_once(':')?;
                let c = k.chars().next()?;
                (k.len() == 1).then_some(())?;
                Some((c, v.parse().ok()?))
            })
            .collect();
        if !axes.is_empty() {
            return Response::Position(axes);
        }
    }
    Response::Other(trimmed.to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbered_lines_carry_marlins_checksum() {
        let line = numbered(0, "M110 N0");
        let (body, cs) = line.rsplit_once('*').unwrap();
        assert_eq!(cs.parse::<u8>().unwrap(), checksum(body));
        let parsed = parse_host_line(&line);
        assert_eq!(parsed.number, Some(0));
        assert_eq!(parsed.command, "M110 N0");
        assert_eq!(parsed.checksum_ok, Some(true));
        let bad = line.replace("M110", "M111");
        assert_eq!(parse_host_line(&bad).checksum_ok, Some(false));
        assert_eq!(parse_host_line("G28").number, None);
        // Pronterface's documented example: N3 T0*57.
        assert_eq!(checksum("N3 T0"), 57);
    }

    #[test]
    fn answers_parse() {
        let ok = parse_response("ok T:21.23 /0.00 B:20.98 /60.00 @:0 B@:127");
        let Response::Ok(Some(t)) = ok else {
            panic!("{ok:?}")
        };
        assert_eq!(t.hotend.current, 21.23);
        assert_eq!(t.bed.unwrap().target, 60.0);
        assert!(!t.targets_off());
        assert_eq!(parse_response("ok"), Response::Ok(None));
        assert_eq!(parse_response("Resend: 12"), Response::Resend(12));
        assert!(matches!(
            parse_response("Error:checksum mismatch, Last Line: 11"),
            Response::LineError(_)
        ));
        assert_eq!(
            parse_response("Error:Printer halted. kill() called!"),
            Response::Killed
        );
        assert_eq!(parse_response("echo:busy: processing"), Response::Busy);
        assert!(matches!(
            parse_response(" T:180.00 /210.00 B:60.00 /60.00 @:127 B@:0 W:?"),
            Response::WaitReport(_)
        ));
        assert_eq!(
            parse_response("X:10.00 Y:20.00 Z:0.20 E:1.50 Count X:800 Y:1600 Z:80"),
            Response::Position(vec![('X', 10.0), ('Y', 20.0), ('Z', 0.2), ('E', 1.5)])
        );
        assert_eq!(code_of("M109 S210"), Some(('M', 109)));
        assert_eq!(word("M109 S210", 'S'), Some(210.0));
        assert_eq!(word("G1 X5 Y-2.5 F1200", 'y'), Some(-2.5));
    }
}
