//! Pairing contours across consecutive frames, with splits and merges reported (docs/method.md §9:
//! the contours of one object must be followed through the sequence).
//!
//! Two links are offered: area overlap of the regions the contours enclose, and centroid
//! distance. Pairs are the one-to-one continuations; an object linked to several in the next
//! frame has split, several linked to one have merged. Only outer contours (not holes) take part;
//! indices refer to the slices given.

use pedo_io::contour::Contour;
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
    let (mut ca, mut cb) = (Vec::new(), Vec::new());
    let mut y = y0 + 0.5 * h;
    while y < y1 {
        crossings(&a.points, y, &mut ca);
        crossings(&b.points, y, &mut cb);
        let (mut ia, mut ib) = (0, 0);
        let mut x = x0 + 0.5 * h;
        while x < x1 {
            // Inside a polygon: an odd number of its row's crossings right of x (the test of
            // `point_in_polygon`, sample for sample).
            while ia < ca.len() && ca[ia] <= x {
                ia += 1;
            }
            while ib < cb.len() && cb[ib] <= x {
                ib += 1;
            }
            if (ca.len() - ia) % 2 == 1 && (cb.len() - ib) % 2 == 1 {
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

/// The abscissae, sorted, at which the edges of `poly` cross the row at `y`, each computed as
/// [`pedo_io::contour::point_in_polygon`] computes it, so that a sample's parity test gives its answer: the raster
/// of [`overlap`] costs a pass over the edges per row instead of one per sample.
fn crossings(poly: &[[f64; 2]], y: f64, out: &mut Vec<f64>) {
    out.clear();
    let mut j = poly.len().wrapping_sub(1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > y) != (b[1] > y) {
            let x = a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            // A crossing at NaN (a NaN vertex) is right of no sample, as the point test has it.
            if !x.is_nan() {
                out.push(x);
            }
        }
        j = i;
    }
    out.sort_unstable_by(f64::total_cmp);
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

/// The step rule of node tracks between two closed planar outlines (docs/method.md §9, "A step
/// no longer than the boundary's own motion"): a track may step from node `from` of one outline
/// to node `to` of the next outline `next` only if the step is no longer than the boundary itself
/// moved there — the distance from `from` to `next` — plus [`STEP_SLACK`] node spacings of
/// `next`. A match that asks for more has no honest partner: the track ends and `to` starts a
/// new one. For any `next` that is not a closed planar outline every step is allowed here; a
/// run's pairs are judged by [`StepBound`], which also bounds surfaces and isocontour levels.
pub fn step_allowed(from: &[f64], to: &[f64], next: &modal_core::Shape) -> bool {
    if !is_outline(next) {
        return true;
    }
    outline_step_allowed(from, to, next.coords(), median_spacing(next.coords()))
}

/// Whether `shape` is a closed planar outline (a contour or an isocontour level).
fn is_outline(shape: &modal_core::Shape) -> bool {
    shape.dim() == 2 && matches!(shape.topology(), modal_core::Topology::ClosedContour)
}

/// [`step_allowed`] with the outline's median node spacing given.
fn outline_step_allowed(from: &[f64], to: &[f64], coords: &[f64], spacing: f64) -> bool {
    let step = ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2)).sqrt();
    let motion = outline_motion(coords, [from[0], from[1]]);
    step <= motion + STEP_SLACK * spacing
}

/// The least overlap, as a fraction of the smaller region, of the regions of two consecutive
/// isocontour levels whose pair continues tracks (docs/method.md §9). Each level's object is its
/// largest region's outline and a higher level nests inside a lower one, so the fraction is
/// about 1 while the largest region stays on the same part of the foot and about 0 when it
/// switches to another (the forefoot's, then the hallux's): measured on the bundled walk and
/// every recording of `benches/data`, every pair overlapped by 0.99 or more, or not at all
/// (docs/method.md §9).
pub const LEVEL_MIN_OVERLAP: f64 = 0.5;

/// The step rule of one pair of objects, made once per pair ([`StepBound::new`]) and asked per
/// match ([`StepBound::allows`]): whether the match of a node of the first object with a node of
/// the second may extend a track (docs/method.md §9).
///
/// - **Contours** of consecutive frames: [`step_allowed`], the boundary's own motion at the node
///   plus [`STEP_SLACK`] node spacings, in sensels.
/// - **Isocontour levels** (two objects of one frame): none when the levels' regions overlap by
///   less than [`LEVEL_MIN_OVERLAP`] of the smaller (the level's largest region has switched to
///   another part of the foot: new tracks start), else the contours' rule between the two level
///   lines.
/// - **Surfaces**: in the plane (x, y) with y scaled by the sensel aspect (true proportions), the
///   distance from the node to the next surface's support (the union of its triangles: 0 inside,
///   else how far the footprint withdrew from there) plus [`STEP_SLACK`] median edge lengths of
///   the next surface's mesh in the plane; none when the two footprints lie apart (fewer than
///   [`FOOTPRINT_MIN_OVERLAP`] of either surface's nodes inside the other's support).
/// - Anything else (point sets, 3-D curves): every step.
#[derive(Debug, Clone)]
pub struct StepBound {
    kind: BoundKind,
}

#[derive(Debug, Clone)]
enum BoundKind {
    Free,
    Cut,
    Outline {
        coords: Vec<f64>,
        spacing: f64,
    },
    Support {
        aspect: f64,
        /// The next surface's triangles, their corners in the plane (y scaled).
        triangles: Vec<[[f64; 2]; 3]>,
        /// Edges of one triangle only: the support's boundary.
        boundary: Vec<[[f64; 2]; 2]>,
        slack: f64,
    },
}

impl StepBound {
    /// The rule of the pair `a` → `b` (`aspect`: the sensels' row pitch over column pitch,
    /// [`crate::SenselAspect`]; only surfaces use it).
    pub fn new(
        a: &crate::SequenceObject,
        b: &crate::SequenceObject,
        aspect: crate::SenselAspect,
    ) -> Self {
        let (sa, sb) = (&a.shape, &b.shape);
        let kind = if is_outline(sb) {
            let coords = sb.coords().to_vec();
            let spacing = median_spacing(&coords);
            if a.frame == b.frame && is_outline(sa) && !levels_overlap(sa, sb) {
                BoundKind::Cut
            } else {
                BoundKind::Outline { coords, spacing }
            }
        } else if let modal_core::Topology::Mesh { triangles } = sb.topology()
            && sb.dim() >= 2
            && a.frame != b.frame
        {
            let next = support(sb, triangles, aspect.0);
            if footprints_apart(sa, sb, &next, aspect.0) {
                BoundKind::Cut
            } else {
                next
            }
        } else {
            BoundKind::Free
        };
        Self { kind }
    }

    /// Whether a track may step from `from` (a node of the first object, its coordinates) to
    /// `to` (a node of the second).
    pub fn allows(&self, from: &[f64], to: &[f64]) -> bool {
        match &self.kind {
            BoundKind::Free => true,
            BoundKind::Cut => false,
            BoundKind::Outline { coords, spacing } => {
                outline_step_allowed(from, to, coords, *spacing)
            }
            BoundKind::Support {
                aspect,
                triangles,
                boundary,
                slack,
            } => {
                let (p, q) = ([from[0], from[1] * aspect], [to[0], to[1] * aspect]);
                let step = (q[0] - p[0]).hypot(q[1] - p[1]);
                step <= support_distance(p, triangles, boundary) + slack
            }
        }
    }

    /// Whether this rule lets every step through (no bound for this kind of object).
    pub fn is_free(&self) -> bool {
        matches!(self.kind, BoundKind::Free)
    }

    /// Whether this rule lets no step through (isocontour levels whose regions do not overlap).
    pub fn is_cut(&self) -> bool {
        matches!(self.kind, BoundKind::Cut)
    }
}

/// Whether the regions of two isocontour levels overlap by at least [`LEVEL_MIN_OVERLAP`] of
/// the smaller one.
fn levels_overlap(a: &modal_core::Shape, b: &modal_core::Shape) -> bool {
    let contour = |s: &modal_core::Shape| Contour {
        points: s.coords().chunks_exact(2).map(|p| [p[0], p[1]]).collect(),
        hole: false,
        level: 0.0,
    };
    let resolution = match PairingMethod::default() {
        PairingMethod::Overlap { resolution, .. } => resolution,
        _ => 4.0,
    };
    overlap(&contour(a), &contour(b), resolution).0 >= LEVEL_MIN_OVERLAP
}

/// The support rule of a surface `s` with `triangles`, y scaled by `aspect`.
fn support(s: &modal_core::Shape, triangles: &[[usize; 3]], aspect: f64) -> BoundKind {
    let d = s.dim();
    let c = s.coords();
    let n = s.len();
    let at = |i: usize| [c[d * i], c[d * i + 1] * aspect];
    let tris: Vec<[[f64; 2]; 3]> = triangles
        .iter()
        .filter(|t| t.iter().all(|&v| v < n))
        .map(|t| t.map(at))
        .collect();
    let mut edges: std::collections::BTreeMap<(usize, usize), usize> = Default::default();
    for t in triangles.iter().filter(|t| t.iter().all(|&v| v < n)) {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            *edges.entry((u.min(v), u.max(v))).or_insert(0) += 1;
        }
    }
    let boundary = edges
        .iter()
        .filter(|(_, count)| **count == 1)
        .map(|(&(u, v), _)| [at(u), at(v)])
        .collect();
    let mut lengths: Vec<f64> = edges
        .keys()
        .map(|&(u, v)| {
            let (p, q) = (at(u), at(v));
            (q[0] - p[0]).hypot(q[1] - p[1])
        })
        .collect();
    lengths.sort_by(f64::total_cmp);
    let spacing = lengths.get(lengths.len() / 2).copied().unwrap_or(0.0);
    if tris.is_empty() {
        return BoundKind::Free;
    }
    BoundKind::Support {
        aspect,
        triangles: tris,
        boundary,
        slack: STEP_SLACK * spacing,
    }
}

/// The least share of a surface's nodes inside the other surface's support, the larger of the
/// two directions, for a pair of surfaces to continue tracks: the overlap pairing's least link
/// (5 % of the smaller region, [`PairingMethod::default`]), estimated on the nodes. Footprints
/// that lie apart are two contacts, not one that moved, whatever the matching pairs.
pub const FOOTPRINT_MIN_OVERLAP: f64 = 0.05;

/// Whether the footprints of surfaces `a` and `b` (`next`: `b`'s support) lie apart: fewer than
/// [`FOOTPRINT_MIN_OVERLAP`] of `a`'s nodes inside `b`'s support and of `b`'s inside `a`'s.
fn footprints_apart(
    a: &modal_core::Shape,
    b: &modal_core::Shape,
    next: &BoundKind,
    aspect: f64,
) -> bool {
    let share = |s: &modal_core::Shape, support: &BoundKind| match support {
        BoundKind::Support {
            triangles,
            boundary,
            ..
        } if s.dim() >= 2 && !s.is_empty() => {
            let inside = (0..s.len())
                .filter(|&k| {
                    let p = s.point(k);
                    support_distance([p[0], p[1] * aspect], triangles, boundary) == 0.0
                })
                .count();
            inside as f64 / s.len() as f64
        }
        // No support to lie in: no evidence that the footprints lie apart.
        _ => 1.0,
    };
    if share(a, next) >= FOOTPRINT_MIN_OVERLAP {
        return false;
    }
    let own = match a.topology() {
        modal_core::Topology::Mesh { triangles } if a.dim() >= 2 => support(a, triangles, aspect),
        _ => BoundKind::Free,
    };
    share(b, &own) < FOOTPRINT_MIN_OVERLAP
}

/// Distance from `p` to the union of `triangles` (0 inside one), whose boundary edges are
/// `boundary`.
fn support_distance(p: [f64; 2], triangles: &[[[f64; 2]; 3]], boundary: &[[[f64; 2]; 2]]) -> f64 {
    let cross =
        |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let inside = triangles.iter().any(|&[a, b, c]| {
        let (u, v, w) = (cross(a, b), cross(b, c), cross(c, a));
        (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0)
    });
    if inside {
        return 0.0;
    }
    boundary
        .iter()
        .map(|&[a, b]| segment_distance(p, a, b))
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let foot = [a[0] + t * ab[0], a[1] + t * ab[1]];
    ((p[0] - foot[0]).powi(2) + (p[1] - foot[1]).powi(2)).sqrt()
}

/// Distance from `p` to the closed polyline `coords` (row-major `x, y`).
fn outline_motion(coords: &[f64], p: [f64; 2]) -> f64 {
    let n = coords.len() / 2;
    let node = |i: usize| [coords[2 * (i % n)], coords[2 * (i % n) + 1]];
    let mut best = f64::INFINITY;
    for i in 0..n {
        best = best.min(segment_distance(p, node(i), node(i + 1)));
    }
    best
}

/// The median segment length of the closed polyline `coords` (row-major `x, y`).
fn median_spacing(coords: &[f64]) -> f64 {
    let n = coords.len() / 2;
    let node = |i: usize| [coords[2 * (i % n)], coords[2 * (i % n) + 1]];
    let mut lengths: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (node(i), node(i + 1));
            let ab = [b[0] - a[0], b[1] - a[1]];
            (ab[0] * ab[0] + ab[1] * ab[1]).sqrt()
        })
        .collect();
    lengths.sort_by(f64::total_cmp);
    lengths.get(n / 2).copied().unwrap_or(0.0)
}

/// Distance from `p` to the closed polyline `coords` (row-major `x, y`), and the polyline's
/// median segment length.
pub(crate) fn outline_distance(coords: &[f64], p: [f64; 2]) -> (f64, f64) {
    (outline_motion(coords, p), median_spacing(coords))
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

#[cfg(test)]
mod bound_tests {
    use super::*;
    use crate::{SenselAspect, SequenceObject};
    use modal_core::{Shape, Topology};

    /// A surface on the grid `x0..x0 + n`, `y0..y0 + n` (unit spacing), two triangles a cell.
    fn patch(frame: usize, x0: f64, y0: f64, n: usize) -> SequenceObject {
        let mut points = Vec::new();
        for r in 0..=n {
            for c in 0..=n {
                points.push([x0 + c as f64, y0 + r as f64, 1.0]);
            }
        }
        let at = |r: usize, c: usize| r * (n + 1) + c;
        let mut triangles = Vec::new();
        for r in 0..n {
            for c in 0..n {
                triangles.push([at(r, c), at(r, c + 1), at(r + 1, c + 1)]);
                triangles.push([at(r, c), at(r + 1, c + 1), at(r + 1, c)]);
            }
        }
        let shape = Shape::from_points_3d(&points, Topology::Mesh { triangles }).unwrap();
        SequenceObject {
            id: frame,
            frame,
            index: 0,
            level: None,
            shape,
            measures: None,
        }
    }

    #[test]
    fn a_surface_step_is_bounded_by_the_footprints_motion_there() {
        let a = patch(0, 0.0, 0.0, 10);
        // A footprint 30 sensels on is another contact: no step at all, not even from the
        // trailing edge (which a rigid jump would otherwise carry as far as the jump).
        let far = StepBound::new(&a, &patch(1, 30.0, 0.0, 10), SenselAspect::SQUARE);
        assert!(far.is_cut());
        assert!(!far.allows(&[0.0, 5.0, 1.0], &[30.0, 5.0, 1.0]));
        // A footprint 8 sensels on, overlapping the old by 3 of its 11 columns: a node reaches
        // out to where the footprint went, plus 1.5 edge lengths (the median edge is 1).
        let on = StepBound::new(&a, &patch(1, 8.0, 0.0, 10), SenselAspect::SQUARE);
        assert!(!on.is_free() && !on.is_cut());
        assert!(on.allows(&[0.0, 5.0, 1.0], &[9.4, 5.0, 1.0]));
        assert!(!on.allows(&[0.0, 5.0, 1.0], &[9.6, 5.0, 1.0]));
        assert!(!on.allows(&[5.0, 5.0, 1.0], &[15.0, 5.0, 1.0]));
        // Inside a footprint that stays, a node may move 1.5 edge lengths only: not heel to toe.
        let still = StepBound::new(&a, &patch(1, 0.0, 0.0, 10), SenselAspect::SQUARE);
        assert!(still.allows(&[2.0, 2.0, 1.0], &[3.0, 3.0, 1.0]));
        assert!(!still.allows(&[2.0, 2.0, 1.0], &[8.0, 8.0, 1.0]));
        // A footprint moving 3 sensels: the trailing edge follows it.
        let moved = StepBound::new(&a, &patch(1, 3.0, 0.0, 10), SenselAspect::SQUARE);
        assert!(moved.allows(&[0.0, 5.0, 1.0], &[3.0, 5.0, 1.0]));
        // Oblong sensels (rows 1.5 times as tall): the same two rows are 3, not 2, in the plane.
        let a_row = patch(0, 0.0, 0.0, 10);
        let up = patch(1, 0.0, 2.0, 10);
        let square = StepBound::new(&a_row, &up, SenselAspect::SQUARE);
        let oblong = StepBound::new(&a_row, &up, SenselAspect::of_pitch(Some([5.08, 7.62])));
        // From the bottom row, 2 rows below the support's edge: 2 + 1.5 in square sensels,
        // 3 + 1.5 × 1.5 in true proportions (the median edge is a row, 1.5 tall).
        assert!(square.allows(&[5.0, 0.0, 1.0], &[5.0, 3.4, 1.0]));
        assert!(!square.allows(&[5.0, 0.0, 1.0], &[8.0, 2.0, 1.0]));
        assert!(oblong.allows(&[5.0, 0.0, 1.0], &[8.0, 2.0, 1.0]));
        assert!(!oblong.allows(&[5.0, 0.0, 1.0], &[5.0, 3.6, 1.0]));
    }

    #[test]
    fn isocontour_levels_whose_regions_do_not_overlap_cut_every_step() {
        let ring = |cx: f64, r: f64| {
            let n = 40;
            let c: Vec<f64> = (0..n)
                .flat_map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    [cx + r * t.cos(), 10.0 + r * t.sin()]
                })
                .collect();
            Shape::new(2, c, Topology::ClosedContour).unwrap()
        };
        let level = |index: usize, shape: Shape| SequenceObject {
            id: index,
            frame: 7,
            index,
            level: Some(index as f64),
            shape,
            measures: None,
        };
        let low = level(0, ring(10.0, 6.0));
        // Nested inside: the contours' rule between the two level lines.
        let inner = StepBound::new(&low, &level(1, ring(10.0, 4.0)), SenselAspect::SQUARE);
        assert!(!inner.is_cut() && !inner.is_free());
        assert!(inner.allows(&[16.0, 10.0], &[14.0, 10.0]));
        assert!(!inner.allows(&[16.0, 10.0], &[6.0, 10.0]));
        // Elsewhere on the foot: no step at all, however short.
        let elsewhere = StepBound::new(&low, &level(1, ring(22.0, 3.0)), SenselAspect::SQUARE);
        assert!(elsewhere.is_cut());
        assert!(!elsewhere.allows(&[16.0, 10.0], &[19.0, 10.0]));
    }
}

#[cfg(test)]
mod overlap_tests {
    use super::*;
    use pedo_io::contour::point_in_polygon;
    use proptest::prelude::*;

    /// The raster of `overlap` sampled point by point: its intersection count.
    fn samples_inside_both(a: &Contour, b: &Contour, res: f64) -> usize {
        let (ba, bb) = (bbox(&a.points), bbox(&b.points));
        let (x0, y0) = (ba[0].max(bb[0]), ba[1].max(bb[1]));
        let (x1, y1) = (ba[2].min(bb[2]), ba[3].min(bb[3]));
        let h = 1.0 / res;
        let mut inter = 0;
        let mut y = y0 + 0.5 * h;
        while y < y1 {
            let mut x = x0 + 0.5 * h;
            while x < x1 {
                let p = [x, y];
                inter +=
                    usize::from(point_in_polygon(p, &a.points) && point_in_polygon(p, &b.points));
                x += h;
            }
            y += h;
        }
        inter
    }

    /// A star-shaped polygon (possibly with vertices on a sample row: radii on a coarse grid).
    fn star(centre: [f64; 2], radii: &[f64]) -> Contour {
        let n = radii.len() as f64;
        let points = (radii.iter().enumerate())
            .map(|(i, r)| {
                let t = std::f64::consts::TAU * i as f64 / n;
                [centre[0] + r * t.cos(), centre[1] + r * t.sin()]
            })
            .collect();
        Contour {
            points,
            hole: false,
            level: 1.0,
        }
    }

    proptest! {
        #[test]
        fn the_scanline_raster_counts_what_the_point_test_counts(
            ra in prop::collection::vec(1u8..16, 3..40),
            rb in prop::collection::vec(1u8..16, 3..40),
            dx in -8i8..8, dy in -8i8..8, res in prop::sample::select(vec![1.0, 2.0, 4.0, 0.5]),
        ) {
            let a = star([10.0, 10.0], &ra.iter().map(|&r| f64::from(r) * 0.5).collect::<Vec<_>>());
            let b = star([10.0 + f64::from(dx) * 0.5, 10.0 + f64::from(dy) * 0.25],
                &rb.iter().map(|&r| f64::from(r) * 0.5).collect::<Vec<_>>());
            let (fraction, iou) = overlap(&a, &b, res);
            let h = 1.0 / res;
            let smaller = a.area().min(b.area());
            let inter = (samples_inside_both(&a, &b, res) as f64 * h * h).min(smaller);
            let want = if inter == 0.0 { (0.0, 0.0) } else {
                (inter / smaller, inter / (a.area() + b.area() - inter))
            };
            prop_assert_eq!((fraction.to_bits(), iou.to_bits()), (want.0.to_bits(), want.1.to_bits()));
        }
    }
}
