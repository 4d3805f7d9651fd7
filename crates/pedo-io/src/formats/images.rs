//! PNG and TIFF grayscale images (8 or 16 bit): a single image, a folder, or a numbered sequence.
//! Raw sample values become pressures as they are (no rescaling from 8 to 16 bit); images carry no
//! sensor mask, pitch or timing.

use super::read_bytes;
use crate::error::{IoError, Result};
use crate::recording::{Format, Recording, SparseFrames};
use image::{DynamicImage, ImageBuffer, ImageDecoder as _, ImageFormat, Luma};
use std::path::{Path, PathBuf};

fn decode(bytes: &[u8], name: &str) -> Result<(usize, usize, Vec<f32>, Format)> {
    let fmt = image::guess_format(bytes)
        .map_err(|e| IoError::format(name, format!("unrecognised image: {e}")))?;
    let format = match fmt {
        ImageFormat::Png => Format::Png,
        ImageFormat::Tiff => Format::Tiff,
        other => {
            return Err(IoError::format(
                name,
                format!("unsupported image format {other:?}"),
            ));
        }
    };
    // A header may claim any size: the decoder may allocate at most what a compressed image of
    // this length can plausibly expand to (deflate reaches ~1000:1), never the claim itself.
    let mut limits = image::Limits::default();
    limits.max_alloc =
        Some((16u64 << 20).saturating_add(1032u64.saturating_mul(bytes.len() as u64)));
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), fmt);
    reader.limits(limits);
    let cannot = |e: image::ImageError| IoError::format(name, format!("cannot decode image: {e}"));
    // The header's size and colour are checked before anything is decoded.
    let decoder = reader.into_decoder().map_err(cannot)?;
    let (w, h) = decoder.dimensions();
    let (w, h) = (w as usize, h as usize);
    crate::limits::check_frame(name, "an image", h, w)?;
    let color = decoder.color_type();
    if !matches!(color, image::ColorType::L8 | image::ColorType::L16) {
        return Err(IoError::format(
            name,
            format!("expected an 8- or 16-bit grayscale image, got {color:?}"),
        ));
    }
    let data: Vec<f32> = match DynamicImage::from_decoder(decoder).map_err(cannot)? {
        DynamicImage::ImageLuma8(b) => b.into_raw().into_iter().map(f32::from).collect(),
        DynamicImage::ImageLuma16(b) => b.into_raw().into_iter().map(f32::from).collect(),
        other => {
            return Err(IoError::format(
                name,
                format!(
                    "expected an 8- or 16-bit grayscale image, got {:?}",
                    other.color()
                ),
            ));
        }
    };
    if w == 0 || h == 0 {
        return Err(IoError::format(name, "empty image"));
    }
    Ok((h, w, data, format))
}

/// Whether the PNG or TIFF image at `path` is one this module reads (8- or 16-bit grayscale), by
/// its header alone; `None` when the header cannot be read. A study search passes over colour
/// images (a photograph of the foot beside a recording is no pressure frame).
pub fn is_grayscale_image(path: &Path) -> Option<bool> {
    let decoder = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?
        .into_decoder()
        .ok()?;
    Some(matches!(
        decoder.color_type(),
        image::ColorType::L8 | image::ColorType::L16
    ))
}

/// Decodes one PNG or TIFF image held in memory into a one-frame recording.
pub fn decode_image(bytes: &[u8], name: &str) -> Result<Recording> {
    let (h, w, data, format) = decode(bytes, name)?;
    let mut rec = Recording::new(1, h, w, data, vec![true; h * w])?;
    rec.format = Some(format);
    Ok(rec)
}

/// Reads images (one frame each, all of the same size) into one recording, in the given order.
pub fn read_image_sequence<P: AsRef<Path>>(paths: &[P]) -> Result<Recording> {
    if paths.is_empty() {
        return Err(IoError::invalid("no images given"));
    }
    // Frames are held sparsely as they are decoded: a folder of large, mostly empty images
    // takes the memory of their loaded pixels.
    let mut frames: Option<SparseFrames> = None;
    let mut dims = None;
    let mut fmt = None;
    for (k, p) in paths.iter().enumerate() {
        let p = p.as_ref();
        let name = p.display().to_string();
        let (h, w, data, f) = decode(&read_bytes(p)?, &name)?;
        match dims {
            None => dims = Some((h, w)),
            Some(d) if d != (h, w) => {
                return Err(IoError::format(
                    &name,
                    format!("image is {w}x{h}, the first one is {}x{}", d.1, d.0),
                ));
            }
            _ => {}
        }
        crate::limits::check_frames(&name, k + 1, h * w)?;
        fmt.get_or_insert(f);
        frames
            .get_or_insert_with(|| SparseFrames::new(h * w))
            .push(&data);
    }
    let ((h, w), Some(frames)) = (dims.expect("at least one image"), frames) else {
        return Err(IoError::invalid("no images given"));
    };
    let mut rec = Recording::from_sparse(h, w, frames, vec![true; h * w])?;
    rec.format = fmt;
    Ok(rec)
}

/// Splits a file name into text and number chunks so that `f2` sorts before `f10`.
fn natural_key(s: &str) -> Vec<(String, u128)> {
    let mut out = Vec::new();
    let mut text = String::new();
    let mut num: Option<u128> = None;
    for ch in s.chars() {
        if let Some(d) = ch.to_digit(10) {
            num = Some(
                num.unwrap_or(0)
                    .saturating_mul(10)
                    .saturating_add(d as u128),
            );
        } else {
            if let Some(n) = num.take() {
                out.push((std::mem::take(&mut text), n));
            }
            text.push(ch);
        }
    }
    out.push((text, num.unwrap_or(0)));
    out
}

/// Reads every `.png`, `.tif` and `.tiff` file of a folder, in natural name order.
pub fn read_image_folder(dir: &Path) -> Result<Recording> {
    let name = dir.display().to_string();
    let rd = std::fs::read_dir(dir).map_err(|source| IoError::Io {
        path: name.clone(),
        source,
    })?;
    let mut files: Vec<PathBuf> = Vec::new();
    for e in rd {
        let e = e.map_err(|source| IoError::Io {
            path: name.clone(),
            source,
        })?;
        let p = e.path();
        let ext = p
            .extension()
            .and_then(|x| x.to_str())
            .map(|x| x.to_ascii_lowercase());
        if p.is_file() && matches!(ext.as_deref(), Some("png" | "tif" | "tiff")) {
            files.push(p);
        }
    }
    if files.is_empty() {
        return Err(IoError::format(&name, "folder holds no PNG or TIFF images"));
    }
    files.sort_by_cached_key(|p| {
        natural_key(
            &p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        )
    });
    read_image_sequence(&files)
}

/// Position and width of a `%d` / `%0Nd` counter in a path pattern.
fn counter(pattern: &str) -> Option<(usize, usize, usize)> {
    let i = pattern.find('%')?;
    let rest = &pattern[i + 1..];
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    if !rest[digits.len()..].starts_with('d') {
        return None;
    }
    let width = digits.parse::<usize>().unwrap_or(0);
    Some((i, i + 1 + digits.len() + 1, width))
}

pub(crate) fn has_counter(s: &str) -> bool {
    counter(s).is_some()
}

/// Reads a numbered sequence `walk_%03d.png`: counting up from 0 (or from 1 when 0 is missing)
/// until the first missing number.
pub fn read_numbered(pattern: &str) -> Result<Recording> {
    let (a, b, w) = counter(pattern)
        .ok_or_else(|| IoError::invalid(format!("no %d counter in {pattern:?}")))?;
    let make = |k: usize| {
        PathBuf::from(format!(
            "{}{:0w$}{}",
            &pattern[..a],
            k,
            &pattern[b..],
            w = w
        ))
    };
    let mut k = if make(0).is_file() { 0 } else { 1 };
    let mut files = Vec::new();
    while make(k).is_file() {
        files.push(make(k));
        k += 1;
    }
    if files.is_empty() {
        return Err(IoError::format(
            pattern,
            "no file of the numbered sequence exists (tried 0 and 1)",
        ));
    }
    read_image_sequence(&files)
}

/// Encodes frame `t` as a 16-bit grayscale PNG of `round(value * scale)`. Every value (times the
/// scale) must be within 0..=65535 and integral to within 1e-3, so that reading back and dividing
/// by `scale` restores the frame; missing sensors are written as 0 (PNG has no mask).
pub fn frame_to_png16(rec: &Recording, t: usize, scale: f64) -> Result<Vec<u8>> {
    let f = rec.frame_slice(t).ok_or_else(|| {
        IoError::invalid(format!(
            "frame {t} out of range ({} frames)",
            rec.n_frames()
        ))
    })?;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(IoError::invalid(format!(
            "scale must be positive, got {scale}"
        )));
    }
    let mut px = Vec::with_capacity(f.len());
    for (i, &v) in f.iter().enumerate() {
        let x = v as f64 * scale;
        let r = x.round();
        if !(0.0..=65535.0).contains(&r) || (x - r).abs() > 1e-3 {
            return Err(IoError::invalid(format!(
                "value {v} at row {}, column {} does not fit a 16-bit integer at scale {scale}",
                i / rec.cols(),
                i % rec.cols()
            )));
        }
        px.push(r as u16);
    }
    let buf: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_raw(rec.cols() as u32, rec.rows() as u32, px)
            .ok_or_else(|| IoError::invalid("image size does not fit".to_string()))?;
    let mut out = std::io::Cursor::new(Vec::new());
    buf.write_to(&mut out, ImageFormat::Png)
        .map_err(|e| IoError::invalid(format!("PNG encoding failed: {e}")))?;
    Ok(out.into_inner())
}

/// Writes frame `t` as a 16-bit PNG (see [`frame_to_png16`]).
pub fn write_png16(rec: &Recording, t: usize, scale: f64, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let bytes = frame_to_png16(rec, t, scale)?;
    std::fs::write(path, bytes).map_err(|source| IoError::Io {
        path: path.display().to_string(),
        source,
    })
}
