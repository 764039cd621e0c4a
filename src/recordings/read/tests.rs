//! [`read_samples`] end to end: the extension, the file checks, the selector kinds,
//! the empty and non-finite checks, the file named in every message, and files that
//! NumPy and SciPy wrote (`tests/data/recordings`, made by its `make.py`) read back
//! as the values they were given.

use std::path::{Path, PathBuf};

use super::fixtures::{bytes, file, npy, wav, PCM};
use super::*;

/// A fixture NumPy or SciPy wrote.
fn written(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/recordings")
        .join(name)
}

/// What `make.py` wrote: -1.0, -0.875, …, 0.875 and -8000, -7000, …, 7000.
fn x() -> Vec<f64> {
    (-8..8).map(|k| f64::from(k) / 8.0).collect()
}
fn n() -> Vec<f64> {
    (0..16).map(|k| f64::from(k * 1000 - 8000)).collect()
}

fn var(name: &str) -> Selector {
    Selector::Variable(name.into())
}

fn values(path: &Path, selector: &Selector) -> Vec<f64> {
    match read_samples(path, selector) {
        Ok(s) => s.values,
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn numpy_written_arrays_and_archives_read_back() {
    assert_eq!(values(&written("numpy_be_f4.npy"), &Selector::None), x());
    assert_eq!(
        values(&written("numpy_i2_column.npy"), &Selector::None),
        n()
    );
    for archive in ["numpy_stored.npz", "numpy_deflated.npz"] {
        assert_eq!(values(&written(archive), &var("a")), x(), "{archive}");
        assert_eq!(values(&written(archive), &var("b.npy")), n(), "{archive}");
    }
    let csv = written("numpy.csv");
    assert_eq!(
        values(&csv, &Selector::Column(ColumnRef::Name("n".into()))),
        n()
    );
    assert_eq!(values(&csv, &Selector::Column(ColumnRef::Index(0))), x());
}

#[test]
fn scipy_written_wav_files_read_back_scaled_with_their_rate() {
    let stereo = written("scipy_i16_stereo.wav");
    let left = read_samples(&stereo, &Selector::ChannelIndex(0)).unwrap();
    let scaled: Vec<f64> = n().iter().map(|v| v / 32768.0).collect();
    assert_eq!((left.values, left.sample_rate), (scaled, Some(12_000.0)));
    let right: Vec<f64> = n().iter().map(|v| (-v - 1.0) / 32768.0).collect();
    assert_eq!(values(&stereo, &Selector::ChannelIndex(1)), right);
    let float = read_samples(&written("scipy_f32.wav"), &Selector::None).unwrap();
    assert_eq!((float.values, float.sample_rate), (x(), Some(48_000.0)));
}

#[test]
fn scipy_written_mat_files_read_back() {
    let compressed = written("scipy_compressed.mat");
    assert_eq!(values(&compressed, &var("bearing.gs")), x());
    assert_eq!(values(&compressed, &var("bearing.n")), n());
    assert_eq!(values(&compressed, &var("bearing.sr")), [12_000.0]);
    let err = read_samples(&compressed, &var("label"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("`label` is a char array"), "{err}");
    let plain = written("scipy_plain.mat");
    assert_eq!(values(&plain, &var("acc")), x());
    assert_eq!(values(&plain, &var("n")), n());
    let err = read_samples(&plain, &Selector::None)
        .unwrap_err()
        .to_string();
    assert!(err.ends_with("choose a variable among acc, n"), "{err}");
}

#[test]
fn the_extension_chooses_the_format_whatever_its_case() {
    let dir = tempfile::tempdir().unwrap();
    let data = npy(
        1,
        "<f8",
        "(2,)",
        false,
        &bytes(&[1.5, -2.0], f64::to_le_bytes),
    );
    assert_eq!(
        values(&file(dir.path(), "a.NPY", &data), &Selector::None),
        [1.5, -2.0]
    );
    let err = read_samples(&file(dir.path(), "a.txt", &data), &Selector::None).unwrap_err();
    let a_txt = dir.path().join("a.txt");
    assert_eq!(
        err.to_string(),
        format!(
            "{}: unknown extension `.txt`; allowed: .npy, .npz, .wav, .csv, .h5, .hdf5, .nc, .mat",
            a_txt.display()
        )
    );
    let err = read_samples(&file(dir.path(), "a", &data), &Selector::None).unwrap_err();
    assert!(
        err.to_string().contains("unknown extension (none)"),
        "{err}"
    );
}

#[test]
fn missing_and_unreadable_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("or_007.mat");
    let err = read_samples(&missing, &Selector::None).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!("{}: no such file", missing.display())
    );
    let folder = dir.path().join("folder.csv");
    std::fs::create_dir(&folder).unwrap();
    let err = read_samples(&folder, &Selector::None).unwrap_err();
    assert!(matches!(err, ReadError::Unreadable { .. }), "{err}");
    assert!(
        err.to_string()
            .ends_with("folder.csv: cannot be read: is a directory"),
        "{err}"
    );
}

#[test]
fn a_selector_of_the_wrong_kind_says_what_the_format_takes() {
    let dir = tempfile::tempdir().unwrap();
    let wav_file = file(dir.path(), "a.wav", &wav(PCM, false, 1, 8000, 16, &[0; 2]));
    let err = read_samples(&wav_file, &var("DE")).unwrap_err().to_string();
    assert!(
        err.ends_with("a WAV file is selected by a channel index, not by variable `DE`"),
        "{err}"
    );
    let npy_file = file(dir.path(), "a.npy", &npy(1, "<f8", "(1,)", false, &[0; 8]));
    let err = read_samples(&npy_file, &Selector::ChannelIndex(0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("not by channel index 0"), "{err}");
    let csv_file = file(dir.path(), "a.csv", b"1\n");
    let err = read_samples(&csv_file, &var("x")).unwrap_err();
    assert!(matches!(err, ReadError::Selection { .. }), "{err}");
    let mat_file = file(dir.path(), "a.mat", b"");
    let err = read_samples(&mat_file, &Selector::Column(ColumnRef::Index(1))).unwrap_err();
    assert!(err.to_string().ends_with("not by column index 1"), "{err}");
}

#[test]
fn every_message_names_the_file_and_the_variable() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("or_007.mat");
    std::fs::copy(written("scipy_compressed.mat"), &path).unwrap();
    let err = read_samples(&path, &var("bearing.gx")).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "{}: no variable `bearing.gx`; it holds bearing.gs, bearing.sr, bearing.n, label",
            path.display()
        )
    );
}

#[test]
fn empty_and_non_finite_samples_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let header_only = file(dir.path(), "h.csv", b"DE\n");
    let err = read_samples(&header_only, &Selector::None).unwrap_err();
    assert!(
        err.to_string()
            .ends_with("h.csv: `DE` is empty (no samples)"),
        "{err}"
    );
    let nan = file(dir.path(), "nan.csv", b"DE\n1\n2\nnan\ninf\n");
    let err = read_samples(&nan, &Selector::None).unwrap_err();
    assert!(
        err.to_string()
            .ends_with("nan.csv: `DE`: sample 2 is NaN; every sample must be finite"),
        "{err}"
    );
    let inf = bytes(&[0.0, 1.0, 2.0, f64::NEG_INFINITY], f64::to_le_bytes);
    let inf = file(dir.path(), "inf.npy", &npy(1, "<f8", "(4,)", false, &inf));
    let err = read_samples(&inf, &Selector::None).unwrap_err();
    assert!(
        matches!(err, ReadError::NonFinite { index: 3, .. }),
        "{err}"
    );
    let empty = file(dir.path(), "e.npy", &npy(1, "<f8", "(0, 1)", false, &[]));
    let err = read_samples(&empty, &Selector::None).unwrap_err();
    assert!(matches!(err, ReadError::Empty { .. }), "{err}");
}
