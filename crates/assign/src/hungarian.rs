//! Kuhn–Munkres (the Hungarian method) in its O(n²m) form with row and column potentials.
//!
//! Rows enter one at a time. For each new row the alternating tree grows one column per step:
//! the column of least slack joins the tree, and all potentials of the tree are shifted by that
//! slack so that the column's edge becomes tight. When the new column is unassigned, the
//! alternating path back to the row is flipped. Unlike the Jonker–Volgenant solver there is no
//! initialisation heuristic, and potentials change at every step rather than once per path.

use crate::{AssignError, Solution};

const NONE: usize = usize::MAX;

/// Solves the normalised problem (`n <= m`, minimise, entries finite or `+inf`).
pub(crate) fn solve(c: &[f64], n: usize, m: usize) -> Result<Solution, AssignError> {
    let mut u = vec![0.0f64; n];
    // Index `m` is a virtual column that holds the row being inserted.
    let mut v = vec![0.0f64; m + 1];
    let mut p = vec![NONE; m + 1];
    let mut way = vec![0usize; m];
    let mut minv = vec![f64::INFINITY; m];
    let mut used = vec![false; m + 1];
    // Columns in the tree, so that the potential shift does not have to scan all columns.
    let mut tree: Vec<usize> = Vec::with_capacity(m + 1);

    for i in 0..n {
        p[m] = i;
        let mut j0 = m;
        minv.fill(f64::INFINITY);
        used.fill(false);
        tree.clear();
        loop {
            used[j0] = true;
            tree.push(j0);
            let i0 = p[j0];
            let row = &c[i0 * m..(i0 + 1) * m];
            let ui0 = u[i0];
            let mut delta = f64::INFINITY;
            let mut j1 = NONE;
            let mut j1_free = false;
            for j in 0..m {
                if used[j] {
                    continue;
                }
                let cur = row[j] - ui0 - v[j];
                if cur < minv[j] {
                    minv[j] = cur;
                    way[j] = j0;
                }
                let mj = minv[j];
                // On ties prefer an unassigned column: the path ends there at once. Without
                // this, heavily tied integer costs grow huge trees of zero-slack columns.
                if mj < delta || (mj == delta && !j1_free && p[j] == NONE) {
                    delta = mj;
                    j1 = j;
                    j1_free = p[j] == NONE;
                }
            }
            if j1 == NONE || delta == f64::INFINITY {
                return Err(AssignError::Infeasible);
            }
            if delta != 0.0 {
                for &j in &tree {
                    u[p[j]] += delta;
                    v[j] -= delta;
                }
                for j in 0..m {
                    if !used[j] {
                        minv[j] -= delta;
                    }
                }
            }
            j0 = j1;
            if p[j0] == NONE {
                break;
            }
        }
        // Flip the alternating path ending at the free column j0.
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == m {
                break;
            }
        }
    }

    let mut row_to_col = vec![0usize; n];
    for j in 0..m {
        if p[j] != NONE {
            row_to_col[p[j]] = j;
        }
    }
    v.truncate(m);
    Ok(Solution { row_to_col, u, v })
}
