//! novel emed ASCII page export (`.lst`): Latin-1 text, one page per picture separated by form
//! feeds; each page prints a window of rows and columns of the full `Matrix: CxR` plate.

use super::asf::trunc;
use super::parse_num;
use crate::error::{IoError, Result};
use crate::recording::{Format, Recording};

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
#[derive(Clone, Copy, PartialEq)]
enum PagePart {
    Header,
    Rows,
    Closed,
}

/// The text split into pages at form feeds, each line with its 1-based number in the file.
fn split_pages(text: &str) -> Vec<Vec<(usize, &str)>> {
    let mut pages: Vec<Vec<(usize, &str)>> = vec![Vec::new()];
    for (i, raw) in text.split('\n').enumerate() {
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let mut parts = raw.split('\x0c');
        if let Some(first) = parts.next() {
            pages.last_mut().expect("non-empty").push((i + 1, first));
        }
        for p in parts {
            pages.push(vec![(i + 1, p)]);
        }
    }
    pages
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

    /// Reads one page's lines.
    fn read(lines: &[(usize, &str)], name: &str) -> Result<Page> {
        let mut pg = Page {
            first_line: lines.first().map(|l| l.0).unwrap_or(1),
            ..Default::default()
        };
        let mut part = PagePart::Header;
        for &(ln, line) in lines {
            let err = |msg: String| IoError::parse(name, ln, msg);
            let t = line.trim();
            if t.is_empty() {
                continue;
            }
            pg.has_content = true;
            match part {
                PagePart::Header => {
                    if pg.header_line(ln, t, err)? {
                        part = PagePart::Rows;
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
                        pg.force_line(&fields[1..], err)?;
                        part = PagePart::Closed;
                    } else {
                        pg.data_row(ln, t, fields, err)?;
                    }
                }
            }
        }
        Ok(pg)
    }

    /// Checks that the page is whole and within the `cols` x `rows` plate, and writes its cells
    /// into `frame`.
    fn fill(&self, frame: &mut [f32], cols: usize, rows: usize, name: &str) -> Result<()> {
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
        for &(r, c, v, ln) in &self.cells {
            if r > rows || c > cols {
                return Err(err(
                    ln,
                    format!("cell (row {r}, column {c}) outside the {cols}x{rows} matrix"),
                ));
            }
            frame[(r - 1) * cols + (c - 1)] = v as f32;
        }
        Ok(())
    }
}

/// Parses a `.lst` file held in memory; returns the recording and, per picture, the forces the
/// export printed (to check against). `name` appears in error messages.
pub fn parse_lst(bytes: &[u8], name: &str) -> Result<(Recording, Vec<LstPageForces>)> {
    let text: String = bytes.iter().map(|&b| b as char).collect();
    let mut parsed = Vec::new();
    for lines in split_pages(&text) {
        let pg = Page::read(&lines, name)?;
        if pg.has_content {
            parsed.push(pg);
        }
    }
    if parsed.is_empty() {
        return Err(IoError::format(name, "no pages"));
    }
    let (cols, rows, _) = parsed
        .iter()
        .find_map(|p| p.matrix)
        .ok_or_else(|| IoError::format(name, "no `Matrix: CxR` line"))?;
    let per = rows * cols;
    // Pages print windows of the plate, so the plate may be larger than the text; but not
    // hundreds of times: a larger claim is a corrupt header, refused before allocating it.
    let cells = per.saturating_mul(parsed.len());
    if cells > bytes.len().saturating_mul(256).max(1 << 16) {
        return Err(IoError::format(
            name,
            format!(
                "{} pages of a {cols}x{rows} matrix are far more than the file holds",
                parsed.len()
            ),
        ));
    }
    let mut data = vec![0.0f32; cells];
    for (pg, frame) in parsed.iter().zip(data.chunks_exact_mut(per)) {
        pg.fill(frame, cols, rows, name)?;
    }
    let forces = parsed.iter().map(|p| p.forces.clone()).collect();
    let mut rec = Recording::new(parsed.len(), rows, cols, data, vec![true; per])?;
    rec.sensel_area_mm2 = parsed.iter().find_map(|p| p.area_cm2).map(|a| a * 100.0);
    rec.dt_s = parsed.iter().find_map(|p| p.dt_ms).map(|ms| ms / 1000.0);
    rec.pitch_mm = parsed
        .iter()
        .find_map(|p| p.size_cm)
        .map(|(x, y)| [x * 10.0, y * 10.0]);
    rec.units = "kPa".to_string();
    rec.format = Some(Format::Lst);
    Ok((rec, forces))
}
