//! `pymodal.linear_sum_assignment`: a drop-in for `scipy.optimize.linear_sum_assignment`.

use numpy::{PyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors::{input_error, internal, to_py};

/// The solver from `solver=` or its deprecated alias `method=` (which warns); `None`: the
/// default solver.
fn solver_of(
    py: Python<'_>,
    solver: Option<&str>,
    method: Option<&str>,
) -> PyResult<assign::Method> {
    let name = match (solver, method) {
        (Some(_), Some(_)) => {
            return Err(input_error(
                "solver and method: give solver= only (method= is its deprecated alias)",
            ));
        }
        (Some(s), None) => Some(s),
        (None, Some(m)) => {
            let warning = py.get_type::<pyo3::exceptions::PyDeprecationWarning>();
            PyErr::warn(py, &warning, c"method= is deprecated; use solver=", 2)?;
            Some(m)
        }
        (None, None) => None,
    };
    crate::options_py::word(name, assign::Method::default())
}

/// Converts any 2-D array-like of numbers or bools to a C-contiguous float64 array, raising the
/// exceptions of scipy 1.17 (if not 2-D a `ValueError`, here the `InputError` subclass; numpy's
/// `TypeError` if the entries cannot be cast safely to float64). Float64 C-contiguous input is
/// used without a copy.
fn as_f64_matrix<'py>(
    py: Python<'py>,
    cost_matrix: &Bound<'py, PyAny>,
) -> PyResult<PyReadonlyArray2<'py, f64>> {
    let np = py.import("numpy")?;
    let arr = np.call_method1("asarray", (cost_matrix,))?;
    let ndim: usize = arr.getattr("ndim")?.extract()?;
    if ndim != 2 {
        return Err(input_error(format!(
            "cost_matrix: expected a matrix (2-D array), got a {ndim}-D array"
        )));
    }
    let kwargs = pyo3::types::PyDict::new(py);
    kwargs.set_item("casting", "safe")?;
    kwargs.set_item("order", "C")?;
    kwargs.set_item("copy", false)?;
    let arr = arr.call_method("astype", (np.getattr("float64")?,), Some(&kwargs))?;
    arr.extract()
}

/// `(row_ind, col_ind)` as returned by scipy.
type IndexArrays<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>);

/// The body shared by the assignment bindings: validate and convert the matrix, solve without
/// the GIL, return scipy's `(row_ind, col_ind)`.
fn solve_to_arrays<'py>(
    py: Python<'py>,
    cost_matrix: &Bound<'py, PyAny>,
    maximize: bool,
    method: assign::Method,
    solve: impl FnOnce(
            &[f64],
            usize,
            usize,
            &assign::Options,
        ) -> Result<assign::Assignment, assign::AssignError>
        + Send,
) -> PyResult<IndexArrays<'py>> {
    let options = assign::Options { method, maximize };
    let arr = as_f64_matrix(py, cost_matrix)?;
    let shape = arr.shape();
    let (rows, cols) = (shape[0], shape[1]);
    let cost = arr.as_slice().map_err(internal)?;
    let result = crate::pool::detach(py, || solve(cost, rows, cols, &options)).map_err(to_py)?;
    let (r, c): (Vec<i64>, Vec<i64>) = result
        .pairs()
        .into_iter()
        .map(|(i, j)| (i as i64, j as i64))
        .unzip();
    Ok((PyArray1::from_vec(py, r), PyArray1::from_vec(py, c)))
}

/// Solve the linear sum assignment problem.
///
/// A drop-in for ``scipy.optimize.linear_sum_assignment``: returns ``(row_ind, col_ind)``, int64
/// arrays with ``row_ind`` sorted, such that ``cost[row_ind, col_ind].sum()`` is optimal over all
/// assignments of ``min(n, m)`` pairs. ``inf`` (``-inf`` when maximising) forbids a pair.
///
/// Parameters
/// ----------
/// cost_matrix : array_like, 2-D, numbers or bools
/// maximize : bool, default False
/// solver : {"jv", "hungarian", "simplex", "ordered"}, keyword-only, default "jv"
///     Jonker–Volgenant shortest augmenting paths, Kuhn–Munkres, or network simplex. All give
///     the same optimal total (the ``--solver`` of ``pedomatch assign``). ``"ordered"`` solves
///     another problem: rows and columns are two closed (cyclic) sequences and the pairs keep
///     their cyclic order (no crossings; they may wrap past the last column); the best such
///     assignment, in ``O(n·m·(m−n+1))`` for ``n ≤ m``.
/// method : deprecated alias of ``solver``.
///
/// Raises
/// ------
/// InputError
///     if the input is not 2-D or contains NaN or ``-inf`` (``+inf`` when maximising), or if
///     both ``solver`` and ``method`` are given; :class:`InfeasibleError` if it admits no
///     complete assignment; :class:`OptionError` for an unknown ``solver``. All are
///     ``ValueError`` subclasses, as scipy raises. ``TypeError`` (numpy's) if the entries cannot
///     be cast safely to float64, as in scipy.
#[pyfunction]
#[pyo3(signature = (cost_matrix, maximize=false, *, solver=None, method=None))]
fn linear_sum_assignment<'py>(
    py: Python<'py>,
    cost_matrix: &Bound<'py, PyAny>,
    maximize: bool,
    solver: Option<&str>,
    method: Option<&str>,
) -> PyResult<IndexArrays<'py>> {
    let method = solver_of(py, solver, method)?;
    solve_to_arrays(py, cost_matrix, maximize, method, assign::solve)
}

/// Assignment in which rows and columns may stay unmatched, rejecting expensive pairs.
///
/// Finds the matching of any size that minimises ``sum(cost[i, j] - tau)`` over its pairs (with
/// ``maximize``: maximises ``sum(cost[i, j] - tau)``), so no pair worse than ``tau`` is kept.
/// Returns ``(row_ind, col_ind)`` like :func:`linear_sum_assignment`, possibly with fewer than
/// ``min(n, m)`` pairs; ``solver`` (and its deprecated alias ``method``) as there.
#[pyfunction]
#[pyo3(signature = (cost_matrix, tau, maximize=false, *, solver=None, method=None))]
fn linear_sum_assignment_threshold<'py>(
    py: Python<'py>,
    cost_matrix: &Bound<'py, PyAny>,
    tau: f64,
    maximize: bool,
    solver: Option<&str>,
    method: Option<&str>,
) -> PyResult<IndexArrays<'py>> {
    let method = solver_of(py, solver, method)?;
    solve_to_arrays(
        py,
        cost_matrix,
        maximize,
        method,
        |cost, rows, cols, options| assign::solve_with_threshold(cost, rows, cols, tau, options),
    )
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(linear_sum_assignment, m)?)?;
    m.add_function(wrap_pyfunction!(linear_sum_assignment_threshold, m)?)?;
    Ok(())
}
