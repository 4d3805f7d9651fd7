//! Python bindings of pedomatch: numpy arrays in and out, Rust errors mapped to Python exceptions
//! in one place (the `errors` module), the GIL released around heavy work.

use pyo3::prelude::*;

mod arrays;
mod assign_py;
mod batch_py;
mod errors;
mod io_py;
mod match_py;
mod model_py;
mod options_py;
mod pickling;
mod pool;
mod run_py;
mod synthetic_py;

#[pymodule]
fn _pymodal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    pickling::register(m)?;
    assign_py::register(m)?;
    model_py::register(m)?;
    match_py::register(m)?;
    io_py::register(m)?;
    run_py::register(m)?;
    batch_py::register(m)?;
    options_py::register(m)?;
    synthetic_py::register(m)?;
    Ok(())
}
