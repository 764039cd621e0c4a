//! HDF5 files, netCDF-4 files (which are HDF5) and MATLAB v7.3 MAT-files (HDF5
//! with a 512-byte user block), read through libhdf5.
//!
//! A variable is a dataset path (`DE`, `group/DE`); any integer or float dataset of
//! one column is read, converted to `f64` by libhdf5. Without a variable the file's
//! only numeric dataset is read. MATLAB's bookkeeping groups `#refs#` and
//! `#subsystem#` are not searched.

use std::path::Path;

use hdf5::types::TypeDescriptor;
use hdf5::{Dataset, File, Group};

use super::bytes::inflated_bound;
use super::{listed, Fault, Loaded, ReadError};

/// Groups nested deeper than this are not searched (a hard link may close a cycle).
const MAX_DEPTH: usize = 32;

/// The first bytes of a netCDF-3 (classic, 64-bit offset, 64-bit data) file.
const NETCDF3: [&[u8]; 3] = [b"CDF\x01", b"CDF\x02", b"CDF\x05"];

/// Reads dataset `variable` of the HDF5 file at `path` (its only numeric dataset
/// when `None`).
pub(super) fn read(path: &Path, variable: Option<&str>) -> Result<Loaded, ReadError> {
    let at = |f: Fault| f.at(path);
    let hdf5_error = |name: &str, source| ReadError::Hdf5 {
        path: path.to_owned(),
        name: name.to_string(),
        source,
    };
    let file = File::open(path).map_err(|e| match opening_fault(path, &e) {
        Some(f) => at(f),
        None => hdf5_error("/", e),
    })?;
    let (name, ds) = match variable {
        Some(v) => {
            let v = v.trim_start_matches('/');
            let ds = file.dataset(v).map_err(|_| {
                let held = datasets(&file).unwrap_or_default();
                at(Fault::Select(format!(
                    "no dataset `{v}`; it holds {}",
                    listed(&held)
                )))
            })?;
            (v.to_string(), ds)
        }
        None => only_numeric(&file, path)?,
    };
    let dtype = ds.dtype().and_then(|t| t.to_descriptor());
    match dtype.map_err(|e| hdf5_error(&name, e))? {
        TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) | TypeDescriptor::Float(_) => {}
        other => {
            return Err(at(Fault::Unsupported(format!(
                "`{name}` is of type {other}; integer and float datasets are read"
            ))))
        }
    }
    let shape = ds.shape();
    let n = match shape[..] {
        [n] | [n, 1] | [1, n] => n,
        _ => {
            let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
            let shape = format!("({})", dims.join(", "));
            return Err(at(Fault::Shape(name, shape)));
        }
    };
    let file_len = std::fs::metadata(path).map_or(0, |m| m.len());
    stored(&ds, &name, n, file_len).map_err(at)?;
    let values = ds.read_raw::<f64>().map_err(|e| hdf5_error(&name, e))?;
    Ok(Loaded {
        name,
        values,
        sample_rate: None,
    })
}

/// Refuses a dataset of `n` elements whose stored bytes (at most the file's
/// `file_len`) cannot hold them, even deflated: libhdf5 would allocate its declared
/// size and fill what is not stored with the fill value.
fn stored(ds: &Dataset, name: &str, n: usize, file_len: u64) -> Result<(), Fault> {
    let bytes = ds.storage_size().min(file_len);
    if n > 0 && bytes == 0 {
        return Err(Fault::Corrupt(format!(
            "`{name}` declares {n} elements but stores no data (it was never written)"
        )));
    }
    let element = ds.dtype().map_or(1, |t| t.size()).max(1);
    let bound = inflated_bound(usize::try_from(bytes).unwrap_or(usize::MAX));
    if n.saturating_mul(element) > bound {
        return Err(Fault::Corrupt(format!(
            "`{name}` declares {n} elements of {element} bytes, more than its {bytes} stored bytes can hold"
        )));
    }
    Ok(())
}

/// What to say when libhdf5 cannot open the file: not HDF5 at all, or netCDF-3.
fn opening_fault(path: &Path, error: &hdf5::Error) -> Option<Fault> {
    if !error.to_string().contains("signature") {
        return None;
    }
    let mut head = [0; 4];
    let netcdf3 = std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok()
        && NETCDF3.contains(&&head[..]);
    Some(if netcdf3 {
        Fault::Unsupported(
            "a netCDF-3 (classic) file; netCDF-4 files, which are HDF5, are read".into(),
        )
    } else {
        Fault::Corrupt("not an HDF5 file (no HDF5 signature)".into())
    })
}

/// The file's only integer or float dataset, or an error listing them all.
fn only_numeric(file: &File, path: &Path) -> Result<(String, Dataset), ReadError> {
    let hdf5_error = |source| ReadError::Hdf5 {
        path: path.to_owned(),
        name: "/".into(),
        source,
    };
    let names = datasets(file).map_err(hdf5_error)?;
    let mut numeric = Vec::new();
    for name in &names {
        let ds = file.dataset(name).map_err(hdf5_error)?;
        let kind = ds
            .dtype()
            .and_then(|t| t.to_descriptor())
            .map_err(hdf5_error)?;
        if matches!(
            kind,
            TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) | TypeDescriptor::Float(_)
        ) {
            numeric.push((name.clone(), ds));
        }
    }
    if numeric.len() == 1 {
        return Ok(numeric.remove(0));
    }
    let what = match numeric.len() {
        0 => "no numeric dataset".to_string(),
        n => format!("{n} numeric datasets"),
    };
    let reason = format!("{what}; choose a variable among {}", listed(&names));
    Err(Fault::Select(reason).at(path))
}

/// The paths of every dataset in the file, without the leading `/`.
fn datasets(file: &File) -> hdf5::Result<Vec<String>> {
    let mut out = Vec::new();
    collect(file, 0, &mut out)?;
    Ok(out)
}

/// Appends the datasets of `group` and its subgroups to `out`.
fn collect(group: &Group, depth: usize, out: &mut Vec<String>) -> hdf5::Result<()> {
    for ds in group.datasets()? {
        out.push(ds.name().trim_start_matches('/').to_string());
    }
    if depth >= MAX_DEPTH {
        return Ok(());
    }
    for g in group.groups()? {
        let name = g.name();
        let last = name.rsplit('/').next().unwrap_or_default();
        if last != "#refs#" && last != "#subsystem#" {
            collect(&g, depth + 1, out)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes `name` as `shape` holding `values` into `file`.
    fn dataset<T: hdf5::H5Type>(file: &Group, name: &str, shape: &[usize], values: &[T]) {
        file.new_dataset::<T>()
            .shape(shape)
            .create(name)
            .and_then(|ds| ds.write_raw(values))
            .unwrap();
    }

    /// A file with `DE` (f64, N), `g/FE` (i16, N x 1), `row` (f32, 1 x N), `m` (2 x 3).
    fn fixture(dir: &Path) -> std::path::PathBuf {
        let path = dir.join("rig.h5");
        let file = File::create(&path).unwrap();
        dataset(&file, "DE", &[4], &[0.5, -1.25, 3.0, 1e-9]);
        let g = file.create_group("g").unwrap();
        dataset(&g, "FE", &[3, 1], &[-32768i16, 0, 32767]);
        dataset(&file, "row", &[1, 2], &[0.25f32, -8.0]);
        dataset(&file, "m", &[2, 3], &[1.0; 6]);
        path
    }

    #[test]
    fn float_and_integer_datasets_of_one_column_read_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = fixture(dir.path());
        let de = read(&path, Some("DE")).unwrap();
        assert_eq!(
            (de.name.as_str(), de.values),
            ("DE", vec![0.5, -1.25, 3.0, 1e-9])
        );
        assert_eq!(
            read(&path, Some("g/FE")).unwrap().values,
            [-32768.0, 0.0, 32767.0]
        );
        assert_eq!(
            read(&path, Some("/g/FE")).unwrap().values,
            [-32768.0, 0.0, 32767.0]
        );
        assert_eq!(read(&path, Some("row")).unwrap().values, [0.25, -8.0]);
    }

    #[test]
    fn a_missing_dataset_or_no_variable_lists_the_datasets() {
        let dir = tempfile::tempdir().unwrap();
        let path = fixture(dir.path());
        let err = read(&path, Some("g/DE")).unwrap_err().to_string();
        assert!(
            err.ends_with("no dataset `g/DE`; it holds DE, m, row, g/FE"),
            "{err}"
        );
        let err = read(&path, None).unwrap_err().to_string();
        assert!(
            err.ends_with("4 numeric datasets; choose a variable among DE, m, row, g/FE"),
            "{err}"
        );
        let one = dir.path().join("one.nc");
        dataset(&File::create(&one).unwrap(), "x", &[2], &[1u8, 2]);
        assert_eq!(read(&one, None).unwrap().values, [1.0, 2.0]);
    }

    #[test]
    fn a_dataset_never_written_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("unwritten.h5");
        let file = File::create(&path).unwrap();
        file.new_dataset::<f64>().shape(1000).create("DE").unwrap();
        drop(file);
        let err = read(&path, Some("DE")).unwrap_err().to_string();
        assert!(
            err.ends_with("`DE` declares 1000 elements but stores no data (it was never written)"),
            "{err}"
        );
    }

    #[test]
    fn a_table_is_refused_naming_its_shape() {
        let dir = tempfile::tempdir().unwrap();
        let err = read(&fixture(dir.path()), Some("m")).unwrap_err();
        assert!(
            matches!(err, ReadError::Shape { ref shape, .. } if shape == "(2, 3)"),
            "{err}"
        );
    }

    #[test]
    fn files_that_are_not_hdf5_are_named_as_such() {
        let dir = tempfile::tempdir().unwrap();
        let text = dir.path().join("text.h5");
        std::fs::write(&text, "time,DE\n").unwrap();
        let err = read(&text, Some("DE")).unwrap_err();
        assert!(err.to_string().contains("not an HDF5 file"), "{err}");
        let classic = dir.path().join("classic.nc");
        std::fs::write(&classic, b"CDF\x01\0\0\0\0").unwrap();
        let err = read(&classic, None).unwrap_err();
        assert!(matches!(err, ReadError::Unsupported { .. }), "{err}");
        assert!(err.to_string().contains("netCDF-3"), "{err}");
    }

    #[test]
    fn a_mat_v73_file_reads_struct_fields_through_hdf5() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("v73.mat");
        let file = File::with_options()
            .with_fcpl(|p| p.userblock(512))
            .create(&path)
            .unwrap();
        let bearing = file.create_group("bearing").unwrap();
        // MATLAB stores an N x 1 column as an HDF5 dataset of shape (1, N).
        dataset(&bearing, "gs", &[1, 3], &[0.5, 0.25, -1.0]);
        drop((bearing, file));
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[..19].copy_from_slice(b"MATLAB 7.3 MAT-file");
        std::fs::write(&path, bytes).unwrap();
        let selector = super::super::Selector::Variable("bearing.gs".into());
        let samples = super::super::read_samples(&path, &selector).unwrap();
        assert_eq!(samples.values, [0.5, 0.25, -1.0]);
    }
}
