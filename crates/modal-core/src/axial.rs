//! Linear axial (bar) elements (SPEC §3).

use crate::model::{ModelOptions, SolverModel};
use crate::{ModalError, Shape};

/// Assembles the bar model of `shape`.
pub fn axial_model(_shape: &Shape, _options: &ModelOptions) -> Result<SolverModel, ModalError> {
    Err(ModalError::InvalidParameter(
        "axial elements: work in progress".into(),
    ))
}
