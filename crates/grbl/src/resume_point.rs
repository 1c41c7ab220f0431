//! Where a program stands after a safe stop flushed the controller's planner.
//!
//! GRBL answers `ok` when a line enters its planner, not when the move is done. A safe stop
//! (feed hold, soft reset) discards what the planner still held, so the lines acknowledged
//! last may never have run. The status report taken in the hold, before the reset, says how
//! many blocks were still queued (`Bf:` planner blocks free, against the planner's size): the
//! block being executed and those behind it. Walking back that many motion lines from the
//! last acknowledged line gives the first line whose move did not finish, which is the line
//! to resume from (re-running it from where the tool stopped ends at the same point, in
//! absolute distance mode).
//!
//! A move is a line with an axis word that is not a setting (`G10`, `G92`, `G28.1`, `G30.1`)
//! or a dwell; `G28`/`G30` through an intermediate point count as one block here (their
//! second block follows at once). Lines without a move (`M3`, `F`, `G4`) take no block.

/// Whether `line` (cleaned: upper case, no comments) queues a motion block.
pub fn is_motion_line(line: &str) -> bool {
    let mut has_axis = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if !c.is_ascii_alphabetic() {
            continue;
        }
        let mut number = String::new();
        while let Some(&d) = chars.peek() {
            if d.is_ascii_digit() || d == '.' || d == '-' || d == '+' || d == ' ' {
                if d != ' ' {
                    number.push(d);
                }
                chars.next();
            } else {
                break;
            }
        }
        match c.to_ascii_uppercase() {
            'X' | 'Y' | 'Z' | 'A' | 'B' | 'C' | 'U' | 'V' | 'W' => has_axis = true,
            'G' => {
                let code = number.parse::<f64>().unwrap_or(-1.0);
                let setting = [4.0, 10.0, 28.1, 30.1, 92.0, 92.1]
                    .iter()
                    .any(|g| (code - g).abs() < 1e-6);
                if setting {
                    return false;
                }
            }
            _ => {}
        }
    }
    has_axis
}

/// The index (into `lines`) of the first line whose move had not finished when the machine
/// stopped with `pending_blocks` motion blocks queued, the last acknowledged line being
/// `lines[last_acked]`. With nothing pending, the line after the acknowledged one.
pub fn first_unfinished<S: AsRef<str>>(
    lines: &[S],
    last_acked: usize,
    pending_blocks: usize,
) -> usize {
    if pending_blocks == 0 {
        return last_acked + 1;
    }
    let mut left = pending_blocks;
    let mut at = last_acked + 1;
    while at > 0 && left > 0 {
        at -= 1;
        if is_motion_line(lines[at].as_ref()) {
            left -= 1;
        }
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motion_lines_are_those_that_queue_a_block() {
        assert!(is_motion_line("G1X10Y5F300"));
        assert!(is_motion_line("X10"));
        assert!(is_motion_line("G0 U5 V5"));
        assert!(is_motion_line("G2X1Y1I0.5J0"));
        assert!(!is_motion_line("M3S1000"));
        assert!(!is_motion_line("G4P0.5"));
        assert!(!is_motion_line("G92X0Y0"));
        assert!(!is_motion_line("G10L2P1X5"));
        assert!(!is_motion_line("G21G90"));
        assert!(!is_motion_line("F600"));
    }

    #[test]
    fn the_resume_line_walks_back_over_pending_moves() {
        let lines = ["G21", "M3S1000", "G1X1F300", "G1X2", "M5", "G1X3", "G1X4"];
        // Nothing pending: the next line.
        assert_eq!(first_unfinished(&lines, 3, 0), 4);
        // Two blocks pending, last acknowledged X4: X3 was running.
        assert_eq!(first_unfinished(&lines, 6, 2), 5);
        // Three: walks over the M5 to X2.
        assert_eq!(first_unfinished(&lines, 6, 3), 3);
        // More blocks than moves: the start.
        assert_eq!(first_unfinished(&lines, 2, 9), 0);
    }
}
