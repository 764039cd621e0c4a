//! Study files: every case's time series, spectra, metrics and status in one HDF5 file
//! laid out netCDF-4 style (flat root group, named dimensions as HDF5 dimension scales,
//! CF attributes), so that `xarray.open_dataset(path, engine="h5netcdf")` gives named
//! dimensions, coordinates and units without `phony_dims`.
//!
//! | variable | dims | dtype | units | written |
//! |---|---|---|---|---|
//! | `case` | `[case]` | i32 | `1` | at create: global case ids (any distinct values up to [`MAX_ID`]) |
//! | `time` | `[time]` | f64 | `s` | at create: sample times |
//! | `frequency` | `[frequency]` | f64 | `Hz` | at create: spectrum bin frequencies |
//! | `reference` | `[reference]` | i32 | `1` | at create: reference (ideal mechanism) run ids |
//! | *parameter* | `[case]` | f64 or string | caller's | at create |
//! | `reference_index` | `[case]` | i32 | `1` | at create: `reference` row each case is compared with |
//! | `status` | `[case]` | i8 | `1` | per case: `flag_values` `[0, 1, 2]`, `flag_meanings` `pending ok failed`; fill 0 |
//! | `error_message` | `[case]` | string | `1` | per case: why it failed, empty otherwise |
//! | *metric* | `[case]` | f64 | caller's | per case; fill NaN |
//! | `order` | `[order]` | f64 | `1` | at create, with order spectra: bin orders (cycles per crank revolution) |
//! | *order spectrum* | `[case, order]` | f64 | caller's | per case, whole-row chunks; fill NaN |
//! | *series* | `[case, time]` | f64 or f32 | caller's | per case; fill NaN |
//! | *spectrum* | `[case, frequency]` | f64 or f32 | caller's | per case; fill NaN |
//! | *reference parameter* | `[reference]` | f64 or string | caller's | at create |
//! | *reference series* | `[reference, time]` | f64 or f32 | caller's | per reference; fill NaN |
//!
//! Variables appear in the file (and in xarray) in this order. Every variable has the
//! string attributes `units` and `long_name`; caller variables also `studyrun_role`
//! (`parameter`, `metric`, `series`, `spectrum`, `reference_parameter`,
//! `reference_series`), from which [`StudyReader::layout`] rebuilds the [`Layout`].
//! Float variables filled with NaN carry `_FillValue = NaN` of their own type. Strings
//! are variable-length UTF-8. The coordinate variables are the dimension scales and
//! carry netCDF-C's `_Netcdf4Dimid`.
//!
//! The ids are int32 because CF-1.8 has no 64-bit or unsigned integers; a layout with
//! an id above [`MAX_ID`] is refused at create. Older files with u64 ids read as well.
//!
//! Root attributes: `studyrun_file_format` = 1 (i64, marks a study file) and the
//! caller's [`Layout::attributes`] in order (strings, f64 or i64); [`provenance`] gives
//! `Conventions`, `studyrun_version`, `git_commit`, `created` (RFC 3339) and `history`
//! (CF §2.6.2: `<time>: studyrun <arguments>`, newest line first; [`merge`] puts its
//! line on top of the first shard's). `history` is netCDF's NC_CHAR (a fixed-length
//! string), the type NCO appends to; every other string is variable-length UTF-8.
//!
//! Interoperability: netCDF tools rewrite what they touch (`ncatted` writes NC_CHAR,
//! `nccopy -k nc4`, `ncks` and xarray make every attribute a one-element array and add
//! `_NCProperties`, `_Netcdf4Coordinates`, `_Netcdf4Dimid`; `ncks` sorts the variables
//! by name). [`StudyReader`] reads such files: strings of any kind (variable- or
//! fixed-length, any character set, NUL padding stripped, a NULL dataspace as ""), any
//! one-element dataspace as a scalar; it skips root attributes starting with `_` and
//! root attributes that are neither a string nor a number (arrays). [`merge`] matches
//! the shards' variables by name. A damaged file is an error, never a crash: strings
//! are read without letting libhdf5 follow them into the file (`text`), and the reads
//! are first done in a child process (`guard`), see [`StudyReader`].
//!
//! Storage: `[case, time]`, `[case, frequency]` and `[reference, time]` arrays are
//! chunked one row per chunk (chunk shape `(1, len)`), so writing or reading a case
//! touches one chunk per variable; with a deflate level above 0 they carry the shuffle and deflate (gzip)
//! filters, with level 0 none. Rows are encoded by a [`ChunkEncoder`] (on any thread)
//! and written with HDF5's direct chunk write; readers inflate them like chunks HDF5
//! deflated itself. The other arrays (1-D, `[case, replicate]`, `[case, revolution]`,
//! `[case, order]`) are written whole, in uncompressed chunks of whole rows. Every
//! numeric variable carries the Fletcher-32 checksum filter.
//! Link and attribute creation order are tracked, as netCDF-4 does.
//!
//! `crate::study::study_layout` gives the layout of a study's file, [`merge`] combines shard files
//! and [`inspect`] summarises one.

mod attributes;
mod datasets;
mod dimension_scales;
mod direct_chunk;
mod encode;
mod error;
mod guard;
mod inspect;
mod layout;
mod lock;
mod merge;
pub mod overwrite;
mod paths;
mod reader;
mod reserve;
mod shuffle;
mod structure;
mod text;
mod writeback;
mod writer;

pub use dimension_scales::ScaleError;
pub use encode::ChunkEncoder;
pub use error::{OutputError, StudyFileError};
pub use inspect::{inspect, verify, Summary};
pub use layout::{
    command_line, history_line, provenance, shell_word, AttrValue, Layout, Param, ParamValues,
    Status, Storage, VarSpec, CASE, ERROR_MESSAGE, FREQUENCY, MAX_ID, ORDER, REFERENCE,
    REFERENCE_INDEX, REPLICATE, REVOLUTION, STATUS, TIME, TIME_UNITS,
};
pub use lock::OutputLock;
pub use merge::merge;
pub use paths::{
    new_journal_path, remove_durably, rename_durably, side_paths, sync_file, sync_parent,
    with_suffix, DataFile,
};
pub use reader::{CaseData, StudyReader};
pub use writer::{CaseRecord, EncodedRecord, Record, StudyWriter};
