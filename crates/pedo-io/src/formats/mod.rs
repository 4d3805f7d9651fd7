//! Readers and writers, and format detection.

pub mod asf;
pub mod csv;
pub mod images;
pub mod lst;
pub mod npy;
pub mod npz;
pub mod own_tables;
pub mod pedar;
pub mod pedcad;
pub mod stamp;
mod stream;
pub mod zebris_raw;

use crate::error::{IoError, Result};
use crate::recording::{Format, Recording};
use std::path::{Path, PathBuf};

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

/// The text of a file written as UTF-16 with its byte-order mark (`FF FE`: little-endian, as
/// Windows Notepad's "Unicode" and Excel's "Unicode Text" write it; `FE FF`: big-endian), as
/// UTF-8 without the mark, so that it reads exactly as its UTF-8 form; `None` for any other
/// file. A unit that is no UTF-16 (a lone surrogate, an odd last byte) becomes U+FFFD.
pub fn utf16_to_utf8(bytes: &[u8]) -> Option<Vec<u8>> {
    let little = utf16_little_endian(bytes)?;
    let units = bytes[2..].chunks(2).map(|c| match (c, little) {
        ([a, b], true) => u16::from_le_bytes([*a, *b]),
        ([a, b], false) => u16::from_be_bytes([*a, *b]),
        _ => 0xFFFD,
    });
    let text: String = char::decode_utf16(units)
        .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
        .collect();
    Some(text.into_bytes())
}

/// For bytes that begin with a UTF-16 byte-order mark, whether they are little-endian.
fn utf16_little_endian(bytes: &[u8]) -> Option<bool> {
    match bytes.get(..2)? {
        b"\xff\xfe" => Some(true),
        b"\xfe\xff" => Some(false),
        _ => None,
    }
}

/// The whole file, its memory reserved for the length the system states (a failed allocation is
/// an error naming the file, not an abort).
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read as _;
    let name = path.display().to_string();
    let io = |source| IoError::Io {
        path: name.clone(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let len = usize::try_from(len).unwrap_or(usize::MAX);
    let mut bytes = crate::limits::try_with_capacity(len).ok_or_else(|| {
        IoError::format(&name, format!("cannot allocate memory for its {len} bytes"))
    })?;
    file.read_to_end(&mut bytes).map_err(io)?;
    Ok(bytes)
}

/// The formats [`read_recording`] understands, as listed in [`IoError::UnknownFormat`].
pub const SUPPORTED: &str = "Tekscan .asf and CSV export, novel emed .lst, novel pedar .asc, \
Zebris .apd and XML raw-data export (or its TRIPOD JSON form, also gzip-compressed), \
RSscan/Materialise footscan export, CSV grid, NumPy .npy/.npz, PNG/TIFF images";

modal_core::option_set! {
    /// What reading needs besides the file itself (`--layout FILE`; Python `layout=`), and the
    /// limits a file is held to ([`crate::limits`]), raised for a file larger than any export
    /// they were sized for.
    ReadOptions {
        let d = crate::limits::Limits::DEFAULT;
        /// A pedar sensor-layout table (see [`pedar::PedarLayout::parse`]); `None`: the bundled
        /// layout of the common insole.
        layout: Option<PathBuf> = None;
            Value, "the bundled layout of the common insole",
            "Sensor-layout table of a novel pedar insole (CSV lines insole,sensor,x1,y1,...,x4,y4; '# unit: mm' or 'cm' for a pitch). Only pedar exports use it.";
        /// Most sensors of one frame ([`crate::limits::MAX_FRAME_SENSORS`]).
        max_frame_sensors: usize = d.frame_sensors;
            Value, d.frame_sensors,
            "Most sensors (rows x columns) a frame may have: a file claiming more is refused before anything is allocated.";
        /// Most frames of one recording ([`crate::limits::MAX_FRAMES`]).
        max_frames: usize = d.frames;
            Value, d.frames,
            "Most frames a recording may have: a file claiming or holding more is refused.";
        /// Most values of one recording ([`crate::limits::MAX_RECORDING_VALUES`]).
        max_values: usize = d.values;
            Value, d.values,
            "Most values (frames x sensors per frame) a recording may hold, zeros included: it bounds the frames a run takes a row of and the work on frames held whole (a frame holding few values costs what it holds).";
        /// Most MiB a compressed recording may expand to ([`crate::limits::MAX_DECOMPRESSED`]).
        max_decompressed_mb: usize = (d.decompressed >> 20) as usize;
            Value, d.decompressed >> 20,
            "Most MiB a gzip-compressed recording (or a deflated .npz member) may expand to; what is decompressed is parsed as it comes, never held whole.";
        /// Most MiB of text held at once ([`crate::limits::MAX_TOKEN_BYTES`]).
        max_text_mb: usize = d.text >> 20;
            Value, d.text >> 20,
            "Longest stretch of a text export held at once, in MiB: a line, an XML element, comment or CDATA section, a JSON string.";
        /// Most MiB of frame values a read holds whatever the file's size
        /// ([`crate::limits::MAX_HELD_BYTES`]).
        max_memory_mb: usize = (d.held >> 20) as usize;
            Value, d.held >> 20,
            "Most MiB of frame values a recording read may hold, or 128 times the file's size on disk when that is more: a small compressed file that expands to dense frames is refused before it takes their memory (zeros take none).";
    }
}

impl ReadOptions {
    /// Each limit at least 1 (the layout table is read, and checked, with the recording).
    pub fn validate(&self) -> std::result::Result<(), modal_core::OptionError> {
        for (option, value) in [
            ("max_frame_sensors", self.max_frame_sensors),
            ("max_frames", self.max_frames),
            ("max_values", self.max_values),
            ("max_decompressed_mb", self.max_decompressed_mb),
            ("max_text_mb", self.max_text_mb),
            ("max_memory_mb", self.max_memory_mb),
        ] {
            if value == 0 {
                return Err(modal_core::OptionError::new(option, 0, "an integer >= 1"));
            }
        }
        Ok(())
    }

    /// The limits a read with these options is held to.
    pub fn limits(&self) -> crate::limits::Limits {
        crate::limits::Limits {
            frame_sensors: self.max_frame_sensors,
            frames: self.max_frames,
            values: self.max_values,
            decompressed: (self.max_decompressed_mb as u64).saturating_mul(1 << 20),
            text: self.max_text_mb.saturating_mul(1 << 20),
            held: (self.max_memory_mb as u64).saturating_mul(1 << 20),
        }
    }
}

/// The reading options' declarations: the command line's flags, Python's keywords and the
/// documentation are made from them.
pub fn read_option_specs() -> Vec<modal_core::OptionSpec> {
    ReadOptions::specs()
}

/// How many leading bytes [`sniff_format`] looks at.
pub const SNIFF_BYTES: usize = 16 * 1024;

/// Guesses the format of a file from its content; see [`sniff_format`].
pub fn detect_format(path: &Path, head: &[u8]) -> Option<Format> {
    sniff_format(path, head).ok()
}

/// Extensions that name one of our recording formats and nothing else: a file that carries one
/// is meant as a recording even when its content is empty or unreadable.
pub const RECORDING_EXTENSIONS: [&str; 5] = ["asf", "lst", "apd", "npy", "npz"];

/// Whether `path`'s extension names a recording format ([`RECORDING_EXTENSIONS`]), whatever the
/// file holds.
pub fn has_recording_extension(path: &Path) -> bool {
    extension(path).is_some_and(|e| RECORDING_EXTENSIONS.contains(&e.as_str()))
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

/// Decides the format of a file from its first bytes (`head`, ideally [`SNIFF_BYTES`] long):
/// magic numbers, then the text's markers; the extension only breaks ties (a text that matches
/// no marker but carries a structured format's extension goes to that format's parser, which
/// then names the line that is wrong). `Err` says what the content looks like instead.
pub fn sniff_format(path: &Path, head: &[u8]) -> std::result::Result<Format, String> {
    let head = &head[..head.len().min(SNIFF_BYTES)];
    if head.is_empty() {
        return Err("the file is empty".into());
    }
    // A results table has a header of names and rows of numbers: a CSV grid, but for its names.
    if let Some(what) = own_tables::own_output(head) {
        return Err(what);
    }
    if let Some(text) = utf16_to_utf8(head) {
        return sniff_format(path, &text).map_err(|what| format!("UTF-16 text: {what}"));
    }
    let magic: [(&[u8], Format); 5] = [
        (b"\x93NUMPY", Format::Npy),
        (b"PK\x03\x04", Format::Npz),
        (b"\x89PNG\r\n\x1a\n", Format::Png),
        (b"II*\0", Format::Tiff),
        (b"MM\0*", Format::Tiff),
    ];
    if let Some(&(_, f)) = magic.iter().find(|(m, _)| head.starts_with(m)) {
        return Ok(f);
    }
    if head.starts_with(GZIP_MAGIC) {
        return sniff_gzip(path, head);
    }
    if head.starts_with(b"PK\x05\x06") {
        return Err("an empty zip archive".into());
    }
    let head = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    // Text: no NUL and hardly any control characters besides tab, line ends and form feed.
    let controls = head
        .iter()
        .filter(|&&b| b < 32 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0c))
        .count();
    if head.contains(&0) || controls * 100 > head.len() {
        return Err(format!(
            "binary data of no known kind (first bytes {})",
            head.iter()
                .take(8)
                .map(|b| format!("{b:02x}"))
                .collect::<Vec<_>>()
                .join(" ")
        ));
    }
    let text: String = head.iter().map(|&b| b as char).collect();
    if let Some(f) = sniff_text(&text) {
        return Ok(f);
    }
    match extension(path).as_deref() {
        Some("asf") => return Ok(Format::Asf),
        Some("lst") => return Ok(Format::Lst),
        Some("apd") => return Ok(Format::Zebris),
        _ => {}
    }
    Err(describe_text(&text))
}

/// The format a text's markers name, if any.
fn sniff_text(text: &str) -> Option<Format> {
    if let Some(f) = zebris_raw::sniff(text) {
        return Some(f);
    }
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let starts = |p: &str| lines.iter().any(|l| l.starts_with(p));
    if text.contains("ASCII_DATA") {
        return Some(Format::Asf);
    }
    let tekscan_keys = [
        "DATA_TYPE",
        "ROWS",
        "COLS",
        "SECONDS_PER_FRAME",
        "START_FRAME",
    ];
    if tekscan_keys.iter().filter(|k| starts(k)).count() >= 2 && starts("Frame") {
        return Some(Format::TekscanCsv);
    }
    if starts("SensCountX=") || starts("[Technical]") {
        let l = text.to_ascii_lowercase();
        let footscan = l.contains("footscan") || l.contains("rsscan") || starts("MinIdx=");
        return Some(if l.contains("zebris") || !footscan {
            Format::Zebris
        } else {
            Format::Footscan
        });
    }
    if (text.contains("scanning rate [Hz]") || text.contains("mask definition"))
        && lines
            .iter()
            .any(|l| l.to_ascii_lowercase().starts_with("time["))
    {
        return Some(Format::Pedar);
    }
    if text.contains("Matrix:") && (text.contains("Page") || text.contains("Pict-No")) {
        return Some(Format::Lst);
    }
    looks_like_grid(&lines).then_some(Format::Csv)
}

/// Whether a file that [`sniff_format`] took for `format` from its first bytes (`head`) has that
/// format's structure, not only its marker words: what a folder search asks before taking a
/// file for a recording (an explicitly named file is read by its sniffed format whatever this
/// says, so that a corrupt one gets its parser's error). A zip is a NumPy `.npz` only with
/// `.npy` members; a text is a Tekscan `.asf` only with an `ASCII_DATA` line after at least two
/// Tekscan header keys (`ROWS 60`, `COLS 21`, ...), a Tekscan CSV export only with those keys and
/// a `Frame N` line, an emed `.lst` only with a `Page N` (or `Pict-No.`) line and a
/// `Matrix: CxR`; so that a Word or Excel file, or a README describing these formats, is no
/// recording. Whether the file then parses is not asked: a corrupt recording still looks like one.
pub fn looks_like_recording(format: Format, head: &[u8]) -> bool {
    let head = &head[..head.len().min(SNIFF_BYTES)];
    if let Some(text) = utf16_to_utf8(head) {
        return looks_like_recording(format, &text);
    }
    if head.starts_with(GZIP_MAGIC) {
        use std::io::Read;
        let mut inner = Vec::new();
        let _ = flate2::read::GzDecoder::new(head)
            .take(SNIFF_BYTES as u64)
            .read_to_end(&mut inner);
        return looks_like_recording(format, &inner);
    }
    match format {
        Format::Npz => {
            return zip_member_names(head)
                .iter()
                .any(|n| n.to_ascii_lowercase().ends_with(".npy"));
        }
        Format::Asf | Format::TekscanCsv | Format::Lst => {}
        _ => return true,
    }
    let head = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    let text: String = head.iter().map(|&b| b as char).collect();
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    match format {
        Format::Asf => lines
            .iter()
            .position(|l| l.starts_with("ASCII_DATA"))
            .is_some_and(|at| tekscan_key_lines(&lines[..at]) >= 2),
        Format::TekscanCsv => lines
            .iter()
            .position(|l| is_frame_line(l))
            .is_some_and(|at| tekscan_key_lines(&lines[..at]) >= 2),
        Format::Lst => {
            let page = lines.iter().any(|l| {
                l.strip_prefix("Page")
                    .is_some_and(|n| n.trim().parse::<u64>().is_ok())
                    || l.starts_with("Pict-No")
            });
            let matrix = text.split("Matrix:").skip(1).any(|rest| {
                let t = rest.trim_start();
                let (c, r) = t.split_once(['x', 'X']).unwrap_or(("", ""));
                !c.is_empty()
                    && c.bytes().all(|b| b.is_ascii_digit())
                    && r.bytes().next().is_some_and(|b| b.is_ascii_digit())
            });
            page && matrix
        }
        _ => true,
    }
}

/// The Tekscan header keys a file's header lines hold (`ROWS 60`, `ROWS,60`), each counted once.
fn tekscan_key_lines(lines: &[&str]) -> usize {
    const KEYS: [&str; 12] = [
        "DATA_TYPE",
        "VERSION",
        "ROWS",
        "COLS",
        "ROW_SPACING",
        "COL_SPACING",
        "SENSEL_AREA",
        "NOISE_THRESHOLD",
        "SECONDS_PER_FRAME",
        "START_FRAME",
        "END_FRAME",
        "UNITS",
    ];
    KEYS.iter()
        .filter(|k| {
            lines.iter().any(|l| {
                l.strip_prefix(*k)
                    .is_some_and(|rest| rest.starts_with([' ', '\t', ',', ';']))
            })
        })
        .count()
}

/// A Tekscan frame line: `Frame 12` (the CSV export follows it with commas).
fn is_frame_line(line: &str) -> bool {
    line.strip_prefix("Frame").is_some_and(|rest| {
        let n = rest.trim_start_matches([' ', '\t', ',', ';']);
        rest.len() > n.len() && n.bytes().next().is_some_and(|b| b.is_ascii_digit())
    })
}

/// The member names a zip archive's first bytes show: its local file headers from the start
/// (as far as their sizes are known) and any central-directory entries within `head`.
fn zip_member_names(head: &[u8]) -> Vec<String> {
    let u16_at = |i: usize| -> Option<usize> {
        head.get(i..i + 2)
            .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]])))
    };
    let u32_at = |i: usize| -> Option<usize> {
        head.get(i..i + 4)
            .and_then(|b| usize::try_from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])).ok())
    };
    let name = |at: usize, len: usize| {
        head.get(at..at + len)
            .map(|n| String::from_utf8_lossy(n).into_owned())
    };
    let mut names = Vec::new();
    let mut at = 0;
    while head.get(at..at + 4) == Some(b"PK\x03\x04") {
        let (Some(flags), Some(size), Some(n), Some(extra)) = (
            u16_at(at + 6),
            u32_at(at + 18),
            u16_at(at + 26),
            u16_at(at + 28),
        ) else {
            break;
        };
        match name(at + 30, n) {
            Some(member) => names.push(member),
            None => break,
        }
        // With a data descriptor (flag bit 3) the size follows the data: no further header.
        if flags & 8 != 0 {
            break;
        }
        at += 30 + n + extra + size;
    }
    let mut from = 0;
    while let Some(i) = head[from..]
        .windows(4)
        .position(|w| w == b"PK\x01\x02")
        .map(|i| from + i)
    {
        if let Some(member) = u16_at(i + 28).and_then(|n| name(i + 46, n)) {
            names.push(member);
        }
        from = i + 4;
    }
    names
}

/// A delimited grid: after at most one header line, the first lines are all numbers (or the
/// no-sensor marks `-1`, `B`, `NaN`).
fn looks_like_grid(lines: &[&str]) -> bool {
    let content: Vec<&&str> = lines.iter().filter(|l| !l.is_empty()).take(6).collect();
    let numeric = |l: &str| {
        let fields: Vec<&str> = l
            .split([',', ';', '\t', ' '])
            .map(str::trim)
            .filter(|f| !f.is_empty())
            .collect();
        !fields.is_empty()
            && fields.iter().all(|f| {
                parse_num(f).is_some() || matches!(f.to_ascii_lowercase().as_str(), "b" | "nan")
            })
    };
    let body = match content.first() {
        Some(first) if !numeric(first) => &content[1..],
        _ => &content[..],
    };
    // A last line may be cut by the sniffing window.
    let full = body.len().saturating_sub(usize::from(body.len() > 1));
    !body.is_empty() && body[..full.max(1)].iter().all(|l| numeric(l))
}

/// One phrase saying what a text that is not a known recording looks like.
fn describe_text(text: &str) -> String {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    let l = text.to_ascii_lowercase();
    if l.contains("pedar") {
        return "text mentioning pedar, but without a pedar ASCII export's header \
                (`scanning rate [Hz]`, `time[secs]` column)"
            .into();
    }
    if first.starts_with('{') || first.starts_with('[') {
        return format!(
            "JSON or other structured text, first line {:?}",
            asf::trunc(first)
        );
    }
    if first.starts_with('<') {
        return "XML/HTML text".into();
    }
    format!(
        "text that is neither a known export nor a numeric grid, first line {:?}",
        asf::trunc(first)
    )
}

/// The first bytes of a gzip stream.
const GZIP_MAGIC: &[u8] = b"\x1f\x8b";

/// The format of the content of a gzip-compressed file, from the part of it `head` holds.
fn sniff_gzip(path: &Path, head: &[u8]) -> std::result::Result<Format, String> {
    use std::io::Read;
    let mut inner = Vec::new();
    // A head cut mid-stream decodes as far as it goes and then fails: what was decoded is enough.
    let _ = flate2::read::GzDecoder::new(head)
        .take(SNIFF_BYTES as u64)
        .read_to_end(&mut inner);
    let inner_path = path.with_extension("");
    match sniff_format(&inner_path, &inner) {
        Ok(f) if !matches!(f, Format::Npy | Format::Npz | Format::Png | Format::Tiff) => Ok(f),
        Ok(f) => Err(format!("gzip-compressed {f} (decompress it first)")),
        Err(what) => Err(format!("gzip-compressed {what}")),
    }
}

/// Parses an in-memory file of a known format; `name` is used in error messages. A
/// gzip-compressed file is decompressed as it is parsed (within [`crate::limits`]), and UTF-16
/// text (with its byte-order mark) read as its UTF-8 form.
pub fn parse_bytes(bytes: &[u8], format: Format, name: &str) -> Result<Recording> {
    parse_bytes_with(bytes, format, name, &ReadOptions::default())
}

/// [`parse_bytes`] with reading options (a pedar layout file).
pub fn parse_bytes_with(
    bytes: &[u8],
    format: Format,
    name: &str,
    opts: &ReadOptions,
) -> Result<Recording> {
    let size = bytes.len() as u64;
    opts.limits().apply(|| {
        crate::limits::reading(size, || {
            let gzip = bytes.starts_with(GZIP_MAGIC);
            if is_binary(format) && !gzip {
                return parse_binary(bytes, format, name);
            }
            parse_source(bytes, gzip, bytes.len(), format, name, opts)
        })
    })
}

/// Whether `format` is parsed from its bytes whole (a zip's directory is at its end, an image
/// decodes whole); the text formats are parsed as a stream.
fn is_binary(format: Format) -> bool {
    matches!(
        format,
        Format::Npy | Format::Npz | Format::Png | Format::Tiff
    )
}

fn parse_binary(bytes: &[u8], format: Format, name: &str) -> Result<Recording> {
    match format {
        Format::Npy => npy::parse_npy(bytes, name),
        Format::Npz => npz::parse_npz(bytes, name),
        _ => images::decode_image(bytes, name),
    }
}

/// Parses a recording of `format` from `source`, its file's bytes from the start, decompressed
/// as they are parsed when `gzip` (never whole first, and at most
/// [`MAX_DECOMPRESSED`](crate::limits::MAX_DECOMPRESSED) bytes); `size` is the length of a file
/// that is not compressed. UTF-16 text, and a compressed binary format, are read whole first.
fn parse_source(
    source: impl std::io::Read,
    gzip: bool,
    size: usize,
    format: Format,
    name: &str,
    opts: &ReadOptions,
) -> Result<Recording> {
    use std::io::BufRead as _;
    let mut decoded: Box<dyn std::io::BufRead> = if gzip {
        Box::new(std::io::BufReader::new(stream::Gunzip::new(source)))
    } else {
        Box::new(std::io::BufReader::new(source))
    };
    let size = match gzip {
        true => usize::try_from(crate::limits::current().decompressed).unwrap_or(usize::MAX),
        false => size,
    };
    let head = decoded
        .fill_buf()
        .map_err(|e| stream::read_error(name, e))?;
    if utf16_little_endian(head).is_some() || is_binary(format) {
        let bytes = stream::read_all(decoded, gzip, name)?;
        let text = utf16_to_utf8(&bytes);
        return parse_bytes_with(text.as_deref().unwrap_or(&bytes), format, name, opts);
    }
    parse_text(decoded, gzip, size, format, name, opts)
}

/// Parses a text format from `decoded` (see [`parse_source`]), each stretch of text bounded
/// ([`stream::Bounded`]).
fn parse_text(
    decoded: impl std::io::Read,
    gzip: bool,
    size: usize,
    format: Format,
    name: &str,
    opts: &ReadOptions,
) -> Result<Recording> {
    use stream::{bounded, parse_lines, Stretch};
    let lines = |stretch| bounded(decoded, gzip, stretch);
    match format {
        Format::Asf | Format::TekscanCsv => {
            let csv = format == Format::TekscanCsv;
            let mut keep = asf::Keep::All;
            asf::read_tekscan(lines(Stretch::Line), size, name, csv, &mut keep)
        }
        Format::Lst => {
            parse_lines(lines(Stretch::Line), name, |l| lst::read_lst(l, name)).map(|(r, _)| r)
        }
        Format::Csv => parse_lines(lines(Stretch::Line), name, |l| csv::read_csv(l, name)),
        Format::Zebris | Format::Footscan => {
            parse_lines(lines(Stretch::Line), name, |l| pedcad::read_pedcad(l, name))
        }
        Format::Pedar => {
            let layout = pedar_layout(opts)?;
            parse_lines(lines(Stretch::Line), name, |l| {
                pedar::read_pedar(l, name, &layout)
            })
        }
        Format::ZebrisXml => zebris_raw::read_zebris_xml(lines(Stretch::Xml), name),
        Format::ZebrisJson => zebris_raw::read_zebris_json(lines(Stretch::Json), name),
        Format::Npy | Format::Npz | Format::Png | Format::Tiff => Err(IoError::invalid(format!(
            "{name}: {format} is not a text format"
        ))),
    }
}

/// The sensor layout a pedar export is read with: the file of `--layout`, else the bundled one.
fn pedar_layout(opts: &ReadOptions) -> Result<std::sync::Arc<pedar::PedarLayout>> {
    Ok(std::sync::Arc::new(match &opts.layout {
        Some(file) => pedar::PedarLayout::from_file(file)?,
        None => pedar::PedarLayout::bundled().clone(),
    }))
}

/// Reads a recording from a file, a folder of images, or a numbered image sequence.
///
/// - a folder: every `.png`/`.tif`/`.tiff` in it, in natural (numeric-aware) name order;
/// - a path with a printf-style counter (`walk_%03d.png`, `walk_%d.png`): the files counting up from
///   0 or 1 until the first missing number;
/// - a file: the format is decided by its content ([`sniff_format`]); the extension only breaks
///   ties. A file that is no recording is an [`IoError::UnknownFormat`] saying what it looks like.
pub fn read_recording(path: impl AsRef<Path>) -> Result<Recording> {
    read_recording_with(path, &ReadOptions::default())
}

/// A recording read for a run that goes through it once, in order (`pedo_track::stream_sequence`):
/// a file whose frames can be read again window by window ([`why_read_whole`] says which) is
/// read once, checked whole, and returned without its values (every frame reads as 0: only its
/// size, sensor mask, units, values below 0 and number of frames are held), with a
/// [`FileFrames`] that reads its frames again, window by window, as the run asks for them; any
/// other recording is read whole, with no [`FileFrames`].
pub fn read_for_streaming(
    path: impl AsRef<Path>,
    opts: &ReadOptions,
) -> Result<(Recording, Option<FileFrames>)> {
    let read = read_for_run(path, opts)?;
    Ok((read.recording, read.frames))
}

/// A recording read for a run ([`read_for_run`]).
pub struct RunInput {
    /// The recording (without its values when `frames` reads them as the run goes).
    pub recording: Recording,
    /// The frames read again, window by window ([`read_for_streaming`]).
    pub frames: Option<FileFrames>,
    /// Lower-case hex SHA-256 of the file's bytes as the parser read them (the whole file:
    /// what the parser left unread is hashed after it); `None` for a folder or a numbered
    /// sequence of images. A second reading of a streamed file must give the same digest.
    pub sha256: Option<String>,
}

/// [`read_for_streaming`], with the SHA-256 of the bytes parsed.
pub fn read_for_run(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<RunInput> {
    let path = path.as_ref();
    opts.limits()
        .apply(|| crate::limits::reading(bytes_on_disk(path), || read_for_run_within(path, opts)))
}

/// [`read_for_run`] within the limits of `opts`, set by the caller.
fn read_for_run_within(path: &Path, opts: &ReadOptions) -> Result<RunInput> {
    let name = path.display().to_string();
    // Anything else, or a file that cannot be opened or sniffed, is read (and its error
    // reported) the usual way.
    let sniffed = match path.is_dir() {
        true => None,
        false => Sniffed::open(path, &name).ok(),
    };
    let Some(sniffed) = sniffed.filter(|s| s.why_read_whole().is_none()) else {
        let (recording, sha256) = read_hashed(path, opts)?;
        return Ok(RunInput {
            recording,
            frames: None,
            sha256,
        });
    };
    let (shape, source, sha256) = match sniffed.format {
        format @ (Format::Npy | Format::Npz) => {
            // The array is read at offsets (or inflated in order), window by window: its digest
            // is of the whole file, read once here; a change later is caught by the caller's
            // size and time check.
            let (mut bytes, sha, rest) = sniffed.hashed(&name)?;
            std::io::copy(&mut bytes, &mut std::io::sink())
                .map_err(|e| stream::read_error(&name, e))?;
            let sha256 =
                stamp::finish(&sha, Some(rest)).map_err(|e| stream::read_error(&name, e))?;
            let array = || -> Result<_> {
                let mut npy = match format {
                    Format::Npy => npy::NpyFile::open(path, &name)?,
                    _ => npz::stream_array(path, &name, true)?,
                };
                Ok((npy.shape()?, npy))
            };
            match array() {
                Ok((shape, npy)) => (shape, Source::Npy(npy), sha256),
                // An archive the whole read refuses, or reads otherwise: its outcome is the
                // whole read's.
                Err(_) if format == Format::Npz => {
                    let (recording, sha256) = read_hashed(path, opts)?;
                    let frames = None;
                    return Ok(RunInput {
                        recording,
                        frames,
                        sha256,
                    });
                }
                Err(e) => return Err(e),
            }
        }
        format => {
            let size = sniffed.size;
            let (bytes, sha, rest) = sniffed.hashed(&name)?;
            let layout = (format == Format::Pedar)
                .then(|| pedar_layout(opts))
                .transpose()?;
            let text = Text {
                format,
                size,
                layout,
            };
            let shape = text.read(bytes, &name, &mut asf::Keep::Handed(None))?;
            let sha256 =
                stamp::finish(&sha, Some(rest)).map_err(|e| stream::read_error(&name, e))?;
            let source = Source::text(path.to_path_buf(), name.clone(), text, opts.limits());
            (shape, source, sha256)
        }
    };
    let frames = FileFrames {
        source,
        next: 0,
        path: path.to_path_buf(),
        name,
        expected: Some(sha256.clone()),
    };
    Ok(RunInput {
        recording: shape,
        frames: Some(frames),
        sha256: Some(sha256),
    })
}

/// Why a run that streams reads the file at `path` whole, `None` when it reads its frames as it
/// goes ([`read_for_streaming`]); `None` too for a file that cannot be read (its error is
/// the reading's).
pub fn why_read_whole(path: impl AsRef<Path>) -> Option<String> {
    let path = path.as_ref();
    if path.is_dir() || (!path.exists() && path.to_str().is_some_and(images::has_counter)) {
        return Some("a folder or sequence of images is read whole".into());
    }
    Sniffed::open(path, &path.display().to_string())
        .ok()?
        .why_read_whole()
}

/// The frames of a file read again, in order (see [`read_for_streaming`]); only a window's
/// frames are held at a time.
pub struct FileFrames {
    source: Source,
    /// The number of the next frame to come.
    next: usize,
    path: PathBuf,
    name: String,
    /// The digest of the first reading, which the second one (a text file's reading thread
    /// sends it after the last frame) must equal.
    expected: Option<String>,
}

/// Where a [`FileFrames`] reads its frames.
enum Source {
    /// A text file (Tekscan `.asf` or CSV export, emed `.lst`, pedar, Zebris `.apd` or footscan export)
    /// parsed again by a thread of its own, handing its frames one by one and, after the last,
    /// the SHA-256 of the bytes it read.
    Text {
        frames: std::sync::mpsc::Receiver<Result<Vec<f32>>>,
        digest: std::sync::mpsc::Receiver<String>,
    },
    /// A `.npy` array, read a window at a time.
    Npy(npy::NpyFile),
}

/// A text format a run reads as it goes, parsed again by a thread of its own ([`Source::Text`]).
#[derive(Clone)]
struct Text {
    format: Format,
    /// The file's length in bytes.
    size: usize,
    /// The sensor layout of a pedar export (read once: both readings place it alike).
    layout: Option<std::sync::Arc<pedar::PedarLayout>>,
}

impl Text {
    /// The recording in `bytes` (the file from its start), each frame kept or handed on as
    /// `keep` says.
    fn read(
        &self,
        bytes: impl std::io::Read,
        name: &str,
        keep: &mut asf::Keep<'_>,
    ) -> Result<Recording> {
        let lines = stream::bounded(bytes, false, stream::Stretch::Line);
        match self.format {
            Format::Lst => {
                stream::parse_lines(lines, name, |l| lst::read_lst_keeping(l, name, keep))
                    .map(|(r, _)| r)
            }
            Format::Zebris | Format::Footscan => {
                stream::parse_lines(lines, name, |l| pedcad::read_pedcad_keeping(l, name, keep))
            }
            Format::Pedar => {
                let layout = self
                    .layout
                    .as_deref()
                    .unwrap_or(pedar::PedarLayout::bundled());
                stream::parse_lines(lines, name, |l| {
                    pedar::read_pedar_keeping(l, name, layout, keep)
                })
            }
            format => {
                let csv = format == Format::TekscanCsv;
                asf::read_tekscan(lines, self.size, name, csv, keep)
            }
        }
    }
}

impl Source {
    fn text(path: PathBuf, name: String, text: Text, limits: crate::limits::Limits) -> Self {
        let (send, frames) = std::sync::mpsc::sync_channel(crate::recording::FRAME_WINDOW);
        let (send_digest, digest) = std::sync::mpsc::sync_channel(1);
        std::thread::spawn(move || {
            let read = || -> Result<String> {
                let io = |source| IoError::Io {
                    path: name.clone(),
                    source,
                };
                let file = std::fs::File::open(&path).map_err(io)?;
                let rest = file.try_clone().map_err(io)?;
                let sha = SharedSha::default();
                let hashed = stamp::Hashing::new(file, &sha);
                let mut hand = |frame: &[f32]| -> Result<()> {
                    send.send(Ok(frame.to_vec()))
                        .map_err(|_| IoError::invalid("the run stopped reading"))
                };
                let mut keep = asf::Keep::Handed(Some(&mut hand));
                text.read(hashed, &name, &mut keep)?;
                stamp::finish(&sha, Some(rest)).map_err(|e| stream::read_error(&name, e))
            };
            match limits.apply(read) {
                Ok(digest) => drop(send_digest.send(digest)),
                // The first reading parsed these bytes whole: any failure now is a change.
                Err(e) => drop(send.send(Err(stamp::changed_because(&name, &e)))),
            }
        });
        Source::Text { frames, digest }
    }
}

impl FileFrames {
    /// The values of frames `next..w1`, those before `w0` dropped.
    fn values(&mut self, w0: usize, w1: usize, per: usize) -> Result<Vec<f32>> {
        let frames = match &mut self.source {
            Source::Npy(npy) => return npy.window(w0, w1),
            Source::Text { frames, .. } => frames,
        };
        let mut data = Vec::with_capacity((w1 - w0) * per);
        while self.next < w1 {
            let frame = frames.recv().map_err(|_| {
                IoError::invalid(format!(
                    "{}: the file has fewer frames on a second read",
                    self.name
                ))
            })??;
            if self.next >= w0 {
                data.extend_from_slice(&frame);
            }
            self.next += 1;
        }
        Ok(data)
    }

    /// Once the file's last frame has been handed over: fails unless a text file's second
    /// reading, or an array's file hashed again whole, gives the first reading's digest (a file
    /// rewritten between them, even to its old size and time).
    fn check_digest(&mut self) -> Result<()> {
        let Some(expected) = self.expected.take() else {
            return Ok(());
        };
        let Source::Text { frames, digest } = &self.source else {
            // An array read at offsets: its file hashed again whole.
            let digest =
                stamp::file_digest(&self.path).map_err(|e| stream::read_error(&self.name, e))?;
            return match digest == expected {
                true => Ok(()),
                false => Err(stamp::changed(&self.name)),
            };
        };
        // Frames after the last (none in a file read whole before) or the reading's error.
        if let Ok(more) = frames.try_recv() {
            more?;
            return Err(stamp::changed(&self.name));
        }
        match digest.recv() {
            Ok(d) if d == expected => Ok(()),
            Ok(_) => Err(stamp::changed(&self.name)),
            // The reading failed after its last frame: its error is on the frames' channel.
            Err(_) => match frames.recv() {
                Ok(Err(e)) => Err(e),
                _ => Err(stamp::changed(&self.name)),
            },
        }
    }
}

impl FileFrames {
    /// Once the run has read its last window: the digest of the whole file checked against the
    /// first reading's, if the last frame did not check it. A text file's reading goes on to
    /// its end (the frames the run did not ask for are passed over); an array read at offsets
    /// is hashed again from its start (the size and time of the file are checked after every
    /// window besides).
    fn check_rest(&mut self, n_frames: usize) -> Result<()> {
        if self.expected.is_none() {
            return Ok(());
        }
        if let Source::Text { .. } = self.source {
            while self.next < n_frames {
                let w1 = (self.next + crate::recording::FRAME_WINDOW).min(n_frames);
                self.values(w1, w1, 0)?;
                self.next = w1;
            }
        }
        self.check_digest()
    }
}

impl crate::recording::FrameSource for FileFrames {
    fn window(&mut self, recording: &Recording, w0: usize, w1: usize) -> Result<Recording> {
        if w0 < self.next || w1 <= w0 || w1 > recording.n_frames() {
            return Err(IoError::invalid(format!(
                "{}: frames {w0}..{w1} asked for after frame {}",
                self.name, self.next
            )));
        }
        let data = self.values(w0, w1, recording.rows() * recording.cols())?;
        self.next = w1;
        if self.next == recording.n_frames() {
            self.check_digest()?;
        }
        // The size, mask and units of the run's recording (its unit overrides applied).
        recording.like(w1 - w0, data)
    }

    fn finish(&mut self, recording: &Recording) -> Result<()> {
        self.check_rest(recording.n_frames())
    }
}

/// [`read_recording`] with reading options (a pedar layout file for `--layout FILE`).
pub fn read_recording_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Recording> {
    read_hashed(path.as_ref(), opts).map(|(recording, _)| recording)
}

/// [`read_recording_with`], with the SHA-256 of the bytes parsed ([`RunInput::sha256`]).
pub fn read_hashed(path: &Path, opts: &ReadOptions) -> Result<(Recording, Option<String>)> {
    opts.limits()
        .apply(|| crate::limits::reading(bytes_on_disk(path), || read_hashed_within(path, opts)))
}

/// The size on disk of the file at `path`, or of the files of a folder (an image sequence)
/// together; 0 when it cannot be read (the read then reports why).
fn bytes_on_disk(path: &Path) -> u64 {
    match std::fs::read_dir(path) {
        Ok(entries) => entries
            .flatten()
            .filter_map(|e| e.metadata().ok())
            .filter(|m| m.is_file())
            .map(|m| m.len())
            .sum(),
        Err(_) => std::fs::metadata(path).map_or(0, |m| m.len()),
    }
}

/// [`read_hashed`] within the limits of `opts`, set by the caller.
fn read_hashed_within(path: &Path, opts: &ReadOptions) -> Result<(Recording, Option<String>)> {
    if path.is_dir() {
        return Ok((images::read_image_folder(path)?, None));
    }
    if let Some(s) = path.to_str()
        && images::has_counter(s)
        && !path.exists()
    {
        return Ok((images::read_numbered(s)?, None));
    }
    let name = path.display().to_string();
    // Every text format is parsed as it is read (a long recording's file is never held whole,
    // a compressed one never decompressed whole); zip archives and images are read whole.
    let sniffed = Sniffed::open(path, &name)?;
    let format = sniffed.format;
    if is_binary(format) && !sniffed.is_gzip() {
        drop(sniffed);
        let bytes = read_bytes(path)?;
        let sha256 = stamp::hex(&<sha2::Sha256 as sha2::Digest>::digest(&bytes));
        return Ok((parse_binary(&bytes, format, &name)?, Some(sha256)));
    }
    let (size, gzip) = (sniffed.size, sniffed.is_gzip());
    let (bytes, sha, rest) = sniffed.hashed(&name)?;
    let recording = parse_source(bytes, gzip, size, format, &name, opts)?;
    let sha256 = stamp::finish(&sha, Some(rest)).map_err(|e| stream::read_error(&name, e))?;
    Ok((recording, Some(sha256)))
}

/// A recording's file opened, its first [`SNIFF_BYTES`] read and its format told from them.
/// A SHA-256 fed by a reader that a parser holds ([`stamp::Hashing`]).
type SharedSha = std::rc::Rc<std::cell::RefCell<sha2::Sha256>>;

struct Sniffed {
    path: PathBuf,
    file: std::fs::File,
    head: Vec<u8>,
    /// The file's length in bytes.
    size: usize,
    format: Format,
}

impl Sniffed {
    fn open(path: &Path, name: &str) -> Result<Self> {
        use std::io::Read as _;
        let io = |source| IoError::Io {
            path: name.to_string(),
            source,
        };
        // A FIFO or a device blocks or never ends: refused before it is opened (opening a FIFO
        // waits for a writer), and checked again once open.
        let regular = |m: &std::fs::Metadata| {
            match m.is_file() {
            true => Ok(()),
            false => Err(IoError::invalid(format!(
                "{name}: not a regular file (a device, FIFO or socket); a recording is read from a file"
            ))),
        }
        };
        regular(&std::fs::metadata(path).map_err(io)?)?;
        let mut file = std::fs::File::open(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        regular(&meta)?;
        let size = meta.len();
        let mut head = Vec::with_capacity(SNIFF_BYTES);
        (&mut file)
            .take(SNIFF_BYTES as u64)
            .read_to_end(&mut head)
            .map_err(io)?;
        // One of pedomatch's own outputs is no unknown format: it is refused naming it.
        if let Some(what) = own_tables::own_output(&head) {
            return Err(IoError::format(name, what));
        }
        let format =
            sniff_format(path, &head).map_err(|what| IoError::unknown_format(name, what))?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
            head,
            size: usize::try_from(size).unwrap_or(usize::MAX),
            format,
        })
    }

    /// Whether the file is gzip-compressed.
    fn is_gzip(&self) -> bool {
        self.head.starts_with(GZIP_MAGIC)
    }

    /// Why a run that streams reads this file whole ([`why_read_whole`]); `None` for a
    /// Tekscan `.asf` file or CSV export, an emed `.lst`, a `.npy` array and a `.npz` archive whose array is
    /// stored or deflated in C order, not gzip-compressed (nor UTF-16): the files a run reads
    /// again, window by window.
    fn why_read_whole(&self) -> Option<String> {
        if self.is_gzip() {
            return Some("a gzip-compressed file is read whole".into());
        }
        if utf16_little_endian(&self.head).is_some() {
            return Some("a UTF-16 text file is read whole".into());
        }
        match self.format {
            Format::Asf
            | Format::TekscanCsv
            | Format::Lst
            | Format::Zebris
            | Format::Footscan
            | Format::Pedar
            | Format::Npy => None,
            Format::Npz => npz::why_read_whole(&self.path, &self.path.display().to_string()),
            Format::Csv | Format::Png | Format::Tiff => Some("a single frame is read whole".into()),
            // Their frames are the windows of loaded sensors the file stores, held as such (a
            // frame costs its window, not the plate); read again they would be handed on as
            // whole plates, which a file of many near-empty frames would make costlier.
            Format::ZebrisXml | Format::ZebrisJson => Some(format!(
                "the {} format is read whole: its frames are held as the windows of loaded \
                 sensors the file stores, a few values each",
                self.format.name()
            )),
        }
    }

    /// The whole file's bytes, from the start.
    fn bytes(self) -> impl std::io::Read {
        use std::io::Read as _;
        std::io::Cursor::new(self.head).chain(self.file)
    }

    /// The whole file's bytes, from the start, hashed as they are read into the returned
    /// SHA-256, with a second handle on the file (sharing its offset) to hash what the parser
    /// leaves unread ([`stamp::finish`]).
    fn hashed(self, name: &str) -> Result<(impl std::io::Read, SharedSha, std::fs::File)> {
        let rest = self.file.try_clone().map_err(|source| IoError::Io {
            path: name.to_string(),
            source,
        })?;
        let sha = SharedSha::default();
        let bytes = stamp::Hashing::new(self.bytes(), &sha);
        Ok((bytes, sha, rest))
    }
}
