//! Strings read from a study file however a netCDF tool left them, and without letting
//! libhdf5 follow a variable-length string into a damaged file.
//!
//! netCDF tools store text in three ways: variable-length strings (studyrun, NC_STRING),
//! fixed-length strings (NC_CHAR: `ncatted`, xarray's netCDF4 engine, `_NCProperties`)
//! and, for an empty NC_CHAR attribute, a NULL dataspace. Their character set (ASCII or
//! UTF-8) says little: `ncatted` stores UTF-8 bytes in an ASCII-typed string. So
//! [`read_attribute`] and [`read_dataset`] take any of them: the bytes are decoded as
//! UTF-8 (invalid sequences replaced), fixed-length strings end at their first NUL
//! (and a space-padded one loses its trailing spaces), a NULL dataspace holds one
//! empty string.
//!
//! A variable-length string is stored as a reference (length u32, address of a global
//! heap collection, object index u32) to its bytes in a global heap collection. HDF5
//! 1.10 follows a damaged reference to a crash (`H5HG_read`) and loops forever on a
//! collection with a zeroed object header. Here libhdf5 only hands over the references
//! as stored: an HDF5 conversion from the variable-length string type to an opaque type
//! of the same size, which leaves the bytes as they are ([`raw_vlen_conv`]). The text is
//! then read from the collection by [`GlobalHeap`], with every offset and length
//! checked against the collection and the file: a damaged reference or collection is an
//! error naming what is wrong.

use std::collections::HashMap;
use std::ffi::{c_void, CStr};
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;
use std::sync::OnceLock;

use crate::signal::{AttrValue, DESCRIPTIVE_ATTRIBUTES};
use hdf5::types::VarLenUnicode;
use hdf5::{Attribute, Dataset, Datatype};
use hdf5_sys::h5::{herr_t, H5free_memory};
use hdf5_sys::h5a::H5Aread;
use hdf5_sys::h5d::H5Dread;
use hdf5_sys::h5i::hid_t;
use hdf5_sys::h5p::H5P_DEFAULT;
use hdf5_sys::h5s::H5S_ALL;
use hdf5_sys::h5t::{
    H5T_bkg_t, H5T_cdata_t, H5T_class_t, H5T_cmd_t, H5T_pers_t, H5T_str_t, H5Tcreate, H5Tget_class,
    H5Tget_size, H5Tget_strpad, H5Tget_tag, H5Tis_variable_str, H5Tregister, H5Tset_tag,
};

/// The tag of the opaque type variable-length references are read as.
const RAW_TAG: &CStr = c"studyrun: stored variable-length string reference";
/// The name the conversion is registered under (at most 31 bytes).
const CONV_NAME: &CStr = c"studyrun_raw_vlen_string";
/// Largest global heap collection read (bytes): a string's length is a u32, and a
/// collection holds at least one string and at most what fits with the others.
const MAX_COLLECTION: u64 = (u32::MAX as u64) + (1 << 20);

/// What a string-typed attribute or dataset holds, per element.
pub(super) enum Strings {
    /// Not a string type.
    NotText,
    /// The strings, in element order (a NULL dataspace holds one empty string).
    Text(Vec<String>),
}

/// Reads every element of `attr` as text, if its type is a string type.
pub(super) fn read_attribute(attr: &Attribute) -> hdf5::Result<Strings> {
    let space = attr.space()?;
    if space.is_null() {
        return Ok(match StringType::of(&attr.dtype()?)? {
            Some(_) => Strings::Text(vec![String::new()]),
            None => Strings::NotText,
        });
    }
    let id = attr.id();
    read_strings(&attr.dtype()?, space.size(), &attr.file()?, |mem, buf| {
        // SAFETY: `id` is a valid attribute owned by `attr`; `buf` holds
        // `space.size()` elements of `mem`'s size (checked by `read_strings`).
        unsafe { H5Aread(id, mem, buf) }
    })
}

/// Reads every element of `ds` as text, if its type is a string type.
pub(super) fn read_dataset(ds: &Dataset) -> hdf5::Result<Strings> {
    let id = ds.id();
    read_strings(&ds.dtype()?, ds.space()?.size(), &ds.file()?, |mem, buf| {
        // SAFETY: `id` is a valid dataset owned by `ds`; `buf` holds every element of
        // the dataset at `mem`'s size (checked by `read_strings`).
        unsafe { H5Dread(id, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) }
    })
}

/// The attribute holding the CRC-32 of a string variable's strings ([`digest`]): what
/// checks them, as HDF5 applies no filter (Fletcher-32) to variable-length strings.
pub(super) const DIGEST_ATTR: &str = "studyrun_crc32";

/// CRC-32 (zlib's) of `strings`: of each one's length in bytes (u64, little-endian)
/// followed by its UTF-8 bytes.
pub(super) fn digest<S: AsRef<str>>(strings: &[S]) -> i64 {
    i64::from(
        strings
            .iter()
            .fold(0, |crc, s| digest_continue(crc, s.as_ref())),
    )
}

/// The CRC-32 `crc` of some strings ([`digest`]) continued over `text`.
pub(super) fn digest_continue(crc: u32, text: &str) -> u32 {
    let b = text.as_bytes();
    let crc = zlib_rs::crc32::crc32(crc, &(b.len() as u64).to_le_bytes());
    zlib_rs::crc32::crc32(crc, b)
}

/// The attribute holding the CRC-32 ([`digest`]) of a variable's text attributes
/// [`DESCRIBED_BY`] (an absent one counting as empty): what checks them, as HDF5
/// checksums no object header of the file's format.
pub(super) const ATTRIBUTES_DIGEST_ATTR: &str = "studyrun_attributes_crc32";

/// The attributes [`ATTRIBUTES_DIGEST_ATTR`] covers.
pub(super) const DESCRIBED_BY: [&str; 3] = ["units", "long_name", super::layout::ROLE_ATTR];

/// Writes the digest attribute `name` of the variable `ds` over `strings` (replacing
/// the one there).
pub(super) fn write_digest<S: AsRef<str>>(
    ds: &Dataset,
    name: &str,
    strings: &[S],
) -> hdf5::Result<()> {
    write_digest_value(ds, name, digest(strings) as u32)
}

/// Writes the digest attribute `name` of the variable `ds` with the CRC-32 `crc`
/// (replacing the one there).
pub(super) fn write_digest_value(ds: &Dataset, name: &str, crc: u32) -> hdf5::Result<()> {
    let attr = match ds.attr(name) {
        Ok(attr) => attr,
        Err(_) => ds.new_attr::<i64>().create(name)?,
    };
    attr.write_scalar(&i64::from(crc))
}

/// Checks `strings`, read from `ds`, against its digest attribute `name` if it has one
/// (a netCDF tool's rewrite may have left none); `what` names them in the error.
pub(super) fn check_digest<S: AsRef<str>>(
    ds: &Dataset,
    name: &str,
    strings: &[S],
    what: &str,
) -> hdf5::Result<()> {
    if !ds.attr_names()?.iter().any(|n| n == name) {
        return Ok(());
    }
    // netCDF tools rewrite a scalar attribute as a one-element array.
    let stored = ds.attr(name)?.read_raw::<i64>()?;
    if stored != [digest(strings)] {
        return Err(format!(
            "its {what} do not match their checksum ({name}): the file is damaged, or \
             they were changed since studyrun wrote them"
        )
        .into());
    }
    Ok(())
}

/// What [`ATTRIBUTES_DIGEST_ATTR`] covers: the text attributes [`DESCRIBED_BY`]
/// (`described`, an absent one as ""), then `name=value` of each of the variable's
/// [`DESCRIPTIVE_ATTRIBUTES`] it has (`descriptive`), in that list's order.
pub(super) fn digested<S: AsRef<str>>(
    described: &[S],
    descriptive: &[(String, AttrValue)],
) -> Vec<String> {
    let mut all: Vec<String> = described.iter().map(|s| s.as_ref().to_owned()).collect();
    for name in DESCRIPTIVE_ATTRIBUTES {
        if let Some((_, value)) = descriptive.iter().find(|(n, _)| n == name) {
            all.push(match value {
                AttrValue::Str(s) => format!("{name}={s}"),
                AttrValue::F64(x) => format!("{name}={x:?}"),
                AttrValue::I64(i) => format!("{name}={i}"),
            });
        }
    }
    all
}

/// The digest of a layout's variable names and roles
/// ([`VARIABLES_DIGEST_ATTR`](super::layout::VARIABLES_DIGEST_ATTR)).
pub(super) fn variables_digest(layout: &super::layout::Layout) -> i64 {
    let strings: Vec<&str> = layout
        .role_variables()
        .into_iter()
        .flat_map(|(name, role)| [name, role.as_str()])
        .collect();
    digest(&strings)
}

/// The text attributes [`DESCRIBED_BY`] of `ds`, an absent one as "", as studyrun
/// reads them: units of `time` that mean seconds from the epoch (a netCDF tool
/// respells them) as [`TIME_UNITS`](super::layout::TIME_UNITS); then its descriptive
/// attributes as [`digested`] lists them.
pub(super) fn described_by(ds: &Dataset) -> hdf5::Result<Vec<String>> {
    let names = ds.attr_names()?;
    let is_time = ds.name() == format!("/{}", super::layout::TIME);
    let described = DESCRIBED_BY
        .iter()
        .map(|&a| {
            if !names.iter().any(|n| n == a) {
                return Ok(String::new());
            }
            let value = super::attributes::read_str(ds, a)?;
            Ok(
                if is_time && a == "units" && super::layout::seconds_from_the_epoch(&value) {
                    super::layout::TIME_UNITS.to_owned()
                } else {
                    value
                },
            )
        })
        .collect::<hdf5::Result<Vec<String>>>()?;
    let descriptive = super::attributes::descriptive(ds, &names)?;
    Ok(digested(&described, &descriptive))
}

/// Checks the text attributes of `ds` against their digest, if it has one.
pub(super) fn check_attributes_digest(ds: &Dataset) -> hdf5::Result<()> {
    let values = described_by(ds)?;
    check_digest(
        ds,
        ATTRIBUTES_DIGEST_ATTR,
        &values,
        "attributes (units, long_name, role and descriptive ones)",
    )
}

/// Reads the strings of a dataset that must hold text.
pub(super) fn read_dataset_text(ds: &Dataset) -> hdf5::Result<Vec<String>> {
    match read_dataset(ds)? {
        Strings::Text(v) => Ok(v),
        Strings::NotText => Err(format!("{} is not a string variable", ds.name()).into()),
    }
}

/// How a string type is stored.
#[derive(Debug, Clone, Copy)]
enum StringType {
    /// Variable-length: references into global heap collections.
    Variable,
    /// Fixed-length strings of this many bytes, padded as said.
    Fixed(usize, H5T_str_t),
}

impl StringType {
    /// The string type `dtype` is, if it is one.
    fn of(dtype: &Datatype) -> hdf5::Result<Option<Self>> {
        let id = dtype.id();
        hdf5::sync::sync(|| {
            // SAFETY: `id` is a valid datatype owned by `dtype`.
            unsafe {
                if H5Tget_class(id) != H5T_class_t::H5T_STRING {
                    return Ok(None);
                }
                match H5Tis_variable_str(id) {
                    v if v > 0 => Ok(Some(Self::Variable)),
                    0 => Ok(Some(Self::Fixed(H5Tget_size(id), H5Tget_strpad(id)))),
                    _ => Err("cannot tell whether a string type is variable-length".into()),
                }
            }
        })
    }
}

/// Reads `n` elements of string type `dtype` with `read(memory type, buffer)` (an
/// `H5Aread` or `H5Dread`), from the object of `file`.
fn read_strings(
    dtype: &Datatype,
    n: usize,
    file: &hdf5::File,
    read: impl FnOnce(hid_t, *mut c_void) -> herr_t,
) -> hdf5::Result<Strings> {
    let Some(kind) = StringType::of(dtype)? else {
        return Ok(Strings::NotText);
    };
    match kind {
        StringType::Fixed(size, pad) => {
            let mut buf = vec![0u8; n.checked_mul(size).ok_or("string array too large")?];
            // The attribute's own type as memory type: no conversion, the stored bytes.
            let status = hdf5::sync::sync(|| read(dtype.id(), buf.as_mut_ptr().cast()));
            hdf5::h5check(status)?;
            let strings = if size == 0 {
                vec![String::new(); n]
            } else {
                buf.chunks(size).map(|s| fixed_text(s, pad)).collect()
            };
            Ok(Strings::Text(strings))
        }
        StringType::Variable => {
            let sizes = file.create_plist()?.sizes();
            let addr_size = usize::from(sizes.sizeof_addr);
            let size_size = usize::from(sizes.sizeof_size);
            let element = 8 + addr_size;
            let mut buf = vec![0u8; n.checked_mul(element).ok_or("string array too large")?];
            let raw = raw_reference_type(element)?;
            let status = hdf5::sync::sync(|| read(raw.id(), buf.as_mut_ptr().cast()));
            hdf5::h5check(status)?;
            let mut heap = GlobalHeap::open(file, addr_size, size_size)?;
            let strings = buf
                .chunks(element)
                .map(|r| heap.string(r).map_err(hdf5::Error::from))
                .collect::<hdf5::Result<_>>()?;
            Ok(Strings::Text(strings))
        }
    }
}

/// The text of one fixed-length string: up to its first NUL (NUL-terminated and
/// NUL-padded strings, and netCDF's NC_CHAR, which may fill every byte), or without
/// trailing spaces (space-padded strings).
fn fixed_text(bytes: &[u8], pad: H5T_str_t) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    let text = String::from_utf8_lossy(&bytes[..end]);
    if pad == H5T_str_t::H5T_STR_SPACEPAD {
        text.trim_end_matches(' ').to_owned()
    } else {
        text.into_owned()
    }
}

/// The opaque memory type of `size` bytes that variable-length string references are
/// read as, after registering [`raw_vlen_conv`] (once per process).
fn raw_reference_type(size: usize) -> hdf5::Result<Datatype> {
    // Initialised under the library lock: a fork (output::guard) never finds it half
    // done by another thread.
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    hdf5::sync::sync(|| {
        REGISTERED
            .get_or_init(|| register_raw_conversion().map_err(|e| e.to_string()))
            .clone()
    })
    .map_err(hdf5::Error::from)?;
    hdf5::sync::sync(|| {
        // SAFETY: H5Tcreate returns a new datatype id (or a negative error), which the
        // returned `Datatype` owns; the tag is a NUL-terminated string HDF5 copies.
        unsafe {
            let id = hdf5::h5check(H5Tcreate(H5T_class_t::H5T_OPAQUE, size))?;
            let t: Datatype = hdf5::from_id(id)?;
            hdf5::h5check(H5Tset_tag(t.id(), RAW_TAG.as_ptr()))?;
            Ok(t)
        }
    })
}

/// Registers [`raw_vlen_conv`] as a soft conversion from variable-length strings to
/// opaque types (HDF5 tries it only for those classes; it accepts only the tagged type).
fn register_raw_conversion() -> hdf5::Result<()> {
    let src = Datatype::from_type::<VarLenUnicode>()?;
    hdf5::sync::sync(|| {
        // SAFETY: `src` and the opaque type are valid datatypes for the call; HDF5 keeps
        // only their classes and the function pointer, which is 'static.
        unsafe {
            let dst: Datatype =
                hdf5::from_id(hdf5::h5check(H5Tcreate(H5T_class_t::H5T_OPAQUE, 1))?)?;
            hdf5::h5check(H5Tregister(
                H5T_pers_t::H5T_PERS_SOFT,
                CONV_NAME.as_ptr(),
                src.id(),
                dst.id(),
                Some(raw_vlen_conv),
            ))?;
            Ok(())
        }
    })
}

/// The conversion from a variable-length string type (as stored in the file) to the
/// opaque type tagged [`RAW_TAG`] of the same size: the stored reference bytes are the
/// result, so nothing is done and nothing is dereferenced. It declines (so HDF5 reports
/// no conversion path) any other pair of types.
extern "C" fn raw_vlen_conv(
    src: hid_t,
    dst: hid_t,
    cdata: *mut H5T_cdata_t,
    _nelmts: usize,
    _buf_stride: usize,
    _bkg_stride: usize,
    _buf: *mut c_void,
    _bkg: *mut c_void,
    _dxpl: hid_t,
) -> herr_t {
    // SAFETY: HDF5 passes a valid `cdata` for the call.
    let cdata = unsafe { &mut *cdata };
    match cdata.command {
        H5T_cmd_t::H5T_CONV_INIT => {
            // SAFETY: `src` and `dst` are valid datatype ids for the call.
            if unsafe { is_raw_pair(src, dst) } {
                cdata.need_bkg = H5T_bkg_t::H5T_BKG_NO;
                0
            } else {
                -1
            }
        }
        // Same size (checked at init): the buffer already holds the result.
        H5T_cmd_t::H5T_CONV_CONV | H5T_cmd_t::H5T_CONV_FREE => 0,
    }
}

/// Whether `src` is a variable-length string and `dst` the tagged opaque type of the
/// same size (the stored reference's size).
///
/// # Safety
/// `src` and `dst` must be valid datatype ids.
unsafe fn is_raw_pair(src: hid_t, dst: hid_t) -> bool {
    if H5Tis_variable_str(src) <= 0 || H5Tget_class(dst) != H5T_class_t::H5T_OPAQUE {
        return false;
    }
    let tag = H5Tget_tag(dst);
    if tag.is_null() {
        return false;
    }
    let ours = CStr::from_ptr(tag) == RAW_TAG;
    H5free_memory(tag.cast());
    ours && H5Tget_size(src) == H5Tget_size(dst) && H5Tget_size(src) > 0
}

/// Reads strings out of the global heap collections of one file, checking every
/// offset: a reference or collection that does not fit is an error, never a read
/// outside the collection.
pub(super) struct GlobalHeap {
    file: std::fs::File,
    len: u64,
    /// File offset of HDF5 address 0 (the user block's size).
    base: u64,
    addr_size: usize,
    size_size: usize,
    /// Collections read so far, by address.
    collections: HashMap<u64, Collection>,
}

impl GlobalHeap {
    /// The heap of `file` (HDF5's file name is opened again, read-only).
    fn open(file: &hdf5::File, addr_size: usize, size_size: usize) -> hdf5::Result<Self> {
        let name = file.filename();
        let handle = std::fs::File::open(&name).map_err(|e| format!("open {name}: {e}"))?;
        let len = handle.metadata().map_err(|e| format!("{name}: {e}"))?.len();
        Ok(Self {
            file: handle,
            len,
            base: file.userblock(),
            addr_size,
            size_size,
            collections: HashMap::new(),
        })
    }

    /// The string a stored reference (length u32, collection address, object index
    /// u32, little-endian) points to.
    fn string(&mut self, reference: &[u8]) -> Result<String, String> {
        let len = le(&reference[..4]) as usize;
        if len == 0 {
            return Ok(String::new());
        }
        let addr = le(&reference[4..4 + self.addr_size]);
        let index = le(&reference[4 + self.addr_size..]);
        let collection = self.collection(addr)?;
        let data = collection.object(index).ok_or_else(|| {
            format!(
                "variable-length string: no object {index} in the global heap collection at {addr}"
            )
        })?;
        let bytes = data.get(..len).ok_or_else(|| {
            format!(
                "variable-length string of {len} bytes in a global heap object of {}",
                data.len()
            )
        })?;
        let end = bytes.iter().position(|&b| b == 0).unwrap_or(len);
        Ok(String::from_utf8_lossy(&bytes[..end]).into_owned())
    }

    /// The collection at HDF5 address `addr`, read, checked and indexed once.
    fn collection(&mut self, addr: u64) -> Result<&Collection, String> {
        if !self.collections.contains_key(&addr) {
            let bytes = self.read_collection(addr)?;
            let collection = Collection::new(bytes, self.size_size);
            self.collections.insert(addr, collection);
        }
        Ok(&self.collections[&addr])
    }

    fn read_collection(&mut self, addr: u64) -> Result<Vec<u8>, String> {
        let bad = |why: String| format!("global heap collection at address {addr}: {why}");
        let start = self
            .base
            .checked_add(addr)
            .filter(|s| *s < self.len)
            .ok_or_else(|| bad(format!("outside the file ({} bytes)", self.len)))?;
        let header = 8 + self.size_size;
        let mut head = vec![0u8; header];
        self.read_at(start, &mut head).map_err(&bad)?;
        if &head[..4] != b"GCOL" || head[4] != 1 {
            return Err(bad("no collection signature".into()));
        }
        let size = le(&head[8..]);
        if size < header as u64 || size > MAX_COLLECTION || start + size > self.len {
            return Err(bad(format!(
                "size {size} does not fit the file ({} bytes)",
                self.len
            )));
        }
        let mut bytes = vec![0u8; size as usize];
        self.read_at(start, &mut bytes).map_err(bad)?;
        Ok(bytes)
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), String> {
        self.file
            .seek(SeekFrom::Start(offset))
            .and_then(|_| self.file.read_exact(buf))
            .map_err(|e| e.to_string())
    }
}

/// A global heap collection (its bytes, whole) and where each of its objects' data
/// is, found in one pass: looking a string up costs the same however many objects
/// the collection holds.
struct Collection {
    bytes: Vec<u8>,
    /// The byte range of each object's data, by object index (the first object of an
    /// index).
    objects: HashMap<u64, Range<usize>>,
}

impl Collection {
    /// Indexes the objects of `bytes`, whose length fields take `size_size` bytes. The
    /// pass ends at free space (object index 0) or at an object that does not fit:
    /// the objects after it are not there.
    fn new(bytes: Vec<u8>, size_size: usize) -> Self {
        let mut objects = HashMap::new();
        let align = |n: usize| n.checked_add(7).map(|n| n & !7);
        // Collection header: signature, version, 3 reserved, collection size; object
        // header: index u16, reference count u16, 4 reserved, object size.
        let (first, object_header) = (align(8 + size_size), align(8 + size_size));
        let mut p = first;
        while let (Some(at), Some(header)) = (p, object_header) {
            if at.checked_add(header).is_none_or(|end| end > bytes.len()) {
                break;
            }
            let id = le(&bytes[at..at + 2]);
            let size = usize::try_from(le(&bytes[at + 8..at + 8 + size_size])).ok();
            let data = at + header;
            let Some(end) = size.and_then(|size| data.checked_add(size)) else {
                break;
            };
            if id == 0 || end > bytes.len() {
                break;
            }
            objects.entry(id).or_insert(data..end);
            p = size.and_then(align).and_then(|size| data.checked_add(size));
        }
        Self { bytes, objects }
    }

    /// The data of object `index`; None if it is not there or does not fit.
    fn object(&self, index: u64) -> Option<&[u8]> {
        self.objects.get(&index).map(|r| &self.bytes[r.clone()])
    }
}

/// A little-endian unsigned integer of up to 8 bytes (longer fields: their low 8 bytes).
fn le(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .take(8)
        .rev()
        .fold(0, |acc, &b| (acc << 8) | u64::from(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A collection (8-byte lengths) holding `objects` as (index, data).
    fn collection(objects: &[(u16, &[u8])]) -> Vec<u8> {
        let mut c = b"GCOL\x01\0\0\0".to_vec();
        c.extend(4096u64.to_le_bytes());
        for (index, data) in objects {
            c.extend(index.to_le_bytes());
            c.extend(1u16.to_le_bytes());
            c.extend([0; 4]);
            c.extend((data.len() as u64).to_le_bytes());
            c.extend(*data);
            c.resize(c.len().next_multiple_of(8), 0);
        }
        c.resize(4096, 0);
        c
    }

    /// Object `index` of the collection `c` with 8-byte lengths.
    fn object(c: &[u8], index: u64) -> Option<Vec<u8>> {
        Collection::new(c.to_vec(), 8)
            .object(index)
            .map(<[u8]>::to_vec)
    }

    #[test]
    fn objects_are_found_by_index() {
        let c = collection(&[(1, b"ok"), (2, b"pending ok failed"), (7, b"")]);
        assert_eq!(object(&c, 1), Some(b"ok".to_vec()));
        assert_eq!(object(&c, 2), Some(b"pending ok failed".to_vec()));
        assert_eq!(object(&c, 7), Some(b"".to_vec()));
        assert_eq!(object(&c, 3), None);
    }

    #[test]
    fn damaged_collections_end_the_search() {
        // A zeroed object header (libhdf5 loops forever on it) is free space.
        let mut c = collection(&[(1, b"ok"), (2, b"x")]);
        c[16..32].fill(0);
        assert_eq!(object(&c, 2), None);
        // An object size running past the collection.
        let mut c = collection(&[(1, b"ok")]);
        c[24..32].copy_from_slice(&u64::MAX.to_le_bytes());
        assert_eq!(object(&c, 1), None);
        let mut c = collection(&[(1, b"ok")]);
        c[24..32].copy_from_slice(&5000u64.to_le_bytes());
        assert_eq!(object(&c, 1), None);
        // Too short for a header.
        assert_eq!(object(&c[..20], 1), None);
    }

    #[test]
    fn fixed_strings_end_at_nul_or_lose_space_padding() {
        use H5T_str_t::*;
        assert_eq!(fixed_text(b"abc", H5T_STR_NULLTERM), "abc");
        assert_eq!(fixed_text(b"ab\0\0", H5T_STR_NULLPAD), "ab");
        assert_eq!(fixed_text(b"ab  ", H5T_STR_SPACEPAD), "ab");
        assert_eq!(fixed_text("été".as_bytes(), H5T_STR_NULLTERM), "été");
        assert_eq!(
            fixed_text(b"\xe9t\xe9", H5T_STR_NULLTERM),
            "\u{FFFD}t\u{FFFD}"
        );
    }

    #[test]
    fn little_endian_fields() {
        assert_eq!(le(&[1, 0, 0, 0]), 1);
        assert_eq!(le(&[0, 1]), 256);
        assert_eq!(le(&[0xff; 8]), u64::MAX);
    }
}
