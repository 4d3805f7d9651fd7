//! A single frame as a delimited text grid (comma, semicolon, tab or spaces, as the first data
//! row shows; no header, or one header line: names, or the column numbers; unless commas
//! separate, decimal commas too). `-1`, `B` and `NaN` mark a missing sensor.

use super::asf::trunc;
use super::parse_num;
use crate::error::{IoError, Result};
use crate::grid::Grid;
use crate::recording::{Format, Recording};
use std::fmt::Write as _;
use std::path::Path;

/// The fields of a line; at most one more than a frame may have sensors (a longer row is
/// refused, and never split whole).
fn split_fields(line: &str, sep: Option<char>) -> Vec<&str> {
    let most = crate::limits::current().frame_sensors.saturating_add(1);
    match sep {
        Some(c) => line.split(c).map(str::trim).take(most).collect(),
        None => line.split_whitespace().take(most).collect(),
    }
}

/// Parses a CSV grid held in memory into a one-frame recording.
pub fn parse_csv(bytes: &[u8], name: &str) -> Result<Recording> {
    let lines = super::stream::bounded(bytes, false, super::stream::Stretch::Line);
    super::stream::parse_lines(lines, name, |l| read_csv(l, name))
}

/// Parses a CSV grid from its lines (see [`super::stream::Lines`]).
pub(crate) fn read_csv(
    lines: impl Iterator<Item = (usize, String)>,
    name: &str,
) -> Result<Recording> {
    let err = |line: usize, msg: String| IoError::parse(name, line, msg);
    let mut sep: Option<Option<char>> = None;
    let mut cols = 0usize;
    let mut values: Vec<f32> = Vec::new();
    let mut present: Vec<bool> = Vec::new();
    let mut rows = 0usize;
    let mut first_content = true;
    for (ln, line) in lines {
        // A byte-order mark (read as Latin-1) starts a file saved as UTF-8 by Windows tools.
        let line = match ln {
            1 => line.strip_prefix("\u{ef}\u{bb}\u{bf}").unwrap_or(&line),
            _ => &line,
        };
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        let s = *sep.get_or_insert_with(|| guess_separator(t));
        let fields = row_fields(t, s);
        if first_content {
            first_content = false;
            if is_header(&fields, s) {
                // The data may use another separator than the header (or the header none).
                sep = None;
                continue;
            }
        }
        if cols == 0 {
            cols = fields.len();
        } else if fields.len() != cols {
            return Err(err(
                ln,
                format!("{} values, the first row has {cols}", fields.len()),
            ));
        }
        // A grid is one frame: refused as soon as it has more sensors than a frame may have.
        crate::limits::frame_sensors("a grid", rows + 1, cols).map_err(|m| err(ln, m))?;
        for (k, f) in fields.iter().enumerate() {
            if is_missing(f) {
                values.push(0.0);
                present.push(false);
            } else {
                let v = number(f, s).ok_or_else(|| {
                    err(
                        ln,
                        format!("value {} is not a number: {:?}", k + 1, trunc(f)),
                    )
                })?;
                values.push(v as f32);
                present.push(true);
            }
        }
        rows += 1;
    }
    if rows == 0 {
        return Err(IoError::format(name, "no data rows"));
    }
    let mut rec = Recording::new(1, rows, cols, values, present)?;
    rec.format = Some(Format::Csv);
    Ok(rec)
}

/// The fields of a row, without the empty field a trailing separator leaves.
fn row_fields(t: &str, sep: Option<char>) -> Vec<&str> {
    let mut fields = split_fields(t, sep);
    if sep.is_some() && fields.len() > 1 && fields.last() == Some(&"") {
        fields.pop();
    }
    fields
}

/// The separator of a row: the first of `;`, tab, `,` and spaces that splits it into two or
/// more values (a value may have a decimal comma unless commas separate: `0,5;12,25`,
/// `0<TAB>12,5`); for a row of names, the first of `;`, `,` and tab it contains.
fn guess_separator(t: &str) -> Option<char> {
    let splits_into_values = |s: Option<char>| {
        let fields = row_fields(t, s);
        s.is_none_or(|c| t.contains(c))
            && fields.len() > 1
            && fields
                .iter()
                .all(|f| number(f, s).is_some() || is_missing(f))
    };
    [Some(';'), Some('\t'), Some(','), None]
        .into_iter()
        .find(|&s| splits_into_values(s))
        .unwrap_or_else(|| [';', ',', '\t'].into_iter().find(|&c| t.contains(c)))
}

/// Whether a first row is a header: names (no field is a number, and not every field marks a
/// missing sensor, as a first row of `NaN` may), or the column numbers.
fn is_header(fields: &[&str], sep: Option<char>) -> bool {
    let any_number = fields.iter().any(|f| number(f, sep).is_some());
    let all_missing = fields.iter().all(|f| is_missing(f));
    (!any_number && !all_missing) || is_column_numbers(fields)
}

/// Whether a text sniffed as a CSV grid reads rather as a table of another kind: a first line
/// of names (not column numbers) or rows of at most 3 values (a point file, a time series). A
/// searched folder passes such files over, as it does notes and spreadsheets (a study folder
/// also holds anthropometrics and force-plate tables); named on their own they are still read.
pub fn looks_like_a_table(head: &str) -> bool {
    let head = head.strip_prefix('\u{feff}').unwrap_or(head);
    let mut lines = head.lines().map(str::trim).filter(|l| !l.is_empty());
    let Some(first) = lines.next() else {
        return false;
    };
    let sep = [';', ',', '\t'].into_iter().find(|&c| first.contains(c));
    let fields = split_fields(first, sep);
    let numeric = fields
        .iter()
        .any(|f| number(f, sep).is_some() || is_missing(f));
    let named_header = !numeric && !is_column_numbers(&fields);
    let row = if numeric { Some(first) } else { lines.next() };
    let narrow = row.is_some_and(|r| row_fields(r, sep).len() <= 3);
    named_header || narrow
}

/// Whether a first line numbers the columns (`1,2,…,n` or `0,1,…,n−1`, as spreadsheets and
/// `numpy.savetxt` headers do): a header, not a row of pressures — no row of five or more
/// sensors reads as an exact count.
fn is_column_numbers(fields: &[&str]) -> bool {
    let numbers: Option<Vec<i64>> = fields.iter().map(|f| f.parse().ok()).collect();
    match numbers {
        Some(n) if n.len() >= 5 && (n[0] == 0 || n[0] == 1) => {
            n.windows(2).all(|w| w[1] == w[0] + 1)
        }
        _ => false,
    }
}

/// A value of the grid: with `;` between values a decimal comma is read as a decimal point.
fn number(f: &str, sep: Option<char>) -> Option<f64> {
    parse_num(f).or_else(|| {
        (sep == Some(';') && f.contains(','))
            .then(|| parse_num(&f.replacen(',', ".", 1)))
            .flatten()
    })
}

fn is_missing(f: &str) -> bool {
    f == "-1" || f == "-1.0" || f.eq_ignore_ascii_case("b") || f.eq_ignore_ascii_case("nan")
}

/// Formats one frame of a recording as CSV: comma separated, `-1` at missing sensors, values with
/// the shortest representation that reads back to the same `f32`.
pub fn frame_to_csv(rec: &Recording, t: usize) -> Result<String> {
    let f = rec.frame_slice(t).ok_or_else(|| {
        IoError::invalid(format!(
            "frame {t} out of range ({} frames)",
            rec.n_frames()
        ))
    })?;
    let mask = rec.sensor_mask();
    if f.iter().zip(mask).any(|(&v, &m)| m && v == -1.0) {
        return Err(IoError::invalid(
            "a sensor holds -1, which CSV reserves for no sensor".to_string(),
        ));
    }
    let mut s = String::with_capacity(f.len() * 4);
    for r in 0..rec.rows() {
        for c in 0..rec.cols() {
            if c > 0 {
                s.push(',');
            }
            let i = r * rec.cols() + c;
            if mask[i] {
                let _ = write!(s, "{}", f[i]);
            } else {
                s.push_str("-1");
            }
        }
        s.push('\n');
    }
    Ok(s)
}

/// Writes one frame of a recording as CSV (see [`frame_to_csv`]).
pub fn write_csv(rec: &Recording, t: usize, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let s = frame_to_csv(rec, t)?;
    std::fs::write(path, s).map_err(|source| IoError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Writes a grid as CSV (all sensors present).
pub fn write_grid_csv(grid: &Grid, path: impl AsRef<Path>) -> Result<()> {
    let data: Vec<f32> = grid.data().iter().map(|&v| v as f32).collect();
    let rec = Recording::new(
        1,
        grid.rows(),
        grid.cols(),
        data,
        vec![true; grid.rows() * grid.cols()],
    )?;
    write_csv(&rec, 0, path)
}

#[cfg(test)]
mod table_tests {
    use super::looks_like_a_table;

    #[test]
    fn tables_of_names_and_narrow_rows_are_not_taken_for_grids() {
        let anthropometrics = "subject,age,mass_kg,height_m\n1,34,70.2,1.78\n2,28,65.0,1.70\n";
        let force_plate = "0.00,0\n0.01,12.5\n0.02,80.1\n";
        let points = "x y\n1.5 2\n3 4\n";
        for t in [anthropometrics, force_plate, points] {
            assert!(looks_like_a_table(t), "{t}");
        }
        let grid = "0,0,1,3,4,2\n0,4,23,5,0,0\n";
        let numbered = "1;2;3;4;5\n0;0,5;12,25;0;0\n";
        let spaced = "0 0 1 3\n0 4 23 5\n";
        let bom = "\u{feff}0,0,1,3,4,2\n";
        for t in [grid, numbered, spaced, bom] {
            assert!(!looks_like_a_table(t), "{t}");
        }
    }
}
