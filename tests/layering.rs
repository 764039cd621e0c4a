//! The crate's layering, as docs/architecture.md draws it, checked against the code.
//!
//! The architecture page has a table of the layers from the top down, each row naming
//! a top-level module of `src/` and the modules it may import. This test reads that
//! table and every source file, and fails when
//! - a module of `src/` is missing from the table, or the table names one that is gone;
//! - a row allows an import of a module that is not below it (a circle, or a climb);
//! - the code of a module names (`crate::<module>`) a module its row does not allow.
//!
//! Comments and `#[cfg(test)]` modules are left out: a doc link may point anywhere,
//! and a unit test may build its fixtures from any layer.
//!
//! It also keeps files and functions below the sizes past which they must be split.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ARCHITECTURE: &str = "docs/architecture.md";

/// The layer table: module names from the top down, each with the modules it may import.
fn documented_layers() -> Vec<(String, BTreeSet<String>)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(ARCHITECTURE);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().skip_while(|l| !l.starts_with("| layer |"));
    assert!(
        lines.next().is_some(),
        "{ARCHITECTURE} has no `| layer |` table"
    );
    lines
        .skip(1) // the |---| row
        .take_while(|l| l.starts_with('|'))
        .map(|row| {
            let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
            assert!(cells.len() >= 3, "{ARCHITECTURE}: short layer row `{row}`");
            let module = cells[1].trim_matches('`').to_string();
            let imports = cells[2]
                .split(',')
                .map(|m| m.trim().trim_matches('`').to_string())
                .filter(|m| !m.is_empty() && m != "nothing")
                .collect();
            (module, imports)
        })
        .collect()
}

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file of `src/` belongs to (`src/run/mod.rs` → `run`,
/// `src/simulate.rs` → `simulate`); `lib` and `main` are the crate roots.
fn module_of(src: &Path, file: &Path) -> String {
    let first = file
        .strip_prefix(src)
        .expect("under src/")
        .components()
        .next();
    let name = first.expect("a file name").as_os_str().to_string_lossy();
    name.trim_end_matches(".rs").to_string()
}

/// The code of a file without comments and without its `#[cfg(test)]` module.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or_default();
    text.lines()
        .map(|l| l.split("//").next().unwrap_or_default())
        .collect::<Vec<_>>()
        .join("\n")
}

/// The modules `code` names as `crate::<module>`.
fn imports(code: &str) -> BTreeSet<String> {
    code.match_indices("crate::")
        .filter(|(i, _)| !code[..*i].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
        .map(|(i, m)| {
            code[i + m.len()..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect::<String>()
        })
        .filter(|m| !m.is_empty())
        .collect()
}

#[test]
fn every_module_imports_only_the_layers_below_it() {
    let layers = documented_layers();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);

    let mut found: BTreeMap<String, BTreeMap<String, Vec<String>>> = BTreeMap::new();
    for file in &files {
        let module = module_of(&src, file);
        if module == "lib" || module == "main" {
            continue;
        }
        let text = std::fs::read_to_string(file).expect("a readable source file");
        let entry = found.entry(module.clone()).or_default();
        for import in imports(&code(&text)) {
            if import != module {
                let shown = file.strip_prefix(&src).unwrap().display().to_string();
                entry.entry(import).or_default().push(shown);
            }
        }
    }

    let documented: BTreeSet<&String> = layers.iter().map(|(m, _)| m).collect();
    let in_code: BTreeSet<&String> = found.keys().collect();
    assert_eq!(
        documented, in_code,
        "{ARCHITECTURE}'s layer table must list exactly the top-level modules of src/"
    );

    let mut wrong = Vec::new();
    for (depth, (module, allowed)) in layers.iter().enumerate() {
        let below: BTreeSet<&String> = layers[depth + 1..].iter().map(|(m, _)| m).collect();
        for a in allowed {
            if !below.contains(a) {
                wrong.push(format!(
                    "the table lets `{module}` import `{a}`, which is not below it"
                ));
            }
        }
        for (import, files) in &found[module] {
            if !allowed.contains(import) {
                wrong.push(format!(
                    "`{module}` imports `{import}` (in {}), which its row does not allow",
                    files.join(", ")
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "layering broken:\n{}", wrong.join("\n"));
}

#[test]
fn an_import_that_climbs_is_found() {
    let code = code(
        "use crate::run::RunError; // crate::cli in a comment\n\
         fn f() -> crate::output::Layout { todo!() }\n\
         /// [`crate::study`]\n\
         #[cfg(test)]\nmod tests { use crate::accuracy; }",
    );
    let expected: BTreeSet<String> = ["run", "output"].map(String::from).into();
    assert_eq!(imports(&code), expected);
}

/// Lines past which a source file must be split (tables of constants aside).
const MAX_FILE_LINES: usize = 850;
/// Lines past which a function must be split.
const MAX_FUNCTION_LINES: usize = 80;
/// Files that are tables of constants.
const TABLES: [&str; 1] = ["solve/tableau.rs"];

/// `(name, first line, lines)` of every `fn` with a body in `text`, by brace count
/// (braces in strings and comments aside).
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let code = line.split("//").next().unwrap_or_default();
        let Some(at) = code.find("fn ") else { continue };
        if at > 0 && !code[..at].ends_with(' ') {
            continue;
        }
        let name: String = code[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let (mut depth, mut opened) = (0i64, false);
        for (j, l) in lines[i..].iter().enumerate() {
            let mut in_string = false;
            for c in l.split("//").next().unwrap_or_default().chars() {
                match c {
                    '"' => in_string = !in_string,
                    '{' if !in_string => (depth, opened) = (depth + 1, true),
                    '}' if !in_string => depth -= 1,
                    _ => {}
                }
            }
            if !opened && l.trim_end().ends_with(';') {
                break;
            }
            if opened && depth <= 0 {
                found.push((name.clone(), i + 1, j + 1));
                break;
            }
        }
    }
    found
}

#[test]
fn no_file_or_function_grows_past_its_ceiling() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut long = Vec::new();
    for file in &files {
        let shown = file.strip_prefix(&src).unwrap().display().to_string();
        let text = std::fs::read_to_string(file).unwrap();
        let n = text.lines().count();
        if n > MAX_FILE_LINES && !TABLES.contains(&shown.as_str()) {
            long.push(format!("{shown}: {n} lines"));
        }
        for (name, at, n) in functions(&text) {
            if n > MAX_FUNCTION_LINES {
                long.push(format!("{shown}:{at}: fn {name}, {n} lines"));
            }
        }
    }
    assert!(long.is_empty(), "split these:\n{}", long.join("\n"));
}

#[test]
fn the_function_counter_counts_a_body() {
    let text = "fn a() {\n    let s = \"}\";\n    {\n    }\n}\nfn b();\n";
    assert_eq!(functions(text), vec![("a".to_string(), 1, 5)]);
}
