//! The order-preserving assignment of two cyclic sequences (closed contours), by dynamic
//! programming, and the count of crossed matches of any assignment between them.
//!
//! Rows and columns are the nodes of two closed sequences, in order. A match `f` is
//! *order-preserving* when the partners of the matched rows, read in row order, go once round the
//! columns in their order: cutting the columns just before the first row's partner makes `f`
//! increasing. Matches may therefore *wrap* (pass from the last column to column 0): a closed
//! contour's numbering starts at an arbitrary node, so only the cyclic order means anything. Both
//! sequences are read in one direction; a caller whose sequences may run opposite ways reverses
//! one of them first (modal-core orients both contours counter-clockwise).
//!
//! **Saturating** ([`solve`], every row matched, `n ≤ m`): for each of the `m` partners `r` of
//! row 0, the rows `1 … n−1` go increasingly into the columns after `r`; row `i` can only take
//! the `i`-th to `(i + m − n)`-th column after `r`, a band of `w = m − n + 1` offsets, and
//! `E[i][k] = c[i][r+i+k] + min_{k' ≤ k} E[i−1][k']` (prefix minima). Time `O(n · m · (m − n +
//! 1))`: `O(n²)` for equal counts, `O(n · m²)` at worst; memory `O(n · (m − n + 1))`. Maes'
//! divide and conquer over `r` (the optimal paths of different starts do not cross) would bring
//! the worst case to `O(n · m · log m)`; contours of consecutive frames differ by a few nodes, so
//! the band is narrow and the plain recurrence keeps a pair's time at JV's (BENCHMARKS.md).
//!
//! No cheap certificate of optimality is known for the constrained problem (the assignment duals
//! certify the unconstrained optimum, only a lower bound here); the tests check it against
//! enumeration of every order-preserving map.
//!
//! **With a threshold** ([`solve_with_threshold`], any row or column unmatched at `τ/2`): the
//! cyclic alignment of the two sequences, the linear alignment (`D[i][j] = min(D[i−1][j],
//! D[i][j−1], D[i−1][j−1] + c − τ)`) of the rows with the columns cut before each of the `m`
//! columns, the cuts visited by Maes' divide and conquer (each aligned inside the corridor its
//! neighbours' optimal paths leave): time `O(n · m · log m)`, memory `O(n · m)`.

use crate::{AssignError, Solution};

/// Best saturating order-preserving match of the normalised problem (`1 ≤ n ≤ m`, minimisation,
/// entries finite or `+inf`): the partner of every row.
///
/// # Errors
/// [`AssignError::Infeasible`] when every order-preserving match uses a forbidden entry.
pub(crate) fn solve(c: &[f64], n: usize, m: usize) -> Result<Solution, AssignError> {
    debug_assert!(1 <= n && n <= m && c.len() == n * m);
    let w = m - n + 1;
    let mut prev = vec![f64::INFINITY; w];
    let mut cur = vec![f64::INFINITY; w];
    let (mut best, mut best_r) = (f64::INFINITY, 0);
    let lanes = band_totals(c, n, m);
    for (r, &total) in lanes.iter().enumerate() {
        if total < best {
            (best, best_r) = (total, r);
        }
    }
    for r in lanes.len()..m {
        let total = band_pass(c, n, m, r, &mut prev, &mut cur, None);
        // Strictly better only: ties keep the lowest start, so the result is deterministic.
        if total < best {
            (best, best_r) = (total, r);
        }
    }
    if best == f64::INFINITY {
        return Err(AssignError::Infeasible);
    }
    let mut table = vec![f64::INFINITY; n * w];
    band_pass(c, n, m, best_r, &mut prev, &mut cur, Some(&mut table));
    Ok(Solution {
        row_to_col: band_traceback(&table, n, m, w, best_r),
        u: Vec::new(),
        v: Vec::new(),
    })
}

/// One start `r` of the saturating recurrence: the cheapest total with row 0 on column `r`.
/// `table`, when given (`n × w`), keeps every row of `E` for the traceback.
fn band_pass(
    c: &[f64],
    n: usize,
    m: usize,
    r: usize,
    prev: &mut Vec<f64>,
    cur: &mut Vec<f64>,
    mut table: Option<&mut [f64]>,
) -> f64 {
    let w = prev.len();
    prev.fill(f64::INFINITY);
    prev[0] = c[r];
    if let Some(t) = table.as_deref_mut() {
        t[..w].copy_from_slice(prev);
    }
    for i in 1..n {
        let row = &c[i * m..(i + 1) * m];
        let mut j = (r + i) % m;
        let mut run_min = f64::INFINITY;
        for (e, &before) in cur.iter_mut().zip(prev.iter()) {
            run_min = run_min.min(before);
            *e = row[j] + run_min;
            j += 1;
            if j == m {
                j = 0;
            }
        }
        std::mem::swap(prev, cur);
        if let Some(t) = table.as_deref_mut() {
            t[i * w..(i + 1) * w].copy_from_slice(prev);
        }
    }
    prev.iter().copied().fold(f64::INFINITY, f64::min)
}

/// [`band_pass`]'s totals of the starts `0 … 8⌊m/8⌋ − 1`, eight starts side by side in two
/// AVX2 registers (lane `l` of a group is start `r + l`, whose costs on a row are the lane
/// before's moved by one column: one load from the row written twice). Each lane runs the same
/// additions and minima as [`band_pass`] in the same order, so the totals are the same; empty
/// when the CPU has no AVX2 or `m < 8` (the caller runs [`band_pass`] for the starts left).
fn band_totals(c: &[f64], n: usize, m: usize) -> Vec<f64> {
    #[cfg(target_arch = "x86_64")]
    {
        if m >= 8
            && let Some(simd) = pulp::x86::V3::try_new()
        {
            return simd.vectorize(BandsAvx2 { simd, c, n, m });
        }
    }
    let _ = (c, n, m);
    Vec::new()
}

/// The arguments of [`bands_avx2`], run by pulp compiled for AVX2.
#[cfg(target_arch = "x86_64")]
struct BandsAvx2<'a> {
    simd: pulp::x86::V3,
    c: &'a [f64],
    n: usize,
    m: usize,
}

#[cfg(target_arch = "x86_64")]
impl pulp::NullaryFnOnce for BandsAvx2<'_> {
    type Output = Vec<f64>;
    #[inline(always)]
    fn call(self) -> Vec<f64> {
        bands_avx2(self.simd, self.c, self.n, self.m)
    }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn bands_avx2(simd: pulp::x86::V3, c: &[f64], n: usize, m: usize) -> Vec<f64> {
    use std::arch::x86_64::__m256d;
    let a = simd.avx;
    let w = m - n + 1;
    // Each row twice, so that the eight starts' columns `j … j + 7` (j < m) are contiguous.
    let mut doubled = vec![0.0; n * 2 * m];
    for (row, twice) in c.chunks_exact(m).zip(doubled.chunks_exact_mut(2 * m)) {
        twice[..m].copy_from_slice(row);
        twice[m..].copy_from_slice(row);
    }
    let load = |at: usize| -> [__m256d; 2] {
        let v: [f64; 8] = doubled[at..at + 8].try_into().expect("eight columns");
        let (lo, hi): ([f64; 4], [f64; 4]) = ([v[0], v[1], v[2], v[3]], [v[4], v[5], v[6], v[7]]);
        [pulp::cast(lo), pulp::cast(hi)]
    };
    let inf = a._mm256_set1_pd(f64::INFINITY);
    let mut prev = vec![[inf; 2]; w];
    let mut cur = vec![[inf; 2]; w];
    let mut totals = Vec::with_capacity(m);
    for r in (0..m - m % 8).step_by(8) {
        prev.fill([inf; 2]);
        prev[0] = load(r);
        for i in 1..n {
            let base = i * 2 * m;
            let mut j = (r + i) % m;
            let mut run_min = [inf; 2];
            for (e, before) in cur.iter_mut().zip(prev.iter()) {
                let cost = load(base + j);
                for h in 0..2 {
                    run_min[h] = a._mm256_min_pd(before[h], run_min[h]);
                    e[h] = a._mm256_add_pd(cost[h], run_min[h]);
                }
                j += 1;
                if j == m {
                    j = 0;
                }
            }
            std::mem::swap(&mut prev, &mut cur);
        }
        let mut best = [inf; 2];
        for v in &prev {
            for h in 0..2 {
                best[h] = a._mm256_min_pd(v[h], best[h]);
            }
        }
        for h in best {
            let v: [f64; 4] = pulp::cast(h);
            totals.extend_from_slice(&v);
        }
    }
    totals
}

/// The partners of the optimum of start `r` from its table of `E`: the last row's best offset,
/// then for each earlier row the offset at or before the next row's that gave its prefix minimum.
fn band_traceback(table: &[f64], n: usize, m: usize, w: usize, r: usize) -> Vec<usize> {
    let argmin = |row: &[f64]| (1..row.len()).fold(0, |b, k| if row[k] < row[b] { k } else { b });
    let mut offsets = vec![0; n];
    offsets[n - 1] = argmin(&table[(n - 1) * w..n * w]);
    for i in (0..n - 1).rev() {
        let row = &table[i * w..(i + 1) * w];
        offsets[i] = argmin(&row[..=offsets[i + 1]]);
    }
    (0..n).map(|i| (r + i + offsets[i]) % m).collect()
}

/// Best order-preserving partial match of the normalised problem (`1 ≤ n ≤ m`, minimisation,
/// entries finite or `+inf`) where every unmatched row or column costs `t/2`: `None` for an
/// unmatched row. Never infeasible.
///
/// Maes' divide and conquer over the cut: the alignment cut before column `r` is a monotone path
/// from `(0, r)` to `(n, r + m)` in the grid whose columns run twice round the sequence, and for
/// cuts `r₁ < r < r₂` an optimal path of `r` lies between optimal paths of `r₁` and `r₂` (where
/// two optimal paths cross, exchanging their tails keeps both optimal). So the cut `0` is aligned
/// in the whole grid, the cut `m` is the same path moved by `m`, and each middle cut only inside
/// the corridor its neighbours' paths leave: every level of the recursion covers the grid about
/// once, `O(n · m · log m)` in all instead of `O(n · m²)`.
pub(crate) fn solve_with_threshold(c: &[f64], n: usize, m: usize, t: f64) -> Vec<Option<usize>> {
    debug_assert!(1 <= n && n <= m && c.len() == n * m);
    // A pair pays `c − t` against leaving both its nodes out; only savings (< 0) are worth taking.
    let saving: Vec<f64> = c.iter().map(|&x| (x - t).min(0.0)).collect();
    let mut grid = Corridor::new(n, m);
    let whole = CutPath::whole(n, m);
    let first = grid.align(&saving, 0, &whole, &whole);
    let last = first.moved(m);
    let mut best = (first.total, 0, first.pairs.clone());
    between(&saving, &mut grid, &first, &last, &mut best);
    best.2
}

/// The middle cuts strictly between `low.r` and `high.r`, recursively; `best` keeps the cheapest
/// total (the lowest cut on ties, for a deterministic answer).
fn between(
    s: &[f64],
    grid: &mut Corridor,
    low: &CutPath,
    high: &CutPath,
    best: &mut (f64, usize, Vec<Option<usize>>),
) {
    if high.r - low.r < 2 {
        return;
    }
    let mid = grid.align(s, (low.r + high.r) / 2, low, high);
    if mid.total < best.0 || (mid.total == best.0 && mid.r < best.1) {
        *best = (mid.total, mid.r, mid.pairs.clone());
    }
    between(s, grid, low, &mid, best);
    between(s, grid, &mid, high, best);
}

/// One cut's optimal alignment: its total saving, the columns its path visits on each row of
/// the doubled grid (`lo[i] ..= hi[i]`), and the partner of every row.
struct CutPath {
    lo: Vec<usize>,
    hi: Vec<usize>,
    total: f64,
    r: usize,
    pairs: Vec<Option<usize>>,
}

impl CutPath {
    /// No path: the bounds of the whole doubled grid, for a cut aligned without a corridor.
    fn whole(n: usize, m: usize) -> CutPath {
        CutPath {
            lo: vec![0; n + 1],
            hi: vec![2 * m; n + 1],
            total: 0.0,
            r: 0,
            pairs: Vec::new(),
        }
    }

    /// The same alignment read from the cut `r + shift` (`shift` a multiple of `m`).
    fn moved(&self, shift: usize) -> CutPath {
        CutPath {
            lo: self.lo.iter().map(|&j| j + shift).collect(),
            hi: self.hi.iter().map(|&j| j + shift).collect(),
            total: self.total,
            r: self.r + shift,
            pairs: self.pairs.clone(),
        }
    }
}

/// Scratch for the corridor alignments: `d[i][j − from[i]]` the best saving of rows `< i` with
/// the columns `r … j − 1` of the doubled grid, `step` the move that reached it.
struct Corridor {
    n: usize,
    m: usize,
    from: Vec<usize>,
    to: Vec<usize>,
    row_start: Vec<usize>,
    d: Vec<f64>,
    step: Vec<u8>,
}

const DIAGONAL: u8 = 0;
const SKIP_ROW: u8 = 1;
const SKIP_COLUMN: u8 = 2;

impl Corridor {
    fn new(n: usize, m: usize) -> Self {
        let cells = (n + 1) * (m + 1);
        Corridor {
            n,
            m,
            from: vec![0; n + 1],
            to: vec![0; n + 1],
            row_start: vec![0; n + 1],
            d: vec![0.0; cells],
            step: vec![0; cells],
        }
    }

    /// The alignment cut before column `r`, its path kept on or right of `low`'s and on or left
    /// of `high`'s on every row.
    fn align(&mut self, s: &[f64], r: usize, low: &CutPath, high: &CutPath) -> CutPath {
        let (n, m) = (self.n, self.m);
        for i in 0..=n {
            self.from[i] = low.lo[i].max(r);
            self.to[i] = high.hi[i].min(r + m);
        }
        // Each row's cells start where the previous row's end: at most `m + 1` per row.
        let at =
            |row_start: &[usize], i: usize, j: usize, from: &[usize]| row_start[i] + j - from[i];
        for i in 1..=n {
            self.row_start[i] = self.row_start[i - 1] + self.to[i - 1] + 1 - self.from[i - 1];
        }
        let (from, to, row_start) = (&self.from, &self.to, &self.row_start);
        for j in from[0]..=to[0] {
            // Row 0: columns skipped before the first pair, free.
            self.d[at(row_start, 0, j, from)] = 0.0;
            self.step[at(row_start, 0, j, from)] = SKIP_COLUMN;
        }
        for i in 1..=n {
            let row = &s[(i - 1) * m..i * m];
            let inside = |i: usize, j: usize| from[i] <= j && j <= to[i];
            for j in from[i]..=to[i] {
                // Skips first on ties, so that a pair saving nothing is left out.
                let mut best = (f64::INFINITY, SKIP_ROW);
                if inside(i - 1, j) {
                    best = (self.d[at(row_start, i - 1, j, from)], SKIP_ROW);
                }
                if j > from[i] {
                    let left = self.d[at(row_start, i, j - 1, from)];
                    if left < best.0 {
                        best = (left, SKIP_COLUMN);
                    }
                }
                if j > 0 && inside(i - 1, j - 1) {
                    let diag = self.d[at(row_start, i - 1, j - 1, from)] + row[(j - 1) % m];
                    if diag < best.0 {
                        best = (diag, DIAGONAL);
                    }
                }
                self.d[at(row_start, i, j, from)] = best.0;
                self.step[at(row_start, i, j, from)] = best.1;
            }
        }
        // Back from (n, r + m): the rows' column spans and the pairs.
        let (mut i, mut j) = (n, r + m);
        let total = self.d[at(row_start, n, j, from)];
        let mut path = CutPath {
            lo: vec![j; n + 1],
            hi: vec![j; n + 1],
            total,
            r,
            pairs: vec![None; n],
        };
        while i > 0 || j > r {
            match self.step[at(row_start, i, j, from)] {
                DIAGONAL => {
                    path.pairs[i - 1] = Some((j - 1) % m);
                    (i, j) = (i - 1, j - 1);
                    path.hi[i] = j;
                }
                SKIP_ROW => {
                    i -= 1;
                    path.hi[i] = j;
                }
                _ => j -= 1,
            }
            path.lo[i] = j;
        }
        path
    }
}

/// The reference for the divide and conquer: every cut aligned in the whole grid, `O(n · m²)`.
#[cfg(test)]
fn solve_with_threshold_every_cut(
    c: &[f64],
    n: usize,
    m: usize,
    t: f64,
) -> (f64, Vec<Option<usize>>) {
    let saving: Vec<f64> = c.iter().map(|&x| (x - t).min(0.0)).collect();
    let mut grid = Corridor::new(n, m);
    let whole = CutPath::whole(n, m);
    let mut best = (f64::INFINITY, Vec::new());
    for r in 0..m {
        let p = grid.align(&saving, r, &whole, &whole);
        if p.total < best.0 {
            best = (p.total, p.pairs);
        }
    }
    best
}

/// The number of crossed pairs of matches between two closed sequences: the fewest pairs of
/// matches `(i, j)`, `(i', j')` with `i < i'` but `j > j'` over every choice of the node each
/// sequence's numbering starts at (both read in the same direction). 0 exactly when the matches
/// preserve the cyclic order (one-to-one or not); a match that shares its row or its column with
/// another never crosses it.
///
/// Any matches of any solver, in any order. Time `O(g · (k + s))` for `k` matches over `g`
/// distinct rows, `s` the sum of the squared numbers of matches sharing a column (`k` when
/// one-to-one); memory `O(k)`.
///
/// ```
/// // Partners in cyclic order (wrapping from column 3 to 0): no crossing.
/// assert_eq!(assign::cyclic_crossings(&[(0, 2), (1, 3), (2, 0), (3, 1)]), 0);
/// // Rows 1 and 2 swapped: one crossed pair, whatever the start.
/// assert_eq!(assign::cyclic_crossings(&[(0, 0), (1, 2), (2, 1), (3, 3)]), 1);
/// ```
pub fn cyclic_crossings(pairs: &[(usize, usize)]) -> usize {
    let k = pairs.len();
    if k < 2 {
        return 0;
    }
    let (ri, ga) = dense_ranks(pairs.iter().map(|p| p.0));
    let (rj, gb) = dense_ranks(pairs.iter().map(|p| p.1));
    let count_by = |r: &[usize], g: usize| {
        let mut c = vec![0usize; g];
        r.iter().for_each(|&x| c[x] += 1);
        c
    };
    let (per_i, per_j) = (count_by(&ri, ga), count_by(&rj, gb));
    // `below_i[x]`: matches whose row rank is `< x` (and likewise for columns).
    let prefix = |c: &[usize]| -> Vec<usize> {
        std::iter::once(0)
            .chain(c.iter().scan(0, |s, &x| {
                *s += x;
                Some(*s)
            }))
            .collect()
    };
    let (below_i, below_j) = (prefix(&per_i), prefix(&per_j));
    let groups = |r: &[usize], g: usize| {
        let mut v: Vec<Vec<usize>> = vec![Vec::new(); g];
        r.iter().enumerate().for_each(|(p, &x)| v[x].push(p));
        v
    };
    let (rows_of, cols_of) = (groups(&ri, ga), groups(&rj, gb));
    let mut at_cut_a = straight_inversions(&ri, &rj) as i64;
    let mut best = at_cut_a;
    for (a, first_rows) in rows_of.iter().enumerate() {
        // Every start of the columns with the rows starting at their `a`-th distinct node.
        let mut f = at_cut_a;
        for group in &cols_of {
            f += column_to_end(group, &ri, a, ga, &below_i, k);
            best = best.min(f);
        }
        // The rows' start moves past row group `a` (columns starting at column rank 0).
        at_cut_a += group_to_end(first_rows, &rj, &below_j, k);
    }
    best as usize
}

/// Inversions of the matches as numbered: pairs with `i < i'` and `j > j'`.
fn straight_inversions(ri: &[usize], rj: &[usize]) -> usize {
    let k = ri.len();
    (0..k)
        .map(|p| {
            (p + 1..k)
                .filter(|&q| (ri[p] < ri[q] && rj[p] > rj[q]) || (ri[p] > ri[q] && rj[p] < rj[q]))
                .count()
        })
        .sum()
}

/// The change in inversions when the matches of `group` (one row rank, currently the first)
/// become the last rows: each loses its inversions with later-numbered columns' smaller ones and
/// gains one with every larger column outside its row.
fn group_to_end(group: &[usize], rj: &[usize], below_j: &[usize], k: usize) -> i64 {
    let mut delta = 0i64;
    for &p in group {
        let inside_below = group.iter().filter(|&&q| rj[q] < rj[p]).count();
        let inside_equal = group.iter().filter(|&&q| rj[q] == rj[p]).count();
        let below = below_j[rj[p]] - inside_below;
        let equal = below_j[rj[p] + 1] - below_j[rj[p]] - inside_equal;
        let above = k - group.len() - below - equal;
        delta += above as i64 - below as i64;
    }
    delta
}

/// The change in inversions when the matches of `group` (one column rank, currently the first
/// after the cut) become the last columns, rows starting at their rank `a` of `ga`.
fn column_to_end(
    group: &[usize],
    ri: &[usize],
    a: usize,
    ga: usize,
    below_i: &[usize],
    k: usize,
) -> i64 {
    let shifted = |p: usize| (ri[p] + ga - a) % ga;
    // Matches whose shifted row rank is below `x`: the ranks a … a + x − 1, cyclically.
    let below_shifted = |x: usize| {
        let end = a + x;
        if end <= ga {
            below_i[end] - below_i[a]
        } else {
            below_i[ga] - below_i[a] + below_i[end - ga]
        }
    };
    let mut delta = 0i64;
    for &p in group {
        let x = shifted(p);
        let inside_below = group.iter().filter(|&&q| shifted(q) < x).count();
        let inside_equal = group.iter().filter(|&&q| shifted(q) == x).count();
        let below = below_shifted(x) - inside_below;
        let equal = below_i[ri[p] + 1] - below_i[ri[p]] - inside_equal;
        let above = k - group.len() - below - equal;
        delta += above as i64 - below as i64;
    }
    delta
}

/// Each value's rank among the distinct values, and how many distinct values there are.
fn dense_ranks(values: impl Iterator<Item = usize>) -> (Vec<usize>, usize) {
    let v: Vec<usize> = values.collect();
    let mut sorted = v.clone();
    sorted.sort_unstable();
    sorted.dedup();
    let ranks = v
        .iter()
        .map(|x| sorted.partition_point(|y| y < x))
        .collect();
    (ranks, sorted.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `Σ (c − t)` over the kept pairs of a partial match.
    fn objective(c: &[f64], m: usize, t: f64, pairs: &[Option<usize>]) -> f64 {
        let row_cost = |(i, j): (usize, &Option<usize>)| j.map_or(0.0, |j| c[i * m + j] - t);
        pairs.iter().enumerate().map(row_cost).sum()
    }

    proptest! {
        /// The divide and conquer over the cut finds every cut's optimum: the same total as
        /// aligning every cut in the whole grid, on sizes the brute force of the integration
        /// tests cannot reach, ties included (integer costs).
        #[test]
        fn divide_and_conquer_equals_every_cut(
            (n, m) in (1usize..30).prop_flat_map(|n| (Just(n), n..40)),
            seed in any::<u64>(),
            levels in 2u32..50,
            t in 0.0f64..50.0,
        ) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let c: Vec<f64> = (0..n * m).map(|_| f64::from(rng.random_range(0..levels))).collect();
            let fast = solve_with_threshold(&c, n, m, t);
            let (every, _) = solve_with_threshold_every_cut(&c, n, m, t);
            let got = objective(&c, m, t, &fast);
            prop_assert!((got - every).abs() <= 1e-9 * (1.0 + every.abs()), "{} vs {}", got, every);
            // One-to-one: no column twice.
            let mut cols: Vec<usize> = fast.iter().flatten().copied().collect();
            cols.sort_unstable();
            cols.dedup();
            prop_assert_eq!(cols.len(), fast.iter().flatten().count());
        }

        /// The eight starts side by side give each start's total of the one-start pass bit for
        /// bit, ties, forbidden (`+inf`) entries and bands of every width included.
        #[test]
        fn starts_side_by_side_equal_one_start_at_a_time(
            (n, m) in (1usize..30).prop_flat_map(|n| (Just(n), n..45)),
            seed in any::<u64>(),
            levels in 2u32..50,
        ) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let c: Vec<f64> = (0..n * m)
                .map(|_| match rng.random_range(0..levels + 2) {
                    0 => f64::INFINITY,
                    v => f64::from(v) * 0.37,
                })
                .collect();
            let lanes = band_totals(&c, n, m);
            #[cfg(target_arch = "x86_64")]
            if pulp::x86::V3::is_available() {
                prop_assert_eq!(lanes.len(), m - m % 8);
            }
            let w = m - n + 1;
            let (mut prev, mut cur) = (vec![f64::INFINITY; w], vec![f64::INFINITY; w]);
            for (r, total) in lanes.iter().enumerate() {
                let one = band_pass(&c, n, m, r, &mut prev, &mut cur, None);
                prop_assert_eq!(total.to_bits(), one.to_bits(), "start {}", r);
            }
        }
    }
}
