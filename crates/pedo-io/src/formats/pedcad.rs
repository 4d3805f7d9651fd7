//! The INI-like "pedcad import file" written by Zebris FDM (`.apd`) and by RSscan/Materialise
//! footscan: `[Section]` headers, `Key=Value` lines, then grids of tab-separated values.
//!
//! - `[Technical]` holds `SensCountX` (rows of every grid), `SensCountY` (values per row),
//!   `LDistX`/`LDistY` (sensor spacing along rows / columns, in `UnitDistance`), and in footscan
//!   exports `MinIdx`, `MaxIdx` (the frame numbers) and `TimeDiff` (time between frames, in
//!   `UnitTime`);
//! - `[General]` holds `UnitDistance`, `UnitPressure`, `UnitTime` and `Source` (`<<zebris>>`);
//! - `[Data]` is the peak-pressure image, `[Data<k>]` frame `k` (footscan); `-1` marks a sensor
//!   outside the recorded window. A sensor that is `-1` in every grid is "no sensor"; `-1` in some
//!   frames only is an unloaded sensor (0).
//!
//! A file with `[Data<k>]` frames reads as those frames; a peak-only file (Zebris `.apd`) as one
//! frame. A streamed run reads it twice: first without holding a frame, then handing each frame
//! on as its grid ends (`Keep::Handed`).

use super::asf::{trunc, Keep};
use super::parse_num;
use crate::error::{IoError, Result};
use crate::recording::stated_units;
use crate::recording::{Format, NegativeValues, Recording, SparseFrames};

/// One `[Data]` or `[Data<k>]` grid as read.
struct Grid {
    /// `None` for the peak image `[Data]`, `Some(k)` for `[Data<k>]`.
    index: Option<i64>,
    header_line: usize,
    values: Vec<f32>,
    rows_read: usize,
}

#[derive(Default)]
struct Header {
    rows: Option<usize>,
    cols: Option<usize>,
    dist_x: Option<f64>,
    dist_y: Option<f64>,
    unit_distance: Option<String>,
    unit_pressure: Option<String>,
    unit_time: Option<String>,
    time_diff: Option<f64>,
    min_idx: Option<i64>,
    max_idx: Option<i64>,
    source: String,
}

fn mm_per(unit: Option<&str>) -> Option<f64> {
    match unit.map(|u| u.trim().to_ascii_lowercase()).as_deref() {
        None | Some("mm") => Some(1.0),
        Some("cm") => Some(10.0),
        Some("m") => Some(1000.0),
        Some("in") | Some("inch") => Some(25.4),
        _ => None,
    }
}

fn s_per(unit: Option<&str>) -> Option<f64> {
    match unit.map(|u| u.trim().to_ascii_lowercase()).as_deref() {
        None | Some("ms") => Some(1e-3),
        Some("s") | Some("sec") => Some(1.0),
        Some("us") | Some("µs") => Some(1e-6),
        _ => None,
    }
}

/// `[Data]` → `Some(None)`, `[Data12]` → `Some(Some(12))`, other sections → `None`.
fn data_section(name: &str) -> Option<Option<i64>> {
    let rest = name.strip_prefix("Data")?;
    if rest.is_empty() {
        return Some(None);
    }
    rest.parse::<i64>().ok().map(Some)
}

/// Parses a Zebris `.apd` or footscan export held in memory; `name` appears in error messages.
pub fn parse_pedcad(bytes: &[u8], name: &str) -> Result<Recording> {
    let lines = super::stream::bounded(bytes, false, super::stream::Stretch::Line);
    super::stream::parse_lines(lines, name, |l| read_pedcad(l, name))
}

/// Parses a Zebris `.apd` or footscan export from its lines (see [`super::stream::Lines`]).
pub(crate) fn read_pedcad(
    lines: impl Iterator<Item = (usize, String)>,
    name: &str,
) -> Result<Recording> {
    read_pedcad_keeping(lines, name, &mut Keep::All)
}

/// [`read_pedcad`], each frame kept or handed on as `keep` says (handed: its values are not
/// held once its grid has ended; the recording's frames read as 0).
pub(crate) fn read_pedcad_keeping(
    lines: impl Iterator<Item = (usize, String)>,
    name: &str,
    keep: &mut Keep<'_>,
) -> Result<Recording> {
    let err = |line: usize, msg: String| IoError::parse(name, line, msg);
    let mut h = Header::default();
    let mut grids: Vec<Grid> = Vec::new();
    let mut handed = Handed::default();
    let mut in_data = false;
    let mut last_ln = 0;
    let mut lines = lines.peekable();
    while let Some((ln, line)) = lines.next() {
        last_ln = ln;
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(sec) = t.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            if let Some(g) = grids.last_mut() {
                check_complete(g, &h, name)?;
                handed.settle(g, keep)?;
            }
            in_data = false;
            if let Some(index) = data_section(sec.trim()) {
                let (Some(rows), Some(cols)) = (h.rows, h.cols) else {
                    return Err(err(
                        ln,
                        "a [Data] section before SensCountX and SensCountY".into(),
                    ));
                };
                let per = crate::limits::frame_sensors("SensCountX x SensCountY", rows, cols)
                    .map_err(|m| err(ln, m))?;
                crate::limits::frame_count(grids.len() + 1, per).map_err(|m| err(ln, m))?;
                // A grid grows row by row as the file holds it, so a header claiming a huge
                // size allocates nothing it does not read.
                grids.push(Grid {
                    index,
                    header_line: ln,
                    values: Vec::new(),
                    rows_read: 0,
                });
                in_data = true;
            }
            continue;
        }
        if in_data {
            let g = grids.last_mut().expect("a data section is open");
            let (rows, cols) = (h.rows.unwrap_or(0), h.cols.unwrap_or(0));
            if g.rows_read == rows {
                return Err(err(
                    ln,
                    format!(
                        "more than SensCountX = {rows} rows in the section opened at line {}",
                        g.header_line
                    ),
                ));
            }
            let mut k = 0usize;
            for tok in t
                .split(['\t', ';'])
                .map(str::trim)
                .filter(|s| !s.is_empty())
            {
                if k == cols {
                    return Err(err(ln, format!("more than SensCountY = {cols} values")));
                }
                let v = parse_num(tok).ok_or_else(|| {
                    err(
                        ln,
                        format!("value {} is not a number: {:?}", k + 1, trunc(tok)),
                    )
                })?;
                g.values.push(v as f32);
                k += 1;
            }
            if k != cols {
                if lines.peek().is_none() {
                    // The file ends inside this row: reported as a truncated section.
                    g.values.truncate(g.values.len() - k);
                    break;
                }
                return Err(err(ln, format!("{k} values, expected SensCountY = {cols}")));
            }
            g.rows_read += 1;
            continue;
        }
        let Some((key, val)) = t.split_once('=') else {
            return Err(err(
                ln,
                format!("expected `Key=Value` or `[Section]`, found {:?}", trunc(t)),
            ));
        };
        read_key(&mut h, key.trim(), val.trim()).map_err(|what| err(ln, what))?;
    }
    // A file cut inside its last frame: that frame is dropped, so that the frame count check
    // names the frames found and the frames the header states.
    if let Some(g) = grids.last()
        && g.index.is_some()
        && h.max_idx.is_some()
        && check_complete(g, &h, name).is_err()
    {
        grids.pop();
    }
    if let Some(g) = grids.last_mut() {
        check_complete(g, &h, name)?;
        handed.settle(g, keep)?;
    }
    build(h, grids, name, last_ln, keep, handed)
}

/// What the frames handed on leave behind: the sensors they show, their values below 0, the
/// first value that is not finite (refused as the whole read refuses it) and a frame of zeros
/// each.
#[derive(Default)]
struct Handed {
    mask: Vec<bool>,
    negatives: NegativeValues,
    not_finite: Option<(usize, usize, f32)>,
    frames: Option<SparseFrames>,
}

impl Handed {
    /// Hands a frame grid that has ended on, unless `keep` holds it, and lets go of its values.
    fn settle(&mut self, g: &mut Grid, keep: &mut Keep<'_>) -> Result<()> {
        let Keep::Handed(hand) = keep else {
            return Ok(());
        };
        if g.index.is_none() {
            return Ok(());
        }
        let values = std::mem::take(&mut g.values);
        let shown: Vec<bool> = values.iter().map(|&v| v != -1.0).collect();
        let frame: Vec<f32> = (values.into_iter())
            .map(|v| if v == -1.0 { 0.0 } else { v })
            .collect();
        self.push(&frame, &shown);
        match hand {
            Some(hand) => hand(&frame),
            None => Ok(()),
        }
    }

    /// The recording of the frames handed on, without their values; a peak-only file's one
    /// frame (`first`, the peak image) handed on now. A value that is not finite at a sensor is
    /// refused with [`Recording::new`]'s words.
    fn recording(
        mut self,
        first: &Grid,
        keep: &mut Keep<'_>,
        rows: usize,
        cols: usize,
        mut mask: Vec<bool>,
    ) -> Result<Recording> {
        if self.frames.is_none() {
            let mut peak = Grid {
                index: Some(0),
                header_line: first.header_line,
                values: first.values.clone(),
                rows_read: first.rows_read,
            };
            self.settle(&mut peak, keep)?;
        }
        for (m, &s) in mask.iter_mut().zip(&self.mask) {
            *m |= s;
        }
        if let Some((t, i, v)) = self.not_finite.filter(|&(_, i, _)| mask[i]) {
            return Err(IoError::invalid(format!(
                "frame {t}, row {}, column {} is not finite ({v})",
                i / cols,
                i % cols
            )));
        }
        let frames = self.frames.expect("a frame was handed on");
        let mut rec = Recording::from_sparse(rows, cols, frames, mask)?;
        rec.set_file_negatives(self.negatives);
        Ok(rec)
    }

    /// Counts one frame handed on (`frame`, its -1 read as 0; `shown`: where it held a value).
    fn push(&mut self, frame: &[f32], shown: &[bool]) {
        let frames = self
            .frames
            .get_or_insert_with(|| SparseFrames::new(frame.len()));
        if self.mask.is_empty() {
            self.mask = vec![false; frame.len()];
        }
        for (m, &s) in self.mask.iter_mut().zip(shown) {
            *m |= s;
        }
        for (i, &v) in frame.iter().enumerate() {
            self.negatives.add(v);
            if !v.is_finite() && self.not_finite.is_none() {
                self.not_finite = Some((frames.n_frames(), i, v));
            }
        }
        frames.push_empty();
    }
}

fn read_key(h: &mut Header, key: &str, val: &str) -> std::result::Result<(), String> {
    let bad = |what: &str| format!("cannot read {what} from {:?}", trunc(val));
    let count = |v: &str| v.parse::<usize>().ok().filter(|&n| n > 0 && n <= 100_000);
    let positive = |v: &str| parse_num(v).filter(|&x| x > 0.0);
    match key {
        "SensCountX" => h.rows = Some(count(val).ok_or_else(|| bad(key))?),
        "SensCountY" => h.cols = Some(count(val).ok_or_else(|| bad(key))?),
        "LDistX" => h.dist_x = Some(positive(val).ok_or_else(|| bad(key))?),
        "LDistY" => h.dist_y = Some(positive(val).ok_or_else(|| bad(key))?),
        "TimeDiff" => h.time_diff = Some(positive(val).ok_or_else(|| bad(key))?),
        "MinIdx" => h.min_idx = Some(val.parse().map_err(|_| bad(key))?),
        "MaxIdx" => h.max_idx = Some(val.parse().map_err(|_| bad(key))?),
        "UnitDistance" => h.unit_distance = Some(val.to_string()),
        "UnitPressure" => h.unit_pressure = Some(val.to_string()),
        "UnitTime" => h.unit_time = Some(val.to_string()),
        "Source" => h.source = val.to_string(),
        _ => {}
    }
    Ok(())
}

fn check_complete(g: &Grid, h: &Header, name: &str) -> Result<()> {
    let rows = h.rows.unwrap_or(0);
    if g.rows_read != rows {
        return Err(IoError::parse(
            name,
            g.header_line,
            format!(
                "truncated: section has {} of SensCountX = {rows} rows",
                g.rows_read
            ),
        ));
    }
    Ok(())
}

fn build(
    h: Header,
    grids: Vec<Grid>,
    name: &str,
    last_ln: usize,
    keep: &mut Keep<'_>,
    handed: Handed,
) -> Result<Recording> {
    let err = |line: usize, msg: String| IoError::parse(name, line, msg);
    let (rows, cols) = match (h.rows, h.cols) {
        (Some(r), Some(c)) => (r, c),
        _ => return Err(IoError::format(name, "no SensCountX / SensCountY")),
    };
    let peak = grids.iter().find(|g| g.index.is_none());
    let mut frames: Vec<&Grid> = grids.iter().filter(|g| g.index.is_some()).collect();
    let expected = match (h.min_idx, h.max_idx) {
        (Some(a), Some(b)) if b >= a => Some((b - a + 1) as u64),
        (Some(a), Some(b)) => {
            return Err(err(last_ln, format!("MaxIdx {b} before MinIdx {a}")));
        }
        _ => None,
    };
    if let Some(e) = expected {
        if (frames.len() as u64) < e {
            return Err(err(
                last_ln,
                format!(
                    "truncated: the file ends after {} frames, its header (MinIdx..MaxIdx) states {e}",
                    frames.len()
                ),
            ));
        }
        if frames.len() as u64 > e {
            return Err(err(
                last_ln,
                format!(
                    "{} frames, more than the {e} its header (MinIdx..MaxIdx) states",
                    frames.len()
                ),
            ));
        }
    }
    for w in frames.windows(2) {
        if w[1].index <= w[0].index {
            return Err(err(
                w[1].header_line,
                format!(
                    "frame [Data{}] after [Data{}]: frames out of order",
                    w[1].index.unwrap_or(0),
                    w[0].index.unwrap_or(0)
                ),
            ));
        }
    }
    if frames.is_empty() {
        frames.extend(peak);
    }
    if frames.is_empty() {
        return Err(IoError::format(name, "no [Data] section"));
    }
    let per = rows * cols;
    // A sensor exists when any grid (frames or peak) holds something other than -1 there (the
    // frames handed on hold no values: they left what they showed in `handed`).
    let mut mask = vec![false; per];
    for g in frames.iter().copied().chain(peak) {
        for (m, &v) in mask.iter_mut().zip(&g.values) {
            *m |= v != -1.0;
        }
    }
    let mut rec = match keep {
        Keep::All => {
            let mut data = Vec::with_capacity(frames.len() * per);
            for g in &frames {
                data.extend(g.values.iter().map(|&v| if v == -1.0 { 0.0 } else { v }));
            }
            Recording::new(frames.len(), rows, cols, data, mask)?
        }
        Keep::Handed(_) => handed.recording(frames[0], keep, rows, cols, mask)?,
    };
    let mm = mm_per(h.unit_distance.as_deref()).ok_or_else(|| {
        IoError::format(
            name,
            format!(
                "unknown UnitDistance {:?}",
                h.unit_distance.unwrap_or_default()
            ),
        )
    })?;
    // LDistX runs along the rows (x of the plate = row index), LDistY along a row.
    rec.pitch_mm = match (h.dist_y, h.dist_x) {
        (Some(dx), Some(dy)) => Some([dx * mm, dy * mm]),
        (Some(d), None) | (None, Some(d)) => Some([d * mm, d * mm]),
        _ => None,
    };
    if (rec.n_frames() > 1 || h.min_idx.is_some())
        && let Some(td) = h.time_diff
    {
        let s = s_per(h.unit_time.as_deref()).ok_or_else(|| {
            IoError::format(
                name,
                format!(
                    "unknown UnitTime {:?}",
                    h.unit_time.clone().unwrap_or_default()
                ),
            )
        })?;
        rec.dt_s = Some(td * s);
    }
    rec.units = stated_units(h.unit_pressure.as_deref().unwrap_or_default());
    let zebris = h.source.to_ascii_lowercase().contains("zebris");
    rec.format = Some(
        if zebris || (h.min_idx.is_none() && h.time_diff.is_none()) {
            Format::Zebris
        } else {
            Format::Footscan
        },
    );
    Ok(rec)
}
