//! The one place where Rust errors become Python exceptions.
//!
//! Every error of the library crates maps by its typed variant (never by its message) to one
//! class of the hierarchy below, exported by the module `pymodal`:
//!
//! ```text
//! Exception
//! └── PedomatchError                      every error of the library
//!     ├── FormatError          (ValueError)  a file that is corrupt or of no known format
//!     ├── DegenerateShapeError (ValueError)  too few, coincident or collinear nodes, NaN
//!     ├── InputError           (ValueError)  an argument's value is invalid or inconsistent
//!     │   └── OptionError                    an option's value is unknown or out of range
//!     ├── InfeasibleError      (ValueError)  the forbidden pairs leave no complete assignment
//!     └── NumericalError       (ValueError)  a numerical method failed (not positive definite)
//! ```
//!
//! Each class but the root also derives from `ValueError`, so code written when every error was
//! a `ValueError` keeps working. Errors of the operating system raise the builtin `OSError`
//! subclass of their errno, with the file name: a missing file raises `FileNotFoundError`.
//!
//! pyo3's `create_exception!` defines the root; the others are created on first use with two
//! bases (`create_exception!` takes only one) and cached.

use assign::AssignError;
use modal_core::{ErrorKind, ModalError};
use pedo_io::IoError;
use pyo3::exceptions::{
    PyException, PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyTypeError,
    PyValueError,
};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

pyo3::create_exception!(
    pymodal,
    PedomatchError,
    PyException,
    "Base class of every error pymodal raises for bad input or a failed computation (errors of \
     the operating system are the builtin ``OSError`` subclasses, e.g. ``FileNotFoundError``)."
);

/// An exception class of the hierarchy, created with two bases on first use.
struct ExceptionClass {
    name: &'static str,
    doc: &'static str,
    /// The class's bases other than `ValueError`; `None` = `PedomatchError`.
    parent: Option<&'static ExceptionClass>,
    class: PyOnceLock<Py<PyType>>,
}

impl ExceptionClass {
    const fn new(
        name: &'static str,
        parent: Option<&'static ExceptionClass>,
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            doc,
            parent,
            class: PyOnceLock::new(),
        }
    }

    /// The Python class: `type(name, (parent, ValueError), {...})`, or `(parent,)` when the
    /// parent already derives from `ValueError`.
    fn type_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyType>> {
        let class = self.class.get_or_try_init(py, || -> PyResult<Py<PyType>> {
            let bases = match self.parent {
                None => PyTuple::new(
                    py,
                    [
                        py.get_type::<PedomatchError>(),
                        py.get_type::<PyValueError>(),
                    ],
                )?,
                Some(parent) => PyTuple::new(py, [parent.type_object(py)?])?,
            };
            let namespace = PyDict::new(py);
            namespace.set_item("__module__", "pymodal")?;
            namespace.set_item("__doc__", self.doc)?;
            let class = py
                .get_type::<PyType>()
                .call1((self.name, bases, namespace))?;
            Ok(class.cast_into::<PyType>()?.unbind())
        })?;
        Ok(class.bind(py).clone())
    }

    /// An exception of this class with the message `msg`.
    fn err(&self, msg: impl Into<String>) -> PyErr {
        let msg = msg.into();
        Python::attach(|py| match self.type_object(py) {
            Ok(class) => PyErr::from_type(class, msg),
            Err(e) => e,
        })
    }
}

static FORMAT_ERROR: ExceptionClass = ExceptionClass::new(
    "FormatError",
    None,
    "A file that is corrupt, truncated or of no known format (the message names the file and, \
     for text formats, the line). Also a ``ValueError``.",
);
static DEGENERATE_SHAPE_ERROR: ExceptionClass = ExceptionClass::new(
    "DegenerateShapeError",
    None,
    "An object that cannot be modelled: too few, coincident or collinear nodes, NaN or infinite \
     coordinates, bad connectivity, or a frame with no object. Also a ``ValueError``.",
);
static INPUT_ERROR: ExceptionClass = ExceptionClass::new(
    "InputError",
    None,
    "An argument's value is invalid or inconsistent (out of range, NaN entries, sizes that do \
     not fit). Also a ``ValueError``.",
);
static OPTION_ERROR: ExceptionClass = ExceptionClass::new(
    "OptionError",
    Some(&INPUT_ERROR),
    "An option's value is unknown or out of range (e.g. ``solver=\"fast\"``, ``modes=2``). An \
     ``InputError``, so also a ``ValueError``.",
);
static INFEASIBLE_ERROR: ExceptionClass = ExceptionClass::new(
    "InfeasibleError",
    None,
    "The forbidden pairs of a cost matrix leave no complete assignment. Also a ``ValueError``.",
);
static NUMERICAL_ERROR: ExceptionClass = ExceptionClass::new(
    "NumericalError",
    None,
    "A numerical method failed: a matrix that should be positive definite is not, an \
     eigensolver did not converge. Also a ``ValueError`` (like ``numpy.linalg.LinAlgError``).",
);

const CLASSES: [&ExceptionClass; 6] = [
    &FORMAT_ERROR,
    &DEGENERATE_SHAPE_ERROR,
    &INPUT_ERROR,
    &OPTION_ERROR,
    &INFEASIBLE_ERROR,
    &NUMERICAL_ERROR,
];

/// An `OptionError`: an option's value is unknown or out of range.
pub fn option_error(msg: impl Into<String>) -> PyErr {
    OPTION_ERROR.err(msg)
}

/// An `InputError`: an argument's value is invalid or inconsistent.
pub fn input_error(msg: impl Into<String>) -> PyErr {
    INPUT_ERROR.err(msg)
}

/// An `InputError` for an argument of the wrong form: "`name` must be `expected`, got <what was
/// given>" (the wording of [`keyword_type_error`]).
pub fn argument_error(name: &str, expected: &str, got: &Bound<'_, PyAny>) -> PyErr {
    INPUT_ERROR.err(must_be(name, expected, got))
}

/// The `TypeError` of a keyword of the wrong type (`run(noise="high")`): "noise must be a number,
/// got 'high'", the message itself naming the keyword and the type it takes, worded as
/// [`argument_error`]. pyo3's own error for a typed parameter names neither (its note "while
/// processing 'noise'" is shown by tracebacks only); the option keywords are read through
/// [`crate::options_py::keyword`], which raises this one.
pub fn keyword_type_error(name: &str, expected: &str, got: &Bound<'_, PyAny>) -> PyErr {
    PyTypeError::new_err(must_be(name, expected, got))
}

/// "`name` must be `expected`, got <what was given>" (its `repr`, shortened; or its type when
/// `repr` fails): the one wording of every argument and keyword error.
fn must_be(name: &str, expected: &str, got: &Bound<'_, PyAny>) -> String {
    const LONGEST: usize = 60;
    let given = match got.repr() {
        Ok(r) => {
            let r = r.to_string_lossy().into_owned();
            if r.chars().count() > LONGEST {
                let short: String = r.chars().take(LONGEST).collect();
                format!("{short}... (a {})", type_name(got))
            } else {
                r
            }
        }
        Err(_) => format!("a {}", type_name(got)),
    };
    format!("{name} must be {expected}, got {given}")
}

/// The name of a Python object's type (`"int"`, `"ndarray"`), or `"?"`.
fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".to_string())
}

/// A failure of the bindings' own bookkeeping (an array that cannot be reshaped to the size
/// just computed): a bug, not bad input.
pub fn internal<E: std::fmt::Display>(err: E) -> PyErr {
    PyRuntimeError::new_err(format!("internal error in pymodal: {err}"))
}

/// A library error the bindings can raise: each maps to its Python exception by its variant.
pub trait LibraryError {
    /// The Python exception standing for this error; its message is the error's `Display`.
    fn into_py_err(self) -> PyErr;
}

/// Converts a library error into its Python exception (for `.map_err(to_py)`).
pub fn to_py<E: LibraryError>(err: E) -> PyErr {
    err.into_py_err()
}

/// The class of an assignment error.
fn assign_class(e: &AssignError) -> &'static ExceptionClass {
    match e {
        AssignError::Infeasible => &INFEASIBLE_ERROR,
        AssignError::InvalidThreshold { .. } => &OPTION_ERROR,
        AssignError::ShapeMismatch { .. } | AssignError::InvalidEntry { .. } => &INPUT_ERROR,
    }
}

/// The class of a modal-core error: by its kind (an assignment error by its own variant).
fn modal_class(e: &ModalError) -> &'static ExceptionClass {
    match e {
        ModalError::Assign(e) => assign_class(e),
        ModalError::Object { error, .. } => modal_class(error),
        e => match e.kind() {
            ErrorKind::Shape => &DEGENERATE_SHAPE_ERROR,
            ErrorKind::Option => &OPTION_ERROR,
            ErrorKind::Numerical => &NUMERICAL_ERROR,
            // Inconsistent arguments, and any kind modal-core adds later.
            _ => &INPUT_ERROR,
        },
    }
}

impl LibraryError for AssignError {
    fn into_py_err(self) -> PyErr {
        assign_class(&self).err(self.to_string())
    }
}

impl LibraryError for ModalError {
    fn into_py_err(self) -> PyErr {
        modal_class(&self).err(self.to_string())
    }
}

impl LibraryError for IoError {
    fn into_py_err(self) -> PyErr {
        match self {
            IoError::Io { path, source } => os_error(path, &source),
            e @ (IoError::Parse { .. }
            | IoError::Format { .. }
            | IoError::UnknownFormat { .. }
            | IoError::TimeLast { .. }) => FORMAT_ERROR.err(e.to_string()),
            IoError::Option(e) => e.into_py_err(),
            e @ IoError::Figure(_) => internal(e),
            e @ (IoError::InvalidInput(_) | IoError::Output { .. }) => {
                INPUT_ERROR.err(e.to_string())
            }
            e @ IoError::NoObject(_) => DEGENERATE_SHAPE_ERROR.err(e.to_string()),
            IoError::Shape(e) => e.into_py_err(),
            // pymodal cancels a run only when a signal handler raised (Ctrl-C), and then raises
            // that exception itself (`pool::detach_cancellable`).
            IoError::Cancelled => PyKeyboardInterrupt::new_err("cancelled"),
        }
    }
}

impl LibraryError for modal_core::OptionError {
    fn into_py_err(self) -> PyErr {
        OPTION_ERROR.err(self.to_string())
    }
}

/// The builtin `OSError` subclass of the errno (`FileNotFoundError`, `PermissionError`, ...),
/// with `errno`, `strerror` and `filename` set as Python's own `open` sets them.
fn os_error(path: String, source: &std::io::Error) -> PyErr {
    const ENOENT: i32 = 2;
    let text = source.to_string();
    // Rust appends " (os error N)" to the system's message; Python's `strerror` has no suffix.
    let strerror = match text.rfind(" (os error ") {
        Some(i) => text[..i].to_string(),
        None => text,
    };
    match (source.kind(), source.raw_os_error()) {
        (std::io::ErrorKind::NotFound, errno) => {
            PyFileNotFoundError::new_err((errno.unwrap_or(ENOENT), strerror, path))
        }
        // `OSError(errno, ...)` constructs the subclass of that errno.
        (_, Some(errno)) => PyOSError::new_err((errno, strerror, path)),
        (_, None) => PyOSError::new_err(format!("{path}: {strerror}")),
    }
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("PedomatchError", py.get_type::<PedomatchError>())?;
    for class in CLASSES {
        m.add(class.name, class.type_object(py)?)?;
    }
    Ok(())
}
