//! Parser for ROS 2 interface files (`.msg`, `.srv`, `.action`).
//!
//! Hand-written: no maintained crate parses the ROS 2 interface syntax into a usable model.
//!
//! Supported: `#` comments, blank lines, constants (`uint8 KIND_CUT=0`, `string NAME="text"`),
//! fields with optional defaults (`float64 w 1`, `int32[] xs [1, 2]`), every ROS 2 primitive
//! (including bounded `string<=N`), arrays `T[]`, `T[<=N]`, `T[N]`, and message types written
//! `pkg/Type`, `pkg/msg/Type` or bare `Type` (same package). Default and constant values are
//! parsed into [`serde_json::Value`]s; non-finite floats (`nan`, `inf`) become `null`, as in
//! `serde_json`.

use serde_json::Value;

/// A ROS 2 primitive type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Primitive {
    /// `bool`: one byte, 0 or 1.
    Bool,
    /// `byte`: an opaque octet.
    Byte,
    /// `char`: an unsigned octet in ROS 2.
    Char,
    /// `int8`.
    Int8,
    /// `uint8`.
    Uint8,
    /// `int16`.
    Int16,
    /// `uint16`.
    Uint16,
    /// `int32`.
    Int32,
    /// `uint32`.
    Uint32,
    /// `int64`.
    Int64,
    /// `uint64`.
    Uint64,
    /// `float32`.
    Float32,
    /// `float64`.
    Float64,
    /// `string` or `string<=N` (`max_len` = N, in bytes).
    String {
        /// Upper bound on the length, if bounded.
        max_len: Option<usize>,
    },
    /// `wstring` or `wstring<=N`.
    WString {
        /// Upper bound on the length, if bounded.
        max_len: Option<usize>,
    },
}

impl Primitive {
    /// Parses a primitive type name such as `uint8` or `string<=10`; `None` if it is not one.
    pub fn from_name(name: &str) -> Option<Self> {
        use Primitive::*;
        Some(match name {
            "bool" => Bool,
            "byte" => Byte,
            "char" => Char,
            "int8" => Int8,
            "uint8" => Uint8,
            "int16" => Int16,
            "uint16" => Uint16,
            "int32" => Int32,
            "uint32" => Uint32,
            "int64" => Int64,
            "uint64" => Uint64,
            "float32" => Float32,
            "float64" => Float64,
            "string" => String { max_len: None },
            "wstring" => WString { max_len: None },
            _ => {
                let (wide, bound) = if let Some(b) = name.strip_prefix("string<=") {
                    (false, b)
                } else {
                    (true, name.strip_prefix("wstring<=")?)
                };
                let max_len = Some(bound.parse().ok()?);
                if wide {
                    WString { max_len }
                } else {
                    String { max_len }
                }
            }
        })
    }
}

/// The element type of a field: a primitive or another message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BaseType {
    /// A primitive type.
    Primitive(Primitive),
    /// A message type, normalised to its full ROS 2 name `pkg/msg/Type`.
    Message(String),
}

/// Array suffix of a field type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Array {
    /// `T[]`: a sequence of any length.
    Unbounded,
    /// `T[<=N]`: a sequence of at most N elements.
    Bounded(usize),
    /// `T[N]`: exactly N elements, serialized without a length.
    Fixed(usize),
}

/// A field type: a base type, optionally as an array.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldType {
    /// Element type.
    pub base: BaseType,
    /// Array suffix, `None` for a single value.
    pub array: Option<Array>,
}

/// One field of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field name.
    pub name: String,
    /// Field type.
    pub ty: FieldType,
    /// Default value, if the definition gives one.
    pub default: Option<Value>,
}

/// One constant of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Constant {
    /// Constant name (upper case).
    pub name: String,
    /// Constant type (constants are always single primitives).
    pub ty: Primitive,
    /// Constant value.
    pub value: Value,
}

/// A parsed message (or one part of a service or action).
#[derive(Debug, Clone, PartialEq)]
pub struct MessageSpec {
    /// Full ROS 2 name, e.g. `cell_msgs/msg/Toolpath` or `cell_msgs/action/PlanHotwire_Goal`.
    pub name: String,
    /// Fields in definition (and serialization) order.
    pub fields: Vec<Field>,
    /// Constants in definition order.
    pub constants: Vec<Constant>,
}

impl MessageSpec {
    /// Message types this one uses directly, in field order, each once.
    pub fn dependencies(&self) -> Vec<&str> {
        let mut deps: Vec<&str> = Vec::new();
        for f in &self.fields {
            if let BaseType::Message(m) = &f.ty.base {
                if !deps.contains(&m.as_str()) {
                    deps.push(m);
                }
            }
        }
        deps
    }
}

/// A parsed `.srv` file.
#[derive(Debug, Clone, PartialEq)]
pub struct ServiceSpec {
    /// `<Name>_Request`.
    pub request: MessageSpec,
    /// `<Name>_Response`.
    pub response: MessageSpec,
}

/// A parsed `.action` file.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionSpec {
    /// `<Name>_Goal`.
    pub goal: MessageSpec,
    /// `<Name>_Result`.
    pub result: MessageSpec,
    /// `<Name>_Feedback`.
    pub feedback: MessageSpec,
}

/// Why an interface definition could not be parsed. `file` is the ROS 2 name of the
/// interface, `line` is 1-based within that file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParseError {
    /// The line is not `TYPE NAME [DEFAULT]` or `TYPE NAME=VALUE`.
    #[error("{file}:{line}: expected `TYPE NAME` or `TYPE NAME=VALUE`, got `{text}`")]
    Syntax {
        /// Interface name.
        file: String,
        /// Line number.
        line: usize,
        /// The offending line.
        text: String,
    },
    /// The type is malformed or not allowed here.
    #[error("{file}:{line}: bad type `{ty}`: {reason}")]
    BadType {
        /// Interface name.
        file: String,
        /// Line number.
        line: usize,
        /// The type as written.
        ty: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A field or constant name breaks the ROS 2 naming rules.
    #[error("{file}:{line}: bad name `{name}`: {reason}")]
    BadName {
        /// Interface name.
        file: String,
        /// Line number.
        line: usize,
        /// The name as written.
        name: String,
        /// The rule it breaks.
        reason: String,
    },
    /// A name is used twice in one message.
    #[error("{file}:{line}: name `{name}` is already used")]
    Duplicate {
        /// Interface name.
        file: String,
        /// Line number.
        line: usize,
        /// The repeated name.
        name: String,
    },
    /// A default or constant value does not fit its type.
    #[error("{file}:{line}: bad value `{value}` for `{name}`: {reason}")]
    BadValue {
        /// Interface name.
        file: String,
        /// Line number.
        line: usize,
        /// Field or constant name.
        name: String,
        /// The value as written.
        value: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A `.srv` or `.action` file has the wrong number of `---` separators.
    #[error("{file}:{line}: expected {expected} sections separated by `---`, found {found}")]
    Sections {
        /// Interface name.
        file: String,
        /// Line of the extra separator, or the last line when separators are missing.
        line: usize,
        /// Sections the file kind needs.
        expected: usize,
        /// Sections found.
        found: usize,
    },
}

impl ParseError {
    /// ROS 2 name of the interface the error is in.
    pub fn file(&self) -> &str {
        match self {
            Self::Syntax { file, .. }
            | Self::BadType { file, .. }
            | Self::BadName { file, .. }
            | Self::Duplicate { file, .. }
            | Self::BadValue { file, .. }
            | Self::Sections { file, .. } => file,
        }
    }

    /// 1-based line number of the error.
    pub fn line(&self) -> usize {
        match self {
            Self::Syntax { line, .. }
            | Self::BadType { line, .. }
            | Self::BadName { line, .. }
            | Self::Duplicate { line, .. }
            | Self::BadValue { line, .. }
            | Self::Sections { line, .. } => *line,
        }
    }
}

/// One `---`-separated part of a `.srv`/`.action` file, borrowed from the file text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Section<'a> {
    /// 1-based line number of the section's first line in the file.
    pub first_line: usize,
    /// The section's text, without the separator lines.
    pub text: &'a str,
}

/// Splits a file on lines that are exactly `---` (a trailing `\r` is tolerated).
pub fn sections(text: &str) -> Vec<Section<'_>> {
    let mut out = Vec::new();
    let (mut start, mut first_line, mut pos) = (0, 1, 0);
    for (i, line) in text.split('\n').enumerate() {
        let next = pos + line.len() + 1;
        if line.trim_end_matches('\r') == "---" {
            // Drop the newline that ends the section's last line.
            let end = if pos > start { pos - 1 } else { start };
            out.push(Section {
                first_line,
                text: &text[start..end],
            });
            start = next.min(text.len());
            first_line = i + 2;
        }
        pos = next;
    }
    out.push(Section {
        first_line,
        text: &text[start..],
    });
    out
}

/// Parses a `.msg` file. `ros_name` (e.g. `cell_msgs/msg/Toolpath`) names the message in
/// errors and supplies the package for bare type names.
pub fn parse_message(ros_name: &str, text: &str) -> Result<MessageSpec, ParseError> {
    parse_section(ros_name, ros_name, 1, text)
}

/// Parses a `.srv` file; `ros_name` is e.g. `cell_msgs/srv/Reset`.
pub fn parse_service(ros_name: &str, text: &str) -> Result<ServiceSpec, ParseError> {
    let [request, response] = parse_parts(ros_name, text, ["Request", "Response"])?;
    Ok(ServiceSpec { request, response })
}

/// Parses an `.action` file; `ros_name` is e.g. `cell_msgs/action/PlanHotwire`.
pub fn parse_action(ros_name: &str, text: &str) -> Result<ActionSpec, ParseError> {
    let [goal, result, feedback] = parse_parts(ros_name, text, ["Goal", "Result", "Feedback"])?;
    Ok(ActionSpec {
        goal,
        result,
        feedback,
    })
}

/// Parses the `N` sections of a `.srv`/`.action` file into `<ros_name>_<suffix>` messages.
fn parse_parts<const N: usize>(
    ros_name: &str,
    text: &str,
    suffixes: [&str; N],
) -> Result<[MessageSpec; N], ParseError> {
    let parts = sections(text);
    if parts.len() != N {
        let line = match parts.get(N) {
            Some(extra) => extra.first_line - 1,
            None => text.lines().count().max(1),
        };
        return Err(ParseError::Sections {
            file: ros_name.to_owned(),
            line,
            expected: N,
            found: parts.len(),
        });
    }
    let mut specs = Vec::with_capacity(N);
    for (part, suffix) in parts.iter().zip(suffixes) {
        let name = format!("{ros_name}_{suffix}");
        specs.push(parse_section(&name, ros_name, part.first_line, part.text)?);
    }
    specs.try_into().map_err(|_| ParseError::Sections {
        file: ros_name.to_owned(),
        line: 1,
        expected: N,
        found: parts.len(),
    })
}

/// Parses message text whose first line is line `first_line` of `file`.
pub(crate) fn parse_section(
    ros_name: &str,
    file: &str,
    first_line: usize,
    text: &str,
) -> Result<MessageSpec, ParseError> {
    let package = ros_name.split('/').next().unwrap_or_default();
    let mut spec = MessageSpec {
        name: ros_name.to_owned(),
        fields: Vec::new(),
        constants: Vec::new(),
    };
    for (i, raw) in text.lines().enumerate() {
        let at = LineCtx {
            file,
            line: first_line + i,
        };
        let line = strip_comment(raw).trim();
        if line.is_empty() {
            continue;
        }
        let (ty_text, rest) = line
            .split_once(char::is_whitespace)
            .ok_or_else(|| at.syntax(line))?;
        let rest = rest.trim_start();
        // The name runs up to whitespace or `=`; a following `=` makes the line a constant.
        let name_end = rest
            .find(|c: char| c.is_whitespace() || c == '=')
            .unwrap_or(rest.len());
        let (name, after) = rest.split_at(name_end);
        if name.is_empty() {
            return Err(at.syntax(line));
        }
        let ty = parse_type(ty_text, package).map_err(|reason| at.bad_type(ty_text, reason))?;
        let taken = spec
            .fields
            .iter()
            .map(|f| &f.name)
            .chain(spec.constants.iter().map(|c| &c.name));
        if taken.into_iter().any(|n| n == name) {
            return Err(ParseError::Duplicate {
                file: file.to_owned(),
                line: at.line,
                name: name.to_owned(),
            });
        }
        let after = after.trim_start();
        if let Some(value) = after.strip_prefix('=') {
            let value = value.trim();
            let prim = match (&ty.base, ty.array) {
                (BaseType::Primitive(p), None) => *p,
                _ => return Err(at.bad_type(ty_text, "constants must be single primitives".into())),
            };
            check_name(name, true).map_err(|reason| at.bad_name(name, reason))?;
            let value =
                parse_scalar(prim, value).map_err(|reason| at.bad_value(name, value, reason))?;
            spec.constants.push(Constant {
                name: name.to_owned(),
                ty: prim,
                value,
            });
        } else {
            check_name(name, false).map_err(|reason| at.bad_name(name, reason))?;
            let default = if after.is_empty() {
                None
            } else {
                Some(
                    parse_default(&ty, after)
                        .map_err(|reason| at.bad_value(name, after, reason))?,
                )
            };
            spec.fields.push(Field {
                name: name.to_owned(),
                ty,
                default,
            });
        }
    }
    Ok(spec)
}

/// File and line of the line being parsed, to build errors.
struct LineCtx<'a> {
    file: &'a str,
    line: usize,
}

impl LineCtx<'_> {
    fn syntax(&self, text: &str) -> ParseError {
        ParseError::Syntax {
            file: self.file.to_owned(),
            line: self.line,
            text: text.to_owned(),
        }
    }
    fn bad_type(&self, ty: &str, reason: String) -> ParseError {
        ParseError::BadType {
            file: self.file.to_owned(),
            line: self.line,
            ty: ty.to_owned(),
            reason,
        }
    }
    fn bad_name(&self, name: &str, reason: String) -> ParseError {
        ParseError::BadName {
            file: self.file.to_owned(),
            line: self.line,
            name: name.to_owned(),
            reason,
        }
    }
    fn bad_value(&self, name: &str, value: &str, reason: String) -> ParseError {
        ParseError::BadValue {
            file: self.file.to_owned(),
            line: self.line,
            name: name.to_owned(),
            value: value.to_owned(),
            reason,
        }
    }
}

/// Cuts a line at the first `#` that is not inside a quoted string value.
fn strip_comment(line: &str) -> &str {
    let mut quote = None;
    let mut escaped = false;
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (Some(_), '\\') if !escaped => {
                escaped = true;
                continue;
            }
            (Some(q), c) if c == q && !escaped => quote = None,
            (None, '"' | '\'') => quote = Some(c),
            (None, '#') => return &line[..i],
            _ => {}
        }
        escaped = false;
    }
    line
}

/// Parses a field type such as `float32[]`, `string<=8[<=4]` or `geometry_msgs/Point[3]`.
fn parse_type(text: &str, package: &str) -> Result<FieldType, String> {
    let (base_text, array) = match text.strip_suffix(']') {
        None => (text, None),
        Some(head) => {
            let open = head.rfind('[').ok_or("unmatched `]`")?;
            let inner = &head[open + 1..];
            let array = if inner.is_empty() {
                Array::Unbounded
            } else if let Some(n) = inner.strip_prefix("<=") {
                Array::Bounded(parse_size(n)?)
            } else {
                Array::Fixed(parse_size(inner)?)
            };
            (&head[..open], Some(array))
        }
    };
    if base_text.contains(['[', ']']) {
        return Err("nested arrays are not allowed".into());
    }
    let base = if let Some(p) = Primitive::from_name(base_text) {
        BaseType::Primitive(p)
    } else {
        BaseType::Message(message_name(base_text, package)?)
    };
    Ok(FieldType { base, array })
}

fn parse_size(n: &str) -> Result<usize, String> {
    match n.parse::<usize>() {
        Ok(v) if v > 0 => Ok(v),
        _ => Err(format!("array size `{n}` is not a positive integer")),
    }
}

/// Normalises `Type`, `pkg/Type` or `pkg/msg/Type` to `pkg/msg/Type`.
fn message_name(text: &str, package: &str) -> Result<String, String> {
    let parts: Vec<&str> = text.split('/').collect();
    let (pkg, ty) = match parts.as_slice() {
        [ty] => (package, *ty),
        [pkg, ty] | [pkg, "msg", ty] => (*pkg, *ty),
        _ => return Err("expected a primitive, `Type`, `pkg/Type` or `pkg/msg/Type`".into()),
    };
    let pkg_ok = pkg.starts_with(|c: char| c.is_ascii_lowercase())
        && pkg
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    let ty_ok = ty.starts_with(|c: char| c.is_ascii_uppercase())
        && ty.chars().all(|c| c.is_ascii_alphanumeric());
    if !pkg_ok || !ty_ok {
        return Err("not a primitive, and not a valid `pkg/Type` message name".into());
    }
    Ok(format!("{pkg}/msg/{ty}"))
}

/// ROS 2 rules: fields `[a-z][a-z0-9_]*` without `__` or a trailing `_`; constants `[A-Z][A-Z0-9_]*`.
fn check_name(name: &str, constant: bool) -> Result<(), String> {
    let ok = if constant {
        name.starts_with(|c: char| c.is_ascii_uppercase())
            && name
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
    } else {
        name.starts_with(|c: char| c.is_ascii_lowercase())
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && !name.contains("__")
            && !name.ends_with('_')
    };
    match (ok, constant) {
        (true, _) => Ok(()),
        (false, true) => Err("constant names must match [A-Z][A-Z0-9_]*".into()),
        (false, false) => {
            Err("field names must match [a-z][a-z0-9_]* without `__` or a trailing `_`".into())
        }
    }
}

/// Parses a field default: a scalar, or `[a, b, ...]` for arrays.
fn parse_default(ty: &FieldType, text: &str) -> Result<Value, String> {
    let BaseType::Primitive(prim) = ty.base else {
        return Err("message-typed fields cannot have defaults".into());
    };
    let Some(array) = ty.array else {
        return parse_scalar(prim, text);
    };
    let inner = text
        .strip_prefix('[')
        .and_then(|t| t.strip_suffix(']'))
        .ok_or("array defaults must be written `[a, b, ...]`")?;
    let items = split_list(inner)?;
    let len = items.len();
    match array {
        Array::Fixed(n) if len != n => {
            return Err(format!("{len} elements given, the array has {n}"))
        }
        Array::Bounded(n) if len > n => {
            return Err(format!("{len} elements given, at most {n} allowed"))
        }
        _ => {}
    }
    items
        .into_iter()
        .map(|item| parse_scalar(prim, item))
        .collect::<Result<Vec<_>, _>>()
        .map(Value::Array)
}

/// Splits `a, "b,c", d` on commas outside quotes; an empty list gives no items.
fn split_list(inner: &str) -> Result<Vec<&str>, String> {
    if inner.trim().is_empty() {
        return Ok(Vec::new());
    }
    let (mut items, mut start, mut quote, mut escaped) = (Vec::new(), 0, None, false);
    for (i, c) in inner.char_indices() {
        match (quote, c) {
            (Some(_), '\\') if !escaped => {
                escaped = true;
                continue;
            }
            (Some(q), c) if c == q && !escaped => quote = None,
            (None, '"' | '\'') => quote = Some(c),
            (None, ',') => {
                items.push(inner[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
        escaped = false;
    }
    if quote.is_some() {
        return Err("unterminated quote".into());
    }
    items.push(inner[start..].trim());
    if items.iter().any(|s| s.is_empty()) {
        return Err("empty list element".into());
    }
    Ok(items)
}

/// Parses one value of a primitive type.
fn parse_scalar(prim: Primitive, text: &str) -> Result<Value, String> {
    use Primitive::*;
    let int = |min: i128, max: i128| -> Result<Value, std::string::String> {
        match text.parse::<i128>() {
            Ok(v) if (min..=max).contains(&v) => Ok(if v < 0 {
                Value::from(v as i64)
            } else {
                Value::from(v as u64)
            }),
            Ok(_) => Err(format!("out of range {min}..={max}")),
            Err(_) => Err("not an integer".into()),
        }
    };
    let float = || text.parse::<f64>().map_err(|_| "not a number".to_owned());
    match prim {
        Bool => match text.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(Value::Bool(true)),
            "false" | "0" => Ok(Value::Bool(false)),
            _ => Err("expected true, false, 1 or 0".into()),
        },
        Byte | Char | Uint8 => int(0, u8::MAX.into()),
        Int8 => int(i8::MIN.into(), i8::MAX.into()),
        Int16 => int(i16::MIN.into(), i16::MAX.into()),
        Uint16 => int(0, u16::MAX.into()),
        Int32 => int(i32::MIN.into(), i32::MAX.into()),
        Uint32 => int(0, u32::MAX.into()),
        Int64 => int(i64::MIN.into(), i64::MAX.into()),
        Uint64 => int(0, u64::MAX.into()),
        // Narrow through f32 so the value equals what serde_json makes of an f32 field.
        Float32 => Ok(Value::from(float()? as f32 as f64)),
        Float64 => Ok(Value::from(float()?)),
        String { max_len } | WString { max_len } => {
            let s = unquote(text)?;
            match max_len {
                Some(n) if s.chars().count() > n => Err(format!("longer than the bound {n}")),
                _ => Ok(Value::String(s)),
            }
        }
    }
}

/// Strips matching quotes and resolves backslash escapes; unquoted text is taken as is.
fn unquote(text: &str) -> Result<String, String> {
    let Some(q) = text.chars().next().filter(|c| *c == '"' || *c == '\'') else {
        return Ok(text.to_owned());
    };
    let inner = text[1..]
        .strip_suffix(q)
        .filter(|_| text.len() >= 2)
        .ok_or("unterminated quote")?;
    let (mut out, mut escaped) = (String::new(), false);
    for c in inner.chars() {
        if escaped || c != '\\' {
            out.push(c);
            escaped = false;
        } else {
            escaped = true;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn field<'a>(spec: &'a MessageSpec, name: &str) -> &'a Field {
        spec.fields
            .iter()
            .find(|f| f.name == name)
            .expect("field present")
    }

    #[test]
    fn parses_types_constants_and_defaults() {
        let text = "# header comment\n\
            uint8 KIND_CUT=0 # trailing comment\n\
            string GREETING = \"hi # not a comment\"\n\
            \n\
            float64 w 1\n\
            string<=8 label 'x'\n\
            int32[] xs [1, -2]\n\
            float32[<=3] ys\n\
            bool[2] flags [true, false]\n\
            Point p\n\
            geometry_msgs/Vector3 v\n\
            std_msgs/msg/Header h\n";
        let spec = parse_message("geometry_msgs/msg/Test", text).expect("parses");
        assert_eq!(spec.constants[0].value, json!(0));
        assert_eq!(spec.constants[1].value, json!("hi # not a comment"));
        assert_eq!(field(&spec, "w").default, Some(json!(1.0)));
        assert_eq!(
            field(&spec, "label").ty.base,
            BaseType::Primitive(Primitive::String { max_len: Some(8) })
        );
        assert_eq!(field(&spec, "xs").default, Some(json!([1, -2])));
        assert_eq!(field(&spec, "ys").ty.array, Some(Array::Bounded(3)));
        assert_eq!(field(&spec, "flags").ty.array, Some(Array::Fixed(2)));
        assert_eq!(
            field(&spec, "p").ty.base,
            BaseType::Message("geometry_msgs/msg/Point".into())
        );
        assert_eq!(
            field(&spec, "v").ty.base,
            BaseType::Message("geometry_msgs/msg/Vector3".into())
        );
        assert_eq!(
            field(&spec, "h").ty.base,
            BaseType::Message("std_msgs/msg/Header".into())
        );
        assert_eq!(
            spec.dependencies(),
            [
                "geometry_msgs/msg/Point",
                "geometry_msgs/msg/Vector3",
                "std_msgs/msg/Header"
            ]
        );
    }

    #[test]
    fn errors_name_file_and_line() {
        let cases = [
            ("uint8 a\nfloat65 b\n", 2, "float65"),
            ("uint8 a\n\n# c\nuint8\n", 4, "expected `TYPE NAME`"),
            ("uint8 Bad\n", 1, "field names"),
            ("uint8 a\nuint8 a\n", 2, "already used"),
            ("uint8 X=300\n", 1, "out of range"),
            ("uint8[] X=1\n", 1, "single primitives"),
            ("Point p 3\n", 1, "defaults"),
            ("int32[2] xs [1]\n", 1, "array has 2"),
            ("string s \"open\n", 1, "unterminated"),
            ("uint8[0] z\n", 1, "positive"),
            ("a/b/c/D d\n", 1, "pkg/Type"),
        ];
        for (text, line, needle) in cases {
            let err = parse_message("pkg/msg/M", text).expect_err(text);
            assert_eq!((err.file(), err.line()), ("pkg/msg/M", line), "{err}");
            let msg = err.to_string();
            assert!(
                msg.starts_with(&format!("pkg/msg/M:{line}:")) && msg.contains(needle),
                "{msg}"
            );
        }
    }

    #[test]
    fn action_sections_and_line_numbers() {
        let text = "int32 a\n---\nint32 b\n---\n# feedback\nbad line here\n";
        let err = parse_action("pkg/action/A", text).expect_err("bad feedback");
        assert_eq!((err.file(), err.line()), ("pkg/action/A", 6));

        let ok = parse_action("pkg/action/A", "int32 a\n---\n---\nint32 c\n").expect("parses");
        assert_eq!(ok.goal.name, "pkg/action/A_Goal");
        assert!(ok.result.fields.is_empty());
        assert_eq!(ok.feedback.fields[0].name, "c");

        let err = parse_action("pkg/action/A", "int32 a\n---\nint32 b\n").expect_err("2 sections");
        assert!(
            matches!(
                err,
                ParseError::Sections {
                    expected: 3,
                    found: 2,
                    ..
                }
            ),
            "{err}"
        );
        let err = parse_service("pkg/srv/S", "---\n---\n").expect_err("3 sections");
        assert!(
            matches!(
                err,
                ParseError::Sections {
                    line: 2,
                    found: 3,
                    ..
                }
            ),
            "{err}"
        );
        let srv = parse_service("pkg/srv/S", "int8 a\n---\nint8 b").expect("parses");
        assert_eq!(srv.response.name, "pkg/srv/S_Response");
    }

    #[test]
    fn sections_borrow_exact_text() {
        let s = sections("a\n---\nb\nc\n---\n");
        assert_eq!(
            s.iter().map(|s| (s.first_line, s.text)).collect::<Vec<_>>(),
            [(1, "a"), (3, "b\nc"), (6, "")]
        );
        assert_eq!(sections("---")[0].text, "");
    }
}
