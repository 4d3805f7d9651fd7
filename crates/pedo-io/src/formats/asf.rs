//! Tekscan ASCII movie (`.asf`): `KEY value` header up to `ASCII_DATA @@`, then `Frame N` blocks of
//! ROWS lines of COLS comma-separated values; `B` marks a sensel outside the sensor outline.
//!
//! The Tekscan CSV export carries the same header and frames, but every line is padded with
//! commas to the width of the widest line (`ROWS 60,,,,`, `Frame 1,,,,`, blank lines `,,,,`),
//! there is no `ASCII_DATA @@` line and no closing `@@`: the header ends at the first `Frame`
//! line (the layout the CSV parser of the public `jiwooba/HSS-TAP` repository,
//! `additionalFiles/onfly_tekscan_2mat.m`, reads).

use super::parse_num;
use crate::error::{IoError, Result};
use crate::recording::stated_units;
use crate::recording::{Format, NegativeValues, Recording, SparseFrames};
use std::iter::Peekable;

/// A length with its unit (`5.08 mm`, `0.2 in`) in mm.
fn length_mm(v: &str) -> Option<f64> {
    let mut it = v.split_whitespace();
    let x = parse_num(it.next()?)?;
    let f = match it.next().map(|u| u.to_ascii_lowercase()).as_deref() {
        None | Some("mm") | Some("millimeters") | Some("millimetres") => 1.0,
        Some("cm") | Some("centimeters") | Some("centimetres") => 10.0,
        Some("in") | Some("inch") | Some("inches") => 25.4,
        Some("m") | Some("meters") | Some("metres") => 1000.0,
        _ => return None,
    };
    Some(x * f)
}

fn area_mm2(v: &str) -> Option<f64> {
    let mut it = v.split_whitespace();
    let x = parse_num(it.next()?)?;
    let f = match it.next().map(|u| u.to_ascii_lowercase()).as_deref() {
        None | Some("mm2") | Some("mm^2") | Some("mm²") => 1.0,
        Some("cm2") | Some("cm^2") | Some("cm²") => 100.0,
        Some("in2") | Some("in^2") | Some("sq.in") => 645.16,
        _ => return None,
    };
    Some(x * f)
}

/// Parses a Tekscan `.asf` file held in memory; `name` appears in error messages.
pub fn parse_asf(bytes: &[u8], name: &str) -> Result<Recording> {
    parse_tekscan(bytes, name, false)
}

/// Parses a Tekscan CSV export held in memory (see the module documentation).
pub fn parse_tekscan_csv(bytes: &[u8], name: &str) -> Result<Recording> {
    parse_tekscan(bytes, name, true)
}

/// A CSV-export line without its comma padding.
fn unpad(line: String) -> String {
    let t = line.trim_end_matches(|c: char| c == ',' || c.is_whitespace());
    if t.len() == line.len() {
        line
    } else {
        t.to_string()
    }
}

fn parse_tekscan(bytes: &[u8], name: &str, csv: bool) -> Result<Recording> {
    let lines = super::stream::bounded(bytes, false, super::stream::Stretch::Line);
    read_tekscan(lines, bytes.len(), name, csv, &mut Keep::All)
}

/// What the Tekscan parser does with each frame it has read.
pub(crate) enum Keep<'a> {
    /// Holds it (sparsely) in the recording.
    All,
    /// Holds none of its values (the recording's frames read as 0) and hands it to the
    /// function, if any; an error from it stops the reading.
    Handed(Option<&'a mut FrameHand<'a>>),
}

/// A function a frame read is handed to.
pub(crate) type FrameHand<'a> = dyn FnMut(&[f32]) -> Result<()> + 'a;

/// Reads a Tekscan `.asf` file or CSV export (`csv`) from `file` line by line: the file is
/// never held in memory, only its frames (sparse). `size` is the file's length in bytes.
pub(crate) fn read_tekscan(
    file: impl std::io::BufRead,
    size: usize,
    name: &str,
    csv: bool,
    keep: &mut Keep<'_>,
) -> Result<Recording> {
    super::stream::parse_lines(file, name, |lines| {
        parse_tekscan_lines(lines, size, name, csv, keep)
    })
}

/// The header fields as read, before they are checked against each other.
#[derive(Default)]
struct HeaderFields {
    rows: Option<usize>,
    cols: Option<usize>,
    dx: Option<f64>,
    dy: Option<f64>,
    area: Option<f64>,
    dt: Option<f64>,
    noise: Option<f64>,
    start: Option<i64>,
    end: Option<i64>,
    units: String,
}

/// The header: everything before the first frame.
struct Header {
    rows: usize,
    cols: usize,
    pitch_mm: Option<[f64; 2]>,
    sensel_area_mm2: Option<f64>,
    dt_s: Option<f64>,
    noise_threshold: Option<f64>,
    units: String,
    /// The frame count START_FRAME..END_FRAME states, when both are given.
    stated_frames: Option<usize>,
    /// The line of `ASCII_DATA` (of the first `Frame` line in a CSV export).
    data_line: usize,
}

impl HeaderFields {
    /// Takes one `KEY value` line; unknown keys are ignored. `bad` makes the error for a value
    /// that cannot be read.
    fn set(&mut self, key: &str, val: &str, bad: impl Fn(&str) -> IoError) -> Result<()> {
        let positive = |v: Option<f64>| v.filter(|&v| v > 0.0).ok_or_else(|| bad(key));
        let num = || parse_num(val.split_whitespace().next().unwrap_or(""));
        match key {
            "ROWS" | "COLS" => {
                let n = val
                    .parse::<usize>()
                    .ok()
                    .filter(|&n| n > 0 && n <= 100_000)
                    .ok_or_else(|| bad(key))?;
                *if key == "ROWS" {
                    &mut self.rows
                } else {
                    &mut self.cols
                } = Some(n);
            }
            "ROW_SPACING" => self.dy = Some(positive(length_mm(val))?),
            "COL_SPACING" => self.dx = Some(positive(length_mm(val))?),
            "SENSEL_AREA" => self.area = Some(positive(area_mm2(val))?),
            "SECONDS_PER_FRAME" => self.dt = Some(positive(num())?),
            "NOISE_THRESHOLD" => self.noise = Some(num().ok_or_else(|| bad(key))?),
            "START_FRAME" => self.start = Some(val.parse::<i64>().map_err(|_| bad(key))?),
            "END_FRAME" => self.end = Some(val.parse::<i64>().map_err(|_| bad(key))?),
            "UNITS" => self.units = normalise_units(val),
            _ => {}
        }
        Ok(())
    }

    /// Checks the fields once the data begin at `data_line`; `size` is the file's length in
    /// bytes.
    fn check(self, data_line: usize, size: usize, name: &str) -> Result<Header> {
        let err = |msg: String| IoError::parse(name, data_line, msg);
        let rows = self.rows.ok_or_else(|| err("header has no ROWS".into()))?;
        let cols = self.cols.ok_or_else(|| err("header has no COLS".into()))?;
        // Every sensel takes at least two bytes in the file, so a frame larger than the file is a
        // corrupt header, refused before anything of its size is allocated.
        if rows.checked_mul(cols).is_none_or(|per| per > size) {
            return Err(err(format!(
                "ROWS x COLS = {rows} x {cols} is more than the file can hold"
            )));
        }
        crate::limits::frame_sensors("ROWS x COLS", rows, cols).map_err(err)?;
        let stated_frames = match (self.start, self.end) {
            (Some(s), Some(e)) if e >= s => Some((e - s + 1) as usize),
            (Some(s), Some(e)) => return Err(err(format!("END_FRAME {e} before START_FRAME {s}"))),
            _ => None,
        };
        Ok(Header {
            rows,
            cols,
            pitch_mm: match (self.dx, self.dy) {
                (Some(x), Some(y)) => Some([x, y]),
                (Some(x), None) => Some([x, x]),
                (None, Some(y)) => Some([y, y]),
                _ => None,
            },
            sensel_area_mm2: self.area,
            dt_s: self.dt,
            noise_threshold: self.noise,
            units: self.units,
            stated_frames,
            data_line,
        })
    }
}

/// Reads the header up to `ASCII_DATA` (the `.asf`, which consumes that line) or up to the
/// first `Frame` line (the CSV export, which leaves it to be read as the first frame's).
fn read_header(
    lines: &mut Peekable<impl Iterator<Item = (usize, String)>>,
    size: usize,
    name: &str,
    csv: bool,
) -> Result<Header> {
    let mut fields = HeaderFields::default();
    while let Some((ln, line)) = lines.peek() {
        let (ln, t) = (*ln, line.trim().to_string());
        if csv && t.starts_with("Frame") {
            return fields.check(ln, size, name);
        }
        lines.next();
        if t.starts_with("ASCII_DATA") {
            return fields.check(ln, size, name);
        }
        let split = |c: char| c.is_whitespace() || (csv && c == ',');
        let (key, val) = match t.split_once(split) {
            Some((k, v)) => (k, v.trim()),
            None => (t.as_str(), ""),
        };
        fields.set(key, val, |what| {
            IoError::parse(name, ln, format!("cannot read {what} from {val:?}"))
        })?;
    }
    Err(IoError::format(
        name,
        if csv {
            "no `Frame` line: not a Tekscan CSV export or truncated header"
        } else {
            "no ASCII_DATA line: not a Tekscan ASCII file or truncated header"
        },
    ))
}

/// The frames as they are read, row by row, kept sparse (a long recording is never held as
/// dense values) or handed on ([`Keep`]).
struct FrameReader<'k, 'a> {
    rows: usize,
    cols: usize,
    stated_frames: Option<usize>,
    frames: SparseFrames,
    /// The values of the frame being read.
    frame: Vec<f32>,
    /// Whether each sensel holds a value (`false`: `B`), as the first frame says.
    mask: Vec<Option<bool>>,
    n_frames: usize,
    /// The number of the last `Frame N` line, and its line.
    last_number: Option<(i64, usize)>,
    /// Rows of the current frame read so far; `rows` between frames.
    row: usize,
    /// The line of the current frame's `Frame N`.
    frame_line: usize,
    keep: &'k mut Keep<'a>,
    /// The values below 0 of the frames handed on (not kept: counted as they pass).
    negatives: NegativeValues,
}

/// How a row of values ended.
enum RowEnd {
    Complete,
    /// The file ends inside this row.
    Cut,
}

impl<'k, 'a> FrameReader<'k, 'a> {
    fn new(header: &Header, keep: &'k mut Keep<'a>) -> Self {
        let per = header.rows * header.cols;
        Self {
            rows: header.rows,
            cols: header.cols,
            stated_frames: header.stated_frames,
            frames: SparseFrames::new(per),
            frame: Vec::with_capacity(per),
            mask: vec![None; per],
            n_frames: 0,
            last_number: None,
            row: header.rows,
            frame_line: header.data_line,
            keep,
            negatives: NegativeValues::default(),
        }
    }

    fn between_frames(&self) -> bool {
        self.row == self.rows
    }

    /// Starts a frame at its `Frame N` line `t` (line `ln`).
    fn start_frame(&mut self, ln: usize, t: &str, err: impl Fn(String) -> IoError) -> Result<()> {
        let rest = t
            .strip_prefix("Frame")
            .ok_or_else(|| err(format!("expected `Frame N`, found {:?}", trunc(t))))?;
        // I-Scan exports follow the number with the frame's time and raw sum:
        // `Frame 1, 0,, 12/2/2019 6:21:52.34PM,,,Raw Sum=,,310`.
        let number = rest
            .split(',')
            .next()
            .unwrap_or("")
            .trim()
            .parse::<i64>()
            .map_err(|_| err(format!("bad frame number in {:?}", trunc(t))))?;
        // Frames are numbered one after the other: a gap is a frame lost from the file, which
        // would shift the time of every later frame.
        if let Some((last, last_line)) = self.last_number
            && last.checked_add(1) != Some(number)
        {
            let what = match last.checked_add(2) {
                Some(n) if n == number => format!("frame {} is missing", last + 1),
                _ => format!("expected Frame {}", last.saturating_add(1)),
            };
            return Err(err(format!(
                "Frame {number} follows Frame {last} (line {last_line}): {what}"
            )));
        }
        self.last_number = Some((number, ln));
        if let Some(e) = self.stated_frames.filter(|&e| self.n_frames >= e) {
            return Err(err(format!(
                "more frames than END_FRAME - START_FRAME + 1 = {e}"
            )));
        }
        crate::limits::frame_count(self.n_frames + 1, self.rows * self.cols).map_err(&err)?;
        self.frame_line = ln;
        self.row = 0;
        Ok(())
    }

    /// Reads one row of values, `t`; `last` says whether it is the file's last line.
    fn read_row(&mut self, t: &str, last: bool, err: impl Fn(String) -> IoError) -> Result<RowEnd> {
        let mut k = 0usize;
        for tok in t.split(',') {
            let tok = tok.trim();
            if k == self.cols {
                if tok.is_empty() {
                    continue; // tolerate a trailing comma
                }
                return Err(err(format!("more than COLS = {} values", self.cols)));
            }
            let (v, present) = if tok.eq_ignore_ascii_case("B") {
                (0.0f32, false)
            } else if let Some(v) = parse_num(tok) {
                (v as f32, true)
            } else if last {
                // The file was cut inside this row (after a comma, or inside a number).
                return Ok(RowEnd::Cut);
            } else {
                return Err(err(format!(
                    "value {} is not a number: {:?}",
                    k + 1,
                    trunc(tok)
                )));
            };
            self.check_mask(k, present, &err)?;
            self.frame.push(v);
            k += 1;
        }
        if k != self.cols {
            return if last {
                Ok(RowEnd::Cut)
            } else {
                Err(err(format!("{k} values, expected COLS = {}", self.cols)))
            };
        }
        self.row += 1;
        if self.row == self.rows {
            self.end_frame()?;
        }
        Ok(RowEnd::Complete)
    }

    /// Checks that sensel `k` of the current row is a value or `B` as in the earlier frames.
    fn check_mask(
        &mut self,
        k: usize,
        present: bool,
        err: impl Fn(String) -> IoError,
    ) -> Result<()> {
        let what = |p: bool| if p { "a value" } else { "B" };
        match &mut self.mask[self.row * self.cols + k] {
            m @ None => *m = Some(present),
            Some(m) if *m != present => {
                return Err(err(format!(
                    "sensel (row {}, column {}) is {} here but was {} in an earlier frame",
                    self.row + 1,
                    k + 1,
                    what(present),
                    what(*m)
                )));
            }
            _ => {}
        }
        Ok(())
    }

    fn end_frame(&mut self) -> Result<()> {
        self.n_frames += 1;
        match self.keep {
            Keep::All => self.frames.push(&self.frame),
            Keep::Handed(hand) => {
                // `B` reads as 0: only sensors' values count.
                self.frame.iter().for_each(|&v| self.negatives.add(v));
                self.frames.push_empty();
                if let Some(hand) = hand {
                    hand(&self.frame)?;
                }
            }
        }
        self.frame.clear();
        Ok(())
    }

    /// Checks that the file held every frame it states, the last one whole; `closed`: the
    /// `.asf`'s closing `@@` was read (the CSV export has none).
    fn finish(
        self,
        last_line: usize,
        closed: bool,
        csv: bool,
        name: &str,
    ) -> Result<(SparseFrames, Vec<bool>, NegativeValues)> {
        let err = |msg: String| IoError::parse(name, last_line, msg);
        let partial = if self.between_frames() {
            String::new()
        } else {
            format!(
                " (the frame at line {} has {} of {} rows)",
                self.frame_line, self.row, self.rows
            )
        };
        if let Some(e) = self.stated_frames.filter(|&e| self.n_frames < e) {
            return Err(err(format!(
                "truncated: the file ends after {} complete frames, its header \
                 (START_FRAME..END_FRAME) states {e}{partial}",
                self.n_frames
            )));
        }
        if !self.between_frames() {
            return Err(err(format!("truncated{partial}")));
        }
        if self.n_frames == 0 {
            return Err(err("no frames".into()));
        }
        if !closed && !csv {
            // The export closes its data with `@@`; without it the file was cut, possibly inside
            // a number of the last row, which would otherwise pass unnoticed.
            return Err(err("truncated: no closing @@ after the last frame".into()));
        }
        let mask = self.mask.into_iter().map(|m| m.unwrap_or(true)).collect();
        Ok((self.frames, mask, self.negatives))
    }
}

fn parse_tekscan_lines(
    lines: impl Iterator<Item = (usize, String)>,
    size: usize,
    name: &str,
    csv: bool,
    keep: &mut Keep<'_>,
) -> Result<Recording> {
    let mut lines = lines
        .map(|(ln, l)| (ln, if csv { unpad(l) } else { l }))
        .peekable();
    let header = read_header(&mut lines, size, name, csv)?;
    let mut reader = FrameReader::new(&header, keep);
    let mut last_line = header.data_line;
    let mut closed = false;
    while let Some((ln, line)) = lines.next() {
        last_line = ln;
        let t = line.trim();
        let err = |msg: String| IoError::parse(name, ln, msg);
        if reader.between_frames() || closed {
            match t {
                "" => {}
                _ if closed => return Err(err("data after the closing @@".into())),
                "@@" => closed = true,
                _ => reader.start_frame(ln, t, err)?,
            }
        } else if let RowEnd::Cut = reader.read_row(t, lines.peek().is_none(), err)? {
            break; // reported by `finish` as a truncated frame
        }
    }
    let handed = matches!(reader.keep, Keep::Handed(_));
    let (frames, mask, negatives) = reader.finish(last_line, closed, csv, name)?;
    let mut rec = Recording::from_sparse(header.rows, header.cols, frames, mask)?;
    if handed {
        rec.set_file_negatives(negatives);
    }
    rec.pitch_mm = header.pitch_mm;
    rec.sensel_area_mm2 = header.sensel_area_mm2;
    rec.dt_s = header.dt_s;
    rec.units = stated_units(&header.units);
    rec.noise_threshold = header.noise_threshold;
    rec.format = Some(if csv { Format::TekscanCsv } else { Format::Asf });
    Ok(rec)
}

fn normalise_units(v: &str) -> String {
    let v = v.trim();
    if v.eq_ignore_ascii_case("kpa") {
        "kPa".to_string()
    } else {
        v.to_string()
    }
}

pub(crate) fn trunc(s: &str) -> String {
    s.chars().take(40).collect()
}
