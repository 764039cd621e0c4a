//! HDF5 dimension scales (`H5DS*` of HDF5's high-level library, linked through `hdf5-metno-sys`'s `hl` feature):
//! what netCDF-4 readers (netCDF-C, h5netcdf, xarray) use to name the dimensions of a
//! dataset. A 1-D coordinate variable is made a scale with [`set_scale`] and attached to
//! each dimension of each data variable along it with [`attach_scale`].
//!
//! `unsafe` code of the output module lives here, in `direct_chunk`, `attributes`
//! (NC_CHAR), `text` (strings) and `guard` (fork).

use std::ffi::{c_char, c_int, c_uint, CString};

use hdf5::Dataset;

/// HDF5's `hid_t`: `int64_t` since HDF5 1.10. `Object::id()` of `hdf5-metno` returns its
/// `hid_t`; handing that value to these bindings checks the width at compile time.
type Hid = i64;
/// HDF5's `herr_t`: negative on failure.
type Herr = c_int;

extern "C" {
    /// `herr_t H5DSset_scale(hid_t dsid, const char *dimname)`.
    fn H5DSset_scale(dsid: Hid, dimname: *const c_char) -> Herr;
    /// `herr_t H5DSattach_scale(hid_t did, hid_t dsid, unsigned int idx)`.
    fn H5DSattach_scale(did: Hid, dsid: Hid, idx: c_uint) -> Herr;
}

/// What can go wrong with a dimension scale.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ScaleError {
    /// The dimension name contains a NUL byte.
    #[error("dimension name {0:?} contains a NUL byte")]
    Name(String),
    /// The dimension index is not below the dataset's rank.
    #[error("cannot attach scale {scale} to dimension {idx} of {dataset}: it has rank {rank}")]
    Rank {
        /// Dataset the scale was to be attached to (HDF5 path).
        dataset: String,
        /// Scale dataset (HDF5 path).
        scale: String,
        /// Dimension index asked for.
        idx: usize,
        /// The dataset's number of dimensions.
        rank: usize,
    },
    /// The HDF5 call returned a negative status.
    #[error("{call} failed on {dataset}")]
    Hdf5 {
        /// `H5DSset_scale` or `H5DSattach_scale`.
        call: &'static str,
        /// Dataset concerned (HDF5 path).
        dataset: String,
    },
}

/// Makes the 1-D dataset `scale` a dimension scale named `name` (for a netCDF
/// coordinate variable the name is the variable's own name).
pub fn set_scale(scale: &Dataset, name: &str) -> Result<(), ScaleError> {
    let c_name = CString::new(name).map_err(|_| ScaleError::Name(name.to_owned()))?;
    let id: Hid = scale.id();
    // SAFETY: `id` is a valid dataset identifier owned by `scale`, which outlives the
    // call; `c_name` is a NUL-terminated string alive for the call. HDF5 is not
    // thread-safe, so the call holds hdf5-metno's global library lock, as every
    // hdf5-metno call does.
    let status = hdf5::sync::sync(|| unsafe { H5DSset_scale(id, c_name.as_ptr()) });
    if status < 0 {
        return Err(ScaleError::Hdf5 {
            call: "H5DSset_scale",
            dataset: scale.name(),
        });
    }
    Ok(())
}

/// Attaches the dimension scale `scale` to dimension `idx` (0-based) of `data`.
pub fn attach_scale(data: &Dataset, scale: &Dataset, idx: usize) -> Result<(), ScaleError> {
    let rank = data.ndim();
    let c_idx = c_uint::try_from(idx)
        .ok()
        .filter(|_| idx < rank)
        .ok_or_else(|| ScaleError::Rank {
            dataset: data.name(),
            scale: scale.name(),
            idx,
            rank,
        })?;
    let (did, dsid): (Hid, Hid) = (data.id(), scale.id());
    // SAFETY: both identifiers are valid dataset identifiers owned by `data` and
    // `scale`, which outlive the call; `c_idx` is below the rank of `data` (checked
    // above). The call holds hdf5-metno's global library lock (HDF5 is not thread-safe).
    let status = hdf5::sync::sync(|| unsafe { H5DSattach_scale(did, dsid, c_idx) });
    if status < 0 {
        return Err(ScaleError::Hdf5 {
            call: "H5DSattach_scale",
            dataset: data.name(),
        });
    }
    Ok(())
}
