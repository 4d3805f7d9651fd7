//! Where each node of A lands on B's outline ([`MatchResult::outline_images`]): after the
//! coherent drift, the point of B's outline nearest each moved node, averaged with the image the
//! drift of B onto A gives it when run backwards (docs/method.md §7.5).
//!
//! The drift is not symmetric: the nodes of A are the centres of the mixture and B's are the
//! data, so drifting A onto B and B onto A give two slightly different maps, each biased the way
//! its mixture pulls. Reading the second backwards and averaging the two along B's outline is the
//! inverse-consistent correspondence of registration (Christensen & Johnson, *Consistent image
//! registration*, IEEE TMI 20(7), 2001): on the landmark benchmark's tuning pairs it carried the
//! landmarks as well within one spacing and better within two than either direction alone.
//!
//! [`MatchResult::outline_images`]: super::MatchResult::outline_images

/// The point of the closed outline `b` (row-major, `m × d`) nearest each of `q`, as a position
/// `j + t` along `b`'s numbering (see [`MatchResult::outline_images`](super::MatchResult::outline_images)).
pub(crate) fn outline_positions(q: &[f64], b: &[f64], d: usize) -> Vec<f64> {
    let m = b.len() / d;
    q.chunks_exact(d)
        .map(|p| {
            let mut best = (f64::INFINITY, 0.0);
            for j in 0..m {
                let (s, e) = (
                    &b[j * d..(j + 1) * d],
                    &b[(j + 1) % m * d..((j + 1) % m + 1) * d],
                );
                let (mut dd, mut dp) = (0.0, 0.0);
                for c in 0..d {
                    dd += (e[c] - s[c]) * (e[c] - s[c]);
                    dp += (p[c] - s[c]) * (e[c] - s[c]);
                }
                let t = if dd > 0.0 {
                    (dp / dd).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d2: f64 = (0..d)
                    .map(|c| (s[c] + t * (e[c] - s[c]) - p[c]).powi(2))
                    .sum();
                if d2 < best.0 {
                    best = (d2, j as f64 + t);
                }
            }
            // t = 1 is the next node itself.
            best.1 % m as f64
        })
        .collect()
}

/// Arc length along a closed outline (row-major, `k × d`): `cum[j]` from node 0 to node `j`,
/// `cum[k]` the perimeter.
struct ArcLength {
    cum: Vec<f64>,
}

impl ArcLength {
    fn of(c: &[f64], d: usize) -> Self {
        let k = c.len() / d;
        let mut cum = Vec::with_capacity(k + 1);
        cum.push(0.0);
        for j in 0..k {
            let (s, e) = (
                &c[j * d..(j + 1) * d],
                &c[(j + 1) % k * d..((j + 1) % k + 1) * d],
            );
            let step: f64 = (0..d).map(|i| (e[i] - s[i]).powi(2)).sum::<f64>().sqrt();
            cum.push(cum[j] + step);
        }
        Self { cum }
    }

    fn perimeter(&self) -> f64 {
        self.cum[self.cum.len() - 1]
    }

    /// The arc length of the position `j + t` along the numbering.
    fn at(&self, pos: f64) -> f64 {
        let k = self.cum.len() - 1;
        let j = (pos.floor() as usize).min(k - 1);
        self.cum[j] + (pos - j as f64) * (self.cum[j + 1] - self.cum[j])
    }

    /// The position `j + t` along the numbering of the arc length `s` (taken round the outline).
    fn position(&self, s: f64) -> f64 {
        let k = self.cum.len() - 1;
        let s = s.rem_euclid(self.perimeter());
        let j = self.cum.partition_point(|&c| c <= s).clamp(1, k) - 1;
        let len = self.cum[j + 1] - self.cum[j];
        let t = if len > 0.0 {
            (s - self.cum[j]) / len
        } else {
            0.0
        };
        (j as f64 + t) % k as f64
    }
}

/// `s` brought into (−total/2, total/2]: the shorter way round a closed outline.
fn wrap(s: f64, total: f64) -> f64 {
    let w = (s + total / 2.0).rem_euclid(total) - total / 2.0;
    if w == -total / 2.0 {
        total / 2.0
    } else {
        w
    }
}

/// The images of A's nodes on B's outline, taken both ways: `forward` (each node of A on B, as
/// positions along B's numbering) averaged along B's outline with `backward` (each node of B on
/// A, along A's numbering) read backwards ([`backward_arcs`]). `a` and `b` are the two closed
/// outlines (row-major, `d` columns). `None` when the backward images cannot be read backwards
/// or a forward image is not finite.
pub(crate) fn both_ways(
    forward: &[f64],
    backward: &[f64],
    a: &[f64],
    b: &[f64],
    d: usize,
) -> Option<Vec<f64>> {
    if forward.len() != a.len() / d || !forward.iter().all(|v| v.is_finite()) {
        return None;
    }
    let (arc_a, arc_b) = (ArcLength::of(a, d), ArcLength::of(b, d));
    let back = backward_arcs(backward, &arc_a, &arc_b)?;
    let total_b = arc_b.perimeter();
    Some(
        forward
            .iter()
            .zip(back)
            .map(|(&f, back)| {
                let s = arc_b.at(f);
                arc_b.position(s + 0.5 * wrap(back - s, total_b))
            })
            .collect(),
    )
}

/// [`backward_arcs`] as positions along B's numbering, for outlines `a` and `b` (row-major, `d`
/// columns).
#[cfg(test)]
pub(crate) fn read_backwards(backward: &[f64], a: &[f64], b: &[f64], d: usize) -> Option<Vec<f64>> {
    let (arc_a, arc_b) = (ArcLength::of(a, d), ArcLength::of(b, d));
    let arcs = backward_arcs(backward, &arc_a, &arc_b)?;
    Some(arcs.into_iter().map(|s| arc_b.position(s)).collect())
}

/// The arc lengths on B's outline of A's nodes' images, from the images on A's outline of B's
/// nodes (`backward`, positions along A's numbering): the map from B to A unwrapped round the
/// outlines, made monotone (matches that cross are flattened, so that each place on A has one
/// place on B) and inverted by linear interpolation in arc length. `None` when a value is not
/// finite, the counts do not fit, or the map does not go once round A.
fn backward_arcs(backward: &[f64], arc_a: &ArcLength, arc_b: &ArcLength) -> Option<Vec<f64>> {
    let total_a = arc_a.perimeter();
    let (n, m) = (arc_a.cum.len() - 1, arc_b.cum.len() - 1);
    if m == 0
        || backward.len() != m
        || !(total_a > 0.0 && arc_b.perimeter() > 0.0)
        || !backward.iter().all(|v| v.is_finite())
    {
        return None;
    }
    // A's arc length at each node of B, unwrapped along B's numbering and closed by node 0 again
    // (at B's perimeter): once round A, either way.
    let mut u = Vec::with_capacity(m + 1);
    u.push(arc_a.at(backward[0]));
    for k in 1..=m {
        let next = arc_a.at(backward[k % m]);
        let prev = u[k - 1];
        u.push(prev + wrap(next - prev, total_a));
    }
    let turn = u[m] - u[0];
    if (turn.abs() - total_a).abs() > 0.5 * total_a {
        return None;
    }
    let rising = turn > 0.0;
    for k in 1..=m {
        u[k] = if rising {
            u[k].max(u[k - 1])
        } else {
            u[k].min(u[k - 1])
        };
    }
    let x = &arc_b.cum;
    let lo = u[0].min(u[m]);
    let inverse = |p: f64| -> f64 {
        let q = lo + (p - lo).rem_euclid(total_a);
        // The segment of u holding q (u rising or falling along k).
        let k = if rising {
            u.partition_point(|&v| v <= q).clamp(1, m) - 1
        } else {
            u.partition_point(|&v| v >= q).clamp(1, m) - 1
        };
        let span = u[k + 1] - u[k];
        let t = if span != 0.0 {
            ((q - u[k]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        x[k] + t * (x[k + 1] - x[k])
    };
    Some(arc_a.cum[..n].iter().map(|&p| inverse(p)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `k` points of an ellipse from angle `start` (a fraction of a turn), turning `sign` ways.
    fn ellipse(k: usize, start: f64, sign: f64) -> Vec<f64> {
        (0..k)
            .flat_map(|i| {
                let t = sign * (start + i as f64 / k as f64) * std::f64::consts::TAU;
                [2.0 * t.cos(), t.sin()]
            })
            .collect()
    }

    #[test]
    fn arc_positions_round_trip() {
        let c = ellipse(37, 0.1, 1.0);
        let arc = ArcLength::of(&c, 2);
        for pos in [0.0, 0.25, 3.5, 17.999, 36.5] {
            assert!((arc.position(arc.at(pos)) - pos).abs() < 1e-9, "{pos}");
        }
        assert!((arc.position(arc.perimeter() + arc.at(2.0)) - 2.0).abs() < 1e-9);
        assert_eq!(wrap(3.0, 4.0), -1.0);
        assert_eq!(wrap(-2.0, 4.0), 2.0);
    }

    #[test]
    fn consistent_maps_give_their_common_images_either_orientation() {
        // A and B: one ellipse sampled from different starts and counts. The true image of each
        // node is the point of B at the same angle; both directions given exactly, the average is
        // that image, whichever way B turns.
        let (n, m) = (40, 53);
        let a = ellipse(n, 0.0, 1.0);
        for sign in [1.0, -1.0] {
            let b = ellipse(m, 0.013, sign);
            let forward = outline_positions(&a, &b, 2);
            let backward = outline_positions(&b, &a, 2);
            let both = both_ways(&forward, &backward, &a, &b, 2).unwrap();
            let arc_b = ArcLength::of(&b, 2);
            for (i, (&f, &s)) in forward.iter().zip(&both).enumerate() {
                let gap = wrap(arc_b.at(s) - arc_b.at(f), arc_b.perimeter());
                assert!(
                    gap.abs() < 0.02 * arc_b.perimeter() / m as f64,
                    "node {i}: {gap}"
                );
            }
        }
    }

    #[test]
    fn the_average_lies_halfway_between_two_slid_maps() {
        // Forward slides each node a quarter of B's spacing ahead of the true place, backward a
        // quarter behind (seen from A): the average is the true place.
        let (n, m) = (30, 30);
        let a = ellipse(n, 0.0, 1.0);
        let b = ellipse(m, 0.0, 1.0);
        let forward: Vec<f64> = (0..n).map(|i| (i as f64 + 0.25) % m as f64).collect();
        let backward: Vec<f64> = (0..m).map(|j| (j as f64 + 0.25) % n as f64).collect();
        let both = both_ways(&forward, &backward, &a, &b, 2).unwrap();
        let arc_b = ArcLength::of(&b, 2);
        for (i, &s) in both.iter().enumerate() {
            let gap = wrap(arc_b.at(s) - arc_b.at(i as f64), arc_b.perimeter());
            assert!(
                gap.abs() < 0.02 * arc_b.perimeter() / m as f64,
                "node {i}: {gap}"
            );
        }
    }

    #[test]
    fn backward_images_that_cannot_be_inverted_give_none() {
        let (a, b) = (ellipse(20, 0.0, 1.0), ellipse(24, 0.0, 1.0));
        let forward = outline_positions(&a, &b, 2);
        let mut backward = outline_positions(&b, &a, 2);
        // Every node of B on one place of A: the map does not go round A.
        let stuck = vec![3.0; backward.len()];
        assert!(both_ways(&forward, &stuck, &a, &b, 2).is_none());
        backward[5] = f64::NAN;
        assert!(both_ways(&forward, &backward, &a, &b, 2).is_none());
        assert!(both_ways(&forward, &backward[..10], &a, &b, 2).is_none());
    }
}
