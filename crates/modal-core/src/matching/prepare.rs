//! Stage 1, prepare: what one object needs for every pair it takes part in, and what a pair adds
//! to that (docs/method.md §5.3).
//!
//! Per object ([`prepare`], reusable): the checks of the nodes (at least 3, none coincident, not
//! all collinear), the normalisation (centroid 0, RMS radius 1), the counter-clockwise order of an
//! ordered contour, its mean node spacing, the neighbour lists of the point-set excess step, and
//! the modes it gets *in its own normalised frame*. The pipeline solves the second object of a
//! pair in that frame, and the first object too in the first pass when nothing moves it
//! (`Prealign::Normalize`); those solves are cached in the [`PreparedShape`] under the exact model, skip and
//! mode count they were made with, so a later pair that asks for the same reuses them and a pair
//! that asks for another count solves again: results never depend on what was cached.
//!
//! Per pair (`Pair`, internal): whether the pair is treated as ordered contours, the mode count
//! `k` (it depends on the smaller object), the band, a common σ, and B's spacing as the re-fit
//! tolerance's unit. The first object's modes after the pre-alignment depend on both objects and
//! are never cached.

use std::borrow::Cow;
use std::sync::{Arc, Mutex, OnceLock};

use super::excess;
use super::features::ModalFeatures;
use super::prealign::{self, Affine};
use super::recipe::MatchOptions;
use super::search::Search;
use crate::error::{ModalError, OptionError, Side, Unsupported};
use crate::model::{modal_basis, ModelOptions};
use crate::shape::{nearest_neighbour_stats_of, Shape, Topology};

/// One object prepared for matching: checked, normalised, oriented, with its own-frame modes
/// cached. Cheap to clone (the data is shared) and safe to share between threads, so one prepared
/// object can serve the pair with its predecessor and the pair with its successor at once.
///
/// ```
/// use modal_core::{match_prepared, match_shapes, prepare, MatchOptions, Parallelism, Shape, Topology};
/// let ellipse = |a: f64, n: usize| -> Shape {
///     let c: Vec<f64> = (0..n)
///         .flat_map(|i| {
///             let t = i as f64 / n as f64 * std::f64::consts::TAU;
///             [a * t.cos(), t.sin()]
///         })
///         .collect();
///     Shape::new(2, c, Topology::ClosedContour).unwrap()
/// };
/// let frames = [ellipse(2.0, 30), ellipse(2.1, 32), ellipse(2.2, 31)];
/// let opts = MatchOptions::default();
/// let prepared: Vec<_> = frames.iter().map(|s| prepare(s, &opts).unwrap()).collect();
/// // Frame 1 serves both pairs.
/// let first = match_prepared(&prepared[0], &prepared[1], &opts, Parallelism::Serial).unwrap();
/// let second = match_prepared(&prepared[1], &prepared[2], &opts, Parallelism::Serial).unwrap();
/// assert_eq!(first.pairs, match_shapes(&frames[0], &frames[1], &opts).unwrap().pairs);
/// assert_eq!(second.one_to_one_count(), 31);
/// ```
#[derive(Debug, Clone)]
pub struct PreparedShape {
    inner: Arc<Prepared>,
}

#[derive(Debug)]
pub(crate) struct Prepared {
    /// The caller's object, kept to prepare it again in the other orientation if a pair needs it.
    pub(crate) shape: Shape,
    /// Oriented counter-clockwise for the ordered-contour search.
    pub(crate) ordered: bool,
    /// Normalised coordinates, in `perm` order.
    pub(crate) pts: Vec<f64>,
    /// `perm[t]` is the caller's index of node `t` of `pts`.
    pub(crate) perm: Vec<usize>,
    /// The topology renumbered to `perm`.
    pub(crate) topology: Topology,
    /// The map from the callers' coordinates to `pts`'s normalised frame.
    pub(crate) to_normalized: Affine,
    spacing: OnceLock<f64>,
    neighbours: OnceLock<Vec<Vec<usize>>>,
    modes: Mutex<Vec<(ModesKey, Arc<ModalFeatures>)>>,
}

/// What a cached own-frame solve was made with.
#[derive(Debug, Clone, PartialEq)]
struct ModesKey {
    model: ModelOptions,
    skip: usize,
    modes: usize,
}

/// Stage 1: checks and normalises `shape` for every pair it takes part in. The object is oriented
/// counter-clockwise when `opts.ordered` says so, or (when that is `None`) when it is a closed
/// contour; a pair that treats it otherwise prepares it again.
///
/// # Errors
/// [`ModalError::TooFewNodes`] for fewer than 3 nodes, [`ModalError::CoincidentNodes`],
/// [`ModalError::Collinear`] or [`ModalError::ZeroExtent`].
pub fn prepare(shape: &Shape, opts: &MatchOptions) -> Result<PreparedShape, ModalError> {
    prepare_as(shape, opts, None)
}

/// [`prepare`] with its errors about object `side` of a pair, when given.
pub(crate) fn prepare_as(
    shape: &Shape,
    opts: &MatchOptions,
    side: Option<Side>,
) -> Result<PreparedShape, ModalError> {
    let too_many = (shape.len() > opts.max_nodes).then_some(ModalError::TooManyNodes {
        nodes: shape.len(),
        max: opts.max_nodes,
    });
    too_many
        .map_or(Ok(()), Err)
        .and_then(|()| validate(shape))
        .map_err(|e| match side {
            Some(side) => e.of(side),
            None => e,
        })?;
    let ordered = opts
        .ordered
        .unwrap_or(matches!(shape.topology(), Topology::ClosedContour));
    oriented(shape, ordered)
}

impl PreparedShape {
    /// The object as given.
    pub fn shape(&self) -> &Shape {
        &self.inner.shape
    }

    /// Whether the object was oriented for the ordered-contour search.
    pub fn ordered(&self) -> bool {
        self.inner.ordered
    }

    pub(crate) fn get(&self) -> &Prepared {
        &self.inner
    }

    /// This object oriented as a pair needs it: itself, or prepared again (already checked).
    fn for_pair(&self, ordered: bool) -> Result<Cow<'_, PreparedShape>, ModalError> {
        Ok(if self.inner.ordered == ordered {
            Cow::Borrowed(self)
        } else {
            Cow::Owned(oriented(&self.inner.shape, ordered)?)
        })
    }
}

impl Prepared {
    pub(crate) fn dim(&self) -> usize {
        self.shape.dim()
    }

    pub(crate) fn len(&self) -> usize {
        self.shape.len()
    }

    /// Mean nearest-neighbour distance in the normalised frame.
    pub(crate) fn spacing(&self) -> f64 {
        *self
            .spacing
            .get_or_init(|| nearest_neighbour_stats_of(&self.pts, self.dim()).0)
    }

    /// Neighbour lists of the point-set excess step: a mesh's 1-rings, else 6 nearest neighbours.
    pub(crate) fn neighbours(&self) -> &[Vec<usize>] {
        self.neighbours.get_or_init(|| match &self.topology {
            Topology::Mesh { triangles } => excess::mesh_rings(self.len(), triangles),
            _ => excess::knn(&self.pts, self.dim(), 6),
        })
    }

    /// Modes `skip .. skip + k` of the model of the normalised object, solved once per model,
    /// skip and count.
    pub(crate) fn own_modes(
        &self,
        model: &ModelOptions,
        skip: usize,
        k: usize,
    ) -> Result<Arc<ModalFeatures>, ModalError> {
        let key = ModesKey {
            model: model.clone(),
            skip,
            modes: k,
        };
        let cached = |c: &Vec<(ModesKey, Arc<ModalFeatures>)>| {
            c.iter().find(|(k, _)| *k == key).map(|(_, f)| f.clone())
        };
        if let Some(f) = cached(&self.modes.lock().expect("modes cache")) {
            return Ok(f);
        }
        // Solved outside the lock: two pairs asking at once both solve, with the same result.
        let f = Arc::new(modes_at(
            &self.pts,
            self.dim(),
            &self.topology,
            model,
            skip,
            k,
        )?);
        let mut cache = self.modes.lock().expect("modes cache");
        if cached(&cache).is_none() {
            cache.push((key, f.clone()));
        }
        Ok(f)
    }
}

/// The modes `skip .. skip + k` of the model of `pts` (fewer when the model has fewer).
pub(crate) fn modes_at(
    pts: &[f64],
    dim: usize,
    topology: &Topology,
    model: &ModelOptions,
    skip: usize,
    k: usize,
) -> Result<ModalFeatures, ModalError> {
    let shape = Shape::new(dim, pts.to_vec(), topology.clone())?;
    let opts = ModelOptions {
        n_modes: Some(skip + k),
        ..model.clone()
    };
    let basis = modal_basis(&shape, &opts)?;
    let avail = basis.modes.ncols();
    if avail < skip + 1 {
        return Err(ModalError::TooFewModes {
            requested: skip + 1,
            available: avail,
        });
    }
    ModalFeatures::from_basis(&basis, skip, k.min(avail - skip))
}

fn validate(s: &Shape) -> Result<(), ModalError> {
    let (n, d) = (s.len(), s.dim());
    if n < 3 {
        return Err(ModalError::TooFewNodes { nodes: n, min: 3 });
    }
    let (pts, _, _) = prealign::normalize(s.coords(), d)?;
    // After normalisation the RMS radius is 1, so absolute tolerances are meaningful.
    for i in 0..n {
        for j in i + 1..n {
            let dd: f64 = (0..d)
                .map(|c| (pts[i * d + c] - pts[j * d + c]).powi(2))
                .sum();
            if dd < 1e-18 {
                return Err(ModalError::CoincidentNodes {
                    first: i,
                    second: j,
                });
            }
        }
    }
    let (_, var) = prealign::principal_axes(&pts, d);
    if var[1] <= 1e-10 * var[0] {
        return Err(ModalError::Collinear);
    }
    Ok(())
}

/// Normalised coordinates, counter-clockwise when `ordered` (`perm` maps back to the caller's
/// numbering), and the topology renumbered to match.
fn oriented(s: &Shape, ordered: bool) -> Result<PreparedShape, ModalError> {
    let d = s.dim();
    let n = s.len();
    let (mut pts, centroid, scale) = prealign::normalize(s.coords(), d)?;
    let to_normalized = normalizing_map(d, centroid, scale);
    let mut perm: Vec<usize> = (0..n).collect();
    if ordered {
        let xy: Vec<f64> = pts.chunks_exact(d).flat_map(|p| [p[0], p[1]]).collect();
        if prealign::signed_area(&xy) < 0.0 {
            perm.reverse();
            pts = perm
                .iter()
                .flat_map(|&i| pts[i * d..(i + 1) * d].to_vec())
                .collect();
        }
    }
    let topology = match s.topology() {
        Topology::Mesh { triangles } => {
            // perm is the identity unless ordered; remap anyway for safety.
            let inv = inverse(&perm);
            Topology::Mesh {
                triangles: triangles
                    .iter()
                    .map(|t| [inv[t[0]], inv[t[1]], inv[t[2]]])
                    .collect(),
            }
        }
        other => other.clone(),
    };
    Ok(PreparedShape {
        inner: Arc::new(Prepared {
            shape: s.clone(),
            ordered,
            pts,
            perm,
            topology,
            to_normalized,
            spacing: OnceLock::new(),
            neighbours: OnceLock::new(),
            modes: Mutex::new(Vec::new()),
        }),
    })
}

/// `v` with `v[perm[t]] = t`.
pub(crate) fn inverse(perm: &[usize]) -> Vec<usize> {
    let mut v = vec![0; perm.len()];
    for (t, &o) in perm.iter().enumerate() {
        v[o] = t;
    }
    v
}

/// `x ↦ scale · (x − centroid)`, the map [`prealign::normalize`] applied.
pub(crate) fn normalizing_map(d: usize, centroid: [f64; 3], scale: f64) -> Affine {
    let mut map = Affine::identity(d);
    for (a, c) in centroid.iter().enumerate().take(d) {
        map.m[a][a] = scale;
        map.t[a] = -scale * c;
    }
    map
}

/// A pair of prepared objects with the choices that depend on both: what every later stage reads.
pub(crate) struct Pair<'p> {
    pub a: Cow<'p, PreparedShape>,
    pub b: Cow<'p, PreparedShape>,
    pub opts: &'p MatchOptions,
    pub dim: usize,
    /// Treated as ordered closed contours (both oriented counter-clockwise).
    pub ordered: bool,
    /// Quasi-rigid modes skipped.
    pub skip: usize,
    /// Modes per object in the features.
    pub k: usize,
    /// Band of the mode reordering: B is solved with `k + band` modes.
    pub band: usize,
    /// The model both objects are solved with (σ resolved when it is common).
    pub model: ModelOptions,
    /// The threshold (`∞` when there is none).
    pub threshold: f64,
    /// B's mean node spacing in its normalised frame: the unit of `refit_tolerance` (0 when no
    /// re-fit can be skipped by it).
    pub spacing_b: f64,
}

impl<'p> Pair<'p> {
    /// The map from A's normalised frame to B's that is the identity in the callers'
    /// coordinates: the start of [`super::Prealign::Sensor`].
    pub(crate) fn sensor_map(&self) -> Affine {
        self.b
            .get()
            .to_normalized
            .compose(&super::inverse_normalizing_map(&self.a.get().to_normalized))
    }

    /// Checks the options against the pair and works out the pair's choices.
    ///
    /// # Errors
    /// [`ModalError::DimensionMismatch`] for objects of different dimensions;
    /// [`ModalError::Option`] for a mode fraction outside (0, 1], a negative or NaN threshold, a
    /// negative or non-finite re-fit tolerance, a cost power ≤ 0, a position weight outside
    /// [0, 1]; [`Unsupported::OrderedMesh`] for `ordered` on meshes;
    /// [`Unsupported::OrderedSolverNeedsContours`] for the ordered solver on anything but two
    /// closed contours matched as ordered;
    /// [`ModalError::NoModeKept`] for a skip that leaves no mode.
    pub fn new(
        a: &'p PreparedShape,
        b: &'p PreparedShape,
        opts: &'p MatchOptions,
    ) -> Result<Self, ModalError> {
        let (sa, sb) = (a.shape(), b.shape());
        check_dims(sa, sb)?;
        let threshold = check_options(opts)?;
        let both_contours = matches!(sa.topology(), Topology::ClosedContour)
            && matches!(sb.topology(), Topology::ClosedContour);
        let ordered = opts.ordered.unwrap_or(both_contours);
        if ordered
            && (matches!(sa.topology(), Topology::Mesh { .. })
                || matches!(sb.topology(), Topology::Mesh { .. }))
        {
            return Err(Unsupported::OrderedMesh.into());
        }
        // The order-preserving solver reads the node numbering as each contour's cyclic order;
        // only ordered contours have one, oriented alike (both counter-clockwise).
        if opts.method == assign::Method::Ordered && !(both_contours && ordered) {
            return Err(Unsupported::OrderedSolverNeedsContours.into());
        }
        let d = sa.dim();
        let (n, m) = (sa.len(), sb.len());
        let skip = match (opts.skip_rigid, d) {
            (false, _) => 0,
            (true, 2) => 3,
            (true, _) => 6,
        };
        let total = d * n.min(m);
        // Modes each model has: a reduced Gaussian basis has fewer than its nodes' degrees of
        // freedom.
        let (dof_a, dof_b) = (
            opts.model.degrees_of_freedom(d, n),
            opts.model.degrees_of_freedom(d, m),
        );
        let avail = total.min(dof_a).min(dof_b);
        if skip >= avail {
            return Err(ModalError::NoModeKept {
                skipped: skip,
                available: avail,
            });
        }
        let k = ((opts.mode_fraction * total as f64).floor() as usize).clamp(1, avail - skip);
        let band = opts.band.min(dof_b - skip - k);
        let (a, b) = (a.for_pair(ordered)?, b.for_pair(ordered)?);
        let mut model = opts.model.clone();
        let common_sigma = opts.common_sigma && model.sigma.is_none();
        let refit_bound = opts.refits > 0 && opts.refit_tolerance > 0.0;
        // B's mean node spacing in its normalised frame: half of the common σ, and the unit of
        // `refit_tolerance`.
        let spacing_b = if common_sigma || refit_bound {
            b.get().spacing()
        } else {
            0.0
        };
        if common_sigma {
            model.sigma = Some(opts.model.kappa * 0.5 * (a.get().spacing() + spacing_b));
        }
        Ok(Self {
            a,
            b,
            opts,
            dim: d,
            ordered,
            skip,
            k,
            band,
            model,
            threshold,
            spacing_b,
        })
    }

    /// Whether the modes enter the cost (a position weight of 1 skips every modal solve).
    pub fn modal(&self) -> bool {
        self.opts.position_weight < 1.0
    }

    /// Whether the excess step runs (global search only).
    pub fn excess(&self) -> bool {
        self.opts.excess && self.opts.search == Search::Global
    }

    /// B's modes in its normalised frame (`k + band`), cached in B.
    pub fn modes_b(&self) -> Result<Arc<ModalFeatures>, ModalError> {
        self.b
            .get()
            .own_modes(&self.model, self.skip, self.k + self.band)
    }

    /// A's `k` modes at the coordinates `cur`; from A's cache when `cur` is A's own frame.
    pub fn modes_a(&self, cur: &[f64]) -> Result<Arc<ModalFeatures>, ModalError> {
        let a = self.a.get();
        if cur == a.pts.as_slice() {
            return a.own_modes(&self.model, self.skip, self.k);
        }
        modes_at(cur, self.dim, &a.topology, &self.model, self.skip, self.k).map(Arc::new)
    }
}

pub(crate) fn check_dims(a: &Shape, b: &Shape) -> Result<(), ModalError> {
    if a.dim() != b.dim() {
        return Err(ModalError::DimensionMismatch {
            a: a.dim(),
            b: b.dim(),
        });
    }
    Ok(())
}

/// Checks the options no single object can check; returns the threshold (`∞` for none).
fn check_options(opts: &MatchOptions) -> Result<f64, ModalError> {
    if !(opts.mode_fraction > 0.0 && opts.mode_fraction <= 1.0) {
        return Err(OptionError::new("modes", opts.mode_fraction, "a fraction in (0, 1]").into());
    }
    if let Some(t) = opts.threshold {
        crate::options::check_threshold(t)?;
    }
    let threshold = opts.threshold.unwrap_or(f64::INFINITY);
    if !(opts.refit_tolerance >= 0.0 && opts.refit_tolerance.is_finite()) {
        return Err(OptionError::new(
            "refit_tolerance",
            opts.refit_tolerance,
            "a finite number >= 0",
        )
        .into());
    }
    if !(opts.cost_power > 0.0 && opts.cost_power.is_finite()) {
        return Err(OptionError::new("cost_power", opts.cost_power, "a finite number > 0").into());
    }
    if !(0.0..=1.0).contains(&opts.position_weight) {
        return Err(OptionError::new(
            "position_weight",
            opts.position_weight,
            "a number in [0, 1]",
        )
        .into());
    }
    Ok(threshold)
}
