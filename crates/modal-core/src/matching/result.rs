//! What a match returns: the pairs and what produced them.

use super::features::AffinityMatrix;
use super::prealign::Affine;

/// One correspondence: node `a` of the first object, node `b` of the second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchPair {
    /// Node of the first object.
    pub a: usize,
    /// Node of the second object.
    pub b: usize,
    /// The search's cost `Z[a, b]`: the max-normalised modal distance, with positions mixed in
    /// and raised to the power as [`MatchOptions::position_weight`](super::MatchOptions::position_weight) and
    /// [`MatchOptions::cost_power`](super::MatchOptions::cost_power) say.
    pub cost: f64,
    /// Found by the excess-node step (one-to-many) rather than by the one-to-one search.
    pub excess: bool,
}

impl MatchPair {
    /// Node `i` of the first object to node `i` of the second, for every `i < n`: the pairs of
    /// points and their images (a field through a displacement rather than through matches).
    pub fn each_to_itself(n: usize) -> Vec<MatchPair> {
        (0..n)
            .map(|i| MatchPair {
                a: i,
                b: i,
                cost: 0.0,
                excess: false,
            })
            .collect()
    }
}

/// Outcome of [`match_shapes`](super::match_shapes).
#[derive(Debug, Clone)]
pub struct MatchResult {
    /// The search's pairs sorted by `a` (one-to-one except with [`Search::Best`](super::Search::Best)), followed by
    /// excess pairs sorted by `b` (or by `a` when the first object is the larger).
    pub pairs: Vec<MatchPair>,
    /// The final affinity matrix the search used (entries in [0, 1]), rows = nodes of the first
    /// object, original order.
    pub affinity: AffinityMatrix,
    /// Mutual-best (local) matches on the final affinity, under the threshold, whatever `search`.
    pub local_pairs: Vec<(usize, usize)>,
    /// Nodes of the first object in no pair.
    pub unmatched_a: Vec<usize>,
    /// Nodes of the second object in no pair.
    pub unmatched_b: Vec<usize>,
    /// Modes per object used in the features.
    pub n_modes: usize,
    /// Modal affine re-fits actually performed.
    pub refits: usize,
    /// Modal solves of the first object (the second is solved once).
    pub solves: usize,
    /// The affine map `x ↦ M x + t` from the first object's coordinates to the second's that
    /// produced the aligned coordinates of the kept iteration (pre-alignment, then re-fits), in
    /// the callers' units: `transform.apply(a.coords())` equals [`Self::aligned_a`] up to
    /// rounding, unless a non-rigid refinement moved the nodes on ([`Self::drifted`],
    /// [`Refine::Modal`](super::Refine::Modal)).
    pub transform: Affine,
    /// The first object's nodes in the second's frame as the search used them (row-major,
    /// `n × dim`, the callers' node order and units).
    pub aligned_a: Vec<f64>,
    /// When both objects are closed contours: how many pairs of matches cross, read along the
    /// two contours in one direction (both counter-clockwise) from the starts that make the
    /// count smallest ([`assign::cyclic_crossings`]); 0 exactly when the matches keep the
    /// contours' cyclic order, as the `ordered` solver's always do. `None` for other objects.
    pub crossings: Option<usize>,
    /// When both objects are closed contours: where each node of the first object lands on the
    /// second's outline, as a position along the second's node numbering: `j + t` (`j` a node,
    /// `0 ≤ t < 1`) is the point `t` of the way from node `j` to node `j + 1` (node `m − 1` to
    /// node 0 for `j = m − 1`). After the coherent drift ([`Refine::Coherent`](super::Refine::Coherent),
    /// and [`Refine::Auto`](super::Refine::Auto) where it drifts) the point of the outline
    /// nearest the node's moved position in [`Self::aligned_a`], a correspondence finer than the
    /// nodes; where [`Refine::Auto`](super::Refine::Auto) drifts, that point averaged along the
    /// outline with the node's image under the second object's drift onto the first, read
    /// backwards (docs/method.md §7.5); otherwise the node of its first pair (`t = 0`), NaN for a
    /// node in no pair. `None` for other objects, and where a caller renumbers or drops the
    /// details.
    pub outline_images: Option<Vec<f64>>,
    /// Whether the coherent drift moved the first object's nodes ([`Refine::Coherent`](super::Refine::Coherent),
    /// and [`Refine::Auto`](super::Refine::Auto) for two outlines its gate takes for two
    /// specimens): [`Self::aligned_a`] then holds the moved nodes, which [`Self::transform`]
    /// does not map to.
    pub drifted: bool,
}

impl MatchResult {
    /// Number of local (mutual-best) matches.
    pub fn local_count(&self) -> usize {
        self.local_pairs.len()
    }
    /// Number of matches from the primary search (the paper's "optimisation" column): one-to-one
    /// except with [`Search::Best`](super::Search::Best), whose pairs are many-to-one. The tables
    /// and `pedomatch match --json` call it `optimisation_matches`, Python `optimisation_count`.
    pub fn one_to_one_count(&self) -> usize {
        self.pairs.iter().filter(|p| !p.excess).count()
    }
    /// Number of matches added by the excess-node step.
    pub fn excess_count(&self) -> usize {
        self.pairs.iter().filter(|p| p.excess).count()
    }
    /// The points of the second object's outline `b` (row-major, `m × dim`: the coordinates the
    /// match was made from) at [`Self::outline_images`]: where each node of the first object
    /// lands, in the callers' node order. `None` without images, where a node has none (NaN),
    /// or when `b` has fewer nodes than an image names.
    pub fn outline_image_points(&self, b: &[f64]) -> Option<Vec<f64>> {
        let d = self.transform.dim;
        let m = b.len() / d;
        let images = self.outline_images.as_ref()?;
        let mut out = Vec::with_capacity(images.len() * d);
        for &s in images {
            if !(s >= 0.0 && s < m as f64) {
                return None;
            }
            let (j, t) = (s.floor() as usize, s - s.floor());
            let k = (j + 1) % m;
            out.extend((0..d).map(|c| b[j * d + c] + t * (b[k * d + c] - b[j * d + c])));
        }
        Some(out)
    }
}
