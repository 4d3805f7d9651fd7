//! Isobaric contours (docs/method.md §8.4): level lines at chosen pressures of the same
//! thresholded, smoothed frame the surfaces use, as 2-D `(x, y)` or 3-D `(x, y, level)` point sets.

use crate::contour::{
    marching_squares, resample_closed, resample_spacing, Contour, Resample, Saddle,
};
use crate::error::{IoError, Result};
use crate::grid::{CoordUnits, Grid};
use crate::preprocess::Preprocess;

/// Options of [`isocontours`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IsoOptions {
    /// Threshold, smoothing and upsampling of the frame before the level lines are drawn;
    /// coordinates are returned in pixels of the original frame whatever the upsampling.
    pub preprocess: Preprocess,
    /// How marching squares resolves a saddle cell.
    pub saddle: Saddle,
    /// How each contour is resampled; a spacing is in output units ([`units`](Self::units)).
    pub resample: Resample,
    /// Keep contours around holes (regions below a level inside a region above it).
    pub include_holes: bool,
    /// Units of the returned points (pixels, or millimetres by the sensor pitch).
    pub units: CoordUnits,
}

/// Level lines at each of `levels` (pressure units of the frame); every returned contour carries
/// its level. Contours of a higher level lie inside the region bounded by the contours of any
/// lower level.
pub fn isocontours(frame: &Grid, levels: &[f64], opts: &IsoOptions) -> Result<Vec<Contour>> {
    opts.units.check()?;
    if let Some(l) = levels.iter().find(|l| !l.is_finite()) {
        return Err(IoError::invalid(format!("levels must be finite, got {l}")));
    }
    let (g, k) = opts.preprocess.apply(frame)?;
    let inv = 1.0 / k as f64;
    let mut out = Vec::new();
    for &level in levels {
        for mut c in marching_squares(&g, level, opts.saddle)? {
            if c.hole && !opts.include_holes {
                continue;
            }
            c.points
                .iter_mut()
                .for_each(|p| *p = opts.units.apply([p[0] * inv, p[1] * inv]));
            c.points = match opts.resample {
                Resample::None => c.points,
                Resample::Points(n) => resample_closed(&c.points, n)?,
                Resample::Spacing(s) => resample_spacing(&c.points, s)?,
            };
            out.push(c);
        }
    }
    Ok(out)
}

/// Evenly spaced levels strictly between 0 and the frame's maximum (`n` of them): `max × i /
/// (n + 1)` for `i` in `1..=n`. None when the maximum is not above 0.
///
/// ```
/// use pedo_io::{isobar::even_levels, Grid};
/// let frame = Grid::new(1, 3, vec![0.0, 100.0, 40.0])?;
/// assert_eq!(even_levels(&frame, 3), vec![25.0, 50.0, 75.0]);
/// assert!(even_levels(&Grid::zeros(2, 2)?, 3).is_empty());
/// # Ok::<(), pedo_io::IoError>(())
/// ```
pub fn even_levels(frame: &Grid, n: usize) -> Vec<f64> {
    let m = frame.max();
    if m <= 0.0 {
        return Vec::new();
    }
    (1..=n).map(|i| m * i as f64 / (n + 1) as f64).collect()
}
