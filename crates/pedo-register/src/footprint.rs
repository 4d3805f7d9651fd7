//! A footprint's whole-foot outline: the sensels ever loaded, their convex hull (holes filled,
//! toes and heel joined), resampled to evenly spaced nodes; and the bilinear sampling of an
//! image at any point of its plane.
//!
//! Coordinates are those of the image's grid: `x` the column, `y` the row, in sensels, the
//! centre of sensel `(r, c)` at `(c, r)`.

use pedo_io::{IoError, Result};

/// The sensels of `values` (`rows × cols`, row-major) loaded above `threshold` (NaN is no load).
pub fn loaded_mask(values: &[f64], threshold: f64) -> Vec<bool> {
    values.iter().map(|&v| v > threshold).collect()
}

/// The convex hull of every loaded sensel of `mask` (each sensel a unit square around its
/// centre), counter-clockwise in `(x, y)`, without repeated points.
///
/// # Errors
/// [`IoError::NoObject`] when fewer than 3 sensels are loaded or they all lie on one line.
pub fn hull_of_mask(mask: &[bool], rows: usize, cols: usize) -> Result<Vec<[f64; 2]>> {
    let loaded = mask.iter().filter(|&&m| m).count();
    if loaded < 3 {
        return Err(IoError::no_object(format!(
            "the footprint has {} (a whole-foot outline needs at least 3)",
            pedo_io::counted(loaded, "loaded sensel")
        )));
    }
    // Per row, the corners of its first and last loaded sensel: every other corner of the row
    // lies between them.
    let mut pts: Vec<[f64; 2]> = Vec::new();
    for r in 0..rows {
        let row = &mask[r * cols..(r + 1) * cols];
        let (Some(first), Some(last)) = (row.iter().position(|&m| m), row.iter().rposition(|&m| m))
        else {
            continue;
        };
        let (y0, y1) = (r as f64 - 0.5, r as f64 + 0.5);
        for x in [first as f64 - 0.5, last as f64 + 0.5] {
            pts.push([x, y0]);
            pts.push([x, y1]);
        }
    }
    let hull = convex_hull(pts);
    if hull.len() < 3 || polygon_area(&hull) < 1.0 {
        return Err(IoError::no_object(
            "the footprint's loaded sensels enclose no area".to_string(),
        ));
    }
    Ok(hull)
}

/// Andrew's monotone chain: the convex hull, counter-clockwise, collinear points dropped.
fn convex_hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut lower: Vec<[f64; 2]> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<[f64; 2]> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// The area of a simple polygon (absolute value of the shoelace sum).
pub fn polygon_area(p: &[[f64; 2]]) -> f64 {
    pedo_io::contour::signed_area(p).abs()
}

/// The distance from `q` to the closed polygon `poly` (its edges).
pub fn distance_to_polygon(q: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let mut best = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 {
            (((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (px, py) = (a[0] + t * dx - q[0], a[1] + t * dy - q[1]);
        best = best.min((px * px + py * py).sqrt());
    }
    best
}

/// The bilinear interpolation of `values` (`rows × cols`, row-major; NaN read as 0) at `(x, y)`
/// (column, row), 0 beyond the grid (a plate reads no pressure outside itself).
pub fn bilinear(values: &[f64], rows: usize, cols: usize, x: f64, y: f64) -> f64 {
    if !(x.is_finite() && y.is_finite()) {
        return 0.0;
    }
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |r: f64, c: f64| -> f64 {
        if r < 0.0 || c < 0.0 || r >= rows as f64 || c >= cols as f64 {
            return 0.0;
        }
        let v = values[r as usize * cols + c as usize];
        if v.is_nan() {
            0.0
        } else {
            v
        }
    };
    (1.0 - fy) * ((1.0 - fx) * at(y0, x0) + fx * at(y0, x0 + 1.0))
        + fy * ((1.0 - fx) * at(y0 + 1.0, x0) + fx * at(y0 + 1.0, x0 + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_an_l_covers_its_corner_sensels() {
        // An L of 3 × 3 sensels: the hull is the triangle-cut square of the squares' corners.
        let mask = [true, false, false, true, false, false, true, true, true];
        let hull = hull_of_mask(&mask, 3, 3).unwrap();
        // Corners of the sensel squares: (-0.5, -0.5), (0.5, -0.5), (2.5, 1.5), (2.5, 2.5),
        // (-0.5, 2.5): area 9 - the cut triangle (2 × 2 / 2) = 7.
        assert!((polygon_area(&hull) - 7.0).abs() < 1e-12, "{hull:?}");
        assert!(pedo_io::contour::signed_area(&hull) > 0.0);
    }

    #[test]
    fn too_few_sensels_is_no_object() {
        let mask = [true, false, false, true];
        assert!(matches!(
            hull_of_mask(&mask, 2, 2),
            Err(IoError::NoObject(_))
        ));
        assert!(matches!(
            hull_of_mask(&[true, true, true], 1, 3),
            Ok(h) if h.len() == 4
        ));
    }

    #[test]
    fn bilinear_matches_hand_values() {
        let v = [0.0, 10.0, 20.0, 30.0];
        assert_eq!(bilinear(&v, 2, 2, 0.5, 0.5), 15.0);
        assert_eq!(bilinear(&v, 2, 2, 1.0, 0.0), 10.0);
        // Half a sensel beyond the last column: halfway to the 0 outside.
        assert_eq!(bilinear(&v, 2, 2, 1.5, 1.0), 15.0);
        assert_eq!(bilinear(&v, 2, 2, -3.0, 0.0), 0.0);
    }

    #[test]
    fn distance_to_unit_square() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!((distance_to_polygon([0.5, 0.25], &sq) - 0.25).abs() < 1e-12);
        assert!((distance_to_polygon([2.0, 0.5], &sq) - 1.0).abs() < 1e-12);
    }
}
