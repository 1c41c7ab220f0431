//! A small RAPID lexer and structure checker for the emitter's tests. It is written from
//! ABB's *Technical reference manual - RAPID kernel* and shares no code with the emitter, so
//! a rule the emitter gets wrong is not also wrong here.
//!
//! It checks, over a program of several modules (in load order):
//! - tokens: identifiers (letter first, then letters, digits, `_`; at most 32 characters),
//!   numbers, strings (`""` and `\\` escapes, `\hh` character codes, no line break, at most 80
//!   characters of value), `!` comments, punctuation; anything else is an error;
//! - structure: `MODULE name` … `ENDMODULE` (the name equal to the file's stem), data
//!   declarations, then `PROC name()` … `ENDPROC`, balanced; every statement ends with `;`;
//! - names: no reserved word as a name; no name declared twice in one scope (any case);
//! - declarations before use: every data name used is declared earlier (in its module, or
//!   globally in an earlier module), predefined by ABB, or one of the `externals` (controller
//!   data such as seamdata and I/O signals);
//! - calls: every statement is a known instruction or a call of a `PROC` defined in one of
//!   the modules.
//!
//! The subset is what the emitter writes: no IF/WHILE/FOR, no functions, no TRAPs.

#![allow(dead_code)]

use std::collections::{HashMap, HashSet};

/// RAPID's longest identifier (RAPID kernel, "Identifiers").
pub const MAX_IDENT: usize = 32;
/// RAPID's longest string value (RAPID kernel, data type `string`).
pub const MAX_STRING: usize = 80;

/// Reserved words (RAPID kernel, "Reserved words").
const RESERVED: &[&str] = &[
    "ALIAS",
    "AND",
    "BACKWARD",
    "CASE",
    "CONNECT",
    "CONST",
    "DEFAULT",
    "DIV",
    "DO",
    "ELSE",
    "ELSEIF",
    "ENDFOR",
    "ENDFUNC",
    "ENDIF",
    "ENDMODULE",
    "ENDPROC",
    "ENDRECORD",
    "ENDTEST",
    "ENDTRAP",
    "ENDWHILE",
    "ERROR",
    "EXIT",
    "FALSE",
    "FOR",
    "FROM",
    "FUNC",
    "GOTO",
    "IF",
    "INOUT",
    "LOCAL",
    "MOD",
    "MODULE",
    "NOSTEPIN",
    "NOT",
    "NOVIEW",
    "OR",
    "PERS",
    "PROC",
    "RAISE",
    "READONLY",
    "RECORD",
    "RETRY",
    "RETURN",
    "STEP",
    "SYSMODULE",
    "TASK",
    "TEST",
    "THEN",
    "TO",
    "TRAP",
    "TRUE",
    "TRYNEXT",
    "UNDO",
    "VAR",
    "VIEWONLY",
    "WHILE",
    "WITH",
    "XOR",
];

/// Instructions the emitter may use (RAPID instructions reference; Arc option).
const INSTRUCTIONS: &[&str] = &[
    "MoveL",
    "MoveJ",
    "ArcLStart",
    "ArcL",
    "ArcLEnd",
    "SetDO",
    "TPWrite",
    "ConfL",
    "ConfJ",
    "WaitTime",
];

/// Data types a declaration may have.
const TYPES: &[&str] = &[
    "robtarget",
    "speeddata",
    "zonedata",
    "tooldata",
    "wobjdata",
    "string",
    "num",
    "bool",
    "jointtarget",
    "seamdata",
    "welddata",
    "loaddata",
];

/// One token.
#[derive(Debug, Clone, PartialEq)]
pub enum Tok {
    /// An identifier or keyword, as written.
    Ident(String),
    /// A numeric literal, as written.
    Num(String),
    /// A string literal's value (escapes decoded).
    Str(String),
    /// Punctuation: `:=`, `[`, `]`, `(`, `)`, `,`, `;`, `\`, `-`, `+`, …
    Punct(String),
}

/// A token and its 1-based line.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    pub tok: Tok,
    pub line: usize,
}

fn is_reserved(name: &str) -> bool {
    RESERVED.contains(&name.to_ascii_uppercase().as_str())
}

/// Splits RAPID source into tokens.
pub fn lex(src: &str) -> Result<Vec<Token>, String> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line = 1;
    while i < chars.len() {
        let c = chars[i];
        match c {
            '\n' => {
                line += 1;
                i += 1;
            }
            ' ' | '\t' | '\r' => i += 1,
            '!' => {
                while i < chars.len() && chars[i] != '\n' {
                    i += 1;
                }
            }
            c if c.is_ascii_alphabetic() => {
                let start = i;
                while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
                let name: String = chars[start..i].iter().collect();
                if name.len() > MAX_IDENT {
                    return Err(format!(
                        "line {line}: identifier {name} has {} characters (max {MAX_IDENT})",
                        name.len()
                    ));
                }
                out.push(Token {
                    tok: Tok::Ident(name),
                    line,
                });
            }
            c if c.is_ascii_digit() => {
                let start = i;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
                if i < chars.len() && chars[i] == '.' {
                    i += 1;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
                if i < chars.len() && (chars[i] == 'E' || chars[i] == 'e') {
                    i += 1;
                    if i < chars.len() && (chars[i] == '+' || chars[i] == '-') {
                        i += 1;
                    }
                    let digits = i;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                    if digits == i {
                        return Err(format!("line {line}: exponent without digits"));
                    }
                }
                if i < chars.len() && (chars[i].is_ascii_alphabetic() || chars[i] == '_') {
                    return Err(format!(
                        "line {line}: a number runs into {:?} (identifiers start with a letter)",
                        chars[i]
                    ));
                }
                out.push(Token {
                    tok: Tok::Num(chars[start..i].iter().collect()),
                    line,
                });
            }
            '"' => {
                i += 1;
                let mut value = String::new();
                loop {
                    let Some(&c) = chars.get(i) else {
                        return Err(format!("line {line}: unterminated string"));
                    };
                    match c {
                        '\n' | '\r' => {
                            return Err(format!("line {line}: line break inside a string"))
                        }
                        '"' if chars.get(i + 1) == Some(&'"') => {
                            value.push('"');
                            i += 2;
                        }
                        '"' => {
                            i += 1;
                            break;
                        }
                        '\\' if chars.get(i + 1) == Some(&'\\') => {
                            value.push('\\');
                            i += 2;
                        }
                        '\\' => {
                            let hex: String =
                                chars.get(i + 1..i + 3).unwrap_or(&[]).iter().collect();
                            let code = (hex.len() == 2)
                                .then(|| u8::from_str_radix(&hex, 16).ok())
                                .flatten()
                                .ok_or_else(|| {
                                    format!(
                                        "line {line}: bad escape in string (\\\\, \\hh or \"\")"
                                    )
                                })?;
                            value.push(char::from(code));
                            i += 3;
                        }
                        c if c.is_ascii_control() => {
                            return Err(format!("line {line}: control character in a string"))
                        }
                        c => {
                            value.push(c);
                            i += 1;
                        }
                    }
                }
                let n = value.chars().count();
                if n > MAX_STRING {
                    return Err(format!(
                        "line {line}: string of {n} characters (max {MAX_STRING})"
                    ));
                }
                out.push(Token {
                    tok: Tok::Str(value),
                    line,
                });
            }
            ':' if chars.get(i + 1) == Some(&'=') => {
                out.push(Token {
                    tok: Tok::Punct(":=".into()),
                    line,
                });
                i += 2;
            }
            '[' | ']' | '(' | ')' | ',' | ';' | '\\' | '-' | '+' | '*' | '/' | '{' | '}' | '='
            | ':' | '%' => {
                out.push(Token {
                    tok: Tok::Punct(c.to_string()),
                    line,
                });
                i += 1;
            }
            c => return Err(format!("line {line}: unexpected character {c:?}")),
        }
    }
    Ok(out)
}

/// What a checked program contains.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Summary {
    /// Module names, in order.
    pub modules: Vec<String>,
    /// PROC names, in order of definition.
    pub procs: Vec<String>,
    /// Statements per PROC: (instruction or called PROC, first argument if a name).
    pub statements: HashMap<String, Vec<(String, Option<String>)>>,
    /// Declarations: (module, type, name).
    pub declarations: Vec<(String, String, String)>,
    /// String values in the program.
    pub strings: Vec<String>,
}

impl Summary {
    /// How many statements of `instruction` the program has.
    pub fn count(&self, instruction: &str) -> usize {
        self.statements
            .values()
            .flatten()
            .filter(|(s, _)| s == instruction)
            .count()
    }

    /// Declarations of a type.
    pub fn declared(&self, ty: &str) -> Vec<&str> {
        self.declarations
            .iter()
            .filter(|(_, t, _)| t.eq_ignore_ascii_case(ty))
            .map(|(_, _, n)| n.as_str())
            .collect()
    }
}

struct Parser<'a> {
    toks: &'a [Token],
    at: usize,
    file: &'a str,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.at).map(|t| &t.tok)
    }

    fn line(&self) -> usize {
        self.toks
            .get(self.at)
            .or(self.toks.last())
            .map_or(0, |t| t.line)
    }

    fn err<T>(&self, what: &str) -> Result<T, String> {
        Err(format!("{}:{}: {what}", self.file, self.line()))
    }

    fn next(&mut self) -> Option<Tok> {
        let t = self.peek().cloned();
        self.at += 1;
        t
    }

    fn is_keyword(&self, kw: &str) -> bool {
        matches!(self.peek(), Some(Tok::Ident(s)) if s.eq_ignore_ascii_case(kw))
    }

    fn is_punct(&self, p: &str) -> bool {
        matches!(self.peek(), Some(Tok::Punct(s)) if s == p)
    }

    fn keyword(&mut self, kw: &str) -> Result<(), String> {
        if self.is_keyword(kw) {
            self.at += 1;
            Ok(())
        } else {
            self.err(&format!("expected {kw}, found {:?}", self.peek()))
        }
    }

    fn punct(&mut self, p: &str) -> Result<(), String> {
        if self.is_punct(p) {
            self.at += 1;
            Ok(())
        } else {
            self.err(&format!("expected '{p}', found {:?}", self.peek()))
        }
    }

    /// A name being defined: an identifier that is not a reserved word.
    fn name(&mut self) -> Result<String, String> {
        match self.next() {
            Some(Tok::Ident(s)) if !is_reserved(&s) => Ok(s),
            Some(Tok::Ident(s)) => {
                self.at -= 1;
                self.err(&format!("reserved word {s} used as a name"))
            }
            other => {
                self.at -= 1;
                self.err(&format!("expected a name, found {other:?}"))
            }
        }
    }
}

/// Names visible while checking: global (all modules so far) and the current module's local.
struct Scope {
    global: HashSet<String>,
    local: HashSet<String>,
    externals: HashSet<String>,
}

impl Scope {
    fn knows(&self, name: &str) -> bool {
        let lower = name.to_ascii_lowercase();
        self.global.contains(&lower)
            || self.local.contains(&lower)
            || self.externals.contains(&lower)
            || predefined(&lower)
    }
}

/// ABB's predefined data: `fine`, `z0` … `z200`, `v5` … `v7000`, `vmax`, `tool0`, `wobj0`,
/// `load0` (lower case).
fn predefined(lower: &str) -> bool {
    const ZONES: &[&str] = &[
        "fine", "z0", "z1", "z5", "z10", "z15", "z20", "z30", "z40", "z50", "z60", "z80", "z100",
        "z150", "z200",
    ];
    const SPEEDS: &[&str] = &[
        "v5", "v10", "v20", "v30", "v40", "v50", "v60", "v80", "v100", "v150", "v200", "v300",
        "v400", "v500", "v600", "v800", "v1000", "v1500", "v2000", "v2500", "v3000", "v4000",
        "v5000", "v6000", "v7000", "vmax",
    ];
    ZONES.contains(&lower)
        || SPEEDS.contains(&lower)
        || ["tool0", "wobj0", "load0"].contains(&lower)
}

/// Checks `files` = (file name, text) as one program, modules in load order. `externals`
/// are names that exist on the controller (I/O signals, seamdata, welddata, tools).
pub fn check_program(files: &[(&str, &str)], externals: &[&str]) -> Result<Summary, String> {
    let mut summary = Summary::default();
    let mut lexed = Vec::new();
    for (file, text) in files {
        let toks = lex(text).map_err(|e| format!("{file}: {e}"))?;
        lexed.push((*file, toks));
    }
    // First pass: every PROC defined anywhere (calls may go forward).
    let mut procs: HashSet<String> = HashSet::new();
    for (_, toks) in &lexed {
        for w in toks.windows(2) {
            if let (Tok::Ident(k), Tok::Ident(n)) = (&w[0].tok, &w[1].tok) {
                if k.eq_ignore_ascii_case("PROC") {
                    procs.insert(n.to_ascii_lowercase());
                }
            }
        }
    }
    let mut scope = Scope {
        global: HashSet::new(),
        local: HashSet::new(),
        externals: externals.iter().map(|s| s.to_ascii_lowercase()).collect(),
    };
    let mut module_names: HashSet<String> = HashSet::new();
    let mut proc_names: HashSet<String> = HashSet::new();
    for (file, toks) in &lexed {
        let mut p = Parser { toks, at: 0, file };
        scope.local.clear();
        p.keyword("MODULE")?;
        let module = p.name()?;
        let stem = file.rsplit_once('.').map_or(*file, |(s, _)| s);
        if module != stem {
            return p.err(&format!(
                "module {module} is in file {file} (expected {stem}.*)"
            ));
        }
        if !module_names.insert(module.to_ascii_lowercase()) {
            return p.err(&format!("module {module} defined twice"));
        }
        summary.modules.push(module.clone());
        // Data declarations.
        loop {
            let mut local = false;
            if p.is_keyword("LOCAL") {
                p.at += 1;
                local = true;
            } else if p.is_keyword("TASK") {
                p.at += 1;
            }
            if !(p.is_keyword("CONST") || p.is_keyword("VAR") || p.is_keyword("PERS")) {
                if local && !p.is_keyword("PROC") {
                    return p.err("LOCAL must be followed by a declaration or PROC");
                }
                if local {
                    p.at -= 1;
                }
                break;
            }
            p.at += 1;
            let ty = p.name()?;
            if !TYPES.iter().any(|t| t.eq_ignore_ascii_case(&ty)) {
                return p.err(&format!("unknown data type {ty}"));
            }
            let name = p.name()?;
            let lower = name.to_ascii_lowercase();
            if procs.contains(&lower) || module_names.contains(&lower) {
                return p.err(&format!("{name} is also a module or routine name"));
            }
            if p.is_punct(":=") {
                p.at += 1;
                expression(&mut p, &scope, &mut summary.strings)?;
            }
            p.punct(";")?;
            let set = if local {
                &mut scope.local
            } else {
                &mut scope.global
            };
            if !set.insert(lower) {
                return p.err(&format!("{name} declared twice"));
            }
            summary.declarations.push((module.clone(), ty, name));
        }
        // Routines.
        while !p.is_keyword("ENDMODULE") {
            if p.is_keyword("LOCAL") {
                p.at += 1;
            }
            if p.peek().is_none() {
                return p.err("missing ENDMODULE");
            }
            p.keyword("PROC")?;
            let name = p.name()?;
            if !proc_names.insert(name.to_ascii_lowercase()) {
                return p.err(&format!("PROC {name} defined twice"));
            }
            if module_names.contains(&name.to_ascii_lowercase()) {
                return p.err(&format!("PROC {name} has a module's name"));
            }
            p.punct("(")?;
            p.punct(")")?;
            summary.procs.push(name.clone());
            let mut statements = Vec::new();
            loop {
                if p.is_keyword("ENDPROC") {
                    p.at += 1;
                    break;
                }
                match p.peek() {
                    None => return p.err(&format!("PROC {name}: missing ENDPROC")),
                    Some(Tok::Ident(s)) if is_reserved(s) => {
                        return p.err(&format!("PROC {name}: unexpected {s} (missing ENDPROC?)"))
                    }
                    _ => {}
                }
                statements.push(statement(&mut p, &scope, &procs, &mut summary.strings)?);
            }
            summary.statements.insert(name, statements);
        }
        p.at += 1;
        if p.peek().is_some() {
            return p.err("text after ENDMODULE");
        }
        // This module's global names are now visible to the modules after it.
    }
    Ok(summary)
}

/// One statement: `Instruction args;` or `ProcName;`.
fn statement(
    p: &mut Parser,
    scope: &Scope,
    procs: &HashSet<String>,
    strings: &mut Vec<String>,
) -> Result<(String, Option<String>), String> {
    let head = p.name()?;
    let known = INSTRUCTIONS.iter().any(|i| i.eq_ignore_ascii_case(&head));
    if !known && !procs.contains(&head.to_ascii_lowercase()) {
        return p.err(&format!(
            "{head} is neither an instruction nor a PROC of the program"
        ));
    }
    if p.is_punct(":=") {
        return p.err("assignments are not part of the checked subset");
    }
    let first = match p.peek() {
        Some(Tok::Ident(s)) => Some(s.clone()),
        _ => None,
    };
    // Arguments: expressions separated by ',', optional arguments `\Name[:=expr]`.
    let mut expect_arg = !p.is_punct(";");
    while expect_arg {
        if p.is_punct("\\") {
            p.at += 1;
            let _switch = p.name()?;
            if p.is_punct(":=") {
                p.at += 1;
                expression(p, scope, strings)?;
            }
        } else {
            expression(p, scope, strings)?;
        }
        if p.is_punct(",") {
            p.at += 1;
        } else if !p.is_punct("\\") {
            expect_arg = false;
        }
    }
    p.punct(";")?;
    Ok((head, first))
}

/// An expression of the subset: literal, name (declared before), aggregate `[...]`, unary
/// minus, `+` between terms.
fn expression(p: &mut Parser, scope: &Scope, strings: &mut Vec<String>) -> Result<(), String> {
    term(p, scope, strings)?;
    while p.is_punct("+") || p.is_punct("-") || p.is_punct("*") || p.is_punct("/") {
        p.at += 1;
        term(p, scope, strings)?;
    }
    Ok(())
}

fn term(p: &mut Parser, scope: &Scope, strings: &mut Vec<String>) -> Result<(), String> {
    match p.next() {
        Some(Tok::Num(_)) => Ok(()),
        Some(Tok::Str(s)) => {
            strings.push(s);
            Ok(())
        }
        Some(Tok::Punct(s)) if s == "-" || s == "+" => term(p, scope, strings),
        Some(Tok::Punct(s)) if s == "[" => {
            expression(p, scope, strings)?;
            while p.is_punct(",") {
                p.at += 1;
                expression(p, scope, strings)?;
            }
            p.punct("]")
        }
        Some(Tok::Ident(s))
            if s.eq_ignore_ascii_case("TRUE") || s.eq_ignore_ascii_case("FALSE") =>
        {
            Ok(())
        }
        Some(Tok::Ident(s)) if is_reserved(&s) => {
            p.at -= 1;
            p.err(&format!("reserved word {s} in an expression"))
        }
        Some(Tok::Ident(s)) => {
            if scope.knows(&s) {
                Ok(())
            } else {
                p.at -= 1;
                p.err(&format!("{s} is used before it is declared"))
            }
        }
        other => {
            p.at -= 1;
            p.err(&format!("expected an expression, found {other:?}"))
        }
    }
}

/// Checks a `.pgf` program file: the XML declaration with `encoding`, `<Program>`, one
/// `<Module>` per line, `</Program>`. Returns the module file names in order.
pub fn check_pgf(text: &str, encoding: &str) -> Result<Vec<String>, String> {
    let mut lines = text.lines();
    let decl = format!("<?xml version=\"1.0\" encoding=\"{encoding}\" ?>");
    if lines.next() != Some(decl.as_str()) {
        return Err(format!("first line is not {decl}"));
    }
    if lines.next().map(str::trim) != Some("<Program>") {
        return Err("second line is not <Program>".into());
    }
    let mut modules = Vec::new();
    let mut closed = false;
    for l in lines {
        let l = l.trim();
        if closed {
            return Err(format!("text after </Program>: {l}"));
        }
        if l == "</Program>" {
            closed = true;
        } else if let Some(m) = l
            .strip_prefix("<Module>")
            .and_then(|r| r.strip_suffix("</Module>"))
        {
            if m.is_empty() || m.contains(['<', '>', '&', '"', '/', '\\']) {
                return Err(format!("bad module file name {m:?}"));
            }
            modules.push(m.to_string());
        } else {
            return Err(format!("unexpected line {l}"));
        }
    }
    if !closed {
        return Err("missing </Program>".into());
    }
    Ok(modules)
}
