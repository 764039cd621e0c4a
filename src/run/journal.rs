//! The crash journal: every finished case is appended here before it goes into the
//! HDF5 file, so a run killed at any moment can resume without recomputing it.
//!
//! The HDF5 file is written as `OUT.h5.partial` and renamed to `OUT.h5` only when
//! complete (an atomic rename), so `OUT.h5` is either absent or whole. The journal
//! `OUT.h5.journal` is deleted after the rename.
//!
//! A case's journal record is also the form in which it reaches the writer thread: a
//! worker encodes the series and spectra into the chunks the study file stores
//! ([`ChunkEncoder`]) straight into the record, and checksums it
//! ([`JournalRecord::encode`]). The writer thread appends the bytes to the journal and
//! hands the chunks to HDF5's direct chunk write; resuming replays the same records.
//!
//! Format: a header (magic, fingerprint of the study, array sizes, storage), then
//! records `[b"CASE", row u64, status i8, message length u32, message bytes, number of
//! series u32, number of spectra u32, chunk lengths u64 each, chunk bytes, number of
//! metrics u32, metrics f64 each, CRC-32 of the record u32]`, little-endian. Reading
//! stops at the first truncated or corrupt record (a kill during a write), which is
//! cut off before appending again.

use std::fs::{File, OpenOptions};
use std::io::{self, BufReader, Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::Path;

use super::case::CaseResult;
use crate::output::{ChunkEncoder, EncodedRecord, Status, Storage, StudyFileError, StudyWriter};

const MAGIC: &[u8; 8] = b"SRJOURN2";
const RECORD: &[u8; 4] = b"CASE";
/// Bytes of a record before its message: tag, row, status, message length.
const FIXED: usize = 4 + 8 + 1 + 4;

/// What a journal must match to be resumed: the study, the array sizes and storage.
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
    /// How the chunks in the records are encoded.
    pub storage: Storage,
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
            u64::from(self.storage.float32),
            u64::from(self.storage.deflate_level),
        ] {
            b.extend(v.to_le_bytes());
        }
        b
    }

    /// Most bytes one stored chunk of `len` elements can take (the encoder's stored
    /// blocks add 5 bytes per 64 KiB, the zlib frame 11): a bound for reading.
    fn max_chunk(&self, len: u64) -> u64 {
        let raw = len * if self.storage.float32 { 4 } else { 8 };
        raw + raw / 1024 + 64
    }
}

/// FNV-1a, 64 bit: the study fingerprint.
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

/// CRC-32 (zlib's) of a record: what tells a whole record from a torn one.
fn checksum(bytes: &[u8]) -> u32 {
    zlib_rs::crc32::crc32(0, bytes)
}

/// One finished case as a journal record: its bytes (with the series and spectra
/// inside as stored chunks) and where its parts lie in them.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalRecord {
    bytes: Vec<u8>,
    row: usize,
    status: Status,
    message: Range<usize>,
    n_series: usize,
    chunks: Vec<Range<usize>>,
    metrics: Vec<f64>,
}

impl JournalRecord {
    /// Encodes `result`: its series and spectra into chunks by `encoder` (which must
    /// encode for the study file's storage), then the whole record with its checksum.
    /// Meant for the worker thread that computed the case.
    pub fn encode(result: &CaseResult, encoder: &mut ChunkEncoder) -> Self {
        let rows = result.series.len() + result.spectra.len();
        let raw: usize = result
            .series
            .iter()
            .chain(&result.spectra)
            .map(|r| 8 * r.len())
            .sum();
        let mut b = Vec::with_capacity(FIXED + result.message.len() + 8 * rows + raw + 64);
        b.extend(RECORD);
        b.extend((result.row as u64).to_le_bytes());
        b.push(result.status.code() as u8);
        b.extend((result.message.len() as u32).to_le_bytes());
        b.extend(result.message.as_bytes());
        let message = FIXED..FIXED + result.message.len();
        b.extend((result.series.len() as u32).to_le_bytes());
        b.extend((result.spectra.len() as u32).to_le_bytes());
        let lengths_at = b.len();
        b.resize(lengths_at + 8 * rows, 0);
        let mut chunks = Vec::with_capacity(rows);
        for values in result.series.iter().chain(&result.spectra) {
            let start = b.len();
            encoder.encode(values, &mut b);
            chunks.push(start..b.len());
        }
        for (k, c) in chunks.iter().enumerate() {
            let at = lengths_at + 8 * k;
            b[at..at + 8].copy_from_slice(&(c.len() as u64).to_le_bytes());
        }
        b.extend((result.metrics.len() as u32).to_le_bytes());
        for v in &result.metrics {
            b.extend(v.to_le_bytes());
        }
        let sum = checksum(&b);
        b.extend(sum.to_le_bytes());
        Self {
            bytes: b,
            row: result.row,
            status: result.status,
            message,
            n_series: result.series.len(),
            chunks,
            metrics: result.metrics.clone(),
        }
    }

    /// The case's row in the study file.
    pub fn row(&self) -> usize {
        self.row
    }

    /// Ok or failed.
    pub fn status(&self) -> Status {
        self.status
    }

    /// Why the case failed (empty when ok).
    pub fn message(&self) -> &str {
        std::str::from_utf8(&self.bytes[self.message.clone()]).expect("checked UTF-8")
    }

    /// One value per metric (NaN where unknown).
    pub fn metrics(&self) -> &[f64] {
        &self.metrics
    }

    /// The record's bytes, as the journal stores them.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Size of the chunks (series and spectra as stored) in bytes.
    pub fn chunk_bytes(&self) -> usize {
        self.chunks.iter().map(Range::len).sum()
    }

    /// Writes the case into the study file: its chunks go in unchanged.
    pub fn write_to(&self, writer: &mut StudyWriter) -> Result<(), StudyFileError> {
        let chunks: Vec<&[u8]> = self.chunks.iter().map(|c| &self.bytes[c.clone()]).collect();
        let (series, spectra) = chunks.split_at(self.n_series);
        writer.write_encoded(
            self.row,
            &EncodedRecord {
                series,
                spectra,
                metrics: &self.metrics,
                status: self.status,
                message: self.message(),
            },
        )
    }
}

/// Appends records; every record is written whole and handed to the OS.
pub struct JournalWriter {
    file: File,
}

impl JournalWriter {
    /// A new journal at `path` (replacing any file there).
    pub fn create(path: &Path, header: &JournalHeader) -> io::Result<Self> {
        let mut file = File::create(path)?;
        file.write_all(&header.bytes())?;
        Ok(Self { file })
    }

    /// Reopens the journal at `path` for appending after its first `valid_len` bytes.
    pub fn append(path: &Path, valid_len: u64) -> io::Result<Self> {
        let mut file = OpenOptions::new().write(true).open(path)?;
        file.set_len(valid_len)?;
        file.seek(SeekFrom::End(0))?;
        Ok(Self { file })
    }

    /// Appends one case.
    pub fn write(&mut self, record: &JournalRecord) -> io::Result<()> {
        self.file.write_all(&record.bytes)
    }
}

/// Reads the valid records of a journal, one at a time.
pub struct JournalReader {
    input: BufReader<File>,
    header: JournalHeader,
    /// Bytes of the header and the valid records read so far.
    valid_len: u64,
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
    /// The journal was written for another study, version, shard or journal format.
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
        })
    }

    /// Length in bytes of the header and every valid record read so far.
    pub fn valid_len(&self) -> u64 {
        self.valid_len
    }

    /// The next valid record, or `None` at the end or at a truncated/corrupt record.
    pub fn next_record(&mut self) -> Option<JournalRecord> {
        let h = self.header;
        let mut b = Vec::new();
        let mut take = |n: u64, b: &mut Vec<u8>| -> Option<Range<usize>> {
            let start = b.len();
            b.resize(start + usize::try_from(n).ok()?, 0);
            self.input.read_exact(&mut b[start..]).ok()?;
            Some(start..b.len())
        };
        let u32_at =
            |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"));
        take(FIXED as u64, &mut b)?;
        if &b[..4] != RECORD {
            return None;
        }
        let row = u64::from_le_bytes(b[4..12].try_into().ok()?) as usize;
        let status = Status::from_code(b[12] as i8)?;
        let message = take(u64::from(u32_at(&b, 13)), &mut b)?;
        std::str::from_utf8(&b[message.clone()]).ok()?;
        let counts = take(8, &mut b)?;
        let n_series = u32_at(&b, counts.start) as usize;
        let n_spectra = u32_at(&b, counts.start + 4) as usize;
        let whole = (n_series as u64, n_spectra as u64) == (h.n_series, h.n_spectra);
        if !whole && (n_series, n_spectra) != (0, 0) {
            return None;
        }
        let lengths = take(8 * (n_series + n_spectra) as u64, &mut b)?;
        let mut chunks = Vec::with_capacity(n_series + n_spectra);
        for (k, len) in b[lengths].chunks_exact(8).enumerate() {
            let len = u64::from_le_bytes(len.try_into().ok()?);
            let dim = if k < n_series { h.n_time } else { h.n_freq };
            if len > h.max_chunk(dim) {
                return None;
            }
            chunks.push(len);
        }
        let chunks = chunks
            .into_iter()
            .map(|len| take(len, &mut b))
            .collect::<Option<Vec<_>>>()?;
        let n_metrics = take(4, &mut b)?;
        if u64::from(u32_at(&b, n_metrics.start)) != h.n_metrics {
            return None;
        }
        let metrics = take(8 * h.n_metrics, &mut b)?;
        let sum = take(4, &mut b)?;
        if checksum(&b[..sum.start]) != u32_at(&b, sum.start) {
            return None;
        }
        let metrics = b[metrics]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        self.valid_len += b.len() as u64;
        Some(JournalRecord {
            bytes: b,
            row,
            status,
            message,
            n_series,
            chunks,
            metrics,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(row: usize, ok: bool) -> CaseResult {
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
            cost: Default::default(),
        }
    }

    /// The header of a journal of [`result`]s.
    fn header(fingerprint: u64) -> JournalHeader {
        JournalHeader {
            fingerprint,
            n_time: 3,
            n_series: 2,
            n_freq: 2,
            n_spectra: 1,
            n_metrics: 2,
            storage: Storage::default(),
        }
    }

    #[test]
    fn round_trips_and_stops_at_a_torn_record() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("j");
        let header = header(7);
        let mut encoder = ChunkEncoder::new(header.storage);
        let mut w = JournalWriter::create(&path, &header).unwrap();
        let written: Vec<JournalRecord> = [(4, true), (1, false), (2, true)]
            .into_iter()
            .map(|(row, ok)| JournalRecord::encode(&result(row, ok), &mut encoder))
            .collect();
        for rec in &written {
            w.write(rec).unwrap();
        }
        drop(w);
        // A kill in the middle of a fourth record leaves a torn tail.
        let full = std::fs::metadata(&path).unwrap().len();
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(&written[0].bytes()[..40]).unwrap();
        drop(f);
        let mut r = JournalReader::open(&path, &header).unwrap();
        let mut read = Vec::new();
        while let Some(rec) = r.next_record() {
            read.push(rec);
        }
        assert_eq!(read.len(), 3);
        for (got, want) in read.iter().zip(&written) {
            assert_eq!(got.bytes(), want.bytes());
            assert_eq!(format!("{got:?}"), format!("{want:?}")); // NaN-aware equality
        }
        assert_eq!(read[1].message(), "step size underflow");
        assert_eq!(read[1].chunk_bytes(), 0);
        assert_eq!(r.valid_len(), full);
        for other in [
            JournalHeader {
                fingerprint: 8,
                ..header
            },
            JournalHeader {
                storage: Storage {
                    float32: true,
                    ..header.storage
                },
                ..header
            },
        ] {
            assert!(matches!(
                JournalReader::open(&path, &other),
                Err(JournalError::Mismatch { .. })
            ));
        }
    }

    #[test]
    fn a_corrupt_byte_ends_the_valid_records() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("j");
        let header = header(1);
        let mut encoder = ChunkEncoder::new(header.storage);
        let mut w = JournalWriter::create(&path, &header).unwrap();
        let first = JournalRecord::encode(&result(0, true), &mut encoder);
        w.write(&first).unwrap();
        w.write(&JournalRecord::encode(&result(1, true), &mut encoder))
            .unwrap();
        drop(w);
        let mut bytes = std::fs::read(&path).unwrap();
        let at = header.bytes().len() + first.bytes().len() + 30;
        bytes[at] ^= 0x40;
        std::fs::write(&path, bytes).unwrap();
        let mut r = JournalReader::open(&path, &header).unwrap();
        assert_eq!(r.next_record().map(|rec| rec.row()), Some(0));
        assert!(r.next_record().is_none());
        assert_eq!(
            r.valid_len(),
            (header.bytes().len() + first.bytes().len()) as u64
        );
    }
}
