//! The simulator's light RAPID check, standing in for the controller's load-time parse.
//!
//! It checks what a failed load on a real controller most often comes down to in generated
//! code: the module is not empty; its first statement is `MODULE name` with the name of the
//! file; `PROC`/`FUNC`/`TRAP` and their `END...` pair up without nesting; `ENDMODULE` closes
//! the module and nothing follows it; no string literal runs past the end of its line; the
//! extension suits the generation (`.mod`/`.sys` on RobotWare 6; also `.modx`/`.sysx`, UTF-8,
//! on RobotWare 7). It is not a RAPID parser: statements inside routines are not checked.

use crate::config::RwsVersion;

/// A load failure: 1-based line (0 for the whole file) and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadFailure {
    /// Line of the problem, 1-based; 0 when it concerns the whole file.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

fn fail(line: usize, message: impl Into<String>) -> LoadFailure {
    LoadFailure {
        line,
        message: message.into(),
    }
}

/// The module's name if `text` passes the light check for a file called `file_name`.
///
/// # Errors
/// The first problem found, with its line.
pub fn check_module(
    file_name: &str,
    text: &[u8],
    version: RwsVersion,
) -> Result<String, LoadFailure> {
    let (stem, ext) = file_name
        .rsplit_once('.')
        .map(|(s, e)| (s, e.to_ascii_lowercase()))
        .unwrap_or((file_name, String::new()));
    let allowed: &[&str] = match version {
        RwsVersion::Rw6 => &["mod", "sys"],
        RwsVersion::Rw7 => &["mod", "sys", "modx", "sysx"],
    };
    if !allowed.contains(&ext.as_str()) {
        return Err(fail(
            0,
            format!("`.{ext}` is not a module extension here (expected one of {allowed:?})"),
        ));
    }
    let text = match std::str::from_utf8(text) {
        Ok(t) => t.to_owned(),
        // RobotWare 6 reads ISO-8859-1: every byte is a character.
        Err(_) if version == RwsVersion::Rw6 => text.iter().map(|&b| b as char).collect(),
        Err(e) => return Err(fail(0, format!("not UTF-8: {e}"))),
    };
    let tokens = tokenize(&text)?;
    let Some(first) = tokens.first() else {
        return Err(fail(0, "empty module (no MODULE statement)"));
    };
    if !first.1.eq_ignore_ascii_case("MODULE") {
        return Err(fail(
            first.0,
            format!("MODULE expected, found `{}`", first.1),
        ));
    }
    let Some((name_line, name)) = tokens.get(1) else {
        return Err(fail(first.0, "module name missing after MODULE"));
    };
    if !name.eq_ignore_ascii_case(stem) {
        return Err(fail(
            *name_line,
            format!("module name `{name}` differs from the file name `{stem}`"),
        ));
    }
    let mut open: Option<(usize, &str)> = None;
    let mut end = None;
    for (line, word) in &tokens[2..] {
        if let Some(end_line) = end {
            return Err(fail(
                *line,
                format!("`{word}` after ENDMODULE (line {end_line})"),
            ));
        }
        let upper = word.to_ascii_uppercase();
        match upper.as_str() {
            "PROC" | "FUNC" | "TRAP" => {
                if let Some((l, kind)) = open {
                    return Err(fail(
                        *line,
                        format!("{upper} inside {kind} opened at line {l} (END{kind} missing)"),
                    ));
                }
                open = Some((
                    *line,
                    match upper.as_str() {
                        "PROC" => "PROC",
                        "FUNC" => "FUNC",
                        _ => "TRAP",
                    },
                ));
            }
            "ENDPROC" | "ENDFUNC" | "ENDTRAP" => match open {
                Some((_, kind)) if upper[3..] == *kind => open = None,
                Some((l, kind)) => {
                    return Err(fail(
                        *line,
                        format!("{upper} closes {kind} opened at line {l}"),
                    ))
                }
                None => return Err(fail(*line, format!("{upper} without an open routine"))),
            },
            "ENDMODULE" => {
                if let Some((l, kind)) = open {
                    return Err(fail(
                        *line,
                        format!("ENDMODULE inside {kind} opened at line {l} (END{kind} missing)"),
                    ));
                }
                end = Some(*line);
            }
            "MODULE" => return Err(fail(*line, "MODULE inside a module")),
            _ => {}
        }
    }
    if end.is_none() {
        let last = tokens.last().map_or(first.0, |t| t.0);
        return Err(match open {
            Some((l, kind)) => fail(
                last,
                format!("END{kind} missing for {kind} opened at line {l}"),
            ),
            None => fail(
                last,
                format!("ENDMODULE missing (MODULE {name} at line {})", first.0),
            ),
        });
    }
    Ok(name.clone())
}

/// True if the module text declares `PROC main(` (case-insensitive, outside comments).
pub fn has_main(text: &[u8]) -> bool {
    let text: String = text.iter().map(|&b| b as char).collect();
    let Ok(tokens) = tokenize(&text) else {
        return false;
    };
    tokens
        .windows(2)
        .any(|w| w[0].1.eq_ignore_ascii_case("PROC") && w[1].1.eq_ignore_ascii_case("main"))
}

/// The signals the module switches on with `SetDO NAME, 1;` (outside comments), in order,
/// each once: what the simulator turns on while the program runs.
pub fn outputs_switched_on(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for line in text.lines() {
        let code = line.split('!').next().unwrap_or_default().trim();
        let Some(args) = code
            .get(..5)
            .filter(|head| head.eq_ignore_ascii_case("SetDO"))
            .map(|_| &code[5..])
            .filter(|rest| rest.starts_with(char::is_whitespace))
        else {
            continue;
        };
        let args = args.trim().trim_end_matches(';');
        let Some((name, value)) = args.split_once(',') else {
            continue;
        };
        let name = name.trim();
        if value.trim() == "1" && !name.is_empty() && !out.iter().any(|n| n == name) {
            out.push(name.to_owned());
        }
    }
    out
}

/// Identifier-like words with their 1-based line, comments (`!` to end of line) and string
/// literals removed.
fn tokenize(text: &str) -> Result<Vec<(usize, String)>, LoadFailure> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let mut in_string = false;
        let mut word = String::new();
        for c in line.chars() {
            if in_string {
                if c == '"' {
                    in_string = false;
                }
                continue;
            }
            if c.is_alphanumeric() || c == '_' {
                word.push(c);
                continue;
            }
            if !word.is_empty() {
                out.push((n, std::mem::take(&mut word)));
            }
            match c {
                '"' => in_string = true,
                '!' => break,
                _ => {}
            }
        }
        if in_string {
            return Err(fail(n, "string literal not closed on its line"));
        }
        if !word.is_empty() {
            out.push((n, word));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "MODULE Job1\n    ! a comment with PROC and \"quotes\n    VAR string s := \"ENDMODULE!\";\n    PROC main()\n        TPWrite s;\n    ENDPROC\nENDMODULE\n";

    #[test]
    fn accepts_a_plain_module() {
        assert_eq!(
            check_module("Job1.mod", GOOD.as_bytes(), RwsVersion::Rw6).unwrap(),
            "Job1"
        );
        assert_eq!(
            check_module("JOB1.modx", GOOD.as_bytes(), RwsVersion::Rw7).unwrap(),
            "Job1"
        );
        assert!(has_main(GOOD.as_bytes()));
    }

    #[test]
    fn rejects_broken_modules_with_the_line() {
        let cases: [(&str, &str, usize, &str); 7] = [
            ("Job1.mod", "", 0, "empty module"),
            ("Job1.mod", "PROC main()\nENDPROC\n", 1, "MODULE expected"),
            ("Other.mod", GOOD, 1, "differs from the file name"),
            (
                "Job1.mod",
                "MODULE Job1\n PROC main()\n ENDPROC\n",
                3,
                "ENDMODULE missing",
            ),
            (
                "Job1.mod",
                "MODULE Job1\n PROC main()\nENDMODULE\n",
                3,
                "ENDMODULE inside PROC",
            ),
            (
                "Job1.mod",
                "MODULE Job1\nENDMODULE\nPROC x()\n",
                3,
                "after ENDMODULE",
            ),
            (
                "Job1.mod",
                "MODULE Job1\n VAR string s := \"x;\nENDMODULE\n",
                2,
                "not closed",
            ),
        ];
        for (file, text, line, what) in cases {
            let e = check_module(file, text.as_bytes(), RwsVersion::Rw6).unwrap_err();
            assert_eq!(e.line, line, "{file}: {text:?}: {e:?}");
            assert!(e.message.contains(what), "{text:?}: {e:?}");
        }
        let e = check_module("Job1.modx", GOOD.as_bytes(), RwsVersion::Rw6).unwrap_err();
        assert!(e.message.contains("not a module extension"), "{e:?}");
    }

    #[test]
    fn finds_the_outputs_a_program_switches_on() {
        let text = "MODULE W\n PROC main()\n  SetDO Local/DRV_1/doWeld, 0;\n  ! SetDO doLaser, 1;\n  SetDO Local/DRV_1/doWeld, 1;\n  SetDO doGas,1;\n  SetDO Local/DRV_1/doWeld, 1;\n ENDPROC\nENDMODULE\n";
        assert_eq!(outputs_switched_on(text), ["Local/DRV_1/doWeld", "doGas"]);
    }
}
