//! The ZIP archives NumPy's `savez` (stored members) and `savez_compressed`
//! (deflated members) write, ZIP64 records included.
//!
//! The central directory, found through the end-of-central-directory record at the
//! archive's end, lists the members: name, method, CRC-32, sizes and the offset of
//! each member's local header, after which its data follow. Sizes come from the
//! central directory (a streamed local header may hold zeros); a member's data are
//! checked against its CRC-32 after extraction.

use super::bytes::{inflate, inflated_bound, Cursor, Endian};
use super::Fault;

/// Signature of the end-of-central-directory record.
const EOCD: &[u8] = b"PK\x05\x06";
/// Signature of the ZIP64 end-of-central-directory locator.
const ZIP64_LOCATOR: &[u8] = b"PK\x06\x07";
/// Signature of the ZIP64 end-of-central-directory record.
const ZIP64_EOCD: &[u8] = b"PK\x06\x06";
/// Signature of a central directory entry.
const CENTRAL: &[u8] = b"PK\x01\x02";
/// Signature of a local file header.
const LOCAL: &[u8] = b"PK\x03\x04";
/// Bytes of the end-of-central-directory record without its comment.
const EOCD_LEN: usize = 22;
/// The ZIP64 extra field's header ID.
const ZIP64_EXTRA: u16 = 0x0001;
/// A 32-bit size or offset field that says "see the ZIP64 record".
const SEE_ZIP64: u32 = u32::MAX;

/// Compression methods read.
const STORED: u16 = 0;
const DEFLATED: u16 = 8;

const LE: Endian = Endian::Little;

/// One member as the central directory describes it.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Member {
    /// The member's name in the archive.
    pub(super) name: String,
    flags: u16,
    method: u16,
    crc: u32,
    compressed: u64,
    size: u64,
    offset: u64,
}

/// The members of the ZIP archive in `data`, in central-directory order.
pub(super) fn members(data: &[u8]) -> Result<Vec<Member>, Fault> {
    let (count, cd_offset) = directory(data)?;
    let mut c = Cursor::at(data, cd_offset, "the central directory")?;
    // Each entry takes at least 46 bytes, so `count` bounds no allocation here.
    let mut members = Vec::new();
    for i in 1..=count {
        let entry = central_entry(&mut c).map_err(|f| match f {
            Fault::Corrupt(m) => {
                Fault::Corrupt(format!("central directory entry {i} of {count}: {m}"))
            }
            other => other,
        })?;
        members.push(entry);
    }
    Ok(members)
}

/// The member count and central directory offset from the end records.
fn directory(data: &[u8]) -> Result<(u64, usize), Fault> {
    let not_zip =
        || Fault::Corrupt("not a ZIP archive (no end of central directory record)".into());
    let lowest = data.len().saturating_sub(EOCD_LEN + usize::from(u16::MAX));
    let at = (lowest..=data.len().saturating_sub(EOCD_LEN))
        .rev()
        .find(|&i| data.get(i..i + 4) == Some(EOCD))
        .ok_or_else(not_zip)?;
    let mut c = Cursor::at(data, at + 10, "the end of central directory record")?;
    let mut count = u64::from(c.u16(LE, "the member count")?);
    let _size = c.u32(LE, "the central directory size")?;
    let mut offset = u64::from(c.u32(LE, "the central directory offset")?);
    if count == u64::from(u16::MAX) || offset == u64::from(SEE_ZIP64) {
        (count, offset) = zip64_directory(data, at)?;
    }
    let offset = usize::try_from(offset)
        .ok()
        .filter(|&o| o <= at)
        .ok_or_else(|| {
            Fault::Corrupt(format!(
                "central directory offset {offset} is past the archive's end records"
            ))
        })?;
    Ok((count, offset))
}

/// The member count and central directory offset from the ZIP64 records, whose
/// locator sits just before the end-of-central-directory record at `eocd`.
fn zip64_directory(data: &[u8], eocd: usize) -> Result<(u64, u64), Fault> {
    let what = "the ZIP64 end of central directory locator";
    let mut c = Cursor::at(
        data,
        eocd.checked_sub(20).ok_or_else(|| missing(what))?,
        what,
    )?;
    if c.take(4, what)? != ZIP64_LOCATOR {
        return Err(missing(what));
    }
    let _disk = c.u32(LE, what)?;
    let record = c.u64(LE, what)?;
    let what = "the ZIP64 end of central directory record";
    let record = usize::try_from(record).map_err(|_| missing(what))?;
    let mut c = Cursor::at(data, record, what)?;
    if c.take(4, what)? != ZIP64_EOCD {
        return Err(missing(what));
    }
    c.take(28, what)?; // record size, versions, disk numbers, entries on this disk
    let count = c.u64(LE, what)?;
    let _size = c.u64(LE, what)?;
    Ok((count, c.u64(LE, what)?))
}

/// The fault for a ZIP record that is not where the archive says.
fn missing(what: &str) -> Fault {
    Fault::Corrupt(format!("{what} is missing or misplaced"))
}

/// One central directory entry at the cursor.
fn central_entry(c: &mut Cursor) -> Result<Member, Fault> {
    let what = "a central directory entry";
    if c.take(4, what)? != CENTRAL {
        return Err(Fault::Corrupt(format!(
            "no entry signature at byte {}",
            c.pos() - 4
        )));
    }
    c.take(4, what)?; // versions made by and needed
    let flags = c.u16(LE, what)?;
    let method = c.u16(LE, what)?;
    c.take(4, what)?; // modification time and date
    let crc = c.u32(LE, what)?;
    let compressed = c.u32(LE, what)?;
    let size = c.u32(LE, what)?;
    let name_len = usize::from(c.u16(LE, what)?);
    let extra_len = usize::from(c.u16(LE, what)?);
    let comment_len = usize::from(c.u16(LE, what)?);
    c.take(8, what)?; // disk number, internal and external attributes
    let offset = c.u32(LE, what)?;
    let name = String::from_utf8_lossy(c.take(name_len, what)?).into_owned();
    let extra = c.take(extra_len, what)?;
    c.take(comment_len, what)?;
    let mut wide = zip64_fields(extra);
    let mut widen = |v: u32| match v {
        SEE_ZIP64 => wide.next().unwrap_or(u64::from(v)),
        _ => u64::from(v),
    };
    // The ZIP64 field holds the sizes and offset that overflowed, in this order.
    let size = widen(size);
    let compressed = widen(compressed);
    let offset = widen(offset);
    Ok(Member {
        name,
        flags,
        method,
        crc,
        compressed,
        size,
        offset,
    })
}

/// The 64-bit values of the ZIP64 extra field among `extra`'s fields, in order.
fn zip64_fields(extra: &[u8]) -> impl Iterator<Item = u64> + '_ {
    let mut c = Cursor::new(extra);
    let mut field: &[u8] = &[];
    while let (Ok(id), Ok(len)) = (c.u16(LE, "an extra field"), c.u16(LE, "an extra field")) {
        match c.take(usize::from(len), "an extra field") {
            Ok(body) if id == ZIP64_EXTRA => {
                field = body;
                break;
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    field.chunks_exact(8).map(|b| {
        let mut a = [0; 8];
        a.copy_from_slice(b);
        u64::from_le_bytes(a)
    })
}

/// The uncompressed bytes of `member`, CRC-checked.
pub(super) fn extract(data: &[u8], member: &Member) -> Result<Vec<u8>, Fault> {
    let name = &member.name;
    if member.flags & 1 != 0 {
        return Err(Fault::Unsupported(format!("member `{name}` is encrypted")));
    }
    let what = format!("member `{name}`");
    let offset = usize::try_from(member.offset).unwrap_or(usize::MAX);
    let mut c = Cursor::at(data, offset, &what)?;
    if c.take(4, &what)? != LOCAL {
        return Err(Fault::Corrupt(format!(
            "{what}: no local header at byte {offset}"
        )));
    }
    c.take(22, &what)?; // versions, flags, method, time, date, CRC, sizes
    let name_len = usize::from(c.u16(LE, &what)?);
    let extra_len = usize::from(c.u16(LE, &what)?);
    c.take(name_len + extra_len, &what)?;
    let compressed = usize::try_from(member.compressed).unwrap_or(usize::MAX);
    let raw = c.take(compressed, &what)?;
    let size = usize::try_from(member.size).unwrap_or(usize::MAX);
    let bytes = match member.method {
        STORED => raw.to_vec(),
        DEFLATED => {
            let limit = size.min(inflated_bound(raw.len()));
            inflate(raw, false, limit).map_err(|e| Fault::Corrupt(format!("{what}: {e}")))?
        }
        m => {
            return Err(Fault::Unsupported(format!(
                "{what} uses compression method {m}; stored (0) and deflated (8) are read"
            )))
        }
    };
    if bytes.len() != size {
        return Err(Fault::Corrupt(format!(
            "{what} holds {} bytes, the directory says {size}",
            bytes.len()
        )));
    }
    if zlib_rs::crc32::crc32(0, &bytes) != member.crc {
        return Err(Fault::Corrupt(format!("{what} fails its CRC-32 check")));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An archive of one stored member `x.npy` holding `data`, its sizes and offset
    /// in ZIP64 extra fields; with `record`, its directory found through the ZIP64
    /// end records too.
    fn zip64(data: &[u8], record: bool) -> Vec<u8> {
        let crc = zlib_rs::crc32::crc32(0, data);
        let len = (data.len() as u64).to_le_bytes();
        let mut out = b"PK\x03\x04".to_vec();
        out.extend([45, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        out.extend(crc.to_le_bytes());
        out.extend([0xFF; 8]);
        out.extend([5, 0, 20, 0]);
        out.extend(b"x.npy");
        out.extend([1, 0, 16, 0]);
        out.extend(len);
        out.extend(len);
        out.extend(data);
        let cd = out.len();
        out.extend(b"PK\x01\x02");
        out.extend([45, 0, 45, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        out.extend(crc.to_le_bytes());
        out.extend([0xFF; 8]);
        out.extend([5, 0, 28, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        out.extend([0xFF; 4]);
        out.extend(b"x.npy");
        out.extend([1, 0, 24, 0]);
        out.extend(len);
        out.extend(len);
        out.extend(0u64.to_le_bytes());
        let cd_len = (out.len() - cd) as u64;
        let mut eocd = b"PK\x05\x06\0\0\0\0".to_vec();
        if record {
            let at = out.len() as u64;
            out.extend(b"PK\x06\x06");
            out.extend(44u64.to_le_bytes());
            out.extend([45, 0, 45, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
            for v in [1, 1, cd_len, cd as u64] {
                out.extend(v.to_le_bytes());
            }
            out.extend(b"PK\x06\x07\0\0\0\0");
            out.extend(at.to_le_bytes());
            out.extend(1u32.to_le_bytes());
            eocd.extend([0xFF; 12]);
        } else {
            eocd.extend([1, 0, 1, 0]);
            eocd.extend(u32::try_from(cd_len).unwrap().to_le_bytes());
            eocd.extend(u32::try_from(cd).unwrap().to_le_bytes());
        }
        out.extend(eocd);
        out.extend([0, 0]);
        out
    }

    #[test]
    fn zip64_sizes_and_end_records_are_followed() {
        let data = b"seventeen bytes!!";
        for record in [false, true] {
            let archive = zip64(data, record);
            let members = members(&archive).unwrap();
            assert_eq!(members.len(), 1, "record {record}");
            assert_eq!((members[0].name.as_str(), members[0].size), ("x.npy", 17));
            assert_eq!(extract(&archive, &members[0]).unwrap(), data);
        }
    }

    #[test]
    fn a_count_or_size_past_the_archive_is_refused_without_allocating_it() {
        let mut archive = zip64(b"data", false);
        let eocd = archive.len() - 22;
        // 65 534 members claimed, one there.
        archive[eocd + 10..eocd + 12].copy_from_slice(&[0xFE, 0xFF]);
        let Err(Fault::Corrupt(m)) = members(&archive) else {
            panic!("a directory of missing entries was read");
        };
        assert_eq!(
            m,
            "central directory entry 2 of 65534: no entry signature at byte 138"
        );
        let mut archive = zip64(b"data", false);
        // The ZIP64 field's compressed size, 16 bytes before the end of the directory.
        let compressed_at = archive.len() - 22 - 16;
        archive[compressed_at..compressed_at + 8].copy_from_slice(&(u64::MAX / 2).to_le_bytes());
        let member = &members(&archive).unwrap()[0];
        assert_eq!(member.compressed, u64::MAX / 2);
        let Err(Fault::Corrupt(m)) = extract(&archive, member) else {
            panic!("a member past the archive's end was read");
        };
        assert!(m.starts_with("truncated: member `x.npy`"), "{m}");
    }
}
