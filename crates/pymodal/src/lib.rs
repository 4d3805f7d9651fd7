//! Python bindings of pedomatch: numpy arrays in and out, Rust errors mapped to Python exceptions
//! in one place (the `errors` module), the GIL released around heavy work.

use pyo3::prelude::*;

mod arrays;
mod assign_py;
mod batch_py;
mod errors;
mod field_py;
mod io_py;
#[rustfmt::skip]
mod keywords;
mod match_py;
mod model_py;
mod options_py;
mod pickling;
mod pool;
mod register_py;
mod run_py;
mod synthetic_py;

/// Loads numpy's C API and rust-numpy's borrow checking now, at import. rust-numpy loads them at
/// their first use otherwise, running Python code that a pending signal interrupts, and then
/// panics: Ctrl-C during the first `pymodal.run` of a process raised a `PanicException`
/// ("Failed to access NumPy array API capsule: ... KeyboardInterrupt") that
/// `except KeyboardInterrupt` does not catch.
fn load_numpy_api(py: Python<'_>) -> PyResult<()> {
    // An ImportError naming numpy if it is missing or broken, rather than a panic below.
    py.import("numpy")?;
    let probe = numpy::PyArray1::<f64>::zeros(py, 1, false);
    drop(numpy::PyArrayMethods::readonly(&probe));
    Ok(())
}

#[pymodule]
fn _pymodal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    load_numpy_api(m.py())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    pickling::register(m)?;
    assign_py::register(m)?;
    model_py::register(m)?;
    match_py::register(m)?;
    field_py::register(m)?;
    io_py::register(m)?;
    run_py::register(m)?;
    batch_py::register(m)?;
    register_py::register(m)?;
    options_py::register(m)?;
    synthetic_py::register(m)?;
    Ok(())
}
