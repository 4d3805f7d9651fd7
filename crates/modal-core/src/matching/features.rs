//! Modal feature vectors, the cross-object mode alignment of docs/method.md §5.4 and the affinity
//! matrix Z.

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use std::sync::OnceLock;

use super::prealign::nearest;
use super::prepare::PreparedShape;
use super::recipe::MatchOptions;
use crate::error::ModalError;
use crate::simd::dot;

/// The retained modes of one object, ready for comparison with another object's.
///
/// Stored `(dim·n) × k`, column-major (`data[p * dim * n + a * n + i]` is component `a` of node `i`
/// in mode `p`), matching the component-major row layout of [`crate::model::ModalBasis::mode`].
#[derive(Debug, Clone, PartialEq)]
pub struct ModalFeatures {
    /// Dimension of the nodes (2 or 3).
    pub dim: usize,
    /// Nodes of the object.
    pub n_nodes: usize,
    /// Modes kept.
    pub n_modes: usize,
    data: Vec<f64>,
}

impl ModalFeatures {
    /// Takes modes `skip .. skip + k` of a `(dim·n) × K` mode matrix given column by column
    /// (`column(p)` returns mode `p`). Each column is scaled to norm `√n` (independent of ρ, σ and
    /// node count, docs/method.md §5.1) and signed so that its largest-|·| entry is positive
    /// (docs/method.md §4.2).
    pub(crate) fn from_columns<'a, F>(
        dim: usize,
        n_nodes: usize,
        available: usize,
        skip: usize,
        k: usize,
        column: F,
    ) -> Result<Self, ModalError>
    where
        F: Fn(usize) -> &'a [f64],
    {
        if skip + k > available {
            return Err(ModalError::TooFewModes {
                requested: skip + k,
                available,
            });
        }
        if k == 0 {
            return Err(ModalError::NoModeKept {
                skipped: skip,
                available,
            });
        }
        let len = dim * n_nodes;
        let cols: Vec<&[f64]> = (skip..skip + k).map(&column).collect();
        if let Some(col) = cols.iter().find(|c| c.len() != len) {
            return Err(ModalError::SizeMismatch {
                what: "entries of a mode",
                expected: len,
                found: col.len(),
            });
        }
        let mut data = Vec::with_capacity(len * k);
        for (col, sum_sq) in cols.iter().zip(sums_of_squares(&cols, len)) {
            let norm = sum_sq.sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(ModalError::NonFiniteResult { stage: "a mode" });
            }
            let big = crate::simd::first_largest_abs(col);
            let s = (n_nodes as f64).sqrt() / norm * if big < 0.0 { -1.0 } else { 1.0 };
            data.extend(col.iter().map(|v| v * s));
        }
        Ok(Self {
            dim,
            n_nodes,
            n_modes: k,
            data,
        })
    }

    /// Builds features from a [`crate::model::ModalBasis`].
    pub(crate) fn from_basis(
        basis: &crate::model::ModalBasis,
        skip: usize,
        k: usize,
    ) -> Result<Self, ModalError> {
        let available = basis.n_modes();
        Self::from_columns(basis.dim, basis.n_nodes, available, skip, k, |p| {
            basis.mode(p)
        })
    }

    /// Mode `p` as a `(dim·n)` component-major vector.
    pub fn mode(&self, p: usize) -> &[f64] {
        let len = self.dim * self.n_nodes;
        &self.data[p * len..(p + 1) * len]
    }

    /// Re-indexes and re-signs the modes: new mode `p` is `signs[p] · old mode order[p]`.
    pub(crate) fn permuted(&self, order: &[usize], signs: &[f64]) -> Self {
        let len = self.dim * self.n_nodes;
        let mut data = Vec::with_capacity(order.len() * len);
        for (&q, &s) in order.iter().zip(signs) {
            data.extend(self.mode(q).iter().map(|v| v * s));
        }
        Self {
            dim: self.dim,
            n_nodes: self.n_nodes,
            n_modes: order.len(),
            data,
        }
    }
}

/// `Σ v²` of each column, each summed in order from its first entry (the bits of a plain
/// sequential sum); four columns at a time, so that four running sums advance side by side
/// instead of one waiting on its previous addition at every entry.
fn sums_of_squares(cols: &[&[f64]], len: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(cols.len());
    let mut quads = cols.chunks_exact(4);
    for q in &mut quads {
        let mut s = [0.0f64; 4];
        for r in 0..len {
            for (c, col) in q.iter().enumerate() {
                s[c] += col[r] * col[r];
            }
        }
        out.extend(s);
    }
    out.extend(
        quads
            .remainder()
            .iter()
            .map(|c| c.iter().map(|v| v * v).sum::<f64>()),
    );
    out
}

/// Outcome of the cross-object mode alignment.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ModeAlignment {
    /// Mode of object B assigned to each of A's modes.
    pub order: Vec<usize>,
    /// Sign applied to that mode of B.
    pub signs: Vec<f64>,
    /// |cosine similarity| of each aligned pair (below about 0.3 the alignment is unreliable).
    pub similarity: Vec<f64>,
}

/// docs/method.md §5.4: aligns the sign and order of B's modes to A's by the spatial correlation of
/// their displacement fields, sampled at each A node's nearest B node (`nn[i]`). Mode `p` of A may
/// be paired with B's modes `q` with `|p − q| ≤ band` (one-to-one, rectangular assignment).
pub(crate) fn align_modes(
    a: &ModalFeatures,
    b: &ModalFeatures,
    nn: &[usize],
    band: usize,
    method: assign::Method,
) -> Result<ModeAlignment, ModalError> {
    if a.dim != b.dim {
        return Err(ModalError::DimensionMismatch { a: a.dim, b: b.dim });
    }
    if nn.len() != a.n_nodes {
        return Err(ModalError::SizeMismatch {
            what: "nearest neighbours of A's nodes",
            expected: a.n_nodes,
            found: nn.len(),
        });
    }
    let (n, m, d) = (a.n_nodes, b.n_nodes, a.dim);
    let ka = a.n_modes;
    let kb = b.n_modes;
    if kb < ka {
        return Err(ModalError::TooFewModes {
            requested: ka,
            available: kb,
        });
    }
    // B's modes resampled at A's nodes through the nearest-neighbour map.
    let mut bs = vec![0.0; kb * d * n];
    let mut bnorm = vec![0.0; kb];
    for q in 0..kb {
        let mode = b.mode(q);
        let dst = &mut bs[q * d * n..(q + 1) * d * n];
        for c in 0..d {
            for i in 0..n {
                dst[c * n + i] = mode[c * m + nn[i]];
            }
        }
        bnorm[q] = dot(dst, dst).sqrt();
    }
    let mut corr = vec![0.0; ka * kb];
    // Pairs outside the band are forbidden, so only the band's correlations are computed.
    const FORBIDDEN: f64 = 1e3;
    let mut cost = vec![FORBIDDEN; ka * kb];
    for p in 0..ka {
        let ap = a.mode(p);
        let an = dot(ap, ap).sqrt();
        for q in p.saturating_sub(band)..(p + band + 1).min(kb) {
            let bq = &bs[q * d * n..(q + 1) * d * n];
            let den = an * bnorm[q];
            let c = if den > 0.0 { dot(ap, bq) / den } else { 0.0 };
            corr[p * kb + q] = c;
            cost[p * kb + q] = -c.abs();
        }
    }
    // Modes have no cyclic order: the order-preserving solver is for the nodes of contours, and
    // the modes are then aligned by the default solver (all others give the same optimum).
    let method = match method {
        assign::Method::Ordered => assign::Method::default(),
        other => other,
    };
    let sol = assign::solve(
        &cost,
        ka,
        kb,
        &assign::Options {
            method,
            ..Default::default()
        },
    )?;
    let mut order = Vec::with_capacity(ka);
    let mut signs = Vec::with_capacity(ka);
    let mut similarity = Vec::with_capacity(ka);
    for (p, q) in sol.row_to_col.iter().enumerate() {
        let q = q.ok_or(ModalError::Assign(assign::AssignError::Infeasible))?;
        let c = corr[p * kb + q];
        order.push(q);
        signs.push(if c < 0.0 { -1.0 } else { 1.0 });
        similarity.push(c.abs());
    }
    Ok(ModeAlignment {
        order,
        signs,
        similarity,
    })
}

/// Dense `rows × cols` matrix of modal distances between the nodes of two objects (docs/method.md
/// §5.1):
/// `Z[i, j] = ‖f_i − f_j‖²`, row `i` a node of A, column `j` a node of B.
#[derive(Debug, Clone, PartialEq)]
pub struct AffinityMatrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl AffinityMatrix {
    /// Wraps a row-major matrix, rejecting wrong sizes and non-finite or negative entries.
    pub fn new(rows: usize, cols: usize, data: Vec<f64>) -> Result<Self, ModalError> {
        if data.len() != rows * cols {
            return Err(ModalError::SizeMismatch {
                what: "entries of the affinity matrix",
                expected: rows * cols,
                found: data.len(),
            });
        }
        // A branch-free sweep first (it vectorises; the check runs on every pass's matrices),
        // the position of the offending entry only when there is one.
        let bad = |v: &f64| !v.is_finite() | (*v < 0.0);
        let any_bad = data
            .chunks(64)
            .any(|c| c.iter().fold(false, |acc, v| acc | bad(v)));
        if let Some(index) = any_bad.then(|| data.iter().position(bad)).flatten() {
            return Err(ModalError::InvalidEntry {
                what: "affinity matrix",
                index,
                value: data[index],
            });
        }
        Ok(Self { rows, cols, data })
    }

    /// `Z` of two feature sets, both with the same number of modes.
    pub(crate) fn from_features(a: &ModalFeatures, b: &ModalFeatures) -> Result<Self, ModalError> {
        if a.dim != b.dim {
            return Err(ModalError::DimensionMismatch { a: a.dim, b: b.dim });
        }
        if a.n_modes != b.n_modes {
            return Err(ModalError::SizeMismatch {
                what: "modes of B",
                expected: a.n_modes,
                found: b.n_modes,
            });
        }
        let (n, m, d, k) = (a.n_nodes, b.n_nodes, a.dim, a.n_modes);
        // ‖f_i − f_j‖² = ‖f_i‖² + ‖f_j‖² − 2 f_i·f_j, the cross terms one product per component
        // (A_c B_cᵀ with A_c the n × k block of component c): a cache-blocked SIMD kernel instead
        // of n·m separate dot products.
        let fa = MatRef::from_column_major_slice(&a.data, d * n, k);
        let fb = MatRef::from_column_major_slice(&b.data, d * m, k);
        let mut cross = Mat::<f64>::zeros(n, m);
        for c in 0..d {
            matmul(
                cross.as_mut(),
                if c == 0 { Accum::Replace } else { Accum::Add },
                fa.subrows(c * n, n),
                fb.subrows(c * m, m).transpose(),
                1.0,
                Par::Seq,
            );
        }
        crate::simd::clear_upper_state();
        let sq_norms = |f: MatRef<'_, f64>, len: usize| -> Vec<f64> {
            let mut out = vec![0.0; len];
            for p in 0..k {
                for c in 0..d {
                    for (i, o) in out.iter_mut().enumerate() {
                        let v = f[(c * len + i, p)];
                        *o += v * v;
                    }
                }
            }
            out
        };
        let (na, nb) = (sq_norms(fa, n), sq_norms(fb, m));
        let mut data = vec![0.0; n * m];
        for i in 0..n {
            for j in 0..m {
                data[i * m + j] = (na[i] + nb[j] - 2.0 * cross[(i, j)]).max(0.0);
            }
        }
        Self::new(n, m, data)
    }

    /// Rows: nodes of the first object.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Columns: nodes of the second object.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// The entry `Z[i, j]`.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.cols + j]
    }

    /// Row-major values.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// The largest entry (0 for an empty matrix).
    pub fn max(&self) -> f64 {
        // Four running maxima break the chain of dependent comparisons; the entries are finite
        // and non-negative (checked by `new`), so the order does not change the result.
        let mut lanes = [0.0f64; 4];
        let chunks = self.data.chunks_exact(4);
        let tail = chunks.remainder().iter().copied().fold(0.0, f64::max);
        for c in chunks {
            for (l, v) in lanes.iter_mut().zip(c) {
                *l = l.max(*v);
            }
        }
        lanes.into_iter().fold(tail, f64::max)
    }

    /// Divides by the largest entry, so thresholds are fractions in [0, 1] (docs/method.md §5.1).
    /// An all-zero matrix (identical objects with identical sampling) is left as is.
    pub(crate) fn normalized(mut self) -> Self {
        let mx = self.max();
        if mx > 0.0 {
            self.data.iter_mut().for_each(|v| *v /= mx);
        }
        self
    }

    /// Raises every entry to the power `p` (> 0). On a max-normalised matrix the entries stay in
    /// [0, 1] and every row's and column's order is kept, so thresholds and mutual-best matches
    /// mean the same; only an optimal assignment, which adds costs up, changes. `p < 1` makes
    /// that sum favour many near-exact pairs over evenly spread errors.
    pub(crate) fn powered(mut self, p: f64) -> Self {
        // Powers 1/2, 1/4 and 1/8 (the surfaces' default) as repeated square roots: monotone like
        // `powf`, within an ulp or two of it, and several times cheaper (`powf` was 4 % of a
        // surface pair). One sweep per root: a loop over the entries vectorises, while the roots
        // of one entry in a row form a chain of dependent scalar square roots (a third of a
        // surface pass's own time).
        let roots = [0.5, 0.25, 0.125].iter().position(|&r| r == p);
        match roots {
            Some(k) => {
                for _ in 0..=k {
                    self.data.iter_mut().for_each(|v| *v = v.sqrt());
                }
            }
            None if p != 1.0 => self.data.iter_mut().for_each(|v| *v = v.powf(p)),
            None => {}
        }
        self
    }

    /// Re-indexes rows and columns: new `(i, j)` is old `(row_of[i], col_of[j])`.
    pub(crate) fn reindexed(&self, row_of: &[usize], col_of: &[usize]) -> Self {
        let mut data = Vec::with_capacity(row_of.len() * col_of.len());
        for &r in row_of {
            data.extend(col_of.iter().map(|&c| self.data[r * self.cols + c]));
        }
        Self {
            rows: row_of.len(),
            cols: col_of.len(),
            data,
        }
    }

    pub(crate) fn transposed(&self) -> Self {
        let mut data = vec![0.0; self.data.len()];
        for i in 0..self.rows {
            for j in 0..self.cols {
                data[j * self.rows + i] = self.data[i * self.cols + j];
            }
        }
        Self {
            rows: self.cols,
            cols: self.rows,
            data,
        }
    }
}

/// Stage 3: the cost matrix the search reads at A's coordinates `cur` (B's at `b`, `k` modes) — the modal
/// distances between A's features and B's after B's modes are aligned to A's (§5.4), or the
/// squared distances of the aligned positions when the modes are left out (`None`), mixed with
/// positions and raised to the power as the options say; max-normalised.
///
/// `ahead`, when given, holds the position term at `cur`, which another thread may have
/// computed while the modes were being solved.
pub(crate) fn cost_matrix(
    cur: &[f64],
    b: &[f64],
    d: usize,
    modes: Option<(&ModalFeatures, &ModalFeatures)>,
    k: usize,
    opts: &MatchOptions,
    ahead: Option<&PositionTermAhead>,
) -> Result<AffinityMatrix, ModalError> {
    let z = match modes {
        Some((fa, fb)) => {
            // B has `k + band` modes.
            let band = fb.n_modes.saturating_sub(k);
            let nn: Vec<usize> = nearest(cur, b, d).into_iter().map(|x| x.0).collect();
            let al = align_modes(fa, fb, &nn, band, opts.method)?;
            let fb_al = fb.permuted(&al.order, &al.signs);
            AffinityMatrix::from_features(fa, &fb_al)?.normalized()
        }
        _ => position_costs(cur, b, d)?,
    }
    .powered(opts.cost_power);
    if !(modes.is_some() && opts.position_weight > 0.0) {
        return Ok(z);
    }
    let w = opts.position_weight;
    let computed;
    let p = match ahead.and_then(PositionTermAhead::get) {
        Some(p) => p,
        None => {
            computed = position_term(cur, b, d, opts.cost_power)?;
            &computed
        }
    };
    debug_assert_eq!((p.rows(), p.cols()), (z.rows(), z.cols()));
    let mixed = z
        .as_slice()
        .iter()
        .zip(p.as_slice())
        .map(|(x, y)| (1.0 - w) * x + w * y)
        .collect();
    Ok(AffinityMatrix::new(z.rows(), z.cols(), mixed)?.normalized())
}

/// The position term [`cost_matrix`] mixes into the modal cost at A's coordinates `cur`
/// (`position_weight`): max-normalised squared distances to B's nodes, raised to the cost power.
/// It needs no modes, so it can be computed while they are being solved.
pub(crate) fn position_term(
    cur: &[f64],
    b: &[f64],
    d: usize,
    cost_power: f64,
) -> Result<AffinityMatrix, ModalError> {
    Ok(position_costs(cur, b, d)?.powered(cost_power))
}

/// The position term at A's start coordinates, computed once by whichever thread asks first
/// (the helper of [`super::Parallelism::Pair`] after B's solve, or the first pass): the other
/// finds it done or waits for it. The start is published when the pre-alignment ends.
pub(crate) struct PositionTermAhead {
    b: PreparedShape,
    cost_power: f64,
    start: OnceLock<Vec<f64>>,
    /// `None` when it could not be computed: the pass computes it again and reports the error.
    term: OnceLock<Option<AffinityMatrix>>,
}

impl PositionTermAhead {
    /// For B's normalised nodes, before A's start is known.
    pub(crate) fn new(b: PreparedShape, cost_power: f64) -> Self {
        Self {
            b,
            cost_power,
            start: OnceLock::new(),
            term: OnceLock::new(),
        }
    }

    /// A's start coordinates, once (later calls are ignored).
    pub(crate) fn publish(&self, start: &[f64]) {
        let _ = self.start.set(start.to_vec());
    }

    /// The term at the published start: computed here unless done (or under way, then waited
    /// for); `None` before the start is published or if it could not be computed.
    pub(crate) fn get(&self) -> Option<&AffinityMatrix> {
        let start = self.start.get()?;
        self.term
            .get_or_init(|| {
                let b = self.b.get();
                position_term(start, &b.pts, b.dim(), self.cost_power).ok()
            })
            .as_ref()
    }
}

/// Max-normalised squared distances between aligned coordinates (2-D or 3-D, as every
/// [`Shape`](crate::Shape) is).
pub(super) fn position_costs(a: &[f64], b: &[f64], d: usize) -> Result<AffinityMatrix, ModalError> {
    let (n, m) = (a.len() / d.max(1), b.len() / d.max(1));
    let data = match d {
        2 => squared_distances::<2>(a, b, m),
        3 => squared_distances::<3>(a, b, m),
        dim => return Err(ModalError::UnsupportedDimension { dim }),
    };
    Ok(AffinityMatrix::new(n, m, data)?.normalized())
}

/// The `n × m` squared distances between the points of `a` and `b` (`D` coordinates each), with
/// the dimension known to the compiler so that the inner loop is unrolled and vectorised.
fn squared_distances<const D: usize>(a: &[f64], b: &[f64], m: usize) -> Vec<f64> {
    let mut data = vec![0.0; a.len() / D * m];
    for (row, p) in data.chunks_exact_mut(m.max(1)).zip(a.chunks_exact(D)) {
        for (z, q) in row.iter_mut().zip(b.chunks_exact(D)) {
            *z = (0..D).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>();
        }
    }
    data
}

#[cfg(test)]
mod tests {
    proptest::proptest! {
        /// The four-lane maximum is the plain one, wherever the largest entry sits (in the lanes
        /// or the tail of a length that is not a multiple of four).
        #[test]
        fn max_is_the_largest_entry(
            xs in proptest::collection::vec(0.0f64..1e6, 0..40),
        ) {
            let z = super::AffinityMatrix::new(1, xs.len(), xs.clone()).unwrap();
            proptest::prop_assert_eq!(z.max(), xs.iter().copied().fold(0.0, f64::max));
        }

        /// A bad entry anywhere (also past the first 64-entry block of the quick check) is
        /// reported at its own index.
        #[test]
        fn new_names_the_first_bad_entry(
            len in 1usize..300,
            at in 0usize..300,
            bad in proptest::sample::select(vec![f64::NAN, f64::INFINITY, -1e-300, -2.0]),
        ) {
            let at = at % len;
            let mut xs = vec![0.5; len];
            xs[at] = bad;
            let err = super::AffinityMatrix::new(1, len, xs).unwrap_err();
            proptest::prop_assert!(
                matches!(err, super::ModalError::InvalidEntry { index, .. } if index == at),
                "{err:?}"
            );
        }
    }

    #[test]
    fn powered_keeps_the_order_and_the_ends() {
        let z = super::AffinityMatrix::new(1, 3, vec![0.0, 0.25, 1.0]).unwrap();
        assert_eq!(z.powered(0.5).as_slice(), &[0.0, 0.5, 1.0]);
    }

    #[test]
    fn root_powers_agree_with_powf_and_keep_the_order() {
        let xs: Vec<f64> = (0..=2000).map(|i| (i as f64 / 2000.0).powi(3)).collect();
        for p in [0.5, 0.25, 0.125] {
            let z = super::AffinityMatrix::new(1, xs.len(), xs.clone()).unwrap();
            let got = z.powered(p);
            for (x, y) in xs.iter().zip(got.as_slice()) {
                let want = x.powf(p);
                assert!(
                    (y - want).abs() <= 4.0 * f64::EPSILON * want,
                    "{x}^{p}: {y} vs {want}"
                );
            }
            assert!(
                got.as_slice().windows(2).all(|w| w[0] <= w[1]),
                "order at p = {p}"
            );
        }
    }

    use super::*;

    fn feats(dim: usize, n: usize, cols: &[Vec<f64>]) -> ModalFeatures {
        ModalFeatures::from_columns(dim, n, cols.len(), 0, cols.len(), |p| &cols[p]).unwrap()
    }

    #[test]
    fn columns_are_scaled_and_signed() {
        let cols = vec![
            vec![0.0, -3.0, 0.0, 4.0 * 0.0 + 1.0],
            vec![2.0, 0.0, 0.0, 0.0],
        ];
        let f = feats(2, 2, &cols);
        let m0 = f.mode(0);
        let norm: f64 = m0.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((norm - 2f64.sqrt()).abs() < 1e-12);
        // largest-|·| entry was -3 → flipped positive
        assert!(m0[1] > 0.0 && m0[3] < 0.0);
        assert!(ModalFeatures::from_columns(2, 2, 2, 1, 2, |p| &cols[p]).is_err());
        let zero = [vec![0.0; 4]];
        assert!(ModalFeatures::from_columns(2, 2, 1, 0, 1, |p| &zero[p]).is_err());
    }

    #[test]
    fn affinity_is_squared_feature_distance() {
        let a = feats(
            2,
            3,
            &[
                vec![1.0, 2.0, 3.0, 0.5, 0.0, -1.0],
                vec![0.0, 1.0, 0.0, 2.0, 1.0, 1.0],
            ],
        );
        let b = feats(2, 2, &[vec![3.0, 1.0, 1.0, 0.0], vec![1.0, 1.0, 0.0, 2.0]]);
        let z = AffinityMatrix::from_features(&a, &b).unwrap();
        for i in 0..3 {
            for j in 0..2 {
                let mut s = 0.0;
                for p in 0..2 {
                    for c in 0..2 {
                        let d = a.mode(p)[c * 3 + i] - b.mode(p)[c * 2 + j];
                        s += d * d;
                    }
                }
                assert!((z.get(i, j) - s).abs() < 1e-12);
            }
        }
        let zn = z.clone().normalized();
        assert!((zn.max() - 1.0).abs() < 1e-15);
        let t = z.transposed();
        assert_eq!(t.get(1, 2), z.get(2, 1));
    }

    #[test]
    fn alignment_recovers_swaps_and_signs() {
        // Five smooth "modes" on 8 nodes; B = A with modes 1,2 swapped and mode 3 negated,
        // plus two extra band modes; identical node sets (nn = identity).
        let n = 8;
        let base: Vec<Vec<f64>> = (0..7)
            .map(|p| {
                (0..2 * n)
                    .map(|r| ((r as f64 + 1.0) * (p as f64 + 1.0) * 0.37).sin() + 0.1 * p as f64)
                    .collect()
            })
            .collect();
        let a = feats(2, n, &base[..5]);
        let order_b = [0usize, 2, 1, 3, 4, 5, 6];
        let cols_b: Vec<Vec<f64>> = order_b
            .iter()
            .enumerate()
            .map(|(k, &p)| {
                base[p]
                    .iter()
                    .map(|v| if k == 3 { -v } else { *v })
                    .collect()
            })
            .collect();
        let b = ModalFeatures::from_columns(2, n, 7, 0, 7, |p| &cols_b[p]).unwrap();
        let nn: Vec<usize> = (0..n).collect();
        let al = align_modes(&a, &b, &nn, 3, assign::Method::default()).unwrap();
        assert_eq!(al.order, vec![0, 2, 1, 3, 4]);
        let bb = b.permuted(&al.order, &al.signs);
        for p in 0..5 {
            for (x, y) in a.mode(p).iter().zip(bb.mode(p)) {
                assert!((x - y).abs() < 1e-12, "mode {p}");
            }
        }
        assert!(al.similarity.iter().all(|s| (s - 1.0).abs() < 1e-12));
    }
}
