//! Step 1 of a line: split it into words. G and M commands keep their number and mantissa
//! (G92.1 → (92, 10)); value words (axes, F, I–L, N, P, R, S, T) are stored by letter, each at
//! most once.

use super::code::*;

/// The words of one line.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Words {
    /// G commands: (number, mantissa × 100), in line order.
    pub gs: Vec<(u16, u8)>,
    /// M commands: (number, 0), in line order.
    pub ms: Vec<(u16, u8)>,
    /// Value words, indexed by letter (A = 0).
    pub vals: [Option<f64>; 26],
}

impl Words {
    /// The value of word `c`, if the line has one.
    pub fn value(&self, c: char) -> Option<f64> {
        self.vals[(c as u8 - b'A') as usize]
    }
}

/// Splits `line` (stored form: no spaces or comments, upper case) into words. `axes` are the
/// configured axis letters; any other letter outside `FIJKLNPRST` is unsupported.
pub(super) fn lex(line: &str, axes: &[char]) -> Result<Words, u8> {
    let bytes = line.as_bytes();
    let mut i = 0;
    let mut gs: Vec<(u16, u8)> = Vec::new();
    let mut ms: Vec<(u16, u8)> = Vec::new();
    let mut vals: [Option<f64>; 26] = [None; 26];
    while i < bytes.len() {
        let letter = bytes[i];
        if !letter.is_ascii_uppercase() {
            return Err(EXPECTED_COMMAND_LETTER);
        }
        i += 1;
        let start = i;
        if i < bytes.len() && (bytes[i] == b'-' || bytes[i] == b'+') {
            i += 1;
        }
        let mut digits = 0;
        let mut dot = false;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || (bytes[i] == b'.' && !dot)) {
            if bytes[i] == b'.' {
                dot = true;
            } else {
                digits += 1;
            }
            i += 1;
        }
        if digits == 0 {
            return Err(BAD_NUMBER_FORMAT);
        }
        // GRBL, grblHAL and FluidNC hold a word in a 32-bit float (GRBL's `read_float`); past
        // its range (3.4e38) the firmware would go on with infinity, and so would our lengths
        // and times (NaN positions). The simulator answers error:2 (bad number) instead.
        let value: f64 = line[start..i]
            .parse()
            .ok()
            .filter(|v: &f64| v.abs() <= f64::from(f32::MAX))
            .ok_or(BAD_NUMBER_FORMAT)?;
        match letter {
            b'G' | b'M' => {
                let int = value.trunc();
                if !(0.0..=999.0).contains(&int) {
                    return Err(UNSUPPORTED_COMMAND);
                }
                let mantissa = ((value - int) * 100.0).round() as u8;
                if letter == b'G' {
                    gs.push((int as u16, mantissa));
                } else {
                    if mantissa > 0 {
                        return Err(COMMAND_VALUE_NOT_INTEGER);
                    }
                    ms.push((int as u16, 0));
                }
            }
            _ => {
                let c = letter as char;
                let known = "FIJKLNPRST".contains(c) || axes.contains(&c);
                if !known {
                    return Err(UNSUPPORTED_COMMAND);
                }
                let slot = &mut vals[(letter - b'A') as usize];
                if slot.is_some() {
                    return Err(WORD_REPEATED);
                }
                *slot = Some(value);
            }
        }
    }
    Ok(Words { gs, ms, vals })
}
