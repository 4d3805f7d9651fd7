//! Finite-element modal models and modal matching.
//!
//! The pipeline follows Sclaroff & Pentland's modal matching as improved by Tavares & Bastos (2005):
//! a [`Shape`] is modelled by finite elements, its vibration modes are computed from the generalized
//! eigenproblem `K φ = ω² M φ`, and nodes of two shapes are put in correspondence in modal space.

pub mod align;
pub mod axial;
pub mod eigen;
mod error;
pub mod excess;
pub mod features;
pub mod gaussian;
mod geometry;
pub mod matching;
pub mod material;
pub mod model;
pub mod options;
pub mod rigid;
pub mod search;
pub mod shape;
mod simd;

pub use align::RotationSearch;
pub use error::ModalError;
pub use features::{AffinityMatrix, ModalFeatures};
pub use matching::{match_shapes, MatchOptions, MatchPair, MatchResult, Prealign, Search};
pub use material::{Material, PlaneModel};
pub use model::{modal_basis, model_matrices, ElementKind, ModalBasis, ModelOptions};
pub use options::{Choice, MatchParams, OptionError, OptionKind, OptionSpec, OptionValue};
pub use search::ThresholdMode;
pub use shape::{Shape, Topology};
