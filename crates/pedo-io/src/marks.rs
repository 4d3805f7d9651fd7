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
    let table = HandTable::parse(text, name, "x,y or x_mm,y_mm")?;
    let (header, col) = (&table.header, |n: &str| table.col(n));
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
    for row in table.rows() {
        let xy = [row.number(x, &header[x])?, row.number(y, &header[y])?];
        let frame = match frame_col {
            Some(c) => {
                let s = row.get(c, "frame")?;
                if s.is_empty() {
                    None
                } else {
                    Some(s.parse::<usize>().map_err(|_| {
                        IoError::parse(
                            name,
                            row.line,
                            format!("frame {s:?} is not a frame number (0-based)"),
                        )
                    })?)
                }
            }
            None => None,
        };
        let label = match name_col.map(|c| row.get(c, "name")).transpose()? {
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

/// The share (0..=1) of each sensel (row-major, `rows × cols`) that the closed polygon `outline`
/// covers, in sensel coordinates (x = column, y = row; sensel `(r, c)` is the unit square
/// centred on `(c, r)`). The area is exact: the polygon's edges are accumulated as signed areas
/// per sensel, as a font rasteriser does, so a region that moves by a tenth of a sensel changes
/// its edge sensels' shares by about a tenth rather than switching whole sensels in or out.
/// A self-intersecting outline counts a doubly covered part once. Points need not lie on the
/// grid: the outline is clipped to it.
pub fn polygon_coverage(outline: &[[f64; 2]], rows: usize, cols: usize) -> Vec<f64> {
    let mut shares = vec![0.0; rows * cols];
    // Clipped to the grid's columns, so that no edge reaches past a row's end (the rasteriser
    // accumulates along the whole buffer); rows outside the grid it skips by itself.
    let clipped = clip_to_columns(outline, -0.5, cols as f64 - 0.5);
    if clipped.len() < 3 || rows == 0 || cols == 0 {
        return shares;
    }
    // One spare column takes the contributions of edges on the grid's right side.
    let mut raster = ab_glyph_rasterizer::Rasterizer::new(cols + 1, rows);
    let at = |p: [f64; 2]| ab_glyph_rasterizer::point((p[0] + 0.5) as f32, (p[1] + 0.5) as f32);
    for (i, &p) in clipped.iter().enumerate() {
        raster.draw_line(at(p), at(clipped[(i + 1) % clipped.len()]));
    }
    // The rasteriser sums in f32: shares within its rounding of 0 or 1 are whole.
    let whole = |a: f32| match f64::from(a) {
        a if a < 1e-5 => 0.0,
        a if a > 1.0 - 1e-5 => 1.0,
        a => a,
    };
    raster.for_each_pixel_2d(|x, y, a| {
        if (x as usize) < cols {
            shares[y as usize * cols + x as usize] = whole(a);
        }
    });
    shares
}

/// The part of the closed polygon `outline` with `lo ≤ x ≤ hi` (Sutherland–Hodgman, one
/// half-plane after the other).
fn clip_to_columns(outline: &[[f64; 2]], lo: f64, hi: f64) -> Vec<[f64; 2]> {
    let keep_left = |p: &[f64; 2]| p[0] >= lo;
    let keep_right = |p: &[f64; 2]| p[0] <= hi;
    let half = clip_half_plane(outline, keep_left, lo);
    clip_half_plane(&half, keep_right, hi)
}

/// The part of a closed polygon on the kept side of the vertical line `x = at`.
fn clip_half_plane(poly: &[[f64; 2]], keep: impl Fn(&[f64; 2]) -> bool, at: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (i, p) in poly.iter().enumerate() {
        let q = &poly[(i + 1) % poly.len()];
        if keep(p) {
            out.push(*p);
        }
        if keep(p) != keep(q) {
            let s = (at - p[0]) / (q[0] - p[0]);
            out.push([at, p[1] + s * (q[1] - p[1])]);
        }
    }
    out
}

/// A small table a user writes by hand (points, polygons): a header, then one row a line,
/// fields separated by commas, semicolons or tabs (quotes and spaces around them dropped),
/// blank lines and `#` comments skipped, a byte-order mark ignored.
pub(crate) struct HandTable<'a> {
    /// The file's name, for errors.
    name: &'a str,
    /// The header's names, lower case.
    pub(crate) header: Vec<String>,
    /// Each row's 1-based line number and fields.
    rows: Vec<(usize, Vec<String>)>,
}

impl<'a> HandTable<'a> {
    /// Splits `text` (the file `name`); `expected` names the header's columns for the error
    /// of a file without one.
    pub(crate) fn parse(text: &str, name: &'a str, expected: &str) -> Result<Self> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let split = |l: &str| -> Vec<String> {
            l.split([',', ';', '\t'])
                .map(|f| f.trim().trim_matches('"').to_string())
                .collect()
        };
        let mut lines = (text.lines().enumerate())
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (_, header) = lines
            .next()
            .ok_or_else(|| IoError::format(name, format!("no header: expected {expected}")))?;
        let header = split(header).iter().map(|h| h.to_lowercase()).collect();
        let rows = lines.map(|(i, l)| (i, split(l))).collect();
        Ok(Self { name, header, rows })
    }

    /// The index of the column named `n` (lower case).
    pub(crate) fn col(&self, n: &str) -> Option<usize> {
        self.header.iter().position(|h| h == n)
    }

    /// The rows under the header.
    pub(crate) fn rows(&self) -> impl Iterator<Item = HandRow<'_>> {
        (self.rows.iter()).map(|(line, fields)| HandRow {
            name: self.name,
            line: *line,
            fields,
        })
    }
}

/// One row of a [`HandTable`].
pub(crate) struct HandRow<'a> {
    name: &'a str,
    /// Its line in the file, 1-based.
    pub(crate) line: usize,
    fields: &'a [String],
}

impl HandRow<'_> {
    /// Field `c`, named `what` in the error of a row too short for it.
    pub(crate) fn get(&self, c: usize, what: &str) -> Result<&String> {
        (self.fields.get(c))
            .ok_or_else(|| IoError::parse(self.name, self.line, format!("no {what} column")))
    }

    /// Field `c` as a finite number.
    pub(crate) fn number(&self, c: usize, what: &str) -> Result<f64> {
        let s = self.get(c, what)?;
        (s.parse::<f64>().ok().filter(|v| v.is_finite())).ok_or_else(|| {
            IoError::parse(
                self.name,
                self.line,
                format!("{what} {s:?} is not a finite number"),
            )
        })
    }
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

    /// The [`measures`](Recording::measures) of a region that covers the share `shares[i]`
    /// (0..=1, row-major, `rows × cols`; [`polygon_coverage`]) of each sensel: every existing
    /// sensor's contact, load and centre of pressure counted by its share, its value towards the
    /// peak where the region covers at least half of it. Whole shares (0 or 1) give exactly
    /// [`cells_measures`](Recording::cells_measures). Nothing is counted when `shares` is not of
    /// the recording's shape.
    pub fn covered_measures(&self, frame: &Grid, threshold: f64, shares: &[f64]) -> FrameMeasures {
        let mut sum = MeasureSum::default();
        let (rows, cols) = (self.rows(), self.cols());
        if shares.len() == rows * cols && frame.rows() == rows && frame.cols() == cols {
            let mask = self.sensor_mask();
            for (i, &w) in shares.iter().enumerate() {
                if w > 0.0 && mask[i] {
                    sum.add_share(
                        frame.get(i / cols, i % cols),
                        i / cols,
                        i % cols,
                        threshold,
                        w,
                    );
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
    fn coverage_is_the_area_of_each_sensel_inside_the_outline() {
        // A rectangle from x = 0.25 to 2.0 and y = -0.5 to 0.75 (sensel (r, c) spans
        // c ± 0.5, r ± 0.5), partly off the grid's left side.
        let rect = [[-1.0, -0.5], [2.0, -0.5], [2.0, 0.75], [-1.0, 0.75]];
        let s = polygon_coverage(&rect, 2, 4);
        let want = [1.0, 1.0, 0.5, 0.0, 0.25, 0.25, 0.125, 0.0];
        for (got, want) in s.iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{s:?}");
        }
        // A triangle over many sensels against counting 64 × 64 points per sensel; the
        // shares sum to its area where it lies on the grid.
        let tri = [[0.3, -2.0], [7.9, 3.1], [1.2, 5.7]];
        let (rows, cols) = (6, 7);
        let s = polygon_coverage(&tri, rows, cols);
        let k = 64;
        for r in 0..rows {
            for c in 0..cols {
                let mut inside = 0;
                for i in 0..k {
                    for j in 0..k {
                        let x = c as f64 - 0.5 + (j as f64 + 0.5) / k as f64;
                        let y = r as f64 - 0.5 + (i as f64 + 0.5) / k as f64;
                        inside += usize::from(crate::contour::point_in_polygon([x, y], &tri));
                    }
                }
                let oracle = inside as f64 / (k * k) as f64;
                let got = s[r * cols + c];
                assert!((got - oracle).abs() < 0.01, "({r}, {c}): {got} vs {oracle}");
            }
        }
        assert!(polygon_coverage(&[[0.0, 0.0], [1.0, 1.0]], 3, 3)
            .iter()
            .all(|&v| v == 0.0));
        assert!(
            polygon_coverage(&[[-9.0, 0.0], [-5.0, 0.0], [-7.0, 2.0]], 3, 3)
                .iter()
                .all(|&v| v == 0.0)
        );
    }

    #[test]
    fn whole_shares_measure_as_the_mask_does_and_half_a_sensel_counts_half() {
        #[rustfmt::skip]
        let rows = vec![
            vec![0.0, 1.0, 1.0, 0.0],
            vec![0.0, 1.0, 1.0, 0.0],
            vec![0.0, 0.0, 1.0, 0.0],
        ];
        let m = LabelMask::of_rows(&rows).unwrap();
        let values: Vec<f32> = (0..12).map(|i| i as f32).collect();
        let rec = Recording::new(1, 3, 4, values, vec![true; 12]).unwrap();
        let grid = rec.frame(0).unwrap();
        let shares = polygon_coverage(&m.outline(1), 3, 4);
        assert_eq!(
            shares,
            m.cells(1)
                .iter()
                .map(|&c| f64::from(u8::from(c)))
                .collect::<Vec<_>>()
        );
        let whole = rec.cells_measures(&grid, 0.0, &m.cells(1));
        let covered = rec.covered_measures(&grid, 0.0, &shares);
        assert_eq!(whole.contact_sensors, covered.contact_sensors);
        assert!((whole.total_force - covered.total_force).abs() < 1e-4);
        assert_eq!(whole.peak_pressure, covered.peak_pressure);
        // Half of sensel (0, 3) (value 3) and a quarter of (1, 3) (value 7) more.
        let mut more = shares.clone();
        more[3] = 0.5;
        more[7] = 0.25;
        let m2 = rec.covered_measures(&grid, 0.0, &more);
        assert!((m2.total_force - (whole.total_force + 1.5 + 1.75)).abs() < 1e-4);
        assert!((m2.contact_area - (whole.contact_area + 0.75)).abs() < 1e-4);
        // Half covered counts to the peak, a quarter does not.
        assert_eq!(m2.peak_pressure, whole.peak_pressure.max(3.0));
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
