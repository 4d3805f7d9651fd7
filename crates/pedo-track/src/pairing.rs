//! Pairing contours across consecutive frames, with splits and merges reported (docs/method.md §9:
//! the contours of one object must be followed through the sequence).
//!
//! Two links are offered: area overlap of the regions the contours enclose, and centroid
//! distance. Pairs are the one-to-one continuations; an object linked to several in the next
//! frame has split, several linked to one have merged. Only outer contours (not holes) take part;
//! indices refer to the slices given.

use pedo_io::contour::{point_in_polygon, Contour};
use pedo_io::{IoError, Result};

/// How contours of consecutive frames are linked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairingMethod {
    /// Linked when the overlap of the enclosed regions is at least `min_fraction` of the smaller
    /// region (estimated on a sub-pixel raster of `resolution` samples per unit, e.g. 4); the
    /// strongest links, which continue an object, are those of largest intersection over union.
    Overlap {
        /// Least overlap, as a fraction of the smaller region's area, that links two contours;
        /// in (0, 1].
        min_fraction: f64,
        /// Raster samples per coordinate unit along x and along y (4: 16 samples per square
        /// sensel); in [0.1, 64].
        resolution: f64,
    },
    /// Linked when the centroids are at most `max_distance` apart (same units as the points).
    Centroid {
        /// Largest centroid distance that links two contours, in the points' units (> 0).
        max_distance: f64,
    },
    /// Centroid tracking with a constant-velocity prediction (the noise-free limit of the paper's
    /// Kalman tracking of centroids): in [`track`], a contour that continued an object from the
    /// frame before is expected at `centroid + (centroid − previous centroid)`, and linked when
    /// the next frame's centroid is at most `max_distance` from that prediction. In
    /// [`pair_contours`] (no history) it equals [`PairingMethod::Centroid`].
    PredictedCentroid {
        /// Largest distance from the predicted centroid that links two contours, in the
        /// points' units (> 0).
        max_distance: f64,
    },
}

impl Default for PairingMethod {
    fn default() -> Self {
        PairingMethod::Overlap {
            min_fraction: 0.05,
            resolution: 4.0,
        }
    }
}

/// Correspondence between the contours of two consecutive frames.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Pairing {
    /// `(i, j)`: contour `i` of the first frame continues as contour `j` of the second
    /// (mutually strongest links, one-to-one).
    pub pairs: Vec<(usize, usize)>,
    /// `(i, [j, …])`: contour `i` is linked to several contours of the second frame.
    pub splits: Vec<(usize, Vec<usize>)>,
    /// `([i, …], j)`: several contours of the first frame are linked to contour `j`.
    pub merges: Vec<(Vec<usize>, usize)>,
    /// Contours of the second frame linked to nothing.
    pub appeared: Vec<usize>,
    /// Contours of the first frame linked to nothing.
    pub vanished: Vec<usize>,
    /// Every link `(i, j, strength)`: the regions' intersection over union (overlap pairing), or
    /// minus the centroid distance.
    pub links: Vec<(usize, usize, f64)>,
}

fn bbox(p: &[[f64; 2]]) -> [f64; 4] {
    p.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, q| {
            [
                b[0].min(q[0]),
                b[1].min(q[1]),
                b[2].max(q[0]),
                b[3].max(q[1]),
            ]
        },
    )
}

/// How much the regions of `a` and `b` overlap: `(fraction, iou)`, the overlap as a fraction of
/// the smaller region (whether they are linked at all: a heel wholly inside the next frame's
/// foot is linked) and the intersection over union (which link is the strongest: at a merge the
/// foot and the toe blob both lie wholly inside the merged region, and the foot, which covers
/// most of it, carries on).
fn overlap(a: &Contour, b: &Contour, res: f64) -> (f64, f64) {
    let (ba, bb) = (bbox(&a.points), bbox(&b.points));
    let (x0, y0, x1, y1) = (
        ba[0].max(bb[0]),
        ba[1].max(bb[1]),
        ba[2].min(bb[2]),
        ba[3].min(bb[3]),
    );
    if x0 >= x1 || y0 >= y1 {
        return (0.0, 0.0);
    }
    let h = 1.0 / res;
    let mut inter = 0usize;
    let mut y = y0 + 0.5 * h;
    while y < y1 {
        let mut x = x0 + 0.5 * h;
        while x < x1 {
            if point_in_polygon([x, y], &a.points) && point_in_polygon([x, y], &b.points) {
                inter += 1;
            }
            x += h;
        }
        y += h;
    }
    let (area_a, area_b) = (a.area(), b.area());
    let smaller = area_a.min(area_b);
    if smaller <= 0.0 {
        return (0.0, 0.0);
    }
    // The raster estimate of the intersection can exceed a region's exact area by a sample.
    let inter = (inter as f64 * h * h).min(smaller);
    (inter / smaller, inter / (area_a + area_b - inter))
}

/// Links the contours of two consecutive frames (see [`Pairing`]).
pub fn pair_contours(a: &[Contour], b: &[Contour], method: PairingMethod) -> Result<Pairing> {
    pair_with_velocity(a, b, method, &vec![[0.0, 0.0]; a.len()])
}

fn pair_with_velocity(
    a: &[Contour],
    b: &[Contour],
    method: PairingMethod,
    vel: &[[f64; 2]],
) -> Result<Pairing> {
    match method {
        PairingMethod::Overlap {
            min_fraction,
            resolution,
        } => {
            let ok = min_fraction > 0.0
                && min_fraction <= 1.0
                && resolution.is_finite()
                && (0.1..=64.0).contains(&resolution);
            if !ok {
                return Err(IoError::invalid(
                    "overlap pairing needs min_fraction in (0, 1] and resolution in [0.1, 64]",
                ));
            }
        }
        PairingMethod::Centroid { max_distance }
        | PairingMethod::PredictedCentroid { max_distance } => {
            if !(max_distance.is_finite() && max_distance > 0.0) {
                return Err(IoError::invalid(
                    "centroid pairing needs a positive max_distance",
                ));
            }
        }
    }
    let mut links = Vec::new();
    for (i, ca) in a.iter().enumerate().filter(|(_, c)| !c.hole) {
        for (j, cb) in b.iter().enumerate().filter(|(_, c)| !c.hole) {
            match method {
                PairingMethod::Overlap {
                    min_fraction,
                    resolution,
                } => {
                    let (fraction, iou) = overlap(ca, cb, resolution);
                    if fraction >= min_fraction {
                        links.push((i, j, iou));
                    }
                }
                PairingMethod::Centroid { max_distance }
                | PairingMethod::PredictedCentroid { max_distance } => {
                    let (c, q) = (ca.centroid(), cb.centroid());
                    let p = [c[0] + vel[i][0], c[1] + vel[i][1]];
                    let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                    if d <= max_distance {
                        links.push((i, j, -d));
                    }
                }
            }
        }
    }
    Ok(classify(a, b, links))
}

/// Pairs, splits, merges, appearances and disappearances from the links `(i, j, strength)`.
fn classify(a: &[Contour], b: &[Contour], links: Vec<(usize, usize, f64)>) -> Pairing {
    let best = |from_a: bool, k: usize| {
        links
            .iter()
            .filter(|l| if from_a { l.0 == k } else { l.1 == k })
            .max_by(|x, y| x.2.total_cmp(&y.2))
            .map(|l| if from_a { l.1 } else { l.0 })
    };
    let mut out = Pairing {
        links: links.clone(),
        ..Default::default()
    };
    for (i, c) in a.iter().enumerate() {
        if c.hole {
            continue;
        }
        let js: Vec<usize> = links.iter().filter(|l| l.0 == i).map(|l| l.1).collect();
        match js.len() {
            0 => out.vanished.push(i),
            1 => {}
            _ => out.splits.push((i, js)),
        }
        if let Some(j) = best(true, i)
            && best(false, j) == Some(i)
        {
            out.pairs.push((i, j));
        }
    }
    for (j, c) in b.iter().enumerate() {
        if c.hole {
            continue;
        }
        let is: Vec<usize> = links.iter().filter(|l| l.1 == j).map(|l| l.0).collect();
        match is.len() {
            0 => out.appeared.push(j),
            1 => {}
            _ => out.merges.push((is, j)),
        }
    }
    out
}

/// Links contours by a caller-supplied cost — for instance the modal deformation energy needed
/// to align two contours, the paper's third option — where `cost(a_i, b_j)` is `None` for "not
/// linked" and lower is better. Holes are skipped as in [`pair_contours`]; non-finite costs are an
/// error.
pub fn pair_contours_by<F>(a: &[Contour], b: &[Contour], mut cost: F) -> Result<Pairing>
where
    F: FnMut(&Contour, &Contour) -> Option<f64>,
{
    let mut links = Vec::new();
    for (i, ca) in a.iter().enumerate().filter(|(_, c)| !c.hole) {
        for (j, cb) in b.iter().enumerate().filter(|(_, c)| !c.hole) {
            if let Some(c) = cost(ca, cb) {
                if !c.is_finite() {
                    return Err(IoError::invalid(format!(
                        "pairing cost of ({i}, {j}) is not finite: {c}"
                    )));
                }
                links.push((i, j, -c));
            }
        }
    }
    Ok(classify(a, b, links))
}

/// Pairs each frame's contours with the next frame's: `result[t]` links frame `t` to `t + 1`.
pub fn track(frames: &[Vec<Contour>], method: PairingMethod) -> Result<Vec<Pairing>> {
    let mut out: Vec<Pairing> = Vec::with_capacity(frames.len().saturating_sub(1));
    for (t, w) in frames.windows(2).enumerate() {
        let mut vel = vec![[0.0, 0.0]; w[0].len()];
        if let (PairingMethod::PredictedCentroid { .. }, Some(prev)) = (method, out.last()) {
            for &(i, j) in &prev.pairs {
                let (c0, c1) = (frames[t - 1][i].centroid(), w[0][j].centroid());
                vel[j] = [c1[0] - c0[0], c1[1] - c0[1]];
            }
        }
        out.push(pair_with_velocity(&w[0], &w[1], method, &vel)?);
    }
    Ok(out)
}

/// The slack of [`step_allowed`], in node spacings of the next outline: how far beyond the
/// boundary's own motion a node may slide along it between two frames (resampling alone shifts
/// nodes along an outline by up to one spacing).
pub const STEP_SLACK: f64 = 1.5;

/// The step rule of node tracks (docs/method.md, "Tracks"): a track may step from node `from` of
/// one frame's outline to node `to` of the next frame's outline `next` only if the step is no
/// longer than the boundary itself moved there — the distance from `from` to `next` — plus
/// [`STEP_SLACK`] node spacings of `next`. A match that asks for more has no honest partner: the
/// track ends and `to` starts a new one. Only closed planar outlines are bounded (the contour
/// model); for any other `next` every step is allowed. Both the whole-recording chaining
/// ([`crate::chain_tracks`], [`crate::drift`]) and incremental chainers call this.
pub fn step_allowed(from: &[f64], to: &[f64], next: &modal_core::Shape) -> bool {
    if next.dim() != 2 || !matches!(next.topology(), modal_core::Topology::ClosedContour) {
        return true;
    }
    let step = ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2)).sqrt();
    let (motion, spacing) = outline_distance(next.coords(), [from[0], from[1]]);
    step <= motion + STEP_SLACK * spacing
}

/// Distance from `p` to the closed polyline `coords` (row-major `x, y`), and the polyline's
/// median segment length.
pub(crate) fn outline_distance(coords: &[f64], p: [f64; 2]) -> (f64, f64) {
    let n = coords.len() / 2;
    let node = |i: usize| [coords[2 * (i % n)], coords[2 * (i % n) + 1]];
    let mut best = f64::INFINITY;
    let mut lengths = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (node(i), node(i + 1));
        let ab = [b[0] - a[0], b[1] - a[1]];
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        lengths.push(len2.sqrt());
        let t = if len2 > 0.0 {
            (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let foot = [a[0] + t * ab[0], a[1] + t * ab[1]];
        best = best.min(((p[0] - foot[0]).powi(2) + (p[1] - foot[1]).powi(2)).sqrt());
    }
    lengths.sort_by(f64::total_cmp);
    (best, lengths.get(n / 2).copied().unwrap_or(0.0))
}

#[cfg(test)]
mod step_tests {
    use super::*;
    use modal_core::{Shape, Topology};

    fn square(side: f64, n_per_side: usize) -> Shape {
        let mut c = Vec::new();
        let h = side / n_per_side as f64;
        for k in 0..4 * n_per_side {
            let (s, r) = (k / n_per_side, (k % n_per_side) as f64 * h);
            let p = match s {
                0 => [r, 0.0],
                1 => [side, r],
                2 => [side - r, side],
                _ => [0.0, side - r],
            };
            c.extend(p);
        }
        Shape::new(2, c, Topology::ClosedContour).unwrap()
    }

    #[test]
    fn a_step_may_follow_the_boundary_plus_the_slack_and_no_further() {
        // A 20 × 20 square sampled every sensel: its boundary lies 2 sensels outside (−2, 5).
        let next = square(20.0, 20);
        let from = [-2.0, 5.0];
        // Straight onto the outline: the boundary's motion.
        assert!(step_allowed(&from, &[0.0, 5.0], &next));
        // Onto the outline and 1.5 spacings along it: √(4 + 1.5²) = 2.5 ≤ 2 + 1.5.
        assert!(step_allowed(&from, &[0.0, 6.5], &next));
        // Across the foot: 2 + 1.5 = 3.5 allowed, 20 asked.
        assert!(!step_allowed(&from, &[0.0, 25.0], &next));
        assert!(!step_allowed(&from, &[0.0, 8.7], &next));
        // Surfaces and point sets are not bounded.
        let cloud = Shape::new(2, next.coords().to_vec(), Topology::None).unwrap();
        assert!(step_allowed(&from, &[0.0, 25.0], &cloud));
    }
}
