//! The one place where Rust errors become Python exceptions.

use pyo3::exceptions::PyValueError;
use pyo3::PyErr;

/// Converts any library error into a Python exception. Every error the library crates return
/// describes bad input or an infeasible request, which Python users expect as `ValueError`.
pub fn to_py<E: std::fmt::Display>(err: E) -> PyErr {
    PyValueError::new_err(err.to_string())
}
