//! The words of one G-code line as GRBL reads them: a letter and a number each, spaces
//! ignored, letters in either case. [`crate::resume`] rebuilds a program's modal state with it.
//!
//! The simulator has its own parser (`sim::gcode`), which is the model the resume is checked
//! against in the tests; the two share no code, so a mistake in one is not hidden by the other.

/// Why a line does not split into words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WordError {
    /// A character where a word letter should be.
    #[error("`{0}` where a word letter should be")]
    NotALetter(char),
    /// A letter without a number after it.
    #[error("word {0} has no number")]
    NoNumber(char),
    /// A value word given twice on one line (GRBL: `error:25`).
    #[error("word {0} appears twice")]
    Repeated(char),
    /// A G or M number GRBL cannot hold (more than one decimal, a decimal M, out of range).
    #[error("{0} is not a G-code command number")]
    BadCode(String),
}

/// The words of one line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Words {
    /// G commands in line order, as (number, tenths): `G92.1` is (92, 1).
    pub g: Vec<(u16, u8)>,
    /// M commands in line order.
    pub m: Vec<u16>,
    /// Value words (every letter but G and M), by letter, A = 0.
    values: [Option<f64>; 26],
}

impl Words {
    /// Splits `line` (comments already removed) into words.
    ///
    /// # Errors
    /// A character that is not a letter where a word starts, a letter with no number, a value
    /// word twice, a G or M number that is no command.
    pub fn scan(line: &str) -> Result<Words, WordError> {
        let chars: Vec<char> = line
            .chars()
            .filter(|c| !c.is_whitespace())
            .map(|c| c.to_ascii_uppercase())
            .collect();
        let mut words = Words::default();
        let mut i = 0;
        while i < chars.len() {
            let letter = chars[i];
            if !letter.is_ascii_uppercase() {
                return Err(WordError::NotALetter(letter));
            }
            i += 1;
            let start = i;
            if i < chars.len() && matches!(chars[i], '+' | '-') {
                i += 1;
            }
            let mut digits = 0;
            let mut dot = false;
            while i < chars.len() && (chars[i].is_ascii_digit() || (chars[i] == '.' && !dot)) {
                dot |= chars[i] == '.';
                digits += usize::from(chars[i].is_ascii_digit());
                i += 1;
            }
            let text: String = chars[start..i].iter().collect();
            let value = match text.parse::<f64>() {
                Ok(v) if digits > 0 => v,
                _ => return Err(WordError::NoNumber(letter)),
            };
            match letter {
                'G' => words.g.push(code(letter, &text, value, true)?),
                'M' => words.m.push(code(letter, &text, value, false)?.0),
                _ => {
                    let slot = &mut words.values[usize::from(letter as u8 - b'A')];
                    if slot.replace(value).is_some() {
                        return Err(WordError::Repeated(letter));
                    }
                }
            }
        }
        Ok(words)
    }

    /// The value of word `letter` (not G or M), if the line has it.
    pub fn value(&self, letter: char) -> Option<f64> {
        let k = letter.to_ascii_uppercase() as u8;
        k.is_ascii_uppercase()
            .then(|| self.values[usize::from(k - b'A')])
            .flatten()
    }

    /// The value words the line has, as (letter, value), in alphabetical order.
    pub fn values(&self) -> impl Iterator<Item = (char, f64)> + '_ {
        self.values
            .iter()
            .enumerate()
            .filter_map(|(k, v)| v.map(|v| ((b'A' + k as u8) as char, v)))
    }

    /// True if the line has G command `number`.`tenths`.
    pub fn has_g(&self, number: u16, tenths: u8) -> bool {
        self.g.contains(&(number, tenths))
    }
}

/// A G or M command number as (number, tenths); M numbers and G numbers with more than one
/// decimal place are refused.
fn code(letter: char, text: &str, value: f64, decimal: bool) -> Result<(u16, u8), WordError> {
    let bad = || WordError::BadCode(format!("{letter}{text}"));
    if !(0.0..1000.0).contains(&value) {
        return Err(bad());
    }
    let number = value.trunc();
    let tenths = (value - number) * 10.0;
    if (tenths - tenths.round()).abs() > 1e-6 || (!decimal && tenths.round() != 0.0) {
        return Err(bad());
    }
    Ok((number as u16, tenths.round() as u8))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_split_into_commands_and_values() {
        let w = Words::scan("g17 G21 g90 G92.1 m3 S300 x-1.5 Y.25 F+36").unwrap();
        assert_eq!(w.g, vec![(17, 0), (21, 0), (90, 0), (92, 1)]);
        assert_eq!(w.m, vec![3]);
        assert_eq!(w.value('S'), Some(300.0));
        assert_eq!(w.value('x'), Some(-1.5));
        assert_eq!(w.value('Y'), Some(0.25));
        assert_eq!(w.value('F'), Some(36.0));
        assert_eq!(w.value('Z'), None);
        assert!(w.has_g(92, 1) && !w.has_g(92, 0));
        let letters: Vec<char> = w.values().map(|(c, _)| c).collect();
        assert_eq!(letters, ['F', 'S', 'X', 'Y']);
        assert_eq!(Words::scan("G 1 X 1 0").unwrap().value('X'), Some(10.0));
    }

    #[test]
    fn bad_words_are_named() {
        assert_eq!(Words::scan("G1 X"), Err(WordError::NoNumber('X')));
        assert_eq!(Words::scan("G1 X-"), Err(WordError::NoNumber('X')));
        assert_eq!(Words::scan("G1 X1 X2"), Err(WordError::Repeated('X')));
        assert_eq!(Words::scan("G1 #1"), Err(WordError::NotALetter('#')));
        assert_eq!(Words::scan("M3.5"), Err(WordError::BadCode("M3.5".into())));
        assert_eq!(
            Words::scan("G38.25"),
            Err(WordError::BadCode("G38.25".into()))
        );
    }
}
