//! Checks of the elements and the modal solve against closed forms, quadrature, golden values
//! and the explicit route; they read the dense matrices the public API does not expose.

mod fem_axial;
mod fem_gaussian;
mod fem_golden;
