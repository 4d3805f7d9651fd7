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

fn leading_num(s: &str) -> Option<f64> {
    let end = s
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
        .map(|(i, _)| i)
        .unwrap_or(s.len());
    parse_num(&s[..end])
}

/// Parses a `.lst` file held in memory; returns the recording and, per picture, the forces the
/// export printed (to check against). `name` appears in error messages.
pub fn parse_lst(bytes: &[u8], name: &str) -> Result<(Recording, Vec<LstPageForces>)> {
    let err = |line: usize, msg: String| IoError::parse(name, line, msg);
    let text: String = bytes.iter().map(|&b| b as char).collect();
    // Split into pages at form feeds while keeping 1-based line numbers.
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

    let mut parsed: Vec<Page> = Vec::new();
    for lines in pages {
        let mut pg = Page {
            first_line: lines.first().map(|l| l.0).unwrap_or(1),
            ..Default::default()
        };
        let mut state = 0; // 0 header, 1 rows, 2 after Force line
        for (ln, line) in lines {
            let t = line.trim();
            if t.is_empty() {
                continue;
            }
            pg.has_content = true;
            if state == 0 {
                if let Some(v) = after(t, "Matrix:") {
                    let tok = v.split_whitespace().next().unwrap_or("");
                    let (c, r) = tok
                        .split_once(['x', 'X'])
                        .ok_or_else(|| err(ln, format!("bad Matrix {:?}", trunc(tok))))?;
                    let (c, r) = (c.parse::<usize>(), r.parse::<usize>());
                    match (c, r) {
                        (Ok(c), Ok(r)) if c > 0 && r > 0 && c <= 10_000 && r <= 10_000 => {
                            pg.matrix = Some((c, r, ln))
                        }
                        _ => return Err(err(ln, format!("bad Matrix {:?}", trunc(tok)))),
                    }
                }
                if let Some(v) = after(t, "Sensor area:") {
                    pg.area_cm2 = Some(
                        leading_num(v)
                            .filter(|&a| a > 0.0)
                            .ok_or_else(|| err(ln, "bad Sensor area".into()))?,
                    );
                }
                if let Some(v) = after(t, "Time/picture:") {
                    pg.dt_ms = Some(
                        leading_num(v)
                            .filter(|&a| a > 0.0)
                            .ok_or_else(|| err(ln, "bad Time/picture".into()))?,
                    );
                }
                if let Some(v) = after(t, "Sensor size:") {
                    let tok = v.split_whitespace().next().unwrap_or("");
                    let (a, b) = tok
                        .split_once(['x', 'X'])
                        .ok_or_else(|| err(ln, "bad Sensor size".into()))?;
                    match (parse_num(a), parse_num(b)) {
                        (Some(a), Some(b)) if a > 0.0 && b > 0.0 => pg.size_cm = Some((a, b)),
                        _ => return Err(err(ln, "bad Sensor size".into())),
                    }
                }
                // The column index line: integers (tab separated), optionally ending with `Force`.
                let toks: Vec<&str> = t.split(['\t', ' ']).filter(|s| !s.is_empty()).collect();
                let (nums, force) = match toks.split_last() {
                    Some((&"Force", rest)) => (rest, true),
                    _ => (&toks[..], false),
                };
                if !nums.is_empty() && nums.iter().all(|s| s.bytes().all(|b| b.is_ascii_digit())) {
                    let mut cols = Vec::with_capacity(nums.len());
                    for s in nums {
                        let c = s
                            .parse::<usize>()
                            .map_err(|_| err(ln, "bad column index".into()))?;
                        if c == 0 {
                            return Err(err(ln, "column indices are 1-based".into()));
                        }
                        cols.push(c);
                    }
                    pg.columns = cols;
                    pg.has_row_force = force;
                    state = 1;
                }
                continue;
            }
            if state == 2 {
                return Err(err(
                    ln,
                    format!("unexpected text after the Force line: {:?}", trunc(t)),
                ));
            }
            let fields: Vec<&str> = line.split('\t').map(str::trim).collect();
            let fields: &[&str] = match fields.split_last() {
                Some((&"", rest)) => rest,
                _ => &fields,
            };
            if fields.first() == Some(&"Force") {
                let mut vals = &fields[1..];
                // With row forces, the Force line may end with the page's total force.
                if pg.has_row_force && vals.len() == pg.columns.len() + 1 {
                    vals = &vals[..pg.columns.len()];
                }
                if vals.len() != pg.columns.len() {
                    return Err(err(
                        ln,
                        format!(
                            "Force line has {} values for {} columns",
                            vals.len(),
                            pg.columns.len()
                        ),
                    ));
                }
                for v in vals {
                    pg.forces.column_forces.push(
                        parse_num(v).ok_or_else(|| err(ln, format!("bad force {:?}", trunc(v))))?,
                    );
                }
                pg.saw_force_line = true;
                state = 2;
                continue;
            }
            let r = fields
                .first()
                .and_then(|s| s.parse::<usize>().ok())
                .filter(|&r| r > 0)
                .ok_or_else(|| err(ln, format!("expected a row index, found {:?}", trunc(t))))?;
            let want = pg.columns.len() + usize::from(pg.has_row_force);
            if fields.len() - 1 != want {
                return Err(err(
                    ln,
                    format!("row {r} has {} values, expected {want}", fields.len() - 1),
                ));
            }
            for (k, v) in fields[1..].iter().enumerate() {
                let x = parse_num(v)
                    .ok_or_else(|| err(ln, format!("value {:?} is not a number", trunc(v))))?;
                if k < pg.columns.len() {
                    pg.cells.push((r, pg.columns[k], x, ln));
                } else {
                    pg.forces.row_forces.push(x);
                }
            }
        }
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
    let mut forces = Vec::with_capacity(parsed.len());
    for (t, pg) in parsed.iter().enumerate() {
        if let Some((c, r, ln)) = pg.matrix
            && (c, r) != (cols, rows)
        {
            return Err(err(
                ln,
                format!("Matrix {c}x{r} differs from the first page's {cols}x{rows}"),
            ));
        }
        if pg.columns.is_empty() {
            return Err(err(
                pg.first_line,
                "page without a column index line (truncated?)".into(),
            ));
        }
        if !pg.saw_force_line {
            return Err(err(
                pg.first_line,
                "page without its closing Force line (truncated?)".into(),
            ));
        }
        for &(r, c, v, ln) in &pg.cells {
            if r > rows || c > cols {
                return Err(err(
                    ln,
                    format!("cell (row {r}, column {c}) outside the {cols}x{rows} matrix"),
                ));
            }
            data[t * per + (r - 1) * cols + (c - 1)] = v as f32;
        }
        forces.push(pg.forces.clone());
    }
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
