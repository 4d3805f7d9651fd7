//! Primal network simplex for the assignment as a min-cost flow on the bipartite graph.
//!
//! Nodes: `n` rows (supply 1) and `m` columns (demand 1). The `m - n` surplus columns are served
//! by the root itself, through zero-cost root→column arcs (LEMON's `GEQ` form of the initial
//! tree): a separate slack node would collect the surplus columns as one huge subtree whose
//! potentials every pivot moving it must update. The arcs row→column are implicit (arc `i*m + j`,
//! cost read from the matrix), which keeps the memory at one byte of state and four of flow per
//! pair.
//!
//! The tree representation and the pivot follow LEMON's `NetworkSimplex` (Kovács, "Minimum-cost
//! flow algorithms: an experimental evaluation", 2015): parent / thread / reverse-thread /
//! subtree-size / last-successor arrays, an artificial root with big-M arcs forming an initial
//! strongly feasible spanning tree, leaving-arc selection that keeps the tree strongly feasible
//! (so degenerate pivots cannot cycle), and block-search pricing: scan the arcs cyclically in
//! blocks of about √(arcs), entering the most negative reduced cost of the first block that has
//! one.

use crate::{AssignError, Solution};

const STATE_TREE: i8 = 0;
const STATE_LOWER: i8 = 1;
const DIR_UP: i8 = 1;
const DIR_DOWN: i8 = -1;
const NIL: usize = usize::MAX;

struct Simplex<'a> {
    /// Shifted costs (`>= 0`), row-major `n × m`.
    c: &'a [f64],
    n: usize,
    m: usize,
    /// Number of real (row→column) arcs.
    nm: usize,
    /// Arcs `nm..search_arcs` are root→column (cost 0); arcs `search_arcs + i` are the
    /// artificial row→root arcs (cost `art_cost`), never entering.
    search_arcs: usize,
    root: usize,
    art_cost: f64,

    // Per arc.
    state: Vec<i8>,
    flow: Vec<i32>,

    // Per node (+ root).
    parent: Vec<usize>,
    pred: Vec<usize>,
    thread: Vec<usize>,
    rev_thread: Vec<usize>,
    succ_num: Vec<usize>,
    last_succ: Vec<usize>,
    pred_dir: Vec<i8>,
    pi: Vec<f64>,
    dirty_revs: Vec<usize>,

    // Pivot state.
    in_arc: usize,
    join: usize,
    u_in: usize,
    v_in: usize,
    u_out: usize,
    delta: i64,
    next_arc: usize,
    block_size: usize,
}

impl Simplex<'_> {
    #[inline]
    fn source(&self, a: usize) -> usize {
        if a < self.nm {
            a / self.m
        } else if a < self.search_arcs {
            self.root
        } else {
            a - self.search_arcs
        }
    }

    #[inline]
    fn target(&self, a: usize) -> usize {
        if a < self.nm {
            self.n + a % self.m
        } else if a < self.search_arcs {
            self.n + (a - self.nm)
        } else {
            self.root
        }
    }

    #[inline]
    fn cost(&self, a: usize) -> f64 {
        if a < self.nm {
            self.c[a]
        } else if a < self.search_arcs {
            0.0
        } else {
            self.art_cost
        }
    }

    /// Block-search pricing. Real arcs are scanned row by row so that the row potential is
    /// loaded once and the inner loop runs over contiguous costs.
    fn find_entering_arc(&mut self) -> bool {
        let total = self.search_arcs;
        let mut min = 0.0f64;
        let mut best = NIL;
        let mut cnt = 0usize;
        let mut e = self.next_arc;
        let mut scanned = 0usize;
        let n = self.n;
        let m = self.m;
        while scanned < total {
            // Scan a run [e, end) that stays inside one row (or the root→column arcs).
            let end = if e < self.nm {
                ((e / m) + 1) * m
            } else {
                total
            };
            let end = end.min(e + (total - scanned));
            if e < self.nm {
                let i = e / m;
                let pi_i = self.pi[i];
                let pi_cols = &self.pi[n..n + m];
                let j0 = e - i * m;
                let j1 = end - i * m;
                let row = &self.c[i * m..(i + 1) * m];
                let st = &self.state[i * m..(i + 1) * m];
                for j in j0..j1 {
                    let r = row[j] + pi_i - pi_cols[j];
                    if r < min && st[j] == STATE_LOWER {
                        min = r;
                        best = i * m + j;
                    }
                }
            } else {
                let pi_s = self.pi[self.root];
                for a in e..end {
                    let j = a - self.nm;
                    let r = pi_s - self.pi[n + j];
                    if r < min && self.state[a] == STATE_LOWER {
                        min = r;
                        best = a;
                    }
                }
            }
            let len = end - e;
            scanned += len;
            cnt += len;
            e = if end == total { 0 } else { end };
            if cnt >= self.block_size {
                if best != NIL {
                    break;
                }
                cnt = 0;
            }
        }
        if best == NIL {
            return false;
        }
        self.in_arc = best;
        self.next_arc = e;
        true
    }

    fn find_join_node(&mut self) {
        let mut u = self.source(self.in_arc);
        let mut v = self.target(self.in_arc);
        while u != v {
            if self.succ_num[u] < self.succ_num[v] {
                u = self.parent[u];
            } else {
                v = self.parent[v];
            }
        }
        self.join = u;
    }

    /// Picks the leaving arc so that the new tree stays strongly feasible. Returns whether it
    /// differs from the entering arc (never the case here: arcs are uncapacitated), or `None`
    /// when the cycle is unbounded.
    fn find_leaving_arc(&mut self) -> Option<bool> {
        // The entering arc is always at its lower bound: the cycle follows its direction.
        let first = self.source(self.in_arc);
        let second = self.target(self.in_arc);
        let mut delta = i64::MAX;
        let mut result = 0;
        let mut u = first;
        while u != self.join {
            if self.pred_dir[u] == DIR_UP {
                let d = self.flow[self.pred[u]] as i64;
                if d < delta {
                    delta = d;
                    self.u_out = u;
                    result = 1;
                }
            }
            u = self.parent[u];
        }
        let mut u = second;
        while u != self.join {
            if self.pred_dir[u] == DIR_DOWN {
                let d = self.flow[self.pred[u]] as i64;
                if d <= delta {
                    delta = d;
                    self.u_out = u;
                    result = 2;
                }
            }
            u = self.parent[u];
        }
        if result == 0 {
            return None;
        }
        if result == 1 {
            self.u_in = first;
            self.v_in = second;
        } else {
            self.u_in = second;
            self.v_in = first;
        }
        self.delta = delta;
        Some(true)
    }

    fn change_flow(&mut self) {
        if self.delta > 0 {
            let val = self.delta as i32;
            self.flow[self.in_arc] += val;
            let mut u = self.source(self.in_arc);
            while u != self.join {
                let e = self.pred[u];
                self.flow[e] -= self.pred_dir[u] as i32 * val;
                u = self.parent[u];
            }
            let mut u = self.target(self.in_arc);
            while u != self.join {
                let e = self.pred[u];
                self.flow[e] += self.pred_dir[u] as i32 * val;
                u = self.parent[u];
            }
        }
        self.state[self.in_arc] = STATE_TREE;
        let out = self.pred[self.u_out];
        // Uncapacitated: the leaving arc always leaves at flow 0.
        debug_assert_eq!(self.flow[out], 0);
        self.state[out] = STATE_LOWER;
    }

    fn update_tree_structure(&mut self) {
        let u_in = self.u_in;
        let v_in = self.v_in;
        let u_out = self.u_out;
        let join = self.join;
        let old_rev_thread = self.rev_thread[u_out];
        let old_succ_num = self.succ_num[u_out];
        let old_last_succ = self.last_succ[u_out];
        let v_out = self.parent[u_out];

        if u_in == u_out {
            self.parent[u_in] = v_in;
            self.pred[u_in] = self.in_arc;
            self.pred_dir[u_in] = if u_in == self.source(self.in_arc) {
                DIR_UP
            } else {
                DIR_DOWN
            };
            if self.thread[v_in] != u_out {
                let mut after = self.thread[old_last_succ];
                self.thread[old_rev_thread] = after;
                self.rev_thread[after] = old_rev_thread;
                after = self.thread[v_in];
                self.thread[v_in] = u_out;
                self.rev_thread[u_out] = v_in;
                self.thread[old_last_succ] = after;
                self.rev_thread[after] = old_last_succ;
            }
        } else {
            let thread_continue = if old_rev_thread == v_in {
                self.thread[old_last_succ]
            } else {
                self.thread[v_in]
            };
            let mut stem = u_in;
            let mut par_stem = v_in;
            let mut last = self.last_succ[u_in];
            let mut after = self.thread[last];
            self.thread[v_in] = u_in;
            self.dirty_revs.clear();
            self.dirty_revs.push(v_in);
            while stem != u_out {
                let next_stem = self.parent[stem];
                self.thread[last] = next_stem;
                self.dirty_revs.push(last);
                let before = self.rev_thread[stem];
                self.thread[before] = after;
                self.rev_thread[after] = before;
                self.parent[stem] = par_stem;
                par_stem = stem;
                stem = next_stem;
                last = if self.last_succ[stem] == self.last_succ[par_stem] {
                    self.rev_thread[par_stem]
                } else {
                    self.last_succ[stem]
                };
                after = self.thread[last];
            }
            self.parent[u_out] = par_stem;
            self.thread[last] = thread_continue;
            self.rev_thread[thread_continue] = last;
            self.last_succ[u_out] = last;
            if old_rev_thread != v_in {
                self.thread[old_rev_thread] = after;
                self.rev_thread[after] = old_rev_thread;
            }
            for k in 0..self.dirty_revs.len() {
                let u = self.dirty_revs[k];
                let t = self.thread[u];
                self.rev_thread[t] = u;
            }
            let mut tmp_sc = 0isize;
            let tmp_ls = self.last_succ[u_out];
            let mut u = u_out;
            while u != u_in {
                let p = self.parent[u];
                self.pred[u] = self.pred[p];
                self.pred_dir[u] = -self.pred_dir[p];
                tmp_sc += self.succ_num[u] as isize - self.succ_num[p] as isize;
                self.succ_num[u] = tmp_sc as usize;
                self.last_succ[p] = tmp_ls;
                u = p;
            }
            self.pred[u_in] = self.in_arc;
            self.pred_dir[u_in] = if u_in == self.source(self.in_arc) {
                DIR_UP
            } else {
                DIR_DOWN
            };
            self.succ_num[u_in] = old_succ_num;
        }

        let up_limit_out = if self.last_succ[join] == v_in {
            join
        } else {
            NIL
        };
        let last_succ_out = self.last_succ[u_out];
        let mut u = v_in;
        while u != NIL && self.last_succ[u] == v_in {
            self.last_succ[u] = last_succ_out;
            u = self.parent[u];
        }
        if join != old_rev_thread && v_in != old_rev_thread {
            let mut u = v_out;
            while u != up_limit_out && self.last_succ[u] == old_last_succ {
                self.last_succ[u] = old_rev_thread;
                u = self.parent[u];
            }
        } else if last_succ_out != old_last_succ {
            let mut u = v_out;
            while u != up_limit_out && self.last_succ[u] == old_last_succ {
                self.last_succ[u] = last_succ_out;
                u = self.parent[u];
            }
        }
        let mut u = v_in;
        while u != join {
            self.succ_num[u] += old_succ_num;
            u = self.parent[u];
        }
        let mut u = v_out;
        while u != join {
            self.succ_num[u] -= old_succ_num;
            u = self.parent[u];
        }
    }

    fn update_potential(&mut self) {
        let u_in = self.u_in;
        let sigma = self.pi[self.v_in]
            - self.pi[u_in]
            - self.pred_dir[u_in] as f64 * self.cost(self.in_arc);
        let end = self.thread[self.last_succ[u_in]];
        let mut u = u_in;
        while u != end {
            self.pi[u] += sigma;
            u = self.thread[u];
        }
    }
}

/// Solves the normalised problem (`n <= m`, minimise, entries finite or `+inf`).
pub(crate) fn solve(c: &[f64], n: usize, m: usize) -> Result<Solution, AssignError> {
    if n.checked_mul(m)
        .is_none_or(|nm| nm >= (isize::MAX as usize) / 2)
        || m >= i32::MAX as usize
    {
        return Err(AssignError::ShapeMismatch {
            rows: n,
            cols: m,
            len: c.len(),
            expected: usize::MAX,
        });
    }
    // Shift costs to be >= 0: every complete assignment has exactly n pairs, so the optimum is
    // unchanged, and the big-M of the artificial arcs can be sized from the largest cost.
    let mut cmin = f64::INFINITY;
    let mut cmax = f64::NEG_INFINITY;
    for &x in c {
        if x.is_finite() {
            cmin = cmin.min(x);
            cmax = cmax.max(x);
        }
    }
    if cmin == f64::INFINITY {
        return Err(AssignError::Infeasible);
    }
    let shifted: Vec<f64> = c.iter().map(|&x| x - cmin).collect();
    let range = cmax - cmin;
    let node_num = n + m;
    // Any path through an artificial arc costs more than any assignment of real arcs.
    let unit = if range > 0.0 { range } else { 1.0 };
    let art_cost = 2.0 * unit * (node_num as f64 + 1.0);
    if !art_cost.is_finite() {
        return Err(AssignError::InvalidEntry { row: 0, col: 0 });
    }

    let nm = n * m;
    let search_arcs = nm + m;
    let total_arcs = search_arcs + n;
    let root = node_num;
    let mut s = Simplex {
        c: &shifted,
        n,
        m,
        nm,
        search_arcs,
        root,
        art_cost,
        state: vec![STATE_LOWER; total_arcs],
        flow: vec![0; total_arcs],
        parent: vec![NIL; node_num + 1],
        pred: vec![NIL; node_num + 1],
        thread: vec![0; node_num + 1],
        rev_thread: vec![0; node_num + 1],
        succ_num: vec![0; node_num + 1],
        last_succ: vec![0; node_num + 1],
        pred_dir: vec![0; node_num + 1],
        pi: vec![0.0; node_num + 1],
        dirty_revs: Vec::new(),
        in_arc: 0,
        join: 0,
        u_in: 0,
        v_in: 0,
        u_out: 0,
        delta: 0,
        next_arc: 0,
        block_size: ((search_arcs as f64).sqrt().ceil() as usize).max(10),
    };
    // Initial strongly feasible tree (LEMON, GEQ form): every column is served by the root
    // through its zero-cost arc, every row sends its unit to the root at the big-M cost.
    s.parent[root] = NIL;
    s.pred[root] = NIL;
    s.thread[root] = 0;
    s.rev_thread[0] = root;
    s.succ_num[root] = node_num + 1;
    s.last_succ[root] = root - 1;
    s.pi[root] = 0.0;
    for u in 0..node_num {
        s.parent[u] = root;
        s.thread[u] = u + 1;
        s.rev_thread[u + 1] = u;
        s.succ_num[u] = 1;
        s.last_succ[u] = u;
        let e = if u < n {
            s.pred_dir[u] = DIR_UP;
            s.pi[u] = -art_cost;
            search_arcs + u
        } else {
            s.pred_dir[u] = DIR_DOWN;
            s.pi[u] = 0.0;
            nm + (u - n)
        };
        s.pred[u] = e;
        s.state[e] = STATE_TREE;
        s.flow[e] = 1;
    }

    while s.find_entering_arc() {
        s.find_join_node();
        if s.find_leaving_arc().is_none() {
            // Unreachable with non-negative costs; treat as numerical breakdown.
            return Err(AssignError::Infeasible);
        }
        s.change_flow();
        s.update_tree_structure();
        s.update_potential();
    }

    for i in 0..n {
        if s.flow[search_arcs + i] != 0 {
            return Err(AssignError::Infeasible);
        }
    }
    let mut row_to_col = vec![NIL; n];
    for u in 0..node_num {
        let e = s.pred[u];
        if e < nm && s.flow[e] > 0 {
            row_to_col[e / m] = e % m;
        }
    }
    if row_to_col.contains(&NIL) {
        return Err(AssignError::Infeasible);
    }
    // Reduced costs c + pi_i - pi_j >= 0 and, on the root→column arcs, -pi_j >= 0 (the root's
    // potential is 0): u_i = -pi_i (+ the shift), v_j = pi_j <= 0, zero on unassigned columns.
    let u = (0..n).map(|i| -s.pi[i] + cmin).collect();
    let v = (0..m).map(|j| s.pi[n + j]).collect();
    Ok(Solution { row_to_col, u, v })
}
