//! Error messages without the file's contents, for callers who may not read the file.
//!
//! serde quotes what it found: `invalid type: string "root:x:0:0:…", expected struct M`,
//! `unknown field `root``, `invalid value: integer `7``; so do some readers (`coordinate
//! `abc` is not a number`). A node that reads a file a remote caller named answers with the
//! place (file, line, column, the field path of our own structs) and what kind of problem it
//! is, never a value from the file: [`without_content`] blanks every quoted value, and
//! [`ParseError::without_content`] also drops field-path segments that are not ours.

use crate::ParseError;

/// What a blanked value reads as.
pub const BLANKED: &str = "…";

/// `message` with the inside of every quoted value (`"…"`, `'…'`, `` `…` ``) replaced by
/// [`BLANKED`], except what the reader says it expected (after `, expected `, which comes from
/// our types) and a field path written ``field `a.b[2].c` `` (identifiers, dots and indices
/// only; none in a message about an unknown field, whose path ends with the file's key).
///
/// ```
/// let m = cell_config::without_content(
///     "m.yaml:1: invalid type: string \"root:x:0:0:root\", expected struct MachineProfile",
/// );
/// assert_eq!(m, "m.yaml:1: invalid type: string \"…\", expected struct MachineProfile");
/// assert_eq!(
///     cell_config::without_content("p.yaml: field `axes.X`: invalid type: string \"x\", expected f64"),
///     "p.yaml: field `axes.X`: invalid type: string \"…\", expected f64"
/// );
/// assert_eq!(
///     cell_config::without_content("p.yaml: field `root`: unknown field `root`, expected `a`"),
///     "p.yaml: field `…`: unknown field `…`, expected `a`"
/// );
/// ```
pub fn without_content(message: &str) -> String {
    let about_unknown_key = message.contains("unknown field `");
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(open) = rest.find(['"', '\'', '`']) {
        let before = &rest[..open];
        out.push_str(before);
        // The current sentence (since the last `: `) says what was expected: ours.
        let sentence = out.rsplit(": ").next().unwrap_or(&out);
        if sentence.contains(", expected ") {
            // Our types' own words from here on, up to the next sentence of the message.
            let end = rest[open..].find(": ").map_or(rest.len(), |i| open + i);
            out.push_str(&rest[open..end]);
            rest = &rest[end..];
            continue;
        }
        let quote = rest[open..].chars().next().unwrap_or('"');
        let inner_start = open + quote.len_utf8();
        // An apostrophe inside a word (`can't`) opens nothing.
        let is_apostrophe = quote == '\''
            && before
                .chars()
                .next_back()
                .is_some_and(char::is_alphanumeric);
        let Some(len) = rest[inner_start..].find(quote).filter(|_| !is_apostrophe) else {
            out.push(quote);
            rest = &rest[inner_start..];
            continue;
        };
        let inner = &rest[inner_start..inner_start + len];
        let keep = quote == '`'
            && before.ends_with("field ")
            && !about_unknown_key
            && is_field_path(inner);
        out.push(quote);
        out.push_str(if keep { inner } else { BLANKED });
        out.push(quote);
        rest = &rest[inner_start + len + quote.len_utf8()..];
    }
    out.push_str(rest);
    out
}

/// A dotted path of identifiers and `[n]` indices, as serde_path_to_error writes one of our
/// structs' fields.
fn is_field_path(path: &str) -> bool {
    !path.is_empty() && path.split('.').all(is_field_segment)
}

fn is_field_segment(segment: &str) -> bool {
    let name = segment.split('[').next().unwrap_or("");
    let indices = &segment[name.len()..];
    let name_ok = name.is_empty() && !indices.is_empty()
        || name.len() <= 64
            && name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    name_ok
        && indices.split_inclusive(']').all(|i| {
            i.len() > 2
                && i.starts_with('[')
                && i.ends_with(']')
                && i[1..i.len() - 1].bytes().all(|b| b.is_ascii_digit())
        })
}

impl ParseError {
    /// The same error without anything read from the file: quoted values blanked (see
    /// [`without_content`]), and of the field path only the part that names our own fields
    /// (an unknown key, the last segment of an `unknown field` error, and a map key that is not
    /// an identifier are cut off, ending the path at the section that holds them).
    ///
    /// ```
    /// #[derive(Debug, serde::Deserialize)]
    /// #[serde(deny_unknown_fields)]
    /// struct M { name: String }
    /// let e = cell_config::from_yaml_str::<M>("root:x:0:0:root:/root:/bin/bash\n", "p").unwrap_err();
    /// assert!(e.to_string().contains("root:x"), "{e}");
    /// let safe = e.without_content().to_string();
    /// assert!(!safe.contains("root"), "{safe}");
    /// assert!(safe.contains("invalid type: string \"…\", expected struct M"), "{safe}");
    /// ```
    #[must_use]
    pub fn without_content(&self) -> ParseError {
        let unknown_key = self.message.starts_with("unknown field")
            || self.message.starts_with("unknown variant");
        let field = self.field.as_deref().and_then(|path| {
            let mut segments: Vec<&str> = path.split('.').collect();
            if unknown_key {
                segments.pop();
            }
            let ours = segments
                .iter()
                .position(|s| !is_field_segment(s))
                .unwrap_or(segments.len());
            segments.truncate(ours);
            (!segments.is_empty()).then(|| segments.join("."))
        });
        ParseError {
            file: self.file.clone(),
            line: self.line,
            column: self.column,
            field,
            message: without_content(&self.message),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_values_are_blanked_and_expectations_kept() {
        assert_eq!(
            without_content("invalid value: integer `7`, expected one of `a`, `b`"),
            "invalid value: integer `…`, expected one of `a`, `b`"
        );
        assert_eq!(
            without_content("a.dat:3: upper coordinate `root:x:0` is not a number"),
            "a.dat:3: upper coordinate `…` is not a number"
        );
        assert_eq!(
            without_content("x: 'secret' and \"more\" can't hide"),
            "x: '…' and \"…\" can't hide"
        );
        // An unclosed quote keeps the rest, which holds no closed value to blank.
        assert_eq!(without_content("odd \"tail"), "odd \"tail");
        // After the expectation, a new sentence may quote content again.
        assert_eq!(
            without_content("expected `a`: field `b`: `c`"),
            "expected `…`: field `b`: `…`"
        );
        assert_eq!(
            without_content("x, expected `a`: then `c`"),
            "x, expected `a`: then `…`"
        );
    }

    #[test]
    fn field_paths_keep_only_our_fields() {
        assert!(is_field_path("parts[2].outer"));
        assert!(is_field_path("gcode.program_start[1]"));
        assert!(is_field_path("[0]"));
        assert!(!is_field_path("root:x:0"));
        assert!(!is_field_path("a b"));
        assert!(!is_field_path("a[x]"));

        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Inner {
            #[allow(dead_code)]
            mm: f64,
        }
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Outer {
            #[allow(dead_code)]
            inner: Inner,
        }
        let e = crate::from_yaml_str::<Outer>("inner:\n  daemon: 1\n", "o.yaml").unwrap_err();
        assert_eq!(e.field.as_deref(), Some("inner.daemon"));
        let safe = e.without_content();
        assert_eq!(safe.field.as_deref(), Some("inner"));
        assert_eq!((safe.line, safe.column), (e.line, e.column));
        assert!(!safe.to_string().contains("daemon"), "{safe}");
        assert!(
            safe.to_string()
                .starts_with("o.yaml:2: field `inner`: unknown field `…`, expected `mm`"),
            "{safe}"
        );

        let e = crate::from_yaml_str::<Outer>("inner: {mm: \"s3cret\"}\n", "o.yaml").unwrap_err();
        let safe = e.without_content().to_string();
        assert!(
            safe.contains("field `inner.mm`: invalid type: string \"…\""),
            "{safe}"
        );
        assert!(!safe.contains("s3cret"), "{safe}");
    }
}
