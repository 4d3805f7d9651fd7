//! Finite-element modal models and modal matching.
//!
//! The pipeline follows Sclaroff & Pentland's modal matching as improved by Tavares & Bastos (2005):
//! a [`Shape`] is modelled by finite elements ([`model`]), its vibration modes are computed from
//! the generalized eigenproblem `K φ = ω² M φ` ([`eigen`]), and nodes of two shapes are put in
//! correspondence in modal space ([`matching`], one file per stage: prepare → prealign → features
//! → search → excess → refine).
//!
//! Modules depend downwards only: `shape` and `error` at the bottom, then `eigen`, `model`,
//! `matching`, and `options` (the user-facing names) on top; this file only declares them and
//! re-exports the types a caller needs.

pub mod eigen;
mod error;
mod geometry;
pub mod matching;
pub mod model;
pub mod options;
pub mod shape;
mod simd;

pub use error::{ErrorKind, ModalError, OptionError, Side, Unsupported};
pub use matching::features::{AffinityMatrix, ModalFeatures};
pub use matching::prealign::{Affine, RotationSearch};
pub use matching::search::ThresholdMode;
pub use matching::{
    match_prepared, match_shapes, prepare, MatchOptions, MatchPair, MatchResult, Parallelism,
    Prealign, PreparedShape, Refine, Search,
};
pub use model::{modal_basis, model_matrices, ElementKind, ModalBasis, ModelOptions};
pub use model::{Material, PlaneModel};
pub use options::{Choice, MatchParams, OptionKind, OptionSpec, OptionValue};
pub use shape::{Shape, Topology};
