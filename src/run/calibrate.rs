//! What one case of a study costs, measured by running it as a worker does: for the
//! estimates of `--dry-run`.

use crate::output::{ChunkEncoder, Status, Storage};
use crate::study::Study;

use super::case::Analyses;
use super::journal::JournalRecord;
use super::references::run_reference;
use super::stats::thread_cpu;

/// One case run whole, as a worker runs it, and what it cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// The case id.
    pub id: u64,
    /// Thread CPU time of the case (s): its simulation, replicates, sensors, analysis
    /// and the encoding of its record; its ideal reference not included.
    pub case_s: f64,
    /// Thread CPU time of its ideal reference (s).
    pub reference_s: f64,
    /// Its series and spectra as the file stores them (bytes, after compression).
    pub stored_bytes: u64,
}

/// Runs case row `row` of `study` whole, with its reference (a simulated case's), as a worker would, and
/// measures it; the error says why the case (or its reference) failed.
pub fn measure_case(study: &Study, row: usize) -> Result<Measured, String> {
    let case = &study.cases[row];
    let start = thread_cpu();
    // A measured recording has no reference.
    let reference = match study.recordings {
        Some(_) => None,
        None => Some(run_reference(study, case.reference).map_err(|e| e.to_string())?),
    };
    let after_reference = thread_cpu();
    let mut analyses = Analyses::new(study).map_err(|e| format!("the analysed window: {e}"))?;
    let result = analyses.run(study, row, case, reference.as_ref());
    if result.status == Status::Failed {
        return Err(result.message);
    }
    let mut encoder = ChunkEncoder::new(Storage {
        float32: study.float32,
        deflate_level: study.compression,
    });
    let record = JournalRecord::encode(&result, &mut encoder);
    Ok(Measured {
        id: case.id,
        case_s: thread_cpu() - after_reference,
        reference_s: after_reference - start,
        stored_bytes: record.chunk_bytes() as u64,
    })
}
