//! Delimited text: one record a line, fields separated by `,` (or by `;` or a tab
//! when the first line has no comma), an optional header row.
//!
//! The first non-empty line is a header when the selected field does not parse as a
//! number (a column selected by name needs one). Empty lines are skipped. A field
//! may be quoted (`"a,b"`, with `""` for a quote inside); quoted fields do not span
//! lines. Fields are trimmed of surrounding spaces; a UTF-8 byte-order mark is
//! ignored.

use std::borrow::Cow;

use super::{listed, ColumnRef, Fault, Loaded};

/// The double quote that may enclose a field.
const QUOTE: char = '\u{22}';

/// Reads column `column` of the CSV text in `data` (its only column when `None`).
pub(super) fn read(data: &[u8], column: Option<&ColumnRef>) -> Result<Loaded, Fault> {
    let text = std::str::from_utf8(data).map_err(|e| {
        Fault::Corrupt(format!(
            "not UTF-8 text (byte {} is not valid UTF-8)",
            e.valid_up_to()
        ))
    })?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((first_no, first)) = lines.next() else {
        return Err(Fault::Empty("the CSV file".into()));
    };
    let delimiter = [',', ';', '\t']
        .into_iter()
        .find(|&d| first.contains(d))
        .unwrap_or(',');
    let names: Vec<String> = fields(first, delimiter)
        .into_iter()
        .map(Cow::into_owned)
        .collect();
    let (index, header) = select(&names, first_no, column)?;
    let name = if header {
        names[index].clone()
    } else {
        format!("column {index}")
    };
    let mut values = Vec::new();
    let first_row = (!header).then_some((first_no, first));
    for (no, line) in first_row.into_iter().chain(lines) {
        let row = fields(line, delimiter);
        let cell = row.get(index).ok_or_else(|| {
            Fault::Corrupt(format!(
                "line {no} has {} field(s), no column {index} (`{name}`)",
                row.len()
            ))
        })?;
        let value = number(cell).ok_or_else(|| {
            Fault::Corrupt(format!(
                "line {no}: `{cell}` in column `{name}` is not a number"
            ))
        })?;
        values.push(value);
    }
    Ok(Loaded {
        name,
        values,
        sample_rate: None,
    })
}

/// The selected column's index and whether the first line (`names`, line `line`) is
/// a header.
fn select(
    names: &[String],
    line: usize,
    column: Option<&ColumnRef>,
) -> Result<(usize, bool), Fault> {
    let is_header = |i: usize| number(&names[i]).is_none();
    match column {
        Some(ColumnRef::Name(wanted)) => {
            if let Some(i) = names.iter().position(|n| n == wanted) {
                return Ok((i, true));
            }
            if (0..names.len()).all(|i| !is_header(i)) {
                return Err(Fault::Select(format!(
                    "no column `{wanted}`: the first line (line {line}) holds numbers, not a header; \
                     select a column by index 0..={}",
                    names.len() - 1
                )));
            }
            Err(Fault::Select(format!(
                "no column `{wanted}`; the header names {}",
                listed(names)
            )))
        }
        Some(ColumnRef::Index(i)) if *i < names.len() => Ok((*i, is_header(*i))),
        Some(ColumnRef::Index(i)) => Err(Fault::Select(format!(
            "no column {i}: line {line} has {} column(s), 0..={}",
            names.len(),
            names.len() - 1
        ))),
        None if names.len() == 1 => Ok((0, is_header(0))),
        None => {
            let shown = if (0..names.len()).any(is_header) {
                format!(" ({})", listed(names))
            } else {
                String::new()
            };
            Err(Fault::Select(format!(
                "{} columns{shown}; choose one by name or by index 0..={}",
                names.len(),
                names.len() - 1
            )))
        }
    }
}

/// A field's number, or `None` when it does not parse (`nan` and `inf` do).
fn number(field: &str) -> Option<f64> {
    field.trim().parse().ok()
}

/// The fields of `line`, trimmed and unquoted.
fn fields(line: &str, delimiter: char) -> Vec<Cow<'_, str>> {
    if !line.contains(QUOTE) {
        return line
            .split(delimiter)
            .map(|f| Cow::Borrowed(f.trim()))
            .collect();
    }
    let mut out = Vec::new();
    let mut field = String::new();
    let (mut quoted, mut chars) = (false, line.chars().peekable());
    while let Some(ch) = chars.next() {
        match ch {
            QUOTE if quoted && chars.peek() == Some(&QUOTE) => {
                field.push(QUOTE);
                chars.next();
            }
            QUOTE => quoted = !quoted,
            d if d == delimiter && !quoted => {
                out.push(Cow::Owned(field.trim().to_string()));
                field.clear();
            }
            _ => field.push(ch),
        }
    }
    out.push(Cow::Owned(field.trim().to_string()));
    out
}
