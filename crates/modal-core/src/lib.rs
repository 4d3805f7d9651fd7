//! Finite-element modal models and modal matching.
//!
//! The pipeline follows Sclaroff & Pentland's modal matching as improved by Tavares & Bastos (2005):
//! a [`Shape`] is modelled by finite elements ([`model`]), its vibration modes are computed from
//! the generalized eigenproblem `K φ = ω² M φ` (the `eigen` module; [`generalized_eigh`] solves a
//! dense one), and nodes of two shapes are put in
//! correspondence in modal space ([`matching`], one file per stage: prepare → prealign → features
//! → search → excess → refine). A [`CorrespondenceField`] carries any point of the first object's
//! plane to the second's, fitted to the matches (`field`).
//!
//! Modules depend downwards only: `shape` and `error` at the bottom, then `eigen`, `model`,
//! `matching`, `field` (on the matches' pairs), and `options` (the user-facing names) on top; this file only declares them and
//! re-exports the types a caller needs.

#![warn(missing_docs)]

mod eigen;
mod error;
mod field;
mod geometry;
pub mod matching;
pub mod model;
pub mod options;
pub mod shape;
mod simd;

pub use eigen::{generalized_eigh, EigenSolution};
pub use error::{ErrorKind, ModalError, OptionError, Side, Unsupported};
pub use field::{
    CorrespondenceField, FactoredSpline, FieldParts, SplineCoefficients, ThinPlateBasis,
};
pub use matching::features::{AffinityMatrix, ModalFeatures};
pub use matching::prealign::{Affine, RotationSearch};
pub use matching::search::ThresholdMode;
pub use matching::{
    match_prepared, match_shapes, prepare, MatchOptions, MatchPair, MatchResult, Parallelism,
    Prealign, PreparedShape, Refine, Search, MAX_NODES,
};
pub use model::{
    modal_basis, model_matrices, ElementKind, ModalBasis, ModelMatrices, ModelOptions,
};
pub use model::{Material, PlaneModel};
pub use options::{
    Choice, MatchParams, OptionKind, OptionSet, OptionSpec, OptionValue, PathOrRows,
};
pub use shape::{Shape, Topology};

/// The eigensolver's building blocks on faer matrices, for the stage benchmarks
/// (`benches/eigen.rs`) only: not part of the API (no stability promise), compiled with the
/// `internals` feature.
#[cfg(feature = "internals")]
#[doc(hidden)]
pub mod internals {
    pub use crate::eigen::{
        generalized_eigen, stages, symmetric_eigen, symmetric_eigen_lowest, EigenPairs,
    };

    /// `(K, M, σ)`: stiffness and mass as dense faer matrices, the Gaussian width if any.
    pub type DenseModel = (faer::Mat<f64>, faer::Mat<f64>, Option<f64>);

    /// The explicit model of [`crate::model_matrices`] as dense faer matrices.
    pub fn model_matrices(
        shape: &crate::Shape,
        options: &crate::ModelOptions,
    ) -> Result<DenseModel, crate::ModalError> {
        crate::model::assembly::explicit_model(shape, options)
    }
}
