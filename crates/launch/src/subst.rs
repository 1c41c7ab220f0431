//! Substitutions in launch file strings: `$(var NAME)`, `$(env NAME)`,
//! `$(env NAME DEFAULT)`, `$(optenv NAME [DEFAULT])` and `$(dirname)`.

use std::collections::BTreeMap;
use std::path::Path;

/// The names of the substitutions we know, for error messages.
const KNOWN: &str = "var, env, optenv, dirname";

/// What substitutions can see.
pub(crate) struct Scope<'a> {
    /// Launch configurations: `arg` values and `let` values defined so far.
    pub vars: &'a BTreeMap<String, String>,
    /// The directory of the launch file, for `$(dirname)`.
    pub dir: &'a Path,
}

/// True if `text` contains something that looks like a substitution.
pub(crate) fn has_substitution(text: &str) -> bool {
    text.contains("$(")
}

/// Replaces every substitution in `text`. The error is a message without
/// location; the caller adds file and key.
pub(crate) fn substitute(text: &str, scope: &Scope<'_>) -> Result<String, String> {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("$(") {
        out.push_str(&rest[..start]);
        let body_start = start + 2;
        let len = body_len(&rest[body_start..])
            .map_err(|why| format!("{why} in substitution starting at {:?}", &rest[start..]))?;
        let body = &rest[body_start..body_start + len];
        out.push_str(&evaluate(body, scope)?);
        rest = &rest[body_start + len + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Length of a substitution body up to (not including) its closing `)`,
/// honouring quotes.
fn body_len(body: &str) -> Result<usize, &'static str> {
    let mut quote: Option<char> = None;
    let mut prev = '\0';
    for (i, c) in body.char_indices() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None => match c {
                '\'' | '"' => quote = Some(c),
                ')' => return Ok(i),
                '(' if prev == '$' => return Err("nested substitutions are not supported"),
                _ => {}
            },
        }
        prev = c;
    }
    Err(if quote.is_some() {
        "unterminated quote"
    } else {
        "missing closing `)`"
    })
}

/// Evaluates one substitution body such as `var name` or `env HOME /root`.
fn evaluate(body: &str, scope: &Scope<'_>) -> Result<String, String> {
    let words = shell_words::split(body)
        .map_err(|e| format!("cannot split substitution $({body}): {e}"))?;
    let Some((kind, args)) = words.split_first() else {
        return Err(format!("empty substitution $({body}) (known: {KNOWN})"));
    };
    match (kind.as_str(), args) {
        ("var", [name]) => scope.vars.get(name).cloned().ok_or_else(|| {
            let known: Vec<&str> = scope.vars.keys().map(String::as_str).collect();
            format!(
                "undefined launch argument {name:?} in $({body}) (defined so far: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )
        }),
        ("env", [name]) => std::env::var(name).map_err(|_| {
            format!(
                "environment variable {name:?} is not set (in $({body}); \
                 give a default with $(env {name} DEFAULT))"
            )
        }),
        ("env" | "optenv", [name, default]) => {
            Ok(std::env::var(name).unwrap_or_else(|_| default.clone()))
        }
        ("optenv", [name]) => Ok(std::env::var(name).unwrap_or_default()),
        ("dirname", []) => Ok(scope.dir.display().to_string()),
        ("var", _) => Err(format!("$({body}): `var` takes one name")),
        ("env", _) => Err(format!(
            "$({body}): `env` takes a name and an optional default"
        )),
        ("optenv", _) => Err(format!(
            "$({body}): `optenv` takes a name and an optional default"
        )),
        ("dirname", _) => Err(format!("$({body}): `dirname` takes no arguments")),
        (other, _) => Err(format!(
            "unknown substitution {other:?} in $({body}) (known: {KNOWN})"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(text: &str) -> Result<String, String> {
        let mut vars = BTreeMap::new();
        vars.insert("cfg".to_string(), "config".to_string());
        vars.insert("two words".to_string(), "x".to_string());
        substitute(
            text,
            &Scope {
                vars: &vars,
                dir: Path::new("/launch/dir"),
            },
        )
    }

    #[test]
    fn plain_text_is_unchanged() {
        assert_eq!(run("a $ b (c)").unwrap(), "a $ b (c)");
    }

    #[test]
    fn var_env_optenv_dirname() {
        assert_eq!(run("$(var cfg)/m.yaml").unwrap(), "config/m.yaml");
        assert_eq!(run("<$(var 'two words')>").unwrap(), "<x>");
        let path = std::env::var("PATH").unwrap();
        assert_eq!(run("$(env PATH)").unwrap(), path);
        assert_eq!(
            run("$(env CELL_LAUNCH_SURELY_UNSET_42 'fall back')").unwrap(),
            "fall back"
        );
        assert_eq!(
            run("[$(optenv CELL_LAUNCH_SURELY_UNSET_42)]").unwrap(),
            "[]"
        );
        assert_eq!(run("$(dirname)/x").unwrap(), "/launch/dir/x");
    }

    #[test]
    fn errors_say_what_is_wrong() {
        let e = run("$(var nope)").unwrap_err();
        assert!(e.contains("undefined launch argument \"nope\""), "{e}");
        assert!(e.contains("cfg"), "{e}");
        let e = run("$(find-pkg-share cellsuite)").unwrap_err();
        assert!(e.contains("unknown substitution \"find-pkg-share\""), "{e}");
        let e = run("$(env CELL_LAUNCH_SURELY_UNSET_42)").unwrap_err();
        assert!(e.contains("is not set"), "{e}");
        let e = run("$(var cfg").unwrap_err();
        assert!(e.contains("missing closing"), "{e}");
        let e = run("$(var $(var cfg))").unwrap_err();
        assert!(e.contains("nested"), "{e}");
        let e = run("$()").unwrap_err();
        assert!(e.contains("empty substitution"), "{e}");
        let e = run("$(var a b)").unwrap_err();
        assert!(e.contains("takes one name"), "{e}");
    }
}
