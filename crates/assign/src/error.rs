use thiserror::Error;

/// Why an assignment could not be solved.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AssignError {
    #[error("cost slice has {len} entries but the shape {rows}x{cols} needs {expected}")]
    ShapeMismatch { rows: usize, cols: usize, len: usize, expected: usize },
    #[error("matrix contains invalid numeric entries (NaN or -inf) at ({row}, {col})")]
    InvalidEntry { row: usize, col: usize },
    #[error("cost matrix is infeasible")]
    Infeasible,
}
