//! The modal-matching options that `match`, `run` and `demo` share.

use crate::cmd_assign::SolverArg;
use clap::{Args, ValueEnum};
use modal_core::ElementKind;
use pedo_io::sequence::{RunParams, SearchMode};

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ElementArg {
    Gaussian,
    Axial,
}

impl From<ElementArg> for ElementKind {
    fn from(e: ElementArg) -> Self {
        match e {
            ElementArg::Gaussian => ElementKind::Gaussian,
            ElementArg::Axial => ElementKind::Axial,
        }
    }
}

/// Finite element, modes, assignment and the recipe's switches.
#[derive(Args, Clone)]
pub struct ModalArgs {
    /// Finite element of the modal model.
    #[arg(long, value_enum, default_value = "gaussian")]
    pub element: ElementArg,
    /// Fraction of the vibration modes used as features.
    #[arg(long, default_value_t = 0.25)]
    pub modes: f64,
    /// Assignment solver of the optimisation (global) search.
    #[arg(long, value_enum, default_value = "jv")]
    pub solver: SolverArg,
    /// Matching threshold on the max-normalised modal cost, in [0, 1] (default: keep all).
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Disable the excess-node step.
    #[arg(long)]
    pub no_excess: bool,
    /// The paper's literal setting (centroid/scale pre-alignment only, no affine re-fits).
    #[arg(long)]
    pub paper: bool,
    /// Gaussian element: a Gaussian on every N-th node only — about twice as fast, as accurate
    /// for the small changes between consecutive frames, less under severe warps.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub center_stride: usize,
}

impl ModalArgs {
    /// These options with `search` as the library's parameters; the rest at their defaults.
    pub fn params(&self, search: SearchMode) -> RunParams {
        RunParams {
            element: self.element.into(),
            modes: self.modes,
            search,
            method: self.solver.into(),
            threshold: self.threshold,
            excess: !self.no_excess,
            paper: self.paper,
            center_stride: self.center_stride,
            ..RunParams::default()
        }
    }
}
