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
pub(crate) fn solve(c: &[f64], n: usize, m: usize) -> Result<Solution, AssignError> {
    let mut v = vec![0.0f64; m];
    let mut x = vec![NONE; n];
    let mut y = vec![NONE; m];
    let mut free: Vec<usize> = if n == m {
        column_reduction(c, n, &mut v, &mut x, &mut y)?
    } else {
        (0..n).collect()
    };
    free = arr(c, m, &mut v, &mut x, &mut y, free)?;
    sap(c, m, &mut v, &mut x, &mut y, &free)?;
    let u = (0..n).map(|i| c[i * m + x[i]] - v[x[i]]).collect();
    Ok(Solution {
        row_to_col: x,
        u,
        v,
    })
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
    let mut imin = vec![0usize; m];
    v.copy_from_slice(&c[..m]);
    for i in 1..n {
        let row = &c[i * m..(i + 1) * m];
        for j in 0..m {
            if row[j] < v[j] {
                v[j] = row[j];
                imin[j] = i;
            }
        }
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
            let row = &c[i * m..(i + 1) * m];
            let mut min = f64::INFINITY;
            for j in 0..m {
                if j != j1 {
                    let h = row[j] - v[j];
                    if h < min {
                        min = h;
                    }
                }
            }
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
/// `lap.lapjv` is several times slower than scipy on Euclidean costs). The phase is only a
/// warm start for the exact shortest paths, so it stops once it has done a few times `n` row
/// scans; the remaining free rows go to the shortest-path phase.
fn arr(
    c: &[f64],
    m: usize,
    v: &mut [f64],
    x: &mut [usize],
    y: &mut [usize],
    mut free: Vec<usize>,
) -> Result<Vec<usize>, AssignError> {
    let n = x.len();
    let mut budget = 4 * n + 16;
    let mut deferred: Vec<usize> = Vec::new();
    for _pass in 0..2 {
        let mut k = 0;
        let prev = free.len();
        let mut numfree = 0;
        while k < prev {
            if budget == 0 {
                // Keep the unprocessed rows, in place after the ones already queued.
                for t in k..prev {
                    free[numfree] = free[t];
                    numfree += 1;
                }
                break;
            }
            budget -= 1;
            let i = free[k];
            k += 1;
            let row = &c[i * m..(i + 1) * m];
            let mut umin = row[0] - v[0];
            let mut j1 = 0;
            let mut usubmin = f64::INFINITY;
            let mut j2 = NONE;
            for j in 1..m {
                let h = row[j] - v[j];
                if h < usubmin {
                    if h >= umin {
                        usubmin = h;
                        j2 = j;
                    } else {
                        usubmin = umin;
                        umin = h;
                        j2 = j1;
                        j1 = j;
                    }
                }
            }
            if umin == f64::INFINITY {
                return Err(AssignError::Infeasible);
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
                j1 = j2;
                i0 = y[j2];
            }
            if let Some(old) = (i0 != NONE).then_some(i0) {
                x[old] = NONE;
            }
            x[i] = j1;
            y[j1] = i;
            if i0 != NONE {
                if strict {
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

/// Shortest augmenting paths from every free row (LAPJV's augmentation phase).
fn sap(
    c: &[f64],
    m: usize,
    v: &mut [f64],
    x: &mut [usize],
    y: &mut [usize],
    free: &[usize],
) -> Result<(), AssignError> {
    let mut d = vec![0.0f64; m];
    let mut pred = vec![0usize; m];
    // collist[..low]: scanned; [low..up): at the current minimum distance; [up..]: to do.
    let mut collist: Vec<usize> = (0..m).collect();
    for &f in free {
        let row = &c[f * m..(f + 1) * m];
        for j in 0..m {
            d[j] = row[j] - v[j];
            pred[j] = f;
            collist[j] = j;
        }
        let mut low = 0;
        let mut up = 0;
        let mut last = 0;
        let mut min = 0.0;
        let endofpath;
        'search: loop {
            if up == low {
                last = low;
                min = d[collist[up]];
                up += 1;
                let start = up;
                for k in start..m {
                    let j = collist[k];
                    let h = d[j];
                    if h <= min {
                        if h < min {
                            up = low;
                            min = h;
                        }
                        collist[k] = collist[up];
                        collist[up] = j;
                        up += 1;
                    }
                }
                if min == f64::INFINITY {
                    return Err(AssignError::Infeasible);
                }
                for &j in &collist[low..up] {
                    if y[j] == NONE {
                        endofpath = j;
                        break 'search;
                    }
                }
            }
            let j1 = collist[low];
            low += 1;
            let i = y[j1];
            let ri = &c[i * m..(i + 1) * m];
            let h = ri[j1] - v[j1] - min;
            let mut k = up;
            while k < m {
                let j = collist[k];
                let v2 = ri[j] - v[j] - h;
                if v2 < d[j] {
                    pred[j] = i;
                    if v2 <= min {
                        // Rounding can put v2 a hair below min; distances never drop below it.
                        d[j] = min;
                        if y[j] == NONE {
                            endofpath = j;
                            break 'search;
                        }
                        collist[k] = collist[up];
                        collist[up] = j;
                        up += 1;
                    } else {
                        d[j] = v2;
                    }
                }
                k += 1;
            }
        }
        for &j in &collist[..last] {
            v[j] += d[j] - min;
        }
        let mut j = endofpath;
        loop {
            let i = pred[j];
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
