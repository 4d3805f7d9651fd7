//! `pymodal.ModalModel`: the finite-element model of one object and its vibration modes, and
//! `pymodal.eigh`: the generalized symmetric-definite eigensolver on user matrices.

use modal_core::model::{modal_basis_with_edges, model_matrices_with_edges};
use modal_core::{
    modal_basis, model_matrices, ElementKind, Material, ModalBasis, ModelMatrices, ModelOptions,
    PlaneModel, Shape, Topology,
};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{checked_array, index_rows, read_only};
use crate::errors::{input_error, internal, option_error, to_py};
use crate::options_py::{count, opt_count};
use crate::pickling::{Reader, Writer};

/// A float64 array of `obj` whose shape `fits`; anything else is an `InputError` naming the
/// argument.
fn float_matrix<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    name: &str,
    expected: &str,
    fits: impl Fn(&[usize]) -> bool,
) -> PyResult<PyReadonlyArray2<'py, f64>> {
    checked_array(py, obj, name, expected, "float64", fits)?.extract()
}

/// A material from `None` (rubber), a preset name, a dict `{young, poisson, density}` or an
/// `(E, nu, rho)` tuple; shared by every binding that takes `material=`.
pub(crate) fn parse_material(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Material> {
    let Some(obj) = obj else {
        return Ok(Material::RUBBER);
    };
    if obj.is_none() {
        return Ok(Material::RUBBER);
    }
    if let Ok(name) = obj.extract::<String>() {
        return Material::preset(&name).map_err(to_py);
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        for key in d.keys() {
            let k: String = key.extract().map_err(|_| {
                option_error(format!(
                    "material's keys must be the strings young, poisson, density; got {key:?}"
                ))
            })?;
            if !["young", "poisson", "density"].contains(&k.as_str()) {
                return Err(option_error(format!(
                    "unknown material key {k:?}; expected young, poisson, density"
                )));
            }
        }
        let get = |k: &str, default: f64| -> PyResult<f64> {
            match d.get_item(k)? {
                Some(v) => v.extract().map_err(|_| {
                    option_error(format!("material[{k:?}] must be a number, got {v:?}"))
                }),
                None => Ok(default),
            }
        };
        let r = Material::RUBBER;
        return Material::new(
            get("young", r.young)?,
            get("poisson", r.poisson)?,
            get("density", r.density)?,
        )
        .map_err(to_py);
    }
    if let Ok(t) = obj.cast::<PyTuple>() {
        let (e, nu, rho): (f64, f64, f64) = t.extract().map_err(|_| {
            option_error(format!(
                "material must be an (E, nu, rho) tuple of 3 numbers, got {t:?}"
            ))
        })?;
        return Material::new(e, nu, rho).map_err(to_py);
    }
    Err(option_error(
        "material must be None, a preset name (rubber, steel, aluminium, cork, unit), a dict \
         {young, poisson, density} or an (E, nu, rho) tuple",
    ))
}

/// A `rows × cols` array from its row-major entries.
fn row_major_to_numpy<'py>(
    py: Python<'py>,
    flat: Vec<f64>,
    rows: usize,
    cols: usize,
) -> Bound<'py, PyArray2<f64>> {
    PyArray1::from_vec(py, flat)
        .reshape([rows, cols])
        .expect("rows × cols reshape")
}

/// A `rows × cols` array from its column-major entries.
fn column_major_to_numpy<'py>(
    py: Python<'py>,
    column_major: &[f64],
    rows: usize,
    cols: usize,
) -> Bound<'py, PyArray2<f64>> {
    let flat = (0..rows * cols)
        .map(|e| column_major[(e % cols) * rows + e / cols])
        .collect();
    row_major_to_numpy(py, flat, rows, cols)
}

/// Finite-element model of one 2-D or 3-D object and its vibration modes.
///
/// Parameters
/// ----------
/// points : (n, 2) or (n, 3) array_like
/// element : {"gaussian", "axial"}, optional
///     Sclaroff's Gaussian element (no connectivity needed; the default) or linear bars (the
///     default when ``edges`` or ``triangles`` are given). Bars need ``edges``, ``triangles`` or
///     (2-D) the points in contour order: a closed contour is braced by its triangulated interior
///     so that exactly the 3 rigid modes have zero frequency. A 3-D mesh gets a hinge-bending
///     regularisation so that exactly the 6 rigid modes do.
/// material : None, preset name, dict {young, poisson, density} or (E, nu, rho); default rubber.
/// sigma : float, optional — Gaussian width; default ``kappa`` × mean nearest-neighbour distance.
/// edges : (e, 2) int array, optional — bars on exactly these edges (implies ``element="axial"``).
/// triangles : (t, 3) int array, optional — bars on the mesh edges (plus hinge bending in 3-D).
/// kappa : float, default 1 — σ rule factor.
/// n_modes : int, optional — compute only the lowest modes (faster); default all ``d·n``.
/// exact_rigid : bool, default False — project out the exact rigid motions (Gaussian element).
/// center_stride : int, default 1 — Gaussians on every ``center_stride``-th node only: a reduced
///     basis with ``d·⌈n/stride⌉`` modes, evaluated at all nodes and mass-normalised in the
///     reduced model; σ follows the centres' spacing; ``stiffness()``/``mass()`` raise
///     :class:`OptionError`.
/// plane : {"stress", "strain"}, default "stress" — 2-D assumption.
///
/// Attributes
/// ----------
/// eigenvalues : (k,) ω², ascending (rad²/s² in the material's SI units).
/// frequencies : (k,) ω = √ω² in rad/s (divide by 2π for Hz).
/// modes : (d·n, k) mass-normalised modes, component-major rows (``a*n + i`` = component a of
///     node i), largest-|·| entry of each column positive.
/// sigma : the Gaussian width used after the conditioning guard (None for bars).
#[pyclass(name = "ModalModel", module = "pymodal", frozen)]
pub struct PyModalModel {
    shape: Shape,
    options: ModelOptions,
    edges: Option<Vec<[usize; 2]>>,
    basis: ModalBasis,
}

#[pymethods]
impl PyModalModel {
    #[new]
    #[pyo3(signature = (points, *, element=None, material=None, sigma=None, edges=None,
        triangles=None, kappa=1.0, n_modes=None, exact_rigid=false, plane="stress", center_stride=1))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        element: Option<&str>,
        material: Option<&Bound<'_, PyAny>>,
        sigma: Option<f64>,
        edges: Option<&Bound<'_, PyAny>>,
        triangles: Option<&Bound<'_, PyAny>>,
        kappa: f64,
        n_modes: Option<i64>,
        exact_rigid: bool,
        plane: &str,
        center_stride: i64,
    ) -> PyResult<Self> {
        const EXPECTED: &str = "an (n, 2) or (n, 3) array (2 or 3 columns of coordinates)";
        let fits = |s: &[usize]| s.len() == 2 && (s[1] == 2 || s[1] == 3);
        let pts = float_matrix(py, points, "points", EXPECTED, fits)?;
        let dim = pts.shape()[1];
        let coords = pts.as_slice().map_err(internal)?.to_vec();
        let edges: Option<Vec<[usize; 2]>> = index_rows(
            py,
            edges,
            2,
            "edges",
            "a (k, 2) array (2 columns of node indices)",
        )?
        .map(|v| v.chunks_exact(2).map(|e| [e[0], e[1]]).collect());
        let tris: Option<Vec<[usize; 3]>> = index_rows(
            py,
            triangles,
            3,
            "triangles",
            "a (k, 3) array (3 columns of node indices)",
        )?
        .map(|v| v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect());
        if edges.is_some() && tris.is_some() {
            return Err(input_error("give edges or triangles, not both"));
        }
        let element = match element {
            None if edges.is_some() || tris.is_some() => ElementKind::Axial,
            None | Some("gaussian") => ElementKind::Gaussian,
            Some("axial" | "bar") => ElementKind::Axial,
            Some(other) => {
                return Err(option_error(format!(
                    "unknown element {other:?}; expected \"gaussian\" or \"axial\""
                )));
            }
        };
        if edges.is_some() && element == ElementKind::Gaussian {
            return Err(input_error(
                "edges define bar elements; they cannot be used with element=\"gaussian\"",
            ));
        }
        let plane = match plane {
            "stress" => PlaneModel::Stress,
            "strain" => PlaneModel::Strain,
            other => {
                return Err(option_error(format!(
                    "unknown plane model {other:?}; expected \"stress\" or \"strain\""
                )));
            }
        };
        let topology = match (&tris, element) {
            (Some(t), _) => Topology::Mesh {
                triangles: t.clone(),
            },
            (None, ElementKind::Axial) if edges.is_none() => Topology::ClosedContour,
            _ => Topology::None,
        };
        let options = ModelOptions {
            element,
            material: parse_material(material)?,
            plane,
            sigma,
            kappa,
            exact_rigid,
            n_modes: opt_count("n_modes", n_modes)?,
            center_stride: count("center_stride", center_stride)?,
        };
        let shape = Shape::new(dim, coords, topology).map_err(to_py)?;
        let basis = {
            let (shape, options, edges) = (&shape, &options, &edges);
            crate::pool::detach(py, move || match edges {
                Some(e) => modal_basis_with_edges(shape, e, options),
                None => modal_basis(shape, options),
            })
            .map_err(to_py)?
        };
        Ok(Self {
            shape,
            options,
            edges,
            basis,
        })
    }

    /// ω², ascending.
    #[getter]
    fn eigenvalues<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        read_only(PyArray1::from_slice(py, &self.basis.eigenvalues))
    }

    /// Natural angular frequencies ω (rad/s), ascending.
    #[getter]
    fn frequencies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        read_only(PyArray1::from_vec(py, self.basis.frequencies()))
    }

    /// (d·n, k) mass-normalised modes, component-major rows.
    #[getter]
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let b = &self.basis;
        read_only(column_major_to_numpy(
            py,
            &b.modes_column_major(),
            b.n_dofs(),
            b.n_modes(),
        ))
    }

    /// Gaussian width σ used (after the conditioning guard), or None for bar elements.
    #[getter]
    fn sigma(&self) -> Option<f64> {
        self.basis.sigma
    }

    /// Spatial dimension, 2 or 3.
    #[getter]
    fn dim(&self) -> usize {
        self.basis.dim
    }

    /// Number of nodes n.
    #[getter]
    fn n_nodes(&self) -> usize {
        self.basis.n_nodes
    }

    /// ``"gaussian"`` or ``"axial"``.
    #[getter]
    fn element(&self) -> &'static str {
        match self.options.element {
            ElementKind::Gaussian => "gaussian",
            ElementKind::Axial => "axial",
        }
    }

    /// (n, d·k) modal features: row i = [u_i(0..k), v_i(0..k), (w_i(0..k))].
    fn features<'py>(&self, py: Python<'py>, k: i64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let k = count("k", k)?;
        let f = self.basis.features(k).map_err(to_py)?;
        Ok(row_major_to_numpy(
            py,
            f,
            self.basis.n_nodes,
            self.basis.dim * k,
        ))
    }

    /// Explicit (d·n × d·n) stiffness K (Gaussian: K = Â K̃ Â with A = G⁻¹; for inspection and
    /// oracles, the modal solve never forms it).
    fn stiffness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.matrices(py)?;
        Ok(row_major_to_numpy(py, m.stiffness, m.n_dofs, m.n_dofs))
    }

    /// Explicit (d·n × d·n) mass M, so that ``modes.T @ M @ modes == I``.
    fn mass<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.matrices(py)?;
        Ok(row_major_to_numpy(py, m.mass, m.n_dofs, m.n_dofs))
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        self.state().reduce(py, "ModalModel")
    }
    /// Equal when every value is the same, bit for bit (as after a pickle round trip).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        self.state()
            .same_as(other.cast::<Self>().ok().map(|o| o.get().state()))
    }
    fn __hash__(&self) -> u64 {
        self.state().digest()
    }

    /// ``ModalModel(dim=2, n_nodes=30, element='gaussian', modes=60, sigma=0.52)``, the values
    /// as Python writes them (``sigma=None`` for bars).
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let sigma = self.basis.sigma.into_pyobject(py)?.repr()?.to_string();
        Ok(format!(
            "ModalModel(dim={}, n_nodes={}, element='{}', modes={}, sigma={sigma})",
            self.basis.dim,
            self.basis.n_nodes,
            self.element(),
            self.basis.n_modes(),
        ))
    }
}

impl PyModalModel {
    /// The shape, the options, the edges and the computed basis, for `__reduce__`.
    fn state(&self) -> Writer {
        let mut w = Writer::new();
        let shape = &self.shape;
        w.usize(shape.dim()).f64s(shape.coords());
        match shape.topology() {
            Topology::None => w.usize(0),
            Topology::ClosedContour => w.usize(1),
            Topology::Mesh { triangles } => w.usize(2).usizes(
                triangles
                    .iter()
                    .flatten()
                    .copied()
                    .collect::<Vec<_>>()
                    .into_iter(),
            ),
        };
        let o = &self.options;
        w.usize(match o.element {
            ElementKind::Gaussian => 0,
            ElementKind::Axial => 1,
        })
        .f64(o.material.young)
        .f64(o.material.poisson)
        .f64(o.material.density)
        .usize(match o.plane {
            PlaneModel::Stress => 0,
            PlaneModel::Strain => 1,
        })
        .opt_f64(o.sigma)
        .f64(o.kappa)
        .bool(o.exact_rigid)
        .opt_usize(o.n_modes)
        .usize(o.center_stride)
        .bool(self.edges.is_some())
        .usizes(
            self.edges
                .iter()
                .flatten()
                .flatten()
                .copied()
                .collect::<Vec<_>>()
                .into_iter(),
        );
        let b = &self.basis;
        w.usize(b.dim)
            .usize(b.n_nodes)
            .f64s(&b.eigenvalues)
            .usize(b.n_dofs())
            .usize(b.n_modes())
            .f64s(&b.modes_column_major())
            .opt_f64(b.sigma);
        w
    }

    /// The inverse of [`Self::state`].
    pub(crate) fn restore(state: &[u8]) -> PyResult<Self> {
        let mut r = Reader::new("ModalModel", state)?;
        let corrupt = || PyValueError::new_err("cannot unpickle ModalModel: corrupt state");
        let (dim, coords) = (r.usize()?, r.f64s()?);
        let topology = match r.usize()? {
            0 => Topology::None,
            1 => Topology::ClosedContour,
            2 => Topology::Mesh {
                triangles: r
                    .usizes()?
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
            },
            _ => return Err(corrupt()),
        };
        let shape = Shape::new(dim, coords, topology).map_err(to_py)?;
        let element = match r.usize()? {
            0 => ElementKind::Gaussian,
            1 => ElementKind::Axial,
            _ => return Err(corrupt()),
        };
        let material = Material {
            young: r.f64()?,
            poisson: r.f64()?,
            density: r.f64()?,
        };
        let plane = match r.usize()? {
            0 => PlaneModel::Stress,
            1 => PlaneModel::Strain,
            _ => return Err(corrupt()),
        };
        let options = ModelOptions {
            element,
            material,
            plane,
            sigma: r.opt_f64()?,
            kappa: r.f64()?,
            exact_rigid: r.bool()?,
            n_modes: r.opt_usize()?,
            center_stride: r.usize()?,
        };
        let has_edges = r.bool()?;
        let edges = r.usizes()?;
        let edges = has_edges.then(|| edges.chunks_exact(2).map(|e| [e[0], e[1]]).collect());
        let (basis_dim, n_nodes, eigenvalues) = (r.usize()?, r.usize()?, r.f64s()?);
        let (rows, cols, column_major) = (r.usize()?, r.usize()?, r.f64s()?);
        if rows.checked_mul(cols) != Some(column_major.len())
            || basis_dim.checked_mul(n_nodes) != Some(rows)
            || eigenvalues.len() != cols
        {
            return Err(corrupt());
        }
        let sigma = r.opt_f64()?;
        let basis =
            ModalBasis::from_column_major(basis_dim, n_nodes, eigenvalues, &column_major, sigma)
                .map_err(|_| corrupt())?;
        r.finish()?;
        Ok(Self {
            shape,
            options,
            edges,
            basis,
        })
    }

    fn matrices(&self, py: Python<'_>) -> PyResult<ModelMatrices> {
        let (shape, options, edges) = (&self.shape, &self.options, &self.edges);
        crate::pool::detach(py, move || match edges {
            Some(e) => model_matrices_with_edges(shape, e, options),
            None => model_matrices(shape, options),
        })
        .map_err(to_py)
    }
}

/// Eigenvalues and eigenvectors returned by [`eigh`].
type EighResult<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// Generalized symmetric-definite eigenproblem ``K x = λ M x`` (like ``scipy.linalg.eigh(K, M)``).
///
/// Returns ``(w, v)``: eigenvalues ascending and M-normalised eigenvectors as columns. Only the
/// lower triangles are read (like scipy's default ``lower=True``): the upper ones may hold
/// anything finite. ``n_modes`` computes only the lowest ones (much faster).
#[pyfunction]
#[pyo3(signature = (k, m, *, n_modes=None))]
fn eigh<'py>(
    py: Python<'py>,
    k: &Bound<'py, PyAny>,
    m: &Bound<'py, PyAny>,
    n_modes: Option<i64>,
) -> PyResult<EighResult<'py>> {
    const EXPECTED: &str = "a square 2-D array of numbers";
    let n_modes = opt_count("n_modes", n_modes)?;
    let matrix = |s: &[usize]| s.len() == 2;
    let ka = float_matrix(py, k, "k", EXPECTED, matrix)?;
    let ma = float_matrix(py, m, "m", EXPECTED, matrix)?;
    let (kr, kc) = (ka.shape()[0], ka.shape()[1]);
    let (mr, mc) = (ma.shape()[0], ma.shape()[1]);
    if kr != kc || mr != mc || kr != mr {
        return Err(input_error(format!(
            "k and m must be square and of the same size, got shapes {:?} and {:?}",
            (kr, kc),
            (mr, mc)
        )));
    }
    if n_modes == Some(0) || n_modes.is_some_and(|k| k > kr) {
        return Err(option_error(format!(
            "n_modes must be in 1..={kr} (the size of k), got {}",
            n_modes.unwrap_or(0)
        )));
    }
    let ks = ka.as_slice().map_err(internal)?;
    let ms = ma.as_slice().map_err(internal)?;
    for (name, values) in [("k", ks), ("m", ms)] {
        if values.iter().any(|v| !v.is_finite()) {
            return Err(input_error(format!("{name} must not contain infs or NaNs")));
        }
    }
    // numpy's row-major layout, as generalized_eigh reads it: the solver reads the lower
    // triangle the caller sees (like scipy.linalg.eigh), whatever the upper one holds.
    let e = crate::pool::detach(py, || modal_core::generalized_eigh(ks, ms, kr, n_modes))
        .map_err(to_py)?;
    Ok((
        PyArray1::from_slice(py, &e.values),
        column_major_to_numpy(py, e.vectors_column_major(), kr, e.values.len()),
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyModalModel>()?;
    m.add_function(wrap_pyfunction!(eigh, m)?)?;
    Ok(())
}
