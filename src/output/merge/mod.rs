//! Combining shard files (`studyrun merge`) into one file equal to a single run.

mod alike;
mod copy;
mod places;
mod survey;

use std::path::{Path, PathBuf};

use alike::Order;
use copy::{block_rows, Merged};
use places::{case_order, merged_layout, reference_places};
use survey::survey;

use super::{side_paths, OutputError, OutputLock};
use crate::output::Layout;

/// Refuses with `message` unless `ok`.
fn ensure(ok: bool, message: impl FnOnce() -> String) -> Result<(), OutputError> {
    if ok {
        Ok(())
    } else {
        Err(OutputError::Refused(message()))
    }
}

/// Merges `shards` (files of `studyrun --shard K/N` runs of one study) into `output`.
/// Every case of the study must be present exactly once, in finished shard files
/// (no partial files, no pending cases); empty shards are allowed. Shards that netCDF
/// tools rewrote are merged too: variables are matched by name, whatever their
/// order. The merged file's variables are in the first shard's order; its `history`
/// is the first shard's with the merge's line on top. Returns the number of cases.
///
/// One shard is open at a time, and the merged file is written a block of case rows
/// at a time (as many rows as fill the writer's 8 MiB window of metric values), its
/// parameters included: what is held for the whole merge is each case's and
/// reference's place and id (about 110 bytes per case), not their values.
pub fn merge(output: &Path, shards: &[PathBuf], force: bool) -> Result<usize, OutputError> {
    merge_in_blocks(output, shards, force, block_rows)
}

/// [`merge`], the merged file written in blocks of `rows(layout)` case rows.
fn merge_in_blocks(
    output: &Path,
    shards: &[PathBuf],
    force: bool,
    rows: fn(&Layout) -> usize,
) -> Result<usize, OutputError> {
    ensure(!shards.is_empty(), || {
        "merge needs at least one shard file".into()
    })?;
    check_inputs(output, shards)?;
    // Nothing replaced that is not ours: no shard, no FIFO or link, and with --force
    // only a study file; checked again under the lock.
    let inputs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    super::overwrite::check_output(output, force, &inputs)?;
    let _lock = OutputLock::acquire(output)?;
    super::overwrite::check_output(output, force, &inputs)?;
    let (first, surveyed) = survey(shards)?;
    let (order, expected) = case_order(&first, &surveyed, shards)?;
    let refs = reference_places(&surveyed);
    let layout = merged_layout(
        &first,
        &surveyed,
        (&order, &refs),
        expected,
        (output, shards, force),
    );
    // The shards' ids are in the merged layout now: only their variables' order stays.
    let orders: Vec<Order> = surveyed.into_iter().map(|s| s.order).collect();
    let merged = Merged {
        shards,
        orders: &orders,
        order: &order,
        refs: &refs,
        layout: &layout,
        block_rows: rows(&layout),
    };
    merged.write(output)?;
    Ok(order.len())
}

/// Refuses shards that are partial files, have a journal beside them, are given twice
/// or are the output itself.
fn check_inputs(output: &Path, shards: &[PathBuf]) -> Result<(), OutputError> {
    for (k, p) in shards.iter().enumerate() {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        ensure(
            super::DataFile::output_of(Path::new(&name)).is_none(),
            || {
                format!(
                    "{} is the partial file of an unfinished run; finish it with --resume first",
                    p.display()
                )
            },
        )?;
        let (journal, _) = side_paths(p);
        ensure(!journal.exists(), || {
            format!(
                "{} has the journal of an interrupted run beside it ({}), whose result will \
                 replace it; finish that run with --resume first",
                p.display(),
                journal.display()
            )
        })?;
        let same = |q: &PathBuf| match (std::fs::canonicalize(p), std::fs::canonicalize(q)) {
            (Ok(a), Ok(b)) => a == b,
            _ => p == q,
        };
        if let Some(q) = shards[..k].iter().find(|q| same(q)) {
            return Err(OutputError::Refused(format!(
                "{} is given twice (also as {})",
                p.display(),
                q.display()
            )));
        }
        ensure(!same(&output.to_path_buf()), || {
            format!("{} is both a shard and the merged output", p.display())
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::survey::without_cases;
    use super::*;
    use crate::output::{
        provenance, AttrValue, CaseRecord, Param, ParamValues, Status, StudyReader, StudyWriter,
        VarSpec,
    };

    /// The layout of a file of cases `ids` of a 7-case study (`shard` "K/3" or ""),
    /// with a numeric and a text parameter, a spectrum, a metric and one reference
    /// per case parity.
    fn layout(ids: &[u64], shard: &str) -> Layout {
        let mut refs: Vec<u64> = ids.iter().map(|id| id % 2).collect();
        refs.sort_unstable();
        refs.dedup();
        let mut attributes = provenance();
        for (name, value) in [
            ("study_fingerprint", AttrValue::Str("f".into())),
            ("study_cases", AttrValue::I64(7)),
            ("file_cases", AttrValue::I64(ids.len() as i64)),
            ("shard", AttrValue::Str(shard.into())),
        ] {
            attributes.push((name.to_owned(), value));
        }
        let param = |name: &str, values| Param {
            spec: VarSpec::new(name, "1", name),
            values,
        };
        Layout {
            case_ids: ids.to_vec(),
            times: vec![0.0, 0.1],
            frequencies: vec![0.0, 5.0],
            spectra: vec![VarSpec::new("x_spectrum", "m", "amplitude of x")],
            metrics: vec![VarSpec::new("x_rms", "m", "rms of x")],
            parameters: vec![
                param(
                    "rpm",
                    ParamValues::F64(ids.iter().map(|&i| 100.0 * i as f64).collect()),
                ),
                param(
                    "label",
                    ParamValues::Str(ids.iter().map(|i| format!("c{i}")).collect()),
                ),
            ],
            reference_parameters: vec![param(
                "parity",
                ParamValues::Str(refs.iter().map(|r| format!("p{r}")).collect()),
            )],
            reference_series: vec![VarSpec::new("x_ideal", "m", "ideal x")],
            reference_index: ids
                .iter()
                .map(|id| refs.partition_point(|&r| r < id % 2) as u64)
                .collect(),
            reference_ids: refs,
            attributes,
            ..Layout::default()
        }
    }

    /// Writes the file of cases `ids` at `path`: case `i`'s spectrum and metric from
    /// `i`, case 5 failed.
    fn write(path: &Path, ids: &[u64], shard: &str) {
        let l = layout(ids, shard);
        let mut w = StudyWriter::create(path, &l).unwrap();
        for (row, &id) in ids.iter().enumerate() {
            let spectrum = [id as f64, -(id as f64)];
            let failed = id == 5;
            let record = CaseRecord {
                series: &[],
                spectra: &[&spectrum],
                metrics: &[0.5 * id as f64],
                status: if failed { Status::Failed } else { Status::Ok },
                message: if failed { "diverged" } else { "" },
                replicate_messages: &[],
            };
            w.write_case(row, &record).unwrap();
        }
        for (k, &r) in l.reference_ids.iter().enumerate() {
            w.write_reference(k, &[&[r as f64, 1.0]]).unwrap();
        }
        w.finish().unwrap();
    }

    #[test]
    fn a_merge_in_blocks_of_two_rows_equals_the_whole_file() {
        let dir = tempfile::tempdir().unwrap();
        let whole = dir.path().join("whole.h5");
        write(&whole, &[0, 1, 2, 3, 4, 5, 6], "");
        let mut shards = Vec::new();
        for k in 1..=3u64 {
            let path = dir.path().join(format!("part{k}.h5"));
            let ids: Vec<u64> = (0..7).filter(|id| id % 3 == k - 1).collect();
            write(&path, &ids, &format!("{k}/3"));
            shards.push(path);
        }
        shards.reverse();
        for (name, rows) in [
            ("two.h5", (|_| 2) as fn(&Layout) -> usize),
            ("one.h5", block_rows),
        ] {
            let merged = dir.path().join(name);
            assert_eq!(merge_in_blocks(&merged, &shards, false, rows).unwrap(), 7);
            let (a, b) = (
                StudyReader::open(&whole).unwrap(),
                StudyReader::open(&merged).unwrap(),
            );
            let (la, lb) = (a.layout(), b.layout());
            assert_eq!(la.case_ids, lb.case_ids, "{name}");
            assert_eq!(la.parameters, lb.parameters, "{name}");
            assert_eq!(la.reference_ids, lb.reference_ids, "{name}");
            assert_eq!(la.reference_parameters, lb.reference_parameters, "{name}");
            assert_eq!(la.reference_index, lb.reference_index, "{name}");
            for row in 0..7 {
                assert_eq!(
                    a.read_case(row).unwrap(),
                    b.read_case(row).unwrap(),
                    "{name} {row}"
                );
            }
            for k in 0..2 {
                assert_eq!(a.read_reference(k).unwrap(), b.read_reference(k).unwrap());
            }
            assert!(
                b.verify().unwrap().is_empty(),
                "{name}: every variable checksummed"
            );
        }
    }

    #[test]
    fn a_block_of_rows_reads_as_its_rows_one_by_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("whole.h5");
        write(&path, &[0, 1, 2, 3, 4, 5, 6], "");
        let r = StudyReader::open(&path).unwrap();
        let block = r.read_cases(2..6).unwrap();
        assert_eq!(block.len(), 4);
        for (k, case) in block.iter().enumerate() {
            assert_eq!(case, &r.read_case(2 + k).unwrap(), "row {}", 2 + k);
        }
        assert_eq!(block[0].metrics, vec![1.0]);
        assert_eq!(block[0].spectra, vec![vec![2.0, -2.0]]);
        assert_eq!(
            (block[3].status, block[3].message.as_str()),
            (Status::Failed, "diverged")
        );
        assert!(r.read_cases(3..3).unwrap().is_empty());
        let past = r.read_cases(5..8).unwrap_err().to_string();
        assert!(past.contains("case row 7 is out of range"), "{past}");
    }

    #[test]
    fn an_unfilled_file_takes_its_parameters_in_order_and_refuses_to_finish_without_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("unfilled.h5");
        let mut l = without_cases(&layout(&[0, 1, 2], ""));
        (l.case_ids, l.reference_ids, l.reference_index) = (vec![0, 1, 2], vec![0], vec![0; 3]);
        let mut w = StudyWriter::create_unfilled(&path, &l).unwrap();
        w.write_parameter_rows(false, 0, &ParamValues::F64(vec![1.0, 2.0]))
            .unwrap();
        let wrong_kind = w.write_parameter_rows(false, 1, &ParamValues::F64(vec![1.0]));
        assert!(wrong_kind
            .unwrap_err()
            .to_string()
            .contains("numbers for a text parameter"));
        let too_many = w.write_parameter_rows(false, 0, &ParamValues::F64(vec![3.0; 2]));
        assert!(too_many
            .unwrap_err()
            .to_string()
            .contains("rows 2..4, but the variable has 3"));
        let err = w.finish().unwrap_err().to_string();
        assert!(
            err.contains("rpm") && err.contains("2 of its 3 rows written"),
            "{err}"
        );
    }
}
