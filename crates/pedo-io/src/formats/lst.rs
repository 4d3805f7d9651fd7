//! novel emed ASCII page export (`.lst`): Latin-1 text, one page per picture separated by form
//! feeds; each page prints a window of rows and columns of the full `Matrix: CxR` plate.

use super::asf::{trunc, Keep};
use super::parse_num;
use crate::error::{IoError, Result};
use crate::recording::{Format, NegativeValues, Recording, SparseFrames};

/// What a `.lst` page prints besides the pressures: the forces the export computed itself.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LstPageForces {
    /// Row forces in N (only on pages whose index line ends with `Force`).
    pub row_forces: Vec<f64>,
    /// Column forces in N (the `Force` line).
    pub column_forces: Vec<f64>,
}

#[derive(Default)]
struct Page {
    first_line: usize,
    part: PagePart,
    matrix: Option<(usize, usize, usize)>, // (cols, rows, line)
    area_cm2: Option<f64>,
    dt_ms: Option<f64>,
    size_cm: Option<(f64, f64)>,
    columns: Vec<usize>,
    has_row_force: bool,
    cells: Vec<(usize, usize, f64, usize)>, // (row, col, value, line) 1-based indices
    forces: LstPageForces,
    saw_force_line: bool,
    has_content: bool,
}

fn after<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.find(key).map(|i| line[i + key.len()..].trim_start())
}

/// The number at the start of `s` (`12.5 ms`, or with a decimal comma `12,5 ms`, as German
/// exports write it; a comma right after the number separates the next field).
fn leading_num(s: &str) -> Option<f64> {
    let end = s
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii_digit() || matches!(c, '.' | ',' | '-' | '+')))
        .map(|(i, _)| i)
        .unwrap_or(s.len());
    parse_num(s[..end].trim_end_matches(','))
}

/// Where a page's reading is: its header, its rows of values, or after its closing `Force`
/// line.
#[derive(Clone, Copy, PartialEq, Default)]
enum PagePart {
    #[default]
    Header,
    Rows,
    Closed,
}

/// A `CxR` pair (`Matrix: 64x32`, `Sensor size: 0.5x0.5`) read with `parse`.
fn pair<T>(tok: &str, parse: impl Fn(&str) -> Option<T>) -> Option<(T, T)> {
    let (a, b) = tok.split_once(['x', 'X'])?;
    Some((parse(a)?, parse(b)?))
}

impl Page {
    /// Reads one header line `t`; returns whether it was the column index line that ends the
    /// header.
    fn header_line(&mut self, ln: usize, t: &str, err: impl Fn(String) -> IoError) -> Result<bool> {
        let first_token = |v: &'_ str| v.split_whitespace().next().unwrap_or("").to_string();
        if let Some(v) = after(t, "Matrix:") {
            let tok = first_token(v);
            let dim = |s: &str| s.parse::<usize>().ok().filter(|&n| n > 0 && n <= 10_000);
            let (c, r) =
                pair(&tok, dim).ok_or_else(|| err(format!("bad Matrix {:?}", trunc(&tok))))?;
            crate::limits::frame_sensors("the Matrix", r, c).map_err(&err)?;
            self.matrix = Some((c, r, ln));
        }
        let positive = |v: Option<f64>| v.filter(|&a| a > 0.0);
        if let Some(v) = after(t, "Sensor area:") {
            self.area_cm2 = Some(
                positive(leading_num(v))
                    .ok_or_else(|| err(format!("bad Sensor area {:?}", trunc(v))))?,
            );
        }
        if let Some(v) = after(t, "Time/picture:") {
            self.dt_ms = Some(
                positive(leading_num(v))
                    .ok_or_else(|| err(format!("bad Time/picture {:?}", trunc(v))))?,
            );
        }
        if let Some(v) = after(t, "Sensor size:") {
            let size = pair(&first_token(v), |s| positive(parse_num(s)));
            self.size_cm =
                Some(size.ok_or_else(|| err(format!("bad Sensor size {:?}", trunc(v))))?);
        }
        // The column index line: integers (tab separated), optionally ending with `Force`.
        let toks: Vec<&str> = t.split(['\t', ' ']).filter(|s| !s.is_empty()).collect();
        let (nums, force) = match toks.split_last() {
            Some((&"Force", rest)) => (rest, true),
            _ => (&toks[..], false),
        };
        if nums.is_empty() || !nums.iter().all(|s| s.bytes().all(|b| b.is_ascii_digit())) {
            return Ok(false);
        }
        let mut cols = Vec::with_capacity(nums.len());
        for s in nums {
            let c = s
                .parse::<usize>()
                .map_err(|_| err("bad column index".into()))?;
            if c == 0 {
                return Err(err("column indices are 1-based".into()));
            }
            cols.push(c);
        }
        self.columns = cols;
        self.has_row_force = force;
        Ok(true)
    }

    /// Reads the closing `Force` line's values (`fields` after the word `Force`).
    fn force_line(&mut self, fields: &[&str], err: impl Fn(String) -> IoError) -> Result<()> {
        let mut vals = fields;
        // With row forces, the Force line may end with the page's total force.
        if self.has_row_force && vals.len() == self.columns.len() + 1 {
            vals = &vals[..self.columns.len()];
        }
        if vals.len() != self.columns.len() {
            return Err(err(format!(
                "Force line has {} values for {} columns",
                vals.len(),
                self.columns.len()
            )));
        }
        for v in vals {
            let f = parse_num(v).ok_or_else(|| err(format!("bad force {:?}", trunc(v))))?;
            self.forces.column_forces.push(f);
        }
        self.saw_force_line = true;
        Ok(())
    }

    /// Reads a row of values (`fields`: the row index, the values, and the row force when the
    /// page prints them) from line `ln`, whose text is `t`.
    fn data_row(
        &mut self,
        ln: usize,
        t: &str,
        fields: &[&str],
        err: impl Fn(String) -> IoError,
    ) -> Result<()> {
        let r = fields
            .first()
            .and_then(|s| s.parse::<usize>().ok())
            .filter(|&r| r > 0)
            .ok_or_else(|| err(format!("expected a row index, found {:?}", trunc(t))))?;
        let want = self.columns.len() + usize::from(self.has_row_force);
        if fields.len() - 1 != want {
            return Err(err(format!(
                "row {r} has {} values, expected {want}",
                fields.len() - 1
            )));
        }
        // A page prints a window of the plate: never more cells than a frame may have.
        let most = crate::limits::current().frame_sensors;
        if self.cells.len() + self.columns.len() > most {
            return Err(err(format!(
                "the page holds more than the {most} sensors a frame may have; {}",
                crate::limits::raise("max_frame_sensors")
            )));
        }
        for (k, v) in fields[1..].iter().enumerate() {
            let x =
                parse_num(v).ok_or_else(|| err(format!("value {:?} is not a number", trunc(v))))?;
            if k < self.columns.len() {
                self.cells.push((r, self.columns[k], x, ln));
            } else {
                self.forces.row_forces.push(x);
            }
        }
        Ok(())
    }

    /// A page whose first line is line `first_line` of the file.
    fn starting_at(first_line: usize) -> Page {
        Page {
            first_line,
            ..Default::default()
        }
    }

    /// Reads the page's next line, line `ln` of the file.
    fn line(&mut self, ln: usize, line: &str, name: &str) -> Result<()> {
        let err = |msg: String| IoError::parse(name, ln, msg);
        let t = line.trim();
        if t.is_empty() {
            return Ok(());
        }
        self.has_content = true;
        match self.part {
            PagePart::Header => {
                if self.header_line(ln, t, err)? {
                    self.part = PagePart::Rows;
                }
            }
            PagePart::Closed => {
                return Err(err(format!(
                    "unexpected text after the Force line: {:?}",
                    trunc(t)
                )));
            }
            PagePart::Rows => {
                let fields: Vec<&str> = line.split('\t').map(str::trim).collect();
                let fields: &[&str] = match fields.split_last() {
                    Some((&"", rest)) => rest,
                    _ => &fields,
                };
                if fields.first() == Some(&"Force") {
                    self.force_line(&fields[1..], err)?;
                    self.part = PagePart::Closed;
                } else {
                    self.data_row(ln, t, fields, err)?;
                }
            }
        }
        Ok(())
    }

    /// Checks that the page is whole and within the `cols` x `rows` plate; returns its cells as
    /// `(position in the frame, value)`.
    fn entries(&self, cols: usize, rows: usize, name: &str) -> Result<Vec<(usize, f32)>> {
        let err = |line: usize, msg: String| IoError::parse(name, line, msg);
        if let Some((c, r, ln)) = self.matrix
            && (c, r) != (cols, rows)
        {
            return Err(err(
                ln,
                format!("Matrix {c}x{r} differs from the first page's {cols}x{rows}"),
            ));
        }
        if self.columns.is_empty() {
            return Err(err(
                self.first_line,
                "page without a column index line (truncated?)".into(),
            ));
        }
        if !self.saw_force_line {
            return Err(err(
                self.first_line,
                "page without its closing Force line (truncated?)".into(),
            ));
        }
        let mut entries = Vec::with_capacity(self.cells.len());
        for &(r, c, v, ln) in &self.cells {
            if r > rows || c > cols {
                return Err(err(
                    ln,
                    format!("cell (row {r}, column {c}) outside the {cols}x{rows} matrix"),
                ));
            }
            entries.push(((r - 1) * cols + (c - 1), v as f32));
        }
        Ok(entries)
    }
}

/// Parses a `.lst` file held in memory; returns the recording and, per picture, the forces the
/// export printed (to check against). `name` appears in error messages.
pub fn parse_lst(bytes: &[u8], name: &str) -> Result<(Recording, Vec<LstPageForces>)> {
    let lines = super::stream::bounded(bytes, false, super::stream::Stretch::Line);
    super::stream::parse_lines(lines, name, |l| read_lst(l, name))
}

/// [`parse_lst`] from the file's lines (see [`super::stream::Lines`]): pages are cut at form
/// feeds and each is placed on the plate as soon as it ends, so that only its frame is held.
pub(crate) fn read_lst(
    lines: impl Iterator<Item = (usize, String)>,
    name: &str,
) -> Result<(Recording, Vec<LstPageForces>)> {
    read_lst_keeping(lines, name, &mut Keep::All)
}

/// [`read_lst`], each picture kept or handed on as `keep` says (handed: neither its values nor
/// its printed forces held).
pub(crate) fn read_lst_keeping(
    lines: impl Iterator<Item = (usize, String)>,
    name: &str,
    keep: &mut Keep<'_>,
) -> Result<(Recording, Vec<LstPageForces>)> {
    let mut pages = Pages::new(name, keep);
    let mut page = Page::starting_at(1);
    for (ln, raw) in lines {
        let mut parts = raw.split('\x0c');
        if let Some(first) = parts.next() {
            page.line(ln, first, name)?;
        }
        for part in parts {
            pages.add(std::mem::replace(&mut page, Page::starting_at(ln)))?;
            page.line(ln, part, name)?;
        }
    }
    pages.add(page)?;
    pages.finish()
}

/// The pages read so far: placed on the plate (the first page's `Matrix`) as frames, or, before
/// a page has stated the plate, kept until one does.
struct Pages<'a, 'k, 'h> {
    name: &'a str,
    keep: &'k mut Keep<'h>,
    /// The values below 0 of the pictures handed on (not kept: counted as they pass).
    negatives: NegativeValues,
    /// The plate, `(cols, rows)`, once a page has stated it.
    plate: Option<(usize, usize)>,
    pending: Vec<Page>,
    frames: Option<SparseFrames>,
    forces: Vec<LstPageForces>,
    n_pages: usize,
    area_cm2: Option<f64>,
    dt_ms: Option<f64>,
    size_cm: Option<(f64, f64)>,
}

impl<'a, 'k, 'h> Pages<'a, 'k, 'h> {
    fn new(name: &'a str, keep: &'k mut Keep<'h>) -> Self {
        Pages {
            name,
            keep,
            negatives: NegativeValues::default(),
            plate: None,
            pending: Vec::new(),
            frames: None,
            forces: Vec::new(),
            n_pages: 0,
            area_cm2: None,
            dt_ms: None,
            size_cm: None,
        }
    }

    /// Adds a page that has ended (one without content is no picture).
    fn add(&mut self, mut pg: Page) -> Result<()> {
        if !pg.has_content {
            return Ok(());
        }
        self.n_pages += 1;
        self.area_cm2 = self.area_cm2.or(pg.area_cm2);
        self.dt_ms = self.dt_ms.or(pg.dt_ms);
        self.size_cm = self.size_cm.or(pg.size_cm);
        if matches!(self.keep, Keep::All) {
            self.forces.push(std::mem::take(&mut pg.forces));
        }
        if self.plate.is_none()
            && let Some((c, r, _)) = pg.matrix
        {
            self.plate = Some((c, r));
            self.frames = Some(SparseFrames::new(r * c));
            for earlier in std::mem::take(&mut self.pending) {
                self.place(&earlier)?;
            }
        }
        if self.plate.is_some() {
            return self.place(&pg);
        }
        // Pages before the first `Matrix` line wait for it, within one frame's worth of cells.
        let waiting: usize = self.pending.iter().map(|p| p.cells.len()).sum();
        let most = crate::limits::current().frame_sensors;
        if waiting + pg.cells.len() > most {
            return Err(IoError::format(
                self.name,
                format!(
                    "more than {most} values before a `Matrix: CxR` line; {}",
                    crate::limits::raise("max_frame_sensors")
                ),
            ));
        }
        self.pending.push(pg);
        Ok(())
    }

    /// Places a page on the plate as the next frame.
    fn place(&mut self, pg: &Page) -> Result<()> {
        let ((cols, rows), Some(frames)) = (self.plate.expect("set"), self.frames.as_mut()) else {
            return Ok(());
        };
        crate::limits::check_frames(self.name, frames.n_frames() + 1, rows * cols)?;
        let mut entries = pg.entries(cols, rows, self.name)?;
        let hand = match self.keep {
            Keep::All => {
                frames.push_entries(&mut entries);
                return Ok(());
            }
            Keep::Handed(hand) => hand,
        };
        // A cell printed twice holds its last value, as the frames kept hold it.
        let mut frame = vec![0.0f32; rows * cols];
        entries.iter().for_each(|&(i, v)| frame[i] = v);
        frame.iter().for_each(|&v| self.negatives.add(v));
        frames.push_empty();
        match hand {
            Some(hand) => hand(&frame),
            None => Ok(()),
        }
    }

    fn finish(self) -> Result<(Recording, Vec<LstPageForces>)> {
        if self.n_pages == 0 {
            return Err(IoError::format(self.name, "no pages"));
        }
        let (Some((cols, rows)), Some(frames)) = (self.plate, self.frames) else {
            return Err(IoError::format(self.name, "no `Matrix: CxR` line"));
        };
        let mut rec = Recording::from_sparse(rows, cols, frames, vec![true; rows * cols])?;
        if let Keep::Handed(_) = self.keep {
            rec.set_file_negatives(self.negatives);
        }
        rec.sensel_area_mm2 = self.area_cm2.map(|a| a * 100.0);
        rec.dt_s = self.dt_ms.map(|ms| ms / 1000.0);
        rec.pitch_mm = self.size_cm.map(|(x, y)| [x * 10.0, y * 10.0]);
        rec.units = "kPa".to_string();
        rec.format = Some(Format::Lst);
        Ok((rec, self.forces))
    }
}
