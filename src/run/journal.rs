//! The crash journal: every finished case is appended here before it goes into the
//! HDF5 file, so a run killed at any moment can resume without recomputing it.
//!
//! The HDF5 file is written as `OUT.h5.partial` and renamed to `OUT.h5` only when
//! complete (an atomic rename), so `OUT.h5` is either absent or whole. The journal
//! `OUT.h5.journal` is deleted after the rename.
//!
//! Format: a header (magic, fingerprint of the study, array sizes), then records
//! `[b"CASE", row u64, status i8, message length u32, message bytes, f64 values,
//! FNV-1a checksum u64]`, little-endian. Reading stops at the first truncated or
//! corrupt record (a kill during a write), which is cut off before appending again.

use std::fs::{File, OpenOptions};
use std::io::{self, BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

use super::case::CaseResult;
use crate::output::Status;

const MAGIC: &[u8; 8] = b"SRJOURN1";
const RECORD: &[u8; 4] = b"CASE";

/// What a journal must match to be resumed: the study and the array sizes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JournalHeader {
    /// Fingerprint of the study (grid text, version, shard).
    pub fingerprint: u64,
    /// Samples per series.
    pub n_time: u64,
    /// Number of series per case.
    pub n_series: u64,
    /// Bins per spectrum.
    pub n_freq: u64,
    /// Number of spectra per case.
    pub n_spectra: u64,
    /// Number of metrics per case.
    pub n_metrics: u64,
}

impl JournalHeader {
    fn bytes(&self) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        for v in [
            self.fingerprint,
            self.n_time,
            self.n_series,
            self.n_freq,
            self.n_spectra,
            self.n_metrics,
        ] {
            b.extend(v.to_le_bytes());
        }
        b
    }
}

/// FNV-1a, 64 bit: a checksum for records and the study fingerprint.
pub fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for &b in *part {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Appends records; every record is written whole and flushed to the OS.
pub struct JournalWriter {
    file: File,
    buf: Vec<u8>,
}

impl JournalWriter {
    /// A new journal at `path` (replacing any file there).
    pub fn create(path: &Path, header: &JournalHeader) -> io::Result<Self> {
        let mut file = File::create(path)?;
        file.write_all(&header.bytes())?;
        Ok(Self {
            file,
            buf: Vec::new(),
        })
    }

    /// Reopens the journal at `path` for appending after its first `valid_len` bytes.
    pub fn append(path: &Path, valid_len: u64) -> io::Result<Self> {
        let mut file = OpenOptions::new().write(true).open(path)?;
        file.set_len(valid_len)?;
        file.seek(SeekFrom::End(0))?;
        Ok(Self {
            file,
            buf: Vec::new(),
        })
    }

    /// Appends one case.
    pub fn write(&mut self, r: &CaseResult) -> io::Result<()> {
        let b = &mut self.buf;
        b.clear();
        b.extend(RECORD);
        b.extend((r.row as u64).to_le_bytes());
        b.push(r.status.code() as u8);
        b.extend((r.message.len() as u32).to_le_bytes());
        b.extend(r.message.as_bytes());
        for v in r
            .series
            .iter()
            .chain(&r.spectra)
            .flatten()
            .chain(&r.metrics)
        {
            b.extend(v.to_le_bytes());
        }
        let sum = fnv1a(&[b]);
        b.extend(sum.to_le_bytes());
        self.file.write_all(b)
    }
}

/// Reads the valid records of a journal, one at a time.
pub struct JournalReader {
    input: BufReader<File>,
    header: JournalHeader,
    /// Bytes of the header and the valid records read so far.
    valid_len: u64,
    buf: Vec<u8>,
}

/// Why a journal cannot be resumed.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// Reading failed.
    #[error("cannot read the journal {path}: {source}")]
    Io {
        /// The journal.
        path: String,
        /// The I/O error.
        source: io::Error,
    },
    /// The journal was written for another study, version or shard.
    #[error("the journal {path} belongs to a different study, studyrun version or shard; run with --force to start over")]
    Mismatch {
        /// The journal.
        path: String,
    },
}

impl JournalReader {
    /// Opens `path` and checks its header against `expected`.
    pub fn open(path: &Path, expected: &JournalHeader) -> Result<Self, JournalError> {
        let io_err = |source| JournalError::Io {
            path: path.display().to_string(),
            source,
        };
        let mut input = BufReader::new(File::open(path).map_err(io_err)?);
        let want = expected.bytes();
        let mut got = vec![0u8; want.len()];
        if input.read_exact(&mut got).is_err() || got != want {
            return Err(JournalError::Mismatch {
                path: path.display().to_string(),
            });
        }
        Ok(Self {
            input,
            header: *expected,
            valid_len: want.len() as u64,
            buf: Vec::new(),
        })
    }

    /// Length in bytes of the header and every valid record read so far.
    pub fn valid_len(&self) -> u64 {
        self.valid_len
    }

    /// The next valid record, or `None` at the end or at a truncated/corrupt record.
    pub fn next_record(&mut self) -> Option<CaseResult> {
        let h = self.header;
        let b = &mut self.buf;
        b.clear();
        let mut take = |n: usize, b: &mut Vec<u8>| -> Option<()> {
            let start = b.len();
            b.resize(start + n, 0);
            self.input.read_exact(&mut b[start..]).ok()
        };
        take(4 + 8 + 1 + 4, b)?;
        if &b[..4] != RECORD {
            return None;
        }
        let row = u64::from_le_bytes(b[4..12].try_into().ok()?) as usize;
        let status = Status::from_code(b[12] as i8)?;
        let msg_len = u32::from_le_bytes(b[13..17].try_into().ok()?) as usize;
        take(msg_len, b)?;
        let message = String::from_utf8(b[17..17 + msg_len].to_vec()).ok()?;
        let ok = status == Status::Ok;
        let n_series = if ok {
            (h.n_series * h.n_time) as usize
        } else {
            0
        };
        let n_spectra = if ok {
            (h.n_spectra * h.n_freq) as usize
        } else {
            0
        };
        let n_values = n_series + n_spectra + h.n_metrics as usize;
        let values_at = b.len();
        take(8 * n_values + 8, b)?;
        let sum_at = b.len() - 8;
        if fnv1a(&[&b[..sum_at]]) != u64::from_le_bytes(b[sum_at..].try_into().ok()?) {
            return None;
        }
        let values: Vec<f64> = b[values_at..sum_at]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        let split = |v: &[f64], n: u64| -> Vec<Vec<f64>> {
            if n == 0 {
                Vec::new()
            } else {
                v.chunks(n as usize).map(<[f64]>::to_vec).collect()
            }
        };
        self.valid_len += b.len() as u64;
        Some(CaseResult {
            row,
            status,
            message,
            series: if ok {
                split(&values[..n_series], h.n_time)
            } else {
                Vec::new()
            },
            spectra: if ok {
                split(&values[n_series..n_series + n_spectra], h.n_freq)
            } else {
                Vec::new()
            },
            metrics: values[n_series + n_spectra..].to_vec(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(row: usize, ok: bool) -> CaseResult {
        CaseResult {
            row,
            status: if ok { Status::Ok } else { Status::Failed },
            message: if ok {
                String::new()
            } else {
                "step size underflow".into()
            },
            series: if ok {
                vec![vec![row as f64, 1.5, -2.0]; 2]
            } else {
                Vec::new()
            },
            spectra: if ok { vec![vec![0.25; 2]] } else { Vec::new() },
            metrics: vec![row as f64, f64::NAN],
        }
    }

    #[test]
    fn round_trips_and_stops_at_a_torn_record() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("j");
        let header = JournalHeader {
            fingerprint: 7,
            n_time: 3,
            n_series: 2,
            n_freq: 2,
            n_spectra: 1,
            n_metrics: 2,
        };
        let mut w = JournalWriter::create(&path, &header).unwrap();
        for (row, ok) in [(4, true), (1, false), (2, true)] {
            w.write(&record(row, ok)).unwrap();
        }
        drop(w);
        // A kill in the middle of a fourth record leaves a torn tail.
        let full = std::fs::metadata(&path).unwrap().len();
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"CASE\x09\x00\x00").unwrap();
        drop(f);
        let mut r = JournalReader::open(&path, &header).unwrap();
        let mut rows = Vec::new();
        while let Some(rec) = r.next_record() {
            let want = record(rec.row, rec.status == Status::Ok);
            assert_eq!(format!("{rec:?}"), format!("{want:?}")); // NaN-aware equality
            rows.push(rec.row);
        }
        assert_eq!(rows, [4, 1, 2]);
        assert_eq!(r.valid_len(), full);
        let other = JournalHeader {
            fingerprint: 8,
            ..header
        };
        assert!(matches!(
            JournalReader::open(&path, &other),
            Err(JournalError::Mismatch { .. })
        ));
    }
}
