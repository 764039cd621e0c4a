//! The YAML parser's errors in the user's words: the place, the key (as a dotted field
//! name, found from the file's indentation) and what is expected, without the
//! parser's or serde's internals (type names, policy names, snippets).

use serde_saphyr::Error;

/// What a parser error says: 1-based (line, column), the dotted field it is in (or
/// empty) and the message.
pub(super) fn describe(e: &Error, text: &str) -> (Option<(u64, u64)>, String, String) {
    let mut e = e;
    // The error under its snippet or alias wrapper.
    while let Error::WithSnippet { error, .. } | Error::AliasError { error, .. } = e {
        e = error;
    }
    let place = e
        .location()
        .map(|l| (l.line(), l.column()))
        .filter(|&(line, column)| line > 0 && column > 0);
    let field = place.map_or_else(String::new, |(l, c)| {
        super::tree::field_at(text, l, c).unwrap_or_else(|| field_at(text, l, c))
    });
    let token = place.map(|(l, c)| token_at(text, l, c)).unwrap_or_default();
    let got = if token.is_empty() {
        String::new()
    } else {
        format!("`{token}` ")
    };
    let message = message(e, &field, &got);
    // A missing field is reported where the mapping that lacks it ends: no field to
    // name there.
    let field = if matches!(e, Error::SerdeMissingField { .. }) {
        String::new()
    } else {
        field
    };
    (place, field, message)
}

/// The message of the parser error `e` (without its snippet or alias wrapper), found in the dotted
/// `field`, at the token quoted in `got` (`` `token` `` and a space, or empty).
fn message(e: &Error, field: &str, got: &str) -> String {
    match e {
        Error::SerdeUnknownField {
            field: key,
            expected,
            ..
        } => format!(
            "unknown field `{key}`; expected one of: {}",
            expected.join(", ")
        ),
        Error::SerdeMissingField { field: key, .. } => {
            let parent = field.rsplit_once('.').map_or("", |(p, _)| p);
            let within = if parent.is_empty() {
                String::new()
            } else {
                format!(" in `{parent}`")
            };
            format!("the required field `{key}` is missing{within}")
        }
        Error::DuplicateMappingKey { key, .. } => match key {
            Some(k) => format!("`{k}` is given twice; give each key once"),
            None => "a key is given twice; give each key once".to_string(),
        },
        Error::SerdeInvalidType {
            unexpected,
            expected,
            ..
        } => format!("{} is not allowed here; expected {}", plain(unexpected), plain(expected)),
        Error::SerdeInvalidValue {
            unexpected,
            expected,
            ..
        } => format!("{} is not allowed; expected {}", plain(unexpected), plain(expected)),
        Error::SerdeInvalidLength { len, expected, .. } => {
            format!("{len} values are not allowed; expected {}", plain(expected))
        }
        Error::SerdeUnknownVariant {
            variant, expected, ..
        } => format!("`{variant}` is not allowed; expected one of: {}", expected.join(", ")),
        Error::InvalidScalar { ty, .. } if field == "output.compression" => {
            format!("{got}is not allowed: a deflate level 0..=9")
        }
        Error::InvalidScalar { ty, .. } => format!("{got}is not allowed; expected {}", type_name(ty)),
        Error::NonFiniteFloat { value, .. } => {
            format!("`{value}` is non-finite; expected a finite number")
        }
        Error::InvalidBooleanStrict { .. } => format!("{got}is not allowed; expected true or false"),
        Error::NullIntoString { .. } => "a value is missing; expected a text".to_string(),
        Error::Unexpected { expected, .. } => format!("expected {}", structure(expected)),
        Error::Eof { .. } => "the file ends in the middle of a value".to_string(),
        Error::MultipleDocuments { .. } => {
            "the file holds more than one YAML document (`---`); a grid file is one".to_string()
        }
        Error::Budget { breach, .. } => format!(
            "the file is too complex for a grid file ({breach:?}); a grid describes its cases with axes"
        ),
        Error::InvalidUtf8Input => "the file is not UTF-8 text".to_string(),
        Error::Message { msg, .. } if msg.contains("untagged enum") => format!(
            "{got}is not allowed; expected a number, or a text: a number with a unit \
             (e.g. \"40 um\") or a name"
        ),
        other => internal_free(&other.without_snippet().to_string()),
    }
}

/// serde's description of a value or type, in the user's words.
fn plain(s: &str) -> String {
    let s = s.trim();
    if s.contains("untagged enum") || s.contains("enum Scalar") {
        return "a number or a text".to_string();
    }
    for (serde, ours) in [
        ("a sequence", "a list, e.g. [300, 600]"),
        ("sequence", "a list, e.g. [300, 600]"),
        ("a map", "a mapping of `key: value` lines"),
        ("map", "a mapping of `key: value` lines"),
        ("struct GridFile", "a mapping of `key: value` lines"),
        ("a string", "a text"),
        ("a boolean", "true or false"),
    ] {
        if s == serde {
            return ours.to_string();
        }
    }
    if let Some(rest) = s.strip_prefix("struct ") {
        let _ = rest;
        return "a mapping of `key: value` lines".to_string();
    }
    for ty in [
        "u8", "u16", "u32", "u64", "usize", "i64", "f64", "f32", "bool",
    ] {
        if s == ty || s.ends_with(&format!(" {ty}")) {
            return type_name(ty).to_string();
        }
    }
    s.to_string()
}

/// A Rust type name in the user's words.
fn type_name(ty: &str) -> &'static str {
    match ty {
        "boolean" => "true or false",
        "integer" | "unsigned integer" => "a whole number",
        "float" | "number" => "a number",
        "string" => "a text",
        "u8" => "a whole number from 0 to 255",
        "u16" => "a whole number from 0 to 65535",
        "u32" => "a whole number from 0 to 4294967295",
        "u64" | "usize" => "a whole number from 0 to 18446744073709551615 (2^64 - 1)",
        "i8" | "i16" | "i32" | "i64" | "isize" => "a whole number",
        "f32" | "f64" => "a number",
        "bool" => "true or false",
        "char" => "a single character",
        _ => "a value of another kind",
    }
}

/// The parser's `expected …` of a structural mismatch, in the user's words.
fn structure(expected: &str) -> String {
    match expected {
        "sequence start" => "a list here, e.g. [300, 600]".to_string(),
        "mapping start" => "a mapping of `key: value` lines here".to_string(),
        other => other.to_string(),
    }
}

/// A parser message with its location prefix and any internal names removed.
fn internal_free(text: &str) -> String {
    let mut t = text.trim();
    t = t.strip_prefix("error:").unwrap_or(t).trim();
    // `line 3 column 12: …`
    if let Some(rest) = t.strip_prefix("line ") {
        if let Some((_, msg)) = rest.split_once(": ") {
            t = msg.trim();
        }
    }
    // … and its ` at line 3, column 12` suffix.
    let t = match t.rfind(" at line ") {
        Some(i) if t[i..].contains("column") => &t[..i],
        _ => t,
    };
    let t = t
        .replace(", set DuplicateKeyPolicy in Options if acceptable", "")
        .replace("Options", "options");
    format!("not valid YAML here: {t}")
}

/// The text of the scalar at (`line`, `column`), as written (up to 40 characters).
fn token_at(text: &str, line: u64, column: u64) -> String {
    let Some(l) = text.lines().nth(line as usize - 1) else {
        return String::new();
    };
    let rest: String = l.chars().skip(column as usize - 1).collect();
    let rest = rest.trim_start();
    let token = if let Some(q) = rest.strip_prefix('"') {
        q.split('"').next().unwrap_or("").to_string()
    } else if rest.starts_with(['[', '{']) {
        flow_collection(rest).to_string()
    } else {
        rest.split([',', ']', '}', '#'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string()
    };
    if token.chars().count() > 40 || token.chars().any(char::is_control) {
        String::new()
    } else {
        token
    }
}

/// The flow collection `rest` starts with (`[300, 600]`, `{a: 1}`), up to its closing
/// bracket, or all of `rest` if it does not close on this line.
fn flow_collection(rest: &str) -> &str {
    let mut depth = 0usize;
    for (i, c) in rest.char_indices() {
        match c {
            '[' | '{' => depth += 1,
            ']' | '}' => {
                depth -= 1;
                if depth == 0 {
                    return &rest[..=i];
                }
            }
            _ => {}
        }
    }
    rest
}

/// The dotted name of the field at (`line`, `column`) of a block-style YAML `text`:
/// the keys of the enclosing mappings (from indentation) and the indices of the
/// enclosing `- ` list items, e.g. `bearing.waviness.amplitude` or `cases[1].rpm`. A
/// best effort for messages about text that does not parse as YAML ([`super::tree::field_at`]
/// names the field of text that does): empty where the structure is not plain block style.
pub(super) fn field_at(text: &str, line: u64, column: u64) -> String {
    // The open mappings and list items: (indent, segment, items seen at this level).
    let mut stack: Vec<(usize, String)> = Vec::new();
    let mut items: Vec<(usize, usize)> = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let n = n as u64 + 1;
        if n > line {
            break;
        }
        let content = raw.trim_start_matches(' ');
        if content.is_empty() || content.starts_with('#') {
            continue;
        }
        let mut indent = raw.len() - content.len();
        let mut content = content;
        if n == line && (column as usize) <= indent {
            break;
        }
        // A `- ` list item opens a level at its dash; its content is one level deeper.
        while let Some(rest) = content
            .strip_prefix("- ")
            .or_else(|| (content == "-").then_some(""))
        {
            // Close deeper levels and the previous item at this indent; a key at the
            // same indent stays open (`key:` followed by `- item` lines at its indent).
            while stack
                .last()
                .is_some_and(|(i, s)| *i > indent || (*i == indent && s.starts_with('[')))
            {
                stack.pop();
            }
            items.retain(|(i, _)| *i <= indent);
            let k = match items.iter_mut().find(|(i, _)| *i == indent) {
                Some((_, k)) => {
                    *k += 1;
                    *k
                }
                None => {
                    items.push((indent, 0));
                    0
                }
            };
            stack.push((indent, format!("[{k}]")));
            let skipped = content.len() - rest.len();
            let inner = rest.trim_start_matches(' ');
            indent += skipped + rest.len() - inner.len();
            content = inner;
            if n == line && (column as usize) <= indent {
                return join(&stack);
            }
        }
        let Some(key) = key_of(content) else {
            continue;
        };
        stack.retain(|(i, _)| *i < indent);
        items.retain(|(i, _)| *i < indent);
        stack.push((indent, key));
    }
    join(&stack)
}

/// The key of a `key: value` or `key:` line, if it is one.
fn key_of(content: &str) -> Option<String> {
    let (key, _) = content
        .split_once(": ")
        .or_else(|| content.strip_suffix(':').map(|k| (k, "")))
        .or_else(|| content.split_once(":\t"))?;
    let key = key.trim().trim_matches(['"', '\'']);
    let plain = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.'));
    plain.then(|| key.to_string())
}

fn join(stack: &[(usize, String)]) -> String {
    let mut out = String::new();
    for (_, s) in stack {
        if !out.is_empty() && !s.starts_with('[') {
            out.push('.');
        }
        out.push_str(s);
    }
    out
}

/// Whether `c` is a control character or an invisible mark that changes how the text
/// around it is shown: bidirectional controls (U+061C, U+200E–U+200F, U+202A–U+202E,
/// U+2066–U+2069), zero-width characters (U+200B–U+200D, U+2060–U+2064, U+FEFF) and
/// the line and paragraph separators U+2028, U+2029.
pub(crate) fn is_hidden_control(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{061C}'
                | '\u{200B}'..='\u{200F}'
                | '\u{2028}'..='\u{202E}'
                | '\u{2060}'..='\u{2064}'
                | '\u{2066}'..='\u{2069}'
                | '\u{FEFF}'
        )
}

#[cfg(test)]
mod tests {
    use super::field_at;

    #[test]
    fn the_field_at_a_place_follows_indentation_and_list_items() {
        let text = "name: t\nbearing:\n  clearance: 1\n  waviness:\n    amplitude: x\nzip:\n  - rpm: [1, 2]\n    ball_count: [8, 9]\n  - rpm: [3]\ncases:\n  - {rpm: 3}\n";
        assert_eq!(field_at(text, 1, 7), "name");
        assert_eq!(field_at(text, 3, 14), "bearing.clearance");
        assert_eq!(field_at(text, 5, 16), "bearing.waviness.amplitude");
        assert_eq!(field_at(text, 7, 12), "zip[0].rpm");
        assert_eq!(field_at(text, 8, 18), "zip[0].ball_count");
        assert_eq!(field_at(text, 9, 12), "zip[1].rpm");
        assert_eq!(field_at(text, 11, 5), "cases[0]");
        let compact = "zip:\n- rpm: [1]\n  ball_count: [8]\n- rpm: [2]\ncases:\n- rpm: 3\n";
        assert_eq!(field_at(compact, 3, 15), "zip[0].ball_count");
        assert_eq!(field_at(compact, 4, 8), "zip[1].rpm");
        assert_eq!(field_at(compact, 6, 8), "cases[0].rpm");
    }
}
