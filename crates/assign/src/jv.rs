//! Jonker–Volgenant (LAPJV) shortest augmenting paths.
//!
//! Only column prices `v` are stored; a row's dual is implicit, `u[i] = c[i][x[i]] - v[x[i]]`,
//! and every assigned row keeps the invariant that its column is a cheapest one in reduced cost
//! `c[i][j] - v[j]`. Three phases:
//!
//! 1. initialisation — square: column reduction and reduction transfer; rectangular: prices
//!    start at zero (column reduction would break `v <= 0` on the unassigned columns);
//! 2. augmenting row reduction (auction-like), with a work budget (see [`arr`]);
//! 3. one Dijkstra-like shortest augmenting path per remaining free row, on dense costs, with
//!    LAPJV's list of columns at the current minimum distance.

use crate::{AssignError, Solution};

const NONE: usize = usize::MAX;

/// Solves the normalised problem (`n <= m`, minimise, entries finite or `+inf`).
///
/// The entries need not have been validated: every row is checked for NaN and `-inf` in the
/// first pass that reads it (column reduction, or the first scan in augmenting row reduction),
/// before anything depends on it, and such an entry gives an [`AssignError::InvalidEntry`]
/// whose position the caller recomputes (see `crate::solve`).
pub(crate) fn solve(c: &[f64], n: usize, m: usize) -> Result<Solution, AssignError> {
    let mut v = vec![0.0f64; m];
    let mut x = vec![NONE; n];
    let mut y = vec![NONE; m];
    // Rows whose entries were checked; column reduction checks them all.
    let mut seen: Vec<bool>;
    let tied = mostly_tied(c, n, m, &v);
    let mut free: Vec<usize> = if n == m && !tied {
        seen = Vec::new();
        column_reduction(c, n, &mut v, &mut x, &mut y)?
    } else {
        seen = vec![false; n];
        (0..n).collect()
    };
    free = arr(c, m, &mut v, &mut x, &mut y, free, &mut seen, tied)?;
    for (i, _) in seen.iter().enumerate().filter(|&(_, &s)| !s) {
        if !row_valid(&c[i * m..(i + 1) * m]) {
            return Err(AssignError::InvalidEntry { row: i, col: 0 });
        }
    }
    sap(c, m, &mut v, &mut x, &mut y, &free)?;
    let u = (0..n).map(|i| c[i * m + x[i]] - v[x[i]]).collect();
    Ok(Solution {
        row_to_col: x,
        u,
        v,
    })
}

/// Whether the cheapest entries of sampled rows are mostly tied (as on small integer costs).
///
/// Column reduction then gives most columns to the few rows that come first among the tied
/// minima, leaving most rows free with all their cheapest columns taken; starting from zero
/// prices instead, augmenting row reduction hands each row a free column among its tied
/// cheapest ones (measured: 11 ms against 7 ms on 2000×2000 integers in 1..=100). On untied
/// costs column reduction and reduction transfer remain much the better start (uniform
/// 2000×2000: 64 against 123 ms). Sixteen row scans decide; they also warm the cache.
fn mostly_tied(c: &[f64], n: usize, m: usize, zeros: &[f64]) -> bool {
    let k = n.min(16);
    let tied = (0..k)
        .map(|s| s * n / k)
        .filter(|&i| {
            let t = scan::<false>(&c[i * m..(i + 1) * m], zeros, zeros).top;
            t.j2 != NONE && t.min1 == t.min2
        })
        .count();
    2 * tied > k
}

/// No NaN and no `-inf` in the row (branch-free, vectorised).
fn row_valid(row: &[f64]) -> bool {
    row.iter().fold(true, |ok, &r| ok & (r > f64::NEG_INFINITY))
}

/// Column reduction and reduction transfer (square case). Returns the free rows.
fn column_reduction(
    c: &[f64],
    n: usize,
    v: &mut [f64],
    x: &mut [usize],
    y: &mut [usize],
) -> Result<Vec<usize>, AssignError> {
    let m = n;
    // Column minima, scanning rows to stay cache friendly on the row-major matrix.
    // The same pass checks every entry for NaN and -inf (see `solve`).
    let mut imin = vec![0usize; m];
    v.copy_from_slice(&c[..m]);
    let mut ok = row_valid(&c[..m]);
    for i in 1..n {
        let row = &c[i * m..(i + 1) * m];
        let (v, imin) = (&mut v[..m], &mut imin[..m]);
        for j in 0..m {
            let r = row[j];
            ok &= r > f64::NEG_INFINITY;
            let lt = r < v[j];
            v[j] = if lt { r } else { v[j] };
            imin[j] = if lt { i } else { imin[j] };
        }
    }
    if !ok {
        return Err(AssignError::InvalidEntry { row: 0, col: 0 });
    }
    if v.contains(&f64::INFINITY) {
        return Err(AssignError::Infeasible);
    }
    let mut matches = vec![0u32; n];
    for j in (0..m).rev() {
        let i = imin[j];
        matches[i] += 1;
        if matches[i] == 1 {
            x[i] = j;
            y[j] = i;
        } else if v[j] < v[x[i]] {
            let j1 = x[i];
            x[i] = j;
            y[j] = i;
            y[j1] = NONE;
        }
    }
    let mut free = Vec::new();
    for i in 0..n {
        if matches[i] == 0 {
            free.push(i);
        } else if matches[i] == 1 {
            // Reduction transfer: move the row's slack onto its column's price.
            let j1 = x[i];
            let t = top2(&c[i * m..(i + 1) * m], v);
            let min = if t.j1 == j1 { t.min2 } else { t.min1 };
            if min.is_finite() {
                v[j1] -= min;
            }
        }
    }
    Ok(free)
}

/// Augmenting row reduction: each free row takes its cheapest column, lowering that column's
/// price to the row's second-best reduced cost and evicting the previous owner, which is then
/// processed in turn.
///
/// On geometric costs many rows compete for columns whose reduced costs differ by little, and the
/// price decrements become tiny: LAPJV's two unbounded passes turn into a long price war (why
/// `lap.lapjv` is several times slower than scipy on Euclidean costs). On heavily tied integer
/// costs the best and second-best reduced costs are often equal, no price moves, and evicted
/// rows just bounce to the next pass. The phase is only a warm start for the exact shortest
/// paths, so it stops after `4n` row scans, or as soon as more than a quarter of the scans ended
/// in such a tie; the remaining free rows go to the shortest-path phase. Measured on the four
/// benchmark classes (BENCHMARKS.md, "Assignment solvers"), this keeps ARR's large gain on uniform and rectangular
/// costs and costs nothing on Euclidean and tied ones.
///
/// A row whose cheapest reduced cost is shared by a free column takes that column at no price
/// change (LAPJV's tie rule applied before evicting anyone): on tied integer costs this settles
/// most rows in one scan instead of bouncing them to the shortest-path phase.
///
/// `seen[i]` (when not empty) records the rows already checked for invalid entries; `tied` says
/// that cheapest entries are expected to be tied (see [`mostly_tied`]).
#[allow(clippy::too_many_arguments)] // the solver state, passed apart for the borrow checker
fn arr(
    c: &[f64],
    m: usize,
    v: &mut [f64],
    x: &mut [usize],
    y: &mut [usize],
    mut free: Vec<usize>,
    seen: &mut [bool],
    tied: bool,
) -> Result<Vec<usize>, AssignError> {
    let n = x.len();
    let mut budget = 4 * n + 16;
    let mut deferred: Vec<usize> = Vec::new();
    let mut processed = 0usize;
    let mut ties = 0usize;
    // 0 on free columns, +inf on assigned ones (columns never become free again here).
    let mut freepen: Vec<f64> = y
        .iter()
        .map(|&r| if r == NONE { 0.0 } else { f64::INFINITY })
        .collect();
    // Per row, its second-best column and reduced cost at the last scan that assigned it. Prices
    // only fall during this phase, so if that column's price has not moved since, it is still the
    // row's cheapest column once the row is evicted: an evicted row takes it, if free, without a
    // new scan of its (long, uncached) row.
    let mut second: Vec<(f64, usize)> = vec![(f64::INFINITY, NONE); n];
    for _pass in 0..2 {
        let mut k = 0;
        let prev = free.len();
        let mut numfree = 0;
        while k < prev {
            if processed > n / 8 && ties * 4 > processed {
                budget = 0;
            }
            if budget == 0 {
                // Keep the unprocessed rows, in place after the ones already queued.
                for t in k..prev {
                    free[numfree] = free[t];
                    numfree += 1;
                }
                break;
            }
            budget -= 1;
            processed += 1;
            let i = free[k];
            k += 1;
            let row = &c[i * m..(i + 1) * m];
            // When ties are the rule, compute the free minimum in the same pass.
            let mut s = if tied {
                scan::<true>(row, v, &freepen)
            } else {
                scan::<false>(row, v, &freepen)
            };
            if !s.valid {
                return Err(AssignError::InvalidEntry { row: i, col: 0 });
            }
            if !tied && s.top.min1 == s.top.min2 && s.top.j1 != NONE && y[s.top.j1] != NONE {
                // Tied cheapest columns, the first one taken: look for a free one among them
                // (the row was just read, so this second scan hits the cache).
                s = scan::<true>(row, v, &freepen);
            }
            if let Some(flag) = seen.get_mut(i) {
                *flag = true;
            }
            let t = s.top;
            let (umin, mut j1, usubmin, j2) = (t.min1, t.j1, t.min2, t.j2);
            if umin == f64::INFINITY {
                return Err(AssignError::Infeasible);
            }
            if y[j1] != NONE && s.min_free == umin {
                let jf = s.arg_free;
                x[i] = jf;
                y[jf] = i;
                freepen[jf] = f64::INFINITY;
                second[i] = (f64::INFINITY, NONE);
                continue;
            }
            if usubmin == f64::INFINITY {
                // A single allowed column: no finite price drop; leave it to the exact phase.
                deferred.push(i);
                continue;
            }
            let mut i0 = y[j1];
            let strict = umin < usubmin;
            if strict {
                v[j1] -= usubmin - umin;
            } else if i0 != NONE {
                ties += 1;
                j1 = j2;
                i0 = y[j2];
            }
            if let Some(old) = (i0 != NONE).then_some(i0) {
                x[old] = NONE;
            }
            x[i] = j1;
            y[j1] = i;
            freepen[j1] = f64::INFINITY;
            second[i] = if strict {
                (usubmin, j2)
            } else {
                (f64::INFINITY, NONE)
            };
            if i0 != NONE {
                let (h2, jb) = second[i0];
                if jb != NONE && y[jb] == NONE && c[i0 * m + jb] - v[jb] == h2 {
                    x[i0] = jb;
                    y[jb] = i0;
                    freepen[jb] = f64::INFINITY;
                    second[i0] = (f64::INFINITY, NONE);
                } else if strict {
                    k -= 1;
                    free[k] = i0;
                } else {
                    free[numfree] = i0;
                    numfree += 1;
                }
            }
        }
        free.truncate(numfree);
        if free.is_empty() {
            break;
        }
    }
    free.extend(deferred);
    Ok(free)
}

/// One row scan of augmenting row reduction: the two smallest reduced costs, the smallest on a
/// free column (lowest index on ties, `+inf` if none) and whether the row is free of NaN and
/// `-inf`.
#[derive(Debug, PartialEq)]
struct Scan {
    top: Top2,
    min_free: f64,
    arg_free: usize,
    valid: bool,
}

///
/// With `FREE == false` the free minimum is not computed (`min_free` stays `+inf`): it is only
/// needed when the row's cheapest columns are tied, and skipping it saves a third of the
/// memory traffic of the common case.
fn scan<const FREE: bool>(row: &[f64], v: &[f64], freepen: &[f64]) -> Scan {
    #[cfg(target_arch = "x86_64")]
    {
        if row.len() >= 8
            && let Some(simd) = pulp::x86::V3::try_new()
        {
            return simd.vectorize(ScanAvx2::<FREE> {
                simd,
                row,
                v,
                freepen,
            });
        }
    }
    scan_portable::<FREE>(row, v, freepen)
}

/// The arguments of [`scan_avx2`], run by pulp compiled for AVX2.
#[cfg(target_arch = "x86_64")]
struct ScanAvx2<'a, const FREE: bool> {
    simd: pulp::x86::V3,
    row: &'a [f64],
    v: &'a [f64],
    freepen: &'a [f64],
}

#[cfg(target_arch = "x86_64")]
impl<const FREE: bool> pulp::NullaryFnOnce for ScanAvx2<'_, FREE> {
    type Output = Scan;
    #[inline(always)]
    fn call(self) -> Scan {
        scan_avx2::<FREE>(self.simd, self.row, self.v, self.freepen)
    }
}

fn scan_portable<const FREE: bool>(row: &[f64], v: &[f64], freepen: &[f64]) -> Scan {
    let mut s = Scan {
        top: Top2::EMPTY,
        min_free: f64::INFINITY,
        arg_free: NONE,
        valid: true,
    };
    for (j, ((&r, &vj), &fp)) in row.iter().zip(v).zip(freepen).enumerate() {
        s.valid &= r > f64::NEG_INFINITY;
        let h = r - vj;
        if h < s.top.min2 {
            s.top.offer(h, j);
        }
        if FREE && h + fp < s.min_free {
            s.min_free = h + fp;
            s.arg_free = j;
        }
    }
    s
}

/// AVX2 row scan. On most rows the two smallest values are found early and later entries
/// rarely beat them, so each block of 16 entries is first reduced with plain minima (cheap,
/// vectorised) and only a block holding a candidate below the current second minimum or free
/// minimum is replayed entry by entry, in index order: exactly the portable semantics, at
/// close to memory speed instead of a dozen blends per vector.
///
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn scan_avx2<const FREE: bool>(
    simd: pulp::x86::V3,
    row: &[f64],
    v: &[f64],
    freepen: &[f64],
) -> Scan {
    use std::arch::x86_64::{_CMP_GT_OQ, _CMP_LT_OQ};
    let a = simd.avx;
    const B: usize = 16;
    let m = row.len();
    assert!(v.len() >= m && freepen.len() >= m);
    let mb = m - m % B;
    let ninf = a._mm256_set1_pd(f64::NEG_INFINITY);
    let mut ok = a._mm256_castsi256_pd(a._mm256_set1_epi64x(-1));
    let mut s = Scan {
        top: Top2::EMPTY,
        min_free: f64::INFINITY,
        arg_free: NONE,
        valid: true,
    };
    // The loads below read four values at `.add(o)` with `o + 4 ≤ mb ≤ m`: in bounds, since
    // `row`, `v` and `freepen` hold at least `m` values (asserted above).
    let (rp, vp, fp) = (row.as_ptr(), v.as_ptr(), freepen.as_ptr());
    let replay = |s: &mut Scan, lo: usize, hi: usize| {
        for j in lo..hi {
            let h = row[j] - v[j];
            if h < s.top.min2 {
                s.top.offer(h, j);
            }
            let hf = h + freepen[j];
            if FREE && hf < s.min_free {
                s.min_free = hf;
                s.arg_free = j;
            }
        }
    };
    let mut k = 0;
    while k < mb {
        let mut bmin = a._mm256_set1_pd(f64::INFINITY);
        let mut bminf = bmin;
        for q in 0..B / 4 {
            let o = k + 4 * q;
            // SAFETY: `o + 4 ≤ mb ≤ m` (see above).
            let r = unsafe { a._mm256_loadu_pd(rp.add(o)) };
            ok = a._mm256_and_pd(ok, a._mm256_cmp_pd::<_CMP_GT_OQ>(r, ninf));
            // SAFETY: as above.
            let h = a._mm256_sub_pd(r, unsafe { a._mm256_loadu_pd(vp.add(o)) });
            bmin = a._mm256_min_pd(bmin, h);
            if FREE {
                // SAFETY: as above.
                let f = unsafe { a._mm256_loadu_pd(fp.add(o)) };
                bminf = a._mm256_min_pd(bminf, a._mm256_add_pd(h, f));
            }
        }
        let t2 = a._mm256_set1_pd(s.top.min2);
        let tf = a._mm256_set1_pd(s.min_free);
        let hit = a._mm256_or_pd(
            a._mm256_cmp_pd::<_CMP_LT_OQ>(bmin, t2),
            a._mm256_cmp_pd::<_CMP_LT_OQ>(bminf, tf),
        );
        if a._mm256_movemask_pd(hit) != 0 {
            replay(&mut s, k, k + B);
        }
        k += B;
    }
    s.valid = a._mm256_movemask_pd(ok) == 0b1111;
    for &r in &row[mb..] {
        s.valid &= r > f64::NEG_INFINITY;
    }
    replay(&mut s, mb, m);
    s
}

/// The two smallest reduced costs `row[j] - v[j]` of a row, ordered by (value, column): ties go
/// to the lower column, which makes the portable and the AVX2 versions agree exactly.
#[derive(Debug, PartialEq)]
struct Top2 {
    min1: f64,
    j1: usize,
    min2: f64,
    /// `NONE` when the row has fewer than two finite entries (`j1` likewise with none).
    j2: usize,
}

impl Top2 {
    const EMPTY: Top2 = Top2 {
        min1: f64::INFINITY,
        j1: NONE,
        min2: f64::INFINITY,
        j2: NONE,
    };

    /// Offers the candidate `(h, j)`; `j` need not come in increasing order.
    #[inline]
    fn offer(&mut self, h: f64, j: usize) {
        let before = |a: f64, ja: usize, b: f64, jb: usize| a < b || (a == b && ja < jb);
        if before(h, j, self.min2, self.j2) {
            if before(h, j, self.min1, self.j1) {
                self.min2 = self.min1;
                self.j2 = self.j1;
                self.min1 = h;
                self.j1 = j;
            } else {
                self.min2 = h;
                self.j2 = j;
            }
        }
    }
}

/// The two smallest reduced costs of a row: the row scan of augmenting row reduction without
/// its free minimum. With `FREE == false` the penalty slice is never read, so `v` stands in.
fn top2(row: &[f64], v: &[f64]) -> Top2 {
    scan::<false>(row, v, v).top
}

/// Shortest augmenting paths from every free row.
///
/// Dijkstra over the columns with dense arrays, one column settled per step, in the spirit of
/// Crouse's (scipy's) initialisation-free variant rather than LAPJV's list of columns at the
/// current minimum: the relaxation of a row, the search for the closest unsettled column and the
/// search for the closest *free* column are one branch-free pass over contiguous memory
/// ([`relax`]), which the compiler vectorises (and an AVX2 kernel does explicitly). Settled
/// columns are masked by temporarily setting their price to `-inf`, which makes every candidate
/// distance `+inf`. The path ends as soon as a free column is among the closest, which also
/// settles ties in favour of free columns (LAPJV's trick against long paths on tied integers).
fn sap(
    c: &[f64],
    m: usize,
    v: &mut [f64],
    x: &mut [usize],
    y: &mut [usize],
    free: &[usize],
) -> Result<(), AssignError> {
    let mut dk = vec![f64::INFINITY; m];
    let mut pred = vec![0u64; m];
    // 0 on free columns, +inf on assigned ones: `dk + freepen` is the distance to free columns.
    let mut freepen: Vec<f64> = y
        .iter()
        .map(|&r| if r == NONE { 0.0 } else { f64::INFINITY })
        .collect();
    // Settled columns: (column, true price, distance when settled).
    let mut settled: Vec<(usize, f64, f64)> = Vec::new();
    let kernel = relax_kernel();
    for &f in free {
        dk.fill(f64::INFINITY);
        settled.clear();
        let mut i = f;
        let mut h = 0.0;
        let (sink, dmin) = loop {
            let row = &c[i * m..(i + 1) * m];
            let r = kernel(row, v, &mut dk, &mut pred, &freepen, h, i as u64);
            if r.min_all == f64::INFINITY {
                // Restore the masked prices before bailing out.
                for &(j, vj, _) in &settled {
                    v[j] = vj;
                }
                return Err(AssignError::Infeasible);
            }
            if r.min_free <= r.min_all {
                break (r.arg_free, r.min_free);
            }
            let j = r.arg_all;
            let dj = r.min_all;
            settled.push((j, v[j], dj));
            i = y[j];
            // Row i's implicit dual is c[i][j] - v[j]; the path reaches it at distance dj.
            h = dj - (c[i * m + j] - v[j]);
            v[j] = f64::NEG_INFINITY;
            dk[j] = f64::INFINITY;
        };
        for &(j, vj, dj) in &settled {
            v[j] = vj + (dj - dmin);
        }
        freepen[sink] = f64::INFINITY;
        let mut j = sink;
        loop {
            let i = pred[j] as usize;
            y[j] = i;
            let next = x[i];
            x[i] = j;
            if i == f {
                break;
            }
            j = next;
        }
    }
    Ok(())
}

/// Outcome of one relaxation pass.
struct Relaxed {
    min_all: f64,
    arg_all: usize,
    min_free: f64,
    arg_free: usize,
}

type Kernel = fn(&[f64], &[f64], &mut [f64], &mut [u64], &[f64], f64, u64) -> Relaxed;

fn relax_kernel() -> Kernel {
    #[cfg(target_arch = "x86_64")]
    {
        if pulp::x86::V3::is_available() {
            return relax_avx2_entry;
        }
    }
    relax
}

/// Relaxes the edges of the row just reached (`dk[j] = min(dk[j], row[j] - v[j] + h)`, `pred`
/// follows) and returns the closest column and the closest free column, lowest index on ties.
fn relax(
    row: &[f64],
    v: &[f64],
    dk: &mut [f64],
    pred: &mut [u64],
    freepen: &[f64],
    h: f64,
    i: u64,
) -> Relaxed {
    let m = row.len();
    let (v, dk, pred, freepen) = (&v[..m], &mut dk[..m], &mut pred[..m], &freepen[..m]);
    let mut out = Relaxed {
        min_all: f64::INFINITY,
        arg_all: 0,
        min_free: f64::INFINITY,
        arg_free: 0,
    };
    for j in 0..m {
        let cand = row[j] - v[j] + h;
        let mut d = dk[j];
        if cand < d {
            d = cand;
            dk[j] = cand;
            pred[j] = i;
        }
        if d < out.min_all {
            out.min_all = d;
            out.arg_all = j;
        }
        let df = d + freepen[j];
        if df < out.min_free {
            out.min_free = df;
            out.arg_free = j;
        }
    }
    out
}

#[cfg(target_arch = "x86_64")]
fn relax_avx2_entry(
    row: &[f64],
    v: &[f64],
    dk: &mut [f64],
    pred: &mut [u64],
    freepen: &[f64],
    h: f64,
    i: u64,
) -> Relaxed {
    /// The arguments of [`relax_avx2`], run by pulp compiled for AVX2.
    struct RelaxAvx2<'a> {
        simd: pulp::x86::V3,
        row: &'a [f64],
        v: &'a [f64],
        dk: &'a mut [f64],
        pred: &'a mut [u64],
        freepen: &'a [f64],
        h: f64,
        i: u64,
    }
    impl pulp::NullaryFnOnce for RelaxAvx2<'_> {
        type Output = Relaxed;
        #[inline(always)]
        fn call(self) -> Relaxed {
            let Self {
                simd,
                row,
                v,
                dk,
                pred,
                freepen,
                h,
                i,
            } = self;
            relax_avx2(simd, row, v, dk, pred, freepen, h, i)
        }
    }
    match pulp::x86::V3::try_new() {
        Some(simd) => simd.vectorize(RelaxAvx2 {
            simd,
            row,
            v,
            dk,
            pred,
            freepen,
            h,
            i,
        }),
        None => relax(row, v, dk, pred, freepen, h, i),
    }
}

/// AVX2 relaxation. The distance update is a plain vectorised min (`pred` by masked store);
/// the two arg-minima, the costly part, are found like in [`scan_avx2`]: per block of 16 columns
/// a vector minimum is compared with the running minima, and only a block holding a smaller
/// value is replayed entry by entry in index order, which gives exactly [`relax`]'s answer.
///
#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn relax_avx2(
    simd: pulp::x86::V3,
    row: &[f64],
    v: &[f64],
    dk: &mut [f64],
    pred: &mut [u64],
    freepen: &[f64],
    h: f64,
    i: u64,
) -> Relaxed {
    use std::arch::x86_64::_CMP_LT_OQ;
    let (a, a2) = (simd.avx, simd.avx2);
    const B: usize = 16;
    let m = row.len();
    assert!(v.len() >= m && dk.len() >= m && pred.len() >= m && freepen.len() >= m);
    let mb = m - m % B;
    let hv = a._mm256_set1_pd(h);
    let iv = a._mm256_set1_epi64x(i as i64);
    let mut out = Relaxed {
        min_all: f64::INFINITY,
        arg_all: 0,
        min_free: f64::INFINITY,
        arg_free: 0,
    };
    // Every `.add(o)` / `.add(j)` access below is in bounds: `o + 4 ≤ mb` and `j < mb ≤ m`,
    // and every slice holds at least `m` values (asserted above); `dk` and `pred` are
    // borrowed mutably, so the stores through `dp` and `pp` alias nothing else.
    let (rp, vp, dp, pp, fp) = (
        row.as_ptr(),
        v.as_ptr(),
        dk.as_mut_ptr(),
        pred.as_mut_ptr(),
        freepen.as_ptr(),
    );
    let mut k = 0;
    while k < mb {
        let mut bmin = a._mm256_set1_pd(f64::INFINITY);
        let mut bminf = bmin;
        for q in 0..B / 4 {
            let o = k + 4 * q;
            // SAFETY (the loads, stores and masked store of four values at `.add(o)`): in
            // bounds, see above.
            let (r, vo, d0, f) = unsafe {
                (
                    a._mm256_loadu_pd(rp.add(o)),
                    a._mm256_loadu_pd(vp.add(o)),
                    a._mm256_loadu_pd(dp.add(o)),
                    a._mm256_loadu_pd(fp.add(o)),
                )
            };
            let cand = a._mm256_add_pd(a._mm256_sub_pd(r, vo), hv);
            let lt = a._mm256_cmp_pd::<_CMP_LT_OQ>(cand, d0);
            // min_pd(a, b) is `a < b ? a : b`: the same update as the portable kernel.
            let d = a._mm256_min_pd(cand, d0);
            // SAFETY: as above.
            unsafe {
                a._mm256_storeu_pd(dp.add(o), d);
                a2._mm256_maskstore_epi64(pp.add(o) as *mut i64, a._mm256_castpd_si256(lt), iv);
            }
            bmin = a._mm256_min_pd(bmin, d);
            bminf = a._mm256_min_pd(bminf, a._mm256_add_pd(d, f));
        }
        let hit = a._mm256_or_pd(
            a._mm256_cmp_pd::<_CMP_LT_OQ>(bmin, a._mm256_set1_pd(out.min_all)),
            a._mm256_cmp_pd::<_CMP_LT_OQ>(bminf, a._mm256_set1_pd(out.min_free)),
        );
        if a._mm256_movemask_pd(hit) != 0 {
            for j in k..k + B {
                // SAFETY: `j < mb ≤ m`, see above.
                let (d, fj) = unsafe { (*dp.add(j), *fp.add(j)) };
                if d < out.min_all {
                    out.min_all = d;
                    out.arg_all = j;
                }
                let df = d + fj;
                if df < out.min_free {
                    out.min_free = df;
                    out.arg_free = j;
                }
            }
        }
        k += B;
    }
    if mb < m {
        let t = relax(
            &row[mb..],
            &v[mb..m],
            &mut dk[mb..m],
            &mut pred[mb..m],
            &freepen[mb..m],
            h,
            i,
        );
        if t.min_all < out.min_all {
            out.min_all = t.min_all;
            out.arg_all = mb + t.arg_all;
        }
        if t.min_free < out.min_free {
            out.min_free = t.min_free;
            out.arg_free = mb + t.arg_free;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Xorshift stream of integers in `0..k` as `f64`: small ranges make ties common.
    fn small_ints(seed: u64, k: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % k) as f64
        }
    }

    /// The two smallest finite `row[j] - v[j]` by (value, index), by sorting.
    fn top2_reference(row: &[f64], v: &[f64]) -> Top2 {
        let mut all: Vec<(f64, usize)> = (0..row.len()).map(|j| (row[j] - v[j], j)).collect();
        all.sort_by(|x, y| x.partial_cmp(y).unwrap());
        let want = |k: usize| match all.get(k) {
            Some(&(h, j)) if h.is_finite() => (h, j),
            _ => (f64::INFINITY, NONE),
        };
        let ((min1, j1), (min2, j2)) = (want(0), want(1));
        Top2 { min1, j1, min2, j2 }
    }

    #[test]
    fn top2_kernels_agree() {
        let mut rnd = small_ints(99, 5);
        for m in [1usize, 2, 3, 7, 8, 9, 16, 33, 100] {
            for t in 0..200 {
                // Every other row mostly forbidden, to exercise rows with 0 or 1 finite entries.
                let p = if t % 2 == 0 { 4.0 } else { 1.0 };
                let row: Vec<f64> = (0..m)
                    .map(|_| if rnd() >= p { f64::INFINITY } else { rnd() })
                    .collect();
                let v: Vec<f64> = (0..m).map(|_| -rnd()).collect();
                let a = scan_portable::<false>(&row, &v, &v).top;
                let b = top2(&row, &v);
                assert_eq!(a, b, "{row:?} {v:?}");
                assert_eq!(a, top2_reference(&row, &v));
            }
        }
    }

    #[test]
    fn scan_kernels_agree() {
        let mut rnd = small_ints(7, 6);
        for m in [1usize, 2, 3, 7, 8, 9, 16, 33, 100] {
            for t in 0..300 {
                let p = if t % 2 == 0 { 5.0 } else { 1.0 };
                let row: Vec<f64> = (0..m)
                    .map(|_| match rnd() {
                        r if r >= p => f64::INFINITY,
                        _ if t % 7 == 3 && rnd() == 0.0 => f64::NAN,
                        _ if t % 7 == 5 && rnd() == 0.0 => f64::NEG_INFINITY,
                        _ => rnd(),
                    })
                    .collect();
                let v: Vec<f64> = (0..m).map(|_| -rnd()).collect();
                let fp: Vec<f64> = (0..m)
                    .map(|_| if rnd() > 2.0 { f64::INFINITY } else { 0.0 })
                    .collect();
                let a = scan_portable::<true>(&row, &v, &fp);
                let b = scan::<true>(&row, &v, &fp);
                let a0 = scan_portable::<false>(&row, &v, &fp);
                let b0 = scan::<false>(&row, &v, &fp);
                let valid = row.iter().all(|r| !r.is_nan() && *r != f64::NEG_INFINITY);
                for s in [&a, &b, &a0, &b0] {
                    assert_eq!(s.valid, valid, "{row:?}");
                }
                if !valid {
                    // The other fields are meaningless then: the solver stops at once.
                    continue;
                }
                assert_eq!(a0.top, a.top);
                assert_eq!(b0.top, a.top);
                assert_eq!((a0.min_free, b0.min_free), (f64::INFINITY, f64::INFINITY));
                assert_eq!(a, b, "{row:?} {v:?} {fp:?}");
                assert_eq!(a.top, top2_reference(&row, &v));
                // Reference for the free minimum: first index of the smallest finite h on a free column.
                let mut want = (f64::INFINITY, NONE);
                for j in 0..m {
                    let h = row[j] - v[j];
                    if fp[j] == 0.0 && h < want.0 {
                        want = (h, j);
                    }
                }
                assert_eq!((a.min_free, a.arg_free), want);
            }
        }
    }

    /// The AVX2 kernel must agree exactly with the portable one, ties and tails included.
    #[test]
    fn kernels_agree() {
        let mut rnd = small_ints(12345, 7);
        for m in [1usize, 3, 4, 5, 8, 13, 64, 67] {
            for _ in 0..50 {
                let row: Vec<f64> = (0..m)
                    .map(|_| if rnd() == 6.0 { f64::INFINITY } else { rnd() })
                    .collect();
                let v: Vec<f64> = (0..m)
                    .map(|_| {
                        if rnd() == 0.0 {
                            f64::NEG_INFINITY
                        } else {
                            -rnd()
                        }
                    })
                    .collect();
                let dk0: Vec<f64> = (0..m)
                    .map(|_| {
                        if rnd() > 4.0 {
                            f64::INFINITY
                        } else {
                            rnd() + 2.0
                        }
                    })
                    .collect();
                let fp: Vec<f64> = (0..m)
                    .map(|_| if rnd() > 3.0 { f64::INFINITY } else { 0.0 })
                    .collect();
                let (mut d1, mut d2) = (dk0.clone(), dk0.clone());
                let (mut p1, mut p2) = (vec![9u64; m], vec![9u64; m]);
                let a = relax(&row, &v, &mut d1, &mut p1, &fp, 0.5, 3);
                let b = relax_kernel()(&row, &v, &mut d2, &mut p2, &fp, 0.5, 3);
                assert_eq!(d1, d2);
                assert_eq!(p1, p2);
                assert_eq!((a.min_all, a.min_free), (b.min_all, b.min_free));
                if a.min_all < f64::INFINITY {
                    assert_eq!(a.arg_all, b.arg_all);
                }
                if a.min_free < f64::INFINITY {
                    assert_eq!(a.arg_free, b.arg_free);
                }
            }
        }
    }
}
