//! Array arguments: numpy array-likes turned into contiguous arrays of one dtype and shape, or
//! an `InputError` that names the argument, says what it must be and what it was.

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use crate::errors::{argument_error, input_error, internal};

/// An array as the messages describe it: "a 1-D array of shape (5,)", "a 2-D array of shape
/// (5, 4)" (the shape as numpy writes it).
pub(crate) fn array_text(shape: &[usize]) -> String {
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    format!("a {}-D array of shape {dims}", shape.len())
}

/// `obj` as a C-contiguous numpy array of `dtype` (`"float64"`, `"float32"`, `"int64"`) whose
/// shape `fits`: anything numpy cannot convert, or of another shape, is an `InputError`
/// "`name` must be `expected`, got …".
pub(crate) fn checked_array<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    name: &str,
    expected: &str,
    dtype: &str,
    fits: impl Fn(&[usize]) -> bool,
) -> PyResult<Bound<'py, PyAny>> {
    let np = py.import("numpy")?;
    let arr = np
        .call_method1("asarray", (obj, np.getattr(dtype)?))
        .map_err(|_| argument_error(name, expected, obj))?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    if !fits(&shape) {
        return Err(input_error(format!(
            "{name} must be {expected}, got {}",
            array_text(&shape)
        )));
    }
    np.call_method1("ascontiguousarray", (arr,))
}

/// Optional rows of `cols` node indices (`None` or a missing argument: `None`), flattened;
/// another shape or a negative index is an `InputError` naming `name`.
pub(crate) fn index_rows(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
    cols: usize,
    name: &str,
    expected: &str,
) -> PyResult<Option<Vec<usize>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let fits = |s: &[usize]| s.len() == 2 && s[1] == cols;
    let arr = checked_array(py, obj, name, expected, "int64", fits)?;
    let arr: PyReadonlyArray2<i64> = arr.extract()?;
    let v = arr.as_slice().map_err(internal)?;
    if let Some(bad) = v.iter().find(|&&x| x < 0) {
        return Err(input_error(format!("{name} holds a negative index {bad}")));
    }
    Ok(Some(v.iter().map(|&x| x as usize).collect()))
}

/// `arr` made read-only, for an attribute of a result. Attributes hand out copies of what the
/// object holds, so a write into one would change nothing and vanish silently; read-only, numpy
/// says so instead ("assignment destination is read-only"). `arr.copy()` gives a writable array.
pub(crate) fn read_only<T>(arr: Bound<'_, T>) -> PyResult<Bound<'_, T>> {
    arr.as_any().call_method1("setflags", (false,))?;
    Ok(arr)
}
