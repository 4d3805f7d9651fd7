//! Preprocessing of a frame: noise threshold, Gaussian smoothing, upsampling of coarse grids.

use crate::error::{IoError, Result};
use crate::grid::Grid;

/// Interpolation used by [`upsample`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Bilinear: piecewise linear along rows and columns; never overshoots.
    #[default]
    Bilinear,
    /// Bicubic convolution (Keys, a = −0.5): smoother, may overshoot slightly near steep edges.
    Bicubic,
}

/// The preprocessing chain, applied in the order threshold → smoothing → upsampling.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Preprocess {
    /// Values strictly below this are set to 0 (noise removal, docs/method.md §8.1).
    pub threshold: Option<f64>,
    /// Gaussian smoothing with this σ in pixels of the input grid (0 or `None`: no smoothing).
    pub sigma: Option<f64>,
    /// Upsampling by an integer factor ≥ 1 (1 or `None`: none).
    pub upsample: Option<(usize, Interpolation)>,
}

impl Preprocess {
    /// Whether each value of the result depends on its own sensel only (no smoothing, no
    /// upsampling; a threshold is per sensel): then the chain on a window of a frame that is 0
    /// outside it gives that part of the chain on the whole frame.
    pub fn is_per_sensel(&self) -> bool {
        self.sigma.is_none_or(|s| s == 0.0) && self.upsample.is_none_or(|(f, _)| f == 1)
    }

    /// Applies the chain; returns the processed grid and the upsampling factor (output pixels
    /// per input pixel), needed to map coordinates back to input pixels.
    pub fn apply(&self, grid: &Grid) -> Result<(Grid, usize)> {
        let mut g = match self.threshold {
            Some(t) => threshold(grid, t)?,
            None => grid.clone(),
        };
        if let Some(s) = self.sigma
            && s != 0.0
        {
            g = gaussian(&g, s)?;
        }
        let mut k = 1;
        if let Some((f, interp)) = self.upsample
            && f != 1
        {
            g = upsample(&g, f, interp)?;
            k = f;
        }
        Ok((g, k))
    }
}

/// Sets values strictly below `t` to 0.
pub fn threshold(grid: &Grid, t: f64) -> Result<Grid> {
    if !t.is_finite() {
        return Err(IoError::invalid(format!(
            "threshold must be finite, got {t}"
        )));
    }
    let mut g = grid.clone();
    for v in g.data_mut() {
        if *v < t {
            *v = 0.0;
        }
    }
    Ok(g)
}

fn kernel(sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil().max(1.0) as usize;
    let mut k: Vec<f64> = (0..=2 * r)
        .map(|i| {
            let x = i as f64 - r as f64;
            (-0.5 * x * x / (sigma * sigma)).exp()
        })
        .collect();
    let s: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    k
}

/// Gaussian smoothing with standard deviation `sigma` pixels (kernel radius ⌈3σ⌉), separable.
/// Outside the grid the image is taken as 0 — no pressure beyond the sensor — so the total is
/// preserved up to what spills over the border.
pub fn gaussian(grid: &Grid, sigma: f64) -> Result<Grid> {
    let (rows, cols) = (grid.rows(), grid.cols());
    Grid::new(rows, cols, gaussian_blur(grid.data(), rows, cols, sigma)?)
}

/// [`gaussian`] on a row-major `rows × cols` image of plain values (the footprint
/// registration's image fits use it too): an error unless `sigma` is in (0, 1000] and the image
/// holds `rows × cols` values.
pub fn gaussian_blur(values: &[f64], rows: usize, cols: usize, sigma: f64) -> Result<Vec<f64>> {
    if !(sigma.is_finite() && sigma > 0.0 && sigma <= 1000.0) {
        return Err(IoError::invalid(format!(
            "sigma must be in (0, 1000], got {sigma}"
        )));
    }
    if rows.checked_mul(cols) != Some(values.len()) {
        return Err(IoError::invalid(format!(
            "an image of {rows} x {cols} values holds {}",
            values.len()
        )));
    }
    let k = kernel(sigma);
    let r = (k.len() / 2) as isize;
    let mut tmp = vec![0.0; rows * cols];
    for y in 0..rows {
        for x in 0..cols {
            let mut s = 0.0;
            for (j, w) in k.iter().enumerate() {
                let xx = x as isize + j as isize - r;
                if xx >= 0 && (xx as usize) < cols {
                    s += w * values[y * cols + xx as usize];
                }
            }
            tmp[y * cols + x] = s;
        }
    }
    let mut out = vec![0.0; rows * cols];
    for y in 0..rows {
        for x in 0..cols {
            let mut s = 0.0;
            for (j, w) in k.iter().enumerate() {
                let yy = y as isize + j as isize - r;
                if yy >= 0 && (yy as usize) < rows {
                    s += w * tmp[yy as usize * cols + x];
                }
            }
            out[y * cols + x] = s;
        }
    }
    Ok(out)
}

fn cubic(t: f64) -> [f64; 4] {
    // Keys' cubic convolution weights for samples at offsets -1, 0, 1, 2 (a = -0.5).
    let a = -0.5;
    let w = |x: f64| {
        let x = x.abs();
        if x <= 1.0 {
            (a + 2.0) * x * x * x - (a + 3.0) * x * x + 1.0
        } else if x < 2.0 {
            a * x * x * x - 5.0 * a * x * x + 8.0 * a * x - 4.0 * a
        } else {
            0.0
        }
    };
    [w(1.0 + t), w(t), w(1.0 - t), w(2.0 - t)]
}

/// Samples an upsampled frame may have per sensor a frame may have
/// ([`Limits::frame_sensors`](crate::limits::Limits)): 16, so 16.7 million (134 MB) by default,
/// a 1024 × 1024 frame upsampled 4-fold.
pub const UPSAMPLED_PER_SENSOR: usize = 16;

/// Upsamples by an integer factor `k`: the output has `(rows − 1)·k + 1` × `(cols − 1)·k + 1`
/// samples, output sample `(R, C)` sitting at input position `(R / k, C / k)`, so input samples are
/// kept exactly and coordinates divide by `k` to return to input pixels.
pub fn upsample(grid: &Grid, k: usize, interp: Interpolation) -> Result<Grid> {
    if k == 0 || k > 64 {
        return Err(IoError::invalid(format!(
            "upsampling factor must be in 1..=64, got {k}"
        )));
    }
    let (rows, cols) = (grid.rows(), grid.cols());
    let (ro, co) = ((rows - 1) * k + 1, (cols - 1) * k + 1);
    // Checked before it is allocated: 64-fold on a large plate is thousands of times the frame.
    let most = crate::limits::current()
        .frame_sensors
        .saturating_mul(UPSAMPLED_PER_SENSOR);
    let samples = ro.checked_mul(co).filter(|&n| n <= most).ok_or_else(|| {
        IoError::invalid(format!(
            "upsampling {rows} x {cols} samples by {k} makes {ro} x {co}, more than the {most} \
             an upsampled frame may have; use a smaller factor"
        ))
    })?;
    let mut out = crate::limits::try_with_capacity(samples).ok_or_else(|| {
        IoError::invalid(format!(
            "cannot allocate memory for {ro} x {co} upsampled samples"
        ))
    })?;
    let at = |r: isize, c: isize| {
        grid.get(
            r.clamp(0, rows as isize - 1) as usize,
            c.clamp(0, cols as isize - 1) as usize,
        )
    };
    for y in 0..ro {
        let (y0, ty) = ((y / k) as isize, (y % k) as f64 / k as f64);
        for x in 0..co {
            let (x0, tx) = ((x / k) as isize, (x % k) as f64 / k as f64);
            let v = match interp {
                Interpolation::Bilinear => {
                    let a = at(y0, x0) * (1.0 - tx) + at(y0, x0 + 1) * tx;
                    let b = at(y0 + 1, x0) * (1.0 - tx) + at(y0 + 1, x0 + 1) * tx;
                    a * (1.0 - ty) + b * ty
                }
                Interpolation::Bicubic => {
                    let (wy, wx) = (cubic(ty), cubic(tx));
                    let mut s = 0.0;
                    for (i, wyi) in wy.iter().enumerate() {
                        let mut row = 0.0;
                        for (j, wxj) in wx.iter().enumerate() {
                            row += wxj * at(y0 + i as isize - 1, x0 + j as isize - 1);
                        }
                        s += wyi * row;
                    }
                    s
                }
            };
            out.push(v);
        }
    }
    Grid::new(ro, co, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_blur_keeps_a_central_mass_and_refuses_bad_widths_and_sizes() {
        // A unit impulse in the middle of a 15 × 15 image: the blur sums to 1 (nothing spills
        // over the border at σ = 1), is symmetric, and peaks where the impulse was.
        let mut values = vec![0.0; 225];
        values[7 * 15 + 7] = 1.0;
        let out = gaussian_blur(&values, 15, 15, 1.0).unwrap();
        assert!((out.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert_eq!(out[7 * 15 + 6], out[7 * 15 + 8]);
        assert_eq!(out[6 * 15 + 7], out[7 * 15 + 6]);
        let peak = out.iter().copied().fold(f64::MIN, f64::max);
        assert_eq!(out[7 * 15 + 7], peak);
        for sigma in [0.0, -1.0, f64::NAN, f64::INFINITY, 1000.5] {
            let err = gaussian_blur(&values, 15, 15, sigma).unwrap_err();
            assert!(
                err.to_string().contains("sigma must be in (0, 1000]"),
                "{err}"
            );
        }
        let err = gaussian_blur(&values, 15, 14, 1.0).unwrap_err();
        assert!(err.to_string().contains("15 x 14"), "{err}");
    }

    /// A 6 × 7 frame, 0 outside rows 2..4 and columns 1..4, and that window of it.
    fn frame_and_window() -> (Grid, Grid) {
        let mut data = vec![0.0; 42];
        for (k, (r, c)) in [(2, 1), (2, 2), (2, 3), (3, 1), (3, 2), (3, 3)]
            .into_iter()
            .enumerate()
        {
            data[r * 7 + c] = 1.0 + k as f64;
        }
        let window = (2..4)
            .flat_map(|r| (1..4).map(move |c| (r, c)))
            .map(|(r, c)| data[r * 7 + c])
            .collect();
        (
            Grid::new(6, 7, data).unwrap(),
            Grid::new(2, 3, window).unwrap(),
        )
    }

    #[test]
    fn a_per_sensel_chain_on_a_window_is_the_chain_on_the_frame() {
        let (frame, window) = frame_and_window();
        let per_sensel = Preprocess {
            threshold: Some(2.5),
            sigma: Some(0.0),
            upsample: Some((1, Interpolation::Bilinear)),
        };
        assert!(per_sensel.is_per_sensel());
        let (whole, _) = per_sensel.apply(&frame).unwrap();
        let (part, _) = per_sensel.apply(&window).unwrap();
        for (r, c) in (0..2).flat_map(|r| (0..3).map(move |c| (r, c))) {
            assert_eq!(part.get(r, c), whole.get(r + 2, c + 1));
        }
        // Smoothing reaches past the window: the frame's result is not 0 outside it.
        let smoothing = Preprocess {
            sigma: Some(1.0),
            ..per_sensel
        };
        assert!(!smoothing.is_per_sensel());
        assert!(smoothing.apply(&frame).unwrap().0.get(1, 2) > 0.0);
        let upsampling = Preprocess {
            upsample: Some((2, Interpolation::Bilinear)),
            ..per_sensel
        };
        assert!(!upsampling.is_per_sensel());
    }
}
