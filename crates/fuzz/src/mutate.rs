//! The byte mutator: libFuzzer's and AFL's "havoc" stage in small (bit and byte flips,
//! interesting integers, inserts, deletes, duplicated ranges, splices between corpus entries,
//! format tokens, numbers swapped for edge cases), 1 to 8 of them stacked per input.
//!
//! Hand-written on purpose: the well-kept mutators are tied to a fuzzing engine (libFuzzer via
//! `cargo fuzz`, nightly only; `libafl` with its own runtime), and `arbitrary`/`proptest`
//! generate structured values rather than mutate a corpus of real files, which is what finds
//! bugs in parsers of real formats.

/// Numbers that break parsers: zero, signs, limits, overflow, huge exponents, not-a-number.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551616",
    "1e308",
    "1e309",
    "-1e309",
    "1e-320",
    "NaN",
    "inf",
    "-inf",
    ".",
    "-",
    "0x10",
    "99999999999999999999999999",
];

/// Byte values at the edges of signed and unsigned integers.
const INTERESTING_U8: &[u8] = &[0, 1, 0x7f, 0x80, 0xff, b'\n', b'\r', 0];
const INTERESTING_U32: &[u32] = &[
    0,
    1,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    0xffff,
    0x1_0000,
];

/// A mutator with its own seeded random numbers (a run is repeatable from its seed).
pub struct Mutator {
    rng: fastrand::Rng,
    tokens: &'static [&'static str],
    max_len: usize,
}

impl Mutator {
    /// A mutator seeded with `seed`, splicing in `tokens`, making inputs of at most `max_len`
    /// bytes.
    pub fn new(seed: u64, tokens: &'static [&'static str], max_len: usize) -> Self {
        Mutator {
            rng: fastrand::Rng::with_seed(seed),
            tokens,
            max_len: max_len.max(1),
        }
    }

    /// A random index below `n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        self.rng.usize(..n.max(1))
    }

    /// A new input from `base`, with `other` (another corpus entry) available for splicing.
    pub fn mutate(&mut self, base: &[u8], other: &[u8]) -> Vec<u8> {
        let mut data = base.to_vec();
        let rounds = 1 << self.rng.u32(0..4);
        for _ in 0..rounds {
            self.once(&mut data, other);
        }
        data.truncate(self.max_len);
        data
    }

    fn once(&mut self, data: &mut Vec<u8>, other: &[u8]) {
        let len = data.len();
        match self.rng.u32(0..12) {
            0 if len > 0 => {
                let i = self.below(len);
                data[i] ^= 1 << self.rng.u32(0..8);
            }
            1 if len > 0 => {
                let i = self.below(len);
                data[i] = self.rng.u8(..);
            }
            2 if len > 0 => {
                let i = self.below(len);
                data[i] = INTERESTING_U8[self.below(INTERESTING_U8.len())];
            }
            3 if len >= 4 => {
                let i = self.below(len - 3);
                let v = INTERESTING_U32[self.below(INTERESTING_U32.len())];
                let bytes = if self.rng.bool() {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                };
                data[i..i + 4].copy_from_slice(&bytes);
            }
            4 => {
                let at = self.below(len + 1);
                let n = 1 + self.below(16);
                let bytes: Vec<u8> = (0..n).map(|_| self.rng.u8(..)).collect();
                data.splice(at..at, bytes);
            }
            5 if len > 0 => {
                let at = self.below(len);
                let n = 1 + self.below((len - at).min(64));
                data.drain(at..at + n);
            }
            6 if len > 0 => {
                // Duplicate a range (repeated records, nested brackets, long lines).
                let at = self.below(len);
                let n = 1 + self.below((len - at).min(256));
                let copy = data[at..at + n].to_vec();
                let to = self.below(len + 1);
                data.splice(to..to, copy);
            }
            7 if !other.is_empty() => {
                // Splice: our head, the other entry's tail.
                let cut = self.below(len + 1);
                let from = self.below(other.len());
                data.truncate(cut);
                data.extend_from_slice(&other[from..]);
            }
            8 | 9 if !self.tokens.is_empty() => {
                let token = self.tokens[self.below(self.tokens.len())].as_bytes();
                let at = self.below(len + 1);
                if self.rng.bool() || len == 0 {
                    data.splice(at..at, token.iter().copied());
                } else {
                    let end = (at + token.len()).min(len);
                    data.splice(at..end, token.iter().copied());
                }
            }
            10 => self.swap_number(data),
            11 if len > 0 => {
                let keep = self.below(len);
                data.truncate(keep);
            }
            _ => {
                let at = self.below(len + 1);
                data.insert(at, self.rng.u8(..));
            }
        }
    }

    /// Replaces an ASCII number in `data` (or inserts at random) with one of [`NUMBERS`].
    fn swap_number(&mut self, data: &mut Vec<u8>) {
        let number = NUMBERS[self.below(NUMBERS.len())].as_bytes();
        let starts: Vec<usize> = (0..data.len())
            .filter(|&i| data[i].is_ascii_digit() && (i == 0 || !data[i - 1].is_ascii_digit()))
            .collect();
        if starts.is_empty() {
            let at = self.below(data.len() + 1);
            data.splice(at..at, number.iter().copied());
            return;
        }
        let start = starts[self.below(starts.len())];
        let mut end = start;
        while end < data.len() && (data[end].is_ascii_digit() || data[end] == b'.') {
            end += 1;
        }
        data.splice(start..end, number.iter().copied());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_makes_the_same_inputs_and_lengths_stay_capped() {
        let run = |seed| {
            let mut m = Mutator::new(seed, &["G1", "X"], 40);
            (0..200)
                .map(|_| m.mutate(b"G1 X10 Y20 F300\n", b"$H\n"))
                .collect::<Vec<_>>()
        };
        let a = run(7);
        assert_eq!(a, run(7));
        assert_ne!(a, run(8));
        assert!(a.iter().all(|x| x.len() <= 40));
        assert!(a.iter().any(|x| x.as_slice() != b"G1 X10 Y20 F300\n"));
    }
}
