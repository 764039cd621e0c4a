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

#[cfg(test)]
mod tests {
    use super::*;

    fn by_name(text: &str, name: &str) -> Result<Loaded, Fault> {
        read(text.as_bytes(), Some(&ColumnRef::Name(name.into())))
    }

    fn by_index(text: &str, i: usize) -> Result<Loaded, Fault> {
        read(text.as_bytes(), Some(&ColumnRef::Index(i)))
    }

    const WITH_HEADER: &str = "time,DE\n0,1.5\n0.001,-2\n0.002,3e-3\n";

    #[test]
    fn a_column_reads_by_header_name_or_index() {
        let named = by_name(WITH_HEADER, "DE").unwrap();
        assert_eq!(
            (named.name.as_str(), &named.values[..]),
            ("DE", &[1.5, -2.0, 3e-3][..])
        );
        let indexed = by_index(WITH_HEADER, 1).unwrap();
        assert_eq!(
            (indexed.name.as_str(), indexed.values),
            ("DE", vec![1.5, -2.0, 3e-3])
        );
        assert_eq!(
            by_index(WITH_HEADER, 0).unwrap().values,
            [0.0, 0.001, 0.002]
        );
    }

    #[test]
    fn without_a_header_every_line_is_data() {
        let read_back = by_index("1,2\n3,4\n", 1).unwrap();
        assert_eq!(
            (read_back.name.as_str(), read_back.values),
            ("column 1", vec![2.0, 4.0])
        );
        assert_eq!(
            read("7\n-8\n".as_bytes(), None).unwrap().values,
            [7.0, -8.0]
        );
        assert_eq!(
            read("x\n7\n-8\n".as_bytes(), None).unwrap().values,
            [7.0, -8.0]
        );
    }

    #[test]
    fn semicolons_and_tabs_separate_when_the_first_line_has_no_comma() {
        assert_eq!(by_name("a;b\n1;2\n3;4\n", "b").unwrap().values, [2.0, 4.0]);
        assert_eq!(
            by_name("a\tb\n1\t2\n3\t4\n", "b").unwrap().values,
            [2.0, 4.0]
        );
    }

    #[test]
    fn empty_lines_crlf_spaces_quotes_and_a_bom_are_handled() {
        let text = "\u{feff}\"t\", \"DE, raw\"\r\n\r\n0, 5\r\n\r\n1,\"-6\"\r\n";
        let read_back = by_name(text, "DE, raw").unwrap();
        assert_eq!(read_back.values, [5.0, -6.0]);
        assert_eq!(
            by_name("\"a\"\"b\",c\n1,2\n", "a\"b").unwrap().values,
            [1.0]
        );
    }

    #[test]
    fn a_cell_that_is_not_a_number_names_its_line() {
        let Err(Fault::Corrupt(m)) = by_name("x,y\n1,2\n\n3,abc\n", "y") else {
            panic!("a text cell was read");
        };
        assert_eq!(m, "line 4: `abc` in column `y` is not a number");
        let Err(Fault::Corrupt(m)) = by_name("x,y\n1,2\n3\n", "y") else {
            panic!("a short row was read");
        };
        assert_eq!(m, "line 3 has 1 field(s), no column 1 (`y`)");
    }

    #[test]
    fn a_wrong_column_lists_what_there_is() {
        let Err(Fault::Select(m)) = by_name(WITH_HEADER, "FE") else {
            panic!("a missing column was read");
        };
        assert_eq!(m, "no column `FE`; the header names time, DE");
        let Err(Fault::Select(m)) = by_name("1,2\n", "FE") else {
            panic!("a column was found by name without a header");
        };
        assert!(m.contains("not a header") && m.contains("0..=1"), "{m}");
        let Err(Fault::Select(m)) = by_index(WITH_HEADER, 2) else {
            panic!("column 2 of 2 was read");
        };
        assert_eq!(m, "no column 2: line 1 has 2 column(s), 0..=1");
        let Err(Fault::Select(m)) = read(WITH_HEADER.as_bytes(), None) else {
            panic!("one of two columns was read without a selector");
        };
        assert_eq!(
            m,
            "2 columns (time, DE); choose one by name or by index 0..=1"
        );
    }

    #[test]
    fn nothing_to_read_is_empty_and_binary_is_refused() {
        assert_eq!(
            read(b"\n \n", None).unwrap_err(),
            Fault::Empty("the CSV file".into())
        );
        assert_eq!(by_name("DE\n", "DE").unwrap().values, Vec::<f64>::new());
        assert!(matches!(
            read(b"1,2\n\xff\xfe", None),
            Err(Fault::Corrupt(_))
        ));
    }
}
