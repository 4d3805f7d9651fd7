//! The finite-element model of one object and its vibration modes.

// Index loops over several matrices at once read better than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::Solve;
use faer::reborrow::ReborrowMut;
use faer::Mat;

use super::axial::{self, BarModel};
use super::gaussian::GaussianIntegrals;
use super::material::{Material, PlaneModel};
use super::rigid;
use crate::eigen::{self, EigenPairs};
use crate::error::{ModalError, OptionError, Unsupported};
use crate::shape::nearest_neighbour_stats;
use crate::shape::{Shape, Topology};

/// Which finite elements model the object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ElementKind {
    /// Sclaroff's isoparametric Gaussian element: one element over all nodes, no order needed.
    #[default]
    Gaussian,
    /// Linear axial (bar) elements along contour edges or mesh edges.
    Axial,
}

/// Parameters of [`modal_basis`].
#[derive(Debug, Clone, PartialEq)]
pub struct ModelOptions {
    /// The finite element: Gaussian (the method's) or bars along the object's edges.
    pub element: ElementKind,
    /// Elastic constants.
    pub material: Material,
    /// Plane stress or plane strain (2-D).
    pub plane: PlaneModel,
    /// Absolute Gaussian width; `None` uses `kappa × mean nearest-neighbour distance`.
    pub sigma: Option<f64>,
    /// σ rule factor (docs/method.md §2.7).
    pub kappa: f64,
    /// Project out the exact rigid-body motions (docs/method.md §2.6).
    pub exact_rigid: bool,
    /// Compute only the lowest `k` modes; `None` computes all the model has (`dim × n`, or
    /// `dim ×` the centre count of a reduced basis).
    pub n_modes: Option<usize>,
    /// Gaussian element only: place a Gaussian on every `center_stride`-th node instead of on
    /// every node (1, Sclaroff's element). The model then has `dim · ⌈n / stride⌉` degrees of
    /// freedom, its modes are evaluated at all nodes (`φ = G_nc ψ`), and the σ rule uses the
    /// centres' spacing (`stride ×` the nodes'). Modes are then mass-normalised in the reduced
    /// model (`ψᵀ Γ̃ ψ = I`); there is no nodal `K`, `M`. A stride of 2 cuts a 60-node solve of 30
    /// modes from 0.54 to 0.19 ms; see BENCHMARKS.md ("Matching accuracy") for what it costs in accuracy.
    pub center_stride: usize,
}

impl ModelOptions {
    /// Degrees of freedom — the number of modes — of the model of `n` nodes in `dim`-D: fewer
    /// than the nodes' `dim · n` with a reduced Gaussian basis.
    pub fn degrees_of_freedom(&self, dim: usize, n: usize) -> usize {
        match self.element {
            ElementKind::Gaussian => dim * n.div_ceil(self.center_stride.max(1)),
            ElementKind::Axial => dim * n,
        }
    }
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            element: ElementKind::Gaussian,
            material: Material::RUBBER,
            plane: PlaneModel::Stress,
            sigma: None,
            kappa: 1.0,
            exact_rigid: false,
            n_modes: None,
            center_stride: 1,
        }
    }
}

/// Vibration modes of one object, ascending by frequency.
///
/// ```
/// use modal_core::{modal_basis, ModelOptions, Shape, Topology};
/// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
/// let shape = Shape::from_points_2d(&square, Topology::None).unwrap();
/// let basis = modal_basis(&shape, &ModelOptions::default()).unwrap();
/// assert_eq!((basis.n_dofs(), basis.n_modes()), (8, 8));
/// assert_eq!(basis.mode(3).len(), 8);
/// ```
#[derive(Debug, Clone)]
pub struct ModalBasis {
    /// Dimension of the nodes (2 or 3).
    pub dim: usize,
    /// Nodes of the object.
    pub n_nodes: usize,
    /// ω², ascending, one per retained mode.
    pub eigenvalues: Vec<f64>,
    /// `(dim·n) × k`, component-major rows (`a·n + i` is component `a` of node `i`), mass-normalised
    /// columns (`φᵀ M φ = I`), each with its largest-|·| entry positive.
    pub(crate) modes: Mat<f64>,
    /// The Gaussian width actually used (after the conditioning guard), if Gaussian.
    pub sigma: Option<f64>,
}

impl ModalBasis {
    /// A basis from its parts, the modes given column-major (`n_dofs × n_modes`, mode `j` at
    /// `j·n_dofs ..`), e.g. one stored with [`ModalBasis::modes_column_major`].
    ///
    /// # Errors
    /// [`ModalError::SizeMismatch`] when the sizes do not fit together
    /// (`n_dofs = dim·n_nodes`, one eigenvalue per mode).
    pub fn from_column_major(
        dim: usize,
        n_nodes: usize,
        eigenvalues: Vec<f64>,
        modes: &[f64],
        sigma: Option<f64>,
    ) -> Result<Self, ModalError> {
        let rows = dim * n_nodes;
        let cols = eigenvalues.len();
        if modes.len() != rows * cols {
            return Err(ModalError::SizeMismatch {
                what: "entries of the modes (dim·n_nodes × eigenvalues)",
                expected: rows * cols,
                found: modes.len(),
            });
        }
        Ok(Self {
            dim,
            n_nodes,
            eigenvalues,
            modes: Mat::from_fn(rows, cols, |i, j| modes[j * rows + i]),
            sigma,
        })
    }

    /// Number of modes computed.
    pub fn n_modes(&self) -> usize {
        self.modes.ncols()
    }

    /// Length of a mode: `dim · n_nodes` degrees of freedom.
    pub fn n_dofs(&self) -> usize {
        self.modes.nrows()
    }

    /// Mode `j` (`j < n_modes()`): `n_dofs()` entries, component-major (`a·n + i` is component
    /// `a` of node `i`), mass-normalised, its largest-|·| entry positive.
    ///
    /// # Panics
    /// When `j >= n_modes()`.
    pub fn mode(&self, j: usize) -> &[f64] {
        eigen::column(&self.modes, j)
    }

    /// Every mode, one after the other (`n_dofs() × n_modes()` column-major).
    pub fn modes_column_major(&self) -> Vec<f64> {
        (0..self.n_modes())
            .flat_map(|j| self.mode(j).iter().copied())
            .collect()
    }

    /// Natural angular frequencies ω = √ω² (rad/s in the material's units); tiny negative ω²
    /// from round-off map to 0.
    pub fn frequencies(&self) -> Vec<f64> {
        self.eigenvalues
            .iter()
            .map(|&l| l.max(0.0).sqrt())
            .collect()
    }

    /// Per-node modal features of the first `k` modes: an `n × (dim·k)` matrix, row-major, whose
    /// row `i` is `[u_i(0..k), v_i(0..k), (w_i(0..k))]` (Tavares & Bastos 2005, eqs 1–2).
    ///
    /// # Errors
    /// [`ModalError::TooFewModes`] when `k > n_modes()`.
    pub fn features(&self, k: usize) -> Result<Vec<f64>, ModalError> {
        if k > self.modes.ncols() {
            return Err(ModalError::TooFewModes {
                requested: k,
                available: self.modes.ncols(),
            });
        }
        let (n, cols) = (self.n_nodes, self.dim * k);
        Ok((0..n * cols)
            .map(|e| {
                let (i, c) = (e / cols, e % cols);
                self.modes[((c / k) * n + i, c % k)]
            })
            .collect())
    }
}

/// Relative eigenvalue below which a mode counts as zero-energy (docs/method.md §4.2).
pub(crate) const ZERO_MODE_TOL: f64 = 1e-9;

/// Largest accepted `max(L_ii)/min(L_ii)` of the Cholesky factor of Γ (cond(Γ) ≲ 10¹²; §2.8).
pub(crate) const CONDITION_GUARD: f64 = 1e6;

/// How many times the conditioning guard shrinks σ by 0.8 before giving up.
const GUARD_RETRIES: usize = 30;

/// Builds the finite-element model of `shape` and solves `K φ = ω² M φ`.
pub fn modal_basis(shape: &Shape, options: &ModelOptions) -> Result<ModalBasis, ModalError> {
    let model = build_model(shape, options)?;
    solve_model(shape, &model, options)
}

/// The bar model on `edges` after the input checks, with `options` set to the axial element.
fn model_on_edges(
    shape: &Shape,
    edges: &[[usize; 2]],
    options: &ModelOptions,
) -> Result<(SolverModel, ModelOptions), ModalError> {
    options.material.validate()?;
    validate_nodes(shape)?;
    let model = axial::axial_model_with_edges(shape, edges, &[], &options.material)?.into();
    let opts = ModelOptions {
        element: ElementKind::Axial,
        ..options.clone()
    };
    Ok((model, opts))
}

/// Bar model on explicitly given edges (no mechanism remedy is added: the edges must brace the
/// structure, or the zero-mode check fails). `options.element` is ignored.
pub fn modal_basis_with_edges(
    shape: &Shape,
    edges: &[[usize; 2]],
    options: &ModelOptions,
) -> Result<ModalBasis, ModalError> {
    let (model, opts) = model_on_edges(shape, edges, options)?;
    solve_model(shape, &model, &opts)
}

/// Solves an assembled model; `options.element` selects the Axial zero-mode check.
pub(crate) fn solve_model(
    shape: &Shape,
    model: &SolverModel,
    options: &ModelOptions,
) -> Result<ModalBasis, ModalError> {
    let dim = shape.dim();
    let n = shape.len();
    let total = dim * n;
    // The model's own degrees of freedom: fewer than the nodes' with a reduced Gaussian basis.
    let dof = model.stiffness.nrows();
    let k = options.n_modes.unwrap_or(dof);
    if k == 0 || k > dof {
        return Err(OptionError::new("n_modes", k, format!("an integer in 1..={dof}")).into());
    }

    let mut c = eigen::block_congruence(model.stiffness.as_ref(), model.mass_factor.as_ref(), dim);
    let rigid = if options.exact_rigid {
        Some(rigid_reduced_basis(shape, model)?)
    } else {
        None
    };
    let r = rigid.as_ref().map_or(0, |u| u.ncols());
    if options.exact_rigid {
        let u = rigid.as_ref().expect("rigid basis built above");
        deflate_rigid(&mut c, u);
    }
    // Bar models count their zero modes over the whole spectrum (docs/method.md §3.2); every other
    // model needs only the eigenvalues of the modes it returns.
    let zero_mode_check = options.element == ElementKind::Axial && !options.exact_rigid;
    let mut pairs = if zero_mode_check {
        eigen::symmetric_eigen(c, Some(k))?
    } else {
        eigen::symmetric_eigen_lowest(c, k)?
    };
    if options.exact_rigid {
        // The deflated rigid space sits at eigenvalue −s; replace the solver's arbitrary basis
        // of it by the canonical M-orthonormal one (docs/method.md §2.6).
        let u = rigid.as_ref().expect("rigid basis built above");
        for j in 0..r.min(k) {
            pairs.values[j] = 0.0;
            pairs.vectors.col_mut(j).copy_from(u.col(j));
        }
        for v in pairs.all_values.iter_mut().flatten().take(r) {
            *v = 0.0;
        }
    }
    if zero_mode_check {
        check_zero_modes(&pairs, dim)?;
    }

    eigen::block_solve_lower_transpose(model.mass_factor.as_ref(), pairs.vectors.as_mut(), dim);
    let mut modes = match &model.interpolation {
        Some(g) => {
            let mut phi = Mat::<f64>::zeros(total, k);
            let centers = g.ncols();
            for a in 0..dim {
                let psi = pairs.vectors.as_ref().subrows(a * centers, centers);
                // Explicitly sequential: faer's `*` runs on the global (rayon) pool, whose
                // start-up and spinning cost more than this 60 × 30 product itself.
                faer::linalg::matmul::matmul(
                    phi.as_mut().subrows_mut(a * n, n),
                    faer::Accum::Replace,
                    g.as_ref(),
                    psi,
                    1.0,
                    faer::Par::Seq,
                );
            }
            crate::simd::clear_upper_state();
            phi
        }
        None => pairs.vectors,
    };
    if options.exact_rigid {
        // Canonical rigid modes keep the sign of T_x, T_y, … rather than the largest-entry rule.
        let mut flexible = modes.as_mut().subcols_mut(r.min(k), k - r.min(k));
        eigen::canonical_signs(flexible.rb_mut());
    } else {
        eigen::canonical_signs(modes.as_mut());
    }
    if !(0..modes.ncols()).all(|j| crate::simd::all_finite(eigen::column(&modes, j))) {
        return Err(ModalError::NonFiniteResult { stage: "the modes" });
    }
    Ok(ModalBasis {
        dim,
        n_nodes: n,
        eigenvalues: pairs.values,
        modes,
        sigma: model.sigma,
    })
}

/// The assembled model in the form the solver uses: `K_s φ_s = ω² (I_d ⊗ L Lᵀ) φ_s`, with the
/// nodal modes `φ = (I_d ⊗ T) φ_s` (`T = G` for the Gaussian element's ψ-form, identity for bars).
#[derive(Debug, Clone)]
pub(crate) struct SolverModel {
    /// `K̃` (Gaussian, ψ-form) or `K` (bars): `d·n × d·n`, full symmetric storage.
    pub stiffness: Mat<f64>,
    /// Lower Cholesky factor of the `n × n` mass block (`ρΓ`, or the bars' consistent `M_s`).
    pub mass_factor: Mat<f64>,
    /// `G` for the Gaussian element: `n × c`, the centres' Gaussians at the nodes (`c = n`,
    /// square and symmetric, unless the basis is reduced).
    pub interpolation: Option<Mat<f64>>,
    /// Gaussian width after the conditioning guard.
    pub sigma: Option<f64>,
}

impl From<BarModel> for SolverModel {
    fn from(bars: BarModel) -> Self {
        Self {
            stiffness: bars.stiffness,
            mass_factor: bars.mass_factor,
            interpolation: None,
            sigma: None,
        }
    }
}

/// Validates the input and assembles the solver form of the model.
pub(crate) fn build_model(
    shape: &Shape,
    options: &ModelOptions,
) -> Result<SolverModel, ModalError> {
    options.material.validate()?;
    let mean_spacing = validate_nodes(shape)?;
    match options.element {
        ElementKind::Gaussian => gaussian_model(shape, mean_spacing, options),
        ElementKind::Axial => Ok(axial::axial_model(shape, &options.material)?.into()),
    }
}

/// Explicit nodal stiffness and mass matrices of a model ([`model_matrices`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelMatrices {
    /// Order of both matrices: `dim · n` degrees of freedom, component-major (`a·n + i` is
    /// component `a` of node `i`).
    pub n_dofs: usize,
    /// Stiffness `K`, `n_dofs × n_dofs`, row-major (symmetric).
    pub stiffness: Vec<f64>,
    /// Mass `M`, `n_dofs × n_dofs`, row-major (symmetric positive definite).
    pub mass: Vec<f64>,
    /// The Gaussian width used (after the conditioning guard), if Gaussian.
    pub sigma: Option<f64>,
}

impl ModelMatrices {
    fn from_explicit((k, m, sigma): ExplicitModel) -> Self {
        let n = k.nrows();
        let row_major = |a: &Mat<f64>| (0..n * n).map(|e| a[(e / n, e % n)]).collect();
        Self {
            n_dofs: n,
            stiffness: row_major(&k),
            mass: row_major(&m),
            sigma,
        }
    }
}

/// Explicit nodal `K` and `M` of the model and the σ used. For inspection and external solvers
/// (e.g. a scipy oracle); [`modal_basis`] never forms them for the Gaussian element, whose
/// explicit form needs `G⁻¹`.
///
/// ```
/// use modal_core::{model_matrices, ModelOptions, Shape, Topology};
/// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
/// let shape = Shape::from_points_2d(&square, Topology::None).unwrap();
/// let m = model_matrices(&shape, &ModelOptions::default()).unwrap();
/// assert_eq!((m.n_dofs, m.stiffness.len()), (8, 64));
/// ```
///
/// # Errors
/// The errors of [`modal_basis`]; [`Unsupported::ReducedNodalMatrices`] for a reduced Gaussian
/// basis (`center_stride > 1`).
pub fn model_matrices(shape: &Shape, options: &ModelOptions) -> Result<ModelMatrices, ModalError> {
    explicit_model(shape, options).map(ModelMatrices::from_explicit)
}

/// [`model_matrices`] for a bar model on explicitly given edges.
pub fn model_matrices_with_edges(
    shape: &Shape,
    edges: &[[usize; 2]],
    options: &ModelOptions,
) -> Result<ModelMatrices, ModalError> {
    let (model, opts) = model_on_edges(shape, edges, options)?;
    explicit_matrices(shape, &model, &opts).map(ModelMatrices::from_explicit)
}

/// `(K, M, σ)` as dense matrices: [`model_matrices`] for the crate's own checks and benchmarks.
pub(crate) fn explicit_model(
    shape: &Shape,
    options: &ModelOptions,
) -> Result<ExplicitModel, ModalError> {
    let model = build_model(shape, options)?;
    explicit_matrices(shape, &model, options)
}

/// `(K, M, σ)`: explicit stiffness and mass (`d·n × d·n`) and the Gaussian width used.
pub(crate) type ExplicitModel = (Mat<f64>, Mat<f64>, Option<f64>);

fn explicit_matrices(
    shape: &Shape,
    model: &SolverModel,
    options: &ModelOptions,
) -> Result<ExplicitModel, ModalError> {
    let dim = shape.dim();
    let n = shape.len();
    match (&model.interpolation, model.sigma) {
        (Some(g), _) if g.ncols() != n => Err(Unsupported::ReducedNodalMatrices.into()),
        (Some(_), Some(sigma)) => {
            let ints = GaussianIntegrals::new(shape, sigma);
            let (k, m) = ints.explicit_matrices(&options.material, options.plane)?;
            Ok((k, m, Some(sigma)))
        }
        _ => {
            let l = model.mass_factor.as_ref();
            let ms = l * l.transpose();
            let mut m = Mat::<f64>::zeros(dim * n, dim * n);
            for a in 0..dim {
                m.as_mut().submatrix_mut(a * n, a * n, n, n).copy_from(&ms);
            }
            Ok((model.stiffness.clone(), m, None))
        }
    }
}

/// Too few nodes and coincident nodes make every model singular: checks both, and returns the
/// nodes' mean nearest-neighbour distance (the σ rule's spacing), which the check computes anyway.
fn validate_nodes(shape: &Shape) -> Result<f64, ModalError> {
    let dim = shape.dim();
    let n = shape.len();
    if n < dim + 1 {
        return Err(ModalError::TooFewNodes {
            nodes: n,
            min: dim + 1,
        });
    }
    let c = shape.coords();
    let mut extent = 0.0f64;
    for a in 0..dim {
        let (lo, hi) = (0..n)
            .map(|i| c[i * dim + a])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            });
        extent = extent.max(hi - lo);
    }
    let (mean_nn, min_nn, (i, j)) = nearest_neighbour_stats(shape);
    if min_nn.is_nan() || min_nn <= 1e-10 * extent {
        return Err(ModalError::CoincidentNodes {
            first: i.min(j),
            second: i.max(j),
        });
    }
    Ok(mean_nn)
}

/// The Gaussian model of `shape`, whose nodes' mean nearest-neighbour distance is `mean_spacing`.
fn gaussian_model(
    shape: &Shape,
    mean_spacing: f64,
    options: &ModelOptions,
) -> Result<SolverModel, ModalError> {
    let dim = shape.dim();
    let stride = options.center_stride;
    let centers = reduced_centers(shape, stride)?;
    let basis = centers.as_ref().unwrap_or(shape);
    let n = basis.len();
    let mut sigma = match options.sigma {
        Some(s) => {
            if !(s.is_finite() && s > 0.0) {
                return Err(OptionError::new("sigma", s, "a finite number > 0").into());
            }
            s
        }
        None => {
            if !(options.kappa.is_finite() && options.kappa > 0.0) {
                return Err(OptionError::new("kappa", options.kappa, "a finite number > 0").into());
            }
            options.kappa * mean_spacing * stride as f64
        }
    };
    let rho = options.material.density;
    let (lambda, mu) = options.material.lame(dim, options.plane);
    for _ in 0..GUARD_RETRIES {
        let ints = GaussianIntegrals::new(basis, sigma);
        let mut l = &ints.gamma * faer::Scale(rho);
        crate::simd::clear_upper_state();
        if eigen::cholesky_in_place(l.as_mut()).is_ok() {
            let diag: Vec<f64> = (0..n).map(|i| l[(i, i)]).collect();
            let lo = diag.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = diag.iter().copied().fold(0.0, f64::max);
            if lo > 0.0 && hi / lo <= CONDITION_GUARD {
                for j in 0..n {
                    for i in 0..j {
                        l[(i, j)] = 0.0;
                    }
                }
                let stiffness = ints.k_tilde(lambda, mu);
                let interpolation = match &centers {
                    None => ints.g,
                    Some(c) => super::gaussian::gaussians_at(shape, c, sigma),
                };
                return Ok(SolverModel {
                    stiffness,
                    mass_factor: l,
                    interpolation: Some(interpolation),
                    sigma: Some(sigma),
                });
            }
        }
        sigma *= 0.8;
    }
    Err(ModalError::IllConditioned { sigma })
}

/// Every `stride`-th node as a Gaussian centre (`None` for stride 1: every node).
fn reduced_centers(shape: &Shape, stride: usize) -> Result<Option<Shape>, ModalError> {
    if stride == 0 {
        return Err(OptionError::new("center_stride", 0, "an integer >= 1").into());
    }
    if stride == 1 {
        return Ok(None);
    }
    let dim = shape.dim();
    // ⌈n / stride⌉ centres, as `ModelOptions::degrees_of_freedom` counts them.
    let coords: Vec<f64> = (0..shape.len())
        .step_by(stride)
        .flat_map(|i| shape.coords()[i * dim..(i + 1) * dim].iter().copied())
        .collect();
    let centers = Shape::new(dim, coords, Topology::None)?;
    validate_nodes(&centers).map_err(|e| {
        OptionError::new(
            "center_stride",
            stride,
            format!(
                "a stride that leaves a valid set of centres; it leaves {} centres of {} nodes: {e}",
                centers.len(),
                shape.len(),
            ),
        )
    })?;
    Ok(Some(centers))
}

/// The rigid basis mapped to the reduced (standard-problem) coordinates `y = (I⊗Lᵀ) T⁻¹ R` and
/// orthonormalised in order: its columns are the canonical M-orthonormal rigid modes.
fn rigid_reduced_basis(shape: &Shape, model: &SolverModel) -> Result<Mat<f64>, ModalError> {
    let dim = shape.dim();
    let n = shape.len();
    if model.interpolation.as_ref().is_some_and(|g| g.ncols() != n) {
        return Err(Unsupported::ExactRigidReduced.into());
    }
    let mut y = rigid::rigid_basis(shape);
    if let Some(g) = &model.interpolation {
        let llt = g
            .llt(faer::Side::Lower)
            .map_err(|_| ModalError::NotPositiveDefinite {
                matrix: "the Gaussian matrix G",
                pivot: None,
            })?;
        for a in 0..dim {
            let blk = y.as_ref().subrows(a * n, n).to_owned();
            let solved = llt.solve(&blk);
            y.as_mut().subrows_mut(a * n, n).copy_from(&solved);
        }
    }
    let lt = model.mass_factor.transpose();
    for a in 0..dim {
        let blk = y.as_ref().subrows(a * n, n).to_owned();
        y.as_mut().subrows_mut(a * n, n).copy_from(lt * &blk);
    }
    rigid::orthonormalise(&mut y)?;
    Ok(y)
}

/// `C ← Q C Q − s U Uᵀ` with `Q = I − U Uᵀ`: the flexible spectrum is that of the M-orthogonal
/// projection (docs/method.md §2.6) and the rigid space is moved to `−s < 0` so that it sorts
/// first.
fn deflate_rigid(c: &mut Mat<f64>, u: &Mat<f64>) {
    let v = &*c * u; // C U
    let h = u.transpose() * &v; // Uᵀ C U
    let s = (0..c.nrows())
        .map(|i| c[(i, i)].abs())
        .fold(0.0, f64::max)
        .max(1.0);
    let uh = u * &h;
    // C − U Vᵀ − V Uᵀ + U H Uᵀ − s U Uᵀ = C − U (V − ½ U H + ½ s U)ᵀ − (V − ½ U H + ½ s U) Uᵀ
    let w = &v - (&uh * faer::Scale(0.5)) + (u * faer::Scale(0.5 * s));
    *c -= u * w.transpose() + &w * u.transpose();
    eigen::symmetrise(c.as_mut());
}

fn check_zero_modes(pairs: &EigenPairs, dim: usize) -> Result<(), ModalError> {
    let expected = if dim == 2 { 3 } else { 6 };
    let all = pairs.all_values.as_deref().ok_or(ModalError::Internal {
        invariant: "the zero-mode check needs every eigenvalue",
    })?;
    let zeros = count_zero_modes(all);
    if zeros != expected {
        return Err(ModalError::Mechanism {
            dim,
            zero_modes: zeros,
            expected,
        });
    }
    Ok(())
}

/// Number of eigenvalues below `ZERO_MODE_TOL × max` (docs/method.md §4.2).
pub fn count_zero_modes(eigenvalues: &[f64]) -> usize {
    let max = eigenvalues
        .iter()
        .copied()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    eigenvalues
        .iter()
        .filter(|&&v| v < ZERO_MODE_TOL * max)
        .count()
}
