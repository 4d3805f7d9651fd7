//! novel pedar ASCII export (`.asc`/`.txt`) and the sensor layouts that turn it into images.
//!
//! The export is tab-separated text: a header (`sensor type:`, `total time [secs]:`,
//! `time per frame [secs]:`, `scanning rate [Hz]:`, `pressure values in kPa`, and a `mask
//! definition` naming the exported sensors of the `left insole:` and `right insole:`), then a
//! `time[secs]` column header and one line per frame: the time, the left insole's sensors, the
//! right insole's sensors (99 each for a full insole).
//!
//! Pedar sensors are not a grid. A [`PedarLayout`] gives each sensor's outline (a quadrilateral);
//! the outlines are rasterised on a grid of half a typical sensor's width and length, each cell
//! taking the value of the sensor that covers its centre and cells outside every sensor being
//! "no sensor". Both insoles share one image, left insole on the left, with two empty columns
//! between them, so they always come out as separate objects; [`parse_pedar_insoles`] gives
//! each insole as a recording of its own. Row 0 is the toe end.

use super::asf::{trunc, Keep};
use super::{parse_num, read_bytes};
use crate::error::{IoError, Result};
use crate::recording::stated_units;
use crate::recording::{FootColumns, Format, NegativeValues, Recording, SparseFrames};
use crate::regions::Side;
use std::path::Path;
use std::sync::OnceLock;

/// Which insole a sensor belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Insole {
    /// The left foot's insole (`left insole:` in the export).
    Left,
    /// The right foot's insole (`right insole:` in the export).
    Right,
}

/// One sensor's outline: `corners` in order around it, in layout units.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorOutline {
    /// The insole the sensor is on.
    pub insole: Insole,
    /// pedar's 1-based sensor number (1 at the heel, 99 at the toes for a full insole).
    pub sensor: usize,
    /// The quadrilateral's four corners `[x, y]`, in order around it, in layout units.
    pub corners: [[f64; 2]; 4],
}

/// Where every sensor of both insoles lies.
#[derive(Debug, Clone, PartialEq)]
pub struct PedarLayout {
    /// Every sensor's outline, both insoles, in the layout file's order.
    pub sensors: Vec<SensorOutline>,
    /// Millimetres per layout unit, when the layout file says (`# unit: mm`); `None` for the
    /// normalised coordinates of the bundled layout (the recording then has no pitch).
    pub mm_per_unit: Option<f64>,
}

/// The bundled layout: the common pedar insole as tabulated by the R package pressuRe
/// (`layouts/pedar-pressuRe.csv`, MIT; source in the file's header).
pub const BUNDLED_LAYOUT: &str = include_str!("../../layouts/pedar-pressuRe.csv");

impl PedarLayout {
    /// The bundled layout (see [`BUNDLED_LAYOUT`]).
    pub fn bundled() -> &'static PedarLayout {
        static L: OnceLock<PedarLayout> = OnceLock::new();
        // The bundled table is part of the crate and covered by a test.
        L.get_or_init(|| {
            PedarLayout::parse(BUNDLED_LAYOUT, "bundled pedar layout").expect("valid table")
        })
    }

    /// Reads a layout file (see [`PedarLayout::parse`]).
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = read_bytes(path)?;
        Self::parse(
            &String::from_utf8_lossy(&bytes),
            &path.display().to_string(),
        )
    }

    /// Parses a layout table: comma-separated lines `insole,sensor,x1,y1,x2,y2,x3,y3,x4,y4`
    /// (`insole` is `L`/`R` or `left`/`right`; the corners go around the sensor; y grows from
    /// heel to toes); an optional header line starting with `insole`; `#` comment lines, of
    /// which `# unit: mm` (or `cm`) makes the coordinates millimetres (centimetres) so that the
    /// recording gets a pitch, and `# unit: normalised` says they are not lengths (no pitch).
    ///
    /// # Errors
    ///
    /// [`IoError::Parse`] naming the line for a malformed line, and for a `# unit:` line naming
    /// another unit or contradicting an earlier one (a misspelt unit is not taken as no unit).
    pub fn parse(text: &str, name: &str) -> Result<Self> {
        let err = |line: usize, msg: String| IoError::parse(name, line, msg);
        let mut sensors: Vec<SensorOutline> = Vec::new();
        let mut mm_per_unit = None;
        // The first `# unit:` line, its line number and the unit it names.
        let mut unit_line: Option<(usize, String)> = None;
        for (i, line) in text.lines().enumerate() {
            let (ln, t) = (i + 1, line.trim());
            if let Some(c) = t.strip_prefix('#') {
                if let Some(u) = c.trim().strip_prefix("unit:") {
                    let unit = u.trim().to_ascii_lowercase();
                    let mm = match unit.as_str() {
                        "mm" => Some(1.0),
                        "cm" => Some(10.0),
                        "normalised" | "normalized" => None,
                        _ => {
                            return Err(err(
                                ln,
                                format!(
                                    "unknown unit {:?}; expected mm, cm or normalised (no pitch)",
                                    trunc(u.trim())
                                ),
                            ));
                        }
                    };
                    if let Some((first, named)) = &unit_line {
                        if mm != mm_per_unit {
                            return Err(err(
                                ln,
                                format!(
                                    "unit {unit:?} contradicts the unit {named:?} of line {first}"
                                ),
                            ));
                        }
                    } else {
                        unit_line = Some((ln, unit));
                        mm_per_unit = mm;
                    }
                }
                continue;
            }
            if t.is_empty() || t.to_ascii_lowercase().starts_with("insole") {
                continue;
            }
            let f: Vec<&str> = t.split(',').map(str::trim).collect();
            if f.len() != 10 {
                return Err(err(
                    ln,
                    format!(
                        "{} fields, expected 10: insole,sensor,x1,y1,...,y4",
                        f.len()
                    ),
                ));
            }
            let insole = match f[0].to_ascii_lowercase().as_str() {
                "l" | "left" => Insole::Left,
                "r" | "right" => Insole::Right,
                o => {
                    return Err(err(
                        ln,
                        format!("insole must be L or R, got {:?}", trunc(o)),
                    ));
                }
            };
            let sensor = f[1]
                .parse::<usize>()
                .ok()
                .filter(|&s| (1..=1024).contains(&s))
                .ok_or_else(|| err(ln, format!("bad sensor number {:?}", trunc(f[1]))))?;
            let mut corners = [[0.0; 2]; 4];
            for (k, tok) in f[2..].iter().enumerate() {
                corners[k / 2][k % 2] = parse_num(tok).ok_or_else(|| {
                    err(ln, format!("corner value {:?} is not a number", trunc(tok)))
                })?;
            }
            if sensors
                .iter()
                .any(|s| s.insole == insole && s.sensor == sensor)
            {
                return Err(err(
                    ln,
                    format!("sensor {sensor} of the {insole:?} insole listed twice"),
                ));
            }
            sensors.push(SensorOutline {
                insole,
                sensor,
                corners,
            });
        }
        if sensors.is_empty() {
            return Err(IoError::format(name, "no sensors in the layout"));
        }
        Ok(Self {
            sensors,
            mm_per_unit,
        })
    }

    fn find(&self, insole: Insole, sensor: usize) -> Option<&SensorOutline> {
        self.sensors
            .iter()
            .find(|s| s.insole == insole && s.sensor == sensor)
    }
}

/// A pedar export as read: times and per frame the values of the listed sensors.
#[derive(Debug, Clone, PartialEq)]
pub struct PedarData {
    /// `(insole, sensor)` of each value column, in file order.
    pub columns: Vec<(Insole, usize)>,
    /// `n_frames × columns.len()` values.
    pub values: Vec<f32>,
    /// Number of frames (data lines).
    pub n_frames: usize,
    /// Time between frames in seconds (from `time per frame` or `scanning rate`).
    pub dt_s: Option<f64>,
    /// Pressure units from the `pressure values in …` line (`"kPa"`); empty when absent.
    pub units: String,
    /// The `sensor type:` line (insole model and size).
    pub sensor_type: String,
}

fn sensor_list(v: &str) -> Option<Vec<usize>> {
    v.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>().ok().filter(|&n| (1..=1024).contains(&n)))
        .collect()
}

/// The value after `key` on a header line (`total time [secs]:  15.050`).
fn after_key(line: &str, key: &str) -> Option<f64> {
    let i = line.find(key)? + key.len();
    parse_num(line[i..].split_whitespace().next()?)
}

/// What the header lines before the `time[secs]` column header say.
#[derive(Default)]
struct PedarHeader {
    total_s: Option<f64>,
    dt_s: Option<f64>,
    rate_hz: Option<f64>,
    left: Option<Vec<usize>>,
    right: Option<Vec<usize>>,
    units: String,
    sensor_type: String,
}

impl PedarHeader {
    /// Reads the header up to the column header line, which it returns with its number.
    fn read(
        lines: &mut impl Iterator<Item = (usize, String)>,
        name: &str,
    ) -> Result<(Self, (usize, String))> {
        let mut h = PedarHeader::default();
        for (ln, line) in lines.by_ref() {
            let t = line.trim();
            let lower = t.to_ascii_lowercase();
            if lower.starts_with("time[") || lower.starts_with("time [") {
                return Ok((h, (ln, line)));
            }
            h.total_s = h.total_s.or(after_key(t, "total time [secs]:"));
            h.dt_s = h.dt_s.or(after_key(t, "time per frame [secs]:"));
            h.rate_hz = h.rate_hz.or(after_key(t, "scanning rate [Hz]:"));
            if let Some(v) = t.strip_prefix("sensor type:") {
                h.sensor_type = v.trim().to_string();
            }
            if let Some(v) = t.strip_prefix("pressure values in") {
                h.units = v.trim().to_string();
            }
            for (side, key, list) in [
                ("left", "left insole:", &mut h.left),
                ("right", "right insole:", &mut h.right),
            ] {
                if let Some(v) = t.strip_prefix(key) {
                    let bad = || IoError::parse(name, ln, format!("bad {side} insole sensor list"));
                    *list = Some(sensor_list(v).ok_or_else(bad)?);
                }
            }
        }
        Err(IoError::format(
            name,
            "no `time[secs]` column header: not a pedar ASCII export or truncated",
        ))
    }

    /// The sensor of each value column, from the insoles' lists (all 99 of each insole when
    /// neither is given and the column header has 198), checked against the column header
    /// `header` at line `hl`.
    fn columns(&mut self, hl: usize, header: &str, name: &str) -> Result<Vec<(Insole, usize)>> {
        let err = |msg: String| IoError::parse(name, hl, msg);
        let n_cols = header.split_whitespace().count().saturating_sub(1);
        let all: Vec<usize> = (1..=99).collect();
        let (left, right) = match (self.left.take(), self.right.take()) {
            (Some(l), Some(r)) => (l, r),
            (None, None) if n_cols == 198 => (all.clone(), all),
            _ => {
                return Err(err(format!(
                    "{n_cols} sensor columns and no `left insole:` / `right insole:` lists"
                )));
            }
        };
        let columns: Vec<(Insole, usize)> = left
            .iter()
            .map(|&s| (Insole::Left, s))
            .chain(right.iter().map(|&s| (Insole::Right, s)))
            .collect();
        if n_cols != columns.len() {
            return Err(err(format!(
                "{n_cols} sensor columns, the mask definition lists {}",
                columns.len()
            )));
        }
        Ok(columns)
    }

    /// Time between frames: `time per frame`, else 1 / `scanning rate`.
    fn dt_s(&self) -> Option<f64> {
        self.dt_s
            .or(self.rate_hz.filter(|&r| r > 0.0).map(|r| 1.0 / r))
            .filter(|&d| d > 0.0)
    }

    /// An error unless the file held `n_frames` frames, at least one, as many as its header
    /// states (when it does).
    fn check_frames(&self, n_frames: usize, name: &str) -> Result<()> {
        if let Some(e) = self.stated_frames()
            && n_frames as u64 != e
        {
            let what = if (n_frames as u64) < e {
                "truncated"
            } else {
                "too many frames"
            };
            return Err(IoError::format(
                name,
                format!(
                    "{what}: the file ends after {n_frames} frames, its header (total time / time \
                     per frame) states {e}"
                ),
            ));
        }
        if n_frames == 0 {
            return Err(IoError::format(name, "no frames"));
        }
        Ok(())
    }

    /// The frame count `total time / time per frame` states.
    fn stated_frames(&self) -> Option<u64> {
        match (self.total_s, self.dt_s()) {
            (Some(t), Some(d)) if t >= 0.0 && t / d < 1e12 => Some((t / d).round() as u64),
            _ => None,
        }
    }
}

/// Reads the data lines (a time, then one value per column), handing each frame's values to
/// `frame` with its line and its number (which `frame` holds to the reading's limits) as it is
/// read; a last line cut short is left out. Returns the number of frames.
fn read_pedar_rows(
    lines: impl Iterator<Item = (usize, String)>,
    n_columns: usize,
    name: &str,
    mut frame: impl FnMut(usize, usize, &[f32]) -> Result<()>,
) -> Result<usize> {
    let mut row: Vec<f32> = Vec::with_capacity(n_columns);
    let mut n_frames = 0usize;
    let mut lines = lines.peekable();
    while let Some((ln, line)) = lines.next() {
        let err = |msg: String| IoError::parse(name, ln, msg);
        let mut f = line.split_whitespace();
        let Some(time) = f.next() else { continue };
        parse_num(time).ok_or_else(|| err(format!("time {:?} is not a number", trunc(time))))?;
        row.clear();
        for tok in f {
            if row.len() == n_columns {
                return Err(err(format!("more than {n_columns} sensor values")));
            }
            let k = row.len();
            let v = parse_num(tok)
                .ok_or_else(|| err(format!("value {} is not a number: {:?}", k + 1, trunc(tok))))?;
            row.push(v as f32);
        }
        if row.len() != n_columns {
            if lines.peek().is_none() {
                break; // cut inside the last line
            }
            return Err(err(format!(
                "{} sensor values, expected {n_columns}",
                row.len()
            )));
        }
        frame(ln, n_frames, &row)?;
        n_frames += 1;
    }
    Ok(n_frames)
}

/// Parses the export itself (no layout needed).
pub fn parse_pedar_data(bytes: &[u8], name: &str) -> Result<PedarData> {
    let lines = super::stream::bounded(bytes, false, super::stream::Stretch::Line);
    super::stream::parse_lines(lines, name, |l| read_pedar_data(l, name))
}

/// [`parse_pedar_data`] from the export's lines (see [`super::stream::Lines`]).
fn read_pedar_data(
    mut lines: impl Iterator<Item = (usize, String)>,
    name: &str,
) -> Result<PedarData> {
    let (mut header, (hl, column_header)) = PedarHeader::read(&mut lines, name)?;
    let columns = header.columns(hl, &column_header, name)?;
    let mut values = Vec::new();
    let n_frames = read_pedar_rows(lines, columns.len(), name, |ln, k, row| {
        crate::limits::frame_count(k + 1, 1).map_err(|m| IoError::parse(name, ln, m))?;
        values.extend_from_slice(row);
        Ok(())
    })?;
    header.check_frames(n_frames, name)?;
    Ok(PedarData {
        columns,
        values,
        n_frames,
        dt_s: header.dt_s(),
        units: header.units,
        sensor_type: header.sensor_type,
    })
}

/// A layout's sensors rasterised: the image size and, per sensor, the cells it covers.
struct Raster {
    rows: usize,
    cols: usize,
    cells: Vec<Vec<usize>>,
    pitch: Option<[f64; 2]>,
    /// The columns of each group, in order.
    group_columns: Vec<std::ops::Range<usize>>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn inside(p: [f64; 2], q: &[[f64; 2]; 4]) -> bool {
    let mut c = false;
    for i in 0..4 {
        let (a, b) = (q[i], q[(i + 1) % 4]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
        {
            c = !c;
        }
    }
    c
}

/// Rasterises `groups` of outlines side by side (two empty columns between groups) with one
/// cell size and one y range.
fn rasterise(groups: &[Vec<&SensorOutline>], mm: Option<f64>, name: &str) -> Result<Raster> {
    let all: Vec<&&SensorOutline> = groups.iter().flatten().collect();
    let span = |s: &SensorOutline, a: usize| {
        let v = s.corners.map(|c| c[a]);
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    };
    let cw = median(
        all.iter()
            .map(|s| {
                let (a, b) = span(s, 0);
                b - a
            })
            .collect(),
    ) / 2.0;
    let ch = median(
        all.iter()
            .map(|s| {
                let (a, b) = span(s, 1);
                b - a
            })
            .collect(),
    ) / 2.0;
    if !(cw > 0.0 && ch > 0.0) {
        return Err(IoError::format(name, "layout sensors have no extent"));
    }
    let y_lo = all
        .iter()
        .map(|s| span(s, 1).0)
        .fold(f64::INFINITY, f64::min);
    let y_hi = all
        .iter()
        .map(|s| span(s, 1).1)
        .fold(f64::NEG_INFINITY, f64::max);
    let rows = ((y_hi - y_lo) / ch).ceil().max(1.0);
    let mut x_ranges = Vec::new();
    let mut cols = 0.0f64;
    for g in groups {
        let lo = g.iter().map(|s| span(s, 0).0).fold(f64::INFINITY, f64::min);
        let hi = g
            .iter()
            .map(|s| span(s, 0).1)
            .fold(f64::NEG_INFINITY, f64::max);
        let n = ((hi - lo) / cw).ceil().max(1.0);
        x_ranges.push((lo, cols));
        cols += n + 2.0;
    }
    cols -= 2.0;
    // Each frame becomes rows × cols values: a layout needing more than 200 000 cells (a
    // thousand per sensor) is not a sensor layout.
    if rows * cols > 2e5 {
        return Err(IoError::format(
            name,
            "layout too fine: more than 200 000 cells",
        ));
    }
    let (rows, cols) = (rows as usize, cols as usize);
    let mut owner = vec![usize::MAX; rows * cols];
    let mut cells = Vec::with_capacity(all.len());
    let mut id = 0;
    for (g, &(x_lo, c0)) in groups.iter().zip(&x_ranges) {
        for s in g {
            let (xa, xb) = span(s, 0);
            let (ya, yb) = span(s, 1);
            let col = |x: f64| c0 + (x - x_lo) / cw;
            let row = |y: f64| (y_hi - y) / ch;
            let mut mine = Vec::new();
            let (r0, r1) = (
                row(yb).floor().max(0.0) as usize,
                (row(ya).ceil() as usize).min(rows),
            );
            let (k0, k1) = (
                col(xa).floor().max(0.0) as usize,
                (col(xb).ceil() as usize).min(cols),
            );
            for r in r0..r1 {
                for c in k0..k1 {
                    let p = [
                        x_lo + (c as f64 - c0 + 0.5) * cw,
                        y_hi - (r as f64 + 0.5) * ch,
                    ];
                    if owner[r * cols + c] == usize::MAX && inside(p, &s.corners) {
                        owner[r * cols + c] = id;
                        mine.push(r * cols + c);
                    }
                }
            }
            if mine.is_empty() {
                // A sensor smaller than a cell: the cell under its centre.
                let cx = s.corners.iter().map(|c| c[0]).sum::<f64>() / 4.0;
                let cy = s.corners.iter().map(|c| c[1]).sum::<f64>() / 4.0;
                let (r, c) = (
                    (row(cy) as usize).min(rows - 1),
                    (col(cx) as usize).min(cols - 1),
                );
                if owner[r * cols + c] != usize::MAX {
                    return Err(IoError::format(
                        name,
                        format!(
                            "layout sensor {} ({:?}) overlaps another sensor entirely",
                            s.sensor, s.insole
                        ),
                    ));
                }
                owner[r * cols + c] = id;
                mine.push(r * cols + c);
            }
            cells.push(mine);
            id += 1;
        }
    }
    let pitch = mm.map(|m| [cw * m, ch * m]);
    // A group's cells never reach past the columns its outlines span (`k1` is clamped to them).
    let group_columns = (groups.iter().zip(&x_ranges))
        .map(|(g, &(x_lo, c0))| {
            let hi = g.iter().map(|s| span(s, 0).1).fold(x_lo, f64::max);
            let n = ((hi - x_lo) / cw).ceil().max(1.0) as usize;
            c0 as usize..(c0 as usize + n).min(cols)
        })
        .collect();
    Ok(Raster {
        rows,
        cols,
        cells,
        pitch,
        group_columns,
    })
}

/// The columns of an export placed on a layout's raster, one group of insoles side by side:
/// the image's size and mask, and which column's value each sensor's cells take.
struct Placement {
    raster: Raster,
    /// Per sensor of the raster (in its order): the value column it takes.
    src: Vec<usize>,
    mask: Vec<bool>,
    insoles: Vec<Insole>,
}

impl Placement {
    /// The `insoles` of an export of these `columns` on `layout`.
    fn new(
        columns: &[(Insole, usize)],
        layout: &PedarLayout,
        insoles: &[Insole],
        name: &str,
    ) -> Result<Self> {
        let mut groups: Vec<Vec<&SensorOutline>> = Vec::new();
        let mut src = Vec::new();
        for &side in insoles {
            let mut g = Vec::new();
            for (k, &(ins, sensor)) in columns.iter().enumerate().filter(|(_, c)| c.0 == side) {
                let s = layout.find(ins, sensor).ok_or_else(|| {
                    IoError::format(
                        name,
                        format!("sensor {sensor} of the {ins:?} insole is not in the layout"),
                    )
                })?;
                g.push(s);
                src.push(k);
            }
            if g.is_empty() {
                return Err(IoError::format(
                    name,
                    format!("the export has no {side:?} insole sensors"),
                ));
            }
            groups.push(g);
        }
        let raster = rasterise(&groups, layout.mm_per_unit, name)?;
        let mut mask = vec![false; raster.rows * raster.cols];
        raster.cells.iter().flatten().for_each(|&i| mask[i] = true);
        Ok(Self {
            raster,
            src,
            mask,
            insoles: insoles.to_vec(),
        })
    }

    /// Values per frame of the image.
    fn per(&self) -> usize {
        self.raster.rows * self.raster.cols
    }

    /// Writes the image of one line of the export's values into `frame` (cells outside every
    /// sensor stay as they are: 0).
    fn place(&self, row: &[f32], frame: &mut [f32]) {
        for (cells, &k) in self.raster.cells.iter().zip(&self.src) {
            for &i in cells {
                frame[i] = row[k];
            }
        }
    }

    /// The recording of these `frames` on this image, with the export's time step and units.
    fn recording(self, frames: SparseFrames, dt_s: Option<f64>, units: &str) -> Result<Recording> {
        let r = self.raster;
        let mut rec = Recording::from_sparse(r.rows, r.cols, frames, self.mask)?;
        rec.pitch_mm = r.pitch;
        rec.dt_s = dt_s;
        rec.units = stated_units(units);
        rec.format = Some(Format::Pedar);
        // Each insole is one foot; a single insole alone is as any single sensor.
        if self.insoles.len() > 1 {
            rec.feet = (self.insoles.iter().zip(&r.group_columns))
                .map(|(&side, columns)| FootColumns {
                    side: match side {
                        Insole::Left => Side::Left,
                        Insole::Right => Side::Right,
                    },
                    columns: columns.clone(),
                })
                .collect();
        }
        Ok(rec)
    }
}

/// Places the export's insoles on a layout: one recording per group of insoles.
fn to_recording(
    d: &PedarData,
    layout: &PedarLayout,
    insoles: &[Insole],
    name: &str,
) -> Result<Recording> {
    let placed = Placement::new(&d.columns, layout, insoles, name)?;
    let per = placed.per();
    crate::limits::check_frames(name, d.n_frames, per)?;
    // Frame by frame into sparse frames: a frame of the image takes many cells per sensor.
    let mut frames = SparseFrames::new(per);
    let mut frame = vec![0.0f32; per];
    for row in d.values.chunks_exact(d.columns.len()).take(d.n_frames) {
        placed.place(row, &mut frame);
        frames.push(&frame);
    }
    placed.recording(frames, d.dt_s, &d.units)
}

/// Parses a pedar export onto a layout: both insoles in one image (left insole on the left,
/// two empty columns between), so that each insole is an object of its own.
pub fn parse_pedar(bytes: &[u8], name: &str, layout: &PedarLayout) -> Result<Recording> {
    let lines = super::stream::bounded(bytes, false, super::stream::Stretch::Line);
    super::stream::parse_lines(lines, name, |l| read_pedar(l, name, layout))
}

/// [`parse_pedar`] from the export's lines (see [`super::stream::Lines`]).
pub(crate) fn read_pedar(
    lines: impl Iterator<Item = (usize, String)>,
    name: &str,
    layout: &PedarLayout,
) -> Result<Recording> {
    read_pedar_keeping(lines, name, layout, &mut Keep::All)
}

/// [`read_pedar`], each frame placed on the layout as its line is read and kept or handed on
/// as `keep` says (handed: its values are not held, so that a run reads the export again
/// frame by frame, as it reads a Tekscan file).
pub(crate) fn read_pedar_keeping(
    mut lines: impl Iterator<Item = (usize, String)>,
    name: &str,
    layout: &PedarLayout,
    keep: &mut Keep<'_>,
) -> Result<Recording> {
    let (mut header, (hl, column_header)) = PedarHeader::read(&mut lines, name)?;
    let columns = header.columns(hl, &column_header, name)?;
    let sides: Vec<Insole> = [Insole::Left, Insole::Right]
        .into_iter()
        .filter(|s| columns.iter().any(|c| c.0 == *s))
        .collect();
    let placed = Placement::new(&columns, layout, &sides, name)?;
    let per = placed.per();
    let mut frames = SparseFrames::new(per);
    let mut frame = vec![0.0f32; per];
    let mut negatives = NegativeValues::default();
    let n_frames = read_pedar_rows(lines, columns.len(), name, |ln, k, row| {
        crate::limits::frame_count(k + 1, per).map_err(|m| IoError::parse(name, ln, m))?;
        placed.place(row, &mut frame);
        match keep {
            Keep::All => frames.push(&frame),
            Keep::Handed(hand) => {
                frame.iter().for_each(|&v| negatives.add(v));
                frames.push_empty();
                if let Some(hand) = hand {
                    hand(&frame)?;
                }
            }
        }
        Ok(())
    })?;
    header.check_frames(n_frames, name)?;
    let handed = matches!(keep, Keep::Handed(_));
    let mut rec = placed.recording(frames, header.dt_s(), &header.units)?;
    if handed {
        rec.set_file_negatives(negatives);
    }
    Ok(rec)
}

/// Parses a pedar export into one recording per insole: `(left, right)`.
pub fn parse_pedar_insoles(
    bytes: &[u8],
    name: &str,
    layout: &PedarLayout,
) -> Result<(Recording, Recording)> {
    let d = parse_pedar_data(bytes, name)?;
    Ok((
        to_recording(&d, layout, &[Insole::Left], name)?,
        to_recording(&d, layout, &[Insole::Right], name)?,
    ))
}
