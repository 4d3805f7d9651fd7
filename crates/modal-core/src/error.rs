use thiserror::Error;

/// Errors of model building and matching.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModalError {
    #[error("invalid shape: {0}")]
    InvalidShape(String),
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A user-facing option has a value it does not accept.
    #[error(transparent)]
    Option(#[from] crate::options::OptionError),
    #[error(transparent)]
    Assign(#[from] assign::AssignError),
}
