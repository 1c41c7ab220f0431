//! A G-code program prepared for streaming: comments and blank lines removed, every remaining
//! line keeping its line number in the original text, and every line checked against what GRBL
//! can take before a byte is sent.

use crate::protocol::{Realtime, LINE_BUFFER_SIZE, RX_BUFFER_SIZE};

/// One line to send, with its 1-based line number in the original program text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramLine {
    /// Line number in the original text (1-based).
    pub number: usize,
    /// The text sent to the controller, without the `\n`.
    pub text: String,
}

impl ProgramLine {
    /// Bytes this line occupies in the controller's RX buffer, `\n` included.
    pub fn wire_len(&self) -> usize {
        self.text.len() + 1
    }
}

/// How a program's text is cleaned before streaming.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CleanOptions {
    /// Remove every space and tab inside a line too (GRBL ignores them; fewer bytes to send).
    /// Off by default, so the sent text stays readable in logs.
    pub strip_whitespace: bool,
    /// Controller commands a program may carry after all, each a whole line as written
    /// (compared without spaces and case, as GRBL reads them), e.g. `$H` for homing. Every
    /// other controller command is refused ([`ProgramError::ControllerCommand`]).
    pub allowed_commands: Vec<String>,
}

/// Why a program cannot be streamed; every variant names the original line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProgramError {
    /// A `(` comment is not closed on its line (GRBL comments do not span lines).
    #[error("line {line}: unclosed '(' comment")]
    UnclosedComment {
        /// Original line number.
        line: usize,
    },
    /// The line is longer than GRBL's 79-character line buffer (spaces and comments not counted).
    #[error(
        "line {line}: {chars} characters, GRBL takes at most {max} (error:11 on the controller)"
    )]
    TooLong {
        /// Original line number.
        line: usize,
        /// Characters GRBL would store (no spaces, no comments).
        chars: usize,
        /// The limit, 79.
        max: usize,
    },
    /// The line with its `\n` is longer than GRBL's 127 usable RX-buffer bytes, so character
    /// counting could never send it.
    #[error("line {line}: {bytes} bytes with its newline, more than the {max} bytes GRBL's RX buffer holds")]
    WiderThanRxBuffer {
        /// Original line number.
        line: usize,
        /// Bytes on the wire, `\n` included.
        bytes: usize,
        /// The limit, 127.
        max: usize,
    },
    /// The line is a command to the controller itself (a GRBL `$` system command or a FluidNC
    /// `[ESP…]` command), not G-code, and the controller file does not allow it.
    #[error("line {line}: `{text}` is a controller command, not G-code (the controller would execute it); allow it in the controller file's `allowed_commands` if it is meant")]
    ControllerCommand {
        /// Original line number.
        line: usize,
        /// The line as written, comments removed.
        text: String,
    },
    /// The line holds a byte GRBL would take as a real-time command (`?`, `!`, `~`, 0x18,
    /// bytes from 0x80) or another control character, or is not ASCII.
    #[error("line {line}: contains byte 0x{byte:02x}, which GRBL would act on as a real-time command or cannot take")]
    ForbiddenByte {
        /// Original line number.
        line: usize,
        /// The offending byte.
        byte: u8,
    },
}

/// Whether a cleaned line is a command to the controller itself rather than G-code: GRBL's
/// `$` system commands (`$H`, `$X`, `$RST=*`, `$N0=…`, `$J=…`, settings `$32=1`) and
/// FluidNC's `[ESP…]` commands. Streamed as program lines, the controller would execute them:
/// `$N0=M3S1000` stores a start-up block that switches the heat on at every reset, `$RST=*`
/// wipes the settings.
pub fn is_controller_command(line: &str) -> bool {
    line.starts_with('$')
        || line
            .get(..4)
            .is_some_and(|head| head.eq_ignore_ascii_case("[ESP"))
}

/// A line as GRBL compares it: no spaces or tabs, letters in upper case.
fn normalised(line: &str) -> String {
    line.chars()
        .filter(|c| !c.is_whitespace())
        .map(|c| c.to_ascii_uppercase())
        .collect()
}

/// A cleaned program: the lines to send, in order.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Program {
    lines: Vec<ProgramLine>,
}

/// Removes `( ... )` and `;` comments from one line (GRBL 1.1's rules: a `(` comment ends at the
/// first `)`, a `;` comment runs to the end of the line).
fn strip_comments(raw: &str, number: usize) -> Result<String, ProgramError> {
    let mut out = String::with_capacity(raw.len());
    let mut in_paren = false;
    for c in raw.chars() {
        if in_paren {
            if c == ')' {
                in_paren = false;
            }
            continue;
        }
        match c {
            '(' => in_paren = true,
            ';' => break,
            _ => out.push(c),
        }
    }
    if in_paren {
        return Err(ProgramError::UnclosedComment { line: number });
    }
    Ok(out)
}

impl Program {
    /// Cleans `text` (the emitter's `MachineProgram` text) for streaming.
    ///
    /// Comments are removed, lines are trimmed, and lines left empty (blank, comment-only, `%`
    /// tape markers) are dropped; every kept line remembers its original line number, which is
    /// what errors, progress and resume use.
    pub fn parse(text: &str, options: CleanOptions) -> Result<Program, ProgramError> {
        let mut lines = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let number = i + 1;
            let stripped = strip_comments(raw, number)?;
            let mut t = stripped.trim().to_string();
            if options.strip_whitespace {
                t.retain(|c| c != ' ' && c != '\t');
            }
            if t.is_empty() || t == "%" {
                continue;
            }
            if is_controller_command(&t)
                && !options
                    .allowed_commands
                    .iter()
                    .any(|allowed| normalised(allowed) == normalised(&t))
            {
                return Err(ProgramError::ControllerCommand {
                    line: number,
                    text: t,
                });
            }
            for b in t.bytes() {
                let forbidden = Realtime::from_byte(b).is_some()
                    || b >= 0x80
                    || (b < 0x20 && b != b'\t')
                    || b == 0x7f;
                if forbidden {
                    return Err(ProgramError::ForbiddenByte {
                        line: number,
                        byte: b,
                    });
                }
            }
            let chars = t.chars().filter(|c| !c.is_whitespace()).count();
            if chars > LINE_BUFFER_SIZE - 1 {
                return Err(ProgramError::TooLong {
                    line: number,
                    chars,
                    max: LINE_BUFFER_SIZE - 1,
                });
            }
            if t.len() + 1 > RX_BUFFER_SIZE - 1 {
                return Err(ProgramError::WiderThanRxBuffer {
                    line: number,
                    bytes: t.len() + 1,
                    max: RX_BUFFER_SIZE - 1,
                });
            }
            lines.push(ProgramLine { number, text: t });
        }
        Ok(Program { lines })
    }

    /// Builds a program from lines that are already clean (numbered 1, 2, 3, ...).
    pub fn from_clean_lines<I, S>(lines: I) -> Result<Program, ProgramError>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        let text: Vec<String> = lines.into_iter().map(|s| s.as_ref().to_string()).collect();
        Program::parse(&text.join("\n"), CleanOptions::default())
    }

    /// The lines to send.
    pub fn lines(&self) -> &[ProgramLine] {
        &self.lines
    }

    /// Number of lines to send.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// True when nothing is left to send.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// Index into [`Program::lines`] of the line with original number `number`, or of the first
    /// line after it when `number` was a dropped (comment or blank) line.
    pub fn index_of_line(&self, number: usize) -> Option<usize> {
        let i = self.lines.partition_point(|l| l.number < number);
        (i < self.lines.len()).then_some(i)
    }

    /// Bytes of the whole program on the wire (`\n` included).
    pub fn wire_bytes(&self) -> usize {
        self.lines.iter().map(ProgramLine::wire_len).sum()
    }

    /// The longest line on the wire (`\n` included).
    pub fn longest_line(&self) -> usize {
        self.lines
            .iter()
            .map(ProgramLine::wire_len)
            .max()
            .unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controller_commands_are_refused_unless_allowed() {
        for (text, line, command) in [
            ("G21\n$N0=M3S1000\nG1 X1 F100\n", 2, "$N0=M3S1000"),
            ("G21\n(wipe) $RST=*\n", 2, "$RST=*"),
            ("$h\n", 1, "$h"),
            ("G90\n\n $32 = 1 ; laser mode\n", 3, "$32 = 1"),
            ("[ESP800]\n", 1, "[ESP800]"),
            ("[esp444]RESTART\n", 1, "[esp444]RESTART"),
        ] {
            let err = Program::parse(text, CleanOptions::default()).unwrap_err();
            assert_eq!(
                err,
                ProgramError::ControllerCommand {
                    line,
                    text: command.into()
                },
                "{text:?}"
            );
            assert!(
                err.to_string()
                    .starts_with(&format!("line {line}: `{command}`")),
                "{err}"
            );
        }
        let homing = CleanOptions {
            allowed_commands: vec!["$H".into()],
            ..CleanOptions::default()
        };
        let p = Program::parse("$H\n$ h\nG1 X1 F100\n", homing.clone()).unwrap();
        assert_eq!(
            p.len(),
            3,
            "the allowed command, in any case and spacing, is kept"
        );
        assert!(matches!(
            Program::parse("$H\n$X\n", homing),
            Err(ProgramError::ControllerCommand { line: 2, .. })
        ));
        // G-code that merely contains `$` or brackets elsewhere is not a controller command.
        assert!(Program::parse("G1 X[1+2] F100\n", CleanOptions::default()).is_ok());
    }

    #[test]
    fn comments_and_blank_lines_go_and_line_numbers_stay() {
        let text = "(header)\nG21 G90 ; metric\n\n  G1 X1 (move) Y2 F100  \n%\n;only\nM2\n";
        let p = Program::parse(text, CleanOptions::default()).unwrap();
        let got: Vec<(usize, &str)> = p
            .lines()
            .iter()
            .map(|l| (l.number, l.text.as_str()))
            .collect();
        assert_eq!(got, vec![(2, "G21 G90"), (4, "G1 X1  Y2 F100"), (7, "M2")]);
        assert_eq!(
            p.index_of_line(3),
            Some(1),
            "a dropped line resumes at the next kept one"
        );
        assert_eq!(p.index_of_line(7), Some(2));
        assert_eq!(p.index_of_line(8), None);
        let compact = Program::parse(
            text,
            CleanOptions {
                strip_whitespace: true,
                ..CleanOptions::default()
            },
        )
        .unwrap();
        assert_eq!(compact.lines()[1].text, "G1X1Y2F100");
        assert_eq!(compact.lines()[1].wire_len(), 11);
    }

    #[test]
    fn lines_grbl_cannot_take_are_refused_with_their_number() {
        assert_eq!(
            Program::parse("G0 X1\nG1 (oops X2", CleanOptions::default()),
            Err(ProgramError::UnclosedComment { line: 2 })
        );
        assert_eq!(
            Program::parse("G0 X1\n\nG1 X2 ! ", CleanOptions::default()),
            Err(ProgramError::ForbiddenByte {
                line: 3,
                byte: b'!'
            })
        );
        let long = format!("G1 X{}", "1".repeat(77));
        assert!(matches!(
            Program::parse(&long, CleanOptions::default()),
            Err(ProgramError::TooLong {
                line: 1,
                chars: 80,
                max: 79
            })
        ));
        // Spaces and comments do not count toward GRBL's 79 characters.
        let ok = format!(
            "G1 X{} (a long comment that GRBL never stores)",
            "1".repeat(75)
        );
        assert!(Program::parse(&ok, CleanOptions::default()).is_ok());
        // A `?` inside a comment is harmless: comments are never sent.
        assert!(Program::parse("G0 X1 (why?)", CleanOptions::default()).is_ok());
    }
}
