//! Readers and writers, and format detection.

pub mod asf;
pub mod csv;
pub mod images;
pub mod lst;
pub mod npy;

use crate::error::{IoError, Result};
use crate::recording::{Format, Recording};
use std::path::Path;

/// Text lines of a Latin-1 (or ASCII/UTF-8 treated bytewise) file with their 1-based numbers and
/// without the line end (`\n` or `\r\n`).
pub(crate) fn latin1_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, String)> + '_ {
    let mut s: &[u8] = bytes;
    if s.last() == Some(&b'\n') {
        s = &s[..s.len() - 1];
    }
    let empty = bytes.is_empty();
    s.split(|&b| b == b'\n')
        .enumerate()
        .filter(move |_| !empty)
        .map(|(i, l)| {
            let l = l.strip_suffix(b"\r").unwrap_or(l);
            (i + 1, l.iter().map(|&b| b as char).collect())
        })
}

/// Parses a finite number (accepting a decimal comma only when it is the sole separator).
pub(crate) fn parse_num(tok: &str) -> Option<f64> {
    let t = tok.trim();
    let v = t.parse::<f64>().ok().or_else(|| {
        if t.contains(',') && !t.contains('.') {
            t.replace(',', ".").parse::<f64>().ok()
        } else {
            None
        }
    })?;
    v.is_finite().then_some(v)
}

pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| IoError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Guesses the format of a file from its first bytes, then from its extension.
pub fn detect_format(path: &Path, head: &[u8]) -> Option<Format> {
    if head.starts_with(b"\x93NUMPY") {
        return Some(Format::Npy);
    }
    if head.starts_with(b"\x89PNG\r\n\x1a\n") {
        return Some(Format::Png);
    }
    if head.starts_with(b"II*\0") || head.starts_with(b"MM\0*") {
        return Some(Format::Tiff);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("asf") => return Some(Format::Asf),
        Some("lst") => return Some(Format::Lst),
        Some("npy") => return Some(Format::Npy),
        Some("png") => return Some(Format::Png),
        Some("tif") | Some("tiff") => return Some(Format::Tiff),
        Some("csv") => return Some(Format::Csv),
        _ => {}
    }
    let text: String = head.iter().take(4096).map(|&b| b as char).collect();
    if text.contains("ASCII_DATA") || text.starts_with("DATA_TYPE") || text.contains("\nFrame ") {
        return Some(Format::Asf);
    }
    if text.contains("Matrix:") && (text.contains("Page") || text.contains("Pict-No")) {
        return Some(Format::Lst);
    }
    let printable = head
        .iter()
        .take(4096)
        .all(|&b| b == b'\t' || b == b'\n' || b == b'\r' || (32..127).contains(&b));
    if printable && !head.is_empty() {
        return Some(Format::Csv);
    }
    None
}

/// Parses an in-memory file of a known format; `name` is used in error messages.
pub fn parse_bytes(bytes: &[u8], format: Format, name: &str) -> Result<Recording> {
    let mut rec = match format {
        Format::Asf => asf::parse_asf(bytes, name)?,
        Format::Lst => lst::parse_lst(bytes, name)?.0,
        Format::Csv => csv::parse_csv(bytes, name)?,
        Format::Npy => npy::parse_npy(bytes, name)?,
        Format::Png | Format::Tiff => images::decode_image(bytes, name)?,
    };
    if matches!(format, Format::Png | Format::Tiff) {
        rec.format = Some(format);
    }
    Ok(rec)
}

/// Reads a recording from a file, a folder of images, or a numbered image sequence.
///
/// - a folder: every `.png`/`.tif`/`.tiff` in it, in natural (numeric-aware) name order;
/// - a path with a printf-style counter (`walk_%03d.png`, `walk_%d.png`): the files counting up from
///   0 or 1 until the first missing number;
/// - a file: the format is detected from its magic bytes, its extension, then its text.
pub fn read_recording(path: impl AsRef<Path>) -> Result<Recording> {
    let path = path.as_ref();
    if path.is_dir() {
        return images::read_image_folder(path);
    }
    if let Some(s) = path.to_str() {
        if images::has_counter(s) && !path.exists() {
            return images::read_numbered(s);
        }
    }
    let bytes = read_bytes(path)?;
    let name = path.display().to_string();
    let format = detect_format(path, &bytes[..bytes.len().min(4096)])
        .ok_or_else(|| IoError::format(&name, "unknown file format"))?;
    parse_bytes(&bytes, format, &name)
}
