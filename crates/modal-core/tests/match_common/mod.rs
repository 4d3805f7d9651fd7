//! Ground-truth cases for the matching tests: real foot outlines and a real pressure image
//! (tests/data, extracted by make_fixtures.py), warped by known smooth deformations and re-sampled.
#![allow(dead_code)]

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// A fixture of modal-core's `tests/data`. The root package's benches include this module too
/// (`#[path]`), and there the manifest directory is the workspace root.
pub fn data_path(name: &str) -> String {
    let dir = if env!("CARGO_PKG_NAME") == "modal-core" {
        "tests/data"
    } else {
        "crates/modal-core/tests/data"
    };
    format!("{}/{dir}/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Dense closed outlines `(name, points)`.
pub fn outlines() -> Vec<(String, Vec<[f64; 2]>)> {
    outlines_in("contours.txt")
}

/// Held-out outlines: the nearly round heel of the first loaded frames of every stance of the
/// F-Scan walk (heel_strike.txt). Used by no tuning.
pub fn heel_strikes() -> Vec<(String, Vec<[f64; 2]>)> {
    outlines_in("heel_strike.txt")
}

/// The outlines of a fixture file: blocks `# name` followed by `x y` lines.
pub fn outlines_in(file: &str) -> Vec<(String, Vec<[f64; 2]>)> {
    let text = std::fs::read_to_string(data_path(file)).expect(file);
    let mut out: Vec<(String, Vec<[f64; 2]>)> = Vec::new();
    for line in text.lines() {
        if let Some(name) = line.strip_prefix("# ") {
            if !name.starts_with("closed outlines") {
                out.push((name.to_string(), Vec::new()));
            }
        } else if !line.trim().is_empty() {
            let v: Vec<f64> = line
                .split_whitespace()
                .map(|s| s.parse().unwrap())
                .collect();
            out.last_mut().unwrap().1.push([v[0], v[1]]);
        }
    }
    out
}

/// The dense outline called `name` in contours.txt.
pub fn outline(name: &str) -> Vec<[f64; 2]> {
    outlines()
        .into_iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no outline {name} in contours.txt"))
        .1
}

/// The MUN104 left peak-pressure template, rows × cols.
pub fn pressure_grid() -> Vec<Vec<f64>> {
    std::fs::read_to_string(data_path("mun104l.txt"))
        .unwrap()
        .lines()
        .map(|l| l.split_whitespace().map(|s| s.parse().unwrap()).collect())
        .collect()
}

#[derive(Clone, Copy, Debug)]
pub enum Severity {
    Mild,
    Moderate,
    Severe,
    /// Moderate rotation and scale with a bend of 0.4: a strongly non-affine warp (more than
    /// three times the severe bend).
    Bent,
}

/// A smooth warp in the normalised frame of the original object: bend, shear, anisotropic scale,
/// rotation, then back to the original centre/scale plus a translation.
#[derive(Clone, Debug)]
pub struct Warp {
    centre: [f64; 2],
    radius: f64,
    axis: f64,
    bend: f64,
    shear: f64,
    sx: f64,
    sy: f64,
    rot: f64,
    shift: [f64; 2],
}

impl Warp {
    pub fn random(rng: &mut StdRng, sev: Severity, pts: &[[f64; 2]]) -> Self {
        let (deg, sc, sh, be) = match sev {
            Severity::Mild => (5.0, 0.05, 0.02, 0.02),
            Severity::Moderate => (15.0, 0.12, 0.05, 0.06),
            Severity::Severe => (35.0, 0.25, 0.15, 0.12),
            Severity::Bent => (15.0, 0.12, 0.05, 0.4),
        };
        let n = pts.len() as f64;
        let c = [
            pts.iter().map(|p| p[0]).sum::<f64>() / n,
            pts.iter().map(|p| p[1]).sum::<f64>() / n,
        ];
        let r = (pts
            .iter()
            .map(|p| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        let mut u = |a: f64| rng.random_range(-a..=a);
        Warp {
            centre: c,
            radius: r,
            axis: u(std::f64::consts::PI),
            bend: u(be),
            shear: u(sh),
            sx: 1.0 + u(sc),
            sy: 1.0 + u(sc),
            rot: u(deg).to_radians(),
            shift: [u(3.0), u(3.0)],
        }
    }

    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (x, y) = (
            (p[0] - self.centre[0]) / self.radius,
            (p[1] - self.centre[1]) / self.radius,
        );
        // bend about a random axis direction
        let (ca, sa) = (self.axis.cos(), self.axis.sin());
        let (s, t) = (ca * x + sa * y, -sa * x + ca * y);
        let t = t + self.bend * s * s;
        let (x, y) = (ca * s - sa * t, sa * s + ca * t);
        let x = x + self.shear * y;
        let (x, y) = (self.sx * x, self.sy * y);
        let (cr, sr) = (self.rot.cos(), self.rot.sin());
        let (x, y) = (cr * x - sr * y, sr * x + cr * y);
        [
            self.centre[0] + self.shift[0] + self.radius * x,
            self.centre[1] + self.shift[1] + self.radius * y,
        ]
    }
}

fn perimeter(c: &[[f64; 2]]) -> f64 {
    (0..c.len()).map(|i| dist(c[i], c[(i + 1) % c.len()])).sum()
}

pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// `n` points at uniform arc length along a closed polyline, starting at fraction `start`.
pub fn resample(c: &[[f64; 2]], n: usize, start: f64) -> Vec<[f64; 2]> {
    let len = perimeter(c);
    let mut cum = vec![0.0];
    for i in 0..c.len() {
        cum.push(cum[i] + dist(c[i], c[(i + 1) % c.len()]));
    }
    (0..n)
        .map(|k| {
            let s = ((start + k as f64 / n as f64) % 1.0) * len;
            let i = cum
                .partition_point(|&v| v <= s)
                .saturating_sub(1)
                .min(c.len() - 1);
            let f = (s - cum[i]) / (cum[i + 1] - cum[i]).max(1e-300);
            let (p, q) = (c[i], c[(i + 1) % c.len()]);
            [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])]
        })
        .collect()
}

/// One contour case: A sampled on the original outline, B on the warped outline, and the true
/// position of every A node in B's frame.
pub struct ContourCase {
    pub a: Vec<[f64; 2]>,
    pub b: Vec<[f64; 2]>,
    pub truth: Vec<[f64; 2]>,
    pub spacing_b: f64,
}

pub fn contour_case(outline: &[[f64; 2]], sev: Severity, seed: u64) -> ContourCase {
    contour_case_of(outline, sev, seed, 48..=72)
}

/// [`contour_case`] with A's node count drawn from `counts` (B's within 6 of it).
pub fn contour_case_of(
    outline: &[[f64; 2]],
    sev: Severity,
    seed: u64,
    counts: std::ops::RangeInclusive<usize>,
) -> ContourCase {
    let mut rng = StdRng::seed_from_u64(seed);
    let w = Warp::random(&mut rng, sev, outline);
    let na = rng.random_range(counts);
    let nb = (na as i64 + rng.random_range(-6..=6i64)) as usize;
    let a = resample(outline, na, rng.random_range(0.0..1.0));
    let warped: Vec<[f64; 2]> = outline.iter().map(|&p| w.apply(p)).collect();
    let b = resample(&warped, nb, rng.random_range(0.0..1.0));
    let truth = a.iter().map(|&p| w.apply(p)).collect();
    ContourCase {
        a,
        b,
        truth,
        spacing_b: perimeter(&warped) / nb as f64,
    }
}

/// Fraction of A's nodes whose match (the one-to-one one if any, else an excess one) lies within
/// `tol` (one B spacing) of the true position; 2-D contours and 3-D surfaces alike.
pub fn accuracy<const D: usize>(
    res: &modal_core::MatchResult,
    b: &[[f64; D]],
    truth: &[[f64; D]],
    tol: f64,
) -> f64 {
    let mut best: Vec<Option<(bool, usize)>> = vec![None; truth.len()];
    for p in &res.pairs {
        let e = &mut best[p.a];
        if e.is_none() || (e.unwrap().0 && !p.excess) {
            *e = Some((p.excess, p.b));
        }
    }
    let dist = |p: [f64; D], q: [f64; D]| (0..D).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
    best.iter()
        .enumerate()
        .filter(|(i, m)| m.is_some_and(|(_, j)| dist(b[j], truth[*i]) <= tol))
        .count() as f64
        / truth.len() as f64
}

/// Bilinear sample of a grid (x = column, y = row).
pub fn bilinear(g: &[Vec<f64>], x: f64, y: f64) -> f64 {
    let (r, c) = (g.len(), g[0].len());
    let x = x.clamp(0.0, (c - 1) as f64 - 1e-9);
    let y = y.clamp(0.0, (r - 1) as f64 - 1e-9);
    let (i, j) = (y.floor() as usize, x.floor() as usize);
    let (fy, fx) = (y - i as f64, x - j as f64);
    g[i][j] * (1.0 - fx) * (1.0 - fy)
        + g[i][j + 1] * fx * (1.0 - fy)
        + g[i + 1][j] * (1.0 - fx) * fy
        + g[i + 1][j + 1] * fx * fy
}

/// One surface case: two independent random samplings of the loaded region of a pressure image,
/// points `(x, y, z·scale)`; B's xy warped, its pressure scaled by a factor. `truth` is the true
/// position in B's frame of every A node.
pub struct SurfaceCase {
    pub a: Vec<[f64; 3]>,
    pub b: Vec<[f64; 3]>,
    pub truth: Vec<[f64; 3]>,
    pub spacing_b: f64,
}

pub fn surface_case(g: &[Vec<f64>], sev: Severity, seed: u64, na: usize, nb: usize) -> SurfaceCase {
    let mut rng = StdRng::seed_from_u64(seed);
    let level = 30.0;
    let (rows, cols) = (g.len() as f64, g[0].len() as f64);
    let sample = |n: usize, rng: &mut StdRng| -> Vec<[f64; 2]> {
        let mut v = Vec::new();
        while v.len() < n {
            let (x, y) = (
                rng.random_range(0.0..cols - 1.0),
                rng.random_range(0.0..rows - 1.0),
            );
            if bilinear(g, x, y) > level {
                v.push([x, y]);
            }
        }
        v
    };
    let pa = sample(na, &mut rng);
    let pb = sample(nb, &mut rng);
    let all: Vec<[f64; 2]> = pa.iter().chain(&pb).copied().collect();
    let w = Warp::random(&mut rng, sev, &all);
    let gain = 1.0 + rng.random_range(-0.1..=0.1);
    // z scaled so its range is comparable to xy (docs/method.md §8.3): 350 kPa ≈ 20 sensels.
    let zs = 20.0 / 350.0;
    let lift = |p: [f64; 2], gain: f64| bilinear(g, p[0], p[1]) * zs * gain;
    let a: Vec<[f64; 3]> = pa.iter().map(|&p| [p[0], p[1], lift(p, 1.0)]).collect();
    let b: Vec<[f64; 3]> = pb
        .iter()
        .map(|&p| {
            let q = w.apply(p);
            [q[0], q[1], lift(p, gain)]
        })
        .collect();
    let truth: Vec<[f64; 3]> = pa
        .iter()
        .map(|&p| {
            let q = w.apply(p);
            [q[0], q[1], lift(p, gain)]
        })
        .collect();
    // Spacing: mean nearest-neighbour distance of B.
    let spacing_b = modal_core::shape::nearest_neighbour_stats_of(&b.concat(), 3).0;
    SurfaceCase {
        a,
        b,
        truth,
        spacing_b,
    }
}
