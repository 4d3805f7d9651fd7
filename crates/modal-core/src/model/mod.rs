//! The finite-element model of one object and its vibration modes (docs/method.md §2–4).
//!
//! - [`material`]: the elastic constants and the plane model;
//! - `gaussian`: Sclaroff's isoparametric Gaussian element (integrals of `Γ`, `K`);
//! - `axial`: bar elements along contour and mesh edges, with the mechanism remedies;
//! - `rigid`: the exact rigid-body modes;
//! - [`assembly`]: the element choice, the solver form of the model and its modal solve
//!   ([`modal_basis`]).
//!
//! The element files depend on [`material`] and on the shape only; [`assembly`] depends on them,
//! never the other way round.

pub mod assembly;
pub(crate) mod axial;
pub(crate) mod gaussian;
pub mod material;
pub(crate) mod rigid;
#[cfg(test)]
mod tests;

pub use assembly::{
    count_zero_modes, modal_basis, modal_basis_with_edges, model_matrices,
    model_matrices_with_edges, ElementKind, ModalBasis, ModelMatrices, ModelOptions,
};
pub use material::{Material, PlaneModel};
