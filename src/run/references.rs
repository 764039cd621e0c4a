//! The ideal-mechanism references of a run: made in groups and written into the file
//! at its creation, then made again where a worker needs one, kept in a cache bounded
//! by [`reference_cache_entries`]. A run's memory thus does not grow with the number of
//! distinct references (speeds, bodies), and a reference made twice is the same bits:
//! it is a pure function of its parameters.

use std::sync::{Arc, Mutex};

use rayon::prelude::*;

use crate::mechanism::CaseParams;
use crate::simulate::{simulate, CaseOutput, CHANNELS};
use crate::study::memory::reference_cache_entries;
use crate::study::Study;

use super::RunError;

/// Runs the ideal reference `index` of `study`.
pub(super) fn run_reference(study: &Study, index: usize) -> Result<CaseOutput, RunError> {
    let r: &CaseParams = study.reference(index);
    simulate(r, &study.solver, &study.sampling).map_err(|source| RunError::Reference {
        index,
        rpm: r.rpm,
        source,
    })
}

/// Runs the references `indices` of `study`, `group` at a time in parallel, handing
/// each to `take` with its position in `indices`, in that order, before the next group
/// is made: at most `group` are held at once.
pub(super) fn each_reference(
    study: &Study,
    indices: &[usize],
    group: usize,
    mut take: impl FnMut(usize, CaseOutput) -> Result<(), RunError>,
) -> Result<(), RunError> {
    for (g, chunk) in indices.chunks(group.max(1)).enumerate() {
        let outputs: Vec<CaseOutput> = chunk
            .par_iter()
            .map(|&k| run_reference(study, k))
            .collect::<Result<_, _>>()?;
        for (i, output) in outputs.into_iter().enumerate() {
            take(g * group.max(1) + i, output)?;
        }
    }
    Ok(())
}

/// The references the workers share: the most recently used ones, at most
/// `capacity`, each made on the first worker that needs it.
pub(super) struct ReferenceCache<'a> {
    study: &'a Study,
    capacity: usize,
    /// `(index, reference)`, the most recently used last.
    kept: Mutex<Vec<(usize, Arc<CaseOutput>)>>,
}

impl<'a> ReferenceCache<'a> {
    /// A cache for the references of `study` run on `jobs` workers, as large as the
    /// memory estimate counts ([`reference_cache_entries`]).
    pub(super) fn new(study: &'a Study, jobs: usize) -> Self {
        let bytes = (CHANNELS.len() + 1) as f64 * 8.0 * study.sampling.len() as f64;
        let capacity = reference_cache_entries(study.references.len() as u64, jobs, bytes);
        Self {
            study,
            capacity: capacity.max(1) as usize,
            kept: Mutex::new(Vec::new()),
        }
    }

    /// Reference `index`, from the cache or made now. Two workers missing the same
    /// reference at once both make it (the same bits); the lock is never held while
    /// one is made.
    pub(super) fn get(&self, index: usize) -> Result<Arc<CaseOutput>, RunError> {
        {
            let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(at) = kept.iter().position(|(k, _)| *k == index) {
                let entry = kept.remove(at);
                let reference = Arc::clone(&entry.1);
                kept.push(entry);
                return Ok(reference);
            }
        }
        let reference = Arc::new(run_reference(self.study, index)?);
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        if !kept.iter().any(|(k, _)| *k == index) {
            if kept.len() >= self.capacity {
                kept.remove(0);
            }
            kept.push((index, Arc::clone(&reference)));
        }
        Ok(reference)
    }
}

/// Every ideal reference `study` holds, in id order, run in parallel and all held:
/// for the accuracy study, which compares each integrator with them (a whole study,
/// whose reference `k` is the `k`-th).
pub(crate) fn run_references(study: &Study) -> Result<Vec<CaseOutput>, RunError> {
    study
        .references
        .par_iter()
        .map(|r| run_reference(study, r.id))
        .collect()
}
