//! The finite-element model of one object and its vibration modes.

use crate::{Material, ModalError, PlaneModel, Shape};

/// Which finite elements model the object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ElementKind {
    /// Sclaroff's isoparametric Gaussian element: one element over all nodes, no order needed.
    #[default]
    Gaussian,
    /// Linear axial (bar) elements along contour edges or mesh edges.
    Axial,
}

/// Parameters of [`modal_basis`].
#[derive(Debug, Clone, PartialEq)]
pub struct ModelOptions {
    pub element: ElementKind,
    pub material: Material,
    pub plane: PlaneModel,
    /// Absolute Gaussian width; `None` uses `kappa × mean nearest-neighbour distance`.
    pub sigma: Option<f64>,
    /// σ rule factor (SPEC §2.8).
    pub kappa: f64,
    /// Project out the exact rigid-body motions (SPEC §2.7).
    pub exact_rigid: bool,
    /// Compute only the lowest `k` modes; `None` computes all `dim × n`.
    pub n_modes: Option<usize>,
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            element: ElementKind::Gaussian,
            material: Material::RUBBER,
            plane: PlaneModel::Stress,
            sigma: None,
            kappa: 1.0,
            exact_rigid: false,
            n_modes: None,
        }
    }
}

/// Vibration modes of one object, ascending by frequency.
#[derive(Debug, Clone)]
pub struct ModalBasis {
    pub dim: usize,
    pub n_nodes: usize,
    /// ω², ascending, one per retained mode.
    pub eigenvalues: Vec<f64>,
    /// `(dim·n) × k`, component-major rows (`a·n + i` is component `a` of node `i`), mass-normalised
    /// columns (`φᵀ M φ = I`), each with its largest-|·| entry positive.
    pub modes: faer::Mat<f64>,
    /// The Gaussian width actually used (after the conditioning guard), if Gaussian.
    pub sigma: Option<f64>,
}

/// Builds the finite-element model of `shape` and solves `K φ = ω² M φ`.
pub fn modal_basis(shape: &Shape, options: &ModelOptions) -> Result<ModalBasis, ModalError> {
    let _ = (shape, options);
    Err(ModalError::Numerical("modal_basis is not implemented yet".into()))
}
