//! `pymodal.match`: modal matching of two point sets, contours or meshes.

use modal_core::shape::looks_like_closed_contour;
use modal_core::Affine;
use modal_core::{match_shapes, AffinityMatrix, MatchPair, MatchResult, Shape, Side, Topology};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::{checked_array, index_rows, read_only};
use crate::errors::{input_error, internal, to_py};
use crate::field_py::PyField;
use crate::pickling::{Reader, Writer};

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
/// local_count, optimisation_count, excess_count : int — mutual-best, one-to-one and excess
///     (one-to-many) matches; the papers' tables count ``optimisation_count + excess_count``
///     (``len(pairs)``) as "excess nodes matching".
/// crossings : int or None — crossed pairs of matches along the two closed contours (both read
///     counter-clockwise, from the starts that make the count smallest): 0 when the matches keep
///     the contours' cyclic order, as ``solver="ordered"``'s always do; None unless both objects
///     are closed contours.
/// n_modes : int — modes per object in the features; refits : int — affine re-fits performed.
/// transform : (d+1, d+1) float64 — the affine map from a's coordinates to b's that produced
///     ``aligned_a`` (pre-alignment, then re-fits), homogeneous: ``aligned = (transform @
///     [x, y, 1])[:d]``, i.e. ``a @ transform[:d, :d].T + transform[:d, d]``.
/// aligned_a : (n, d) float64 — a's nodes in b's frame as the search used them.
/// outline_images : (n,) float64 or None — for two closed contours, where each node of a lands
///     on b's outline, as a position along b's numbering: ``j + t`` is the point ``t`` of the way
///     from node ``j`` to node ``j + 1`` (cyclically). After the coherent drift
///     (``refine="coherent"``, and the default ``refine="auto"`` where it drifts) the point of
///     b's outline nearest the node's moved position (``aligned_a``), finer than b's nodes —
///     with ``refine="auto"`` averaged along b's outline with the node's image under b's drift
///     onto a, read backwards; otherwise the node of its first pair (NaN: in no pair). None for
///     other objects.
/// drifted : bool — whether the coherent drift moved a's nodes (``refine="coherent"``, or
///     ``refine="auto"`` on two outlines it takes for two specimens); ``aligned_a`` then holds
///     the moved nodes.
///
/// The arrays are read-only copies made at each access (``.copy()`` to change one). Matches
/// pickle (``pickle``, ``multiprocessing``, Dask) and round-trip exactly: ``==`` compares
/// every value, bit for bit.
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

    /// Every field of the result, for `__reduce__`.
    fn state(&self) -> Writer {
        let r = &self.inner;
        let mut w = Writer::new();
        w.usize(r.pairs.len());
        for p in &r.pairs {
            w.usize(p.a).usize(p.b).f64(p.cost).bool(p.excess);
        }
        w.usize(r.affinity.rows())
            .usize(r.affinity.cols())
            .f64s(r.affinity.as_slice())
            .usizes(
                r.local_pairs
                    .iter()
                    .flat_map(|&(a, b)| [a, b])
                    .collect::<Vec<_>>()
                    .into_iter(),
            )
            .usizes(r.unmatched_a.iter().copied())
            .usizes(r.unmatched_b.iter().copied())
            .usize(r.n_modes)
            .usize(r.refits)
            .usize(r.solves);
        let t = &r.transform;
        w.usize(t.dim);
        t.m.iter().flatten().chain(&t.t).for_each(|&v| {
            w.f64(v);
        });
        w.f64s(&r.aligned_a);
        w.bool(r.crossings.is_some())
            .usize(r.crossings.unwrap_or(0));
        w.bool(r.outline_images.is_some())
            .f64s(r.outline_images.as_deref().unwrap_or(&[]))
            .bool(r.drifted);
        w
    }

    /// The inverse of [`Self::state`].
    pub(crate) fn restore(state: &[u8]) -> PyResult<Self> {
        let mut r = Reader::new("Match", state)?;
        // a, b, cost: 8 bytes each; excess: 1.
        let n_pairs = r.count(25)?;
        let pairs = (0..n_pairs)
            .map(|_| {
                Ok(MatchPair {
                    a: r.usize()?,
                    b: r.usize()?,
                    cost: r.f64()?,
                    excess: r.bool()?,
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let (rows, cols) = (r.usize()?, r.usize()?);
        let affinity = AffinityMatrix::new(rows, cols, r.f64s()?).map_err(to_py)?;
        let local = r.usizes()?;
        let local_pairs = local.chunks_exact(2).map(|p| (p[0], p[1])).collect();
        let (unmatched_a, unmatched_b) = (r.usizes()?, r.usizes()?);
        let (n_modes, refits, solves) = (r.usize()?, r.usize()?, r.usize()?);
        let mut transform = Affine::identity(r.usize()?);
        for v in transform.m.iter_mut().flatten().chain(&mut transform.t) {
            *v = r.f64()?;
        }
        let aligned_a = r.f64s()?;
        let counted = r.bool()?;
        let crossings = Some(r.usize()?).filter(|_| counted);
        let imaged = r.bool()?;
        let outline_images = Some(r.f64s()?).filter(|_| imaged);
        let drifted = r.bool()?;
        r.finish()?;
        Ok(Self::from_result(MatchResult {
            pairs,
            affinity,
            local_pairs,
            unmatched_a,
            unmatched_b,
            n_modes,
            refits,
            solves,
            transform,
            aligned_a,
            crossings,
            outline_images,
            drifted,
        }))
    }
}

#[pymethods]
impl PyMatch {
    /// (k, 2) int64 ``(index in a, index in b)``: the search's pairs, then the excess pairs.
    #[getter]
    fn pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        read_only(pairs_array(py, self.inner.pairs.iter().map(|p| (p.a, p.b))))
    }
    /// (k,) float64 cost Z[a, b] of each pair.
    #[getter]
    fn costs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        read_only(PyArray1::from_vec(
            py,
            self.inner.pairs.iter().map(|p| p.cost).collect(),
        ))
    }
    /// (k,) bool, True for the pairs added by the excess-node step.
    #[getter]
    fn excess<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<bool>>> {
        read_only(PyArray1::from_vec(
            py,
            self.inner.pairs.iter().map(|p| p.excess).collect(),
        ))
    }
    /// (n, m) float64 final affinity matrix Z in [0, 1].
    #[getter]
    fn affinity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let z = &self.inner.affinity;
        read_only(
            PyArray1::from_slice(py, z.as_slice())
                .reshape([z.rows(), z.cols()])
                .expect("n × m reshape"),
        )
    }
    /// int64 nodes of ``a`` in no pair.
    #[getter]
    fn unmatched_a<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        read_only(PyArray1::from_vec(
            py,
            self.inner.unmatched_a.iter().map(|&i| i as i64).collect(),
        ))
    }
    /// int64 nodes of ``b`` in no pair.
    #[getter]
    fn unmatched_b<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        read_only(PyArray1::from_vec(
            py,
            self.inner.unmatched_b.iter().map(|&i| i as i64).collect(),
        ))
    }
    /// (l, 2) int64 mutual-best matches on the final Z, under the threshold.
    #[getter]
    fn local_pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        read_only(pairs_array(py, self.inner.local_pairs.iter().copied()))
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
    /// Crossed pairs of matches along the two closed contours (0: the cyclic order is kept); None
    /// unless both objects are closed contours.
    #[getter]
    fn crossings(&self) -> Option<usize> {
        self.inner.crossings
    }
    /// (n,) float64 positions along b's numbering where a's nodes land on b's outline (``j + t``:
    /// ``t`` of the way from node ``j`` to ``j + 1``): after the coherent drift the point nearest
    /// each moved node, otherwise its first pair's node (NaN: in no pair); None unless both
    /// objects are closed contours.
    #[getter]
    fn outline_images<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        self.inner
            .outline_images
            .as_deref()
            .map(|v| read_only(PyArray1::from_slice(py, v)))
            .transpose()
    }
    /// Whether the coherent drift moved a's nodes (``refine="coherent"``, or the default
    /// ``refine="auto"`` on two outlines it takes for two specimens): ``aligned_a`` then holds
    /// the moved nodes, which ``transform`` does not map to.
    #[getter]
    fn drifted(&self) -> bool {
        self.inner.drifted
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
    /// (d+1, d+1) float64 homogeneous affine map from a's coordinates to b's that produced
    /// ``aligned_a``: ``a @ transform[:d, :d].T + transform[:d, d]``.
    #[getter]
    fn transform<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = &self.inner.transform;
        let d = t.dim;
        let mut h = vec![0.0; (d + 1) * (d + 1)];
        for r in 0..d {
            h[r * (d + 1)..r * (d + 1) + d].copy_from_slice(&t.m[r][..d]);
            h[r * (d + 1) + d] = t.t[r];
        }
        h[(d + 1) * (d + 1) - 1] = 1.0;
        read_only(
            PyArray1::from_vec(py, h)
                .reshape([d + 1, d + 1])
                .expect("(d+1) × (d+1) reshape"),
        )
    }
    /// (n, d) float64 nodes of a in b's frame, as the search used them.
    #[getter]
    fn aligned_a<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self.inner.transform.dim;
        read_only(
            PyArray1::from_slice(py, &self.inner.aligned_a)
                .reshape([self.inner.aligned_a.len() / d, d])
                .expect("n × d reshape"),
        )
    }
    /// The correspondence field of this match: a :class:`Field` fitted to its one-to-one pairs
    /// between ``a`` and ``b`` (the coordinates the match was made from), with ``smoothing`` λ.
    /// The excess pairs are left out: they match one node to several, and a map sends each
    /// point to one place. After the coherent drift (``drifted``) the field is fitted instead to
    /// each node of ``a`` and its image: for two closed contours the point of ``b``'s outline at
    /// ``outline_images``, otherwise its moved position (``aligned_a``); its ``pairs`` are then
    /// ``(i, i)``. Raises as :class:`Field` does, and with an ``InputError`` when ``b`` has
    /// fewer nodes than the images name (not the ``b`` of the match).
    #[pyo3(signature = (a, b, *, smoothing = 0.0))]
    fn field(
        &self,
        py: Python<'_>,
        a: &Bound<'_, PyAny>,
        b: &Bound<'_, PyAny>,
        smoothing: f64,
    ) -> PyResult<PyField> {
        if self.inner.drifted {
            let d = self.inner.transform.dim;
            let n = self.inner.aligned_a.len() / d;
            let images = match &self.inner.outline_images {
                Some(_) => {
                    let (_, cb) = points(py, b, "b")?;
                    self.inner.outline_image_points(&cb).ok_or_else(|| {
                        input_error(
                            "b has fewer nodes than the match's outline images name: give the b \
                             the match was made from",
                        )
                    })?
                }
                None => self.inner.aligned_a.clone(),
            };
            let images = PyArray1::from_slice(py, &images)
                .reshape([n, d])
                .expect("n × d reshape");
            let pairs = MatchPair::each_to_itself(n);
            return crate::field_py::fit(py, a, images.as_any(), pairs, smoothing);
        }
        crate::field_py::fit(py, a, b, self.inner.pairs.clone(), smoothing)
    }
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        self.state().reduce(py, "Match")
    }
    /// Equal when every value is the same, bit for bit (as after a pickle round trip).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        self.state()
            .same_as(other.cast::<Self>().ok().map(|o| o.get().state()))
    }
    fn __hash__(&self) -> u64 {
        self.state().digest()
    }
    fn __len__(&self) -> usize {
        self.inner.pairs.len()
    }
    /// The match's counts as an HTML table (shown by Jupyter).
    fn _repr_html_(&self) -> String {
        let r = &self.inner;
        let one_to_one: Vec<f64> = r
            .pairs
            .iter()
            .filter(|p| !p.excess)
            .map(|p| p.cost)
            .collect();
        let mean_cost = if one_to_one.is_empty() {
            "n/a".to_string()
        } else {
            format!(
                "{:.4}",
                one_to_one.iter().sum::<f64>() / one_to_one.len() as f64
            )
        };
        let rows = [
            ("matches", r.pairs.len().to_string()),
            ("local (mutual best)", r.local_count().to_string()),
            ("one-to-one", r.one_to_one_count().to_string()),
            ("excess", r.excess_count().to_string()),
            ("unmatched in a", r.unmatched_a.len().to_string()),
            ("unmatched in b", r.unmatched_b.len().to_string()),
            ("mean one-to-one cost", mean_cost),
            ("modes", r.n_modes.to_string()),
            ("refits", r.refits.to_string()),
        ];
        let body: String = rows
            .iter()
            .map(|(k, v)| format!("<tr><th style='text-align:left'>{k}</th><td>{v}</td></tr>"))
            .collect();
        format!("<table class='pymodal-match'><caption>pymodal.Match</caption>{body}</table>")
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

/// The (n, d) float64 coordinates of `obj`; anything but a 2-D array of numbers with 2 or 3
/// columns is an `InputError` naming the argument.
pub(crate) fn points(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(usize, Vec<f64>)> {
    const EXPECTED: &str = "an (n, 2) or (n, 3) array (2 or 3 columns of coordinates)";
    let fits = |s: &[usize]| s.len() == 2 && (s[1] == 2 || s[1] == 3);
    let arr = checked_array(py, obj, name, EXPECTED, "float64", fits)?;
    let arr: PyReadonlyArray2<f64> = arr.extract()?;
    Ok((arr.shape()[1], arr.as_slice().map_err(internal)?.to_vec()))
}

fn triangles(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
    name: &str,
) -> PyResult<Option<Vec<[usize; 3]>>> {
    const EXPECTED: &str = "a (t, 3) array (3 columns of node indices)";
    Ok(index_rows(py, obj, 3, name, EXPECTED)?
        .map(|v| v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()))
}

macro_rules! define_match {
    (
        match: [$($m:ident),*], match_doc: $match_doc:literal,
        pair: [$($p:ident),*], pair_doc: $pair_doc:literal,
        $($rest:tt)*
    ) => {
        /// Modal matching of two objects.
        ///
        /// Builds a finite-element model of each object, computes its vibration modes and matches the
        /// nodes in modal space. Every option defaults to ``None``: the documented default below, the
        /// same as ``pedomatch match`` (keyword ``x_y`` is the flag ``--x-y``; ``pymodal._options()``
        /// lists them all). The defaults are the most accurate setting measured (robust rotation
        /// pre-alignment, which for two closed outlines ends in a fit of the outlines and needs no modal
        /// affine re-fits (one σ for both outlines), up to two re-fits otherwise; cross-object mode
        /// alignment, excess nodes on contours; for unordered 3-D point sets the surface setting: wide
        /// common σ, no re-fits, aligned positions mixed in, powered costs); ``paper=True`` is the
        /// paper's literal setting.
        ///
        /// Parameters
        /// ----------
        /// a, b : (n, 2) or (n, 3) array_like — the node coordinates of the two objects.
        #[doc = $match_doc]
        #[doc = $pair_doc]
        /// triangles_a, triangles_b : (t, 3) int arrays — meshes (for ``element="axial"``).
        ///
        /// Raises
        /// ------
        /// InputError — ``a``, ``b`` or ``triangles_a``/``triangles_b`` not arrays of the documented
        ///     shape (e.g. 4 columns, 1-D), or ``a`` and ``b`` of different dimensions; the message
        ///     names the argument;
        /// OptionError — an unknown or out-of-range option value (an ``InputError``);
        /// DegenerateShapeError — too few, coincident or collinear nodes, NaN or infinite coordinates;
        /// NumericalError — the eigensolver failed.
        /// All are :class:`PedomatchError` and ``ValueError`` subclasses. An option of the wrong type
        /// raises ``TypeError`` naming it and the type it takes (``modes="many"``: "modes must be a
        /// number, got 'many'").
        #[pyfunction]
        #[pyo3(name = "match", signature = (a, b, *, $($m = None,)* $($p = None,)* triangles_a = None, triangles_b = None))]
        #[allow(clippy::too_many_arguments)]
        fn match_py(
            py: Python<'_>,
            a: &Bound<'_, PyAny>,
            b: &Bound<'_, PyAny>,
            $($m: Option<&Bound<'_, PyAny>>,)*
            $($p: Option<&Bound<'_, PyAny>>,)*
            triangles_a: Option<&Bound<'_, PyAny>>,
            triangles_b: Option<&Bound<'_, PyAny>>,
        ) -> PyResult<PyMatch> {
            let given = [$((stringify!($m), $m),)* $((stringify!($p), $p),)*];
            let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
            match_objects(py, a, b, &get, triangles_a, triangles_b)
        }
    };
}

crate::keywords::with_option_keywords!(define_match);

/// [`match_py`] with its option keywords by name (`get`).
fn match_objects<'a, 'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    get: &dyn Fn(&str) -> Option<&'a Bound<'py, PyAny>>,
    triangles_a: Option<&Bound<'py, PyAny>>,
    triangles_b: Option<&Bound<'py, PyAny>>,
) -> PyResult<PyMatch>
where
    'py: 'a,
{
    let params = crate::options_py::match_params(get)?;
    let ordered = get("ordered");
    let (da, ca) = points(py, a, "a")?;
    let (db, cb) = points(py, b, "b")?;
    if da != db {
        return Err(input_error(format!(
            "a and b must have the same number of columns (both 2-D or both 3-D), got {da} and \
             {db}"
        )));
    }
    let ta = triangles(py, triangles_a, "triangles_a")?;
    let tb = triangles(py, triangles_b, "triangles_b")?;
    let ordered = match crate::options_py::keyword::<bool>("ordered", ordered)? {
        Some(o) => o,
        None => {
            ta.is_none()
                && tb.is_none()
                && looks_like_closed_contour(&ca, da)
                && looks_like_closed_contour(&cb, db)
        }
    };
    // Contours get the contour recipe; unordered 3-D point sets the measured surface setting.
    let mut opts = params.to_match_options(da, ordered).map_err(to_py)?;
    opts.ordered = Some(ordered);
    let topo = |t: Option<Vec<[usize; 3]>>| match t {
        Some(triangles) => Topology::Mesh { triangles },
        None if ordered => Topology::ClosedContour,
        None => Topology::None,
    };
    let (topo_a, topo_b) = (topo(ta), topo(tb));
    let inner = crate::pool::detach(py, move || {
        let sa = Shape::new(da, ca, topo_a).map_err(|e| e.of(Side::A))?;
        let sb = Shape::new(db, cb, topo_b).map_err(|e| e.of(Side::B))?;
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
