//! The keyword options of `pymodal.match`, `run`, `batch` and `read_recording`, read into the
//! library's option sets ([`OptionSet`]: `MatchParams`, `RunParams`, `UnitOverrides`,
//! `OutputOptions`): every keyword defaults to `None`, meaning the documented default, which the
//! set's `Default` fills in; words are parsed by the Rust types' `FromStr`, so Python and the CLI
//! accept the same values.

use modal_core::options::OptionInput;
use modal_core::{Choice, MatchParams, OptionKind, OptionSet, OptionSpec};
use modal_core::{Material, OptionError, PathOrRows};
use pedo_io::units::UnitOverrides;
use pedo_output::{Cell, Table};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString};

use crate::errors::{argument_error, keyword_type_error, option_error, to_py};

/// A word option: `None` keeps `default`, a string is parsed by `T`'s `FromStr`.
pub fn word<T: Choice>(value: Option<&str>, default: T) -> PyResult<T> {
    value.map_or(Ok(default), |s| T::parse_word(s).map_err(to_py))
}

/// The Python type of a scalar keyword, as its `TypeError` names it.
pub trait KeywordType: Sized {
    /// What the keyword takes: "a number", "an integer", ...
    const EXPECTED: &'static str;
    /// The value, if `v` is of the type (as pyo3 reads a parameter of this Rust type).
    fn from_py(v: &Bound<'_, PyAny>) -> Option<Self>;
}

/// `KeywordType` for a type pyo3 reads as a parameter, named `$expected` in errors.
macro_rules! keyword_type {
    ($($t:ty => $expected:literal),* $(,)?) => {$(
        impl KeywordType for $t {
            const EXPECTED: &'static str = $expected;
            fn from_py(v: &Bound<'_, PyAny>) -> Option<Self> {
                v.extract().ok()
            }
        }
    )*};
}

keyword_type!(
    f64 => "a number",
    i64 => "an integer",
    bool => "True or False",
    String => "a string",
);

/// A scalar option keyword, taken from Python as any object: `None` (or absent) is `None`, a
/// value of the type is read as pyo3 reads a typed parameter, anything else is the `TypeError`
/// of [`keyword_type_error`] ("noise must be a number, got 'high'"). Every option keyword of
/// `match`, `run`, `batch`, `batch_row`, `read_recording` and `Recording.from_array` is read here,
/// so that the message itself names the keyword and its type, in one wording.
pub fn keyword<T: KeywordType>(
    name: &str,
    value: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<T>> {
    match value.filter(|v| !v.is_none()) {
        None => Ok(None),
        Some(v) => T::from_py(v)
            .map(Some)
            .ok_or_else(|| keyword_type_error(name, T::EXPECTED, v)),
    }
}

/// An integer keyword (a count, a size, a frame index) as the library's `usize`.
///
/// Such keywords are taken from Python as `i64`, not `usize`: pyo3 refuses a negative int for a
/// `usize` with an `OverflowError` that names neither the keyword nor the value, outside the
/// exception hierarchy; here it is an `OptionError` (a `ValueError`) like every other
/// out-of-range option.
pub fn count(name: &str, value: i64) -> PyResult<usize> {
    usize::try_from(value).map_err(|_| {
        option_error(format!(
            "{name} must be a non-negative integer, got {value}"
        ))
    })
}

/// [`count`] of a keyword that may be absent.
pub fn opt_count(name: &str, value: Option<i64>) -> PyResult<Option<usize>> {
    value.map(|v| count(name, v)).transpose()
}

/// A keyword as given: the object, or `None` when absent.
type Kw<'a, 'py> = Option<&'a Bound<'py, PyAny>>;

/// A keyword's value as the library's option declarations read it ([`OptionInput`]): each type
/// read as [`keyword`] reads it, so that a value of the wrong type is the `TypeError` naming the
/// keyword and an out-of-range one an `OptionError`.
struct PyKeyword<'a, 'py>(&'a Bound<'py, PyAny>);

/// The error of reading a [`PyKeyword`]: the Python exception to raise.
struct KeywordError(PyErr);

impl From<OptionError> for KeywordError {
    fn from(e: OptionError) -> Self {
        KeywordError(to_py(e))
    }
}

impl From<PyErr> for KeywordError {
    fn from(e: PyErr) -> Self {
        KeywordError(e)
    }
}

impl PyKeyword<'_, '_> {
    fn read<T: KeywordType>(&self, option: &'static str) -> Result<T, KeywordError> {
        keyword::<T>(option, Some(self.0))?
            .ok_or_else(|| KeywordError(keyword_type_error(option, T::EXPECTED, self.0)))
    }
}

impl OptionInput for PyKeyword<'_, '_> {
    type Error = KeywordError;
    fn number(&self, option: &'static str) -> Result<f64, KeywordError> {
        self.read(option)
    }
    fn count(&self, option: &'static str) -> Result<usize, KeywordError> {
        Ok(count(option, self.read(option)?)?)
    }
    fn switch(&self, option: &'static str) -> Result<bool, KeywordError> {
        self.read(option)
    }
    fn text(&self, option: &'static str) -> Result<String, KeywordError> {
        self.read(option)
    }
    /// A str or an `os.PathLike`.
    fn path(&self, option: &'static str) -> Result<std::path::PathBuf, KeywordError> {
        self.0.extract().map_err(|_| {
            KeywordError(keyword_type_error(
                option,
                "a path (str or os.PathLike)",
                self.0,
            ))
        })
    }
    /// A preset name or `E,NU,RHO`, a dict or an `(E, nu, rho)` tuple, or a `Material`.
    fn material(&self, _option: &'static str) -> Result<Material, KeywordError> {
        Ok(match self.0.extract::<String>() {
            Ok(s) => s.parse()?,
            Err(_) => crate::model_py::parse_material(Some(self.0))?,
        })
    }
    /// A `(start, end)` pair of ints or None (not bools); anything else (a string too) is an
    /// `InputError` naming the keyword.
    fn bounds(
        &self,
        option: &'static str,
        expected: &str,
    ) -> Result<[Option<isize>; 2], KeywordError> {
        let v = self.0;
        let bound = |b: Bound<'_, PyAny>| -> Option<Option<isize>> {
            if b.is_none() {
                Some(None)
            } else if b.is_instance_of::<PyBool>() {
                None
            } else {
                b.extract::<isize>().ok().map(Some)
            }
        };
        let pair = match v.extract::<Vec<Bound<'_, PyAny>>>() {
            Ok(items) if !v.is_instance_of::<PyString>() => match <[_; 2]>::try_from(items) {
                Ok([start, end]) => bound(start).zip(bound(end)),
                Err(_) => None,
            },
            _ => None,
        };
        let (start, end) = pair.ok_or_else(|| argument_error(option, expected, v))?;
        Ok([start, end])
    }
    /// A number or an `(x, y)` pair of numbers; a string (which would read as a sequence of
    /// characters) or anything else is an `InputError` naming the keyword.
    fn one_or_two(&self, option: &'static str, expected: &str) -> Result<[f64; 2], KeywordError> {
        let v = self.0;
        if !v.is_instance_of::<PyString>() {
            if let Ok(x) = v.extract::<f64>() {
                return Ok([x, x]);
            }
            if let Ok([x, y]) = v.extract::<Vec<f64>>().as_deref() {
                return Ok([*x, *y]);
            }
        }
        Err(KeywordError(argument_error(option, expected, v)))
    }
    /// A path (`str` or `os.PathLike`), or a 2-D array-like of numbers (a NumPy array, nested
    /// sequences) as its rows; anything else is an `InputError` naming the keyword.
    fn path_or_rows(&self, option: &'static str) -> Result<PathOrRows, KeywordError> {
        let v = self.0;
        if let Ok(p) = v.extract::<std::path::PathBuf>() {
            return Ok(PathOrRows::Path(p.display().to_string()));
        }
        let py = v.py();
        let rows = (|| -> PyResult<Vec<Vec<f64>>> {
            let arr = py
                .import("numpy")?
                .call_method1("asarray", (v, "float64"))?;
            if arr.getattr("ndim")?.extract::<usize>()? != 2 {
                return Err(pyo3::exceptions::PyValueError::new_err("not 2-D"));
            }
            arr.call_method0("tolist")?.extract()
        })();
        rows.map(PathOrRows::Rows).map_err(|_| {
            KeywordError(argument_error(
                option,
                "a path or a 2-D array of numbers",
                v,
            ))
        })
    }
}

/// The options of set `T` (those of the sets it holds included) among the keywords `get`
/// gives (a keyword's value by name; `None` when absent or None), each read as its declaration
/// says; the others at their defaults. Not yet validated.
pub fn option_set<'a, 'py: 'a, T: OptionSet>(get: impl Fn(&str) -> Kw<'a, 'py>) -> PyResult<T> {
    let mut params = T::default();
    for spec in T::option_specs() {
        if let Some(v) = get(spec.name).filter(|v| !v.is_none()) {
            params
                .set_option(spec.name, &PyKeyword(v))
                .map_err(|e| e.0)?;
        }
    }
    Ok(params)
}

/// The matching options among the keywords `get` gives, as [`option_set`] reads them.
pub fn match_params<'a, 'py: 'a>(get: impl Fn(&str) -> Kw<'a, 'py>) -> PyResult<MatchParams> {
    option_set(get)
}

/// The unit keywords among those `get` gives, checked.
pub fn units<'a, 'py: 'a>(get: impl Fn(&str) -> Kw<'a, 'py>) -> PyResult<UnitOverrides> {
    let u: UnitOverrides = option_set(get)?;
    u.validate().map_err(to_py)?;
    Ok(u)
}

/// A table as a list of dicts keyed by column name.
pub fn table_rows<'py>(py: Python<'py>, t: &Table) -> PyResult<Bound<'py, PyList>> {
    let rows = PyList::empty(py);
    for r in &t.rows {
        let d = PyDict::new(py);
        for (k, c) in t.header.iter().zip(r) {
            d.set_item(k, cell_to_py(py, c)?)?;
        }
        rows.append(d)?;
    }
    Ok(rows)
}

/// A table cell as a Python int, float, str or None.
pub fn cell_to_py<'py>(py: Python<'py>, c: &Cell) -> PyResult<Bound<'py, PyAny>> {
    Ok(match c {
        Cell::Int(v) => v.into_pyobject(py)?.into_any(),
        Cell::Float(v, _) => v.into_pyobject(py)?.into_any(),
        Cell::Text(s) => s.into_pyobject(py)?.into_any(),
        Cell::Empty => py.None().into_bound(py),
    })
}

/// A JSON value as the equivalent Python object (dicts, lists, numbers, strings, None).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

fn spec_dicts<'py>(py: Python<'py>, specs: &[OptionSpec]) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for s in specs {
        let d = PyDict::new(py);
        d.set_item("name", s.name)?;
        let (kind, values): (&str, Vec<&str>) = match s.kind {
            OptionKind::Flag | OptionKind::NegatedFlag | OptionKind::TriState => ("bool", vec![]),
            OptionKind::Word(w) => ("word", w.to_vec()),
            OptionKind::Value => ("value", vec![]),
        };
        d.set_item("kind", kind)?;
        d.set_item("values", values)?;
        d.set_item("default", &s.default)?;
        d.set_item("help", s.help)?;
        d.set_item("cli_flags", s.cli_flags())?;
        out.append(d)?;
    }
    Ok(out)
}

/// The library's option tables: ``{"match": [...], "pair": [...], "recording": [...],
/// "units": [...], "output": [...]}``, each option a dict ``{name, kind, values, default, help,
/// cli_flags}``. ``match`` takes the "match" and "pair" options, ``run`` the "match" and
/// "recording" ones (which include "units"), ``read_recording`` the "units" and "read" ones (the
/// pedar layout and the reading limits), ``batch`` the "output" and "read" ones besides those of
/// ``run``.
#[pyfunction]
fn _options<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "match",
        spec_dicts(py, &modal_core::options::match_option_specs())?,
    )?;
    d.set_item(
        "pair",
        spec_dicts(py, &modal_core::options::pair_option_specs())?,
    )?;
    d.set_item(
        "recording",
        spec_dicts(py, &pedo_track::recording_option_specs())?,
    )?;
    d.set_item(
        "units",
        spec_dicts(py, &pedo_io::units::unit_option_specs())?,
    )?;
    d.set_item(
        "read",
        spec_dicts(py, &pedo_io::formats::read_option_specs())?,
    )?;
    d.set_item(
        "output",
        spec_dicts(py, &pedo_output::output_option_specs())?,
    )?;
    d.set_item("study", spec_dicts(py, &pedo_study::study_option_specs())?)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_options, m)?)?;
    Ok(())
}
