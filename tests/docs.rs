//! docs/grid-file.md against the code, so that it cannot drift: its parameter table
//! holds every entry of `study::params::PARAMETERS` (name, stored unit, long_name and
//! the default a study gets) and nothing else; its key tables hold exactly the keys of
//! the grid file's serde mirror (`study::config`); its units table lists the spellings
//! each quantity accepts.

use std::cell::Cell;
use std::collections::BTreeSet;
use std::fmt;
use std::path::Path;

use serde::de::{self, Deserialize, Deserializer, Visitor};
use studyrun::study::config::{
    BearingSection, DefectSection, DesignParameter, DesignSection, EnvelopeSection,
    FrictionSection, GeometrySection, GridFile, HarmonicSection, HousingSection, JournalSection,
    MechanismSection, NoiseSection, OutputSection, RecordingSection, ReplicatesSection,
    SensorSection, SolverSection, SpectraSection, SpeedSection, WavinessSection,
};
use studyrun::study::params::PARAMETERS;
use studyrun::study::units::Dimension;
use studyrun::study::Study;

const GRID_FILE_DOC: &str = "docs/grid-file.md";

fn grid_file_doc() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(GRID_FILE_DOC);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// One Markdown table: its header cells and its rows' cells (trimmed).
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    // `\|` inside a cell is a literal bar, not a cell boundary.
    let mut out = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                out.last_mut().unwrap().push('|');
                chars.next();
            }
            '|' => out.push(String::new()),
            c => out.last_mut().unwrap().push(c),
        }
    }
    out.into_iter().map(|c| c.trim().to_string()).collect()
}

/// Every table of `md` outside code blocks.
fn tables(md: &str) -> Vec<Table> {
    let mut out = Vec::new();
    let mut in_code = false;
    let mut lines = md.lines().peekable();
    while let Some(line) = lines.next() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code || !line.trim_start().starts_with('|') {
            continue;
        }
        let header = cells(line);
        // The delimiter row.
        match lines.next() {
            Some(d) if d.trim_start().starts_with("|") && d.contains("---") => {}
            _ => continue,
        }
        let mut rows = Vec::new();
        while let Some(row) = lines.peek() {
            if !row.trim_start().starts_with('|') {
                break;
            }
            rows.push(cells(row));
            lines.next();
        }
        out.push(Table { header, rows });
    }
    out
}

/// The tables whose first header cell is `first`.
fn tables_headed<'a>(all: &'a [Table], first: &str) -> Vec<&'a Table> {
    all.iter()
        .filter(|t| t.header.first().map(String::as_str) == Some(first))
        .collect()
}

/// The text inside the first pair of backticks of `cell`.
fn code(cell: &str) -> Option<&str> {
    let start = cell.find('`')? + 1;
    let len = cell[start..].find('`')?;
    Some(&cell[start..start + len])
}

/// Every backticked item of `cell`.
fn codes(cell: &str) -> Vec<&str> {
    cell.split('`').skip(1).step_by(2).collect()
}

/// A study of defaults only: one explicit case with nothing set.
fn default_study() -> Study {
    Study::from_yaml(
        "name: defaults\nduration: 0.1\nsample_rate: 1000\ncases: [{}]\n",
        Path::new("defaults.yaml"),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_parameter_table_lists_every_parameter_with_its_unit_long_name_and_default() {
    let doc = grid_file_doc();
    let all = tables(&doc);
    let found = tables_headed(&all, "parameter");
    assert_eq!(
        found.len(),
        1,
        "{GRID_FILE_DOC}: expected one table headed `| parameter | unit | long_name | default | ...`"
    );
    let table = found[0];
    assert_eq!(
        &table.header[..4],
        ["parameter", "unit", "long_name", "default"],
        "{GRID_FILE_DOC}: parameter table columns"
    );
    let base = default_study().cases[0].params.clone();
    let mut documented = BTreeSet::new();
    for row in &table.rows {
        let name = code(&row[0]).unwrap_or_else(|| panic!("no `name` in row {row:?}"));
        let p = PARAMETERS
            .iter()
            .find(|p| p.name == name)
            .unwrap_or_else(|| {
                panic!("{GRID_FILE_DOC}: `{name}` is in the parameter table but is no parameter")
            });
        assert!(
            documented.insert(name.to_string()),
            "{GRID_FILE_DOC}: `{name}` is listed twice"
        );
        assert_eq!(
            code(&row[1]),
            Some(p.dimension.base_unit()),
            "{GRID_FILE_DOC}: unit of `{name}`"
        );
        assert_eq!(
            row[2], p.long_name,
            "{GRID_FILE_DOC}: long_name of `{name}`"
        );
        let default = code(&row[3]).unwrap_or_else(|| panic!("no `default` for `{name}`"));
        // `NaN`: the parameter of a speed profile the default case does not have.
        let value = match default {
            "NaN" => f64::NAN,
            _ => p
                .dimension
                .parse(default)
                .unwrap_or_else(|e| panic!("{GRID_FILE_DOC}: default of `{name}`: {e}")),
        };
        let actual = p.get(&base);
        assert!(
            (value - actual).abs() <= 1e-12 * actual.abs() || (value.is_nan() && actual.is_nan()),
            "{GRID_FILE_DOC}: default of `{name}` is {actual} {}, the table says {default}",
            p.dimension.base_unit()
        );
    }
    for p in PARAMETERS {
        assert!(
            documented.contains(p.name),
            "{GRID_FILE_DOC}: parameter `{}` ({}, {}) is missing from the parameter table",
            p.name,
            p.dimension.base_unit(),
            p.long_name
        );
    }
}

/// A deserializer that records the field names a derived `Deserialize` struct asks
/// for, and deserializes nothing.
struct FieldNames<'a>(&'a Cell<Option<&'static [&'static str]>>);

#[derive(Debug)]
struct Stop;

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("field names recorded")
    }
}

impl std::error::Error for Stop {}

impl de::Error for Stop {
    fn custom<T: fmt::Display>(_: T) -> Self {
        Stop
    }
}

impl<'de> Deserializer<'de> for FieldNames<'_> {
    type Error = Stop;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
        Err(Stop)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        _visitor: V,
    ) -> Result<V::Value, Stop> {
        self.0.set(Some(fields));
        Err(Stop)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes
        byte_buf option unit unit_struct newtype_struct seq tuple tuple_struct map enum
        identifier ignored_any
    }
}

/// The keys of the serde struct `T`, each prefixed.
fn keys_of<'de, T: Deserialize<'de>>(prefix: &str) -> Vec<String> {
    let fields = Cell::new(None);
    let _ = T::deserialize(FieldNames(&fields));
    let fields = fields
        .get()
        .unwrap_or_else(|| panic!("{} is not a struct", std::any::type_name::<T>()));
    fields.iter().map(|f| format!("{prefix}{f}")).collect()
}

#[test]
fn the_key_tables_hold_exactly_the_keys_of_the_grid_file() {
    let mut expected: BTreeSet<String> = BTreeSet::new();
    expected.extend(keys_of::<GridFile>(""));
    expected.extend(keys_of::<MechanismSection>("mechanism."));
    expected.extend(keys_of::<BearingSection>("bearing."));
    expected.extend(keys_of::<HousingSection>("housing."));
    expected.extend(keys_of::<JournalSection>("journal."));
    expected.extend(keys_of::<FrictionSection>("journal.friction."));
    // inner_waviness and outer_waviness take the same keys; the document says so once.
    expected.extend(keys_of::<WavinessSection>("bearing.waviness."));
    expected.extend(keys_of::<HarmonicSection>("bearing.waviness.harmonics[]."));
    expected.extend(keys_of::<GeometrySection>("bearing.geometry."));
    expected.extend(keys_of::<DefectSection>("bearing.defects[]."));
    expected.extend(keys_of::<SolverSection>("solver."));
    expected.extend(keys_of::<SpectraSection>("spectra."));
    expected.extend(keys_of::<EnvelopeSection>("envelope."));
    expected.extend(keys_of::<OutputSection>("output."));
    expected.extend(keys_of::<DesignSection>("design."));
    expected.extend(keys_of::<DesignParameter>("design.parameters.*."));
    expected.extend(keys_of::<SpeedSection>("speed."));
    expected.extend(keys_of::<ReplicatesSection>("replicates."));
    expected.extend(keys_of::<SensorSection>("sensors[]."));
    expected.extend(keys_of::<NoiseSection>("sensors[].noise."));
    expected.extend(keys_of::<RecordingSection>("recordings[]."));
    assert!(expected.contains("bearing.waviness.amplitude") && expected.contains("zip"));

    let doc = grid_file_doc();
    let all = tables(&doc);
    let mut documented = BTreeSet::new();
    for table in tables_headed(&all, "key") {
        for row in &table.rows {
            let key = code(&row[0]).unwrap_or_else(|| panic!("no `key` in row {row:?}"));
            assert!(
                documented.insert(key.to_string()),
                "{GRID_FILE_DOC}: key `{key}` is listed twice"
            );
        }
    }
    let missing: Vec<_> = expected.difference(&documented).collect();
    let unknown: Vec<_> = documented.difference(&expected).collect();
    assert!(
        missing.is_empty() && unknown.is_empty(),
        "{GRID_FILE_DOC}: keys of the grid file not in its key tables: {missing:?}; \
         keys in the tables the grid file does not have: {unknown:?}"
    );
}

#[test]
fn the_units_table_lists_what_each_quantity_accepts() {
    let doc = grid_file_doc();
    let all = tables(&doc);
    let found = tables_headed(&all, "stored unit");
    assert_eq!(found.len(), 1, "{GRID_FILE_DOC}: one units table");
    let table = found[0];
    let dimensions = [
        Dimension::Length,
        Dimension::Speed,
        Dimension::Stiffness,
        Dimension::SpringStiffness,
        Dimension::Damping,
        Dimension::InverseSpeed,
        Dimension::Time,
        Dimension::Frequency,
        Dimension::Mass,
        Dimension::Inertia,
        Dimension::Angle,
        Dimension::Pressure,
        Dimension::Viscosity,
        Dimension::Velocity,
    ];
    // Every parameter's quantity is among them.
    for p in PARAMETERS {
        assert!(
            p.dimension == Dimension::Dimensionless || dimensions.contains(&p.dimension),
            "`{}`: add its quantity to this test",
            p.name
        );
    }
    for d in dimensions {
        let unit = d.base_unit();
        let row = table
            .rows
            .iter()
            .find(|r| code(&r[0]) == Some(unit))
            .unwrap_or_else(|| panic!("{GRID_FILE_DOC}: no row for the unit `{unit}`"));
        let listed: BTreeSet<&str> = codes(&row[2]).into_iter().collect();
        let accepted = d.accepted();
        let accepted: BTreeSet<&str> = accepted
            .split_once("one of: ")
            .unwrap_or_else(|| panic!("{accepted}"))
            .1
            .split(", ")
            .collect();
        assert_eq!(listed, accepted, "{GRID_FILE_DOC}: spellings of `{unit}`");
    }
}

/// The code blocks of Markdown-like `lines` whose opening fence satisfies `opens`.
fn code_blocks<'a>(
    lines: impl Iterator<Item = &'a str>,
    opens: impl Fn(&str) -> bool,
) -> Vec<Vec<&'a str>> {
    let mut blocks = Vec::new();
    let mut current: Option<Vec<&str>> = None;
    let mut in_other = false;
    for line in lines {
        let fence = line.trim_start().starts_with("```");
        match (&mut current, fence) {
            (Some(block), false) => block.push(line),
            (Some(_), true) => blocks.push(current.take().unwrap()),
            (None, true) if in_other => in_other = false,
            (None, true) if opens(line.trim()) => current = Some(Vec::new()),
            (None, true) => in_other = true,
            (None, false) => {}
        }
    }
    blocks
}

#[test]
fn the_readme_shows_the_crate_level_doctests_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lib = std::fs::read_to_string(root.join("src/lib.rs")).unwrap();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    // The crate docs, without the `//!` markers; rustdoc hides lines starting with `# `.
    let docs = lib
        .lines()
        .take_while(|l| l.starts_with("//!") || l.trim().is_empty())
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l));
    let doctests: Vec<Vec<&str>> = code_blocks(docs, |f| f == "```" || f == "```rust")
        .into_iter()
        .map(|b| {
            b.into_iter()
                .filter(|l| !(l.trim() == "#" || l.trim_start().starts_with("# ")))
                .collect()
        })
        .collect();
    assert!(
        !doctests.is_empty(),
        "src/lib.rs has no crate-level doctest"
    );
    let shown = code_blocks(readme.lines(), |f| f == "```rust");
    assert_eq!(
        shown, doctests,
        "README.md's ```rust blocks must be the crate-level doctests of src/lib.rs as rustdoc \
         shows them (hidden `# ` lines left out), in order: copy them over"
    );
}

#[test]
fn the_readme_stays_short() {
    // Details belong in docs/: the README is the first screen and the map.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let lines = std::fs::read_to_string(&path).unwrap().lines().count();
    assert!(
        lines <= 250,
        "README.md has {lines} lines; move details to docs/"
    );
}
