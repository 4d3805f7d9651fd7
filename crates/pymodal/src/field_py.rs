//! `pymodal.Field`: the dense correspondence field of a matched pair (modal-core's
//! `CorrespondenceField`), and `Match.field`, which fits one to a match's pairs.

use modal_core::{CorrespondenceField, FieldParts, MatchPair, Shape, Side, Topology};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::{checked_array, index_rows, read_only};
use crate::errors::{input_error, internal, to_py};
use crate::match_py::points;
use crate::pickling::{Reader, Writer};

/// A smooth map of the plane fitted to a pair's matches: the thin-plate spline with an affine
/// part that sends each matched node of ``a`` to (``smoothing=0``) or near (``smoothing > 0``)
/// its partner in ``b``. It carries any point of ``a``'s plane (an interior landmark, a region's
/// pixels) to ``b``'s, where the matches alone carry only the nodes.
///
/// The field is ``scipy.interpolate.RBFInterpolator(a[pairs[:, 0]], b[pairs[:, 1]],
/// kernel="thin_plate_spline", smoothing=smoothing)``, the same system (solved in normalised
/// coordinates), so the same values to rounding. It minimises
/// ``Σ |f(a_i) − b_i|² + smoothing/(8π) · J(f)``, ``J`` the bending energy; an affine map of the
/// matches is reproduced exactly for every ``smoothing``.
///
/// Parameters
/// ----------
/// a, b : (n, 2) and (m, 2) array_like — the node coordinates of the two objects (2-D only: for
///     a brightness surface, give its nodes' x and y).
/// pairs : (k, 2) int array_like — ``(index in a, index in b)``, one-to-one: every row is used
///     (:meth:`Match.field` leaves out a match's excess pairs, which are one-to-many).
/// smoothing : float, default 0 — the weight λ ≥ 0 of the bending energy, in the units of
///     ``a`` as scipy's ``smoothing``; 0 interpolates the matches.
///
/// Attributes
/// ----------
/// pairs : (k, 2) int64 — the pairs fitted, ``(source node, target node)``: (a, b) for a fitted
///     field, (b, a) for its :meth:`inverse`.
/// residuals : (k,) float64 — the distance from each matched node's image to its partner.
/// smoothing : float — λ.
///
/// Raises
/// ------
/// DegenerateShapeError — fewer than 3 pairs, a node in two pairs or two matched nodes at one
///     place, the matched nodes of one object on a line, NaN or infinite coordinates;
/// InputError — arrays of the wrong shape, 3-D objects, an index beyond its object;
/// OptionError — a negative or NaN ``smoothing``.
///
/// Fields pickle and round-trip exactly; ``==`` compares every value, bit for bit.
#[pyclass(name = "Field", module = "pymodal", frozen)]
pub struct PyField {
    inner: CorrespondenceField,
}

/// Fits the field of `pairs` between the objects `a` and `b` (Python array-likes), with the GIL
/// released around the solve.
pub(crate) fn fit(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    pairs: Vec<MatchPair>,
    smoothing: f64,
) -> PyResult<PyField> {
    let (da, ca) = points(py, a, "a")?;
    let (db, cb) = points(py, b, "b")?;
    let inner = crate::pool::detach(py, move || {
        let sa = Shape::new(da, ca, Topology::None).map_err(|e| e.of(Side::A))?;
        let sb = Shape::new(db, cb, Topology::None).map_err(|e| e.of(Side::B))?;
        CorrespondenceField::fit(&sa, &sb, &pairs, smoothing)
    })
    .map_err(to_py)?;
    Ok(PyField { inner })
}

#[pymethods]
impl PyField {
    #[new]
    #[pyo3(signature = (a, b, pairs, *, smoothing = 0.0))]
    fn new(
        py: Python<'_>,
        a: &Bound<'_, PyAny>,
        b: &Bound<'_, PyAny>,
        pairs: &Bound<'_, PyAny>,
        smoothing: f64,
    ) -> PyResult<Self> {
        const EXPECTED: &str = "a (k, 2) array of node indices (index in a, index in b)";
        let rows = index_rows(py, Some(pairs), 2, "pairs", EXPECTED)?
            .ok_or_else(|| input_error(format!("pairs must be {EXPECTED}, got None")))?;
        let pairs = rows
            .chunks_exact(2)
            .map(|p| MatchPair {
                a: p[0],
                b: p[1],
                cost: 0.0,
                excess: false,
            })
            .collect();
        fit(py, a, b, pairs, smoothing)
    }

    /// The images of ``points`` ((k, 2) array_like, in a's coordinates) in b's coordinates, a new
    /// (k, 2) float64 array. A NaN or infinite coordinate gives NaN or infinite values; far
    /// outside the matched nodes the field extrapolates (its affine part plus a slowly growing
    /// bend).
    fn apply<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        const EXPECTED: &str = "a (k, 2) array of x, y coordinates";
        let fits = |s: &[usize]| s.len() == 2 && s[1] == 2;
        let arr = checked_array(py, points, "points", EXPECTED, "float64", fits)?;
        let arr: PyReadonlyArray2<f64> = arr.extract()?;
        let pts: Vec<[f64; 2]> = arr
            .as_slice()
            .map_err(internal)?
            .chunks_exact(2)
            .map(|p| [p[0], p[1]])
            .collect();
        let k = pts.len();
        let out = crate::pool::detach(py, || self.inner.apply(&pts));
        let flat = out.into_iter().flatten().collect();
        PyArray1::from_vec(py, flat)
            .reshape([k, 2])
            .map_err(internal)
    }

    /// The field fitted the other way, from b's plane to a's, to the same pairs and
    /// ``smoothing``. A fit, not the exact inverse map: ``f.inverse().apply(f.apply(x))`` is
    /// ``x`` to rounding at the matched nodes and off between them by what the two fits leave,
    /// which grows with the bend squared (on a 240 mm foot outline bent by ±0.04 rad, as between
    /// two frames, at most 0.008 mm inside it; bent by ±0.4 rad, 0.75 mm).
    fn inverse(&self, py: Python<'_>) -> PyResult<Self> {
        let inner = crate::pool::detach(py, || self.inner.inverse()).map_err(to_py)?;
        Ok(Self { inner })
    }

    /// (k, 2) int64 ``(source node, target node)`` of the pairs fitted, in the order of
    /// ``residuals``.
    #[getter]
    fn pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let p = self.inner.pairs();
        let flat = p.iter().flatten().map(|&i| i as i64).collect();
        read_only(
            PyArray1::from_vec(py, flat)
                .reshape([p.len(), 2])
                .map_err(internal)?,
        )
    }

    /// (k,) float64 distance from each matched node's image to its partner: zero to rounding
    /// with ``smoothing=0``.
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        read_only(PyArray1::from_vec(py, self.inner.residuals()))
    }

    /// The weight λ of the bending energy.
    #[getter]
    fn smoothing(&self) -> f64 {
        self.inner.smoothing()
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        self.state().reduce(py, "Field")
    }

    /// Equal when every value is the same, bit for bit (as after a pickle round trip).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        self.state()
            .same_as(other.cast::<Self>().ok().map(|o| o.get().state()))
    }

    fn __hash__(&self) -> u64 {
        self.state().digest()
    }

    fn __repr__(&self) -> String {
        let largest = self.inner.residuals().into_iter().fold(0.0, f64::max);
        format!(
            "Field(pairs={}, smoothing={:?}, max_residual={largest:.3e})",
            self.inner.pairs().len(),
            self.inner.smoothing()
        )
    }
}

impl PyField {
    /// Every number of the field, for `__reduce__`: the solved coefficients too, so that a
    /// restored field is the same bit for bit without solving again.
    fn state(&self) -> Writer {
        let p = self.inner.parts();
        let flat = |v: &[[f64; 2]]| v.iter().flatten().copied().collect::<Vec<_>>();
        let mut w = Writer::new();
        w.usizes(
            p.pairs
                .iter()
                .flatten()
                .copied()
                .collect::<Vec<_>>()
                .into_iter(),
        )
        .f64s(&flat(&p.from))
        .f64s(&flat(&p.to))
        .f64(p.smoothing)
        .f64s(&p.centre)
        .f64(p.radius)
        .f64s(&flat(&p.weights))
        .f64s(p.affine.as_flattened());
        w
    }

    /// The inverse of [`Self::state`].
    pub(crate) fn restore(state: &[u8]) -> PyResult<Self> {
        let mut r = Reader::new("Field", state)?;
        let corrupt =
            || pyo3::exceptions::PyValueError::new_err("cannot unpickle Field: corrupt state");
        let pairs = r.usizes()?.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        let points = |v: Vec<f64>| v.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        let (from, to) = (points(r.f64s()?), points(r.f64s()?));
        let smoothing = r.f64()?;
        let centre: [f64; 2] = r.f64s()?.try_into().map_err(|_| corrupt())?;
        let radius = r.f64()?;
        let weights = points(r.f64s()?);
        let affine: [f64; 6] = r.f64s()?.try_into().map_err(|_| corrupt())?;
        r.finish()?;
        let parts = FieldParts {
            pairs,
            from,
            to,
            smoothing,
            centre,
            radius,
            weights,
            affine: [
                [affine[0], affine[1], affine[2]],
                [affine[3], affine[4], affine[5]],
            ],
        };
        let inner = CorrespondenceField::from_parts(parts).map_err(to_py)?;
        Ok(Self { inner })
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyField>()?;
    Ok(())
}
