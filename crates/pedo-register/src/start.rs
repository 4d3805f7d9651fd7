//! Where the image fit starts: the outline match's field, and the footprints' principal axes.
//!
//! The whole-foot outline is a convex hull: when the toes of one trial load and those of the
//! other do not, or the heel's edge lies differently, modal matching may slide the outlines along
//! each other and start the correction by the images and the warp in another basin of the
//! pressures (on the tuning pairs, footprints a few sensels from where the masks' moments put
//! them). The second start is the one moment-initialised registrations use (centroids onto each
//! other, the principal axes turned onto each other within the prior, the areas' ratio as
//! scale); each start is corrected by the images and the one that then fits them better is kept.

use crate::Template;
use modal_core::{Affine, CorrespondenceField, MatchPair, Shape, Topology};
use pedo_io::Result;

/// A start of the image fit: the field of the template's plane into the trial's and the affine
/// map it reports.
pub(crate) struct Start {
    pub(crate) field: CorrespondenceField,
    pub(crate) map: Affine,
}

/// Centroid, principal-axis angle (radians, in `(x, y)`) and area of a mask's sensels.
fn moments(mask: &[bool], cols: usize) -> Option<([f64; 2], f64, f64)> {
    let pts: Vec<[f64; 2]> = mask
        .iter()
        .enumerate()
        .filter(|(_, m)| **m)
        .map(|(i, _)| [(i % cols) as f64, (i / cols) as f64])
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let c = [
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    Some((c, 0.5 * (2.0 * sxy).atan2(sxx - syy), n))
}

/// The principal-axes similarity of the template's footprint onto the trial's: centroid onto
/// centroid, scaled by the square root of the areas' ratio, turned by the smaller turn between
/// the two axes when it is within `max_turn` degrees (else not turned: a footprint does not
/// turn heel to toe). `None` when either mask has fewer than 3 sensels.
pub(crate) fn principal_axes(
    template: &[bool],
    trial: &[bool],
    cols: [usize; 2],
    max_turn: f64,
) -> Option<Affine> {
    let (ca, aa, na) = moments(template, cols[0])?;
    let (cb, ab, nb) = moments(trial, cols[1])?;
    let half = std::f64::consts::FRAC_PI_2;
    let mut turn = (ab - aa + half).rem_euclid(std::f64::consts::PI) - half;
    if turn.abs().to_degrees() > max_turn {
        turn = 0.0;
    }
    let s = (nb / na).sqrt();
    let (sin, cos) = turn.sin_cos();
    let m = [[s * cos, -s * sin], [s * sin, s * cos]];
    let mut t = Affine::identity(2);
    t.m[0][0] = m[0][0];
    t.m[0][1] = m[0][1];
    t.m[1][0] = m[1][0];
    t.m[1][1] = m[1][1];
    t.t[0] = cb[0] - m[0][0] * ca[0] - m[0][1] * ca[1];
    t.t[1] = cb[1] - m[1][0] * ca[0] - m[1][1] * ca[1];
    Some(t)
}

/// The field of an affine map: the template's outline nodes and their images as pairs.
pub(crate) fn affine_start(template: &Template, map: Affine, smoothing: f64) -> Result<Start> {
    let a = Shape::from_points_2d(&template.outline, Topology::ClosedContour)?;
    let mapped: Vec<[f64; 2]> = template
        .outline
        .iter()
        .map(|q| {
            [
                map.m[0][0] * q[0] + map.m[0][1] * q[1] + map.t[0],
                map.m[1][0] * q[0] + map.m[1][1] * q[1] + map.t[1],
            ]
        })
        .collect();
    let b = Shape::from_points_2d(&mapped, Topology::ClosedContour)?;
    let pairs = MatchPair::each_to_itself(mapped.len());
    Ok(Start {
        field: CorrespondenceField::fit(&a, &b, &pairs, smoothing)?,
        map,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rectangle's footprint shifted, scaled and turned by 20°: the principal axes recover the
    /// turn, the centroid and the scale.
    #[test]
    fn principal_axes_recover_a_turned_rectangle() {
        let (rows, cols) = (60, 60);
        let rect = |cx: f64, cy: f64, turn: f64, s: f64| -> Vec<bool> {
            let (sin, cos) = turn.to_radians().sin_cos();
            (0..rows * cols)
                .map(|i| {
                    let (x, y) = ((i % cols) as f64 - cx, (i / cols) as f64 - cy);
                    let (u, v) = (cos * x + sin * y, -sin * x + cos * y);
                    u.abs() < 5.5 * s && v.abs() < 15.5 * s
                })
                .collect()
        };
        let a = rect(25.0, 30.0, 0.0, 1.0);
        let b = rect(32.0, 28.0, 20.0, 1.2);
        let t = principal_axes(&a, &b, [cols, cols], 45.0).unwrap();
        let turn = t.m[1][0].atan2(t.m[0][0]).to_degrees();
        let scale = (t.m[0][0] * t.m[1][1] - t.m[0][1] * t.m[1][0]).sqrt();
        assert!((turn - 20.0).abs() < 1.5, "turn {turn}");
        assert!((scale - 1.2).abs() < 0.03, "scale {scale}");
        let c = [
            t.m[0][0] * 25.0 + t.m[0][1] * 30.0 + t.t[0],
            t.m[1][0] * 25.0 + t.m[1][1] * 30.0 + t.t[1],
        ];
        assert!(
            (c[0] - 32.0).abs() < 0.3 && (c[1] - 28.0).abs() < 0.3,
            "{c:?}"
        );
        // Beyond the prior: not turned.
        let t = principal_axes(&a, &b, [cols, cols], 10.0).unwrap();
        assert!(t.m[1][0].abs() < 1e-12);
    }
}
