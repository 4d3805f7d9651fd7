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

use crate::refine::{blurred, GridImage};
use nalgebra::{DMatrix, DVector};

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
    /// Weight of the footprints' masks (1 inside, 0 outside) beside the pressures, relative to
    /// the template's mean squared value: keeps the edges together while the pressures move.
    pub mask_weight: f64,
}

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

    /// The 16 control points (index) and weights of the template point `(x, y)`.
    fn support(&self, x: f64, y: f64) -> [(usize, f64); 16] {
        let (u, v) = (x / self.spacing, y / self.spacing);
        let (i0, j0) = (u.floor().max(0.0), v.floor().max(0.0));
        let (bx, by) = (basis(u - i0), basis(v - j0));
        let (i0, j0) = (i0 as usize, j0 as usize);
        let mut out = [(0, 0.0); 16];
        for (b, wy) in by.iter().enumerate() {
            for (a, wx) in bx.iter().enumerate() {
                let (i, j) = ((i0 + a).min(self.nx - 1), (j0 + b).min(self.ny - 1));
                out[b * 4 + a] = (j * self.nx + i, wx * wy);
            }
        }
        out
    }

    /// `Σ ‖second differences‖²` of each displacement component along rows and columns, as the
    /// matrix `R` of `θᵀ R θ` over one component's control values.
    fn bending(&self) -> DMatrix<f64> {
        let n = self.len();
        let mut r = DMatrix::zeros(n, n);
        let mut add = |idx: [usize; 3]| {
            let w = [1.0, -2.0, 1.0];
            for (p, &a) in idx.iter().enumerate() {
                for (q, &b) in idx.iter().enumerate() {
                    r[(a, b)] += w[p] * w[q];
                }
            }
        };
        for j in 0..self.ny {
            for i in 1..self.nx.saturating_sub(1) {
                add([j * self.nx + i - 1, j * self.nx + i, j * self.nx + i + 1]);
            }
        }
        for j in 1..self.ny.saturating_sub(1) {
            for i in 0..self.nx {
                add([
                    (j - 1) * self.nx + i,
                    j * self.nx + i,
                    (j + 1) * self.nx + i,
                ]);
            }
        }
        r
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
    fn moved(&self, theta: &[f64], n: usize) -> Vec<[f64; 2]> {
        self.base
            .iter()
            .zip(&self.supports)
            .map(|(b, s)| {
                let (mut dx, mut dy) = (0.0, 0.0);
                for &(k, w) in s {
                    dx += w * theta[k];
                    dy += w * theta[n + k];
                }
                [b[0] + dx, b[1] + dy]
            })
            .collect()
    }

    fn data_cost(&self, at: &[[f64; 2]]) -> f64 {
        let n = at.len().max(1) as f64;
        self.channels
            .iter()
            .map(|ch| {
                ch.weight
                    * at.iter()
                        .zip(&ch.tpl)
                        .map(|(q, t)| {
                            (crate::footprint::bilinear(&ch.img, self.rows, self.cols, q[0], q[1])
                                - t)
                                .powi(2)
                        })
                        .sum::<f64>()
                    / n
            })
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
        at = warp_stage(&at, images, sigma, settings);
    }
    at
}

fn warp_stage(
    base: &[[f64; 2]],
    images: &WarpImages<'_>,
    sigma: f64,
    settings: &WarpSettings,
) -> Vec<[f64; 2]> {
    let (template, trial) = (images.template, images.trial);
    let (rows, cols) = (template.rows, template.cols);
    let lattice = Lattice::new(rows, cols, settings.spacing);
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
        channels,
        rows: trial.rows,
        cols: trial.cols,
        base_det: determinants(base, rows, cols),
        grid_cols: cols,
        grid_rows: rows,
    };
    let alpha = settings.smoothing * scale;
    let bend = lattice.bending();
    let mut theta = vec![0.0; 2 * n];
    let penalty = |th: &[f64]| -> f64 {
        let (x, y) = (
            DVector::from_column_slice(&th[..n]),
            DVector::from_column_slice(&th[n..]),
        );
        alpha * ((&bend * &x).dot(&x) + (&bend * &y).dot(&y))
    };
    let mut at = base.to_vec();
    let mut current = p.data_cost(&at);
    let mut lambda = 1e-3;
    for _ in 0..settings.iterations {
        let (jtj, jtr) = normal_equations(&p, &at, n);
        let mut improved = false;
        for _ in 0..6 {
            let Some(step) = damped_step(&jtj, &jtr, &bend, alpha, lambda, &theta) else {
                lambda *= 10.0;
                continue;
            };
            let next: Vec<f64> = theta.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            let moved = p.moved(&next, n);
            let cost = p.data_cost(&moved) + penalty(&next);
            if cost < current + penalty(&theta) && p.unfolded(&moved) {
                current = cost - penalty(&next);
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
    }
    at
}

/// `JᵀJ / N` and `Jᵀr / N` of the data term at the points `at`, the unknowns the control
/// displacements (`x` of every control point, then `y`).
fn normal_equations(p: &Problem<'_>, at: &[[f64; 2]], n: usize) -> (DMatrix<f64>, DVector<f64>) {
    let m = 2 * n;
    // Row-major in a flat buffer: the inner loop is the hot one of the whole registration.
    let mut jtj = vec![0.0; m * m];
    let mut jtr = vec![0.0; m];
    let inv = 1.0 / at.len().max(1) as f64;
    for ch in &p.channels {
        for ((q, t), s) in at.iter().zip(&ch.tpl).zip(&p.supports) {
            let (v, gx, gy) = crate::refine::bilinear_grad(&ch.img, p.rows, p.cols, q[0], q[1]);
            if gx == 0.0 && gy == 0.0 {
                continue;
            }
            let w = ch.weight * inv;
            let r = v - t;
            let mut idx = [0usize; 32];
            let mut jac = [0.0; 32];
            for (k, &(c, wk)) in s.iter().enumerate() {
                idx[k] = c;
                jac[k] = gx * wk;
                idx[16 + k] = n + c;
                jac[16 + k] = gy * wk;
            }
            for a in 0..32 {
                let ja = w * jac[a];
                jtr[idx[a]] += ja * r;
                let row = &mut jtj[idx[a] * m..(idx[a] + 1) * m];
                for b in 0..32 {
                    row[idx[b]] += ja * jac[b];
                }
            }
        }
    }
    (DMatrix::from_row_slice(m, m, &jtj), DVector::from_vec(jtr))
}

/// The Levenberg–Marquardt step of the penalised problem, or `None` when its matrix is not
/// positive definite.
fn damped_step(
    jtj: &DMatrix<f64>,
    jtr: &DVector<f64>,
    bend: &DMatrix<f64>,
    alpha: f64,
    lambda: f64,
    theta: &[f64],
) -> Option<DVector<f64>> {
    let n = bend.nrows();
    let mut a = jtj.clone();
    let mut g = jtr.clone();
    for c in 0..2 {
        let th = DVector::from_column_slice(&theta[c * n..(c + 1) * n]);
        let bt = bend * th;
        for i in 0..n {
            g[c * n + i] += alpha * bt[i];
            for j in 0..n {
                a[(c * n + i, c * n + j)] += alpha * bend[(i, j)];
            }
        }
    }
    // The damping on the diagonal, with a floor so that control points no sensel sees (beyond
    // the footprint) stay where they are.
    let floor = 1e-6
        * (0..a.nrows())
            .map(|i| a[(i, i)])
            .fold(0.0, f64::max)
            .max(1e-12);
    for i in 0..a.nrows() {
        a[(i, i)] += lambda * a[(i, i)].max(floor) + floor;
    }
    let step = a.cholesky()?.solve(&(-g));
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
