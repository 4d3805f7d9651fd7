//! `pymodal.match`: modal matching of two point sets, contours or meshes.

use modal_core::shape::looks_like_closed_contour;
use modal_core::{
    match_shapes, ElementKind, MatchOptions, MatchResult, Prealign, RotationSearch, Search, Shape,
    ThresholdMode, Topology,
};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::to_py;

/// Result of :func:`match`.
///
/// Attributes
/// ----------
/// pairs : (k, 2) int64 — (index in a, index in b); the search's pairs first (sorted by a;
///     one-to-one, except many-to-one with ``search="best"``), then the pairs added by the
///     excess-node step.
/// costs : (k,) float64 — the search's cost Z[a, b] of each pair: the normalised modal distance,
///     with positions mixed in and raised to ``cost_power`` when those options say so.
/// excess : (k,) bool — True for pairs from the excess-node step (one-to-many).
/// affinity : (n, m) float64 — the final affinity matrix Z the search used, in [0, 1].
/// unmatched_a, unmatched_b : int64 arrays of nodes in no pair.
/// local_pairs : (l, 2) int64 — mutual-best matches on the final Z (under the threshold).
/// local_count, optimisation_count, excess_count : int — the three counts of the paper's tables.
/// n_modes : int — modes per object in the features; refits : int — affine re-fits performed.
#[pyclass(name = "Match", module = "pymodal", frozen)]
pub struct PyMatch {
    inner: MatchResult,
}

fn pairs_array<'py>(
    py: Python<'py>,
    pairs: impl Iterator<Item = (usize, usize)>,
) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = pairs.flat_map(|(a, b)| [a as i64, b as i64]).collect();
    let k = flat.len() / 2;
    PyArray1::from_vec(py, flat)
        .reshape([k, 2])
        .expect("k × 2 reshape")
}

impl PyMatch {
    /// Wraps a Rust result (for other bindings that return matches, e.g. sequences).
    pub fn from_result(inner: MatchResult) -> Self {
        Self { inner }
    }
}

#[pymethods]
impl PyMatch {
    /// (k, 2) int64 ``(index in a, index in b)``: the search's pairs, then the excess pairs.
    #[getter]
    fn pairs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        pairs_array(py, self.inner.pairs.iter().map(|p| (p.a, p.b)))
    }
    /// (k,) float64 cost Z[a, b] of each pair.
    #[getter]
    fn costs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.pairs.iter().map(|p| p.cost).collect())
    }
    /// (k,) bool, True for the pairs added by the excess-node step.
    #[getter]
    fn excess<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_vec(py, self.inner.pairs.iter().map(|p| p.excess).collect())
    }
    /// (n, m) float64 final affinity matrix Z in [0, 1].
    #[getter]
    fn affinity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let z = &self.inner.affinity;
        PyArray1::from_slice(py, z.as_slice())
            .reshape([z.rows(), z.cols()])
            .expect("n × m reshape")
    }
    /// int64 nodes of ``a`` in no pair.
    #[getter]
    fn unmatched_a<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(
            py,
            self.inner.unmatched_a.iter().map(|&i| i as i64).collect(),
        )
    }
    /// int64 nodes of ``b`` in no pair.
    #[getter]
    fn unmatched_b<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(
            py,
            self.inner.unmatched_b.iter().map(|&i| i as i64).collect(),
        )
    }
    /// (l, 2) int64 mutual-best matches on the final Z, under the threshold.
    #[getter]
    fn local_pairs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        pairs_array(py, self.inner.local_pairs.iter().copied())
    }
    /// Number of mutual-best (local) matches.
    #[getter]
    fn local_count(&self) -> usize {
        self.inner.local_count()
    }
    /// Number of the search's own pairs (the paper's optimisation column).
    #[getter]
    fn optimisation_count(&self) -> usize {
        self.inner.one_to_one_count()
    }
    /// Number of pairs added by the excess-node step.
    #[getter]
    fn excess_count(&self) -> usize {
        self.inner.excess_count()
    }
    /// Modes per object in the features.
    #[getter]
    fn n_modes(&self) -> usize {
        self.inner.n_modes
    }
    /// Modal affine re-fits performed.
    #[getter]
    fn refits(&self) -> usize {
        self.inner.refits
    }
    fn __len__(&self) -> usize {
        self.inner.pairs.len()
    }
    fn __repr__(&self) -> String {
        format!(
            "Match(pairs={}, local={}, optimisation={}, excess={}, n_modes={}, refits={})",
            self.inner.pairs.len(),
            self.inner.local_count(),
            self.inner.one_to_one_count(),
            self.inner.excess_count(),
            self.inner.n_modes,
            self.inner.refits
        )
    }
}

fn points(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(usize, Vec<f64>)> {
    let np = py.import("numpy")?;
    let arr = np.call_method1("asarray", (obj,))?;
    let ndim: usize = arr.getattr("ndim")?.extract()?;
    if ndim != 2 {
        return Err(PyValueError::new_err(format!(
            "{name} must be a 2-D (n, 2) or (n, 3) array, got {ndim}-D"
        )));
    }
    let arr = np
        .call_method1("ascontiguousarray", (arr, np.getattr("float64")?))
        .map_err(|_| PyValueError::new_err(format!("{name} must hold numbers")))?;
    let arr: PyReadonlyArray2<f64> = arr.extract()?;
    let shape = arr.shape();
    if shape[1] != 2 && shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} must have 2 or 3 columns, got shape {shape:?}"
        )));
    }
    Ok((shape[1], arr.as_slice().map_err(to_py)?.to_vec()))
}

fn triangles(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
    name: &str,
) -> PyResult<Option<Vec<[usize; 3]>>> {
    let Some(obj) = obj else { return Ok(None) };
    if obj.is_none() {
        return Ok(None);
    }
    let np = py.import("numpy")?;
    let arr = np.call_method1("asarray", (obj, np.getattr("int64")?))?;
    let arr: PyReadonlyArray2<i64> = arr
        .extract()
        .map_err(|_| PyValueError::new_err(format!("{name} must be a (t, 3) integer array")))?;
    if arr.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!("{name} must have 3 columns")));
    }
    let v = arr.as_slice().map_err(to_py)?;
    if let Some(bad) = v.iter().find(|&&x| x < 0) {
        return Err(PyValueError::new_err(format!(
            "{name} holds a negative index {bad}"
        )));
    }
    Ok(Some(
        v.chunks_exact(3)
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
            .collect(),
    ))
}

/// Modal matching of two objects.
///
/// Builds a finite-element model of each object, computes its vibration modes and matches the
/// nodes in modal space. The defaults are the most accurate setting measured (robust rotation
/// pre-alignment, up to two modal affine re-fits, cross-object mode alignment, excess nodes on
/// contours; for unordered 3-D point sets the surface setting: wide common σ, no re-fits, aligned
/// positions mixed in, powered costs); ``prealign="normalize", refits=0`` is the paper's literal
/// setting.
///
/// Parameters
/// ----------
/// a, b : (n, 2) or (n, 3) array_like — the node coordinates of the two objects.
/// element : {"gaussian", "axial"} — Sclaroff's Gaussian element or bar elements (contours/meshes).
/// modes : float in (0, 1] — fraction of ``dim · min(n, m)`` modes kept (default 0.25).
/// search : {"global", "local", "best"} — optimal assignment, mutual best matches, or every node
///     of a to its best node of b (many-to-one, no excess step; the most accurate read-out for
///     independent samplings of one surface, README).
/// solver : {"jv", "hungarian", "simplex"} — assignment algorithm.
/// threshold : float or None — reject pairs with normalised cost above it.
/// excess : bool — match the nodes the one-to-one search leaves over (global search).
/// ordered : bool or None — treat the inputs as ordered closed contours; None decides from the
///     data (2-D arrays whose consecutive points are nearest-neighbour close).
/// material : None, preset name, dict or (E, nu, rho) — only ν changes the matches.
/// prealign : {"robust", "spec", "normalize"} — rotation search over 36 turns plus the principal
///     axes (default), the five principal-axes starts only, or centroid and scale only;
/// skip_rigid : bool; band : int;
/// refits : int or None — modal affine re-fits (None: 2, or 0 for 3-D point sets);
/// refit_tolerance : float ≥ 0 or None — no (further) re-fit once one affine map explains the
///     pairs: every one-to-one pair within this fraction of b's node spacing of its partner
///     (None: 0.6; 0 re-fits ``refits`` times);
/// kappa : float or None — σ = kappa × mean nearest-neighbour distance (None: 0.8, or 3 for 3-D
///     point sets, where independent samplings need smoother modes);
/// center_stride : int ≥ 1 — Gaussians on every ``center_stride``-th node only (Gaussian element):
///     2 solves in a third of the time, at the cost of accuracy under severe warps (README);
/// threshold_in_optimizer : bool — let the assignment itself reject pairs above the threshold;
/// position_weight : float in [0, 1] or None — mix of aligned-position distance into the cost
///     (1 = positions only, a baseline; None: 0, or 0.7 for 3-D point sets);
/// cost_power : float > 0 or None — the assignment minimises the sum of costs to this power
///     (None: 1, the squared modal distance; 0.125 for 3-D point sets, whose independent
///     samplings need many near-exact pairs rather than evenly spread errors); costs, affinity
///     and threshold are in powered units;
/// common_sigma : bool or None — one σ for both objects (None: on for 3-D point sets);
/// triangles_a, triangles_b : (t, 3) int arrays — meshes (for ``element="axial"`` and §6.4).
///
/// Raises
/// ------
/// ValueError — bad shapes, degenerate objects (too few, coincident or collinear nodes, NaN),
///     unknown option values.
#[pyfunction]
#[pyo3(name = "match", signature = (a, b, *, element="gaussian", modes=0.25, search="global", solver="jv",
    threshold=None, excess=true, ordered=None, material=None, prealign="robust", refits=None,
    refit_tolerance=None, skip_rigid=false, band=3, kappa=None, center_stride=1, threshold_in_optimizer=false, position_weight=None, cost_power=None, common_sigma=None, triangles_a=None,
    triangles_b=None))]
#[allow(clippy::too_many_arguments)]
fn match_py(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    element: &str,
    modes: f64,
    search: &str,
    solver: &str,
    threshold: Option<f64>,
    excess: bool,
    ordered: Option<bool>,
    material: Option<&Bound<'_, PyAny>>,
    prealign: &str,
    refits: Option<usize>,
    refit_tolerance: Option<f64>,
    skip_rigid: bool,
    band: usize,
    kappa: Option<f64>,
    center_stride: usize,
    threshold_in_optimizer: bool,
    position_weight: Option<f64>,
    cost_power: Option<f64>,
    common_sigma: Option<bool>,
    triangles_a: Option<&Bound<'_, PyAny>>,
    triangles_b: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyMatch> {
    let (da, ca) = points(py, a, "a")?;
    let (db, cb) = points(py, b, "b")?;
    if da != db {
        return Err(PyValueError::new_err(format!(
            "a has {da} columns but b has {db}"
        )));
    }
    let ta = triangles(py, triangles_a, "triangles_a")?;
    let tb = triangles(py, triangles_b, "triangles_b")?;
    let ordered = match ordered {
        Some(o) => o,
        None => {
            ta.is_none()
                && tb.is_none()
                && looks_like_closed_contour(&ca, da)
                && looks_like_closed_contour(&cb, db)
        }
    };
    // Contours get the §10 recipe; unordered 3-D point sets the measured surface setting.
    let mut opts = MatchOptions::for_input(da, ordered);
    opts.model.element = match element {
        "gaussian" => ElementKind::Gaussian,
        "axial" => ElementKind::Axial,
        o => {
            return Err(PyValueError::new_err(format!(
                "unknown element {o:?}; expected \"gaussian\" or \"axial\""
            )))
        }
    };
    // None keeps the matching default; anything else is parsed as for ModalModel.
    if let Some(m) = material.filter(|o| !o.is_none()) {
        let m = crate::model_py::parse_material(Some(m))?;
        opts.model.material = m;
    }
    if let Some(kappa) = kappa {
        opts.model.kappa = kappa;
    }
    opts.model.center_stride = center_stride;
    opts.mode_fraction = modes;
    opts.search = match search {
        "global" => Search::Global,
        "local" => Search::Local,
        "best" => Search::Best,
        o => {
            return Err(PyValueError::new_err(format!(
                "unknown search {o:?}; expected \"global\", \"local\" or \"best\""
            )))
        }
    };
    opts.method = crate::assign_py::parse_method("solver", solver)?;
    opts.prealign = match prealign {
        "robust" => Prealign::Robust,
        "spec" => {
            opts.rotation_search = RotationSearch::spec(5);
            Prealign::Robust
        }
        "normalize" => Prealign::Normalize,
        o => {
            return Err(PyValueError::new_err(format!(
                "unknown prealign {o:?}; expected \"robust\", \"spec\" or \"normalize\""
            )))
        }
    };
    opts.threshold = threshold;
    opts.threshold_mode = if threshold_in_optimizer {
        ThresholdMode::InOptimizer
    } else {
        ThresholdMode::AfterAssignment
    };
    opts.excess = excess;
    if let Some(r) = refits {
        opts.refits = r;
    }
    if let Some(t) = refit_tolerance {
        opts.refit_tolerance = t;
    }
    opts.skip_rigid = skip_rigid;
    opts.band = band;
    if let Some(w) = position_weight {
        opts.position_weight = w;
    }
    if let Some(p) = cost_power {
        opts.cost_power = p;
    }
    if let Some(c) = common_sigma {
        opts.common_sigma = c;
    }
    opts.ordered = Some(ordered);
    let topo = |t: Option<Vec<[usize; 3]>>| match t {
        Some(triangles) => Topology::Mesh { triangles },
        None if ordered => Topology::ClosedContour,
        None => Topology::None,
    };
    let (topo_a, topo_b) = (topo(ta), topo(tb));
    let inner = py
        .detach(move || {
            let sa = Shape::new(da, ca, topo_a)?;
            let sb = Shape::new(db, cb, topo_b)?;
            match_shapes(&sa, &sb, &opts)
        })
        .map_err(to_py)?;
    Ok(PyMatch { inner })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMatch>()?;
    m.add_function(wrap_pyfunction!(match_py, m)?)?;
    Ok(())
}
