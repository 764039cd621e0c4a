//! Study files: a synthetic study written out of order and read back bit for bit;
//! float32 storage; chunking and filters; resuming; errors naming file and variable.
//! `synthetic_file_for_python` leaves `target/test-files/synthetic_study.h5` for
//! `tests/python/test_study_file.py`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use hdf5::filters::Filter;
use studyrun::output::{
    provenance, AttrValue, CaseRecord, ChunkEncoder, EncodedRecord, Layout, Param, ParamValues,
    Status, Storage, StudyFileError, StudyReader, StudyWriter, VarSpec,
};
use studyrun::signal::spectrum::{frequencies, SpectrumPlan, Window};
use studyrun::simulate::CHANNELS;

use crate::common::{bits, create_unlocked};

const N_TIME: usize = 1001;
const SAMPLE_RATE: f64 = 1000.0;
const CASE_IDS: [u64; 6] = [3, 5, 7, 9, 11, 13];
/// The order rows are written in; row 3 is never written, row 5 fails.
const WRITE_ORDER: [usize; 5] = [4, 0, 5, 2, 1];
const UNWRITTEN: usize = 3;
const FAILED: usize = 5;
/// The grid of the two f64 parameters (3 ball counts × 2 speeds), for xarray's unstack.
const BALLS: [f64; 6] = [8.0, 9.0, 10.0, 8.0, 9.0, 10.0];
const RPM: [f64; 6] = [300.0, 300.0, 300.0, 600.0, 600.0, 600.0];

fn synthetic_layout(storage: Storage) -> Layout {
    let mut attributes = provenance();
    attributes.extend([
        (
            "grid_yaml".to_owned(),
            AttrValue::from("ball_count: [8, 9, 10]\nrpm: [300, 600]\nwaviness: 4 µm\n"),
        ),
        ("solver_rtol".to_owned(), AttrValue::F64(1e-8)),
        ("threads".to_owned(), AttrValue::I64(2)),
    ]);
    let channel =
        |i: usize| VarSpec::new(CHANNELS[i].name, CHANNELS[i].units, CHANNELS[i].long_name);
    Layout {
        case_ids: CASE_IDS.to_vec(),
        times: (0..N_TIME).map(|k| k as f64 / SAMPLE_RATE).collect(),
        frequencies: frequencies(N_TIME, SAMPLE_RATE),
        reference_ids: vec![100, 101],
        series: (0..3).map(channel).collect(),
        spectra: (0..2)
            .map(|i| {
                let c = channel(i);
                VarSpec::new(
                    format!("{}_spectrum", c.name),
                    c.units,
                    format!("amplitude spectrum of {}", c.long_name),
                )
            })
            .collect(),
        metrics: vec![
            VarSpec::new(
                "slider_acceleration_rms_deviation",
                "m s-2",
                "RMS deviation of the slider acceleration from the ideal mechanism",
            ),
            VarSpec::new(
                "slider_acceleration_peak_deviation",
                "m s-2",
                "peak deviation of the slider acceleration from the ideal mechanism",
            ),
            VarSpec::new("wall_time", "s", "wall-clock time of the run"),
            VarSpec::new("rhs_evaluations", "1", "right-hand-side evaluations"),
        ],
        parameters: vec![
            Param {
                spec: VarSpec::new("ball_count", "1", "number of balls"),
                values: ParamValues::F64(BALLS.to_vec()),
            },
            Param {
                spec: VarSpec::new("rpm", "min-1", "crank speed"),
                values: ParamValues::F64(RPM.to_vec()),
            },
            Param {
                spec: VarSpec::new("location", "1", "bearing location"),
                values: ParamValues::Str(
                    [
                        "crank_ground",
                        "crank_rod",
                        "crank_ground",
                        "crank_rod",
                        "crank_ground",
                        "crank_rod",
                    ]
                    .map(String::from)
                    .to_vec(),
                ),
            },
        ],
        replicates: Vec::new(),
        replicate_metrics: Vec::new(),
        revolutions: Vec::new(),
        revolution_metrics: Vec::new(),
        orders: Vec::new(),
        order_spectra: Vec::new(),
        sk_frequencies: Vec::new(),
        kurtosis: Vec::new(),
        reference_parameters: vec![
            Param {
                spec: VarSpec::new("reference_rpm", "min-1", "crank speed of the reference run"),
                values: ParamValues::F64(vec![300.0, 600.0]),
            },
            Param {
                spec: VarSpec::new("reference_kind", "1", "what the reference run is"),
                values: ParamValues::Str(vec!["ideal".into(), "ideal ✓".into()]),
            },
        ],
        reference_series: vec![VarSpec::new(
            "reference_slider_acceleration",
            "m s-2",
            "slider acceleration of the reference run",
        )],
        reference_index: RPM.iter().map(|&r| u64::from(r > 450.0)).collect(),
        attributes,
        storage,
    }
}

/// Deterministic case data: smooth signals with a little pseudo-random noise (so that
/// compression sees realistic mantissas), their spectra, and metrics.
struct Synthetic {
    series: Vec<Vec<f64>>,
    spectra: Vec<Vec<f64>>,
    metrics: Vec<f64>,
}

fn synthetic_case(row: usize, plan: &mut SpectrumPlan) -> Synthetic {
    let mut state = 0x9e37_79b9_7f4a_7c15_u64 ^ row as u64;
    let mut noise = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let omega = std::f64::consts::TAU * RPM[row] / 60.0;
    let series: Vec<Vec<f64>> = (0..3)
        .map(|i| {
            (0..N_TIME)
                .map(|k| {
                    let t = k as f64 / SAMPLE_RATE;
                    let amp = 10f64.powi(i) * (1.0 + row as f64);
                    amp * ((i + 1) as f64 * omega * t).sin() + 1e-3 * amp * noise()
                })
                .collect()
        })
        .collect();
    let spectra = series[..2]
        .iter()
        .map(|s| {
            let mut out = vec![0.0; plan.bins()];
            plan.amplitude(s, &mut out).unwrap();
            out
        })
        .collect();
    Synthetic {
        series,
        spectra,
        metrics: vec![
            1.5 * row as f64 + 0.1,
            2.5 + row as f64,
            0.3,
            1e5 + row as f64,
        ],
    }
}

fn reference_row(row: usize) -> Vec<f64> {
    (0..N_TIME)
        .map(|k| ((row + 1) as f64 * k as f64 * 1e-3).cos())
        .collect()
}

/// Writes the synthetic study to `path`; returns the raw bytes of series and spectra
/// written and the seconds spent in `write_case`/`write_reference`/`finish`.
fn write_synthetic(path: &Path, storage: Storage) -> (usize, f64) {
    let layout = synthetic_layout(storage);
    let mut writer = StudyWriter::create(path, &layout).unwrap();
    let mut plan = SpectrumPlan::new(N_TIME, Window::Hann).unwrap();
    let mut raw = 0;
    let mut seconds = 0.0;
    for row in WRITE_ORDER {
        let case = synthetic_case(row, &mut plan);
        let series: Vec<&[f64]> = case.series.iter().map(Vec::as_slice).collect();
        let spectra: Vec<&[f64]> = case.spectra.iter().map(Vec::as_slice).collect();
        let record = if row == FAILED {
            CaseRecord {
                series: &[],
                spectra: &[],
                metrics: &[],
                status: Status::Failed,
                message: "step size underflow at t = 0.123 s",
                replicate_messages: &[],
            }
        } else {
            raw += 8 * (series.len() * N_TIME + spectra.len() * plan.bins());
            CaseRecord {
                series: &series,
                spectra: &spectra,
                metrics: &case.metrics,
                status: Status::Ok,
                message: "",
                replicate_messages: &[],
            }
        };
        let start = Instant::now();
        writer.write_case(row, &record).unwrap();
        seconds += start.elapsed().as_secs_f64();
    }
    for row in 0..2 {
        let r = reference_row(row);
        let start = Instant::now();
        writer.write_reference(row, &[&r]).unwrap();
        seconds += start.elapsed().as_secs_f64();
        raw += 8 * N_TIME;
    }
    let start = Instant::now();
    writer.finish().unwrap();
    seconds += start.elapsed().as_secs_f64();
    (raw, seconds)
}

/// Checks every row of the file at `path` against the synthetic data, with values
/// passed through `stored` (identity for float64, rounding for float32).
fn check_contents(path: &Path, storage: Storage, stored: fn(f64) -> f64) {
    let reader = StudyReader::open(path).unwrap();
    let layout = synthetic_layout(storage);
    let mut got = reader.layout().clone();
    // `created` and `history` (which starts with the same time) differ between two
    // calls of provenance() a second apart; everything else must match.
    for name in ["created", "history"] {
        let at = |l: &Layout| l.attributes.iter().position(|(n, _)| n == name).unwrap();
        let (i, j) = (at(&got), at(&layout));
        assert_eq!(i, j);
        got.attributes[i] = layout.attributes[j].clone();
    }
    assert_eq!(got, layout);
    assert_eq!(
        reader.attribute("grid_yaml"),
        Some(&AttrValue::from(
            "ball_count: [8, 9, 10]\nrpm: [300, 600]\nwaviness: 4 µm\n"
        ))
    );
    assert_eq!(reader.attribute("threads"), Some(&AttrValue::I64(2)));
    assert_eq!(reader.attribute("nonexistent"), None);

    let mut plan = SpectrumPlan::new(N_TIME, Window::Hann).unwrap();
    for row in 0..CASE_IDS.len() {
        let case = reader.read_case(row).unwrap();
        if row == UNWRITTEN || row == FAILED {
            for v in case.series.iter().chain(&case.spectra) {
                assert!(v.iter().all(|x| x.is_nan()), "row {row}: not NaN");
            }
            assert!(case.metrics.iter().all(|x| x.is_nan()));
            let (status, message) = if row == FAILED {
                (Status::Failed, "step size underflow at t = 0.123 s")
            } else {
                (Status::Pending, "")
            };
            assert_eq!((case.status, case.message.as_str()), (status, message));
            continue;
        }
        let want = synthetic_case(row, &mut plan);
        assert_eq!(case.status, Status::Ok);
        assert_eq!(case.message, "");
        for (g, w) in case
            .series
            .iter()
            .zip(&want.series)
            .chain(case.spectra.iter().zip(&want.spectra))
        {
            let w: Vec<f64> = w.iter().map(|&x| stored(x)).collect();
            assert_eq!(bits(g), bits(&w), "row {row}");
        }
        assert_eq!(
            bits(&case.metrics),
            bits(&want.metrics),
            "row {row} metrics"
        );
    }
    for row in 0..2 {
        let want: Vec<f64> = reference_row(row).into_iter().map(stored).collect();
        assert_eq!(bits(&reader.read_reference(row).unwrap()[0]), bits(&want));
    }
    let mut statuses = vec![Status::Ok; CASE_IDS.len()];
    statuses[UNWRITTEN] = Status::Pending;
    statuses[FAILED] = Status::Failed;
    assert_eq!(reader.statuses().unwrap(), statuses);
}

/// Sum of the stored (compressed) sizes of the series and spectra datasets (bytes).
fn stored_bytes(path: &Path, layout: &Layout) -> u64 {
    let file = hdf5::File::open(path).unwrap();
    layout
        .series
        .iter()
        .chain(&layout.spectra)
        .chain(&layout.reference_series)
        .map(|s| file.dataset(&s.name).unwrap().storage_size())
        .sum()
}

#[test]
fn float64_round_trips_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("study.h5");
    let storage = Storage {
        float32: false,
        deflate_level: 4,
    };
    write_synthetic(&path, storage);
    check_contents(&path, storage, |x| x);
}

#[test]
fn float32_round_trips_to_float32_precision() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("study32.h5");
    let storage = Storage {
        float32: true,
        deflate_level: 0,
    };
    write_synthetic(&path, storage);
    check_contents(&path, storage, |x| f64::from(x as f32));
    let file = hdf5::File::open(&path).unwrap();
    let ds = file.dataset(CHANNELS[0].name).unwrap();
    assert_eq!(ds.dtype().unwrap().size(), 4);
    assert_eq!(ds.chunk(), Some(vec![1, N_TIME]));
    assert_eq!(
        ds.filters(),
        vec![Filter::Fletcher32],
        "level 0 must mean the checksum alone"
    );
}

#[test]
fn series_are_chunked_by_case_with_shuffle_deflate_and_fletcher32() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("chunks.h5");
    let level = 6;
    write_synthetic(
        &path,
        Storage {
            float32: false,
            deflate_level: level,
        },
    );
    let file = hdf5::File::open(&path).unwrap();
    let layout = synthetic_layout(Storage::default());
    for (spec, cols) in layout
        .series
        .iter()
        .map(|s| (s, N_TIME))
        .chain(layout.spectra.iter().map(|s| (s, N_TIME / 2 + 1)))
    {
        let ds = file.dataset(&spec.name).unwrap();
        assert_eq!(ds.shape(), vec![CASE_IDS.len(), cols], "{}", spec.name);
        assert_eq!(ds.chunk(), Some(vec![1, cols]), "{}", spec.name);
        assert_eq!(
            ds.filters(),
            vec![Filter::Shuffle, Filter::Deflate(level), Filter::Fletcher32],
            "{}",
            spec.name
        );
    }
    // 1-D variables: whole (they are small), checksummed, not compressed.
    for name in ["status", "ball_count", "slider_acceleration_rms_deviation"] {
        let ds = file.dataset(name).unwrap();
        assert_eq!(ds.chunk(), Some(vec![CASE_IDS.len()]), "{name}");
        assert_eq!(ds.filters(), vec![Filter::Fletcher32], "{name}");
    }
    assert_eq!(
        StudyReader::open(&path)
            .unwrap()
            .layout()
            .storage
            .deflate_level,
        level
    );
}

#[test]
fn resume_writes_into_an_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("resume.h5");
    write_synthetic(&path, Storage::default());
    let mut writer = StudyWriter::open(&path).unwrap();
    assert_eq!(writer.layout().case_ids, CASE_IDS);
    let mut plan = SpectrumPlan::new(N_TIME, Window::Hann).unwrap();
    let case = synthetic_case(UNWRITTEN, &mut plan);
    let series: Vec<&[f64]> = case.series.iter().map(Vec::as_slice).collect();
    let spectra: Vec<&[f64]> = case.spectra.iter().map(Vec::as_slice).collect();
    let record = CaseRecord {
        series: &series,
        spectra: &spectra,
        metrics: &case.metrics,
        status: Status::Ok,
        message: "",
        replicate_messages: &[],
    };
    writer.write_case(UNWRITTEN, &record).unwrap();
    writer.finish().unwrap();
    let reader = StudyReader::open(&path).unwrap();
    let got = reader.read_case(UNWRITTEN).unwrap();
    assert_eq!(got.status, Status::Ok);
    assert_eq!(bits(&got.series[2]), bits(&case.series[2]));
    assert_eq!(
        reader
            .statuses()
            .unwrap()
            .iter()
            .filter(|s| **s == Status::Ok)
            .count(),
        5
    );
}

/// What the crash journal relies on: while the file is still open (nothing flushed),
/// a case's chunks are in the file, in order, after the size `file_len` gave before
/// `write_encoded`, within a little metadata of each other. Tiny chunks (a constant
/// series deflates to a few bytes) included, which HDF5's small-data aggregation would
/// otherwise put in space allocated earlier.
#[test]
fn chunks_lie_after_the_file_length_before_their_write() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("offsets.h5");
    let storage = Storage::default();
    let layout = synthetic_layout(storage);
    let mut writer = StudyWriter::create(&path, &layout).unwrap();
    let mut plan = SpectrumPlan::new(N_TIME, Window::Hann).unwrap();
    let mut encoder = ChunkEncoder::new(storage);
    let mut written: Vec<(u64, Vec<Vec<u8>>)> = Vec::new();
    for row in WRITE_ORDER {
        let mut case = synthetic_case(row, &mut plan);
        if row % 2 == 0 {
            case.series[1] = vec![2.0; N_TIME]; // a chunk of a few dozen bytes
        }
        let chunks: Vec<Vec<u8>> = case
            .series
            .iter()
            .chain(&case.spectra)
            .map(|values| {
                let mut c = Vec::new();
                encoder.encode(values, &mut c);
                c
            })
            .collect();
        assert!(row % 2 != 0 || chunks[1].len() < 120, "{}", chunks[1].len());
        let refs: Vec<&[u8]> = chunks.iter().map(Vec::as_slice).collect();
        let (series, spectra) = refs.split_at(case.series.len());
        let record = EncodedRecord {
            series,
            spectra,
            metrics: &case.metrics,
            status: Status::Ok,
            message: "",
            replicate_messages: &[],
        };
        let before = writer.file_len();
        assert_eq!(writer.write_encoded(row, &record).unwrap(), before);
        written.push((before, chunks));
        // Every case written so far, in the file as it is now.
        let file = std::fs::read(&path).unwrap();
        for (before, chunks) in &written {
            let mut at = *before as usize;
            let total: usize = chunks.iter().map(Vec::len).sum();
            for (k, chunk) in chunks.iter().enumerate() {
                let found = file[at..]
                    .windows(chunk.len())
                    .position(|w| w == &chunk[..])
                    .unwrap_or_else(|| panic!("chunk {k} is not after {at}"));
                at += found + chunk.len();
            }
            let spread = at - *before as usize - total;
            assert!(
                spread < 64 * 1024,
                "{spread} bytes of other things between chunks"
            );
        }
    }
    writer.finish().unwrap();
}

#[test]
fn errors_name_the_file_and_the_variable() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("errors.h5");
    let layout = synthetic_layout(Storage::default());
    let mut writer = StudyWriter::create(&path, &layout).unwrap();
    let short = [0.0; 10];
    let ok = vec![0.0; N_TIME];
    let record = CaseRecord {
        series: &[&ok, &short, &ok],
        spectra: &[],
        metrics: &[],
        status: Status::Ok,
        message: "",
        replicate_messages: &[],
    };
    let err = writer.write_case(0, &record).unwrap_err().to_string();
    assert!(
        err.contains("errors.h5") && err.contains("`crank_moment`") && err.contains("10 values"),
        "{err}"
    );
    let err = writer
        .write_case(
            6,
            &CaseRecord {
                series: &[],
                ..record
            },
        )
        .unwrap_err();
    assert!(
        matches!(err, StudyFileError::Row { row: 6, len: 6, .. }),
        "{err}"
    );
    let err = writer.write_reference(0, &[]).unwrap_err().to_string();
    assert!(err.contains("reference_series"), "{err}");
    // A NUL in a message is stored as U+FFFD rather than refused.
    let failed = CaseRecord {
        series: &[],
        status: Status::Failed,
        message: "bad\0byte",
        replicate_messages: &[],
        ..record
    };
    writer.write_case(1, &failed).unwrap();
    // Nothing was written by the refused records.
    drop(writer);
    let reader = StudyReader::open(&path).unwrap();
    assert_eq!(reader.read_case(0).unwrap().status, Status::Pending);
    assert_eq!(reader.read_case(1).unwrap().message, "bad\u{FFFD}byte");
    assert!(reader.read_case(0).unwrap().series[0]
        .iter()
        .all(|x| x.is_nan()));
    assert!(reader.read_case(6).is_err());

    let mut bad = layout.clone();
    bad.reference_index[2] = 7;
    let err = StudyWriter::create(dir.path().join("bad.h5"), &bad)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bad.h5") && err.contains("`reference_index` holds row 7"),
        "{err}"
    );

    let plain = dir.path().join("plain.h5");
    create_unlocked(&plain);
    let err = StudyReader::open(&plain).unwrap_err().to_string();
    assert!(
        err.contains("plain.h5") && err.contains("studyrun_file_format"),
        "{err}"
    );
    // A study file of another format version: named as such, and `--force` may
    // replace it (it is a study file), unlike the plain HDF5 file.
    let older = dir.path().join("older.h5");
    create_unlocked(&older)
        .new_attr::<i64>()
        .create("studyrun_file_format")
        .unwrap()
        .write_scalar(&1i64)
        .unwrap();
    let err = StudyReader::open(&older).unwrap_err().to_string();
    assert!(
        err.contains("older.h5") && err.contains("format version 1, this build reads version"),
        "{err}"
    );
    assert!(studyrun::output::overwrite::check_replaceable(&older).is_ok());
    assert!(studyrun::output::overwrite::check_replaceable(&plain).is_err());
    let err = StudyReader::open(dir.path().join("missing.h5"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("missing.h5"), "{err}");
}

#[test]
fn writer_can_move_to_a_writer_thread() {
    fn assert_send<T: Send>() {}
    assert_send::<StudyWriter>();
    assert_send::<StudyReader>();
}

/// The synthetic study (float64, deflate 4) at `target/test-files/synthetic_study.h5`,
/// for the Python test; prints its write throughput and compression ratio.
#[test]
fn synthetic_file_for_python() {
    let target = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .map_or_else(|| PathBuf::from("target"), Path::to_path_buf);
    let dir = target.join("test-files");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("synthetic_study.h5");
    let tmp = dir.join("synthetic_study.h5.partial");
    let storage = Storage {
        float32: false,
        deflate_level: 4,
    };
    let (raw, seconds) = write_synthetic(&tmp, storage);
    std::fs::rename(&tmp, &path).unwrap();
    check_contents(&path, storage, |x| x);
    let stored = stored_bytes(&path, &synthetic_layout(storage));
    println!(
        "synthetic study: {raw} B raw in {:.2} ms = {:.0} MB/s, stored {stored} B, ratio {:.3}; \
         STUDYRUN_TEST_FILE={} STUDYRUN_TEST_AXES=ball_count,rpm",
        seconds * 1e3,
        raw as f64 / seconds / 1e6,
        raw as f64 / stored as f64,
        path.display()
    );
}

/// Rows with every kind of value: a noisy smooth signal, integers, NaN, infinities,
/// signed zeros, subnormals and extremes, so that chunks mix stored and deflated
/// byte planes.
fn awkward_rows(n_rows: usize, n: usize) -> Vec<Vec<f64>> {
    let mut state = 0x853c_49e6_748f_ea9b_u64;
    let mut noise = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let specials = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        -0.0,
        f64::MIN_POSITIVE / 3.0,
        f64::MAX,
        f64::MIN,
    ];
    (0..n_rows)
        .map(|r| {
            (0..n)
                .map(|k| match r % 3 {
                    0 => 1e3 * (k as f64 * 2e-3 * (r + 1) as f64).sin() + 1e-4 * noise(),
                    1 => (k % 11) as f64,
                    _ if k % 97 == 0 => specials[k / 97 % specials.len()],
                    _ => noise() * 10f64.powi((k % 40) as i32 - 20),
                })
                .collect()
        })
        .collect()
}

/// A one-variable study file of `rows` written through [`StudyWriter::write_encoded`]
/// with chunks a [`ChunkEncoder`] made (as the workers do).
fn write_encoded_file(path: &Path, storage: Storage, rows: &[Vec<f64>]) {
    let n = rows[0].len();
    let layout = Layout {
        case_ids: (0..rows.len() as u64).collect(),
        times: (0..n).map(|k| k as f64 * 1e-3).collect(),
        frequencies: vec![],
        reference_ids: vec![0],
        series: vec![VarSpec::new("x", "m", "awkward values")],
        spectra: vec![],
        metrics: vec![VarSpec::new("m", "1", "a metric")],
        parameters: vec![],
        replicates: Vec::new(),
        replicate_metrics: Vec::new(),
        revolutions: Vec::new(),
        revolution_metrics: Vec::new(),
        orders: Vec::new(),
        order_spectra: Vec::new(),
        sk_frequencies: Vec::new(),
        kurtosis: Vec::new(),
        reference_parameters: vec![],
        reference_series: vec![],
        reference_index: vec![0; rows.len()],
        attributes: vec![],
        storage,
    };
    let mut writer = StudyWriter::create(path, &layout).unwrap();
    let mut encoder = ChunkEncoder::new(storage);
    for (row, values) in rows.iter().enumerate().rev() {
        let mut chunk = Vec::new();
        encoder.encode(values, &mut chunk);
        writer
            .write_encoded(
                row,
                &EncodedRecord {
                    series: &[&chunk],
                    spectra: &[],
                    metrics: &[row as f64],
                    status: Status::Ok,
                    message: "",
                    replicate_messages: &[],
                },
            )
            .unwrap();
    }
    writer.finish().unwrap();
}

/// The same rows written by HDF5's own filter pipeline (shuffle + deflate, or none;
/// then Fletcher-32).
fn write_through_hdf5_filters(path: &Path, storage: Storage, rows: &[Vec<f64>]) {
    let file = create_unlocked(path);
    let n = rows[0].len();
    let mut builder = file
        .new_dataset::<f64>()
        .chunk((1, n))
        .shape((rows.len(), n));
    if storage.deflate_level > 0 {
        builder = builder.shuffle().deflate(storage.deflate_level);
    }
    builder
        .fletcher32()
        .create("x")
        .unwrap()
        .write_raw(&rows.concat())
        .unwrap();
}

fn stored_values(storage: Storage, rows: &[Vec<f64>]) -> Vec<Vec<u64>> {
    rows.iter()
        .map(|r| {
            r.iter()
                .map(|&v| {
                    if storage.float32 {
                        f64::from(v as f32).to_bits()
                    } else {
                        v.to_bits()
                    }
                })
                .collect()
        })
        .collect()
}

/// Direct chunk writes read back bit for bit, through the Rust reader and through
/// HDF5's own inflate and unshuffle, and equal what HDF5's filter pipeline stores;
/// the dataset keeps the standard shuffle + deflate filters and Fletcher-32. Leaves
/// `target/test-files/direct_chunks/` (files and the expected values as raw
/// little-endian f64) for `tests/python/test_direct_chunks.py`.
#[test]
fn direct_chunks_read_like_hdf5_filtered_chunks() {
    let target = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .map_or_else(|| PathBuf::from("target"), Path::to_path_buf);
    let dir = target.join("test-files").join("direct_chunks");
    std::fs::create_dir_all(&dir).unwrap();
    let rows = awkward_rows(9, 3001);
    for (name, float32, level) in [
        ("f64_deflate1", false, 1),
        ("f64_deflate9", false, 9),
        ("f64_plain", false, 0),
        ("f32_deflate4", true, 4),
    ] {
        let storage = Storage {
            float32,
            deflate_level: level,
        };
        let path = dir.join(format!("{name}.h5"));
        write_encoded_file(&path, storage, &rows);
        let want = stored_values(storage, &rows);
        let reader = StudyReader::open(&path).unwrap();
        for (row, w) in want.iter().enumerate() {
            let case = reader.read_case(row).unwrap();
            assert_eq!(&bits(&case.series[0]), w, "{name} row {row}");
            assert_eq!(case.metrics, [row as f64]);
        }
        let file = hdf5::File::open(&path).unwrap();
        let ds = file.dataset("x").unwrap();
        let expected_filters = if level > 0 {
            vec![Filter::Shuffle, Filter::Deflate(level), Filter::Fletcher32]
        } else {
            vec![Filter::Fletcher32]
        };
        assert_eq!(ds.filters(), expected_filters, "{name}");
        let all = bits(&ds.read_raw::<f64>().unwrap());
        assert_eq!(all, want.concat(), "{name}: HDF5's read_raw");
        if !float32 {
            let reference = dir.join(format!("{name}_hdf5_filters.h5"));
            write_through_hdf5_filters(&reference, storage, &rows);
            let theirs = hdf5::File::open(&reference).unwrap().dataset("x").unwrap();
            let theirs = bits(&theirs.read_raw::<f64>().unwrap());
            assert_eq!(all, theirs, "{name}: same values as HDF5's own filters");
            if level == 0 {
                // No deflate: HDF5's chunks are ours byte for byte, Fletcher-32 included.
                let bytes = std::fs::read(&reference).unwrap();
                let mut encoder = ChunkEncoder::new(storage);
                for row in &rows {
                    let mut chunk = Vec::new();
                    encoder.encode(row, &mut chunk);
                    assert!(
                        bytes.windows(chunk.len()).any(|w| w == chunk),
                        "{name}: a chunk HDF5 did not store"
                    );
                }
            }
            std::fs::remove_file(&reference).unwrap();
        }
        let raw: Vec<u8> = want.concat().iter().flat_map(|b| b.to_le_bytes()).collect();
        std::fs::write(dir.join(format!("{name}.f64")), raw).unwrap();
    }
    println!("STUDYRUN_CHUNKS_DIR={}", dir.display());
}

/// Write throughput of a paper-sized study: 32 cases × 12 series of 20 001 samples and
/// 12 spectra, float64, for several deflate levels. `cargo test --release --test
/// hdf5_file -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement, not a check"]
fn write_throughput() {
    let (n_case, n_time) = (32usize, 20_001usize);
    let rate = 50_000.0;
    let freqs = frequencies(n_time, rate);
    let dir = tempfile::tempdir().unwrap();
    let mut plan = SpectrumPlan::new(n_time, Window::Hann).unwrap();
    let specs: Vec<VarSpec> = CHANNELS
        .iter()
        .map(|c| VarSpec::new(c.name, c.units, c.long_name))
        .collect();
    // A smooth response with harmonics and integrator-level noise, per channel.
    let series: Vec<Vec<f64>> = (0..CHANNELS.len())
        .map(|i| {
            (0..n_time)
                .map(|k| {
                    let t = k as f64 / rate;
                    let x = 62.8 * t * (1.0 + i as f64);
                    100.0 * x.sin() + 7.0 * (35.0 * x).sin() + 1e-6 * (1e4 * x).sin()
                })
                .collect()
        })
        .collect();
    let spectra: Vec<Vec<f64>> = series
        .iter()
        .map(|s| {
            let mut out = vec![0.0; plan.bins()];
            plan.amplitude(s, &mut out).unwrap();
            out
        })
        .collect();
    for (float32, level) in [(false, 0), (false, 1), (false, 4), (true, 1)] {
        let layout = Layout {
            case_ids: (0..n_case as u64).collect(),
            times: (0..n_time).map(|k| k as f64 / rate).collect(),
            frequencies: freqs.clone(),
            reference_ids: vec![0],
            series: specs.clone(),
            spectra: specs
                .iter()
                .map(|s| {
                    VarSpec::new(
                        format!("{}_spectrum", s.name),
                        s.units.clone(),
                        s.long_name.clone(),
                    )
                })
                .collect(),
            metrics: vec![VarSpec::new("rms", "m s-2", "rms")],
            parameters: vec![],
            replicates: Vec::new(),
            replicate_metrics: Vec::new(),
            revolutions: Vec::new(),
            revolution_metrics: Vec::new(),
            orders: Vec::new(),
            order_spectra: Vec::new(),
            sk_frequencies: Vec::new(),
            kurtosis: Vec::new(),
            reference_parameters: vec![],
            reference_series: vec![],
            reference_index: vec![0; n_case],
            attributes: vec![],
            storage: Storage {
                float32,
                deflate_level: level,
            },
        };
        let path = dir.path().join(format!("bench_{float32}_{level}.h5"));
        let s: Vec<&[f64]> = series.iter().map(Vec::as_slice).collect();
        let p: Vec<&[f64]> = spectra.iter().map(Vec::as_slice).collect();
        let start = Instant::now();
        let mut writer = StudyWriter::create(&path, &layout).unwrap();
        for row in 0..n_case {
            let record = CaseRecord {
                series: &s,
                spectra: &p,
                metrics: &[1.0],
                status: Status::Ok,
                message: "",
                replicate_messages: &[],
            };
            writer.write_case(row, &record).unwrap();
        }
        writer.finish().unwrap();
        let seconds = start.elapsed().as_secs_f64();
        let raw = n_case * 8 * CHANNELS.len() * (n_time + freqs.len());
        let stored = stored_bytes(&path, &layout);
        println!(
            "float32={float32} deflate={level}: {:.1} MB raw in {:.3} s = {:.0} MB/s, ratio {:.2} (file {:.1} MB)",
            raw as f64 / 1e6,
            seconds,
            raw as f64 / seconds / 1e6,
            raw as f64 / stored as f64,
            std::fs::metadata(&path).unwrap().len() as f64 / 1e6
        );
    }
}

/// A study without spectra (empty `frequency` dimension) and with a single case.
#[test]
fn minimal_layout_without_spectra() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("minimal.h5");
    let layout = Layout {
        case_ids: vec![42],
        times: vec![0.0, 0.5],
        frequencies: vec![],
        reference_ids: vec![0],
        series: vec![VarSpec::new("x", "m", "position")],
        spectra: vec![],
        metrics: vec![],
        parameters: vec![],
        replicates: Vec::new(),
        replicate_metrics: Vec::new(),
        revolutions: Vec::new(),
        revolution_metrics: Vec::new(),
        orders: Vec::new(),
        order_spectra: Vec::new(),
        sk_frequencies: Vec::new(),
        kurtosis: Vec::new(),
        reference_parameters: vec![],
        reference_series: vec![],
        reference_index: vec![0],
        attributes: vec![],
        storage: Storage::default(),
    };
    let mut writer = StudyWriter::create(&path, &layout).unwrap();
    let x = [1.0, -2.0];
    let record = CaseRecord {
        series: &[&x],
        spectra: &[],
        metrics: &[],
        status: Status::Ok,
        message: "",
        replicate_messages: &[],
    };
    writer.write_case(0, &record).unwrap();
    writer.finish().unwrap();
    let reader = StudyReader::open(&path).unwrap();
    assert_eq!(reader.layout(), &layout);
    assert_eq!(reader.read_case(0).unwrap().series, vec![x.to_vec()]);
}
