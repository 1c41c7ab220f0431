//! The simulator's light RAPID check, standing in for the controller's load-time parse.
//!
//! It checks what a failed load on a real controller most often comes down to in generated
//! code: the module is not empty; its first statement is `MODULE name` with the name of the
//! file; `PROC`/`FUNC`/`TRAP` and their `END...` pair up without nesting; `ENDMODULE` closes
//! the module and nothing follows it; no string literal runs past the end of its line; the
//! extension suits the generation (`.mod`/`.sys` on RobotWare 6; also `.modx`/`.sysx`, UTF-8,
//! on RobotWare 7). It is not a RAPID parser: statements inside routines are not checked,
//! except that over a whole program [`check_names`] finds the data names the motion, weld
//! and I/O instructions use that no module declares and the controller does not have.

use std::collections::HashSet;

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

/// ABB's predefined data, on every controller (*Technical reference manual - RAPID
/// Instructions, Functions and Data types*, data types `zonedata`, `speeddata`, `tooldata`,
/// `wobjdata`, `loaddata`: "predefined data"): the stop point `fine` and zones `z0` … `z200`,
/// TCP speeds `v5` … `v7000` and `vmax`, external-axis speeds `vrot*` and `vlin*`, `tool0`,
/// `wobj0`, `load0`. The simulator's default controller-side data.
pub const PREDEFINED_DATA: &[&str] = &[
    "fine", "z0", "z1", "z5", "z10", "z15", "z20", "z30", "z40", "z50", "z60", "z80", "z100",
    "z150", "z200", "v5", "v10", "v20", "v30", "v40", "v50", "v60", "v80", "v100", "v150", "v200",
    "v300", "v400", "v500", "v600", "v800", "v1000", "v1500", "v2000", "v2500", "v3000", "v4000",
    "v5000", "v6000", "v7000", "vmax", "vrot1", "vrot2", "vrot5", "vrot10", "vrot20", "vrot50",
    "vrot100", "vlin10", "vlin20", "vlin50", "vlin100", "vlin200", "vlin500", "vlin1000", "tool0",
    "wobj0", "load0",
];

/// Instructions whose arguments [`check_names`] checks: motion, arc welding, I/O and
/// `TPWrite`.
const CHECKED_INSTRUCTIONS: &[&str] = &[
    "MoveL",
    "MoveJ",
    "MoveC",
    "MoveAbsJ",
    "MoveLDO",
    "MoveJDO",
    "ArcLStart",
    "ArcL",
    "ArcLEnd",
    "ArcCStart",
    "ArcC",
    "ArcCEnd",
    "SetDO",
    "SetAO",
    "SetGO",
    "PulseDO",
    "WaitDI",
    "WaitDO",
    "TPWrite",
];

/// Words that are operators or literals, never data names.
const NOT_NAMES: &[&str] = &["TRUE", "FALSE", "AND", "OR", "NOT", "XOR", "DIV", "MOD"];

/// A name a program uses without declaring it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Undeclared {
    /// The module that uses it.
    pub module: String,
    /// Line of the use in that module, 1-based.
    pub line: usize,
    /// The name as written.
    pub name: String,
}

impl std::fmt::Display for Undeclared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "module {}, line {}: `{}` is not declared in the program nor on the controller",
            self.module, self.line, self.name
        )
    }
}

/// Checks the modules of one program, `(module name, text)`, for names used but declared
/// nowhere: a real controller loads such a program with reference errors and will not run
/// it; the simulator refuses the load instead, so the error shows where the program comes
/// in.
///
/// A light check, not name resolution: the names used are the identifiers among the
/// arguments of the instructions in `CHECKED_INSTRUCTIONS` (not the names of optional
/// arguments after `\`, components after `.`, or functions before `(`); the declared names
/// are those of every `CONST`/`PERS`/`VAR` `type name` and every routine in any of the
/// modules (LOCAL or not), plus `controller_data` (data and I/O signals the controller
/// has). Names compare ignoring case, as in RAPID.
///
/// # Errors
/// The first undeclared use, in module order.
pub fn check_names(modules: &[(&str, &str)], controller_data: &[&str]) -> Result<(), Undeclared> {
    let lexed: Vec<(&str, Vec<(usize, Lexeme)>)> = modules
        .iter()
        .map(|(name, text)| (*name, lex(text).0))
        .collect();
    let mut declared: HashSet<String> = controller_data
        .iter()
        .map(|n| n.to_ascii_lowercase())
        .collect();
    for (_, toks) in &lexed {
        for w in toks.windows(3) {
            let word = |i: usize| match &w[i].1 {
                Lexeme::Word(s) => Some(s.as_str()),
                _ => None,
            };
            if let (Some(kind), Some(a), Some(b)) = (word(0), word(1), word(2)) {
                if ["CONST", "PERS", "VAR"]
                    .iter()
                    .any(|k| k.eq_ignore_ascii_case(kind))
                {
                    declared.insert(b.to_ascii_lowercase());
                }
                if ["PROC", "FUNC", "TRAP"]
                    .iter()
                    .any(|k| k.eq_ignore_ascii_case(kind))
                {
                    declared.insert(a.to_ascii_lowercase());
                }
            }
        }
    }
    for (module, toks) in &lexed {
        let mut i = 0;
        while i < toks.len() {
            let head = match &toks[i].1 {
                Lexeme::Word(s) => s,
                _ => {
                    i += 1;
                    continue;
                }
            };
            let starts_statement =
                i == 0 || toks[i - 1].1 == Lexeme::Punct(';') || toks[i - 1].0 != toks[i].0;
            if !(starts_statement
                && CHECKED_INSTRUCTIONS
                    .iter()
                    .any(|c| c.eq_ignore_ascii_case(head)))
            {
                i += 1;
                continue;
            }
            let end = toks[i..]
                .iter()
                .position(|t| t.1 == Lexeme::Punct(';'))
                .map_or(toks.len(), |k| i + k);
            for k in i + 1..end {
                let (line, Lexeme::Word(name)) = &toks[k] else {
                    continue;
                };
                let before = &toks[k - 1].1;
                let after = toks.get(k + 1).map(|t| &t.1);
                let is_name = !name.starts_with(|c: char| c.is_ascii_digit())
                    && *before != Lexeme::Punct('\\')
                    && *before != Lexeme::Punct('.')
                    && after != Some(&Lexeme::Punct('('))
                    && !NOT_NAMES.iter().any(|n| n.eq_ignore_ascii_case(name));
                if is_name && !declared.contains(&name.to_ascii_lowercase()) {
                    return Err(Undeclared {
                        module: (*module).to_owned(),
                        line: *line,
                        name: name.clone(),
                    });
                }
            }
            i = end + 1;
        }
    }
    Ok(())
}

/// A word (identifier, keyword or number) or one punctuation character.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Lexeme {
    Word(String),
    Punct(char),
}

/// The module's words and punctuation with their 1-based line; comments dropped, a string
/// literal as the punctuation `"`. A string left open ends at its line; the first such line is
/// returned too (the structure check reports it).
fn lex(text: &str) -> (Vec<(usize, Lexeme)>, Option<usize>) {
    let mut out = Vec::new();
    let mut unclosed = None;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let mut in_string = false;
        let mut word = String::new();
        for c in line.chars() {
            if in_string {
                in_string = c != '"';
                continue;
            }
            if c.is_alphanumeric() || c == '_' {
                word.push(c);
                continue;
            }
            if !word.is_empty() {
                out.push((n, Lexeme::Word(std::mem::take(&mut word))));
            }
            match c {
                '!' => break,
                '"' => {
                    in_string = true;
                    out.push((n, Lexeme::Punct('"')));
                }
                c if c.is_whitespace() => {}
                c => out.push((n, Lexeme::Punct(c))),
            }
        }
        if in_string && unclosed.is_none() {
            unclosed = Some(n);
        }
        if !word.is_empty() {
            out.push((n, Lexeme::Word(word)));
        }
    }
    (out, unclosed)
}

/// Identifier-like words with their 1-based line, comments (`!` to end of line) and string
/// literals removed ([`lex`]'s words).
fn tokenize(text: &str) -> Result<Vec<(usize, String)>, LoadFailure> {
    let (lexemes, unclosed) = lex(text);
    if let Some(n) = unclosed {
        return Err(fail(n, "string literal not closed on its line"));
    }
    Ok(lexemes
        .into_iter()
        .filter_map(|(n, l)| match l {
            Lexeme::Word(w) => Some((n, w)),
            Lexeme::Punct(_) => None,
        })
        .collect())
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

    const MAIN: &str = "MODULE W\n    PERS tooldata tA := [TRUE,[[0,0,1],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n    LOCAL CONST robtarget p1 := [[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E9,9E9,9E9,9E9,9E9]];\n    LOCAL CONST string s := \"seamX\";\n    PROC main()\n        TPWrite s;\n        ! ArcL p1, v10, seamX, weldX, z1, tA;\n        MoveL Offs(p1,0,0,10), v100, z1, tA\\WObj:=wobj0;\n        MoveL p1, v100, fine, tA\\WObj:=wobj0;\n        W_1_run;\n    ENDPROC\nENDMODULE\n";
    const PART: &str = "MODULE W_1\n    LOCAL PERS welddata weldX1 := [8,8,[1,0,0,5.53,0,0,0,0,0],[1,0,0,5.53,0,0,0,0,0]];\n    PROC W_1_run()\n        ArcLStart p1, v100, seamX, weldX1, fine, tA\\WObj:=wobj0;\n        ArcLEnd p1, v100, seamX,\n            weldX1, fine, tA\\WObj:=wobjX;\n        SetDO doWeld, 0;\n    ENDPROC\nENDMODULE\n";

    fn predefined() -> Vec<&'static str> {
        PREDEFINED_DATA.to_vec()
    }

    #[test]
    fn names_declared_in_any_module_or_on_the_controller_pass() {
        let mut known = predefined();
        known.extend(["seamX", "wobjX", "doWeld"]);
        check_names(&[("W", MAIN), ("W_1", PART)], &known).unwrap();
        // Names ignore case; declarations in a later module count too.
        let upper = PART.replace("seamX", "SEAMX");
        check_names(&[("W_1", &upper), ("W", MAIN)], &known).unwrap();
    }

    #[test]
    fn an_undeclared_name_is_reported_with_module_and_line() {
        let known = predefined();
        // seamX is only in a string and a comment in the main module: undeclared.
        let e = check_names(&[("W", MAIN), ("W_1", PART)], &known).unwrap_err();
        assert_eq!(
            e,
            Undeclared {
                module: "W_1".into(),
                line: 4,
                name: "seamX".into()
            }
        );
        assert_eq!(
            e.to_string(),
            "module W_1, line 4: `seamX` is not declared in the program nor on the controller"
        );
        // A statement across lines: the name on its own line.
        let mut known = predefined();
        known.extend(["seamX", "doWeld"]);
        let e = check_names(&[("W", MAIN), ("W_1", PART)], &known).unwrap_err();
        assert_eq!((e.line, e.name.as_str()), (6, "wobjX"));
        // The signal of SetDO, and a predefined zone without the predefined list.
        known.push("wobjX");
        let e = check_names(
            &[("W", MAIN), ("W_1", &PART.replace("doWeld", "doLaser"))],
            &known,
        )
        .unwrap_err();
        assert_eq!(e.name, "doLaser");
        let e =
            check_names(&[("W", MAIN), ("W_1", PART)], &["seamX", "wobjX", "doWeld"]).unwrap_err();
        assert_eq!(
            (e.module.as_str(), e.line, e.name.as_str()),
            ("W", 8, "v100")
        );
    }

    #[test]
    fn finds_the_outputs_a_program_switches_on() {
        let text = "MODULE W\n PROC main()\n  SetDO Local/DRV_1/doWeld, 0;\n  ! SetDO doLaser, 1;\n  SetDO Local/DRV_1/doWeld, 1;\n  SetDO doGas,1;\n  SetDO Local/DRV_1/doWeld, 1;\n ENDPROC\nENDMODULE\n";
        assert_eq!(outputs_switched_on(text), ["Local/DRV_1/doWeld", "doGas"]);
    }
}
