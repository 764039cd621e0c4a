//! What HDF5 does not checksum in a study file, checked against what it must be.
//!
//! HDF5 checksums every chunk (Fletcher-32) but neither the index that finds them (a
//! version 1 B-tree) nor a variable's datatype. A damaged index can lose a chunk,
//! which then reads as the fill value without an error: [`check_chunks`] looks up
//! every chunk the file must hold (one B-tree lookup each,
//! `H5Dget_chunk_storage_size`) and refuses one the index lacks. A damaged datatype
//! (an exponent bias, a byte order) converts intact bytes into other numbers:
//! [`check_numeric_type`] accepts only the standard little-endian types.

use std::collections::HashMap;

use hdf5::{Dataset, Datatype, File, H5Type};
use hdf5_sys::h5::{herr_t, hsize_t};
use hdf5_sys::h5i::hid_t;

use super::datasets::RowDatasets;
use super::layout::{Layout, Status};

extern "C" {
    /// HDF5 ≥ 1.10.2 (`H5Dpublic.h`), not bound by `hdf5-metno-sys`: the stored size
    /// of the chunk at `offset`, an error if the index holds none there.
    fn H5Dget_chunk_storage_size(
        dset_id: hid_t,
        offset: *const hsize_t,
        chunk_bytes: *mut hsize_t,
    ) -> herr_t;
}

/// Where a dataset's chunks must exist.
enum Written {
    /// Every chunk (coordinates, parameters, anything written when the file is made).
    Always,
    /// The chunks holding a row (of the first dimension) for which the flag is true.
    Rows(Vec<bool>),
}

/// Looks up every chunk of `ds` (named `name`) that `written` requires; an error names
/// the first the index lacks.
fn check_dataset(ds: &Dataset, name: &str, written: &Written) -> Result<(), String> {
    let Some(chunk) = ds.chunk() else {
        return Ok(());
    };
    let shape = ds.shape();
    let counts: Vec<usize> = shape
        .iter()
        .zip(&chunk)
        .map(|(&n, &c)| n.div_ceil(c.max(1)))
        .collect();
    let total: usize = counts.iter().product();
    let mut coordinate = vec![0 as hsize_t; shape.len()];
    for index in 0..total {
        let mut rest = index;
        for d in (0..shape.len()).rev() {
            coordinate[d] = ((rest % counts[d]) * chunk[d]) as hsize_t;
            rest /= counts[d];
        }
        let required = match written {
            Written::Always => true,
            Written::Rows(rows) => {
                let first = coordinate.first().map_or(0, |&c| c as usize);
                let end = (first + chunk.first().copied().unwrap_or(1)).min(rows.len());
                rows[first.min(end)..end].iter().any(|&r| r)
            }
        };
        if required && !stored(ds, &coordinate) {
            return Err(format!(
                "`{name}`: the chunk index has no chunk at {coordinate:?}, which the file's \
                 statuses say was written"
            ));
        }
    }
    Ok(())
}

/// Whether the index of `ds` holds a chunk at `coordinate`.
fn stored(ds: &Dataset, coordinate: &[hsize_t]) -> bool {
    let mut size: hsize_t = 0;
    // SAFETY: `ds.id()` is a valid dataset identifier owned by `ds`, which outlives the
    // call; `coordinate` has one entry per dimension of `ds` and lives for the call;
    // `size` is a plain integer the call writes. The call holds hdf5-metno's global
    // library lock (HDF5 is not thread-safe).
    let status = hdf5::sync::sync(|| unsafe {
        H5Dget_chunk_storage_size(ds.id(), coordinate.as_ptr(), &mut size)
    });
    status >= 0 && size > 0
}

/// Checks the chunk index of every chunked dataset of `file` whose case
/// rows have `statuses`: the rows of ok cases in every `[case, ...]` variable, those of
/// finished cases (ok or failed: their metrics and statuses were written) in the
/// metric variables, the references of ok cases, and every chunk of the rest.
pub(super) fn check_chunks(
    file: &File,
    layout: &Layout,
    rows: &RowDatasets,
    statuses: &[Status],
) -> Result<(), String> {
    let ok: Vec<bool> = statuses.iter().map(|s| *s == Status::Ok).collect();
    let finished: Vec<bool> = statuses.iter().map(|s| *s != Status::Pending).collect();
    let mut used = vec![false; layout.n_references()];
    for (case, &k) in layout.reference_index.iter().enumerate() {
        if ok.get(case) == Some(&true) {
            if let Some(u) = used.get_mut(k as usize) {
                *u = true;
            }
        }
    }
    let mut written: HashMap<String, Written> = HashMap::new();
    let mut mark = |datasets: &[Dataset], rows: &'_ [bool]| {
        for ds in datasets {
            written.insert(
                ds.name().trim_start_matches('/').to_owned(),
                Written::Rows(rows.to_vec()),
            );
        }
    };
    mark(&rows.series, &ok);
    mark(&rows.spectra, &ok);
    mark(&rows.kurtosis, &ok);
    mark(&rows.order_spectra, &ok);
    mark(&rows.metrics, &finished);
    mark(&rows.replicate_metrics, &finished);
    mark(&rows.revolution_metrics, &finished);
    mark(std::slice::from_ref(&rows.status), &finished);
    if let Some((status, _)) = &rows.replicates {
        mark(std::slice::from_ref(status), &finished);
    }
    mark(&rows.reference_series, &used);
    let names = file.member_names().map_err(|e| e.to_string())?;
    for name in names {
        let Ok(ds) = file.dataset(&name) else {
            continue;
        };
        let rule = written.remove(&name).unwrap_or(Written::Always);
        check_dataset(&ds, &name, &rule)?;
    }
    Ok(())
}

/// Checks that the numeric variable `ds` has one of the standard little-endian
/// datatypes studyrun and netCDF tools write (IEEE floats, two's-complement integers
/// of 1 to 8 bytes).
pub(super) fn check_numeric_type(ds: &Dataset) -> Result<(), String> {
    fn is<T: H5Type>(dtype: &Datatype) -> bool {
        Datatype::from_type::<T>().is_ok_and(|t| &t == dtype)
    }
    let dtype = ds.dtype().map_err(|e| e.to_string())?;
    let standard = is::<f64>(&dtype)
        || is::<f32>(&dtype)
        || is::<i8>(&dtype)
        || is::<u8>(&dtype)
        || is::<i16>(&dtype)
        || is::<u16>(&dtype)
        || is::<i32>(&dtype)
        || is::<u32>(&dtype)
        || is::<i64>(&dtype)
        || is::<u64>(&dtype);
    if standard {
        Ok(())
    } else {
        Err("its datatype is none of the standard little-endian floats and integers".into())
    }
}
