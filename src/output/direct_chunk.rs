//! HDF5's direct chunk write (`H5Dwrite_chunk`, HDF5 ≥ 1.10.3, bound by
//! `hdf5-metno-sys`): a chunk's stored bytes, already filtered by the caller (see
//! [`ChunkEncoder`](super::ChunkEncoder)), go into the file as they are, past HDF5's
//! filter pipeline and chunk cache.

use hdf5::Dataset;
use hdf5_sys::h5::hsize_t;
use hdf5_sys::h5d::H5Dwrite_chunk;
use hdf5_sys::h5p::H5P_DEFAULT;

/// Filter mask of a chunk that went through every filter of its dataset's pipeline.
const ALL_FILTERS_APPLIED: u32 = 0;

/// Whether `ds` is a 2-D dataset chunked one row per chunk, as [`write_row_chunk`]
/// needs.
pub(super) fn chunked_by_row(ds: &Dataset) -> bool {
    let shape = ds.shape();
    matches!((ds.chunk().as_deref(), shape.as_slice()), (Some([1, c]), [_, n]) if c == n)
}

/// Writes `bytes` as the stored chunk of row `row` of `ds`, a 2-D dataset chunked one
/// row per chunk (see [`chunked_by_row`]; the caller checks it once). The bytes must be
/// what the dataset's filters (all of them) make of the row.
pub(super) fn write_row_chunk(ds: &Dataset, row: usize, bytes: &[u8]) -> hdf5::Result<()> {
    let offset: [hsize_t; 2] = [row as hsize_t, 0];
    let id = ds.id();
    // SAFETY: `id` is a valid dataset identifier owned by `ds`, which outlives the
    // call; `offset` holds one coordinate per dimension (rank 2, checked by the caller) and
    // lives for the call; `bytes` is valid for `bytes.len()` bytes and HDF5 only reads
    // it. The call holds hdf5-metno's global library lock (HDF5 is not thread-safe).
    let status = hdf5::sync::sync(|| unsafe {
        H5Dwrite_chunk(
            id,
            H5P_DEFAULT,
            ALL_FILTERS_APPLIED,
            offset.as_ptr(),
            bytes.len(),
            bytes.as_ptr().cast(),
        )
    });
    hdf5::h5check(status).map(|_| ())
}
