//! NumPy `.npy` (format versions 1–3): 2-D (one frame) or 3-D (T × rows × cols) arrays of
//! `f4 f8 i1 i2 i4 i8 u1 u2 u4` in either byte order and C or Fortran layout. NaN marks a missing
//! sensor (it must then be NaN in every frame).

use crate::error::{IoError, Result};
use crate::recording::{Format, Recording, SparseFrames};
use std::io::Read;
use std::path::Path;

#[derive(Clone, Copy)]
enum Kind {
    F,
    I,
    U,
}

fn header_value<'a>(h: &'a str, key: &str) -> Option<&'a str> {
    let i = h
        .find(&format!("'{key}'"))
        .or_else(|| h.find(&format!("\"{key}\"")))?;
    let rest = &h[i + key.len() + 2..];
    let rest = rest.trim_start().strip_prefix(':')?;
    Some(rest.trim_start())
}

/// What the header says of the array.
struct NpyHeader {
    /// The dtype as written (`<f4`), for messages.
    descr: String,
    kind: Kind,
    /// Bytes per value.
    size: usize,
    big_endian: bool,
    fortran: bool,
    shape: Vec<usize>,
}

/// Reads the magic, version and header dictionary; returns the header and where the data
/// begin.
fn read_header(bytes: &[u8], fail: &impl Fn(String) -> IoError) -> Result<(NpyHeader, usize)> {
    if bytes.len() < 10 || !bytes.starts_with(b"\x93NUMPY") {
        return Err(fail("not a .npy file (bad magic)".into()));
    }
    let (hlen, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10usize),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12usize,
        ),
        2 | 3 => return Err(fail("truncated header".into())),
        v => return Err(fail(format!("unsupported .npy version {v}"))),
    };
    let end = start
        .checked_add(hlen)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| fail("truncated header".into()))?;
    let header =
        std::str::from_utf8(&bytes[start..end]).map_err(|_| fail("header is not text".into()))?;
    let (descr, kind, size, big_endian) = dtype(header, fail)?;
    let fortran = match header_value(header, "fortran_order") {
        Some(v) if v.starts_with("True") => true,
        Some(v) if v.starts_with("False") => false,
        _ => return Err(fail("header has no valid 'fortran_order'".into())),
    };
    let shape = shape(header, fail)?;
    let header = NpyHeader {
        descr,
        kind,
        size,
        big_endian,
        fortran,
        shape,
    };
    Ok((header, end))
}

/// The header's `descr`: the dtype as written, its kind, bytes per value and byte order.
fn dtype(header: &str, fail: &impl Fn(String) -> IoError) -> Result<(String, Kind, usize, bool)> {
    let descr =
        header_value(header, "descr").ok_or_else(|| fail("header has no 'descr'".into()))?;
    let q = descr
        .chars()
        .next()
        .filter(|&c| c == '\'' || c == '"')
        .ok_or_else(|| fail("bad 'descr'".into()))?;
    let descr = descr[1..].split(q).next().unwrap_or("");
    let unsupported = || fail(format!("unsupported dtype {descr:?}"));
    let (order, code) = descr.split_at(descr.len().min(1));
    let big = match order {
        "<" | "|" | "=" => false,
        ">" => true,
        _ => return Err(unsupported()),
    };
    let (kind, size) = match code {
        "f4" => (Kind::F, 4),
        "f8" => (Kind::F, 8),
        "i1" => (Kind::I, 1),
        "i2" => (Kind::I, 2),
        "i4" => (Kind::I, 4),
        "i8" => (Kind::I, 8),
        "u1" | "b1" => (Kind::U, 1),
        "u2" => (Kind::U, 2),
        "u4" => (Kind::U, 4),
        _ => return Err(unsupported()),
    };
    Ok((descr.to_string(), kind, size, big))
}

/// The header's `shape` tuple.
fn shape(header: &str, fail: &impl Fn(String) -> IoError) -> Result<Vec<usize>> {
    let bad = || fail("bad 'shape'".into());
    let s = header_value(header, "shape").ok_or_else(|| fail("header has no 'shape'".into()))?;
    let s = s.strip_prefix('(').ok_or_else(bad)?;
    let s = s.split(')').next().ok_or_else(bad)?;
    s.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|tok| {
            tok.trim_end_matches('L')
                .parse::<usize>()
                .map_err(|_| fail(format!("bad 'shape' entry {tok:?}")))
        })
        .collect()
}

/// One value of `h`'s dtype from its `h.size` bytes.
fn decode(chunk: &[u8], h: &NpyHeader) -> f64 {
    let size = h.size;
    let mut b = [0u8; 8];
    b[..size].copy_from_slice(chunk);
    if h.big_endian {
        b[..size].reverse();
    }
    match (h.kind, size) {
        (Kind::F, 4) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        (Kind::F, _) => f64::from_le_bytes(b),
        (Kind::I, 1) => b[0] as i8 as f64,
        (Kind::I, 2) => i16::from_le_bytes([b[0], b[1]]) as f64,
        (Kind::I, 4) => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        (Kind::I, _) => i64::from_le_bytes(b) as f64,
        (Kind::U, 1) => b[0] as f64,
        (Kind::U, 2) => u16::from_le_bytes([b[0], b[1]]) as f64,
        (Kind::U, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}

/// Parses a `.npy` file held in memory into a recording.
pub fn parse_npy(bytes: &[u8], name: &str) -> Result<Recording> {
    let fail = |msg: String| IoError::format(name, msg);
    let (h, data_start) = read_header(bytes, &fail)?;
    let dims = dims(&h, &fail)?;
    check_body(&h, (bytes.len() - data_start) as u64, &fail)?;
    read_body(&h, dims, Body::Bytes(&bytes[data_start..]), name)
}

/// The most bytes a Fortran-order array read as a stream may hold: its frames are spread over
/// all of it, so it is read whole.
const MAX_FORTRAN_STREAM: usize = 256 << 20;

/// Parses a `.npy` array as it is read from `source` (a `.npz` member), whose stated length is
/// `size` bytes: only its frames (sparse) are held, not its data.
pub(crate) fn read_npy(source: &mut dyn Read, size: u64, name: &str) -> Result<Recording> {
    let fail = |msg: String| IoError::format(name, msg);
    let (h, data_start) = read_head(source, size, &fail)?;
    let dims = dims(&h, &fail)?;
    check_body(&h, size.saturating_sub(data_start as u64), &fail)?;
    read_body(&h, dims, Body::Stream(source), name)
}

/// The header of a `.npy` array read from the start of `source`, whose stated length is `size`
/// bytes, and where its data begin; `source` is left at the data.
fn read_head(
    source: &mut dyn Read,
    size: u64,
    fail: &impl Fn(String) -> IoError,
) -> Result<(NpyHeader, usize)> {
    let mut some = |n: usize| -> Result<Vec<u8>> {
        let mut v = Vec::new();
        (&mut *source)
            .take(n as u64)
            .read_to_end(&mut v)
            .map_err(|e| fail(format!("cannot read the array: {e}")))?;
        Ok(v)
    };
    let mut head = some(10)?;
    if matches!(head.get(6), Some(2 | 3)) {
        head.extend(some(2)?);
    }
    // NumPy writes a header of about a hundred bytes.
    let end = header_end(&head).filter(|&e| e <= (1 << 20) && e as u64 <= size);
    let Some(end) = end else {
        read_header(&head, fail)?;
        return Err(fail("truncated header".into()));
    };
    head.extend(some(end.saturating_sub(head.len()))?);
    read_header(&head, fail)
}

/// Where the header of a `.npy` whose first bytes are `b` ends, when they show it.
fn header_end(b: &[u8]) -> Option<usize> {
    if !b.starts_with(b"\x93NUMPY") {
        return None;
    }
    match *b.get(6)? {
        1 => Some(10 + usize::from(u16::from_le_bytes([*b.get(8)?, *b.get(9)?]))),
        2 | 3 => Some(12 + u32::from_le_bytes(b.get(8..12)?.try_into().ok()?) as usize),
        _ => None,
    }
}

/// The array's frames, rows and columns, within the limits of a recording.
fn dims(h: &NpyHeader, fail: &impl Fn(String) -> IoError) -> Result<(usize, usize, usize)> {
    let shape = &h.shape;
    let (t, r, c) = match shape[..] {
        [r, c] => (1, r, c),
        [t, r, c] => (t, r, c),
        _ => {
            return Err(fail(format!(
                "expected a 2-D or 3-D array, got shape {shape:?}"
            )));
        }
    };
    t.checked_mul(r)
        .and_then(|x| x.checked_mul(c))
        .filter(|&n| n > 0 && n <= 1 << 31)
        .ok_or_else(|| fail(format!("unusable shape {shape:?}")))?;
    let per = crate::limits::frame_sensors("a frame", r, c).map_err(fail)?;
    crate::limits::frame_count(t, per).map_err(fail)?;
    Ok((t, r, c))
}

/// Checks that the data hold `body` bytes, what the shape and dtype need.
fn check_body(h: &NpyHeader, body: u64, fail: &impl Fn(String) -> IoError) -> Result<()> {
    let need = (h.shape.iter().product::<usize>() * h.size) as u64;
    if body != need {
        let cut = if body < need { " (truncated)" } else { "" };
        return Err(fail(format!(
            "data holds {body} bytes, shape {:?} of {} needs {need}{cut}",
            h.shape, h.descr
        )));
    }
    Ok(())
}

/// The data of an array: in memory, or a stream read as the frames need it.
enum Body<'a> {
    Bytes(&'a [u8]),
    Stream(&'a mut dyn Read),
}

/// One value as a recording holds it: finite, within float32's range.
fn value(chunk: &[u8], h: &NpyHeader, fail: &impl Fn(String) -> IoError) -> Result<f32> {
    let v = decode(chunk, h);
    if v.is_infinite() {
        return Err(fail("array holds an infinite value".into()));
    }
    if v.abs() > f32::MAX as f64 {
        return Err(fail(format!(
            "array holds {v:e}, beyond the float32 range of a recording (±3.4e38)"
        )));
    }
    Ok(v as f32)
}

/// Reads the data (checked to hold the array) into sparse frames, frame by frame; NaN marks
/// a missing sensor.
fn read_body(
    h: &NpyHeader,
    (t, r, c): (usize, usize, usize),
    body: Body,
    name: &str,
) -> Result<Recording> {
    let fail = |msg: String| IoError::format(name, msg);
    let (per, size) = (r * c, h.size);
    let mut frames = SparseFrames::new(per);
    let mut frame = vec![0.0f32; per];
    if h.fortran {
        let owned;
        let bytes = match body {
            Body::Bytes(b) => b,
            Body::Stream(source) => {
                crate::limits::may_hold((t * per * size) as u64).map_err(&fail)?;
                owned = read_whole(source, t * per * size, name)?;
                &owned[..]
            }
        };
        // Fortran layout: index (i, j, k) of shape (t, r, c) sits at i + t * (j + r * k).
        for i in 0..t {
            for (p, v) in frame.iter_mut().enumerate() {
                let (j, k) = (p / c, p % c);
                *v = value(&bytes[(i + t * (j + r * k)) * size..][..size], h, &fail)?;
            }
            frames.push(&frame);
        }
    } else {
        let source: &mut dyn Read = match body {
            Body::Bytes(b) => &mut &b[..],
            Body::Stream(s) => s,
        };
        let mut raw = vec![0u8; per * size];
        for i in 0..t {
            // The frames held so far within the read's budget (a deflated member of dense
            // values may be far larger than its file).
            crate::limits::frame_count(i + 1, per).map_err(&fail)?;
            source
                .read_exact(&mut raw)
                .map_err(|e| fail(format!("cannot read the array: {e}")))?;
            for (v, chunk) in frame.iter_mut().zip(raw.chunks_exact(size)) {
                *v = value(chunk, h, &fail)?;
            }
            frames.push(&frame);
        }
    }
    let mut rec = Recording::from_sparse_nan(r, c, frames).map_err(|e| fail(e.to_string()))?;
    rec.format = Some(Format::Npy);
    Ok(rec)
}

/// A `.npy` array in a file, read window of frames by window as a streamed run asks for them
/// ([`super::FileFrames`]): never more than a window's values held. A `.npy` file's array, or a
/// stored `.npz` member's, is read at offsets: a C-order array's frames are contiguous (one read
/// a window); a Fortran-order array's values of one sensor are, so a window is one read of its
/// frames per sensor, in file order. A deflated member's C-order array is inflated from its
/// start, a window at a time, in order.
pub(crate) struct NpyFile {
    data: Data,
    h: NpyHeader,
    dims: (usize, usize, usize),
    name: String,
    format: Format,
}

/// Reopens a deflated `.npz` member: its array's bytes from the start, inflated as they are read
/// (its length and CRC-32 checked once the last is read).
pub(crate) type Reopen = Box<dyn FnMut() -> Result<Box<dyn Read + Send>> + Send>;

/// Where an [`NpyFile`] reads its values.
enum Data {
    /// At offsets of a file: the values begin at `at`.
    Seek { file: std::fs::File, at: u64 },
    /// Inflated in order: `reader` is at the start of frame `next`; the values begin `at`
    /// bytes into the member.
    Inflate {
        reopen: Reopen,
        reader: Box<dyn Read + Send>,
        next: usize,
        at: usize,
    },
}

impl NpyFile {
    /// The array of the `.npy` file at `path`, its header read and its length checked.
    pub(crate) fn open(path: &Path, name: &str) -> Result<Self> {
        let io = |source| IoError::Io {
            path: name.to_string(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let size = file.metadata().map_err(io)?.len();
        Self::at(file, 0, size, name, Format::Npy)
    }

    /// The array that fills `len` bytes of `file` from `base` (a stored `.npz` member), its
    /// header read and its length checked.
    pub(crate) fn at(
        mut file: std::fs::File,
        base: u64,
        len: u64,
        name: &str,
        format: Format,
    ) -> Result<Self> {
        use std::io::{Seek, SeekFrom};
        let fail = |msg: String| IoError::format(name, msg);
        (&file)
            .seek(SeekFrom::Start(base))
            .map_err(|e| fail(format!("cannot read the array: {e}")))?;
        let (h, data) = read_head(&mut file, len, &fail)?;
        let dims = dims(&h, &fail)?;
        check_body(&h, len - data as u64, &fail)?;
        let data = Data::Seek {
            file,
            at: base + data as u64,
        };
        let name = name.to_string();
        Ok(Self {
            data,
            h,
            dims,
            name,
            format,
        })
    }

    /// The C-order array of a deflated `.npz` member of `len` bytes (inflated), its header read
    /// and its length checked; a Fortran-order one is an error (its frames are spread over all
    /// of it: it is read whole).
    pub(crate) fn inflated(mut reopen: Reopen, len: u64, name: &str) -> Result<Self> {
        let fail = |msg: String| IoError::format(name, msg);
        let mut reader = reopen()?;
        let (h, at) = read_head(&mut reader, len, &fail)?;
        let dims = dims(&h, &fail)?;
        check_body(&h, len - at as u64, &fail)?;
        if h.fortran {
            return Err(fail(FORTRAN_DEFLATED.into()));
        }
        let data = Data::Inflate {
            reopen,
            reader,
            next: 0,
            at,
        };
        let name = name.to_string();
        Ok(Self {
            data,
            h,
            dims,
            name,
            format: Format::Npz,
        })
    }

    /// Frames `w0..w1` (within the array), their values in C order, NaN where the array holds
    /// NaN; an infinite value or one beyond float32's range is an error, as read whole. An
    /// inflated array's windows come in order.
    pub(crate) fn window(&mut self, w0: usize, w1: usize) -> Result<Vec<f32>> {
        use std::io::{Seek, SeekFrom};
        let (t, r, c) = self.dims;
        let (per, size, n) = (r * c, self.h.size, w1 - w0);
        let fail = |msg: String| IoError::format(&self.name, msg);
        let read_fail = |e: std::io::Error| fail(format!("cannot read the array: {e}"));
        let mut out = vec![0.0f32; n * per];
        let frame_bytes = (per * size) as u64;
        let file = match &mut self.data {
            Data::Seek { file, at } if self.h.fortran => (file, *at),
            Data::Seek { file, at } => {
                let mut raw = vec![0u8; n * per * size];
                file.seek(SeekFrom::Start(*at + w0 as u64 * frame_bytes))
                    .map_err(read_fail)?;
                file.read_exact(&mut raw).map_err(read_fail)?;
                return self.decode_into(&raw, out);
            }
            Data::Inflate { reader, next, .. } => {
                if w0 < *next {
                    return Err(fail(format!("frames {w0}..{w1} asked for after {next}")));
                }
                let skip = (w0 - *next) as u64 * frame_bytes;
                let skipped = std::io::copy(&mut (&mut *reader).take(skip), &mut std::io::sink());
                let mut raw = vec![0u8; n * per * size];
                skipped
                    .and_then(|_| reader.read_exact(&mut raw))
                    .map_err(read_fail)?;
                // After the last frame: the member's length and CRC-32, checked at its end.
                if w1 == t {
                    let mut rest = Vec::new();
                    reader.read_to_end(&mut rest).map_err(read_fail)?;
                }
                *next = w1;
                return self.decode_into(&raw, out);
            }
        };
        // Fortran layout: index (i, j, k) of shape (t, r, c) sits at i + t * (j + r * k).
        let (file, at) = file;
        let mut raw = vec![0u8; n * size];
        for k in 0..c {
            for j in 0..r {
                let from = at + ((w0 + t * (j + r * k)) * size) as u64;
                file.seek(SeekFrom::Start(from)).map_err(read_fail)?;
                file.read_exact(&mut raw).map_err(read_fail)?;
                for (i, chunk) in raw.chunks_exact(size).enumerate() {
                    out[i * per + j * c + k] = value(chunk, &self.h, &fail)?;
                }
            }
        }
        Ok(out)
    }

    /// `raw`'s values (C order) into `out`.
    fn decode_into(&self, raw: &[u8], mut out: Vec<f32>) -> Result<Vec<f32>> {
        let fail = |msg: String| IoError::format(&self.name, msg);
        for (v, chunk) in out.iter_mut().zip(raw.chunks_exact(self.h.size)) {
            *v = value(chunk, &self.h, &fail)?;
        }
        Ok(out)
    }

    /// An inflated array read again from its first frame.
    fn rewind(&mut self) -> Result<()> {
        if let Data::Inflate {
            reopen,
            reader,
            next,
            at,
        } = &mut self.data
        {
            let mut fresh = reopen()?;
            let mut head = (&mut fresh).take(*at as u64);
            std::io::copy(&mut head, &mut std::io::sink())
                .map_err(|e| IoError::format(&self.name, format!("cannot read the array: {e}")))?;
            (*reader, *next) = (fresh, 0);
        }
        Ok(())
    }

    /// The array as a recording without its values (see [`super::read_for_streaming`]): every
    /// frame read once, in windows, for its missing sensors (NaN in every frame; NaN in only
    /// some is an error, as read whole) and its values below 0; none held.
    pub(crate) fn shape(&mut self) -> Result<Recording> {
        let (t, r, c) = self.dims;
        let per = r * c;
        let mut nans = vec![0usize; per];
        let mut negatives = crate::recording::NegativeValues::default();
        for w0 in (0..t).step_by(crate::recording::FRAME_WINDOW) {
            let w1 = (w0 + crate::recording::FRAME_WINDOW).min(t);
            for (k, &v) in self.window(w0, w1)?.iter().enumerate() {
                match v.is_nan() {
                    true => nans[k % per] += 1,
                    false => negatives.add(v),
                }
            }
        }
        if let Some(i) = nans.iter().position(|&n| n > 0 && n < t) {
            // The message of the whole read (`Recording::from_sparse_nan`).
            let e = IoError::invalid(format!(
                "row {}, column {} is NaN in {} of {t} frames only",
                i / c,
                i % c,
                nans[i]
            ));
            return Err(IoError::format(&self.name, e.to_string()));
        }
        let mut frames = SparseFrames::new(per);
        (0..t).for_each(|_| frames.push_empty());
        let mask = nans.iter().map(|&n| n == 0).collect();
        let mut rec = Recording::from_sparse(r, c, frames, mask)?;
        rec.set_file_negatives(negatives);
        rec.format = Some(self.format);
        self.rewind()?;
        Ok(rec)
    }
}

/// Why a deflated member's Fortran-order array is read whole.
pub(crate) const FORTRAN_DEFLATED: &str =
    "a Fortran-order array in a deflated member is read whole (its frames are spread over all of it)";

/// `n` bytes of `source` (a Fortran-order array's data).
fn read_whole(source: &mut dyn Read, n: usize, name: &str) -> Result<Vec<u8>> {
    if n > MAX_FORTRAN_STREAM {
        return Err(IoError::format(
            name,
            format!(
                "a Fortran-order array of {n} bytes in an archive: more than the \
                 {MAX_FORTRAN_STREAM} read whole (save it in C order)"
            ),
        ));
    }
    let mut v = crate::limits::try_filled(n, 0u8).ok_or_else(|| {
        IoError::format(
            name,
            format!("cannot allocate memory for an array of {n} bytes"),
        )
    })?;
    source
        .read_exact(&mut v)
        .map_err(|e| IoError::format(name, format!("cannot read the array: {e}")))?;
    Ok(v)
}

/// Encodes a recording as a 3-D little-endian `f4` array (T, rows, cols) in C order, NaN at
/// missing sensors.
pub fn recording_to_npy(rec: &Recording) -> Vec<u8> {
    let shape = format!("({}, {}, {})", rec.n_frames(), rec.rows(), rec.cols());
    let mut out = npy_header("<f4", &shape);
    for v in rec.frames_with_nan() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Encodes an image of `rows × cols` values (row-major) as a 2-D little-endian `f8` array in C
/// order (NumPy's `float64`), such as the peak or PTI image of `pedo_io::measures`.
///
/// # Errors
///
/// [`IoError::InvalidInput`] when `values` does not hold `rows × cols` values.
pub fn image_to_npy(rows: usize, cols: usize, values: &[f64]) -> Result<Vec<u8>> {
    if rows.checked_mul(cols) != Some(values.len()) {
        return Err(IoError::invalid(format!(
            "an image of {rows}x{cols} needs {} values, got {}",
            rows.saturating_mul(cols),
            values.len()
        )));
    }
    let mut out = npy_header("<f8", &format!("({rows}, {cols})"));
    out.reserve(values.len() * 8);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

/// The magic, version 1.0 and header dict of an array of type `descr` and shape `shape` (a
/// Python tuple), padded so that the data starts at a multiple of 64 bytes.
fn npy_header(descr: &str, shape: &str) -> Vec<u8> {
    let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // Magic (6) + version (2) + length (2) + dict + padding + '\n' must be a multiple of 64.
    let total = (10 + dict.len() + 1).div_ceil(64) * 64;
    let mut header = dict.into_bytes();
    header.resize(total - 10 - 1, b' ');
    header.push(b'\n');
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    out
}

/// Writes a recording as `.npy` (see [`recording_to_npy`]).
pub fn write_npy(rec: &Recording, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    std::fs::write(path, recording_to_npy(rec)).map_err(|source| IoError::Io {
        path: path.display().to_string(),
        source,
    })
}
