//! Closed contours of a frame: sub-pixel marching squares (default) or the paper's chain
//! (threshold, smoothing, Sobel edge enhancement, hysteresis, boundary tracking).
//!
//! Every contour is closed (the last point joins the first, which is not repeated),
//! counter-clockwise in `(x, y)` (positive shoelace area; see [`crate::grid`] for why it looks
//! clockwise on a picture drawn with row 0 on top), and optionally resampled.

use crate::error::{IoError, Result};
use crate::grid::{CoordUnits, Grid};
use crate::preprocess::{self, Preprocess};
use modal_core::{Shape, Topology};

/// How marching squares resolves a saddle cell (two diagonal corners above the level).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Saddle {
    /// Values below the level are fully (8-) connected: diagonal blobs stay separate contours.
    /// Same as `skimage.measure.find_contours(fully_connected="low")`, its default.
    #[default]
    LowConnected,
    /// Values above the level are fully connected: diagonal blobs join.
    HighConnected,
    /// Decide per cell by the mean of its four corners (joined when the mean is above the level).
    Average,
}

/// The contour extraction method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContourMethod {
    /// Sub-pixel marching squares at the level (linear interpolation along cell edges).
    MarchingSquares {
        /// How a saddle cell is resolved.
        saddle: Saddle,
    },
    /// The paper's chain: regions by hysteresis (seeds above `high`, grown through pixels above the
    /// level, 8-connected), Moore tracing of each region's outer boundary, and, if `refine`, each
    /// boundary pixel moved along the gradient to the peak of the Sobel gradient magnitude (the
    /// edge-enhancement step) with a parabolic fit, at most one pixel.
    Chain {
        /// Hysteresis seed level, in the frame's pressure units (`None`: twice the contour
        /// level); a region is kept only if some value in it is above this.
        high: Option<f64>,
        /// Move each boundary pixel to the gradient's peak (sub-pixel edge); off: contours run
        /// through the centres of the region's boundary sensels.
        refine: bool,
    },
}

impl Default for ContourMethod {
    fn default() -> Self {
        ContourMethod::MarchingSquares {
            saddle: Saddle::LowConnected,
        }
    }
}

/// Resampling of each contour.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Resample {
    /// Keep the points the method produced.
    #[default]
    None,
    /// Exactly this many points, uniform in arc length (at least 3).
    Points(usize),
    /// Uniform arc length with about this spacing (in output units), at least 3 points.
    Spacing(f64),
}

/// Options of [`contours`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContourOptions {
    /// Contour level. `None`: half the smallest positive value of the (thresholded) frame, i.e.
    /// the contact boundary halfway between an unloaded and the least-loaded sensel.
    pub level: Option<f64>,
    /// Threshold, smoothing and upsampling applied before extraction. Coordinates are always
    /// returned in pixels of the original frame, whatever the upsampling.
    pub preprocess: Preprocess,
    /// How contours are extracted.
    pub method: ContourMethod,
    /// How each contour is resampled; a spacing is in output units ([`units`](Self::units)).
    pub resample: Resample,
    /// Contours enclosing less than this area (px², before unit conversion) are dropped.
    pub min_area: f64,
    /// Keep contours around holes (regions below the level inside a region above it).
    pub include_holes: bool,
    /// Units of the returned points (pixels, or millimetres by the sensor pitch).
    pub units: CoordUnits,
}

impl Default for ContourOptions {
    fn default() -> Self {
        Self {
            level: None,
            preprocess: Preprocess::default(),
            method: ContourMethod::default(),
            resample: Resample::None,
            min_area: 0.0,
            include_holes: true,
            units: CoordUnits::Pixels,
        }
    }
}

/// One closed contour.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    /// Points, counter-clockwise, not repeating the first at the end.
    pub points: Vec<[f64; 2]>,
    /// True when the contour bounds a hole (the region inside is below the level).
    pub hole: bool,
    /// The level it was extracted at.
    pub level: f64,
}

impl Contour {
    /// Enclosed area (positive).
    pub fn area(&self) -> f64 {
        signed_area(&self.points).abs()
    }
    /// Perimeter of the closed polygon.
    pub fn perimeter(&self) -> f64 {
        perimeter(&self.points)
    }
    /// Area centroid.
    pub fn centroid(&self) -> [f64; 2] {
        centroid(&self.points)
    }
    /// As a modal-core shape (dimension 2, `Topology::ClosedContour`).
    pub fn to_shape(&self) -> Result<Shape> {
        Ok(Shape::from_points_2d(
            &self.points,
            Topology::ClosedContour,
        )?)
    }
    /// As a 3-D modal-core shape `(x, y, level)` (isobaric contours in 3-D).
    pub fn to_shape_3d(&self) -> Result<Shape> {
        let p: Vec<[f64; 3]> = self
            .points
            .iter()
            .map(|q| [q[0], q[1], self.level])
            .collect();
        Ok(Shape::from_points_3d(&p, Topology::ClosedContour)?)
    }
}

/// Shoelace signed area (positive = counter-clockwise in (x, y)).
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    let mut s = 0.0;
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        s += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * s
}

fn perimeter(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n).map(|i| dist(p[i], p[(i + 1) % n])).sum()
}

fn centroid(p: &[[f64; 2]]) -> [f64; 2] {
    let n = p.len();
    let a = signed_area(p);
    if n == 0 {
        return [0.0, 0.0];
    }
    if a.abs() < 1e-300 {
        let m = p.iter().fold([0.0, 0.0], |s, q| [s[0] + q[0], s[1] + q[1]]);
        return [m[0] / n as f64, m[1] / n as f64];
    }
    let (mut cx, mut cy) = (0.0, 0.0);
    for i in 0..n {
        let (u, v) = (p[i], p[(i + 1) % n]);
        let c = u[0] * v[1] - v[0] * u[1];
        cx += (u[0] + v[0]) * c;
        cy += (u[1] + v[1]) * c;
    }
    [cx / (6.0 * a), cy / (6.0 * a)]
}

#[inline]
fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// Point-in-polygon (even-odd rule).
pub fn point_in_polygon(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Resamples a closed polygon to `n ≥ 3` points uniform in arc length, starting at its first point.
pub fn resample_closed(p: &[[f64; 2]], n: usize) -> Result<Vec<[f64; 2]>> {
    if n < 3 {
        return Err(IoError::invalid(format!(
            "resampling needs at least 3 points, got {n}"
        )));
    }
    let m = p.len();
    let total = perimeter(p);
    if m < 2 || total.is_nan() || total <= 0.0 {
        return Err(IoError::invalid(
            "cannot resample a contour of zero length".to_string(),
        ));
    }
    let mut out = Vec::with_capacity(n);
    let (mut seg, mut acc) = (0usize, 0.0);
    let mut len = dist(p[0], p[1 % m]);
    for k in 0..n {
        let s = total * k as f64 / n as f64;
        while acc + len < s && seg < m - 1 {
            acc += len;
            seg += 1;
            len = dist(p[seg], p[(seg + 1) % m]);
        }
        let t = if len > 0.0 {
            ((s - acc) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (p[seg], p[(seg + 1) % m]);
        out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
    }
    Ok(out)
}

/// Resamples to about `spacing` between consecutive points (at least 3 points).
pub fn resample_spacing(p: &[[f64; 2]], spacing: f64) -> Result<Vec<[f64; 2]>> {
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(IoError::invalid(format!(
            "spacing must be positive, got {spacing}"
        )));
    }
    let n = (perimeter(p) / spacing).round().max(3.0);
    if n > 1e7 {
        return Err(IoError::invalid(format!(
            "spacing {spacing} gives too many points"
        )));
    }
    resample_closed(p, n as usize)
}

// ---------------------------------------------------------------------------------------------
// Marching squares

/// Oriented segments per cell case (bits tl=1, tr=2, bl=4, br=8), edges T=0, R=1, B=2, L=3, each
/// segment running with the region above the level on its left in (x, y).
fn segments(case: u8, saddle_high: bool) -> &'static [(u8, u8)] {
    const T: u8 = 0;
    const R: u8 = 1;
    const B: u8 = 2;
    const L: u8 = 3;
    match case {
        1 => &[(T, L)],
        2 => &[(R, T)],
        3 => &[(R, L)],
        4 => &[(L, B)],
        5 => &[(T, B)],
        6 if saddle_high => &[(L, T), (R, B)],
        6 => &[(R, T), (L, B)],
        7 => &[(R, B)],
        8 => &[(B, R)],
        9 if saddle_high => &[(T, R), (B, L)],
        9 => &[(T, L), (B, R)],
        10 => &[(B, T)],
        11 => &[(B, L)],
        12 => &[(L, R)],
        13 => &[(T, R)],
        14 => &[(L, T)],
        _ => &[],
    }
}

/// Marching squares on `grid` at `level`, the grid surrounded by a ring that is below the level
/// (0 when the level is positive), so every contour closes. Points in grid pixel coordinates.
pub fn marching_squares(grid: &Grid, level: f64, saddle: Saddle) -> Result<Vec<Contour>> {
    marching_squares_at(grid, level, saddle, (0, 0))
}

/// [`marching_squares`] of a window of a larger grid whose first row and column are `origin`
/// there: the points are those of the larger grid, bit for bit, when the level is positive and
/// the larger grid is 0 around the window.
fn marching_squares_at(
    grid: &Grid,
    level: f64,
    saddle: Saddle,
    origin: (usize, usize),
) -> Result<Vec<Contour>> {
    if !level.is_finite() {
        return Err(IoError::invalid(format!(
            "level must be finite, got {level}"
        )));
    }
    let (rows, cols) = (grid.rows(), grid.cols());
    let (h, w) = (rows + 2, cols + 2);
    let pad = if level > 0.0 { 0.0 } else { level - 1.0 };
    let val = |i: usize, j: usize| -> f64 {
        if i == 0 || j == 0 || i == h - 1 || j == w - 1 {
            pad
        } else {
            grid.get(i - 1, j - 1)
        }
    };
    let frac = |a: f64, b: f64| if a == b { 0.0 } else { (level - a) / (b - a) };
    // Only the cells touching a value above the level cross it (the padding is below it): the
    // cells walked and the edges keyed are those of the window around such values, so that a
    // frame of a few loaded sensels on a large plate costs its window, not the plate.
    let Some(((r0, c0), (r1, c1))) = above_bounds(grid, level) else {
        return Ok(Vec::new());
    };
    // Cells (i, j) of the padded grid with i in r0..=r1 + 1, j in c0..=c1 + 1; their corners
    // in rows r0..=r1 + 2, columns c0..=c1 + 2, numbered from (r0, c0) in a width `kw`.
    let (kh, kw) = (r1 - r0 + 3, c1 - c0 + 3);
    // Edge keys: horizontal edge from (i, j) to (i, j+1) = 2(i w + j); vertical (i, j)-(i+1, j) = +1.
    let key_of = |i: usize, j: usize, e: u8| -> usize {
        let (i, j) = (i - r0, j - c0);
        match e {
            0 => 2 * (i * kw + j),
            2 => 2 * ((i + 1) * kw + j),
            3 => 2 * (i * kw + j) + 1,
            _ => 2 * (i * kw + j + 1) + 1,
        }
    };
    let point_of = |key: usize| -> [f64; 2] {
        let (cell, vert) = (key / 2, key % 2 == 1);
        let (i, j) = (cell / kw + r0, cell % kw + c0);
        let (y, x) = ((i + origin.0) as f64 - 1.0, (j + origin.1) as f64 - 1.0);
        if vert {
            let t = frac(val(i, j), val(i + 1, j));
            [x, y + t]
        } else {
            let t = frac(val(i, j), val(i, j + 1));
            [x + t, y]
        }
    };
    // Two edges per cell: a grid larger than memory allows is an error, not an abort (a
    // recording's frames are within `limits::MAX_FRAME_SENSORS`, an upsampled one may not be).
    let too_large = || {
        IoError::invalid(format!(
            "a grid of {rows} x {cols} is too large for its contours in memory"
        ))
    };
    let nkeys = kh
        .checked_mul(kw)
        .and_then(|n| n.checked_mul(2))
        .ok_or_else(too_large)?;
    let mut next = crate::limits::try_filled(nkeys, usize::MAX).ok_or_else(too_large)?;
    let mut starts = Vec::new();
    for i in r0..=r1 + 1 {
        for j in c0..=c1 + 1 {
            let (tl, tr, bl, br) = (val(i, j), val(i, j + 1), val(i + 1, j), val(i + 1, j + 1));
            let case = u8::from(tl > level)
                | u8::from(tr > level) << 1
                | u8::from(bl > level) << 2
                | u8::from(br > level) << 3;
            if case == 0 || case == 15 {
                continue;
            }
            let high = match saddle {
                Saddle::LowConnected => false,
                Saddle::HighConnected => true,
                Saddle::Average => (tl + tr + bl + br) / 4.0 > level,
            };
            for &(a, b) in segments(case, high) {
                let (ka, kb) = (key_of(i, j, a), key_of(i, j, b));
                next[ka] = kb;
                starts.push(ka);
            }
        }
    }
    let mut seen = crate::limits::try_filled(nkeys, false).ok_or_else(too_large)?;
    let mut out = Vec::new();
    for &s in &starts {
        if seen[s] {
            continue;
        }
        let mut pts: Vec<[f64; 2]> = Vec::new();
        let mut k = s;
        while !seen[k] {
            seen[k] = true;
            let p = point_of(k);
            if pts.last().is_none_or(|q| dist(*q, p) > 1e-12) {
                pts.push(p);
            }
            k = next[k];
            if k == usize::MAX {
                return Err(IoError::invalid(
                    "internal error: open marching-squares contour".to_string(),
                ));
            }
        }
        while pts.len() > 1 && dist(pts[0], *pts.last().expect("non-empty")) <= 1e-12 {
            pts.pop();
        }
        if pts.len() < 3 {
            continue;
        }
        let a = signed_area(&pts);
        let hole = a < 0.0;
        if hole {
            pts.reverse();
        }
        out.push(Contour {
            points: pts,
            hole,
            level,
        });
    }
    Ok(out)
}

/// The first and last row and column of `grid` holding a value above `level`, if any.
fn above_bounds(grid: &Grid, level: f64) -> Option<((usize, usize), (usize, usize))> {
    let cols = grid.cols();
    let mut rows_above = (0..grid.rows()).filter(|&r| {
        let row = &grid.data()[r * cols..(r + 1) * cols];
        row.iter().any(|&v| v > level)
    });
    let r0 = rows_above.next()?;
    let r1 = rows_above.next_back().unwrap_or(r0);
    let (mut c0, mut c1) = (cols, 0);
    for r in r0..=r1 {
        let row = &grid.data()[r * cols..(r + 1) * cols];
        if let Some(first) = row.iter().position(|&v| v > level) {
            c0 = c0.min(first);
            c1 = c1.max(row.iter().rposition(|&v| v > level).unwrap_or(first));
        }
    }
    Some(((r0, c0), (r1, c1)))
}

// ---------------------------------------------------------------------------------------------
// The paper's chain

const DIRS: [(isize, isize); 8] = [
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
];

fn sobel(g: &Grid) -> (Vec<f64>, Vec<f64>) {
    let (rows, cols) = (g.rows() as isize, g.cols() as isize);
    let at = |r: isize, c: isize| {
        if r < 0 || c < 0 || r >= rows || c >= cols {
            0.0
        } else {
            g.get(r as usize, c as usize)
        }
    };
    let mut gx = vec![0.0; (rows * cols) as usize];
    let mut gy = gx.clone();
    for r in 0..rows {
        for c in 0..cols {
            let i = (r * cols + c) as usize;
            gx[i] = (at(r - 1, c + 1) + 2.0 * at(r, c + 1) + at(r + 1, c + 1))
                - (at(r - 1, c - 1) + 2.0 * at(r, c - 1) + at(r + 1, c - 1));
            gy[i] = (at(r + 1, c - 1) + 2.0 * at(r + 1, c) + at(r + 1, c + 1))
                - (at(r - 1, c - 1) + 2.0 * at(r - 1, c) + at(r - 1, c + 1));
        }
    }
    (gx, gy)
}

fn bilinear(v: &[f64], rows: usize, cols: usize, x: f64, y: f64) -> f64 {
    if !(x >= 0.0 && y >= 0.0 && x <= (cols - 1) as f64 && y <= (rows - 1) as f64) {
        return 0.0;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(cols - 1), (y0 + 1).min(rows - 1));
    let (tx, ty) = (x - x0 as f64, y - y0 as f64);
    let a = v[y0 * cols + x0] * (1.0 - tx) + v[y0 * cols + x1] * tx;
    let b = v[y1 * cols + x0] * (1.0 - tx) + v[y1 * cols + x1] * tx;
    a * (1.0 - ty) + b * ty
}

/// The paper's chain on an already preprocessed grid (see [`ContourMethod::Chain`]).
pub fn chain_contours(g: &Grid, low: f64, high: f64, refine: bool) -> Result<Vec<Contour>> {
    if !(low.is_finite() && high.is_finite()) {
        return Err(IoError::invalid(
            "hysteresis thresholds must be finite".to_string(),
        ));
    }
    let (rows, cols) = (g.rows(), g.cols());
    let (label, components) = hysteresis_components(g, low, high);
    let edges = refine.then(|| EdgeStrength::new(g));
    let mut out = Vec::new();
    for (id, &(strong, s)) in components.iter().enumerate() {
        if !strong {
            continue;
        }
        let inside = |r: isize, c: isize| {
            r >= 0
                && c >= 0
                && (r as usize) < rows
                && (c as usize) < cols
                && label[r as usize * cols + c as usize] == id
        };
        let chain = moore_trace(
            ((s / cols) as isize, (s % cols) as isize),
            rows * cols,
            inside,
        );
        let mut pts: Vec<[f64; 2]> = chain.iter().map(|&(r, c)| [c as f64, r as f64]).collect();
        if pts.len() < 3 {
            continue;
        }
        if let Some(edges) = &edges {
            pts.iter_mut().for_each(|q| edges.move_to_edge(q));
        }
        if signed_area(&pts) < 0.0 {
            pts.reverse();
        }
        if signed_area(&pts).abs() <= 0.0 {
            continue;
        }
        out.push(Contour {
            points: pts,
            hole: false,
            level: low,
        });
    }
    Ok(out)
}

/// Hysteresis: the 8-connected components of the sensels above `low`, each sensel's component
/// (`usize::MAX` for none) and, per component, whether it holds a value above `high` and its
/// first sensel in raster order.
fn hysteresis_components(g: &Grid, low: f64, high: f64) -> (Vec<usize>, Vec<(bool, usize)>) {
    let (rows, cols) = (g.rows(), g.cols());
    let fg: Vec<bool> = g.data().iter().map(|&v| v > low).collect();
    let mut label = vec![usize::MAX; rows * cols];
    let mut components = Vec::new();
    let mut stack = Vec::new();
    for s in 0..rows * cols {
        if !fg[s] || label[s] != usize::MAX {
            continue;
        }
        let id = components.len();
        let mut strong = false;
        label[s] = id;
        stack.push(s);
        while let Some(p) = stack.pop() {
            strong |= g.data()[p] > high;
            let (r, c) = ((p / cols) as isize, (p % cols) as isize);
            for (dx, dy) in DIRS {
                let (rr, cc) = (r + dy, c + dx);
                if rr >= 0 && cc >= 0 && (rr as usize) < rows && (cc as usize) < cols {
                    let q = rr as usize * cols + cc as usize;
                    if fg[q] && label[q] == usize::MAX {
                        label[q] = id;
                        stack.push(q);
                    }
                }
            }
        }
        components.push((strong, s));
    }
    (label, components)
}

/// Moore-neighbour tracing of the component `inside` says holds a (row, column), from its first
/// sensel in raster order, `start`, whose west neighbour is outside; stops when the first move
/// repeats (Jacob's criterion). `cells` (the grid's size) bounds the walk.
fn moore_trace(
    start: (isize, isize),
    cells: usize,
    inside: impl Fn(isize, isize) -> bool,
) -> Vec<(isize, isize)> {
    let mut p = start;
    let mut back = 0usize;
    let mut chain = vec![p];
    let mut first_move: Option<(isize, isize)> = None;
    for _ in 0..4 * cells + 16 {
        let found = (1..=8).find_map(|k| {
            let d = (back + k) % 8;
            let q = (p.0 + DIRS[d].1, p.1 + DIRS[d].0);
            inside(q.0, q.1).then_some((q, (back + k - 1) % 8))
        });
        let Some((q, prev)) = found else { break };
        if p == start {
            if first_move == Some(q) {
                break;
            }
            first_move.get_or_insert(q);
        }
        let bpos = (p.0 + DIRS[prev].1, p.1 + DIRS[prev].0);
        let delta = (bpos.1 - q.1, bpos.0 - q.0);
        back = DIRS.iter().position(|&d| d == delta).unwrap_or(0);
        p = q;
        chain.push(p);
    }
    if chain.last() == Some(&start) {
        chain.pop();
    }
    chain
}

/// The Sobel gradient of a grid and its magnitude, to move chain points onto the edge.
struct EdgeStrength {
    gx: Vec<f64>,
    gy: Vec<f64>,
    mag: Vec<f64>,
    rows: usize,
    cols: usize,
}

impl EdgeStrength {
    fn new(g: &Grid) -> Self {
        let (gx, gy) = sobel(g);
        let mag = gx
            .iter()
            .zip(&gy)
            .map(|(a, b)| (a * a + b * b).sqrt())
            .collect();
        Self {
            gx,
            gy,
            mag,
            rows: g.rows(),
            cols: g.cols(),
        }
    }

    /// Moves sensel centre `q` along the gradient to the parabola-fitted maximum of the gradient
    /// magnitude, at most one sensel away.
    fn move_to_edge(&self, q: &mut [f64; 2]) {
        let i = q[1] as usize * self.cols + q[0] as usize;
        let m = self.mag[i];
        if m <= 0.0 {
            return;
        }
        let n = [self.gx[i] / m, self.gy[i] / m];
        let f = |t: f64| {
            bilinear(
                &self.mag,
                self.rows,
                self.cols,
                q[0] + t * n[0],
                q[1] + t * n[1],
            )
        };
        let (a, b, c) = (f(-1.0), m, f(1.0));
        let den = a - 2.0 * b + c;
        if den < 0.0 {
            let d = (0.5 * (a - c) / den).clamp(-1.0, 1.0);
            *q = [q[0] + d * n[0], q[1] + d * n[1]];
        }
    }
}

/// The default level: half the smallest positive value of `g` (`None` if nothing is positive).
pub fn default_level(g: &Grid) -> Option<f64> {
    g.min_positive().map(|m| 0.5 * m)
}

/// Extracts the closed contours of a frame (see [`ContourOptions`]). A frame with nothing above
/// the level has no contours (an empty vector, not an error).
///
/// # Errors
///
/// [`IoError::InvalidInput`] for options out of range: a pitch that is not finite and positive,
/// a negative or non-finite `min_area`, a level or threshold that is not finite, a smoothing σ
/// that is negative, not finite or above 1000, an upsampling factor outside 1..=64, or a
/// resampling to fewer than 3 points or at a spacing that is not positive.
///
/// ```
/// use pedo_io::{contours, ContourOptions, Grid};
/// // A 3 × 3 loaded block (10 kPa) in a 5 × 5 frame, sensel centres at integer (x, y).
/// let mut data = vec![0.0; 25];
/// for r in 1..4 {
///     for c in 1..4 {
///         data[r * 5 + c] = 10.0;
///     }
/// }
/// let frame = Grid::new(5, 5, data)?;
/// let cs = contours(&frame, &ContourOptions::default())?;
/// assert_eq!(cs.len(), 1);
/// // The default level is 5 kPa, halfway between unloaded and loaded sensels: the outline runs
/// // half a sensel outside the block's centres, its corners cut diagonally.
/// assert_eq!(cs[0].level, 5.0);
/// assert!((cs[0].area() - 8.5).abs() < 1e-12);
/// assert_eq!(cs[0].centroid(), [2.0, 2.0]);
/// assert!(!cs[0].hole);
/// # Ok::<(), pedo_io::IoError>(())
/// ```
pub fn contours(frame: &Grid, opts: &ContourOptions) -> Result<Vec<Contour>> {
    contours_at(frame, (0, 0), opts)
}

/// Whether [`contours_of_window`] gives a frame's contours with these options: marching
/// squares at a positive level, without smoothing or upsampling (which reach past a window).
pub fn window_gives_contours(opts: &ContourOptions) -> bool {
    matches!(opts.method, ContourMethod::MarchingSquares { .. })
        && opts.level.is_none_or(|l| l > 0.0)
        && opts.preprocess.is_per_sensel()
}

/// The [`contours`] of a frame that is 0 outside `window`, whose first row and column are
/// `origin` in the frame: the same contours, bit for bit, at the cost of the window, when
/// [`window_gives_contours`] (an error otherwise).
///
/// # Errors
///
/// As [`contours`]; [`IoError::InvalidInput`] when the options reach past a window.
pub fn contours_of_window(
    window: &Grid,
    origin: (usize, usize),
    opts: &ContourOptions,
) -> Result<Vec<Contour>> {
    if !window_gives_contours(opts) {
        return Err(IoError::invalid(
            "these contour options reach past a window of the frame (smoothing, upsampling, \
             the chain method or a level at or below 0)",
        ));
    }
    contours_at(window, origin, opts)
}

fn contours_at(
    frame: &Grid,
    origin: (usize, usize),
    opts: &ContourOptions,
) -> Result<Vec<Contour>> {
    opts.units.check()?;
    if !(opts.min_area.is_finite() && opts.min_area >= 0.0) {
        return Err(IoError::invalid(format!(
            "min_area must be >= 0, got {}",
            opts.min_area
        )));
    }
    let level = match opts.level {
        Some(l) => l,
        None => {
            let base = match opts.preprocess.threshold {
                Some(t) => preprocess::threshold(frame, t)?,
                None => frame.clone(),
            };
            match default_level(&base) {
                Some(l) => l,
                None => return Ok(Vec::new()),
            }
        }
    };
    let (g, k) = opts.preprocess.apply(frame)?;
    let mut cs = match opts.method {
        ContourMethod::MarchingSquares { saddle } => {
            marching_squares_at(&g, level, saddle, origin)?
        }
        ContourMethod::Chain { high, refine } => {
            let high = high.unwrap_or(2.0 * level);
            chain_contours(&g, level, high, refine)?
        }
    };
    let inv = 1.0 / k as f64;
    let kk = (k * k) as f64;
    cs.retain(|c| (opts.include_holes || !c.hole) && c.area() / kk >= opts.min_area);
    for c in cs.iter_mut() {
        if k != 1 {
            c.points
                .iter_mut()
                .for_each(|p| *p = [p[0] * inv, p[1] * inv]);
        }
        if opts.units != CoordUnits::Pixels {
            c.points.iter_mut().for_each(|p| *p = opts.units.apply(*p));
        }
        c.points = match opts.resample {
            Resample::None => std::mem::take(&mut c.points),
            Resample::Points(n) => resample_closed(&c.points, n)?,
            Resample::Spacing(s) => resample_spacing(&c.points, s)?,
        };
    }
    Ok(cs)
}

/// [`contours`] as modal-core shapes (dimension 2, `Topology::ClosedContour`).
pub fn contour_shapes(frame: &Grid, opts: &ContourOptions) -> Result<Vec<Shape>> {
    contours(frame, opts)?
        .iter()
        .map(Contour::to_shape)
        .collect()
}

/// [`contours`] as plain point lists.
pub fn contour_points(frame: &Grid, opts: &ContourOptions) -> Result<Vec<Vec<[f64; 2]>>> {
    Ok(contours(frame, opts)?
        .into_iter()
        .map(|c| c.points)
        .collect())
}
