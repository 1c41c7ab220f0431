//! An independent reader of the ABB RAPID programs the emitter writes (no code shared with
//! `cell_emitter`): the modules of one program read together, their data declarations and
//! routines, a structure check (every name an instruction uses is declared in the program or
//! predefined by ABB), and the motion the program makes when `main` runs, with each move's
//! target, speed, weld data, tool and work object resolved from the declarations.
//!
//! It reads what RAPID allows in the generated code's style: one statement ends at `;`
//! (declarations and instructions), `MODULE`/`PROC`/`FUNC`/`TRAP` headers and their `END…` stand
//! alone, comments run from `!` to the end of the line, optional arguments are written
//! `\Name` or `\Name:=value` with no comma before them.
#![allow(dead_code)] // each test binary uses a different subset

use std::collections::HashMap;
use std::fmt;

/// One file of the program: its name and text.
pub struct SourceFile<'a> {
    /// File name, e.g. `WAAM_job.mod`.
    pub name: &'a str,
    /// The file's text.
    pub text: &'a str,
}

/// A value of a declaration: a number, string, boolean, name or aggregate `[…]`.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Num(f64),
    Str(String),
    Bool(bool),
    Name(String),
    Agg(Vec<Value>),
}

impl Value {
    /// The number, for `Num`.
    pub fn num(&self) -> Option<f64> {
        match self {
            Value::Num(v) => Some(*v),
            _ => None,
        }
    }

    /// Component `i` of an aggregate.
    pub fn at(&self, i: usize) -> Option<&Value> {
        match self {
            Value::Agg(items) => items.get(i),
            _ => None,
        }
    }

    /// The numbers of an aggregate of numbers.
    pub fn nums(&self) -> Option<Vec<f64>> {
        match self {
            Value::Agg(items) => items.iter().map(Value::num).collect(),
            _ => None,
        }
    }
}

/// A data declaration: `[LOCAL] CONST|PERS|VAR type name [:= value];`.
#[derive(Debug, Clone)]
pub struct Declaration {
    pub module: usize,
    /// The routine it is declared in (routine data), if any.
    pub routine: Option<String>,
    pub local: bool,
    pub storage: String,
    pub data_type: String,
    pub name: String,
    pub value: Option<Value>,
    pub line: usize,
}

/// One argument of an instruction: positional, or optional (`\Name`, `\Name:=expr`).
#[derive(Debug, Clone, PartialEq)]
pub struct Argument {
    /// The optional argument's name (without `\`), `None` for a positional argument.
    pub switch: Option<String>,
    /// The expression's text, `None` for a bare switch.
    pub expr: Option<String>,
}

/// One instruction or procedure call in a routine.
#[derive(Debug, Clone)]
pub struct Statement {
    pub name: String,
    pub args: Vec<Argument>,
    pub line: usize,
}

/// A `PROC`, `FUNC` or `TRAP`.
#[derive(Debug, Clone)]
pub struct Routine {
    pub module: usize,
    pub local: bool,
    pub kind: String,
    pub name: String,
    pub statements: Vec<Statement>,
    pub line: usize,
}

/// One module.
#[derive(Debug, Clone)]
pub struct Module {
    pub file: String,
    pub name: String,
}

/// Every module of one program, read together.
#[derive(Debug, Clone, Default)]
pub struct Program {
    pub modules: Vec<Module>,
    pub declarations: Vec<Declaration>,
    pub routines: Vec<Routine>,
}

/// A reading or structure problem, at `file:line`.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub file: String,
    pub line: usize,
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.file, self.line, self.message)
    }
}

/// Names ABB predefines on every controller (RAPID reference, "Predefined data"): the fine
/// point, zones `z0`…`z200`, speeds `v5`…`v7000` and `vmax`, the base tool, work object and load.
pub fn is_predefined(name: &str) -> bool {
    const ZONES: [u32; 14] = [0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200];
    const SPEEDS: [u32; 25] = [
        5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000, 1500, 2000,
        2500, 3000, 4000, 5000, 6000, 7000,
    ];
    let lower = name.to_ascii_lowercase();
    if ["fine", "vmax", "tool0", "wobj0", "load0", "true", "false"].contains(&lower.as_str()) {
        return true;
    }
    let number = |prefix: &str| {
        lower
            .strip_prefix(prefix)
            .and_then(|n| n.parse::<u32>().ok())
    };
    number("z").is_some_and(|n| ZONES.contains(&n))
        || number("v").is_some_and(|n| SPEEDS.contains(&n))
}

/// RAPID words that are operators or literals, never data names.
const KEYWORDS: [&str; 8] = ["AND", "OR", "NOT", "XOR", "DIV", "MOD", "TRUE", "FALSE"];

/// Instructions whose first argument is an I/O signal (declared in the controller's I/O
/// configuration, not in RAPID).
const SIGNAL_INSTRUCTIONS: [&str; 5] = ["SetDO", "Set", "Reset", "PulseDO", "WaitDI"];

/// Reads the modules of one program. Problems are syntax the reader does not understand.
pub fn read(files: &[SourceFile]) -> Result<Program, Vec<Problem>> {
    let mut program = Program::default();
    let mut problems = Vec::new();
    for file in files {
        read_module(file, &mut program, &mut problems);
    }
    if problems.is_empty() {
        Ok(program)
    } else {
        Err(problems)
    }
}

/// Text with comments removed, cut into statements: (first line, text).
fn statements(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current = String::new();
    let mut start = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut in_string = false;
        let mut code = String::new();
        for c in raw.chars() {
            if c == '"' {
                in_string = !in_string;
            }
            if c == '!' && !in_string {
                break;
            }
            code.push(c);
        }
        let code = code.trim();
        if code.is_empty() {
            continue;
        }
        if current.is_empty() {
            start = line;
            let first = code
                .split_whitespace()
                .next()
                .unwrap_or("")
                .to_ascii_uppercase();
            let header = [
                "MODULE",
                "ENDMODULE",
                "PROC",
                "ENDPROC",
                "FUNC",
                "ENDFUNC",
                "TRAP",
                "ENDTRAP",
            ]
            .contains(&first.as_str())
                || (first == "LOCAL"
                    && code.split_whitespace().nth(1).is_some_and(|w| {
                        ["PROC", "FUNC", "TRAP"].contains(&w.to_ascii_uppercase().as_str())
                    }));
            if header {
                out.push((line, code.to_string()));
                continue;
            }
        }
        if !current.is_empty() {
            current.push(' ');
        }
        current.push_str(code);
        // Statements end with `;` outside strings.
        let mut in_string = false;
        let mut pieces = Vec::new();
        let mut piece = String::new();
        for c in current.chars() {
            if c == '"' {
                in_string = !in_string;
            }
            if c == ';' && !in_string {
                pieces.push(std::mem::take(&mut piece));
            } else {
                piece.push(c);
            }
        }
        for p in pieces {
            let p = p.trim().to_string();
            if !p.is_empty() {
                out.push((start, p));
            }
        }
        current = piece.trim().to_string();
    }
    if !current.is_empty() {
        out.push((start, format!("{current} <missing ;>")));
    }
    out
}

fn read_module(file: &SourceFile, program: &mut Program, problems: &mut Vec<Problem>) {
    let problem = |line: usize, message: String| Problem {
        file: file.name.to_string(),
        line,
        message,
    };
    let module = program.modules.len();
    let mut routine: Option<Routine> = None;
    let mut ended = false;
    for (line, text) in statements(file.text) {
        if text.ends_with("<missing ;>") {
            problems.push(problem(line, format!("statement not ended by `;`: {text}")));
            continue;
        }
        let words: Vec<&str> = text.split_whitespace().collect();
        let first = words[0].to_ascii_uppercase();
        if ended {
            problems.push(problem(line, format!("text after ENDMODULE: {text}")));
            continue;
        }
        match first.as_str() {
            "MODULE" => {
                let name = words
                    .get(1)
                    .map(|n| n.split('(').next().unwrap_or(n))
                    .unwrap_or("");
                program.modules.push(Module {
                    file: file.name.to_string(),
                    name: name.to_string(),
                });
                continue;
            }
            "ENDMODULE" => {
                ended = true;
                continue;
            }
            _ => {}
        }
        if program.modules.len() != module + 1 {
            problems.push(problem(line, format!("statement before MODULE: {text}")));
            continue;
        }
        let (local, rest) = match first.as_str() {
            "LOCAL" | "TASK" => (first == "LOCAL", &words[1..]),
            _ => (false, &words[..]),
        };
        let head = rest
            .first()
            .map(|w| w.to_ascii_uppercase())
            .unwrap_or_default();
        match head.as_str() {
            "PROC" | "FUNC" | "TRAP" => {
                if let Some(open) = &routine {
                    problems.push(problem(line, format!("{head} inside {}", open.name)));
                }
                // PROC name(...) / FUNC type name(...) / TRAP name
                let after = if head == "FUNC" {
                    rest.get(2)
                } else {
                    rest.get(1)
                };
                let name = after
                    .map(|w| w.split('(').next().unwrap_or(w).to_string())
                    .unwrap_or_default();
                if !is_identifier(&name) {
                    problems.push(problem(
                        line,
                        format!("routine name missing or bad: {text}"),
                    ));
                }
                routine = Some(Routine {
                    module,
                    local,
                    kind: head.clone(),
                    name,
                    statements: Vec::new(),
                    line,
                });
            }
            "ENDPROC" | "ENDFUNC" | "ENDTRAP" => match routine.take() {
                Some(r) if format!("END{}", r.kind) == head => program.routines.push(r),
                Some(r) => problems.push(problem(
                    line,
                    format!("{head} closes {} {}", r.kind, r.name),
                )),
                None => problems.push(problem(line, format!("{head} without a routine"))),
            },
            "CONST" | "PERS" | "VAR" => match declaration(&text, local) {
                Ok((storage, data_type, name, value)) => program.declarations.push(Declaration {
                    module,
                    routine: routine.as_ref().map(|r| r.name.clone()),
                    local,
                    storage,
                    data_type,
                    name,
                    value,
                    line,
                }),
                Err(e) => problems.push(problem(line, e)),
            },
            _ => match &mut routine {
                Some(r) => match statement(&text) {
                    Ok((name, args)) => r.statements.push(Statement { name, args, line }),
                    Err(e) => problems.push(problem(line, e)),
                },
                None => problems.push(problem(
                    line,
                    format!("instruction outside a routine: {text}"),
                )),
            },
        }
    }
    if program.modules.len() != module + 1 {
        problems.push(problem(0, "no MODULE statement".into()));
    } else if !ended {
        problems.push(problem(0, "no ENDMODULE".into()));
    }
    if let Some(r) = routine {
        problems.push(problem(
            r.line,
            format!("{} {} never ended", r.kind, r.name),
        ));
    }
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && s.len() <= 32
}

/// `[LOCAL] CONST type name := value` → (storage, type, name, value).
fn declaration(text: &str, local: bool) -> Result<(String, String, String, Option<Value>), String> {
    let text = if local {
        text.trim_start()[5..].trim_start()
    } else {
        text
    };
    let text = text.strip_prefix("TASK ").unwrap_or(text);
    let (head, init) = match text.split_once(":=") {
        Some((h, v)) => (h, Some(v.trim())),
        None => (text, None),
    };
    let words: Vec<&str> = head.split_whitespace().collect();
    let [storage, data_type, name] = words.as_slice() else {
        return Err(format!("declaration not understood: {text}"));
    };
    if !is_identifier(name) || !is_identifier(data_type) {
        return Err(format!("declaration with a bad name or type: {text}"));
    }
    let value = match init {
        Some(v) => Some(parse_value(v).map_err(|e| format!("{name}: {e}"))?),
        None => None,
    };
    Ok((
        storage.to_ascii_uppercase(),
        data_type.to_string(),
        name.to_string(),
        value,
    ))
}

/// Parses a literal value: numbers (with exponent), strings, booleans, names and aggregates.
pub fn parse_value(text: &str) -> Result<Value, String> {
    let chars: Vec<char> = text.chars().collect();
    let mut at = 0;
    let v = value_at(&chars, &mut at)?;
    while at < chars.len() && chars[at].is_whitespace() {
        at += 1;
    }
    if at != chars.len() {
        return Err(format!(
            "unexpected `{}` in {text}",
            chars[at..].iter().collect::<String>()
        ));
    }
    Ok(v)
}

fn value_at(c: &[char], at: &mut usize) -> Result<Value, String> {
    while *at < c.len() && c[*at].is_whitespace() {
        *at += 1;
    }
    let Some(&first) = c.get(*at) else {
        return Err("value missing".into());
    };
    if first == '[' {
        *at += 1;
        let mut items = Vec::new();
        loop {
            items.push(value_at(c, at)?);
            while *at < c.len() && c[*at].is_whitespace() {
                *at += 1;
            }
            match c.get(*at) {
                Some(',') => *at += 1,
                Some(']') => {
                    *at += 1;
                    return Ok(Value::Agg(items));
                }
                other => return Err(format!("`,` or `]` expected, found {other:?}")),
            }
        }
    }
    if first == '"' {
        let start = *at + 1;
        let mut i = start;
        while i < c.len() {
            if c[i] == '"' {
                if c.get(i + 1) == Some(&'"') {
                    i += 2;
                    continue;
                }
                *at = i + 1;
                return Ok(Value::Str(c[start..i].iter().collect()));
            }
            i += 1;
        }
        return Err("string not closed".into());
    }
    let start = *at;
    while *at < c.len() && !matches!(c[*at], ',' | ']') && !c[*at].is_whitespace() {
        *at += 1;
    }
    let word: String = c[start..*at].iter().collect();
    if let Ok(v) = word.parse::<f64>() {
        return Ok(Value::Num(v));
    }
    match word.to_ascii_uppercase().as_str() {
        "TRUE" => Ok(Value::Bool(true)),
        "FALSE" => Ok(Value::Bool(false)),
        _ if is_identifier(&word) => Ok(Value::Name(word)),
        _ => Err(format!("value `{word}` not understood")),
    }
}

/// `Name arg, arg\Opt:=x, \Switch` → (name, arguments).
fn statement(text: &str) -> Result<(String, Vec<Argument>), String> {
    let text = text.trim();
    let name_end = text
        .find(|c: char| c.is_whitespace() || c == '\\')
        .unwrap_or(text.len());
    let name = &text[..name_end];
    if !is_identifier(name) {
        return Err(format!("instruction not understood: {text}"));
    }
    // Split the rest at commas and backslashes outside brackets and strings.
    let rest = &text[name_end..];
    let mut pieces: Vec<(bool, String)> = Vec::new();
    let mut depth = 0i32;
    let mut in_string = false;
    let mut piece = String::new();
    let mut optional = false;
    for ch in rest.chars() {
        match ch {
            '"' => {
                in_string = !in_string;
                piece.push(ch);
            }
            '[' | '(' if !in_string => {
                depth += 1;
                piece.push(ch);
            }
            ']' | ')' if !in_string => {
                depth -= 1;
                piece.push(ch);
            }
            ',' | '\\' if !in_string && depth == 0 => {
                if !piece.trim().is_empty() || optional {
                    pieces.push((optional, std::mem::take(&mut piece)));
                }
                piece.clear();
                optional = ch == '\\';
            }
            _ => piece.push(ch),
        }
    }
    if in_string || depth != 0 {
        return Err(format!("unbalanced string or brackets: {text}"));
    }
    if !piece.trim().is_empty() || optional {
        pieces.push((optional, piece));
    }
    let args = pieces
        .into_iter()
        .map(|(optional, p)| {
            let p = p.trim();
            if optional {
                match p.split_once(":=") {
                    Some((n, e)) => Argument {
                        switch: Some(n.trim().to_string()),
                        expr: Some(e.trim().to_string()),
                    },
                    None => Argument {
                        switch: Some(p.to_string()),
                        expr: None,
                    },
                }
            } else {
                Argument {
                    switch: None,
                    expr: Some(p.to_string()),
                }
            }
        })
        .collect();
    Ok((name.to_string(), args))
}

/// The data names an expression refers to (not function names, record fields or keywords).
pub fn referenced_names(expr: &str) -> Vec<String> {
    let chars: Vec<char> = expr.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut in_string = false;
    while i < chars.len() {
        let c = chars[i];
        if c == '"' {
            in_string = !in_string;
            i += 1;
            continue;
        }
        if in_string {
            i += 1;
            continue;
        }
        let after_dot = i > 0 && chars[i - 1] == '.';
        let in_number = i > 0 && (chars[i - 1].is_ascii_digit());
        if c.is_ascii_alphabetic() && !in_number {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            let is_call = chars[i..].iter().find(|c| !c.is_whitespace()) == Some(&'(');
            if !after_dot && !is_call && !KEYWORDS.contains(&word.to_ascii_uppercase().as_str()) {
                out.push(word);
            }
        } else {
            i += 1;
        }
    }
    out
}

impl Program {
    /// The declaration `name` resolves to from `module` (and `routine`): routine data, then
    /// the module's own data (local or global), then global data of any module.
    pub fn lookup(&self, module: usize, routine: Option<&str>, name: &str) -> Option<&Declaration> {
        let same = |d: &&Declaration| d.name.eq_ignore_ascii_case(name);
        self.declarations
            .iter()
            .filter(same)
            .find(|d| d.module == module && d.routine.is_some() && d.routine.as_deref() == routine)
            .or_else(|| {
                self.declarations
                    .iter()
                    .filter(same)
                    .find(|d| d.module == module && d.routine.is_none())
            })
            .or_else(|| {
                self.declarations
                    .iter()
                    .filter(same)
                    .find(|d| !d.local && d.routine.is_none())
            })
    }

    /// The routine `name` resolves to from `module`.
    pub fn routine(&self, module: usize, name: &str) -> Option<&Routine> {
        let same = |r: &&Routine| r.name.eq_ignore_ascii_case(name);
        self.routines
            .iter()
            .filter(same)
            .find(|r| r.module == module)
            .or_else(|| self.routines.iter().filter(same).find(|r| !r.local))
    }

    fn file(&self, module: usize) -> String {
        self.modules
            .get(module)
            .map(|m| m.file.clone())
            .unwrap_or_default()
    }

    /// The structure check: one `main`, unique global names, module names unique, every
    /// procedure called declared, and every data name an instruction uses declared in the
    /// program (in scope) or predefined ([`is_predefined`]). I/O signals of `SetDO` and the
    /// like are the controller's and not checked here.
    pub fn structure_problems(&self) -> Vec<Problem> {
        let mut out = Vec::new();
        let mut globals: HashMap<String, (usize, usize)> = HashMap::new();
        for d in self
            .declarations
            .iter()
            .filter(|d| !d.local && d.routine.is_none())
        {
            let key = d.name.to_ascii_lowercase();
            if let Some((m, line)) = globals.insert(key, (d.module, d.line)) {
                out.push(Problem {
                    file: self.file(d.module),
                    line: d.line,
                    message: format!(
                        "global `{}` declared twice (also {}:{line})",
                        d.name,
                        self.file(m)
                    ),
                });
            }
        }
        let mut names: HashMap<String, usize> = HashMap::new();
        for (i, m) in self.modules.iter().enumerate() {
            if let Some(j) = names.insert(m.name.to_ascii_lowercase(), i) {
                out.push(Problem {
                    file: m.file.clone(),
                    line: 1,
                    message: format!("module name {} also in {}", m.name, self.modules[j].file),
                });
            }
        }
        let mains = self
            .routines
            .iter()
            .filter(|r| r.kind == "PROC" && r.name.eq_ignore_ascii_case("main"))
            .count();
        if mains != 1 {
            out.push(Problem {
                file: self
                    .modules
                    .first()
                    .map(|m| m.file.clone())
                    .unwrap_or_default(),
                line: 0,
                message: format!("{mains} PROC main (one expected)"),
            });
        }
        for r in &self.routines {
            for s in &r.statements {
                let problem = |message: String| Problem {
                    file: self.file(r.module),
                    line: s.line,
                    message,
                };
                if s.args.is_empty()
                    && !is_instruction_without_arguments(&s.name)
                    && self.routine(r.module, &s.name).is_none()
                {
                    out.push(problem(format!(
                        "procedure `{}` called but not declared",
                        s.name
                    )));
                }
                for (i, a) in s.args.iter().enumerate() {
                    if i == 0
                        && a.switch.is_none()
                        && SIGNAL_INSTRUCTIONS.contains(&s.name.as_str())
                    {
                        continue;
                    }
                    let Some(expr) = &a.expr else { continue };
                    for name in referenced_names(expr) {
                        if !is_predefined(&name)
                            && self.lookup(r.module, Some(&r.name), &name).is_none()
                        {
                            out.push(problem(format!(
                                "`{name}` (argument of {}) is not declared in the program",
                                s.name
                            )));
                        }
                    }
                }
            }
        }
        out
    }
}

fn is_instruction_without_arguments(name: &str) -> bool {
    [
        "Stop",
        "Exit",
        "Break",
        "RETURN",
        "StopMove",
        "StartMove",
        "ClearPath",
        "EXIT",
    ]
    .iter()
    .any(|n| n.eq_ignore_ascii_case(name))
}

/// A robtarget's position (mm, in its work object), orientation and configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobTarget {
    pub name_line: usize,
    pub pos: [f64; 3],
    pub quat: [f64; 4],
    pub conf: [f64; 4],
}

/// Weld data as ABB's Arc option declares it (RobotWare 6/7 `welddata`): weld speed (mm/s)
/// first, then the original weld speed, then the main `arcdata`, whose fourth component is
/// the wire feed (m/min). Zero means "not set here".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeldData {
    pub weld_speed_mm_s: f64,
    pub wire_feed_m_min: Option<f64>,
}

/// What kind of move an instruction makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveKind {
    MoveL,
    MoveJ,
    ArcLStart,
    ArcL,
    ArcLEnd,
}

/// One move of the running program, its data resolved.
#[derive(Debug, Clone)]
pub struct Motion {
    pub kind: MoveKind,
    pub target_name: String,
    pub target: RobTarget,
    /// The speeddata's TCP speed (mm/s).
    pub speed_mm_s: f64,
    pub weld: Option<WeldData>,
    pub tool: String,
    pub wobj: String,
    pub file: String,
    pub line: usize,
}

/// What `main` does, in order.
#[derive(Debug, Clone, Default)]
pub struct Run {
    pub motions: Vec<Motion>,
    /// `WaitTime` seconds in total.
    pub wait_s: f64,
    /// `ConfL` switches seen (`On`/`Off`).
    pub confl: Vec<String>,
    /// Weld data names an arc move used that no module declares.
    pub undeclared_weld_data: Vec<String>,
}

impl Program {
    /// Runs `main` in order (following procedure calls) and resolves every move's data.
    ///
    /// # Errors
    /// A move whose target, speed or weld data cannot be resolved to a literal value, or calls
    /// nested deeper than 16.
    pub fn run_main(&self) -> Result<Run, Problem> {
        let main = self
            .routines
            .iter()
            .find(|r| r.kind == "PROC" && r.name.eq_ignore_ascii_case("main"))
            .ok_or(Problem {
                file: String::new(),
                line: 0,
                message: "no PROC main".into(),
            })?;
        let mut run = Run::default();
        self.run_routine(main, &mut run, 0)?;
        Ok(run)
    }

    fn run_routine(&self, r: &Routine, run: &mut Run, depth: usize) -> Result<(), Problem> {
        let file = self.file(r.module);
        let problem = |line: usize, message: String| Problem {
            file: file.clone(),
            line,
            message,
        };
        if depth > 16 {
            return Err(problem(r.line, "calls nested deeper than 16".into()));
        }
        for s in &r.statements {
            let value_of = |expr: &str, want: &str| -> Result<Value, Problem> {
                let expr = expr.trim();
                if let Ok(v @ (Value::Agg(_) | Value::Num(_))) = parse_value(expr) {
                    return Ok(v);
                }
                // ABB's predefined speeds: vN is N mm/s.
                if want == "speeddata" && is_predefined(expr) {
                    if let Ok(v) = expr[1..].parse::<f64>() {
                        return Ok(Value::Agg(vec![Value::Num(v), Value::Num(500.0)]));
                    }
                }
                let d = self
                    .lookup(r.module, Some(&r.name), expr)
                    .ok_or_else(|| problem(s.line, format!("`{expr}` is not declared")))?;
                if !d.data_type.eq_ignore_ascii_case(want) {
                    return Err(problem(
                        s.line,
                        format!("`{expr}` is a {}, {want} expected", d.data_type),
                    ));
                }
                d.value
                    .clone()
                    .ok_or_else(|| problem(s.line, format!("`{expr}` has no value")))
            };
            let kind = match s.name.as_str() {
                "MoveL" => Some(MoveKind::MoveL),
                "MoveJ" => Some(MoveKind::MoveJ),
                "ArcLStart" => Some(MoveKind::ArcLStart),
                "ArcL" => Some(MoveKind::ArcL),
                "ArcLEnd" => Some(MoveKind::ArcLEnd),
                _ => None,
            };
            if let Some(kind) = kind {
                let positional: Vec<&str> = s
                    .args
                    .iter()
                    .filter(|a| a.switch.is_none())
                    .filter_map(|a| a.expr.as_deref())
                    .collect();
                // MoveL ToPoint, Speed, Zone, Tool; ArcL ToPoint, Speed, Seam, Weld, Zone, Tool
                // (an optional \Weave sits between Weld and Zone).
                let arc = !matches!(kind, MoveKind::MoveL | MoveKind::MoveJ);
                let expected = if arc { 6 } else { 4 };
                if positional.len() != expected {
                    return Err(problem(
                        s.line,
                        format!(
                            "{} with {} arguments, {expected} expected",
                            s.name,
                            positional.len()
                        ),
                    ));
                }
                let target_value = value_of(positional[0], "robtarget")?;
                let target = robtarget(&target_value).ok_or_else(|| {
                    problem(
                        s.line,
                        format!("robtarget {} not understood", positional[0]),
                    )
                })?;
                let speed = value_of(positional[1], "speeddata")?
                    .at(0)
                    .and_then(Value::num)
                    .ok_or_else(|| {
                        problem(
                            s.line,
                            format!("speeddata {} not understood", positional[1]),
                        )
                    })?;
                // Undeclared weld data (controller-side) leaves the speed to the speeddata;
                // the structure check reports the name.
                let weld =
                    match arc.then(|| self.lookup(r.module, Some(&r.name), positional[3].trim())) {
                        Some(Some(d)) => {
                            let v = d.value.clone().unwrap_or(Value::Agg(Vec::new()));
                            Some(weld_data(&v).ok_or_else(|| {
                                problem(
                                    s.line,
                                    format!("welddata {} not understood: {v:?}", positional[3]),
                                )
                            })?)
                        }
                        Some(None) => {
                            run.undeclared_weld_data
                                .push(positional[3].trim().to_string());
                            None
                        }
                        None => None,
                    };
                let wobj = s
                    .args
                    .iter()
                    .find(|a| a.switch.as_deref() == Some("WObj"))
                    .and_then(|a| a.expr.clone())
                    .unwrap_or_else(|| "wobj0".into());
                run.motions.push(Motion {
                    kind,
                    target_name: positional[0].trim().to_string(),
                    target: RobTarget {
                        name_line: s.line,
                        ..target
                    },
                    speed_mm_s: speed,
                    weld,
                    tool: positional[expected - 1].trim().to_string(),
                    wobj,
                    file: file.clone(),
                    line: s.line,
                });
                continue;
            }
            match s.name.as_str() {
                "WaitTime" => {
                    let t = s
                        .args
                        .iter()
                        .find(|a| a.switch.is_none())
                        .and_then(|a| a.expr.as_deref())
                        .and_then(|e| value_of(e, "num").ok())
                        .and_then(|v| v.num())
                        .ok_or_else(|| problem(s.line, "WaitTime without a time".into()))?;
                    run.wait_s += t;
                }
                "ConfL" => run
                    .confl
                    .extend(s.args.iter().filter_map(|a| a.switch.clone())),
                _ => {
                    if let Some(called) = self.routine(r.module, &s.name) {
                        self.run_routine(called, run, depth + 1)?;
                    }
                }
            }
        }
        Ok(())
    }
}

/// `[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax…]]`.
pub fn robtarget(v: &Value) -> Option<RobTarget> {
    let pos = v.at(0)?.nums()?;
    let quat = v.at(1)?.nums()?;
    let conf = v.at(2)?.nums()?;
    v.at(3)?.nums()?;
    Some(RobTarget {
        name_line: 0,
        pos: pos.try_into().ok()?,
        quat: quat.try_into().ok()?,
        conf: conf.try_into().ok()?,
    })
}

/// `[weld_speed, org_weld_speed, main_arc, org_arc]`, `arcdata` = `[sched, mode, voltage,
/// wirefeed, …]`.
pub fn weld_data(v: &Value) -> Option<WeldData> {
    let weld_speed_mm_s = v.at(0)?.num()?;
    let wire_feed_m_min = v
        .at(2)
        .and_then(|arc| arc.at(3))
        .and_then(Value::num)
        .filter(|w| *w > 0.0);
    Some(WeldData {
        weld_speed_mm_s,
        wire_feed_m_min,
    })
}
