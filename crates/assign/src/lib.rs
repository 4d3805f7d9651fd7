//! Dense linear assignment.
//!
//! Three independent solvers of the same problem — [`Method::JonkerVolgenant`],
//! [`Method::Hungarian`] and [`Method::NetworkSimplex`] — that always agree on the optimal cost.
//! Costs are dense `f64`, row-major; `+inf` marks a forbidden pair. A fourth,
//! [`Method::Ordered`], solves a constrained problem: rows and columns are two closed (cyclic)
//! sequences and the matches must keep their cyclic order; [`cyclic_crossings`] counts how far any
//! assignment is from that.
//!
//! ```
//! use assign::{solve, Options};
//! let cost = [4.0, 1.0, 3.0,
//!             2.0, 0.0, 5.0,
//!             3.0, 2.0, 2.0];
//! let a = solve(&cost, 3, 3, &Options::default()).unwrap();
//! assert_eq!(a.cost, 5.0);
//! assert_eq!(a.row_to_col, vec![Some(1), Some(0), Some(2)]);
//! ```
//!
//! Rectangular matrices are solved like `scipy.optimize.linear_sum_assignment`: every row of the
//! smaller side is assigned, `min(rows, cols)` pairs in total, without padding the matrix.
//! [`solve_with_threshold`] lets rows and columns stay unassigned instead, which is what a matching
//! with a rejection threshold needs.

#![warn(missing_docs)]

use std::borrow::Cow;

mod error;
mod hungarian;
mod jv;
mod network_simplex;
mod ordered;

pub use error::AssignError;
pub use ordered::cyclic_crossings;

/// Which algorithm solves the assignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Shortest augmenting paths in the style of Jonker & Volgenant (LAPJV).
    #[default]
    JonkerVolgenant,
    /// Kuhn–Munkres, O(n³).
    Hungarian,
    /// Primal network simplex on the bipartite min-cost-flow graph.
    NetworkSimplex,
    /// The rows and the columns are two closed sequences (the nodes of two closed contours, in
    /// the same direction) and the matches keep their cyclic order: no two cross. Exact, by
    /// dynamic programming over the `m` possible partners of row 0 (matches may wrap past the
    /// last column), in `O(n · m · (m − n + 1))` for `n ≤ m` (`O(n · m · log m)` with
    /// [`solve_with_threshold`]). Its optimum is never below the other solvers', and equal to
    /// theirs when their optimum happens to keep the order. No duals.
    Ordered,
}

impl Method {
    /// The solvers' names as the CLI (`--solver`) and Python (`solver=`) spell them, in the order
    /// of the variants: `jv`, `hungarian`, `simplex`, `ordered`.
    pub const NAMES: [&'static str; 4] = ["jv", "hungarian", "simplex", "ordered"];

    /// This solver's name (one of [`Method::NAMES`]).
    pub fn name(self) -> &'static str {
        match self {
            Method::JonkerVolgenant => Self::NAMES[0],
            Method::Hungarian => Self::NAMES[1],
            Method::NetworkSimplex => Self::NAMES[2],
            Method::Ordered => Self::NAMES[3],
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A solver name that is not one of [`Method::NAMES`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown solver {0:?}; expected one of jv, hungarian, simplex, ordered")]
pub struct UnknownMethod(pub String);

impl std::str::FromStr for Method {
    type Err = UnknownMethod;

    /// Parses `jv`, `hungarian`, `simplex` or `ordered`.
    ///
    /// ```
    /// assert_eq!("simplex".parse::<assign::Method>(), Ok(assign::Method::NetworkSimplex));
    /// assert_eq!(assign::Method::Hungarian.to_string(), "hungarian");
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "jv" => Ok(Method::JonkerVolgenant),
            "hungarian" => Ok(Method::Hungarian),
            "simplex" => Ok(Method::NetworkSimplex),
            "ordered" => Ok(Method::Ordered),
            other => Err(UnknownMethod(other.to_string())),
        }
    }
}

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Options {
    /// The solver (the first three give the same optimal cost; [`Method::Ordered`] the optimum
    /// under its order constraint).
    pub method: Method,
    /// Maximise the total instead of minimising it.
    pub maximize: bool,
}

/// An optimal assignment.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    /// `row_to_col[i]` is the column assigned to row `i`, if any.
    pub row_to_col: Vec<Option<usize>>,
    /// `col_to_row[j]` is the row assigned to column `j`, if any.
    pub col_to_row: Vec<Option<usize>>,
    /// Sum of the costs of the assigned pairs (in the caller's sense: not negated when maximising).
    pub cost: f64,
    /// Row and column dual variables, where the method produces them.
    ///
    /// For a minimisation `u[i] + v[j] <= cost[i][j]` for every allowed pair, with equality on
    /// assigned pairs, and `sum(u) + sum(v)` equals the optimal cost. On a rectangular matrix the
    /// duals of the longer side are `<= 0` and zero on its unassigned entries. For a maximisation
    /// every inequality is reversed (`>=`, and `>= 0` on the longer side).
    /// [`solve_with_threshold`] and [`Method::Ordered`] do not report duals.
    pub duals: Option<(Vec<f64>, Vec<f64>)>,
}

impl Assignment {
    /// The assigned `(row, col)` pairs, sorted by row.
    pub fn pairs(&self) -> Vec<(usize, usize)> {
        self.row_to_col
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.map(|j| (i, j)))
            .collect()
    }
}

/// Result of a solver on the normalised problem: `n <= m`, minimisation, entries finite or `+inf`.
pub(crate) struct Solution {
    /// Column of every row (all rows are assigned).
    pub row_to_col: Vec<usize>,
    /// Row duals.
    pub u: Vec<f64>,
    /// Column duals (`<= 0`, and `0` on unassigned columns when `m > n`).
    pub v: Vec<f64>,
}

fn run_method(method: Method, c: &[f64], n: usize, m: usize) -> Result<Solution, AssignError> {
    debug_assert!(n <= m && c.len() == n * m);
    match method {
        Method::JonkerVolgenant => jv::solve(c, n, m),
        Method::Hungarian => hungarian::solve(c, n, m),
        Method::NetworkSimplex => network_simplex::solve(c, n, m),
        Method::Ordered => ordered::solve(c, n, m),
    }
}

/// Checks that every entry is allowed: NaN fails, and so does the infinity that would make the
/// objective unbounded (`-inf` when minimising, `+inf` when maximising). The error names the
/// first offending entry in row-major order.
pub(crate) fn validate(cost: &[f64], cols: usize, maximize: bool) -> Result<(), AssignError> {
    let sign = if maximize { -1.0 } else { 1.0 };
    let valid = |x: f64| sign * x > f64::NEG_INFINITY;
    // A branch-free scan (vectorised) first; the slow path only locates the culprit.
    let all_valid = cost
        .chunks(1024)
        .all(|ch| ch.iter().fold(true, |ok, &x| ok & valid(x)));
    if !all_valid {
        let k = cost.iter().position(|&x| !valid(x)).unwrap_or(0);
        return Err(AssignError::InvalidEntry {
            row: k / cols.max(1),
            col: k % cols.max(1),
        });
    }
    Ok(())
}

/// Brings `cost` into the normalised form the solvers expect: a minimisation with at most as
/// many rows as columns, every entry finite or `+inf`. A wide (or square) minimisation is used
/// in place: copying a large matrix costs as much as solving an easy one. Otherwise the matrix
/// is copied, negated when maximising and transposed when tall.
///
/// With `check == false` the entries are not validated: the caller's solver does it in its own
/// first pass over the matrix (only JV on a wide minimisation, see [`solve`]).
///
/// Returns the matrix and whether it was transposed.
fn normalise(
    cost: &[f64],
    rows: usize,
    cols: usize,
    maximize: bool,
    check: bool,
) -> Result<(Cow<'_, [f64]>, bool), AssignError> {
    let sign = if maximize { -1.0 } else { 1.0 };
    if check {
        validate(cost, cols, maximize)?;
    }
    if rows <= cols {
        if maximize {
            Ok((Cow::Owned(cost.iter().map(|&x| -x).collect()), false))
        } else {
            Ok((Cow::Borrowed(cost), false))
        }
    } else {
        let mut c = vec![0.0; cost.len()];
        // Blocked transpose: keeps both sides cache friendly on large matrices.
        const B: usize = 32;
        for i0 in (0..rows).step_by(B) {
            for j0 in (0..cols).step_by(B) {
                for i in i0..(i0 + B).min(rows) {
                    for j in j0..(j0 + B).min(cols) {
                        c[j * rows + i] = sign * cost[i * cols + j];
                    }
                }
            }
        }
        Ok((Cow::Owned(c), true))
    }
}

fn check_shape(cost: &[f64], rows: usize, cols: usize) -> Result<(), AssignError> {
    let expected = rows.checked_mul(cols);
    if expected != Some(cost.len()) {
        return Err(AssignError::ShapeMismatch {
            rows,
            cols,
            len: cost.len(),
            expected: expected.unwrap_or(usize::MAX),
        });
    }
    Ok(())
}

/// Solves the linear assignment problem on a dense row-major `rows × cols` cost matrix.
///
/// Assigns `min(rows, cols)` pairs, each row and column at most once, minimising (or with
/// [`Options::maximize`], maximising) the total cost. `+inf` (`-inf` when maximising) marks a
/// forbidden pair.
///
/// # Errors
/// - [`AssignError::ShapeMismatch`] if `cost.len() != rows * cols`;
/// - [`AssignError::InvalidEntry`] on NaN, or on `-inf` (`+inf` when maximising);
/// - [`AssignError::Infeasible`] if the forbidden pairs leave no complete assignment.
///
/// An empty matrix (`rows == 0` or `cols == 0`) gives an empty assignment of cost 0, as does any
/// method. With [`Method::Ordered`] a tall matrix (`rows > cols`) is solved transposed (the order
/// constraint is the same read from either side), and [`Assignment::duals`] is `None`.
pub fn solve(
    cost: &[f64],
    rows: usize,
    cols: usize,
    options: &Options,
) -> Result<Assignment, AssignError> {
    check_shape(cost, rows, cols)?;
    // JV on a matrix used in place validates it during its first pass (column reduction or the
    // first row scans) instead of in a separate pass: on easy inputs that pass is a large share
    // of the whole solve. Any error it reports is re-checked here, so that an invalid entry
    // takes precedence over infeasibility and is located exactly, as with the separate pass.
    let fused = options.method == Method::JonkerVolgenant && !options.maximize && rows <= cols;
    let (c, transposed) = normalise(cost, rows, cols, options.maximize, !fused)?;
    let (n, m) = if transposed {
        (cols, rows)
    } else {
        (rows, cols)
    };
    let sol = if n == 0 {
        Solution {
            row_to_col: Vec::new(),
            u: Vec::new(),
            v: vec![0.0; m],
        }
    } else if fused {
        match jv::solve(&c, n, m) {
            Ok(s) => s,
            Err(e) => {
                validate(cost, cols, false)?;
                return Err(e);
            }
        }
    } else {
        run_method(options.method, &c, n, m)?
    };
    drop(c);

    let mut row_to_col = vec![None; rows];
    let mut col_to_row = vec![None; cols];
    for (a, &b) in sol.row_to_col.iter().enumerate() {
        let (i, j) = if transposed { (b, a) } else { (a, b) };
        row_to_col[i] = Some(j);
        col_to_row[j] = Some(i);
    }
    let total = row_to_col
        .iter()
        .enumerate()
        .filter_map(|(i, j)| j.map(|j| cost[i * cols + j]))
        .sum();
    let sign = if options.maximize { -1.0 } else { 1.0 };
    let flip = |v: Vec<f64>| -> Vec<f64> { v.into_iter().map(|x| sign * x + 0.0).collect() };
    let (u, v) = if transposed {
        (sol.v, sol.u)
    } else {
        (sol.u, sol.v)
    };
    Ok(Assignment {
        row_to_col,
        col_to_row,
        cost: total,
        duals: (options.method != Method::Ordered).then(|| (flip(u), flip(v))),
    })
}

/// Solves an assignment in which any row or column may stay unassigned.
///
/// Finds the matching (of any size) that minimises `Σ cost[i][j] + τ/2 · (unassigned rows +
/// unassigned columns)`, which is the same as maximising the total saving `Σ (τ − cost[i][j])`
/// over the matched pairs. So no pair costing more than `τ` is ever kept (dropping it would
/// save money), and a pair is matched whenever that lowers the total. Pairs costing exactly `τ`
/// are indifferent and may or may not be kept. With `options.maximize` the sense flips: the
/// saving is `Σ (cost[i][j] − τ)` and no pair below `τ` is kept.
///
/// This is the `(n + m) × (n + m)` padding with dummy cost `τ` of docs/method.md §6.2 (dummy rows
/// and columns at `τ/2` each), solved without building the padded matrix: the smaller side gets one
/// private dummy partner each, `min(n, m) × (n + m)` entries in total.
///
/// With [`Method::Ordered`] the kept pairs also keep the cyclic order of rows and columns (the
/// cyclic alignment of the two sequences, `O(n · m · log m)`).
///
/// # Errors
/// As [`solve`], plus [`AssignError::InvalidThreshold`] if `tau` is not finite. The problem is
/// never infeasible. [`Assignment::duals`] is `None`.
pub fn solve_with_threshold(
    cost: &[f64],
    rows: usize,
    cols: usize,
    tau: f64,
    options: &Options,
) -> Result<Assignment, AssignError> {
    check_shape(cost, rows, cols)?;
    if !tau.is_finite() {
        return Err(AssignError::InvalidThreshold { tau });
    }
    let (c, transposed) = normalise(cost, rows, cols, options.maximize, true)?;
    let (n, m) = if transposed {
        (cols, rows)
    } else {
        (rows, cols)
    };
    let t = if options.maximize { -tau } else { tau };
    if options.method == Method::Ordered {
        let sol = match n {
            0 => Vec::new(),
            _ => ordered::solve_with_threshold(&c, n, m, t),
        };
        let pairs = sol
            .iter()
            .enumerate()
            .filter_map(|(a, b)| b.map(|b| (a, b)));
        return Ok(assignment_of(cost, rows, cols, transposed, pairs));
    }
    let w = m + n;
    let mut aug = vec![f64::INFINITY; n * w];
    for i in 0..n {
        let src: &[f64] = &c[i * m..(i + 1) * m];
        let dst = &mut aug[i * w..i * w + m];
        for (d, &s) in dst.iter_mut().zip(src) {
            // Pairs that can never pay off are forbidden outright: it prunes the search and
            // keeps `s - t` from turning a huge `s` into a spurious preference.
            *d = if s <= t { s - t } else { f64::INFINITY };
        }
        aug[i * w + m + i] = 0.0;
    }
    drop(c);
    let sol = if n == 0 {
        Solution {
            row_to_col: Vec::new(),
            u: Vec::new(),
            v: Vec::new(),
        }
    } else {
        run_method(options.method, &aug, n, w)?
    };
    let pairs = sol.row_to_col.iter().enumerate().filter(|&(_, &b)| b < m);
    let pairs = pairs.map(|(a, &b)| (a, b));
    Ok(assignment_of(cost, rows, cols, transposed, pairs))
}

/// The assignment (without duals) of the `(a, b)` pairs of the normalised problem, in the
/// caller's orientation, with its cost in the caller's matrix.
fn assignment_of(
    cost: &[f64],
    rows: usize,
    cols: usize,
    transposed: bool,
    pairs: impl Iterator<Item = (usize, usize)>,
) -> Assignment {
    let mut row_to_col = vec![None; rows];
    let mut col_to_row = vec![None; cols];
    for (a, b) in pairs {
        let (i, j) = if transposed { (b, a) } else { (a, b) };
        row_to_col[i] = Some(j);
        col_to_row[j] = Some(i);
    }
    let total = row_to_col
        .iter()
        .enumerate()
        .filter_map(|(i, j)| j.map(|j| cost[i * cols + j]))
        .sum();
    Assignment {
        row_to_col,
        col_to_row,
        cost: total,
        duals: None,
    }
}
