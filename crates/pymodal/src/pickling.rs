//! Pickle support of the result classes: each class's `__reduce__` returns
//! `(pymodal._pymodal._restore, (class name, state))`, the state a `bytes` object holding the
//! wrapped Rust value field by field (numbers as their exact little-endian bits), so a round
//! trip gives back the same value bit for bit, across processes and machines.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

/// Format version of the state: bumped whenever a class's layout changes, so an old pickle
/// raises a clear error instead of decoding garbage.
const VERSION: u8 = 2;

/// Serialises fields into a state.
pub struct Writer(Vec<u8>);

impl Default for Writer {
    fn default() -> Self {
        Self::new()
    }
}

impl Writer {
    pub fn new() -> Self {
        Self(vec![VERSION])
    }
    pub fn usize(&mut self, v: usize) -> &mut Self {
        self.0.extend_from_slice(&(v as u64).to_le_bytes());
        self
    }
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn bool(&mut self, v: bool) -> &mut Self {
        self.0.push(v as u8);
        self
    }
    pub fn opt_f64(&mut self, v: Option<f64>) -> &mut Self {
        self.bool(v.is_some()).f64(v.unwrap_or(0.0))
    }
    pub fn opt_usize(&mut self, v: Option<usize>) -> &mut Self {
        self.bool(v.is_some()).usize(v.unwrap_or(0))
    }
    pub fn str(&mut self, v: &str) -> &mut Self {
        self.usize(v.len());
        self.0.extend_from_slice(v.as_bytes());
        self
    }
    pub fn f64s(&mut self, v: &[f64]) -> &mut Self {
        self.usize(v.len());
        v.iter().for_each(|&x| {
            self.f64(x);
        });
        self
    }
    pub fn f32s(&mut self, v: &[f32]) -> &mut Self {
        self.usize(v.len());
        v.iter()
            .for_each(|x| self.0.extend_from_slice(&x.to_le_bytes()));
        self
    }
    pub fn usizes(&mut self, v: impl ExactSizeIterator<Item = usize>) -> &mut Self {
        self.usize(v.len());
        v.for_each(|x| {
            self.usize(x);
        });
        self
    }
    pub fn bools(&mut self, v: &[bool]) -> &mut Self {
        self.usize(v.len());
        v.iter().for_each(|&x| {
            self.bool(x);
        });
        self
    }
    /// Whether `other`, if there is one, holds the same state bit for bit: value equality of
    /// the result classes (`__eq__`), the very equality a pickle round trip keeps.
    pub fn same_as(&self, other: Option<Writer>) -> bool {
        other.is_some_and(|o| o.0 == self.0)
    }
    /// A hash of the state, consistent with [`Self::same_as`] (`__hash__`; the classes are
    /// immutable).
    pub fn digest(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        self.0.hash(&mut h);
        h.finish()
    }
    /// `(pymodal._pymodal._restore, (class_name, state))`, what `__reduce__` returns.
    pub fn reduce<'py>(&self, py: Python<'py>, class_name: &str) -> PyResult<Bound<'py, PyTuple>> {
        let restore = py.import("pymodal._pymodal")?.getattr("_restore")?;
        let args = (class_name, PyBytes::new(py, &self.0));
        PyTuple::new(py, [restore, args.into_pyobject(py)?.into_any()])
    }
}

/// Reads fields back from a state, in the order they were written.
pub struct Reader<'a> {
    bytes: &'a [u8],
    class_name: &'a str,
}

impl<'a> Reader<'a> {
    pub fn new(class_name: &'a str, bytes: &'a [u8]) -> PyResult<Self> {
        let mut r = Self { bytes, class_name };
        let version = r.take(1)?[0];
        if version != VERSION {
            return Err(PyValueError::new_err(format!(
                "cannot unpickle {class_name}: state version {version}, this pymodal reads \
                 version {VERSION}"
            )));
        }
        Ok(r)
    }
    fn corrupt(&self) -> PyErr {
        PyValueError::new_err(format!(
            "cannot unpickle {}: the state is truncated or corrupt",
            self.class_name
        ))
    }
    fn take(&mut self, n: usize) -> PyResult<&'a [u8]> {
        if self.bytes.len() < n {
            return Err(self.corrupt());
        }
        let (head, tail) = self.bytes.split_at(n);
        self.bytes = tail;
        Ok(head)
    }
    fn array<const N: usize>(&mut self) -> PyResult<[u8; N]> {
        Ok(self.take(N)?.try_into().expect("N bytes taken"))
    }
    pub fn usize(&mut self) -> PyResult<usize> {
        let v = u64::from_le_bytes(self.array()?);
        usize::try_from(v).map_err(|_| self.corrupt())
    }
    pub fn f64(&mut self) -> PyResult<f64> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    pub fn bool(&mut self) -> PyResult<bool> {
        match self.take(1)?[0] {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(self.corrupt()),
        }
    }
    pub fn opt_f64(&mut self) -> PyResult<Option<f64>> {
        let some = self.bool()?;
        let v = self.f64()?;
        Ok(some.then_some(v))
    }
    pub fn opt_usize(&mut self) -> PyResult<Option<usize>> {
        let some = self.bool()?;
        let v = self.usize()?;
        Ok(some.then_some(v))
    }
    /// A length prefix, checked against the bytes left (each element takes `width` bytes).
    pub fn count(&mut self, width: usize) -> PyResult<usize> {
        let n = self.usize()?;
        if n.checked_mul(width).is_none_or(|b| b > self.bytes.len()) {
            return Err(self.corrupt());
        }
        Ok(n)
    }
    pub fn string(&mut self) -> PyResult<String> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| self.corrupt())
    }
    pub fn f64s(&mut self) -> PyResult<Vec<f64>> {
        let n = self.count(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    pub fn f32s(&mut self) -> PyResult<Vec<f32>> {
        let n = self.count(4)?;
        (0..n)
            .map(|_| Ok(f32::from_le_bytes(self.array()?)))
            .collect()
    }
    pub fn usizes(&mut self) -> PyResult<Vec<usize>> {
        let n = self.count(8)?;
        (0..n).map(|_| self.usize()).collect()
    }
    pub fn bools(&mut self) -> PyResult<Vec<bool>> {
        let n = self.count(1)?;
        (0..n).map(|_| self.bool()).collect()
    }
    /// Checks that every byte was read.
    pub fn finish(self) -> PyResult<()> {
        if self.bytes.is_empty() {
            Ok(())
        } else {
            Err(self.corrupt())
        }
    }
}

/// Rebuilds a pickled object from its class name and state (the callable of `__reduce__`).
#[pyfunction]
fn _restore(py: Python<'_>, class_name: &str, state: &[u8]) -> PyResult<Py<PyAny>> {
    let obj = match class_name {
        "Match" => Py::new(py, crate::match_py::PyMatch::restore(state)?)?.into_any(),
        "Field" => Py::new(py, crate::field_py::PyField::restore(state)?)?.into_any(),
        "Recording" => Py::new(py, crate::io_py::PyRecording::restore(state)?)?.into_any(),
        "Surface" => Py::new(py, crate::io_py::PySurface::restore(state)?)?.into_any(),
        "ModalModel" => Py::new(py, crate::model_py::PyModalModel::restore(state)?)?.into_any(),
        "SyntheticWalk" => {
            Py::new(py, crate::synthetic_py::PySyntheticWalk::restore(state)?)?.into_any()
        }
        other => {
            return Err(PyValueError::new_err(format!(
                "cannot unpickle unknown pymodal class {other:?}"
            )));
        }
    };
    Ok(obj)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_restore, m)?)?;
    Ok(())
}
