//! Program start and end templates of a G-code profile: placeholders and forbidden modal words.

/// Placeholders a start or end template may use.
pub const TEMPLATE_PLACEHOLDERS: &[&str] = &["{job}", "{profile}"];

/// Checks one start/end template line: known placeholders only, and none of the modal words
/// the emitter writes itself (a template that switched to G91 or G20 would silently change
/// every move after it).
///
/// # Errors
/// A one-line reason: an unclosed `{`, an unknown placeholder, or a modal word (G20/G21,
/// G90/G91, G93/G94) the emitter writes from `units` and `feed_mode`.
pub(crate) fn check_template(line: &str) -> Result<(), String> {
    let mut rest = line;
    while let Some(open) = rest.find('{') {
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| format!("{line:?}: unclosed '{{'"))?;
        let placeholder = &rest[open..open + close + 1];
        if !TEMPLATE_PLACEHOLDERS.contains(&placeholder) {
            return Err(format!(
                "{line:?}: unknown placeholder {placeholder} (known: {})",
                TEMPLATE_PLACEHOLDERS.join(", ")
            ));
        }
        rest = &rest[open + close + 1..];
    }
    let upper = line.to_ascii_uppercase();
    // Words only: text inside (...) or after ';' is a comment.
    let code: String = {
        let mut depth = 0;
        let mut out = String::new();
        for c in upper.chars() {
            match c {
                ';' if depth == 0 => break,
                '(' => depth += 1,
                ')' => depth -= 1,
                _ if depth == 0 => out.push(c),
                _ => {}
            }
        }
        out
    };
    let compact: String = code.chars().filter(|c| !c.is_whitespace()).collect();
    for word in ["G20", "G21", "G90", "G91", "G93", "G94"] {
        let mut from = 0;
        while let Some(i) = compact[from..].find(word) {
            let end = from + i + word.len();
            // G90 but not G90.1 (arc-centre mode), and not G901 etc.
            let next = compact[end..].chars().next();
            if !matches!(next, Some(c) if c.is_ascii_digit() || c == '.') {
                return Err(format!(
                    "{line:?}: {word} is written by the emitter from units and feed_mode; remove it"
                ));
            }
            from = end;
        }
    }
    Ok(())
}
