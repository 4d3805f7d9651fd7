//! NumPy `.npz`: a zip archive of `.npy` members (`np.savez`, stored; `np.savez_compressed`,
//! deflated; both write ZIP64 size fields). The first member holding a 2-D or 3-D numeric array
//! is read as the recording; the archive's central directory is authoritative.
//!
//! Sizes come from the archive and are checked against its length before anything is
//! allocated; a deflated member is inflated with a limit equal to its stated size, and its CRC-32
//! is verified, so a corrupt or hostile archive is an error, never a huge allocation.

use super::npy::parse_npy;
use crate::error::{IoError, Result};
use crate::recording::{Format, Recording};

/// A member as listed by the central directory.
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

/// Offset and entry count of the central directory (ZIP64 aware).
fn central_directory(b: &[u8]) -> Option<(u64, u64)> {
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
    let rec = usize::try_from(u64_at(b, loc + 8)?).ok()?;
    if !b.get(rec..)?.starts_with(b"PK\x06\x06") {
        return None;
    }
    Some((u64_at(b, rec + 48)?, u64_at(b, rec + 32)?))
}

fn members(b: &[u8], name: &str) -> Result<Vec<Member>> {
    let fail = |msg: &str| IoError::format(name, format!("corrupt zip archive: {msg}"));
    let (offset, count) =
        central_directory(b).ok_or_else(|| fail("no end of central directory record"))?;
    // Each central entry takes at least 46 bytes: a count beyond that is corrupt.
    if count > (b.len() / 46) as u64 {
        return Err(fail("more entries than the archive can hold"));
    }
    let mut at = usize::try_from(offset).map_err(|_| fail("bad directory offset"))?;
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

/// The bytes of one member, inflated and CRC-checked.
fn member_bytes(b: &[u8], m: &Member, name: &str) -> Result<Vec<u8>> {
    let fail = |msg: String| IoError::format(name, format!("zip member {}: {msg}", m.name));
    let at = usize::try_from(m.local_offset).map_err(|_| fail("bad offset".into()))?;
    let local = b
        .get(at..)
        .filter(|l| l.starts_with(b"PK\x03\x04"))
        .ok_or_else(|| fail("bad local header".into()))?;
    let n = u16_at(local, 26).ok_or_else(|| fail("truncated local header".into()))? as usize;
    let x = u16_at(local, 28).ok_or_else(|| fail("truncated local header".into()))? as usize;
    let start = 30 + n + x;
    let size = usize::try_from(m.compressed).map_err(|_| fail("too large".into()))?;
    let data = start
        .checked_add(size)
        .and_then(|end| local.get(start..end))
        .ok_or_else(|| {
            fail(format!(
                "truncated: {size} bytes stated, the archive ends first"
            ))
        })?;
    let out = match m.method {
        0 => data.to_vec(),
        8 => {
            // Inflating can expand ~1000:1; the stated size bounds it, and the stated size itself
            // is bounded by that ratio so a lying header cannot reserve gigabytes.
            let limit = usize::try_from(m.uncompressed)
                .ok()
                .filter(|&u| u <= data.len().saturating_mul(1032).max(1 << 16))
                .ok_or_else(|| fail("uncompressed size out of proportion".into()))?;
            miniz_oxide::inflate::decompress_to_vec_with_limit(data, limit)
                .map_err(|e| fail(format!("deflate stream is corrupt ({:?})", e.status)))?
        }
        other => return Err(fail(format!("compression method {other} is not supported"))),
    };
    if out.len() as u64 != m.uncompressed {
        return Err(fail(format!(
            "{} bytes, the directory states {}",
            out.len(),
            m.uncompressed
        )));
    }
    let mut h = crc32fast::Hasher::new();
    h.update(&out);
    if h.finalize() != m.crc {
        return Err(fail("CRC mismatch".into()));
    }
    Ok(out)
}

/// Parses a `.npz` archive held in memory: the first `.npy` member that is a 2-D or 3-D
/// numeric array becomes the recording.
pub fn parse_npz(bytes: &[u8], name: &str) -> Result<Recording> {
    let list = members(bytes, name)?;
    let mut tried = Vec::new();
    for m in list.iter().filter(|m| m.name.ends_with(".npy")) {
        let raw = member_bytes(bytes, m, name)?;
        match parse_npy(&raw, &format!("{name}:{}", m.name)) {
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
