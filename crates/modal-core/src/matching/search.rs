//! Searching the affinity matrix for one-to-one correspondences (docs/method.md §6.1–6.2).

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::features::AffinityMatrix;
use crate::error::ModalError;

/// Which search produces the primary matches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Search {
    /// Mutual best matches under the threshold (the original modal matching, docs/method.md §6.1).
    Local,
    /// Optimal assignment saturating the smaller object (the paper's optimisation, docs/method.md
    /// §6.2).
    #[default]
    Global,
    /// Every node of the first object to its lowest-cost node of the second, under the
    /// threshold: many-to-one, no excess step. For independent samplings of one surface, where
    /// no one-to-one answer can be right for every node (BENCHMARKS.md, "Surfaces").
    Best,
}

/// How a threshold interacts with the optimal assignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ThresholdMode {
    /// Solve the assignment first, then delete pairs whose cost exceeds the threshold (the paper's
    /// order).
    #[default]
    AfterAssignment,
    /// Let the optimiser reject pairs: every node may instead pay half the threshold to stay
    /// unmatched, so a pair is kept only where it beats leaving both of its nodes out.
    InOptimizer,
}

/// Local search (docs/method.md §6.1): `(i, j)` is a match iff `j` is the row minimum of `i`, `i`
/// the column minimum of `j` (ties to the lowest index) and `Z[i, j] ≤ threshold`. Sorted by `i`.
pub(crate) fn local_matches(z: &AffinityMatrix, threshold: f64) -> Vec<(usize, usize)> {
    let (n, m) = (z.rows(), z.cols());
    if n == 0 || m == 0 {
        return Vec::new();
    }
    let mut col_best = vec![0usize; m];
    for j in 0..m {
        for i in 1..n {
            if z.get(i, j) < z.get(col_best[j], j) {
                col_best[j] = i;
            }
        }
    }
    let mut out = Vec::new();
    for (i, row) in z.as_slice().chunks_exact(m).enumerate() {
        let best = row_minimum(row);
        if col_best[best] == i && row[best] <= threshold {
            out.push((i, best));
        }
    }
    out
}

/// Index of a row's smallest entry, the lowest on ties (the rule of both searches below).
fn row_minimum(row: &[f64]) -> usize {
    let mut best = 0;
    for j in 1..row.len() {
        if row[j] < row[best] {
            best = j;
        }
    }
    best
}

/// One-sided best matches: every node `i` of A paired with its row minimum `j` (ties to the lowest
/// index) when `Z[i, j] ≤ threshold` — many-to-one, the read-out of coherent point drift's
/// `argmax P`. For independent samplings of one surface, where no one-to-one answer can be right
/// for every node. Sorted by `i`.
pub(crate) fn best_matches(z: &AffinityMatrix, threshold: f64) -> Vec<(usize, usize)> {
    if z.cols() == 0 {
        return Vec::new();
    }
    z.as_slice()
        .chunks_exact(z.cols())
        .enumerate()
        .filter_map(|(i, row)| {
            let j = row_minimum(row);
            (row[j] <= threshold).then_some((i, j))
        })
        .collect()
}

/// The price of leaving a node out of the order-preserving search when an excess step follows
/// (a share of the largest cost, as the threshold): `τ/2` for each node of a pair costlier than
/// `τ`. Between two closed contours of (nearly) equal node counts, a saturating order-preserving
/// match is (nearly) a rotation of the numbering, so where a warp stretches one stretch of the
/// outline and shrinks another a whole run of nodes lands a spacing off; with this price the
/// search leaves a node out there instead and the excess step gives it its partner, in order.
/// 0.4 was chosen on the tuning halves of the synthetic and landmark benchmarks (BENCHMARKS.md,
/// "The order-preserving solver"); 0.2–0.3 and 0.5–1.0 were measured beside it.
pub(crate) const ORDERED_GAP: f64 = 0.4;

/// Global search (docs/method.md §6.2): the minimum-cost one-to-one matching that saturates the
/// smaller object (equivalent to padding with constant-cost dummy nodes), then the threshold.
/// With the order-preserving solver and `gaps` (an excess step follows), the search may leave
/// nodes out at [`ORDERED_GAP`] unless the threshold already prices them. Sorted by `i`.
pub(crate) fn global_matches(
    z: &AffinityMatrix,
    method: assign::Method,
    threshold: f64,
    mode: ThresholdMode,
    gaps: bool,
) -> Result<Vec<(usize, usize)>, ModalError> {
    let (n, m) = (z.rows(), z.cols());
    if n == 0 || m == 0 {
        return Ok(Vec::new());
    }
    let opts = assign::Options {
        method,
        ..Default::default()
    };
    let priced = mode == ThresholdMode::InOptimizer && threshold.is_finite();
    let sol = if gaps && method == assign::Method::Ordered && !priced {
        assign::solve_with_threshold(z.as_slice(), n, m, ORDERED_GAP, &opts)?
    } else if priced {
        // The (n+m)² padding with dummy cost τ of docs/method.md §6.2, solved without building it.
        assign::solve_with_threshold(z.as_slice(), n, m, threshold, &opts)?
    } else {
        assign::solve(z.as_slice(), n, m, &opts)?
    };
    let out = sol
        .pairs()
        .into_iter()
        .filter(|&(i, j)| z.get(i, j) <= threshold)
        .collect();
    Ok(out)
}

/// Stage 4: the primary matches of `z` by the options' search (local, global or best) under
/// `threshold`, sorted by row; `gaps` as in [`global_matches`].
pub(crate) fn primary_matches(
    z: &AffinityMatrix,
    search: Search,
    method: assign::Method,
    threshold: f64,
    mode: ThresholdMode,
    gaps: bool,
) -> Result<Vec<(usize, usize)>, ModalError> {
    Ok(match search {
        Search::Global => global_matches(z, method, threshold, mode, gaps)?,
        Search::Local => local_matches(z, threshold),
        Search::Best => best_matches(z, threshold),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zm(rows: usize, cols: usize, v: &[f64]) -> AffinityMatrix {
        AffinityMatrix::new(rows, cols, v.to_vec()).unwrap()
    }

    #[test]
    fn local_is_mutual_best_with_threshold() {
        // Row 0 prefers col 0, col 0 prefers row 1 → no match for row 0.
        let z = zm(3, 3, &[0.2, 0.5, 0.9, 0.1, 0.4, 0.8, 0.7, 0.6, 0.3]);
        assert_eq!(local_matches(&z, 1.0), vec![(1, 0), (2, 2)]);
        assert_eq!(local_matches(&z, 0.2), vec![(1, 0)]);
        // Ties go to the lowest index.
        let t = zm(2, 2, &[0.5, 0.5, 0.5, 0.5]);
        assert_eq!(local_matches(&t, 1.0), vec![(0, 0)]);
    }

    #[test]
    fn best_is_each_row_minimum_many_to_one() {
        // Rows 0 and 1 both prefer column 0; row 2 ties columns 1 and 2.
        let z = zm(3, 3, &[0.2, 0.5, 0.9, 0.1, 0.4, 0.8, 0.7, 0.3, 0.3]);
        assert_eq!(best_matches(&z, 1.0), vec![(0, 0), (1, 0), (2, 1)]);
        assert_eq!(best_matches(&z, 0.2), vec![(0, 0), (1, 0)]);
        // Every mutual-best match is a row minimum.
        for p in local_matches(&z, 1.0) {
            assert!(best_matches(&z, 1.0).contains(&p));
        }
        assert!(best_matches(&zm(2, 0, &[]), 1.0).is_empty());
    }

    #[test]
    fn global_is_optimal_and_rectangular() {
        // Greedy would take (0,0)=0.1 and then pay 0.9; optimum is (0,1)+(1,0) = 0.4.
        let z = zm(2, 2, &[0.1, 0.2, 0.2, 0.9]);
        for method in [
            assign::Method::JonkerVolgenant,
            assign::Method::Hungarian,
            assign::Method::NetworkSimplex,
        ] {
            let g = global_matches(&z, method, 1.0, ThresholdMode::AfterAssignment, false).unwrap();
            assert_eq!(g, vec![(0, 1), (1, 0)]);
        }
        // 3 × 2 and its transpose: one row stays unmatched.
        let z = zm(3, 2, &[0.0, 0.5, 0.4, 0.45, 0.5, 0.0]);
        let g = global_matches(
            &z,
            assign::Method::default(),
            1.0,
            ThresholdMode::AfterAssignment,
            false,
        )
        .unwrap();
        assert_eq!(g, vec![(0, 0), (2, 1)]);
        let gt = global_matches(
            &z.transposed(),
            assign::Method::default(),
            1.0,
            ThresholdMode::AfterAssignment,
            false,
        )
        .unwrap();
        assert_eq!(gt, vec![(0, 0), (1, 2)]);
    }

    #[test]
    fn the_ordered_search_leaves_a_costly_node_to_the_excess_step() {
        // Equal counts: the only saturating order-preserving matches are rotations, and the
        // cheapest (the identity) must pair row 1 with column 1 at 0.9. With gaps, row 1 and
        // column 1 are left out (0.9 > ORDERED_GAP), the rest kept.
        let z = zm(3, 3, &[0.0, 1.0, 1.0, 1.0, 0.9, 0.1, 1.0, 1.0, 0.0]);
        let ordered = assign::Method::Ordered;
        let after = ThresholdMode::AfterAssignment;
        let saturating = global_matches(&z, ordered, 1.0, after, false).unwrap();
        assert_eq!(saturating, vec![(0, 0), (1, 1), (2, 2)]);
        let gapped = global_matches(&z, ordered, 1.0, after, true).unwrap();
        assert_eq!(gapped, vec![(0, 0), (2, 2)]);
        // Gaps are the ordered solver's only; a threshold in the optimiser sets its own price.
        let jv = global_matches(&z, assign::Method::default(), 1.0, after, true).unwrap();
        assert_eq!(jv.len(), 3);
        let during = global_matches(&z, ordered, 0.95, ThresholdMode::InOptimizer, true).unwrap();
        assert_eq!(during, vec![(0, 0), (1, 1), (2, 2)]);
    }

    #[test]
    fn thresholds_after_and_inside_the_optimizer() {
        let z = zm(2, 2, &[0.1, 0.6, 0.3, 0.95]);
        // Optimum: (0,1)+(1,0) = 0.9 < 0.1+0.95. After-threshold 0.5 drops (0,1).
        let after = global_matches(
            &z,
            assign::Method::default(),
            0.5,
            ThresholdMode::AfterAssignment,
            false,
        )
        .unwrap();
        assert_eq!(after, vec![(1, 0)]);
        // Inside the optimizer with τ = 0.5: keeping (0,0) alone costs 0.1 + 2·0.25 = 0.6, better
        // than (1,0) alone (0.3 + 0.5) → (0,0).
        let inside = global_matches(
            &z,
            assign::Method::default(),
            0.5,
            ThresholdMode::InOptimizer,
            false,
        )
        .unwrap();
        assert_eq!(inside, vec![(0, 0)]);
    }
}
