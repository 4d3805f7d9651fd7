use thiserror::Error;

/// Why an assignment could not be solved.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AssignError {
    /// The cost slice does not hold `rows * cols` entries.
    #[error("cost slice has {len} entries but the shape {rows}x{cols} needs {expected}")]
    ShapeMismatch {
        /// Rows of the shape given.
        rows: usize,
        /// Columns of the shape given.
        cols: usize,
        /// Entries in the cost slice.
        len: usize,
        /// Entries the shape needs (`rows * cols`).
        expected: usize,
    },
    /// NaN, or an infinity that would make the objective unbounded (`-inf` when minimising,
    /// `+inf` when maximising). The message starts like scipy's.
    #[error(
        "matrix contains invalid numeric entries (NaN, or an infinity favouring the objective) at ({row}, {col})"
    )]
    InvalidEntry {
        /// Row of the first invalid entry.
        row: usize,
        /// Its column.
        col: usize,
    },
    /// The forbidden pairs leave no assignment of `min(rows, cols)` pairs.
    #[error("cost matrix is infeasible")]
    Infeasible,
    /// The threshold of [`crate::solve_with_threshold`] is NaN or infinite.
    #[error("threshold must be finite, got {tau}")]
    InvalidThreshold {
        /// The threshold given.
        tau: f64,
    },
}
