//! Dense linear assignment.
//!
//! Three independent solvers of the same problem — [`Method::JonkerVolgenant`],
//! [`Method::Hungarian`] and [`Method::NetworkSimplex`] — that always agree on the optimal cost.
//! Costs are dense `f64`, row-major; `+inf` marks a forbidden pair.

mod error;
pub use error::AssignError;

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
}

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Options {
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
    pub duals: Option<(Vec<f64>, Vec<f64>)>,
}
