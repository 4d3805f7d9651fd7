//! A single 2-D scalar image in `f64`, row-major, and the coordinate convention of the crate.
//!
//! # Coordinates
//!
//! Every point this crate returns is `(x, y)` with **x = column index** and **y = row index**, in
//! pixel (sensel) units, the centre of sensel `(row r, column c)` being at `(c, r)`. Row 0 is the
//! first row stored in the file. This is scikit-image's `(row, col)` swapped into `(x, y)` order.
//! Because y grows downwards in the file's picture, a contour that is counter-clockwise in `(x, y)`
//! (positive shoelace area, as returned here) looks clockwise when the image is drawn with row 0 at
//! the top. Millimetres are available through [`CoordUnits::Millimetres`], which multiplies x by
//! the column pitch and y by the row pitch (the origin stays at the centre of sensel (0, 0)).

use crate::error::{IoError, Result};

/// Pixel or physical coordinates of produced objects.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum CoordUnits {
    /// x = column index, y = row index (sensel centres at integers).
    #[default]
    Pixels,
    /// x = column index × column pitch, y = row index × row pitch, in mm.
    Millimetres {
        /// Column pitch: millimetres between the centres of horizontally adjacent sensels
        /// (finite, > 0).
        dx_mm: f64,
        /// Row pitch: millimetres between the centres of vertically adjacent sensels
        /// (finite, > 0).
        dy_mm: f64,
    },
}

impl CoordUnits {
    /// Converts a pixel-unit point `[x, y]` into these units (no check of the pitch: the
    /// functions that take a `CoordUnits` reject a pitch that is not finite and positive).
    ///
    /// ```
    /// use pedo_io::CoordUnits;
    /// let mm = CoordUnits::Millimetres { dx_mm: 5.08, dy_mm: 7.62 };
    /// assert_eq!(mm.apply([2.0, 1.0]), [10.16, 7.62]);
    /// assert_eq!(CoordUnits::Pixels.apply([2.0, 1.0]), [2.0, 1.0]);
    /// ```
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        match *self {
            CoordUnits::Pixels => p,
            CoordUnits::Millimetres { dx_mm, dy_mm } => [p[0] * dx_mm, p[1] * dy_mm],
        }
    }
    pub(crate) fn check(&self) -> Result<()> {
        if let CoordUnits::Millimetres { dx_mm, dy_mm } = *self
            && !(dx_mm.is_finite() && dy_mm.is_finite() && dx_mm > 0.0 && dy_mm > 0.0)
        {
            return Err(IoError::invalid(format!(
                "pitch must be positive and finite, got ({dx_mm}, {dy_mm})"
            )));
        }
        Ok(())
    }
}

/// A rows × cols image of finite `f64` values, row-major (`data[r * cols + c]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Grid {
    /// Builds a grid from `rows × cols` row-major values; every value must be finite (map "no
    /// sensor" to 0 before, see [`crate::Recording::frame`]).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `rows` or `cols` is 0, when `data` does not hold exactly
    /// `rows × cols` values, or when a value is NaN or infinite (the message names its row and
    /// column, 0-based).
    ///
    /// ```
    /// use pedo_io::Grid;
    /// let g = Grid::new(2, 3, vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
    /// assert_eq!(g.get(1, 0), 3.0); // row 1, column 0
    /// assert!(Grid::new(2, 3, vec![0.0; 5]).is_err());
    /// assert!(Grid::new(1, 1, vec![f64::NAN]).is_err());
    /// ```
    pub fn new(rows: usize, cols: usize, data: Vec<f64>) -> Result<Self> {
        if rows == 0 || cols == 0 {
            return Err(IoError::invalid(format!("empty grid {rows}x{cols}")));
        }
        if rows.checked_mul(cols) != Some(data.len()) {
            return Err(IoError::invalid(format!(
                "grid {rows}x{cols} needs {} values, got {}",
                rows.saturating_mul(cols),
                data.len()
            )));
        }
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(IoError::invalid(format!(
                "value at row {}, column {} is not finite ({})",
                i / cols,
                i % cols,
                data[i]
            )));
        }
        Ok(Self { rows, cols, data })
    }

    /// A `rows × cols` grid of zeros; an empty size is refused as by [`Grid::new`].
    pub fn zeros(rows: usize, cols: usize) -> Result<Self> {
        let len = rows.checked_mul(cols).ok_or_else(|| {
            IoError::invalid(format!("grid {rows}x{cols} is larger than memory can hold"))
        })?;
        Self::new(rows, cols, vec![0.0; len])
    }

    /// Builds a grid from `f32` values, mapping NaN (no sensor) to 0 and rejecting infinities.
    pub fn from_f32_nan_as_zero(rows: usize, cols: usize, data: &[f32]) -> Result<Self> {
        Self::new(
            rows,
            cols,
            data.iter()
                .map(|&v| if v.is_nan() { 0.0 } else { v as f64 })
                .collect(),
        )
    }

    /// Number of rows (the y extent; at least 1 for a grid from [`Grid::new`]).
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// Number of columns (the x extent; at least 1 for a grid from [`Grid::new`]).
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// Row-major values.
    pub fn data(&self) -> &[f64] {
        &self.data
    }
    pub(crate) fn data_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }
    /// Value at (row, column); panics out of range like slice indexing.
    #[inline]
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.data[r * self.cols + c]
    }
    /// Largest value.
    pub fn max(&self) -> f64 {
        self.data.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }
    /// Smallest value.
    pub fn min(&self) -> f64 {
        self.data.iter().copied().fold(f64::INFINITY, f64::min)
    }
    /// Smallest strictly positive value, if any.
    pub fn min_positive(&self) -> Option<f64> {
        self.data
            .iter()
            .copied()
            .filter(|&v| v > 0.0)
            .reduce(f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_or_impossible_size_is_refused_by_every_constructor() {
        for (rows, cols) in [(0, 4), (4, 0), (0, 0)] {
            let msg = Grid::zeros(rows, cols).unwrap_err().to_string();
            assert!(msg.contains(&format!("empty grid {rows}x{cols}")), "{msg}");
            assert!(Grid::new(rows, cols, Vec::new()).is_err());
        }
        let msg = Grid::zeros(usize::MAX, 2).unwrap_err().to_string();
        assert!(msg.contains("larger than memory"), "{msg}");
        let g = Grid::zeros(2, 3).unwrap();
        assert_eq!((g.rows(), g.cols(), g.max()), (2, 3, 0.0));
    }
}
