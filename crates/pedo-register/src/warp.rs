//! The non-rigid intensity step after the outline's field and the rigid correction: a cubic
//! B-spline displacement of the trial's plane (free-form deformation, Rueckert et al. 1999),
//! its control points on a grid of `spacing` sensels over the template's grid, fitted by
//! Levenberg–Marquardt to the mean squared difference of the peak images with a bending
//! penalty on the control grid, coarse images first (blurred), then as they are. A step that
//! would fold the map (a sensel's Jacobian determinant below a quarter of the map's before the
//! warp) is refused as a step that does not lower the cost.
//!
//! The outline fixes the footprint's shape and the rigid step where the pressure lies; this
//! step moves the pressure pattern inside the footprint (the toes, the metatarsal heads) onto the
//! template's, which a global map cannot.

use crate::band::Band;
use crate::refine::{blurred, GridImage};

/// How the warp is fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarpSettings {
    /// Spacing of the control points, in template sensels.
    pub spacing: f64,
    /// Weight of the bending penalty, relative to the template's mean squared value.
    pub smoothing: f64,
    /// Gaussian blurs of the stages, coarse to fine (sensels; 0: the images as they are).
    pub blurs: [f64; 2],
    /// Levenberg–Marquardt iterations per stage, at most.
    pub iterations: usize,
    /// Spacing of a last, finer stage on the images as they are, after the stages of `blurs`
    /// (0: none): the coarse lattice brings the pattern near, the fine one fits the detail.
    pub fine_spacing: f64,
    /// Weight of the bending penalty of the fine stage (as `smoothing`).
    pub fine_smoothing: f64,
    /// Levenberg–Marquardt iterations of the fine stage, at most.
    pub fine_iterations: usize,
    /// Weight of the footprints' masks (1 inside, 0 outside) beside the pressures, relative to
    /// the template's mean squared value: keeps the edges together while the pressures move.
    pub mask_weight: f64,
}

/// The damping of a stage's first Levenberg–Marquardt step: damped enough to step along the
/// gradient (a first Gauss–Newton step of the whole lattice may jump into another basin of the
/// pressures; on the tuning pairs, 1e-3 fitted the between-subject pairs worse, 718 against 695
/// kPa² mean squared difference), lowered by each step that helps.
const FIRST_DAMPING: f64 = 0.1;

/// A stage stops once a step lowers the penalised cost by less than this fraction: the last
/// steps of a stage lower it by hundredths of a percent each, and the steps that fail to (every
/// damping tried) cost a factorisation each.
const STOP_GAIN: f64 = 1e-3;

/// The images the warp compares: the peak images and, when weighted, the footprints' masks.
#[derive(Debug, Clone, Copy)]
pub struct WarpImages<'a> {
    /// The template's peak image.
    pub template: GridImage<'a>,
    /// The trial's peak image.
    pub trial: GridImage<'a>,
    /// The template's footprint as 0/1 on its grid.
    pub template_mask: &'a [f64],
    /// The trial's footprint as 0/1 on its grid.
    pub trial_mask: &'a [f64],
}

/// The cubic B-spline basis at `t ∈ [0, 1)`: the weights of the four control points around.
fn basis(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ]
}

/// The control grid: `nx × ny` points, point `(i, j)` at `((i − 1) s, (j − 1) s)`, so that every
/// template sensel has its four-by-four support inside the grid.
struct Lattice {
    spacing: f64,
    nx: usize,
    ny: usize,
}

impl Lattice {
    fn new(rows: usize, cols: usize, spacing: f64) -> Self {
        let n = |len: usize| ((len.max(2) - 1) as f64 / spacing).floor() as usize + 4;
        Self {
            spacing,
            nx: n(cols),
            ny: n(rows),
        }
    }

    fn len(&self) -> usize {
        self.nx * self.ny
    }

    /// The first of the four control columns (or rows) around the coordinate `x` and their
    /// weights.
    fn axis(&self, x: f64) -> (usize, [f64; 4]) {
        let u = x / self.spacing;
        let i0 = u.floor().max(0.0);
        (i0 as usize, basis(u - i0))
    }

    /// The 16 control points (index) and weights of the template point `(x, y)`.
    fn support(&self, x: f64, y: f64) -> [(usize, f64); 16] {
        let ((i0, bx), (j0, by)) = (self.axis(x), self.axis(y));
        let mut out = [(0, 0.0); 16];
        for (b, wy) in by.iter().enumerate() {
            for (a, wx) in bx.iter().enumerate() {
                let (i, j) = ((i0 + a).min(self.nx - 1), (j0 + b).min(self.ny - 1));
                out[b * 4 + a] = (j * self.nx + i, wx * wy);
            }
        }
        out
    }

    /// The second-difference stencils of the bending penalty, along rows and along columns:
    /// `Σ ‖θ_a − 2 θ_b + θ_c‖²` over them is the penalty of each displacement component.
    fn stencils(&self) -> Vec<[usize; 3]> {
        let nx = self.nx;
        let mut out = Vec::new();
        for j in 0..self.ny {
            for i in 1..nx.saturating_sub(1) {
                out.push([j * nx + i - 1, j * nx + i, j * nx + i + 1]);
            }
        }
        for j in 1..self.ny.saturating_sub(1) {
            for i in 0..nx {
                out.push([(j - 1) * nx + i, j * nx + i, (j + 1) * nx + i]);
            }
        }
        out
    }

    /// The super-diagonals of the normal matrix with the unknowns interleaved (`x` then `y` of
    /// each control point): two control points share a sensel only within three rows and three
    /// columns of each other.
    fn band_width(&self) -> usize {
        2 * (3 * self.nx + 3) + 1
    }
}

/// The bending penalty `Σ ‖second differences‖²` of the interleaved displacements `theta`, and
/// its half-gradient `R θ`.
fn bending(stencils: &[[usize; 3]], theta: &[f64]) -> (f64, Vec<f64>) {
    const W: [f64; 3] = [1.0, -2.0, 1.0];
    let mut grad = vec![0.0; theta.len()];
    let mut value = 0.0;
    for s in stencils {
        for c in 0..2 {
            let d: f64 = s.iter().zip(W).map(|(&k, w)| w * theta[2 * k + c]).sum();
            value += d * d;
            for (&k, w) in s.iter().zip(W) {
                grad[2 * k + c] += w * d;
            }
        }
    }
    (value, grad)
}

/// `R` of [`bending`] times `alpha`, added to the band.
fn add_bending(band: &mut Band, stencils: &[[usize; 3]], alpha: f64) {
    const W: [f64; 3] = [1.0, -2.0, 1.0];
    for s in stencils {
        for (p, &a) in s.iter().enumerate() {
            for (q, &b) in s.iter().enumerate() {
                if a <= b {
                    let v = alpha * W[p] * W[q];
                    band.add(2 * a, 2 * b, v);
                    band.add(2 * a + 1, 2 * b + 1, v);
                }
            }
        }
    }
}

/// The four sensels of an image grid around a point (`None` beyond the grid, read as 0) and the
/// point's place between them: the bilinear interpolation of every channel sampled at one point
/// (the same arithmetic as `footprint::bilinear` and `refine::bilinear_grad`, the corners found
/// once).
struct Cell {
    idx: [Option<usize>; 4],
    fx: f64,
    fy: f64,
}

impl Cell {
    fn at(rows: usize, cols: usize, x: f64, y: f64) -> Self {
        if !(x.is_finite() && y.is_finite()) {
            return Self {
                idx: [None; 4],
                fx: 0.0,
                fy: 0.0,
            };
        }
        let (x0, y0) = (x.floor(), y.floor());
        let id = |r: f64, c: f64| {
            (r >= 0.0 && c >= 0.0 && r < rows as f64 && c < cols as f64)
                .then(|| r as usize * cols + c as usize)
        };
        Self {
            idx: [
                id(y0, x0),
                id(y0, x0 + 1.0),
                id(y0 + 1.0, x0),
                id(y0 + 1.0, x0 + 1.0),
            ],
            fx: x - x0,
            fy: y - y0,
        }
    }

    fn corners(&self, v: &[f64]) -> [f64; 4] {
        self.idx.map(|i| i.map_or(0.0, |i| v[i]))
    }

    fn value(&self, v: &[f64]) -> f64 {
        let ([v00, v01, v10, v11], fx, fy) = (self.corners(v), self.fx, self.fy);
        (1.0 - fy) * ((1.0 - fx) * v00 + fx * v01) + fy * ((1.0 - fx) * v10 + fx * v11)
    }

    /// The value and its gradient `(v, ∂v/∂x, ∂v/∂y)`.
    fn value_grad(&self, v: &[f64]) -> (f64, f64, f64) {
        let ([v00, v01, v10, v11], fx, fy) = (self.corners(v), self.fx, self.fy);
        let value = (1.0 - fy) * ((1.0 - fx) * v00 + fx * v01) + fy * ((1.0 - fx) * v10 + fx * v11);
        let gx = (1.0 - fy) * (v01 - v00) + fy * (v11 - v10);
        let gy = (1.0 - fx) * (v10 - v00) + fx * (v11 - v01);
        (value, gx, gy)
    }
}

/// One image pair the warp fits: the template's values, the trial's, and the weight of its mean
/// squared difference.
struct Channel {
    tpl: Vec<f64>,
    img: Vec<f64>,
    weight: f64,
}

/// The images and the points the warp starts from.
struct Problem<'a> {
    /// Template sensel `i`'s image in the trial's plane before the warp.
    base: &'a [[f64; 2]],
    supports: Vec<[(usize, f64); 16]>,
    /// Each template column's first control column and weights, and each row's.
    col_axes: Vec<(usize, [f64; 4])>,
    row_axes: Vec<(usize, [f64; 4])>,
    /// Control points per lattice row.
    nx: usize,
    /// Control points of the lattice.
    unknowns: usize,
    channels: Vec<Channel>,
    rows: usize,
    cols: usize,
    /// Each template sensel's Jacobian determinant before the warp (sensels with a right and a
    /// lower neighbour).
    base_det: Vec<f64>,
    grid_cols: usize,
    grid_rows: usize,
}

impl Problem<'_> {
    /// The points moved by the interleaved control displacements `theta`.
    fn moved(&self, theta: &[f64]) -> Vec<[f64; 2]> {
        self.base
            .iter()
            .zip(&self.supports)
            .map(|(b, s)| {
                let (mut dx, mut dy) = (0.0, 0.0);
                for &(k, w) in s {
                    dx += w * theta[2 * k];
                    dy += w * theta[2 * k + 1];
                }
                [b[0] + dx, b[1] + dy]
            })
            .collect()
    }

    fn data_cost(&self, at: &[[f64; 2]]) -> f64 {
        let n = at.len().max(1) as f64;
        let mut sums = [0.0; 2];
        for (i, q) in at.iter().enumerate() {
            let cell = Cell::at(self.rows, self.cols, q[0], q[1]);
            for (sum, ch) in sums.iter_mut().zip(&self.channels) {
                *sum += (cell.value(&ch.img) - ch.tpl[i]).powi(2);
            }
        }
        self.channels
            .iter()
            .zip(sums)
            .map(|(ch, sum)| ch.weight * sum / n)
            .sum()
    }

    /// Whether the map `at` keeps every sensel's Jacobian determinant above a quarter of its
    /// value before the warp (no fold, no collapse).
    fn unfolded(&self, at: &[[f64; 2]]) -> bool {
        determinants(at, self.grid_rows, self.grid_cols)
            .iter()
            .zip(&self.base_det)
            .all(|(d, b)| *d > 0.25 * b.max(1e-6))
    }
}

/// The Jacobian determinant of the map `at` (template sensel → trial point) at every sensel with
/// a right and a lower neighbour, by forward differences.
fn determinants(at: &[[f64; 2]], rows: usize, cols: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(rows.saturating_sub(1) * cols.saturating_sub(1));
    for r in 0..rows.saturating_sub(1) {
        for c in 0..cols.saturating_sub(1) {
            let (p, px, py) = (
                at[r * cols + c],
                at[r * cols + c + 1],
                at[(r + 1) * cols + c],
            );
            let (a, b) = (px[0] - p[0], py[0] - p[0]);
            let (cc, d) = (px[1] - p[1], py[1] - p[1]);
            out.push(a * d - b * cc);
        }
    }
    out
}

/// The template's sensels (`template`'s grid, row-major) carried to `base` in the trial's plane,
/// moved further by the fitted B-spline warp: the points to sample the trial's images at. `base`
/// itself when no step lowers the cost.
pub fn refine_warp(
    base: &[[f64; 2]],
    images: &WarpImages<'_>,
    settings: &WarpSettings,
) -> Vec<[f64; 2]> {
    let mut at = base.to_vec();
    let t = images.template;
    if settings.spacing.is_nan() || settings.spacing <= 0.0 || base.len() != t.rows * t.cols {
        return at;
    }
    for &sigma in &settings.blurs {
        let stage = (settings.spacing, settings.smoothing, settings.iterations);
        at = warp_stage(&at, images, sigma, stage, settings);
    }
    if settings.fine_spacing > 0.0 && settings.fine_spacing < settings.spacing {
        let stage = (
            settings.fine_spacing,
            settings.fine_smoothing,
            settings.fine_iterations,
        );
        at = warp_stage(&at, images, 0.0, stage, settings);
    }
    at
}

fn warp_stage(
    base: &[[f64; 2]],
    images: &WarpImages<'_>,
    sigma: f64,
    (spacing, smoothing, iterations): (f64, f64, usize),
    settings: &WarpSettings,
) -> Vec<[f64; 2]> {
    let (template, trial) = (images.template, images.trial);
    let (rows, cols) = (template.rows, template.cols);
    let lattice = Lattice::new(rows, cols, spacing);
    let n = lattice.len();
    let supports = (0..rows * cols)
        .map(|i| lattice.support((i % cols) as f64, (i / cols) as f64))
        .collect();
    let tpl = blurred(template, sigma);
    // The weights in the data's units: the template's mean squared value.
    let scale = (tpl.iter().map(|v| v * v).sum::<f64>() / tpl.len().max(1) as f64).max(1e-12);
    let mut channels = vec![Channel {
        tpl,
        img: blurred(trial, sigma),
        weight: 1.0,
    }];
    if settings.mask_weight > 0.0 && images.trial_mask.len() == trial.values.len() {
        let g = |im: GridImage<'_>, v| GridImage { values: v, ..im };
        channels.push(Channel {
            tpl: blurred(g(template, images.template_mask), sigma),
            img: blurred(g(trial, images.trial_mask), sigma),
            weight: settings.mask_weight * scale,
        });
    }
    let p = Problem {
        base,
        supports,
        col_axes: (0..cols).map(|x| lattice.axis(x as f64)).collect(),
        row_axes: (0..rows).map(|y| lattice.axis(y as f64)).collect(),
        nx: lattice.nx,
        unknowns: n,
        channels,
        rows: trial.rows,
        cols: trial.cols,
        base_det: determinants(base, rows, cols),
        grid_cols: cols,
        grid_rows: rows,
    };
    let alpha = smoothing * scale;
    let stencils = lattice.stencils();
    let mut theta = vec![0.0; 2 * n];
    let mut at = base.to_vec();
    let mut current = p.data_cost(&at);
    let mut lambda = FIRST_DAMPING;
    for _ in 0..iterations {
        let (mut normal, mut gradient) = normal_equations(&p, &at, lattice.band_width());
        add_bending(&mut normal, &stencils, alpha);
        let (bent, rtheta) = bending(&stencils, &theta);
        for (g, r) in gradient.iter_mut().zip(&rtheta) {
            *g += alpha * r;
        }
        let before = current + alpha * bent;
        let mut improved = false;
        for _ in 0..6 {
            let Some(step) = damped_step(&normal, &gradient, lambda) else {
                lambda *= 10.0;
                continue;
            };
            let next: Vec<f64> = theta.iter().zip(&step).map(|(a, b)| a + b).collect();
            let moved = p.moved(&next);
            let data = p.data_cost(&moved);
            let after = data + alpha * bending(&stencils, &next).0;
            if after < before && p.unfolded(&moved) {
                current = data;
                theta = next;
                at = moved;
                lambda = (lambda / 3.0).max(1e-9);
                improved = true;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
        if before - (current + alpha * bending(&stencils, &theta).0) < STOP_GAIN * before {
            break;
        }
    }
    at
}

/// `JᵀJ / N` and `Jᵀr / N` of the data term at the points `at`, the unknowns the control
/// displacements interleaved (`x`, `y` of control point 0, then of 1, …), `JᵀJ` as a band.
/// Each sensel's Jacobian is its image gradient times its 16 B-spline weights, so its share of
/// `JᵀJ` is the 2 × 2 gradient product (summed over the channels) times the weights' outer
/// product. The weights are a column factor times a row factor, and every sensel of one lattice
/// cell has the same 16 control points: the products are summed along each row of a cell first
/// (4 × 4 column weights), then over the cell's rows (16 × 16), and added to the band once per
/// cell: several times fewer operations than the 16 × 16 products of every sensel.
fn normal_equations(p: &Problem<'_>, at: &[[f64; 2]], width: usize) -> (Band, Vec<f64>) {
    let m = 2 * p.unknowns;
    let mut jtr = vec![0.0; m];
    let inv = 1.0 / at.len().max(1) as f64;
    let mut g2s = vec![[0.0; 3]; at.len()];
    for (i, (q, s)) in at.iter().zip(&p.supports).enumerate() {
        // [gx², gx gy, gy²] and [gx r, gy r], each weighted, over the channels.
        let (mut g2, mut gr) = ([0.0; 3], [0.0; 2]);
        let cell = Cell::at(p.rows, p.cols, q[0], q[1]);
        for ch in &p.channels {
            let (v, gx, gy) = cell.value_grad(&ch.img);
            let (w, r) = (ch.weight * inv, v - ch.tpl[i]);
            g2 = [
                g2[0] + w * gx * gx,
                g2[1] + w * gx * gy,
                g2[2] + w * gy * gy,
            ];
            gr = [gr[0] + w * gx * r, gr[1] + w * gy * r];
        }
        if g2 == [0.0; 3] {
            continue;
        }
        g2s[i] = g2;
        for &(c, w) in s {
            jtr[2 * c] += w * gr[0];
            jtr[2 * c + 1] += w * gr[1];
        }
    }
    (cell_products(p, &g2s, width), jtr)
}

/// `JᵀJ / N` from each sensel's weighted gradient products `g2s`, cell by cell.
fn cell_products(p: &Problem<'_>, g2s: &[[f64; 3]], width: usize) -> Band {
    let mut jtj = Band::zeros(2 * p.unknowns, width);
    let cols = p.col_axes.len();
    // Runs of template columns (rows) sharing their first control column (row): the cells.
    let runs = |axes: &[(usize, [f64; 4])]| -> Vec<(usize, std::ops::Range<usize>)> {
        let mut out: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
        for (k, (first, _)) in axes.iter().enumerate() {
            match out.last_mut() {
                Some((f, r)) if f == first => r.end = k + 1,
                _ => out.push((*first, k..k + 1)),
            }
        }
        out
    };
    let (col_runs, row_runs) = (runs(&p.col_axes), runs(&p.row_axes));
    for (j0, ys) in &row_runs {
        for (i0, xs) in &col_runs {
            // cell[a][b][k], a = 4 r + c: control point (i0 + c, j0 + r).
            let mut cell = [[[0.0; 3]; 16]; 16];
            let mut any = false;
            for y in ys.clone() {
                let mut sx = [[[0.0; 3]; 4]; 4];
                let mut row_any = false;
                for x in xs.clone() {
                    let g = g2s[y * cols + x];
                    if g == [0.0; 3] {
                        continue;
                    }
                    row_any = true;
                    let bx = p.col_axes[x].1;
                    for (c, sc) in sx.iter_mut().enumerate() {
                        for (d, scd) in sc.iter_mut().enumerate() {
                            let w = bx[c] * bx[d];
                            for k in 0..3 {
                                scd[k] += w * g[k];
                            }
                        }
                    }
                }
                if !row_any {
                    continue;
                }
                any = true;
                let by = p.row_axes[y].1;
                for a in 0..16 {
                    for b in a..16 {
                        let w = by[a / 4] * by[b / 4];
                        let v = sx[a % 4][b % 4];
                        for k in 0..3 {
                            cell[a][b][k] += w * v[k];
                        }
                    }
                }
            }
            if any {
                add_cell(&mut jtj, &cell, p.nx, (*i0, *j0));
            }
        }
    }
    jtj
}

/// A cell's 16 × 16 products (upper half, `a ≤ b`) added to the band: its control points
/// `(i0 + a % 4, j0 + a / 4)` are distinct (the lattice extends three points beyond the grid).
fn add_cell(jtj: &mut Band, cell: &[[[f64; 3]; 16]; 16], nx: usize, (i0, j0): (usize, usize)) {
    let index = |a: usize| (j0 + a / 4) * nx + i0 + a % 4;
    for (a, row) in cell.iter().enumerate() {
        for (b, &g2) in row.iter().enumerate().skip(a) {
            let (ca, cb) = (index(a), index(b));
            if a == b {
                jtj.add(2 * ca, 2 * ca, g2[0]);
                jtj.add(2 * ca, 2 * ca + 1, g2[1]);
                jtj.add(2 * ca + 1, 2 * ca + 1, g2[2]);
            } else {
                // cb > ca: the index grows with a's row, then its column.
                jtj.add(2 * ca, 2 * cb, g2[0]);
                jtj.add(2 * ca, 2 * cb + 1, g2[1]);
                jtj.add(2 * ca + 1, 2 * cb, g2[1]);
                jtj.add(2 * ca + 1, 2 * cb + 1, g2[2]);
            }
        }
    }
}

/// The Levenberg–Marquardt step `−(A + damping)⁻¹ g` of the penalised problem (`A` its normal
/// matrix with the bending, `g` its gradient), or `None` when the damped matrix is not positive
/// definite.
fn damped_step(normal: &Band, gradient: &[f64], lambda: f64) -> Option<Vec<f64>> {
    let mut a = normal.clone();
    // The damping on the diagonal, with a floor so that control points no sensel sees (beyond
    // the footprint) stay where they are.
    let floor = 1e-6
        * (0..a.len())
            .map(|i| a.diagonal(i))
            .fold(0.0, f64::max)
            .max(1e-12);
    for i in 0..a.len() {
        let d = a.diagonal(i);
        a.add(i, i, lambda * d.max(floor) + floor);
    }
    let minus: Vec<f64> = gradient.iter().map(|g| -g).collect();
    let step = a.cholesky()?.solve(&minus);
    step.iter().all(|v| v.is_finite()).then_some(step)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_basis_is_a_partition_of_unity() {
        for t in [0.0, 0.25, 0.5, 0.9] {
            let b = basis(t);
            assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(b.iter().all(|w| *w >= 0.0));
        }
    }

    /// A blob bent non-rigidly (its top half shifted sideways) is brought back closer than the
    /// identity leaves it, without a fold.
    #[test]
    fn a_locally_shifted_pattern_is_brought_back() {
        let (rows, cols) = (40, 24);
        let blobs = |shift: f64| -> Vec<f64> {
            (0..rows * cols)
                .map(|i| {
                    let (x, y) = ((i % cols) as f64, (i / cols) as f64);
                    let top =
                        100.0 * (-((x - 9.0 - shift).powi(2) + (y - 10.0).powi(2)) / 8.0).exp();
                    let heel = 80.0 * (-((x - 12.0).powi(2) + (y - 30.0).powi(2)) / 10.0).exp();
                    top + heel
                })
                .collect()
        };
        let (tpl, trial) = (blobs(0.0), blobs(2.5));
        let base: Vec<[f64; 2]> = (0..rows * cols)
            .map(|i| [(i % cols) as f64, (i / cols) as f64])
            .collect();
        fn gi(rows: usize, cols: usize, values: &[f64]) -> GridImage<'_> {
            GridImage { rows, cols, values }
        }
        let settings = WarpSettings {
            spacing: 6.0,
            smoothing: 1e-4,
            blurs: [1.5, 0.0],
            iterations: 20,
            fine_spacing: 0.0,
            fine_smoothing: 0.0,
            fine_iterations: 0,
            mask_weight: 0.0,
        };
        let images = WarpImages {
            template: gi(rows, cols, &tpl),
            trial: gi(rows, cols, &trial),
            template_mask: &[],
            trial_mask: &[],
        };
        let at = refine_warp(&base, &images, &settings);
        let mse = |pts: &[[f64; 2]]| -> f64 {
            pts.iter()
                .zip(&tpl)
                .map(|(q, v)| {
                    (crate::footprint::bilinear(&trial, rows, cols, q[0], q[1]) - v).powi(2)
                })
                .sum::<f64>()
                / pts.len() as f64
        };
        let (before, after) = (mse(&base), mse(&at));
        assert!(after < 0.1 * before, "MSE {before:.2} -> {after:.2}");
        // The top blob's centre moves by about the shift, the heel's hardly.
        let top = at[10 * cols + 9];
        let heel = at[30 * cols + 12];
        assert!((top[0] - 11.5).abs() < 0.5, "{top:?}");
        assert!(
            (heel[0] - 12.0).abs() < 0.5 && (heel[1] - 30.0).abs() < 0.5,
            "{heel:?}"
        );
        assert!(determinants(&at, rows, cols).iter().all(|d| *d > 0.0));
    }
}
