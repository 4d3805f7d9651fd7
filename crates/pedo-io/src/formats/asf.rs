//! Tekscan ASCII movie (`.asf`): `KEY value` header up to `ASCII_DATA @@`, then `Frame N` blocks of
//! ROWS lines of COLS comma-separated values; `B` marks a sensel outside the sensor outline.
//!
//! The Tekscan CSV export carries the same header and frames, but every line is padded with
//! commas to the width of the widest line (`ROWS 60,,,,`, `Frame 1,,,,`, blank lines `,,,,`),
//! there is no `ASCII_DATA @@` line and no closing `@@`: the header ends at the first `Frame`
//! line (the layout the CSV parser of the public `jiwooba/HSS-TAP` repository,
//! `additionalFiles/onfly_tekscan_2mat.m`, reads).

use super::{latin1_lines, parse_num};
use crate::error::{IoError, Result};
use crate::recording::stated_units;
use crate::recording::{Format, Recording, SparseFrames};

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
    parse_tekscan_lines(latin1_lines(bytes), bytes.len(), name, csv, &mut Keep::All)
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
    // The lines as `latin1_lines` cuts them; a read error ends them and is reported instead of
    // what the parser makes of the cut file.
    let failure: std::cell::Cell<Option<std::io::Error>> = std::cell::Cell::new(None);
    let lines = file
        .split(b'\n')
        .map_while(|l| match l {
            Ok(l) => Some(l),
            Err(e) => {
                failure.set(Some(e));
                None
            }
        })
        .enumerate()
        .map(|(i, l)| {
            let l = l.strip_suffix(b"\r").unwrap_or(&l);
            (i + 1, l.iter().map(|&b| b as char).collect::<String>())
        });
    let parsed = parse_tekscan_lines(lines, size, name, csv, keep);
    match failure.take() {
        Some(source) => Err(IoError::Io {
            path: name.to_string(),
            source,
        }),
        None => parsed,
    }
}

fn parse_tekscan_lines(
    lines: impl Iterator<Item = (usize, String)>,
    size: usize,
    name: &str,
    csv: bool,
    keep: &mut Keep<'_>,
) -> Result<Recording> {
    let err = |line: usize, msg: String| IoError::parse(name, line, msg);
    let mut lines = lines
        .map(|(ln, l)| (ln, if csv { unpad(l) } else { l }))
        .peekable();
    let (mut rows, mut cols) = (None::<usize>, None::<usize>);
    let (mut dy, mut dx, mut area, mut dt, mut noise) = (None, None, None, None, None);
    let (mut start, mut end) = (None::<i64>, None::<i64>);
    let mut units = String::new();
    let mut data_line = None;
    while let Some((ln, line)) = lines.peek() {
        let (ln, t) = (*ln, line.trim().to_string());
        if csv && t.starts_with("Frame") {
            data_line = Some(ln);
            break;
        }
        lines.next();
        if t.starts_with("ASCII_DATA") {
            data_line = Some(ln);
            break;
        }
        let t = t.as_str();
        let split = |c: char| c.is_whitespace() || (csv && c == ',');
        let (key, val) = match t.split_once(split) {
            Some((k, v)) => (k, v.trim()),
            None => (t, ""),
        };
        let num = || parse_num(val.split_whitespace().next().unwrap_or(""));
        let bad = |what: &str| err(ln, format!("cannot read {what} from {val:?}"));
        match key {
            "ROWS" | "COLS" => {
                let n = val
                    .parse::<usize>()
                    .ok()
                    .filter(|&n| n > 0 && n <= 100_000)
                    .ok_or_else(|| bad(key))?;
                if key == "ROWS" {
                    rows = Some(n)
                } else {
                    cols = Some(n)
                }
            }
            "ROW_SPACING" => {
                dy = Some(
                    length_mm(val)
                        .filter(|&v| v > 0.0)
                        .ok_or_else(|| bad(key))?,
                )
            }
            "COL_SPACING" => {
                dx = Some(
                    length_mm(val)
                        .filter(|&v| v > 0.0)
                        .ok_or_else(|| bad(key))?,
                )
            }
            "SENSEL_AREA" => {
                area = Some(area_mm2(val).filter(|&v| v > 0.0).ok_or_else(|| bad(key))?)
            }
            "SECONDS_PER_FRAME" => dt = Some(num().filter(|&v| v > 0.0).ok_or_else(|| bad(key))?),
            "NOISE_THRESHOLD" => noise = Some(num().ok_or_else(|| bad(key))?),
            "START_FRAME" => start = Some(val.parse::<i64>().map_err(|_| bad(key))?),
            "END_FRAME" => end = Some(val.parse::<i64>().map_err(|_| bad(key))?),
            "UNITS" => units = normalise_units(val),
            _ => {}
        }
    }
    let data_line = data_line.ok_or_else(|| {
        IoError::format(
            name,
            if csv {
                "no `Frame` line: not a Tekscan CSV export or truncated header"
            } else {
                "no ASCII_DATA line: not a Tekscan ASCII file or truncated header"
            },
        )
    })?;
    let rows = rows.ok_or_else(|| err(data_line, "header has no ROWS".into()))?;
    let cols = cols.ok_or_else(|| err(data_line, "header has no COLS".into()))?;
    // Every sensel takes at least two bytes in the file, so a frame larger than the file is a
    // corrupt header, refused before anything of its size is allocated.
    let per = rows
        .checked_mul(cols)
        .filter(|&p| p <= size)
        .ok_or_else(|| {
            err(
                data_line,
                format!("ROWS x COLS = {rows} x {cols} is more than the file can hold"),
            )
        })?;
    let expected = match (start, end) {
        (Some(s), Some(e)) if e >= s => Some((e - s + 1) as usize),
        (Some(s), Some(e)) => {
            return Err(err(
                data_line,
                format!("END_FRAME {e} before START_FRAME {s}"),
            ));
        }
        _ => None,
    };

    // Frames are kept sparse as they are read: a long recording is never held as dense values.
    let mut frames = SparseFrames::new(per);
    let mut frame: Vec<f32> = Vec::with_capacity(per);
    let mut mask: Vec<Option<bool>> = vec![None; per];
    let mut n_frames = 0usize;
    let mut row_in_frame = rows; // `rows` = not inside a frame
    let mut last_ln = data_line;
    let mut frame_ln = data_line;
    let mut ended = false;
    while let Some((ln, line)) = lines.next() {
        last_ln = ln;
        let t = line.trim();
        if ended {
            if t.is_empty() {
                continue;
            }
            return Err(err(ln, "data after the closing @@".into()));
        }
        if row_in_frame == rows {
            if t.is_empty() {
                continue;
            }
            if t == "@@" {
                ended = true;
                continue;
            }
            let rest = t
                .strip_prefix("Frame")
                .ok_or_else(|| err(ln, format!("expected `Frame N`, found {:?}", trunc(t))))?;
            // I-Scan exports follow the number with the frame's time and raw sum:
            // `Frame 1, 0,, 12/2/2019 6:21:52.34PM,,,Raw Sum=,,310`.
            rest.split(',')
                .next()
                .unwrap_or("")
                .trim()
                .parse::<i64>()
                .map_err(|_| err(ln, format!("bad frame number in {:?}", trunc(t))))?;
            if expected.is_some_and(|e| n_frames >= e) {
                return Err(err(
                    ln,
                    format!(
                        "more frames than END_FRAME - START_FRAME + 1 = {}",
                        expected.unwrap_or(0)
                    ),
                ));
            }
            frame_ln = ln;
            row_in_frame = 0;
            continue;
        }
        let mut k = 0usize;
        let mut cut = false;
        for tok in t.split(',') {
            let tok = tok.trim();
            if k == cols {
                if tok.is_empty() {
                    continue; // tolerate a trailing comma
                }
                return Err(err(ln, format!("more than COLS = {cols} values")));
            }
            let idx = row_in_frame * cols + k;
            let (v, present) = if tok.eq_ignore_ascii_case("B") {
                (0.0f32, false)
            } else if let Some(v) = parse_num(tok) {
                (v as f32, true)
            } else if lines.peek().is_none() {
                // The file was cut inside this row (after a comma, or inside a number).
                cut = true;
                break;
            } else {
                return Err(err(
                    ln,
                    format!("value {} is not a number: {:?}", k + 1, trunc(tok)),
                ));
            };
            match mask[idx] {
                None => mask[idx] = Some(present),
                Some(m) if m != present => {
                    return Err(err(
                        ln,
                        format!(
                            "sensel (row {}, column {}) is {} here but was {} in an earlier frame",
                            row_in_frame + 1,
                            k + 1,
                            if present { "a value" } else { "B" },
                            if m { "a value" } else { "B" }
                        ),
                    ));
                }
                _ => {}
            }
            frame.push(v);
            k += 1;
        }
        if k != cols || cut {
            if lines.peek().is_none() {
                // The file ends inside this row: reported below as a truncated frame.
                break;
            }
            return Err(err(ln, format!("{k} values, expected COLS = {cols}")));
        }
        row_in_frame += 1;
        if row_in_frame == rows {
            n_frames += 1;
            match keep {
                Keep::All => frames.push(&frame),
                Keep::Handed(hand) => {
                    // Frames too large to hold sparsely are held whole all the same.
                    if frames.is_whole() {
                        frames.push(&frame);
                    } else {
                        frames.push_empty();
                    }
                    if let Some(hand) = hand {
                        hand(&frame)?;
                    }
                }
            }
            frame.clear();
        }
    }
    let partial = if row_in_frame != rows {
        format!(" (the frame at line {frame_ln} has {row_in_frame} of {rows} rows)")
    } else {
        String::new()
    };
    if let Some(e) = expected
        && n_frames < e
    {
        return Err(err(
            last_ln,
            format!(
                "truncated: the file ends after {n_frames} complete frames, its header \
                     (START_FRAME..END_FRAME) states {e}{partial}"
            ),
        ));
    }
    if row_in_frame != rows {
        return Err(err(last_ln, format!("truncated{partial}")));
    }
    if n_frames == 0 {
        return Err(err(last_ln, "no frames".into()));
    }
    if !ended && !csv {
        // The export closes its data with `@@`; without it the file was cut, possibly inside a
        // number of the last row, which would otherwise pass unnoticed.
        return Err(err(
            last_ln,
            "truncated: no closing @@ after the last frame".into(),
        ));
    }
    let mask: Vec<bool> = mask.into_iter().map(|m| m.unwrap_or(true)).collect();
    let mut rec = Recording::from_sparse(rows, cols, frames, mask)?;
    rec.pitch_mm = match (dx, dy) {
        (Some(x), Some(y)) => Some([x, y]),
        (Some(x), None) => Some([x, x]),
        (None, Some(y)) => Some([y, y]),
        _ => None,
    };
    rec.sensel_area_mm2 = area;
    rec.dt_s = dt;
    rec.units = stated_units(&units);
    rec.noise_threshold = noise;
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
