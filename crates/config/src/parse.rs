//! Text into a serde struct, with the file, line, column and field of the first error.

use serde::de::DeserializeOwned;

use crate::Place;

/// A configuration text that does not parse or does not fit its struct: YAML or JSON syntax,
/// an unknown or missing key, a value of the wrong type or an unknown variant.
///
/// Written as [`Place`] then the parser's message (without the parser's own path prefix and
/// `at line L column C` suffix, which are the fields here):
/// `r1.yaml:5: field `timeouts.request`: unknown field `request`, expected …`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{message}", Place { file, line: *line, field: field.as_deref() })]
pub struct ParseError {
    /// The file, or a name for text that has none.
    pub file: String,
    /// 1-based line, when the parser knows it (32 bits keep the errors that carry this small).
    pub line: Option<u32>,
    /// 1-based column, when the parser knows it.
    pub column: Option<u32>,
    /// Dotted path of the offending field (`cost.wire_sek_kg`, `parts[2].outer`; for an
    /// unknown key, the key itself); `None` when the problem is the document itself.
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
}

/// Parses YAML `text` into `T`; `file` names it in errors.
///
/// # Errors
/// [`ParseError`] with the line, column and field path of the first problem.
pub fn from_yaml_str<T: DeserializeOwned>(text: &str, file: &str) -> Result<T, ParseError> {
    let de = serde_norway::Deserializer::from_str(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = field_path(e.path());
        let inner = e.into_inner();
        let location = inner.location();
        ParseError {
            file: file.into(),
            line: location.as_ref().and_then(|l| position(l.line())),
            column: location.as_ref().and_then(|l| position(l.column())),
            field,
            message: yaml_message(inner.to_string()),
        }
    })
}

/// Parses JSON `text` into `T`; `file` names it in errors.
///
/// # Errors
/// [`ParseError`] with the line, column and field path of the first problem.
pub fn from_json_str<T: DeserializeOwned>(text: &str, file: &str) -> Result<T, ParseError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = field_path(e.path());
        let inner = e.into_inner();
        ParseError {
            file: file.into(),
            line: position(inner.line()),
            column: position(inner.column()),
            field,
            message: without_location(inner.to_string()),
        }
    })
}

/// A 1-based line or column; the parsers say 0 when they have none.
fn position(n: usize) -> Option<u32> {
    u32::try_from(n).ok().filter(|&n| n > 0)
}

/// serde_path_to_error's path, `None` for the document itself (written `.`).
fn field_path(path: &serde_path_to_error::Path) -> Option<String> {
    let path = path.to_string();
    (path != ".").then_some(path)
}

/// serde_norway's message without its own path prefix (`hotwire: unknown field …`) and
/// location suffix: the error carries both separately.
fn yaml_message(message: String) -> String {
    let message = without_location(message);
    match message.split_once(": ") {
        // A path has no spaces; a message head such as `invalid type` does.
        Some((head, rest)) if !head.is_empty() && !head.contains(' ') => rest.to_owned(),
        _ => message,
    }
}

/// `message` without a trailing ` at line L column C`.
fn without_location(mut message: String) -> String {
    if let Some(i) = message.rfind(" at line ") {
        let tail = &message[i + " at line ".len()..];
        let is_position = tail
            .split_once(" column ")
            .is_some_and(|(l, c)| is_number(l) && is_number(c));
        if is_position {
            message.truncate(i);
        }
    }
    message
}

fn is_number(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Timeouts {
        request_s: f64,
    }

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Config {
        id: String,
        #[serde(default)]
        parts: Vec<Timeouts>,
        timeouts: Timeouts,
    }

    #[test]
    fn yaml_errors_name_file_line_column_and_field() {
        let e =
            from_yaml_str::<Config>("id: r1\ntimeouts: {request: 10}\n", "r1.yaml").unwrap_err();
        assert_eq!(e.file, "r1.yaml");
        assert_eq!((e.line, e.column), (Some(2), Some(12)));
        assert_eq!(e.field.as_deref(), Some("timeouts.request"));
        assert!(
            e.to_string()
                .starts_with("r1.yaml:2: field `timeouts.request`: unknown field `request`"),
            "{e}"
        );
        assert!(!e.to_string().contains("at line"), "{e}");

        let e = from_yaml_str::<Config>(
            "id: r1\ntimeouts: {request_s: 1}\nparts:\n  - request_s: x\n",
            "r1.yaml",
        )
        .unwrap_err();
        assert_eq!(e.field.as_deref(), Some("parts[0].request_s"));
        assert_eq!(e.line, Some(4));
        assert!(e.message.starts_with("invalid type: string \"x\""), "{e}");
    }

    #[test]
    fn unknown_keys_and_syntax_errors_name_their_place() {
        let e = from_yaml_str::<Config>("id: r1\nbogus: 1\ntimeouts: {request_s: 1}\n", "c.yaml")
            .unwrap_err();
        // serde_path_to_error ends the path with the unknown key itself.
        assert_eq!((e.line, e.field.as_deref()), (Some(2), Some("bogus")));
        assert!(
            e.to_string()
                .starts_with("c.yaml:2: field `bogus`: unknown field `bogus`"),
            "{e}"
        );

        // A syntax error is reported where the scanner stopped, inside the field it was reading.
        let e = from_yaml_str::<Config>("id: [\n", "c.yaml").unwrap_err();
        assert_eq!(e.field.as_deref(), Some("id"));
        assert!(e.line.is_some(), "{e}");

        let ok: Config = from_yaml_str("id: r1\ntimeouts: {request_s: 1.5}\n", "c.yaml").unwrap();
        assert_eq!(ok.timeouts.request_s, 1.5);
    }

    #[test]
    fn json_errors_name_file_line_column_and_field() {
        let text = "{\"id\": \"a\",\n \"timeouts\": {\"request_s\": \"slow\"}}";
        let e = from_json_str::<Config>(text, "<layout_json>").unwrap_err();
        assert_eq!(e.field.as_deref(), Some("timeouts.request_s"));
        assert_eq!(e.line, Some(2));
        assert!(e.column.is_some());
        assert!(
            e.to_string().starts_with(
                "<layout_json>:2: field `timeouts.request_s`: invalid type: string \"slow\""
            ),
            "{e}"
        );
        assert!(!e.message.contains("at line"), "{e}");
    }

    #[test]
    fn only_a_trailing_position_is_cut() {
        assert_eq!(without_location("bad at line 3 column 4".into()), "bad");
        assert_eq!(
            without_location("a plate at line up column 4".into()),
            "a plate at line up column 4"
        );
        assert_eq!(
            yaml_message("foams.xps: unknown field `x`".into()),
            "unknown field `x`"
        );
        assert_eq!(
            yaml_message("invalid type: map".into()),
            "invalid type: map"
        );
    }
}
