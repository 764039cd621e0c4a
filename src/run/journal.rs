//! The crash journal: every finished case is recorded here once its chunks are in the
//! partial HDF5 file, so a run killed at any moment can resume without recomputing it.
//!
//! The HDF5 file is written as `OUT.h5.partial` and renamed to `OUT.h5` only when
//! complete (an atomic rename), so `OUT.h5` is either absent or whole. The journal
//! `OUT.h5.journal` is deleted after the rename.
//!
//! The journal does not hold the chunks, so the bytes are written once: a case's record
//! has the partial file's length before its chunks were written and, per chunk, its
//! length, first and last eight bytes and CRC-32. A killed run's partial file is not readable as
//! HDF5 (its metadata was never flushed), but its chunks' bytes are where HDF5 wrote
//! them: `H5Dwrite_chunk` hands raw data straight to the file driver, and a new chunk's
//! space is allocated at the end of the file, so a case's chunks follow that length in
//! order, with at most some HDF5 metadata between them. Resuming finds each one there
//! (its first and last bytes, then its CRC over its length), and a case with a chunk it
//! does not find is run again. (HDF5 1.10 can tell a chunk's address, `H5Dget_chunk_info_by_coord`,
//! but by a scan of the dataset's chunks: asked per case, a 2 000-case study's writer
//! spent 0.9 ms per case on it against 0.1 ms at 200 cases.)
//!
//! Resuming never changes the files it reads: it writes the other of the two partial
//! files ([`DataFile`]: `OUT.h5.partial`, `OUT.h5.partial.resumed`) and a new journal
//! `OUT.h5.journal.new` that names it, replays into them, then renames the new journal
//! over the old one (the switch, atomic) and deletes the old partial file. A kill at
//! any moment leaves a journal whose partial file holds its chunks.
//!
//! A case's chunks reach the writer thread in a [`JournalRecord`]: a worker encodes the
//! series and spectra into the chunks the study file stores ([`ChunkEncoder`]) and
//! checksums each. The writer thread hands the chunks to HDF5's direct chunk write,
//! which says the file's length before them, and appends the record with that length
//! ([`JournalWriter::write`]).
//!
//! Format: a header (magic, fingerprint of the study, array sizes, storage, the partial
//! file), then records `[b"CASE", row u64, status i8, message length u32, message
//! bytes, number of series u32, number of spectra u32, partial file length before the
//! chunks u64, per chunk (first 8 bytes, last 8 bytes, length u64, CRC-32 u32), number
//! of metrics
//! u32, metrics f64 each, number of replicate messages u32, per message its length u32
//! and bytes, CRC-32 of the record u32]`, little-endian. Reading stops at the first truncated or corrupt record (a kill
//! during a write).

use std::fs::File;
use std::io::{self, BufReader, Read, Write};
use std::ops::Range;
use std::os::unix::fs::FileExt;
use std::path::Path;

use super::case::CaseResult;
use crate::output::{
    sync_parent, ChunkEncoder, DataFile, EncodedRecord, Status, Storage, StudyFileError,
    StudyWriter,
};

const MAGIC: &[u8; 8] = b"SRJOURN5";
/// What the magic of every studyrun journal format starts with.
const MAGIC_STEM: &[u8; 7] = b"SRJOURN";
const RECORD: &[u8; 4] = b"CASE";
/// Bytes of a record before its message: tag, row, status, message length.
const FIXED: usize = 4 + 8 + 1 + 4;
/// Bytes of a chunk's entry in a record: first and last bytes, length, CRC-32.
const CHUNK_ENTRY: usize = 2 * PREFIX + 8 + 4;
/// Bytes of each end of a chunk that its record keeps, to find it again.
const PREFIX: usize = 8;
/// Most bytes of HDF5 metadata resuming expects between a case's chunks, all told: it
/// looks for them between the recorded file length and that plus the chunks' size and
/// this.
const SEARCH_SLACK: u64 = 1 << 20;

/// What a journal must match to be resumed: the study, the array sizes and storage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JournalHeader {
    /// Fingerprint of the study (grid text, version, shard).
    pub fingerprint: u64,
    /// Samples per series.
    pub n_time: u64,
    /// Number of series per case.
    pub n_series: u64,
    /// Bins of the longest spectrum-like row (spectra and spectral kurtoses).
    pub n_freq: u64,
    /// Number of spectrum-like rows per case (spectra and spectral kurtoses).
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

/// CRC-32 (zlib's): of a record, what tells a whole record from a torn one; of a
/// chunk, what tells its bytes in the partial file from anything else.
fn checksum(bytes: &[u8]) -> u32 {
    zlib_rs::crc32::crc32(0, bytes)
}

/// One finished case on its way to the study file: its series and spectra as the
/// chunks the file stores, with their checksums, and its scalars.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalRecord {
    row: usize,
    status: Status,
    message: String,
    /// Why each replicate failed (see [`CaseResult::replicate_messages`]).
    replicate_messages: Vec<String>,
    n_series: usize,
    /// The stored chunks, one after the other (series, then spectra).
    bytes: Vec<u8>,
    chunks: Vec<Range<usize>>,
    /// CRC-32 of each chunk.
    sums: Vec<u32>,
    metrics: Vec<f64>,
}

impl JournalRecord {
    /// Encodes `result`: its series and spectra into chunks by `encoder` (which must
    /// encode for the study file's storage), each with its checksum. Meant for the
    /// worker thread that computed the case.
    pub fn encode(result: &CaseResult, encoder: &mut ChunkEncoder) -> Self {
        let raw: usize = result
            .series
            .iter()
            .chain(&result.spectra)
            .map(|r| 8 * r.len())
            .sum();
        let mut bytes = Vec::with_capacity(raw + raw / 64 + 64);
        let mut chunks = Vec::with_capacity(result.series.len() + result.spectra.len());
        for values in result.series.iter().chain(&result.spectra) {
            let start = bytes.len();
            encoder.encode(values, &mut bytes);
            chunks.push(start..bytes.len());
        }
        let sums = chunks.iter().map(|c| checksum(&bytes[c.clone()])).collect();
        Self {
            row: result.row,
            status: result.status,
            message: result.message.clone(),
            replicate_messages: result.replicate_messages.clone(),
            n_series: result.series.len(),
            bytes,
            chunks,
            sums,
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

    /// How many of its replicates failed.
    pub fn failed_replicates(&self) -> usize {
        self.replicate_messages
            .iter()
            .filter(|m| !m.is_empty())
            .count()
    }

    /// Size of the chunks (series and spectra as stored) in bytes.
    pub fn chunk_bytes(&self) -> usize {
        self.bytes.len()
    }

    /// Writes the case into the study file (its chunks go in unchanged) and returns
    /// the file's length before, for [`JournalWriter::write`].
    pub fn write_to(&self, writer: &mut StudyWriter) -> Result<u64, StudyFileError> {
        let chunks: Vec<&[u8]> = self.chunks.iter().map(|c| &self.bytes[c.clone()]).collect();
        let (series, spectra) = chunks.split_at(self.n_series);
        writer.write_encoded(
            self.row,
            &EncodedRecord {
                series,
                spectra,
                metrics: &self.metrics,
                status: self.status,
                message: &self.message,
                replicate_messages: &self.replicate_messages,
            },
        )
    }
}

/// Appends records; every record is written whole and handed to the OS.
pub struct JournalWriter {
    file: File,
    /// A record's bytes, reused.
    buf: Vec<u8>,
}

impl JournalWriter {
    /// A new journal at `path` (replacing any file there) of cases whose chunks lie in
    /// the partial file `data`; its header and its name are on the disk when this
    /// returns.
    pub fn create(path: &Path, header: &JournalHeader, data: DataFile) -> io::Result<Self> {
        let mut file = File::create(path)?;
        let mut b = header.bytes();
        b.push(data.code());
        let sum = checksum(&b);
        b.extend(sum.to_le_bytes());
        file.write_all(&b)?;
        file.sync_all()?;
        sync_parent(path)?;
        Ok(Self {
            file,
            buf: Vec::new(),
        })
    }

    /// Appends `record`, whose chunks [`JournalRecord::write_to`] wrote into the partial
    /// file when it was `before` bytes long.
    pub fn write(&mut self, record: &JournalRecord, before: u64) -> io::Result<()> {
        let b = &mut self.buf;
        b.clear();
        b.extend(RECORD);
        b.extend((record.row as u64).to_le_bytes());
        b.push(record.status.code() as u8);
        b.extend((record.message.len() as u32).to_le_bytes());
        b.extend(record.message.as_bytes());
        b.extend((record.n_series as u32).to_le_bytes());
        b.extend(((record.chunks.len() - record.n_series) as u32).to_le_bytes());
        b.extend(before.to_le_bytes());
        for (chunk, sum) in record.chunks.iter().zip(&record.sums) {
            let (head, tail) = ends(&record.bytes[chunk.clone()]);
            b.extend(head);
            b.extend(tail);
            b.extend((chunk.len() as u64).to_le_bytes());
            b.extend(sum.to_le_bytes());
        }
        b.extend((record.metrics.len() as u32).to_le_bytes());
        for v in &record.metrics {
            b.extend(v.to_le_bytes());
        }
        b.extend((record.replicate_messages.len() as u32).to_le_bytes());
        for m in &record.replicate_messages {
            b.extend((m.len() as u32).to_le_bytes());
            b.extend(m.as_bytes());
        }
        let sum = checksum(b);
        b.extend(sum.to_le_bytes());
        self.file.write_all(b)
    }
}

/// A chunk's first and last [`PREFIX`] bytes (zero-padded if it is shorter).
fn ends(chunk: &[u8]) -> ([u8; PREFIX], [u8; PREFIX]) {
    let n = chunk.len().min(PREFIX);
    let (mut head, mut tail) = ([0; PREFIX], [0; PREFIX]);
    head[..n].copy_from_slice(&chunk[..n]);
    tail[..n].copy_from_slice(&chunk[chunk.len() - n..]);
    (head, tail)
}

/// What a record keeps of a chunk, to find it again.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ChunkMark {
    head: [u8; PREFIX],
    tail: [u8; PREFIX],
    len: u64,
    sum: u32,
}

impl ChunkMark {
    /// Where in `window`, at or after `from`, the chunk lies: the first place where
    /// its first bytes, its last bytes and then its checksum match. (The last bytes
    /// keep the checksum off the many false starts that runs of equal bytes, such as
    /// unwritten space or an uncompressed series of zeros, would give.)
    fn find(&self, window: &[u8], from: usize) -> Option<usize> {
        let len = usize::try_from(self.len).ok()?;
        if len == 0 {
            return Some(from);
        }
        let n = len.min(PREFIX);
        let (head, tail) = (&self.head[..n], &self.tail[..n]);
        let last = window.len().checked_sub(len)?;
        (from..=last).find(|&at| {
            window[at..at + n] == *head
                && window[at + len - n..at + len] == *tail
                && checksum(&window[at..at + len]) == self.sum
        })
    }
}

/// A case as the journal records it: its scalars and how to find its chunks.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalEntry {
    row: usize,
    status: Status,
    message: String,
    replicate_messages: Vec<String>,
    n_series: usize,
    /// The partial file's length before the chunks were written.
    before: u64,
    chunks: Vec<ChunkMark>,
    metrics: Vec<f64>,
}

impl JournalEntry {
    /// The case's row in the study file.
    pub fn row(&self) -> usize {
        self.row
    }

    /// The case with its chunks found in `data` (the journal's partial file), or
    /// `None` if a chunk is not there: in order, after the recorded file length, within
    /// [`SEARCH_SLACK`] bytes of other things, with its first bytes and checksum.
    pub fn load(&self, data: &File) -> Option<JournalRecord> {
        let total: u64 = self.chunks.iter().map(|c| c.len).sum();
        if self.chunks.is_empty() {
            // A failed case: nothing to find (the recorded length may even lie past
            // the end of the file, in space HDF5 had allocated but not yet written).
            return Some(self.record(Vec::new(), Vec::new()));
        }
        let end = data
            .metadata()
            .ok()?
            .len()
            .min(self.before + total + SEARCH_SLACK);
        let mut window = vec![0u8; usize::try_from(end.checked_sub(self.before)?).ok()?];
        data.read_exact_at(&mut window, self.before).ok()?;
        let mut bytes = Vec::with_capacity(usize::try_from(total).ok()?);
        let mut ranges = Vec::with_capacity(self.chunks.len());
        let mut cursor = 0;
        for mark in &self.chunks {
            let at = mark.find(&window, cursor)?;
            cursor = at + mark.len as usize;
            let start = bytes.len();
            bytes.extend_from_slice(&window[at..cursor]);
            ranges.push(start..bytes.len());
        }
        Some(self.record(bytes, ranges))
    }

    /// The record of this case with its chunks, `chunks` in `bytes`.
    fn record(&self, bytes: Vec<u8>, chunks: Vec<Range<usize>>) -> JournalRecord {
        JournalRecord {
            row: self.row,
            status: self.status,
            message: self.message.clone(),
            replicate_messages: self.replicate_messages.clone(),
            n_series: self.n_series,
            bytes,
            chunks,
            sums: self.chunks.iter().map(|c| c.sum).collect(),
            metrics: self.metrics.clone(),
        }
    }
}

/// Reads the valid records of a journal, one at a time.
pub struct JournalReader {
    input: BufReader<File>,
    header: JournalHeader,
    data: DataFile,
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
    /// The journal ends before its header does: its run was stopped before it
    /// recorded anything, so nothing is lost by starting over.
    #[error("the journal {path} ends inside its header")]
    Unstarted {
        /// The journal.
        path: String,
    },
    /// The journal's header is damaged: it cannot say which study it belongs to.
    #[error("the journal {path} is damaged ({what}); run with --force to start over")]
    Damaged {
        /// The journal.
        path: String,
        /// What is wrong with its header.
        what: &'static str,
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
        let mut got = vec![0u8; want.len() + 1 + 4];
        match input.read_exact(&mut got) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => {
                return Err(JournalError::Unstarted {
                    path: path.display().to_string(),
                })
            }
            Err(e) => return Err(io_err(e)),
        }
        let damaged = |what| JournalError::Damaged {
            path: path.display().to_string(),
            what,
        };
        let (content, sum) = got.split_at(want.len() + 1);
        if !content.starts_with(MAGIC_STEM) {
            return Err(damaged("it does not start like a studyrun journal"));
        }
        if content.starts_with(MAGIC) && checksum(content).to_le_bytes() != sum {
            return Err(damaged("its header's checksum does not match"));
        }
        if content[..want.len()] != want[..] {
            return Err(JournalError::Mismatch {
                path: path.display().to_string(),
            });
        }
        let data = DataFile::from_code(content[want.len()])
            .ok_or_else(|| damaged("it names no partial file"))?;
        Ok(Self {
            input,
            header: *expected,
            data,
        })
    }

    /// The partial file the journal's chunks lie in.
    pub fn data_file(&self) -> DataFile {
        self.data
    }

    /// The next valid record, or `None` at the end or at a truncated/corrupt record.
    pub fn next_entry(&mut self) -> Option<JournalEntry> {
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
        let u64_at =
            |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"));
        take(FIXED as u64, &mut b)?;
        if &b[..4] != RECORD {
            return None;
        }
        let row = usize::try_from(u64_at(&b, 4)).ok()?;
        let status = Status::from_code(b[12] as i8)?;
        let message = take(u64::from(u32_at(&b, 13)), &mut b)?;
        let message = std::str::from_utf8(&b[message]).ok()?.to_owned();
        let counts = take(8, &mut b)?;
        let n_series = u32_at(&b, counts.start) as usize;
        let n_spectra = u32_at(&b, counts.start + 4) as usize;
        let whole = (n_series as u64, n_spectra as u64) == (h.n_series, h.n_spectra);
        if !whole && (n_series, n_spectra) != (0, 0) {
            return None;
        }
        let before = take(8, &mut b)?;
        let before = u64_at(&b, before.start);
        let entries = take((CHUNK_ENTRY * (n_series + n_spectra)) as u64, &mut b)?;
        let mut chunks = Vec::with_capacity(n_series + n_spectra);
        for (k, e) in b[entries].chunks_exact(CHUNK_ENTRY).enumerate() {
            let mark = ChunkMark {
                head: e[..PREFIX].try_into().expect("PREFIX bytes"),
                tail: e[PREFIX..2 * PREFIX].try_into().expect("PREFIX bytes"),
                len: u64_at(e, 2 * PREFIX),
                sum: u32_at(e, 2 * PREFIX + 8),
            };
            let dim = if k < n_series { h.n_time } else { h.n_freq };
            if mark.len > h.max_chunk(dim) {
                return None;
            }
            chunks.push(mark);
        }
        let n_metrics = take(4, &mut b)?;
        if u64::from(u32_at(&b, n_metrics.start)) != h.n_metrics {
            return None;
        }
        let metrics = take(8 * h.n_metrics, &mut b)?;
        let n_messages = take(4, &mut b)?;
        let n_messages = u32_at(&b, n_messages.start);
        let mut replicate_messages = Vec::new();
        for _ in 0..n_messages {
            let len = take(4, &mut b)?;
            let text = take(u64::from(u32_at(&b, len.start)), &mut b)?;
            replicate_messages.push(std::str::from_utf8(&b[text]).ok()?.to_owned());
        }
        let sum = take(4, &mut b)?;
        if checksum(&b[..sum.start]) != u32_at(&b, sum.start) {
            return None;
        }
        let metrics = b[metrics]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        Some(JournalEntry {
            row,
            status,
            message,
            replicate_messages,
            n_series,
            before,
            chunks,
            metrics,
        })
    }
}

#[cfg(test)]
impl JournalRecord {
    /// What two runs of the same case share whatever their timing: the row, status,
    /// stored bytes and checksums, and the bits of every metric value but the one at
    /// `wall_time` (the case's wall-clock time).
    pub(super) fn data_bits(&self, wall_time: usize) -> (usize, Status, &[u8], &[u32], Vec<u64>) {
        let metrics = self.metrics.iter().enumerate();
        let bits = metrics
            .filter(|&(i, _)| i != wall_time)
            .map(|(_, v)| v.to_bits())
            .collect();
        (self.row, self.status, &self.bytes, &self.sums, bits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

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
            replicate_messages: if ok {
                vec![String::new(), format!("replicate 1 of row {row} failed")]
            } else {
                Vec::new()
            },
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

    /// Writes `records` the way a run does: each record's chunks at the end of the
    /// data file `data` (each after 100 bytes of something else, as HDF5 puts
    /// metadata between chunks), then the record into a new journal at `path`.
    fn write_journal(
        path: &Path,
        data: &Path,
        header: &JournalHeader,
        records: &[JournalRecord],
    ) -> u64 {
        let mut file = File::create(data).unwrap();
        let mut w = JournalWriter::create(path, header, DataFile::Resumed).unwrap();
        let mut at = 0u64;
        for rec in records {
            let before = at;
            for c in &rec.chunks {
                file.write_all_at(&[0x78; 100], at).unwrap(); // a gap
                at += 100;
                file.write_all_at(&rec.bytes[c.clone()], at).unwrap();
                at += c.len() as u64;
            }
            w.write(rec, before).unwrap();
        }
        file.flush().unwrap();
        std::fs::metadata(path).unwrap().len()
    }

    /// A scratch directory with the paths of a journal and its data file in it, the
    /// header of study `fingerprint`, and the records of `cases` (row, ok).
    fn scene(
        fingerprint: u64,
        cases: &[(usize, bool)],
    ) -> (
        tempfile::TempDir,
        PathBuf,
        PathBuf,
        JournalHeader,
        Vec<JournalRecord>,
    ) {
        let dir = tempfile::tempdir().unwrap();
        let (path, data) = (dir.path().join("j"), dir.path().join("d"));
        let header = header(fingerprint);
        let mut encoder = ChunkEncoder::new(header.storage);
        let records = cases
            .iter()
            .map(|&(row, ok)| JournalRecord::encode(&result(row, ok), &mut encoder))
            .collect();
        (dir, path, data, header, records)
    }

    #[test]
    fn round_trips_through_the_data_file_and_stops_at_a_torn_record() {
        let (_dir, path, data, header, written) = scene(7, &[(4, true), (1, false), (2, true)]);
        let full = write_journal(&path, &data, &header, &written);
        // A kill in the middle of a fourth record leaves a torn tail.
        let torn = std::fs::read(&path).unwrap()[header.bytes().len() + 5..][..40].to_vec();
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        f.write_all(&torn).unwrap();
        drop(f);
        assert!(std::fs::metadata(&path).unwrap().len() > full);
        let mut r = JournalReader::open(&path, &header).unwrap();
        assert_eq!(r.data_file(), DataFile::Resumed);
        let data = File::open(&data).unwrap();
        let mut read = Vec::new();
        while let Some(entry) = r.next_entry() {
            read.push(entry.load(&data).expect("intact chunks"));
        }
        assert_eq!(read.len(), 3);
        for (got, want) in read.iter().zip(&written) {
            assert_eq!(format!("{got:?}"), format!("{want:?}")); // NaN-aware equality
        }
        assert_eq!(read[1].message, "step size underflow");
        assert_eq!(read[0].replicate_messages[1], "replicate 1 of row 4 failed");
        assert_eq!(read[1].chunk_bytes(), 0);
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
    fn a_damaged_header_is_reported_as_damage_not_as_another_study() {
        let (_dir, path, data, header, written) = scene(9, &[(0, true)]);
        write_journal(&path, &data, &header, &written);
        let good = std::fs::read(&path).unwrap();
        for (at, want) in [
            (0, "does not start like"),
            (12, "checksum"),
            (70, "checksum"),
        ] {
            let mut bytes = good.clone();
            bytes[at] ^= 0x04;
            std::fs::write(&path, bytes).unwrap();
            match JournalReader::open(&path, &header) {
                Err(e @ JournalError::Damaged { .. }) => {
                    assert!(e.to_string().contains(want), "byte {at}: {e}")
                }
                other => panic!("byte {at}: {:?}", other.map(|r| r.data_file())),
            }
        }
    }

    #[test]
    fn a_corrupt_byte_ends_the_valid_records() {
        let (_dir, path, data, header, written) = scene(1, &[(0, true), (1, true)]);
        write_journal(&path, &data, &header, &written[..1]);
        let first = std::fs::metadata(&path).unwrap().len() as usize;
        write_journal(&path, &data, &header, &written);
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[first + 30] ^= 0x40;
        std::fs::write(&path, bytes).unwrap();
        let mut r = JournalReader::open(&path, &header).unwrap();
        assert_eq!(r.next_entry().map(|e| e.row()), Some(0));
        assert!(r.next_entry().is_none());
    }

    #[test]
    fn a_failed_case_loads_without_reading_the_data_file() {
        let (_dir, path, data, header, written) = scene(5, &[(3, false)]);
        File::create(&data).unwrap(); // empty
        let mut w = JournalWriter::create(&path, &header, DataFile::Partial).unwrap();
        // Recorded while HDF5 had space allocated past the end of the file.
        w.write(&written[0], 1 << 30).unwrap();
        drop(w);
        let mut r = JournalReader::open(&path, &header).unwrap();
        let entry = r.next_entry().unwrap();
        let got = entry
            .load(&File::open(&data).unwrap())
            .expect("nothing to find");
        assert_eq!(format!("{got:?}"), format!("{:?}", written[0]));
    }

    #[test]
    fn a_chunk_is_found_after_runs_of_its_own_first_bytes() {
        // An uncompressed chunk that starts with zeros, after unwritten (zero) space.
        let mut chunk = vec![0u8; 100];
        chunk.extend(1..=20u8);
        let (head, tail) = ends(&chunk);
        let mark = ChunkMark {
            head,
            tail,
            len: chunk.len() as u64,
            sum: checksum(&chunk),
        };
        let mut window = vec![0u8; 5000];
        window.extend(&chunk);
        window.extend([0u8; 100]);
        assert_eq!(mark.find(&window, 0), Some(5000));
        assert_eq!(mark.find(&window, 5001), None);
        assert_eq!(
            mark.find(&window[..5100], 0),
            None,
            "a cut chunk is not found"
        );
    }

    #[test]
    fn a_chunk_that_changed_in_the_data_file_is_not_loaded() {
        let (_dir, path, data, header, written) = scene(3, &[(0, true), (1, true)]);
        write_journal(&path, &data, &header, &written);
        // One byte inside the second record's last chunk.
        let mut bytes = std::fs::read(&data).unwrap();
        let at = bytes.len() - 2;
        bytes[at] ^= 0x01;
        std::fs::write(&data, bytes).unwrap();
        let mut r = JournalReader::open(&path, &header).unwrap();
        let data = File::open(&data).unwrap();
        let loaded: Vec<Option<usize>> = std::iter::from_fn(|| r.next_entry())
            .map(|e| e.load(&data).map(|rec| rec.row()))
            .collect();
        assert_eq!(loaded, [Some(0), None]);
    }
}
