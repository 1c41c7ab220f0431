//! Parameter values: what a launch file may give a node with
//! `param: [{name: ..., value: ...}]`, and how it is written on a command
//! line (`-p NAME:=VALUE`).

use std::fmt;

use serde_norway::Value;

/// The value of one node parameter, as ROS 2 types them: a bool, a 64-bit
/// integer, a double, a string, or a list of one of those.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// `true` / `false`.
    Bool(bool),
    /// A 64-bit signed integer.
    Int(i64),
    /// A double.
    Float(f64),
    /// A string.
    String(String),
    /// A list of scalars, all of the same kind (an empty list is allowed).
    List(Vec<ParamValue>),
}

impl ParamValue {
    /// Converts a YAML value. Only scalars and flat, homogeneous lists of
    /// scalars are parameter values; the error says what else was found.
    pub(crate) fn from_yaml(value: &Value) -> Result<Self, String> {
        match value {
            Value::Sequence(items) => {
                let mut list = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    if matches!(item, Value::Sequence(_)) {
                        return Err(format!(
                            "item [{i}] is a list; lists of lists are not supported"
                        ));
                    }
                    let item = Self::from_yaml(item).map_err(|e| format!("item [{i}]: {e}"))?;
                    if let Some(first) = list.first() {
                        if !same_kind(first, &item) {
                            return Err(format!(
                                "item [{i}] is {} but item [0] is {}; list items must all have one type",
                                item.kind(),
                                kind_of(first)
                            ));
                        }
                    }
                    list.push(item);
                }
                Ok(Self::List(list))
            }
            Value::Bool(b) => Ok(Self::Bool(*b)),
            Value::Number(n) => {
                if let Some(i) = n.as_i64() {
                    Ok(Self::Int(i))
                } else if n.is_u64() {
                    Err(format!("integer {n} does not fit in 64 signed bits"))
                } else {
                    n.as_f64()
                        .map(Self::Float)
                        .ok_or_else(|| format!("number {n} is not supported"))
                }
            }
            Value::String(s) => Ok(Self::String(s.clone())),
            Value::Null => Err("null is not a parameter value".to_string()),
            Value::Mapping(_) => Err(
                "a mapping is not a parameter value (put nested parameters in a params file)"
                    .to_string(),
            ),
            Value::Tagged(t) => Err(format!("tagged value {} is not a parameter value", t.tag)),
        }
    }

    /// What kind of value this is, for messages: `bool`, `integer`, ...
    pub fn kind(&self) -> &'static str {
        kind_of(self)
    }

    /// The value as YAML text that reads back as the same value: a plain or
    /// quoted scalar, or a flow list such as `[a, '42', b]`.
    pub fn to_yaml(&self) -> String {
        let mut out = String::new();
        self.write_yaml(&mut out);
        out
    }

    fn write_yaml(&self, out: &mut String) {
        match self {
            Self::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
            Self::Int(i) => out.push_str(&i.to_string()),
            Self::Float(f) => out.push_str(&float_yaml(*f)),
            Self::String(s) => write_string(s, out),
            Self::List(items) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    item.write_yaml(out);
                }
                out.push(']');
            }
        }
    }
}

impl fmt::Display for ParamValue {
    /// Same as [`ParamValue::to_yaml`].
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_yaml())
    }
}

fn kind_of(v: &ParamValue) -> &'static str {
    match v {
        ParamValue::Bool(_) => "bool",
        ParamValue::Int(_) => "integer",
        ParamValue::Float(_) => "float",
        ParamValue::String(_) => "string",
        ParamValue::List(_) => "list",
    }
}

fn same_kind(a: &ParamValue, b: &ParamValue) -> bool {
    std::mem::discriminant(a) == std::mem::discriminant(b)
}

/// A float as YAML that YAML 1.1 and 1.2 parsers (and `strtod`) all read as
/// this float: always a `.` in the mantissa and a signed exponent.
fn float_yaml(f: f64) -> String {
    if f.is_nan() {
        return ".nan".to_string();
    }
    if f.is_infinite() {
        return if f > 0.0 { ".inf" } else { "-.inf" }.to_string();
    }
    // `{:?}` is the shortest text that reads back exactly: `2.5`, `1.0`,
    // `1e20`, `1.5e-7`.
    let text = format!("{f:?}");
    match text.split_once('e') {
        None => text,
        Some((mantissa, exponent)) => {
            let dot = if mantissa.contains('.') { "" } else { ".0" };
            let sign = if exponent.starts_with('-') { "" } else { "+" };
            format!("{mantissa}{dot}e{sign}{exponent}")
        }
    }
}

/// Words that some YAML parser (1.1 style, as ROS 2's `rcl` uses) reads as a
/// bool or null, so they must be quoted to stay strings.
const SPECIAL_WORDS: &[&str] = &[
    "y", "n", "yes", "no", "true", "false", "on", "off", "null", "none", "~",
];

fn write_string(s: &str, out: &mut String) {
    if is_plain_safe(s) {
        out.push_str(s);
    } else if s.chars().any(needs_escape) {
        write_double_quoted(s, out);
    } else {
        out.push('\'');
        out.push_str(&s.replace('\'', "''"));
        out.push('\'');
    }
}

/// A string can go unquoted if it is made of harmless characters, starts
/// like a word or a path, is no special word, and reads back as itself.
fn is_plain_safe(s: &str) -> bool {
    let Some(first) = s.chars().next() else {
        return false;
    };
    (first.is_ascii_alphabetic() || first == '/' || first == '_')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '/' | '-'))
        && !SPECIAL_WORDS.contains(&s.to_ascii_lowercase().as_str())
        && matches!(serde_norway::from_str::<Value>(s), Ok(Value::String(back)) if back == s)
}

/// Characters that cannot appear raw in a single-quoted YAML scalar.
fn needs_escape(c: char) -> bool {
    c.is_control() || matches!(c, '\u{2028}' | '\u{2029}' | '\u{feff}')
}

fn write_double_quoted(s: &str, out: &mut String) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if needs_escape(c) => out.push_str(&format!("\\u{:04X}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
}

#[cfg(test)]
mod tests {
    use super::*;

    fn back(v: &ParamValue) -> ParamValue {
        let text = v.to_yaml();
        let yaml: Value = serde_norway::from_str(&text).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        ParamValue::from_yaml(&yaml).unwrap_or_else(|e| panic!("{text:?}: {e}"))
    }

    fn s(text: &str) -> ParamValue {
        ParamValue::String(text.to_string())
    }

    #[test]
    fn renders_like_ros() {
        assert_eq!(ParamValue::Float(2.5).to_yaml(), "2.5");
        assert_eq!(ParamValue::Float(1.0).to_yaml(), "1.0");
        assert_eq!(ParamValue::Float(1e20).to_yaml(), "1.0e+20");
        assert_eq!(ParamValue::Float(-1.5e-7).to_yaml(), "-1.5e-7");
        assert_eq!(ParamValue::Int(1).to_yaml(), "1");
        assert_eq!(ParamValue::Bool(true).to_yaml(), "true");
        assert_eq!(ParamValue::List(vec![s("a"), s("b")]).to_yaml(), "[a, b]");
        assert_eq!(s("42").to_yaml(), "'42'");
        assert_eq!(s("yes").to_yaml(), "'yes'");
        assert_eq!(s("it's").to_yaml(), "'it''s'");
        assert_eq!(s("/plan/toolpath").to_yaml(), "/plan/toolpath");
        assert_eq!(s("").to_yaml(), "''");
        assert_eq!(s("a\nb").to_yaml(), "\"a\\nb\"");
    }

    #[test]
    fn every_value_reads_back_as_itself() {
        let values = [
            ParamValue::Bool(false),
            ParamValue::Int(i64::MIN),
            ParamValue::Int(i64::MAX),
            ParamValue::Float(0.1),
            ParamValue::Float(-0.0),
            ParamValue::Float(1e300),
            ParamValue::Float(5e-324),
            ParamValue::Float(f64::INFINITY),
            ParamValue::Float(f64::NEG_INFINITY),
            ParamValue::Float(3.0),
            s("plain"),
            s("42"),
            s("-7"),
            s("2.5"),
            s("1e3"),
            s("0x1F"),
            s(".inf"),
            s("true"),
            s("On"),
            s("NO"),
            s("null"),
            s("~"),
            s(""),
            s(" padded "),
            s("a: b"),
            s("- dash"),
            s("#hash"),
            s("a, b"),
            s("[x]"),
            s("{y}"),
            s("'quoted'"),
            s("\"dq\""),
            s("back\\slash"),
            s("tab\there"),
            s("line\nbreak\r\n"),
            s("bell\u{7}del\u{7f}"),
            s("ünïcødé ✓"),
            s("*alias"),
            s("&anchor"),
            s("!tag"),
            s("%directive"),
            s("@at"),
            s("`tick`"),
            s("|"),
            s(">"),
            s("?"),
            ParamValue::List(vec![]),
            ParamValue::List(vec![s("a"), s("42"), s("b, c"), s("")]),
            ParamValue::List(vec![ParamValue::Int(1), ParamValue::Int(-2)]),
            ParamValue::List(vec![ParamValue::Float(1.0), ParamValue::Float(0.5)]),
            ParamValue::List(vec![ParamValue::Bool(true), ParamValue::Bool(false)]),
        ];
        for v in &values {
            assert_eq!(&back(v), v, "rendered as {:?}", v.to_yaml());
        }
        match back(&ParamValue::Float(f64::NAN)) {
            ParamValue::Float(f) => assert!(f.is_nan()),
            other => panic!("NaN came back as {other:?}"),
        }
    }

    #[test]
    fn rejects_what_ros_cannot_hold() {
        let v = |t: &str| ParamValue::from_yaml(&serde_norway::from_str(t).unwrap());
        assert!(v("[1, a]").unwrap_err().contains("one type"));
        assert!(v("[[1]]").unwrap_err().contains("lists of lists"));
        assert!(v("{a: 1}").unwrap_err().contains("mapping"));
        assert!(v("null").unwrap_err().contains("null"));
        assert!(v("18446744073709551615")
            .unwrap_err()
            .contains("64 signed bits"));
    }
}
