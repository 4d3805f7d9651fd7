//! What a user marks on a recording to be followed through a stance: named points (a CSV of
//! `x,y` in sensels or `x_mm,y_mm` in millimetres, optional `name` and `frame` columns) and
//! regions (a mask of integer labels over one frame, 0 = none), read here and followed by
//! `pedo-track` (`follow`).

use crate::error::{IoError, Result};
use crate::recording::{FrameMeasures, MeasureSum, Recording};
use crate::Grid;
use std::collections::HashMap;
use std::path::Path;

/// A point a user gives to follow.
#[derive(Debug, Clone, PartialEq)]
pub struct GivenPoint {
    /// Its name: the file's `name` column, else `p1`, `p2`, ... in file order.
    pub name: String,
    /// Its position: x = column, y = row, in sensels, or in mm when [`mm`](Self::mm).
    pub xy: [f64; 2],
    /// Whether [`xy`](Self::xy) is in millimetres (`x_mm,y_mm` columns).
    pub mm: bool,
    /// The frame (0-based) it is given on, from the file's `frame` column.
    pub frame: Option<usize>,
}

/// Parses a points file: a header naming `x,y` (sensels) or `x_mm,y_mm` (millimetres), and
/// optionally `name` and `frame` (0-based), in any order; then one point a line (comma,
/// semicolon or tab separated; blank lines and `#` comments skipped). `name` is the file's name
/// in errors.
///
/// # Errors
/// [`IoError::Parse`] naming the line for a missing column, a value that is not a finite
/// number or a frame that is not a non-negative integer; [`IoError::Format`] for a file without
/// a header or without points.
pub fn parse_given_points(text: &str, name: &str) -> Result<Vec<GivenPoint>> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let split = |l: &str| -> Vec<String> {
        l.split([',', ';', '\t'])
            .map(|f| f.trim().trim_matches('"').to_string())
            .collect()
    };
    let (_, header) = lines
        .next()
        .ok_or_else(|| IoError::format(name, "no header: expected x,y or x_mm,y_mm"))?;
    let header: Vec<String> = split(header).iter().map(|h| h.to_lowercase()).collect();
    let col = |n: &str| header.iter().position(|h| h == n);
    let (x, y, mm) = match (col("x"), col("y"), col("x_mm"), col("y_mm")) {
        (Some(x), Some(y), _, _) => (x, y, false),
        (_, _, Some(x), Some(y)) => (x, y, true),
        _ => {
            return Err(IoError::format(
                name,
                format!(
                    "the header names no x,y (sensels) or x_mm,y_mm (mm) columns: {}",
                    header.join(",")
                ),
            ));
        }
    };
    let (name_col, frame_col) = (col("name"), col("frame"));
    let mut out = Vec::new();
    for (i, line) in lines {
        let f = split(line);
        let get = |c: usize, what: &str| {
            f.get(c)
                .ok_or_else(|| IoError::parse(name, i + 1, format!("no {what} column")))
        };
        let number = |c: usize, what: &str| -> Result<f64> {
            let s = get(c, what)?;
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    IoError::parse(name, i + 1, format!("{what} {s:?} is not a finite number"))
                })
        };
        let xy = [number(x, &header[x])?, number(y, &header[y])?];
        let frame = match frame_col {
            Some(c) => {
                let s = get(c, "frame")?;
                if s.is_empty() {
                    None
                } else {
                    Some(s.parse::<usize>().map_err(|_| {
                        IoError::parse(
                            name,
                            i + 1,
                            format!("frame {s:?} is not a frame number (0-based)"),
                        )
                    })?)
                }
            }
            None => None,
        };
        let label = match name_col.map(|c| get(c, "name")).transpose()? {
            Some(s) if !s.is_empty() => s.clone(),
            _ => format!("p{}", out.len() + 1),
        };
        out.push(GivenPoint {
            name: label,
            xy,
            mm,
            frame,
        });
    }
    if out.is_empty() {
        return Err(IoError::format(name, "no points"));
    }
    Ok(out)
}

/// Reads a points file ([`parse_given_points`]).
///
/// # Errors
/// As [`parse_given_points`]; [`IoError::Io`] when the file cannot be read.
pub fn read_given_points(path: impl AsRef<Path>) -> Result<Vec<GivenPoint>> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Io {
        path: name.clone(),
        source,
    })?;
    parse_given_points(&text, &name)
}

/// Points given as rows `x, y` in sensels (Python's `(n, 2)` array), named `p1`, `p2`, ...
///
/// # Errors
/// [`IoError::InvalidInput`] naming the row for a row of another length or a value that is not
/// finite, or for no rows at all.
pub fn given_points_of_rows(rows: &[Vec<f64>]) -> Result<Vec<GivenPoint>> {
    if rows.is_empty() {
        return Err(IoError::invalid("points: no points given"));
    }
    rows.iter()
        .enumerate()
        .map(|(k, r)| match r[..] {
            [x, y] if x.is_finite() && y.is_finite() => Ok(GivenPoint {
                name: format!("p{}", k + 1),
                xy: [x, y],
                mm: false,
                frame: None,
            }),
            _ => Err(IoError::invalid(format!(
                "points: row {k} is {r:?}; expected two finite numbers x, y (sensels)"
            ))),
        })
        .collect()
}

/// A mask of region labels over the sensels of one frame: 0 = no region, each other integer one
/// region.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelMask {
    rows: usize,
    cols: usize,
    labels: Vec<u32>,
}

impl LabelMask {
    /// A mask of `rows × cols` labels, row-major.
    ///
    /// # Errors
    /// [`IoError::InvalidInput`] when `labels` does not hold `rows × cols` values, or when no
    /// sensel carries a label.
    pub fn new(rows: usize, cols: usize, labels: Vec<u32>) -> Result<Self> {
        if labels.len() != rows * cols || rows == 0 || cols == 0 {
            return Err(IoError::invalid(format!(
                "regions: {} labels for a {rows} × {cols} mask",
                labels.len()
            )));
        }
        if labels.iter().all(|&l| l == 0) {
            return Err(IoError::invalid(
                "regions: the mask labels no sensel (0 = no region)",
            ));
        }
        Ok(Self { rows, cols, labels })
    }

    /// A mask from rows of numbers (Python's 2-D array), each a non-negative integer.
    ///
    /// # Errors
    /// [`IoError::InvalidInput`] for rows of unequal lengths or a value that is not a
    /// non-negative integer, naming its row and column; as [`LabelMask::new`].
    pub fn of_rows(rows: &[Vec<f64>]) -> Result<Self> {
        let cols = rows.first().map_or(0, Vec::len);
        let mut labels = Vec::with_capacity(rows.len() * cols);
        for (r, row) in rows.iter().enumerate() {
            if row.len() != cols {
                return Err(IoError::invalid(format!(
                    "regions: row {r} has {} values, row 0 has {cols}",
                    row.len()
                )));
            }
            for (c, &v) in row.iter().enumerate() {
                labels.push(label_of(v).ok_or_else(|| {
                    IoError::invalid(format!(
                        "regions: the value at row {r}, column {c} is {v}; labels are integers \
                         >= 0 (0 = no region)"
                    ))
                })?);
            }
        }
        Self::new(rows.len(), cols, labels)
    }

    /// Reads a mask from any file a recording is read from (`.npy`, a CSV grid, a PNG/TIFF
    /// image, ...) holding one frame of non-negative integers.
    ///
    /// # Errors
    /// As [`crate::read_recording`]; [`IoError::InvalidInput`] for a file of several frames or
    /// a value that is not a non-negative integer.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let rec = crate::read_recording(path)?;
        let name = path.display();
        if rec.n_frames() != 1 {
            return Err(IoError::invalid(format!(
                "regions: {name} holds {} frames; a mask is one frame of labels",
                rec.n_frames()
            )));
        }
        let grid = rec.frame(0)?;
        let mut labels = Vec::with_capacity(rec.rows() * rec.cols());
        for r in 0..rec.rows() {
            for c in 0..rec.cols() {
                let v = grid.get(r, c);
                labels.push(label_of(v).ok_or_else(|| {
                    IoError::invalid(format!(
                        "regions: {name} has {v} at row {r}, column {c}; labels are integers \
                         >= 0 (0 = no region)"
                    ))
                })?);
            }
        }
        Self::new(rec.rows(), rec.cols(), labels)
    }

    /// `(rows, cols)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    /// The labels of the mask's regions, ascending.
    pub fn regions(&self) -> Vec<u32> {
        let mut l: Vec<u32> = self.labels.iter().copied().filter(|&l| l != 0).collect();
        l.sort_unstable();
        l.dedup();
        l
    }

    /// Which sensels carry `label` (row-major).
    pub fn cells(&self, label: u32) -> Vec<bool> {
        self.labels.iter().map(|&l| l == label).collect()
    }

    /// The outline of region `label`: the boundary of its sensels' squares (corners at half
    /// sensels; x = column, y = row), the longest closed loop of it (the outer boundary of its
    /// largest part), its corners only. The sensel centres inside it are the region's sensels (for a region of one part
    /// without holes). Empty for a label the mask does not hold.
    pub fn outline(&self, label: u32) -> Vec<[f64; 2]> {
        let inside = |r: isize, c: isize| {
            r >= 0
                && c >= 0
                && (r as usize) < self.rows
                && (c as usize) < self.cols
                && self.labels[r as usize * self.cols + c as usize] == label
        };
        // Directed edges between lattice corners (corner (i, j) = x j - 0.5, y i - 0.5), the
        // region on their left when y points down: each boundary side of a sensel once.
        let mut next: HashMap<(isize, isize), Vec<(isize, isize)>> = HashMap::new();
        for r in 0..self.rows as isize {
            for c in 0..self.cols as isize {
                if !inside(r, c) {
                    continue;
                }
                let mut add = |a: (isize, isize), b: (isize, isize)| {
                    next.entry(a).or_default().push(b);
                };
                // Corners as (row, col) of the lattice.
                if !inside(r - 1, c) {
                    add((r, c + 1), (r, c));
                }
                if !inside(r, c - 1) {
                    add((r, c), (r + 1, c));
                }
                if !inside(r + 1, c) {
                    add((r + 1, c), (r + 1, c + 1));
                }
                if !inside(r, c + 1) {
                    add((r + 1, c + 1), (r, c + 1));
                }
            }
        }
        let mut best: Vec<(isize, isize)> = Vec::new();
        let mut starts: Vec<(isize, isize)> = next.keys().copied().collect();
        starts.sort_unstable();
        for start in starts {
            while next.get(&start).is_some_and(|v| !v.is_empty()) {
                let mut lp = vec![start];
                let mut at = start;
                while let Some(b) = next.get_mut(&at).and_then(Vec::pop) {
                    if b == start {
                        break;
                    }
                    lp.push(b);
                    at = b;
                }
                if lp.len() > best.len() {
                    best = lp;
                }
            }
        }
        // Corners only: drop the points where the boundary runs straight on.
        let n = best.len();
        let corners: Vec<[f64; 2]> = (0..n)
            .filter(|&i| {
                let (p, q, s) = (best[(i + n - 1) % n], best[i], best[(i + 1) % n]);
                (q.0 - p.0, q.1 - p.1) != (s.0 - q.0, s.1 - q.1)
            })
            .map(|i| [best[i].1 as f64 - 0.5, best[i].0 as f64 - 0.5])
            .collect();
        corners
    }
}

/// The sensels (row-major, `rows × cols`) whose centres lie inside the closed `outline`
/// (x = column, y = row, in sensels): a followed region's outline rasterised.
pub fn polygon_cells(rows: usize, cols: usize, outline: &[[f64; 2]]) -> Vec<bool> {
    let mut cells = vec![false; rows * cols];
    let (lo, hi) = outline.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let span = |lo: f64, hi: f64, n: usize| {
        let first = lo.ceil().clamp(0.0, n as f64) as usize;
        let last = (hi.floor() + 1.0).clamp(0.0, n as f64) as usize;
        first..last.max(first)
    };
    for r in span(lo[1], hi[1], rows) {
        for c in span(lo[0], hi[0], cols) {
            cells[r * cols + c] = crate::contour::point_in_polygon([c as f64, r as f64], outline);
        }
    }
    cells
}

fn label_of(v: f64) -> Option<u32> {
    (v.is_finite() && v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64).then_some(v as u32)
}

impl Recording {
    /// The [`measures`](Recording::measures) of the existing sensors of `frame` where `cells`
    /// (row-major, `rows × cols`) is true: a fixed region of the sensor. Nothing is counted when
    /// `cells` is not of the recording's shape.
    pub fn cells_measures(&self, frame: &Grid, threshold: f64, cells: &[bool]) -> FrameMeasures {
        let mut sum = MeasureSum::default();
        let (rows, cols) = (self.rows(), self.cols());
        if cells.len() == rows * cols && frame.rows() == rows && frame.cols() == cols {
            let mask = self.sensor_mask();
            for (i, &c) in cells.iter().enumerate() {
                if c && mask[i] {
                    sum.add(frame.get(i / cols, i % cols), i / cols, i % cols, threshold);
                }
            }
        }
        sum.measures(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_files_read_sensels_mm_names_and_frames() {
        let p = parse_given_points("name,x,y\nheel,3,4.5\n,1,2\n", "a.csv").unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(
            (p[0].name.as_str(), p[0].xy, p[0].mm),
            ("heel", [3.0, 4.5], false)
        );
        assert_eq!(p[1].name, "p2");
        let p = parse_given_points("x_mm;y_mm;frame\n10;20;3\n", "b.csv").unwrap();
        assert_eq!(
            (p[0].xy, p[0].mm, p[0].frame),
            ([10.0, 20.0], true, Some(3))
        );
        let e = parse_given_points("x,y\n1,nan\n", "c.csv").unwrap_err();
        assert!(e.to_string().contains("c.csv:2"), "{e}");
        assert!(parse_given_points("a,b\n1,2\n", "d.csv").is_err());
        assert!(parse_given_points("x,y\n", "e.csv").is_err());
        assert!(parse_given_points("x,y,frame\n1,2,-1\n", "f.csv").is_err());
        assert!(given_points_of_rows(&[vec![1.0, f64::NAN]]).is_err());
        assert!(given_points_of_rows(&[vec![1.0, 2.0, 3.0]]).is_err());
        assert_eq!(
            given_points_of_rows(&[vec![1.0, 2.0]]).unwrap()[0].xy,
            [1.0, 2.0]
        );
    }

    #[test]
    fn a_region_outline_holds_exactly_its_sensels() {
        // An L-shaped region beside a square one.
        #[rustfmt::skip]
        let rows = vec![
            vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0, 2.0, 2.0, 0.0],
            vec![0.0, 1.0, 1.0, 2.0, 2.0, 0.0],
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ];
        let m = LabelMask::of_rows(&rows).unwrap();
        assert_eq!(m.regions(), vec![1, 2]);
        for label in [1, 2] {
            let outline = m.outline(label);
            let cells = m.cells(label);
            for r in 0..4 {
                for c in 0..6 {
                    let inside = crate::contour::point_in_polygon([c as f64, r as f64], &outline);
                    assert_eq!(inside, cells[r * 6 + c], "label {label} at {r},{c}");
                }
            }
        }
        assert_eq!(m.outline(2).len(), 4);
        assert_eq!(m.outline(1).len(), 6);
        assert!(LabelMask::of_rows(&[vec![0.0, 1.5]]).is_err());
        assert!(LabelMask::of_rows(&[vec![0.0, 0.0]]).is_err());
        assert!(LabelMask::of_rows(&[vec![0.0, 1.0], vec![1.0]]).is_err());
    }
}
