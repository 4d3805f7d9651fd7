//! Builds the modal model of a foot-like closed contour, then matches it against a turned,
//! stretched and bent copy sampled with a different number of points, and prints how many of
//! its points were matched within one node spacing of their true position.
//!
//! Run: `cargo run --example match_contours`

use modal_core::{match_shapes, modal_basis, MatchOptions, ModelOptions, Shape, Topology};
use std::f64::consts::TAU;

/// A smooth, non-symmetric closed outline (radius as a function of the angle), at parameter `t`.
fn outline(t: f64) -> [f64; 2] {
    let r = 1.0 + 0.3 * (2.0 * t).cos() + 0.1 * (3.0 * t).sin() + 0.05 * (5.0 * t).cos();
    [1.6 * r * t.cos(), r * t.sin()]
}

/// The known deformation: bend, anisotropic scale, a 25° turn and a shift.
fn warp([x, y]: [f64; 2]) -> [f64; 2] {
    let (x, y) = (1.10 * x, 0.92 * (y + 0.08 * x * x));
    let (s, c) = 25f64.to_radians().sin_cos();
    [c * x - s * y + 3.0, s * x + c * y - 1.0]
}

/// `n` points evenly spaced by arc length along `curve`, starting at parameter `start`,
/// with the parameter of each point.
fn sample(curve: impl Fn(f64) -> [f64; 2], n: usize, start: f64) -> (Vec<[f64; 2]>, Vec<f64>) {
    const FINE: usize = 4000;
    let ts: Vec<f64> = (0..=FINE)
        .map(|i| start + TAU * i as f64 / FINE as f64)
        .collect();
    let pts: Vec<[f64; 2]> = ts.iter().map(|&t| curve(t)).collect();
    let mut arc = vec![0.0];
    for w in pts.windows(2) {
        arc.push(arc.last().unwrap() + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
    }
    let total = *arc.last().unwrap();
    let mut params = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let s = total * k as f64 / n as f64;
        while arc[j + 1] < s {
            j += 1;
        }
        let f = (s - arc[j]) / (arc[j + 1] - arc[j]);
        params.push(ts[j] + f * (ts[j + 1] - ts[j]));
    }
    (params.iter().map(|&t| curve(t)).collect(), params)
}

fn dist(p: &[f64], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn main() -> Result<(), modal_core::ModalError> {
    let (a_pts, a_params) = sample(outline, 60, 0.0);
    let (b_pts, _) = sample(|t| warp(outline(t)), 66, 1.3);
    let a = Shape::from_points_2d(&a_pts, Topology::ClosedContour)?;
    let b = Shape::from_points_2d(&b_pts, Topology::ClosedContour)?;

    // The model of A alone: Gaussian element, 30 lowest modes.
    let model = modal_basis(
        &a,
        &ModelOptions {
            n_modes: Some(30),
            ..Default::default()
        },
    )?;
    let omega2: Vec<String> = model.eigenvalues[..6]
        .iter()
        .map(|w| format!("{w:.4e}"))
        .collect();
    println!(
        "A: {} nodes, sigma {:.3}, lowest squared frequencies {}",
        model.n_nodes,
        model.sigma.unwrap_or(f64::NAN),
        omega2.join(" ")
    );

    // Match with the setting for two outlines that `pedomatch match` uses (rotation search ending
    // in a fit of the outlines, no affine re-fits, excess nodes).
    let r = match_shapes(&a, &b, &MatchOptions::for_outlines())?;
    println!(
        "matches: {} local, {} one-to-one, {} excess; {} re-fits",
        r.local_count(),
        r.one_to_one_count(),
        r.excess_count(),
        r.refits
    );

    // Ground truth: A's point i lies at warp(outline(t_i)) on B.
    let spacing = (0..b.len())
        .map(|j| dist(b.point(j), b_pts[(j + 1) % b.len()]))
        .sum::<f64>()
        / b.len() as f64;
    let mut right = 0;
    for (i, &t) in a_params.iter().enumerate() {
        let truth = warp(outline(t));
        let found = r.pairs.iter().find(|p| p.a == i);
        if found.is_some_and(|p| dist(b.point(p.b), truth) <= spacing) {
            right += 1;
        }
    }
    println!(
        "accuracy: {right}/{} points of A matched within one B spacing ({:.1} %)",
        a.len(),
        100.0 * right as f64 / a.len() as f64
    );
    Ok(())
}
