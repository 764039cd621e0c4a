//! Study files that netCDF tools rewrote are read, inspected and merged like the
//! originals. The edits are made here with the HDF5 library the way
//! the tools make them (tests/python/test_netcdf_tools.py runs the tools themselves):
//! NC_CHAR attributes (`ncatted`: fixed-length, ASCII-typed even for UTF-8 text, a NULL
//! dataspace when empty), one-element string arrays (`ncatted ... sng`), every attribute
//! a one-element array plus `_NCProperties` and `_Netcdf4Coordinates` (`nccopy -k nc4`,
//! `ncks`, xarray), a numeric array attribute, variables in another order (`ncks`).
//! Also: ids are int32, `history` is NC_CHAR with the merge's line on top.

use std::ffi::CString;
use std::path::{Path, PathBuf};

use crate::common::{open_rw_unlocked, studyrun_ok};
use hdf5::types::{TypeDescriptor, VarLenUnicode};
use hdf5_sys::h5a::{
    H5Aclose, H5Acreate2, H5Adelete, H5Aexists, H5Aget_space, H5Aget_type, H5Aopen, H5Aread,
    H5Awrite,
};
use hdf5_sys::h5i::hid_t;
use hdf5_sys::h5p::H5P_DEFAULT;
use hdf5_sys::h5s::{
    H5S_class_t, H5Sclose, H5Screate, H5Screate_simple, H5Sget_simple_extent_npoints,
};
use hdf5_sys::h5t::{
    H5T_class_t, H5T_cset_t, H5T_direction_t, H5T_str_t, H5Tclose, H5Tcopy, H5Tget_class,
    H5Tget_native_type, H5Tget_size, H5Tset_cset, H5Tset_size, H5Tset_strpad, H5T_C_S1,
    H5T_NATIVE_INT,
};
use studyrun::output::{inspect, AttrValue, CaseRecord, Layout, StudyReader, StudyWriter, VarSpec};

/// 4 cases of 10 ms: a file of a few hundred kB, made in a fraction of a second.
const TINY: &str = "name: tiny\nduration: 0.01\nsample_rate: 2000\ntransient: \"0.002 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9]\n  rpm: [600]\n";

/// The tiny study in `dir`: `tiny.h5` (the whole run), `s1.h5`, `s2.h5` (its two
/// shards) and `merged.h5` (their merge).
fn tiny_files(dir: &Path) {
    std::fs::write(dir.join("tiny.yaml"), TINY).unwrap();
    studyrun_ok(dir, &["tiny.yaml", "-q"]);
    for k in 1..=2 {
        let shard = format!("{k}/2");
        let out = format!("s{k}.h5");
        studyrun_ok(dir, &["tiny.yaml", "--shard", &shard, "-o", &out, "-q"]);
    }
    studyrun_ok(dir, &["merge", "merged.h5", "s1.h5", "s2.h5"]);
}

/// Runs `f` under hdf5-metno's library lock (libhdf5 is not thread-safe).
fn locked<T>(f: impl FnOnce() -> T) -> T {
    hdf5::sync::sync(f)
}

fn cname(name: &str) -> CString {
    CString::new(name).unwrap()
}

/// Adds (or replaces) attribute `name` of object `obj` (`/` for the root) as NC_CHAR:
/// a scalar fixed-length ASCII-typed string of exactly `bytes` (NULL dataspace if
/// empty), as `ncatted -a name,obj,c,c,text` writes it.
fn nc_char(path: &Path, obj: &str, name: &str, bytes: &[u8]) {
    let file = open_rw_unlocked(path);
    let ds = (obj != "/").then(|| file.dataset(obj).unwrap());
    let id = ds.as_ref().map_or(file.id(), |d| d.id());
    let name = cname(name);
    locked(|| unsafe {
        if H5Aexists(id, name.as_ptr()) > 0 {
            assert!(H5Adelete(id, name.as_ptr()) >= 0);
        }
        let t = H5Tcopy(*H5T_C_S1);
        assert!(H5Tset_size(t, bytes.len().max(1)) >= 0);
        assert!(H5Tset_strpad(t, H5T_str_t::H5T_STR_NULLTERM) >= 0);
        assert!(H5Tset_cset(t, H5T_cset_t::H5T_CSET_ASCII) >= 0);
        let s = if bytes.is_empty() {
            H5Screate(H5S_class_t::H5S_NULL)
        } else {
            H5Screate(H5S_class_t::H5S_SCALAR)
        };
        let a = H5Acreate2(id, name.as_ptr(), t, s, H5P_DEFAULT, H5P_DEFAULT);
        assert!(a >= 0);
        if !bytes.is_empty() {
            assert!(H5Awrite(a, t, bytes.as_ptr().cast()) >= 0);
        }
        H5Aclose(a);
        H5Sclose(s);
        H5Tclose(t);
    });
}

/// Adds root attribute `name` as a one-element variable-length UTF-8 string array
/// (`ncatted -a name,global,c,sng,text`).
fn string_array(path: &Path, name: &str, text: &str) {
    let file = open_rw_unlocked(path);
    let v: VarLenUnicode = text.parse().unwrap();
    file.new_attr_builder()
        .with_data(&[v])
        .create(name)
        .unwrap();
}

/// Adds root attribute `name` holding two numbers (`ncatted -a pair,global,c,d,"1,2"`).
fn number_array(path: &Path, name: &str) {
    let file = open_rw_unlocked(path);
    file.new_attr_builder()
        .with_data(&[1.0f64, 2.0])
        .create(name)
        .unwrap();
}

/// Turns every scalar attribute of `obj` into a one-element array of the same type
/// (what nccopy, ncks and xarray leave), except the dimension scales' own.
///
/// # Safety
/// `obj` must be a valid object id.
unsafe fn one_element_arrays(obj: hid_t, names: &[String]) {
    for name in names {
        if ["CLASS", "NAME", "DIMENSION_LIST", "REFERENCE_LIST"].contains(&name.as_str()) {
            continue;
        }
        let c = cname(name);
        let a = H5Aopen(obj, c.as_ptr(), H5P_DEFAULT);
        assert!(a >= 0, "{name}");
        let t = H5Aget_type(a);
        let space = H5Aget_space(a);
        let n = H5Sget_simple_extent_npoints(space);
        H5Sclose(space);
        let class = H5Tget_class(t);
        let plain = matches!(
            class,
            H5T_class_t::H5T_INTEGER | H5T_class_t::H5T_FLOAT | H5T_class_t::H5T_STRING
        );
        if n != 1 || !plain {
            H5Aclose(a);
            H5Tclose(t);
            continue;
        }
        let mem = if class == H5T_class_t::H5T_STRING {
            H5Tcopy(t)
        } else {
            H5Tget_native_type(t, H5T_direction_t::H5T_DIR_DEFAULT)
        };
        // Variable-length strings read as a pointer HDF5 allocated (left to leak).
        let mut buf = vec![0u8; H5Tget_size(mem).max(16)];
        assert!(H5Aread(a, mem, buf.as_mut_ptr().cast()) >= 0, "{name}");
        H5Aclose(a);
        assert!(H5Adelete(obj, c.as_ptr()) >= 0);
        let dims = [1u64];
        let s1 = H5Screate_simple(1, dims.as_ptr(), std::ptr::null());
        let b = H5Acreate2(obj, c.as_ptr(), t, s1, H5P_DEFAULT, H5P_DEFAULT);
        assert!(b >= 0, "{name}");
        assert!(H5Awrite(b, mem, buf.as_ptr().cast()) >= 0, "{name}");
        H5Aclose(b);
        H5Sclose(s1);
        H5Tclose(mem);
        H5Tclose(t);
    }
}

/// What `nccopy -k nc4` does to the attributes: every one a one-element array,
/// `_NCProperties` (fixed-length, NUL-padded) on the root, `_Netcdf4Coordinates` (an
/// int32 array) on every variable.
fn netcdf_rewrite(path: &Path) {
    let file = open_rw_unlocked(path);
    let datasets = file.member_names().unwrap();
    locked(|| unsafe { one_element_arrays(file.id(), &file.attr_names().unwrap()) });
    for name in &datasets {
        let ds = file.dataset(name).unwrap();
        locked(|| unsafe { one_element_arrays(ds.id(), &ds.attr_names().unwrap()) });
        let dims: Vec<i32> = (0..ds.ndim() as i32).collect();
        let c = cname("_Netcdf4Coordinates");
        locked(|| unsafe {
            let d = [dims.len() as u64];
            let s = H5Screate_simple(1, d.as_ptr(), std::ptr::null());
            let a = H5Acreate2(
                ds.id(),
                c.as_ptr(),
                *H5T_NATIVE_INT,
                s,
                H5P_DEFAULT,
                H5P_DEFAULT,
            );
            assert!(a >= 0);
            assert!(H5Awrite(a, *H5T_NATIVE_INT, dims.as_ptr().cast()) >= 0);
            H5Aclose(a);
            H5Sclose(s);
        });
    }
    drop(file);
    let props = b"version=2,netcdf=4.9.0,hdf5=1.10.8\0\0\0";
    nc_char(path, "/", "_NCProperties", props);
}

/// A copy of the study file `src` at `dst` with every group of variables in reverse
/// order (as `ncks`, which sorts them by name, changes their order).
fn reversed_copy(src: &Path, dst: &Path) {
    let r = StudyReader::open(src).unwrap();
    let mut layout: Layout = r.layout().clone();
    layout.series.reverse();
    layout.spectra.reverse();
    layout.metrics.reverse();
    layout.parameters.reverse();
    let mut w = StudyWriter::create(dst, &layout).unwrap();
    for k in 0..layout.reference_ids.len() {
        let series = r.read_reference(k).unwrap();
        let refs: Vec<&[f64]> = series.iter().map(Vec::as_slice).collect();
        w.write_reference(k, &refs).unwrap();
    }
    for row in 0..layout.case_ids.len() {
        let mut c = r.read_case(row).unwrap();
        c.series.reverse();
        c.spectra.reverse();
        c.metrics.reverse();
        let series: Vec<&[f64]> = c.series.iter().map(Vec::as_slice).collect();
        let spectra: Vec<&[f64]> = c.spectra.iter().map(Vec::as_slice).collect();
        w.write_case(
            row,
            &CaseRecord {
                series: &series,
                spectra: &spectra,
                metrics: &c.metrics,
                status: c.status,
                message: &c.message,
                replicate_messages: &c.replicate_messages,
            },
        )
        .unwrap();
    }
    w.finish().unwrap();
}

type Edit = fn(&Path);

/// The tools' edits, by the tool and command they stand for.
fn edits() -> Vec<(&'static str, Edit)> {
    vec![
        ("ncatted -a comment,global,c,c,x", |p| {
            nc_char(p, "/", "comment", b"x")
        }),
        ("ncatted -a comment,global,c,c,", |p| {
            nc_char(p, "/", "comment", b"")
        }),
        ("ncatted -a comment,global,c,c,été", |p| {
            nc_char(p, "/", "comment", "été".as_bytes())
        }),
        ("ncatted -a comment,global,c,sng,x", |p| {
            string_array(p, "comment", "x")
        }),
        ("ncatted -a units,slider_acceleration,o,c,m s-2", |p| {
            nc_char(p, "slider_acceleration", "units", b"m s-2")
        }),
        ("ncatted -a study_name,global,o,c,tiny", |p| {
            nc_char(p, "/", "study_name", b"tiny")
        }),
        ("ncatted -a pair,global,c,d,1,2", |p| {
            number_array(p, "pair")
        }),
        ("nccopy -k nc4 (attributes)", netcdf_rewrite),
    ]
}

/// `inspect`'s summary without its first line (the file name).
fn summary(path: &Path) -> String {
    let text = inspect(path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
    text.lines().skip(1).collect::<Vec<_>>().join("\n")
}

/// Asserts that two study files hold the same variables and values (in any order of
/// the variables), the same parameters and the root attributes of `want` but
/// `created` and `history`.
fn assert_same_study(got: &Path, want: &Path) {
    let (rg, rw) = (
        StudyReader::open(got).unwrap(),
        StudyReader::open(want).unwrap(),
    );
    let (lg, lw) = (rg.layout(), rw.layout());
    assert_eq!(lg.case_ids, lw.case_ids);
    assert_eq!(lg.times, lw.times);
    assert_eq!(lg.frequencies, lw.frequencies);
    assert_eq!(lg.reference_index, lw.reference_index);
    let by_name = |specs: &[VarSpec], name: &str| specs.iter().position(|s| s.name == name);
    for p in &lw.parameters {
        let q = lg.parameters.iter().find(|q| q.spec == p.spec);
        assert_eq!(q, Some(p), "parameter {}", p.spec.name);
    }
    for (name, value) in &lw.attributes {
        if name != "created" && name != "history" {
            assert_eq!(rg.attribute(name), Some(value), "attribute {name}");
        }
    }
    for row in 0..lw.case_ids.len() {
        let (cg, cw) = (rg.read_case(row).unwrap(), rw.read_case(row).unwrap());
        assert_eq!((cg.status, &cg.message), (cw.status, &cw.message));
        for (specs_w, specs_g, vw, vg) in [
            (&lw.series, &lg.series, &cw.series, &cg.series),
            (&lw.spectra, &lg.spectra, &cw.spectra, &cg.spectra),
        ] {
            assert_eq!(specs_w.len(), specs_g.len());
            for (i, s) in specs_w.iter().enumerate() {
                let j = by_name(specs_g, &s.name).unwrap();
                assert_eq!(&specs_g[j], s);
                assert_eq!(format!("{:?}", vg[j]), format!("{:?}", vw[i]), "{}", s.name);
            }
        }
        for (i, s) in lw.metrics.iter().enumerate() {
            let j = by_name(&lg.metrics, &s.name).unwrap();
            if s.name != "wall_time" {
                assert_eq!(
                    format!("{:?}", cg.metrics[j]),
                    format!("{:?}", cw.metrics[i])
                );
            }
        }
    }
    for k in 0..lw.reference_ids.len() {
        assert_eq!(rg.read_reference(k).unwrap(), rw.read_reference(k).unwrap());
    }
}

#[test]
fn files_the_tools_rewrote_are_read_inspected_and_merged() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_files(d);
    let original = summary(&d.join("tiny.h5"));
    for (k, (tool, edit)) in edits().into_iter().enumerate() {
        // The whole run's file, edited: read and inspected like the original.
        let copy = d.join(format!("edit{k}.h5"));
        std::fs::copy(d.join("tiny.h5"), &copy).unwrap();
        edit(&copy);
        let reader = StudyReader::open(&copy).unwrap_or_else(|e| panic!("{tool}: {e}"));
        let want = StudyReader::open(d.join("tiny.h5")).unwrap();
        assert_eq!(
            reader.layout().parameters,
            want.layout().parameters,
            "{tool}"
        );
        for (name, value) in &want.layout().attributes {
            if name != "study_name" {
                assert_eq!(reader.attribute(name), Some(value), "{tool}: {name}");
            }
        }
        assert!(
            reader
                .layout()
                .attributes
                .iter()
                .all(|(n, _)| !n.starts_with('_')),
            "{tool}: netCDF's own attributes are not the study's"
        );
        drop((reader, want));
        assert_eq!(summary(&copy), original, "{tool}");
        // Both shards, or only the second, edited: the merge holds the same study.
        for both in [true, false] {
            let shards: Vec<PathBuf> = (1..=2)
                .map(|s| {
                    let p = d.join(format!("edit{k}_{both}_s{s}.h5"));
                    std::fs::copy(d.join(format!("s{s}.h5")), &p).unwrap();
                    if both || s == 2 {
                        edit(&p);
                    }
                    p
                })
                .collect();
            let merged = d.join(format!("edit{k}_{both}_merged.h5"));
            let mut args = vec!["merge".to_owned(), merged.display().to_string()];
            args.extend(shards.iter().map(|p| p.display().to_string()));
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            studyrun_ok(d, &args);
            assert_same_study(&merged, &d.join("merged.h5"));
        }
    }
}

#[test]
fn unknown_attributes_are_skipped_and_known_ones_read_as_text() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_files(d);
    let p = d.join("tiny.h5");
    nc_char(&p, "/", "comment", "été".as_bytes());
    number_array(&p, "pair");
    string_array(&p, "keywords", "bearing");
    netcdf_rewrite(&p);
    let r = StudyReader::open(&p).unwrap();
    assert_eq!(r.attribute("comment"), Some(&AttrValue::from("été")));
    assert_eq!(r.attribute("keywords"), Some(&AttrValue::from("bearing")));
    assert_eq!(r.attribute("pair"), None, "an array is not the study's");
    assert_eq!(r.attribute("_NCProperties"), None);
    assert!(matches!(
        r.attribute("study_cases"),
        Some(AttrValue::I64(4))
    ));
}

#[test]
fn merge_matches_variables_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_files(d);
    reversed_copy(&d.join("s1.h5"), &d.join("r1.h5"));
    reversed_copy(&d.join("s2.h5"), &d.join("r2.h5"));
    for (a, b) in [("s1.h5", "r2.h5"), ("r1.h5", "s2.h5"), ("r2.h5", "r1.h5")] {
        let out = format!("m_{a}_{b}");
        studyrun_ok(d, &["merge", &out, a, b]);
        assert_same_study(&d.join(&out), &d.join("merged.h5"));
    }
    // The refusals stay: a shard twice, a pending case.
    let twice = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(d)
        .args(["merge", "m.h5", "r1.h5", "r1.h5"])
        .output()
        .unwrap();
    assert_eq!(twice.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&twice.stderr).contains("given twice"));
}

#[test]
fn ids_are_int32_and_history_is_nc_char_with_the_merge_on_top() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_files(d);
    for name in ["tiny.h5", "s1.h5", "merged.h5"] {
        let file = hdf5::File::open(d.join(name)).unwrap();
        for id in ["case", "reference", "reference_index"] {
            let t = file.dataset(id).unwrap().dtype().unwrap();
            assert_eq!(
                t.to_descriptor().unwrap(),
                TypeDescriptor::Integer(hdf5::types::IntSize::U4),
                "{name}: {id}"
            );
        }
        let history = file.attr("history").unwrap();
        assert!(
            matches!(
                history.dtype().unwrap().to_descriptor().unwrap(),
                TypeDescriptor::FixedAscii(_)
            ),
            "{name}: history is not NC_CHAR"
        );
    }
    let text = |name: &str| match StudyReader::open(d.join(name))
        .unwrap()
        .attribute("history")
    {
        Some(AttrValue::Str(s)) => s.clone(),
        other => panic!("{name}: history {other:?}"),
    };
    let shard = text("s1.h5");
    assert_eq!(shard.lines().count(), 1, "{shard}");
    assert!(
        shard.contains(": studyrun tiny.yaml --shard 1/2 -o s1.h5 -q"),
        "{shard}"
    );
    let merged = text("merged.h5");
    let lines: Vec<&str> = merged.lines().collect();
    assert_eq!(lines.len(), 2, "{merged}");
    assert!(
        lines[0].ends_with(": studyrun merge merged.h5 s1.h5 s2.h5"),
        "{merged}"
    );
    assert_eq!(lines[1], shard);
}

/// Rewrites `time` of the file at `path` through `f(sample, time)`.
fn rewrite_times(path: &Path, f: impl Fn(usize, f64) -> f64) {
    let file = open_rw_unlocked(path);
    let ds = file.dataset("time").unwrap();
    let times: Vec<f64> = ds.read_raw::<f64>().unwrap();
    let moved: Vec<f64> = times.iter().enumerate().map(|(j, &t)| f(j, t)).collect();
    ds.write_raw(&moved).unwrap();
}

/// xarray decodes `time` to datetime64[ns] by truncation, so writing a decoded file back
/// moves some times down by a nanosecond (tests/python/test_netcdf_tools.py runs it). The reader puts back the times studyrun
/// writes: such a shard merges with an untouched one into the same study. A time moved
/// further is kept as read, and the merge refuses the mix.
#[test]
fn times_a_datetime_round_trip_moved_are_put_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_files(d);
    let original = StudyReader::open(d.join("s2.h5"))
        .unwrap()
        .layout()
        .times
        .clone();

    std::fs::copy(d.join("s2.h5"), d.join("ns.h5")).unwrap();
    rewrite_times(
        &d.join("ns.h5"),
        |j, t| if j % 3 == 1 { t - 1e-9 } else { t },
    );
    assert_eq!(
        StudyReader::open(d.join("ns.h5")).unwrap().layout().times,
        original
    );
    studyrun_ok(d, &["merge", "m_ns.h5", "s1.h5", "ns.h5"]);
    assert_same_study(&d.join("m_ns.h5"), &d.join("merged.h5"));

    std::fs::copy(d.join("s2.h5"), d.join("far.h5")).unwrap();
    rewrite_times(&d.join("far.h5"), |j, t| if j == 3 { t + 3e-9 } else { t });
    let far = StudyReader::open(d.join("far.h5")).unwrap();
    assert_eq!(far.layout().times[3], original[3] + 3e-9);
    drop(far);
    let out = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(d)
        .args(["merge", "m_far.h5", "s1.h5", "far.h5"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("different layout"));
}
