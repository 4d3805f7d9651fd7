//! NumPy `.npz`: a zip archive of `.npy` members (`np.savez`, stored; `np.savez_compressed`,
//! deflated; both write ZIP64 size fields). The first member holding a 2-D or 3-D numeric array
//! is read as the recording; the archive's central directory is authoritative.
//!
//! Sizes come from the archive and are checked against its length before anything is
//! allocated; a member is parsed as it is inflated (its array's frames held sparsely, never its
//! data whole), within its stated size, and its CRC-32 is verified, so a corrupt or hostile
//! archive is an error, never a huge allocation.

use super::npy::NpyFile;
use crate::error::{IoError, Result};
use crate::recording::{Format, Recording};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// A member as listed by the central directory.
#[derive(Clone)]
struct Member {
    name: String,
    method: u16,
    crc: u32,
    compressed: u64,
    uncompressed: u64,
    local_offset: u64,
}

fn u16_at(b: &[u8], i: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(i..i + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], i: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(i..i + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], i: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(i..i + 8)?.try_into().ok()?))
}

/// Offset and entry count of the central directory (ZIP64 aware), in an archive whose bytes from
/// `base` to its end are `b`.
fn central_directory(b: &[u8], base: u64) -> Option<(u64, u64)> {
    let lo = b.len().saturating_sub(22 + 65_535);
    let eocd = (lo..=b.len().checked_sub(22)?)
        .rev()
        .find(|&i| b[i..].starts_with(b"PK\x05\x06"))?;
    let count = u16_at(b, eocd + 10)? as u64;
    let offset = u32_at(b, eocd + 16)? as u64;
    if count != 0xFFFF && offset != 0xFFFF_FFFF {
        return Some((offset, count));
    }
    // ZIP64: the locator sits just before the end record and points at the ZIP64 end record.
    let loc = eocd.checked_sub(20)?;
    if !b[loc..].starts_with(b"PK\x06\x07") {
        return None;
    }
    let rec = usize::try_from(u64_at(b, loc + 8)?.checked_sub(base)?).ok()?;
    if !b.get(rec..)?.starts_with(b"PK\x06\x06") {
        return None;
    }
    Some((u64_at(b, rec + 48)?, u64_at(b, rec + 32)?))
}

/// The members the central directory lists, in an archive whose bytes from `base` to its end
/// are `b`.
fn members(b: &[u8], base: u64, name: &str) -> Result<Vec<Member>> {
    let fail = |msg: &str| IoError::format(name, format!("corrupt zip archive: {msg}"));
    let (offset, count) =
        central_directory(b, base).ok_or_else(|| fail("no end of central directory record"))?;
    // Each central entry takes at least 46 bytes: a count beyond that is corrupt.
    if count > (b.len() / 46) as u64 {
        return Err(fail("more entries than the archive can hold"));
    }
    let at = offset.checked_sub(base).map(usize::try_from);
    let mut at = at
        .and_then(|at| at.ok())
        .ok_or_else(|| fail("bad directory offset"))?;
    let mut out = Vec::with_capacity(count as usize);
    for _ in 0..count {
        let e = b.get(at..).filter(|e| e.starts_with(b"PK\x01\x02"));
        let e = e.ok_or_else(|| fail("bad central directory entry"))?;
        let field = |i| u16_at(e, i).ok_or_else(|| fail("truncated directory entry"));
        let word = |i| u32_at(e, i).ok_or_else(|| fail("truncated directory entry"));
        let (n, x, c) = (
            field(28)? as usize,
            field(30)? as usize,
            field(32)? as usize,
        );
        let raw_name = e.get(46..46 + n).ok_or_else(|| fail("truncated name"))?;
        let extra = e
            .get(46 + n..46 + n + x)
            .ok_or_else(|| fail("truncated extra field"))?;
        let mut m = Member {
            name: String::from_utf8_lossy(raw_name).into_owned(),
            method: field(10)?,
            crc: word(16)?,
            compressed: word(20)? as u64,
            uncompressed: word(24)? as u64,
            local_offset: word(42)? as u64,
        };
        apply_zip64(&mut m, extra);
        out.push(m);
        at += 46 + n + x + c;
    }
    Ok(out)
}

/// Replaces the 0xFFFFFFFF sizes and offset by the ZIP64 extra field's values, in its order.
fn apply_zip64(m: &mut Member, mut extra: &[u8]) {
    while extra.len() >= 4 {
        let id = u16::from_le_bytes([extra[0], extra[1]]);
        let len = u16::from_le_bytes([extra[2], extra[3]]) as usize;
        let Some(body) = extra.get(4..4 + len) else {
            return;
        };
        if id == 1 {
            let mut vals = body
                .chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().expect("chunks of 8 bytes")));
            for f in [&mut m.uncompressed, &mut m.compressed, &mut m.local_offset] {
                if *f == 0xFFFF_FFFF {
                    match vals.next() {
                        Some(v) => *f = v,
                        None => return,
                    }
                }
            }
        }
        extra = &extra[4 + len..];
    }
}

/// Where a member's data lie in the archive, its size checked against the archive's length
/// and, deflated, its stated size against what deflate can expand to.
fn member_data<'b>(b: &'b [u8], m: &Member, name: &str) -> Result<&'b [u8]> {
    let fail = |msg: &str| IoError::format(name, format!("zip member {}: {msg}", m.name));
    let at = usize::try_from(m.local_offset).map_err(|_| fail("bad offset"))?;
    let local = b.get(at..).ok_or_else(|| fail("bad local header"))?;
    let start = data_offset(local, local.len() as u64, m, name)? as usize;
    Ok(&local[start..][..m.compressed as usize])
}

/// Where a member's data begin after its local header, whose first bytes are `local` (30 or
/// more), `available` bytes of the archive from the header on; checked as [`member_data`] says.
fn data_offset(local: &[u8], available: u64, m: &Member, name: &str) -> Result<u64> {
    let fail = |msg: String| IoError::format(name, format!("zip member {}: {msg}", m.name));
    if !local.starts_with(b"PK\x03\x04") {
        return Err(fail("bad local header".into()));
    }
    let n = u16_at(local, 26).ok_or_else(|| fail("truncated local header".into()))? as u64;
    let x = u16_at(local, 28).ok_or_else(|| fail("truncated local header".into()))? as u64;
    let start = 30 + n + x;
    let size = m.compressed;
    if usize::try_from(size).is_err() {
        return Err(fail("too large".into()));
    }
    if start.checked_add(size).is_none_or(|end| end > available) {
        return Err(fail(format!(
            "truncated: {size} bytes stated, the archive ends first"
        )));
    }
    match m.method {
        0 | 8 => {}
        other => return Err(fail(format!("compression method {other} is not supported"))),
    }
    // Inflating can expand ~1000:1: a stated size beyond that is a lying header.
    if m.method == 8 && m.uncompressed > size.saturating_mul(1032).max(1 << 16) {
        return Err(fail("uncompressed size out of proportion".into()));
    }
    Ok(start)
}

/// A member's bytes as they are read, inflated when deflated (never whole), with their count
/// and CRC-32 checked against the directory once all are read.
struct MemberReader<'b> {
    inner: Box<dyn Read + Send + 'b>,
    crc: crc32fast::Hasher,
    read: u64,
    stated: u64,
    stated_crc: u32,
    /// What went wrong reading the member, if anything.
    failure: Option<String>,
}

impl<'b> MemberReader<'b> {
    fn new(data: &'b [u8], m: &Member) -> Self {
        Self::over(data, m)
    }

    /// The member whose bytes as stored (deflated or not) `data` reads.
    fn over(data: impl Read + Send + 'b, m: &Member) -> Self {
        let inner: Box<dyn Read + Send + 'b> = match m.method {
            8 => Box::new(flate2::read::DeflateDecoder::new(data)),
            _ => Box::new(data),
        };
        MemberReader {
            // One byte more than stated, so that a longer member shows.
            inner: Box::new(inner.take(m.uncompressed.saturating_add(1))),
            crc: crc32fast::Hasher::new(),
            read: 0,
            stated: m.uncompressed,
            stated_crc: m.crc,
            failure: None,
        }
    }

    fn fail(&mut self, msg: String) -> std::io::Error {
        self.failure = Some(msg.clone());
        std::io::Error::new(std::io::ErrorKind::InvalidData, msg)
    }

    /// Reads what is left and checks the member whole: `Err` says what is wrong with it.
    fn finish(&mut self) -> std::result::Result<(), String> {
        let _ = std::io::copy(self, &mut std::io::sink());
        match self.failure.take() {
            Some(msg) => Err(msg),
            None => Ok(()),
        }
    }
}

impl Read for MemberReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.failure.is_some() {
            return Err(std::io::Error::other("the member is corrupt"));
        }
        let n = match self.inner.read(buf) {
            Ok(n) => n,
            Err(e) => return Err(self.fail(format!("deflate stream is corrupt ({e})"))),
        };
        self.read += n as u64;
        self.crc.update(&buf[..n]);
        if self.read > self.stated || (n == 0 && self.read < self.stated) {
            let (read, stated) = (self.read, self.stated);
            return Err(self.fail(format!("{read} bytes, the directory states {stated}")));
        }
        if n == 0 && self.crc.clone().finalize() != self.stated_crc {
            return Err(self.fail("CRC mismatch".into()));
        }
        Ok(n)
    }
}

/// Parses a `.npz` archive held in memory: the first `.npy` member that is a 2-D or 3-D
/// numeric array becomes the recording. Each member is parsed as it is inflated.
pub fn parse_npz(bytes: &[u8], name: &str) -> Result<Recording> {
    let list = members(bytes, 0, name)?;
    let mut tried = Vec::new();
    for m in list.iter().filter(|m| m.name.ends_with(".npy")) {
        let data = member_data(bytes, m, name)?;
        let mut reader = MemberReader::new(data, m);
        let parsed =
            super::npy::read_npy(&mut reader, m.uncompressed, &format!("{name}:{}", m.name));
        // A corrupt member is the archive's error, whatever its array looked like so far.
        if let Err(msg) = reader.finish() {
            return Err(IoError::format(
                name,
                format!("zip member {}: {msg}", m.name),
            ));
        }
        match parsed {
            Ok(mut rec) => {
                rec.format = Some(Format::Npz);
                return Ok(rec);
            }
            Err(e) => tried.push(e.to_string()),
        }
    }
    if list.iter().all(|m| !m.name.ends_with(".npy")) {
        return Err(IoError::format(
            name,
            "a zip archive without .npy members: not a NumPy .npz",
        ));
    }
    Err(IoError::format(
        name,
        format!(
            "no member is a 2-D or 3-D numeric array ({})",
            tried.join("; ")
        ),
    ))
}

/// The array of the `.npz` file at `path` a streamed run reads window by window
/// ([`super::FileFrames`]): the member the whole read takes (the first `.npy` member whose header
/// is a 2-D or 3-D array's), a stored one at its offset in the file, a deflated one inflated in
/// order; the archive located from its end, never read whole. With `check`, every member up to
/// it is read through and checked (length, CRC-32) as the whole read checks it, but a deflated
/// one, checked as the run reads it. `Err` for an archive whose array cannot be read so (a
/// deflated Fortran-order array), or that the whole read would refuse or read otherwise: the
/// caller reads it whole, with the whole read's outcome.
pub(crate) fn stream_array(path: &Path, name: &str, check: bool) -> Result<NpyFile> {
    let io = |source| IoError::Io {
        path: name.to_string(),
        source,
    };
    let file = File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let (tail, base) = directory(&file, size, name)?;
    for m in members(&tail, base, name)?
        .iter()
        .filter(|m| m.name.ends_with(".npy"))
    {
        let local = read_range(&file, m.local_offset, 30.min(size), name)?;
        let available = size.saturating_sub(m.local_offset);
        let start = m.local_offset + data_offset(&local, available, m, name)?;
        let member = format!("{name}:{}", m.name);
        let opened = match m.method {
            0 => {
                let copy = file.try_clone().map_err(io)?;
                NpyFile::at(copy, start, m.uncompressed, &member, Format::Npz)
            }
            _ => NpyFile::inflated(reopen(path, m, start, name), m.uncompressed, &member),
        };
        if check && (opened.is_err() || m.method == 0) {
            check_member(&file, start, m, name)?;
        }
        match opened {
            Err(e) if e.to_string().contains(super::npy::FORTRAN_DEFLATED) => return Err(e),
            Err(_) => continue,
            Ok(npy) => return Ok(npy),
        }
    }
    Err(IoError::format(name, "no .npy member holds a recording"))
}

/// Why a streamed run reads the `.npz` file at `path` whole ([`super::why_read_whole`]), `None`
/// when it reads its array window by window.
pub(crate) fn why_read_whole(path: &Path, name: &str) -> Option<String> {
    match stream_array(path, name, false) {
        Ok(_) => None,
        Err(e) if e.to_string().contains(super::npy::FORTRAN_DEFLATED) => {
            Some(super::npy::FORTRAN_DEFLATED.into())
        }
        Err(_) => Some("an archive whose first arrays are no recording's is read whole".into()),
    }
}

/// Most bytes of an archive's central directory read for a streamed run (NumPy writes a few
/// hundred): a larger one is read whole.
const MAX_DIRECTORY: u64 = 16 << 20;

/// The archive's bytes from its central directory (or ZIP64 end record, wherever the first is)
/// to its end, and where they begin.
fn directory(file: &File, size: u64, name: &str) -> Result<(Vec<u8>, u64)> {
    let corrupt = || {
        IoError::format(
            name,
            "corrupt zip archive: no end of central directory record",
        )
    };
    let mut base = size.saturating_sub(22 + 65_535 + 20);
    // Each round reads from further back: the end record, the ZIP64 record, the directory.
    for _ in 0..4 {
        let tail = read_range(file, base, size - base, name)?;
        let need = directory_from(&tail, base).ok_or_else(corrupt)?;
        if need >= base {
            return Ok((tail, base));
        }
        if size - need > MAX_DIRECTORY {
            return Err(IoError::format(name, "a zip directory too large to stream"));
        }
        base = need;
    }
    Err(corrupt())
}

/// Where the central directory (or the ZIP64 end record, wherever the first is) begins, in an
/// archive whose bytes from `base` to its end are `b`: as far as `b` shows it.
fn directory_from(b: &[u8], base: u64) -> Option<u64> {
    if let Some((offset, _)) = central_directory(b, base) {
        return Some(offset);
    }
    // ZIP64: the locator before the end record points at the ZIP64 record, perhaps before `b`.
    let lo = b.len().saturating_sub(22 + 65_535);
    let eocd = (lo..=b.len().checked_sub(22)?)
        .rev()
        .find(|&i| b[i..].starts_with(b"PK\x05\x06"))?;
    let loc = eocd.checked_sub(20)?;
    b[loc..]
        .starts_with(b"PK\x06\x07")
        .then(|| u64_at(b, loc + 8))?
        .filter(|&rec| rec < base)
}

/// `len` bytes of `file` from `at` (fewer where it ends).
fn read_range(file: &File, at: u64, len: u64, name: &str) -> Result<Vec<u8>> {
    let fail = |e: std::io::Error| IoError::format(name, format!("cannot read the archive: {e}"));
    let mut f = file;
    f.seek(SeekFrom::Start(at)).map_err(fail)?;
    let mut out = Vec::new();
    f.take(len).read_to_end(&mut out).map_err(fail)?;
    Ok(out)
}

/// Reads member `m`, whose data begin at `start`, through: its length and CRC-32 checked.
fn check_member(file: &File, start: u64, m: &Member, name: &str) -> Result<()> {
    let mut f = file;
    f.seek(SeekFrom::Start(start))
        .map_err(|e| IoError::format(name, format!("cannot read the archive: {e}")))?;
    let buffered = std::io::BufReader::new(f.take(m.compressed));
    MemberReader::over(buffered, m)
        .finish()
        .map_err(|msg| IoError::format(name, format!("zip member {}: {msg}", m.name)))
}

/// Reopens member `m` of the archive at `path`, whose data begin at `start`: its bytes inflated
/// from the start, checked as [`MemberReader`] checks them.
fn reopen(path: &Path, m: &Member, start: u64, name: &str) -> super::npy::Reopen {
    let (path, m, name) = (path.to_path_buf(), m.clone(), name.to_string());
    Box::new(move || {
        let io = |source| IoError::Io {
            path: name.clone(),
            source,
        };
        let mut file = File::open(&path).map_err(io)?;
        file.seek(SeekFrom::Start(start)).map_err(io)?;
        let reader = MemberReader::over(file.take(m.compressed), &m);
        Ok(Box::new(reader) as Box<dyn Read + Send>)
    })
}
