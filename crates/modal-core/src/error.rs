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
    Option(#[from] OptionError),
    #[error(transparent)]
    Assign(#[from] assign::AssignError),
}

/// An option value that is not allowed: which option, the value given, what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{option} = {value}: expected {expected}")]
pub struct OptionError {
    /// The option's name (Python spelling, `x_y`; the CLI flag is `--x-y`).
    pub option: &'static str,
    /// The rejected value as given.
    pub value: String,
    /// What the option accepts.
    pub expected: String,
}

impl OptionError {
    /// A rejected value of `option`.
    pub fn new(option: &'static str, value: impl ToString, expected: impl Into<String>) -> Self {
        Self {
            option,
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}
