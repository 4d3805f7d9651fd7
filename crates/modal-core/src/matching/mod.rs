//! The modal matching pipeline: pre-alignment, modal features, mode alignment, affinity,
//! search, excess nodes and iterative affine re-fits (docs/method.md §5–7).

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use crate::align::{self, Affine};
use crate::excess;
use crate::features::{align_modes, AffinityMatrix, ModalFeatures};
use crate::gaussian::nearest_neighbour_stats_of;
use crate::search::{best_matches, global_matches, local_matches, ThresholdMode};
use crate::{modal_basis, ModalError, ModelOptions, Shape, Topology};

mod first_phase;

/// Which search produces the primary matches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Search {
    /// Mutual best matches under the threshold (the original modal matching, docs/method.md §6.1).
    Local,
    /// Optimal assignment saturating the smaller object (the paper's optimisation, docs/method.md
    /// §6.2).
    #[default]
    Global,
    /// Every node of the first object to its lowest-cost node of the second, under the
    /// threshold: many-to-one, no excess step. For independent samplings of one surface, where
    /// no one-to-one answer can be right for every node (README, "Surfaces").
    Best,
}

/// How the two objects are brought into a common frame before their modes are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Prealign {
    /// Centroid and RMS scale only (the paper's setting; enough for consecutive frames).
    Normalize,
    /// Centroid, scale, rotation candidates scored by chamfer after symmetric affine ICP (§10).
    #[default]
    Robust,
}

/// Parameters of [`match_shapes`]. The defaults are the measured recipe of docs/method.md §7.3.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOptions {
    /// Element, material (only ν matters, E and ρ do not change matches), σ rule, exact-rigid
    /// option. `n_modes` is ignored: the pipeline requests exactly the modes it needs.
    pub model: ModelOptions,
    /// Fraction of the `dim · min(n, m)` modes kept: `k = ⌊fraction · dim · min(n, m)⌋`.
    pub mode_fraction: f64,
    /// Skip the first 3 (2-D) or 6 (3-D) quasi-rigid modes.
    pub skip_rigid: bool,
    /// Band of the cross-object mode reordering (docs/method.md §5.4); 0 fixes signs only.
    pub band: usize,
    pub search: Search,
    /// Assignment algorithm of the global search and of the mode alignment.
    pub method: assign::Method,
    /// Reject pairs with normalised `Z` above this (in [0, 1]); `None` keeps everything.
    pub threshold: Option<f64>,
    pub threshold_mode: ThresholdMode,
    /// Match the nodes the one-to-one search leaves over (global search only).
    pub excess: bool,
    /// Treat both objects as ordered closed contours; `None`: when both shapes say so.
    pub ordered: Option<bool>,
    pub prealign: Prealign,
    /// How the robust pre-alignment searches the rotation (starts, ICP iterations).
    pub rotation_search: align::RotationSearch,
    /// Maximum modal affine re-fits; stops earlier when the pairs stop changing.
    pub refits: usize,
    /// No (further) re-fit once one affine map explains the pairs: every one-to-one pair lands
    /// within this fraction of B's mean node spacing of its partner under the fit. A re-fit then
    /// only moves A by a map its pairs already agree with. 0 re-fits up to `refits` times.
    pub refit_tolerance: f64,
    /// Weight `w` of aligned positions in the cost: `Z = (1 − w)·Z_modal + w·D`, both
    /// max-normalised (and each raised to [`MatchOptions::cost_power`]), `D` the squared distance
    /// of the aligned coordinates. 0 is pure modal
    /// matching; 1 skips the modal solves and matches aligned positions (a baseline).
    pub position_weight: f64,
    /// Exponent `p` of the costs the search adds up: the assignment minimises `Σ Z[i, j]^p`,
    /// with positions mixed in `(1 − w)·Z_modal^p + w·D^p`. 1 is the paper's squared modal
    /// distance. Below 1 the sum prefers many near-exact pairs to evenly spread errors, which
    /// independent samplings of one surface need: even with the true positions, an optimal
    /// assignment of squared distances puts only 25 % of the points within one spacing, of
    /// (squared distances)^0.25 42 % (bench_match.py surfaces). Each row's and column's order is
    /// kept, so local matches do not change; the affinity, the pair costs and the threshold are
    /// in powered units.
    pub cost_power: f64,
    /// Return the iteration whose pairs are best explained by one affine map (least-squares
    /// residual in B's frame) instead of the last one: a re-fit can lock onto a wrong pairing.
    pub keep_best_fit: bool,
    /// Use one Gaussian width for both objects, `kappa ×` the mean of their mean nearest-neighbour
    /// distances, instead of one per object (for independently sampled point sets).
    pub common_sigma: bool,
}

impl Default for MatchOptions {
    fn default() -> Self {
        let model = ModelOptions {
            material: crate::Material {
                young: 1.0,
                poisson: 0.49,
                density: 1.0,
            },
            // σ = 0.8 × the mean nearest-neighbour distance: measured on 270 ground-truth contour
            // pairs (bench_match.py, seeds 1–3), 0.8 beat the earlier 1.0 at moderate and severe
            // warps (0.986 vs 0.976 and 0.939 vs 0.926); 0.6, 0.7, 0.9 and ≥ 1.15 did not.
            kappa: 0.8,
            ..ModelOptions::default()
        };
        Self {
            model,
            mode_fraction: 0.25,
            skip_rigid: false,
            band: 3,
            search: Search::Global,
            method: assign::Method::JonkerVolgenant,
            threshold: None,
            threshold_mode: ThresholdMode::AfterAssignment,
            excess: true,
            ordered: None,
            prealign: Prealign::Robust,
            rotation_search: align::RotationSearch::default(),
            refits: 2,
            // Measured on 630 ground-truth contour pairs (bench_match.py cases, seeds 1–7, mild /
            // moderate / severe) and checked on 630 more (seeds 8–14): re-fits per pair 1.11 /
            // 1.08 / 1.34 → 0.57 / 0.65 / 0.95 (held out: 1.17 / 1.24 / 1.39 → 0.55 / 0.73 /
            // 1.05), accuracy 0.9993 / 0.9967 / 0.9755 → 0.9996 / 0.9965 / 0.9751 (held out:
            // 0.9994 / 0.9952 / 0.9782 → 0.9994 / 0.9955 / 0.9784), against the earlier test
            // (RMS of all pairs below 0.3 spacing, none beyond 0.6). 0.8 skipped nearly every
            // re-fit but lost 0.0015–0.003 at severe. 0 restores every re-fit.
            refit_tolerance: 0.6,
            position_weight: 0.0,
            cost_power: 1.0,
            common_sigma: false,
            keep_best_fit: true,
        }
    }
}

impl MatchOptions {
    /// Measured best for independently sampled 3-D point sets (brightness surfaces): a wider,
    /// common Gaussian (σ = 3 × mean nearest-neighbour distance of both objects), because per-node
    /// modal features of different samplings only agree on smooth modes; no affine re-fits (the
    /// surface's pairs are too noisy to improve the fit); costs raised to the power 1/8 (an
    /// assignment of squared distances cannot put more than about a quarter of two independent
    /// samplings within one spacing, see [`MatchOptions::cost_power`]); and aligned positions
    /// weighted 0.7 beside the modal distance. On 90 cases per severity of bench_match.py this
    /// scores 0.393 / 0.394 / 0.391 (mild / moderate / severe) — the same as aligned positions
    /// alone and above coherent point drift (0.368 / 0.369 / 0.366); modal distance alone reaches
    /// 0.29: after the affine pre-alignment these warps leave little that positions miss. See the
    /// README, "Surfaces".
    pub fn for_surfaces() -> Self {
        let mut o = Self {
            refits: 0,
            common_sigma: true,
            position_weight: 0.7,
            cost_power: 0.125,
            ..Self::default()
        };
        o.model.kappa = 3.0;
        o
    }

    /// The measured best setting for a kind of input: [`MatchOptions::for_surfaces`] for
    /// unordered 3-D point sets and meshes (`dim == 3 && !ordered`), the default recipe for
    /// contours and 2-D point sets. What `pymodal.match` and the `pedomatch` CLI start from.
    ///
    /// ```
    /// use modal_core::MatchOptions;
    /// assert_eq!(MatchOptions::for_input(3, false), MatchOptions::for_surfaces());
    /// assert_eq!(MatchOptions::for_input(2, true), MatchOptions::default());
    /// ```
    pub fn for_input(dim: usize, ordered: bool) -> Self {
        if dim == 3 && !ordered {
            Self::for_surfaces()
        } else {
            Self::default()
        }
    }

    /// The paper's literal setting: no rotation pre-alignment, no re-fits.
    pub fn paper() -> Self {
        Self {
            prealign: Prealign::Normalize,
            refits: 0,
            ..Self::default()
        }
    }
}

/// One correspondence: node `a` of the first object, node `b` of the second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchPair {
    pub a: usize,
    pub b: usize,
    /// The search's cost `Z[a, b]`: the max-normalised modal distance, with positions mixed in
    /// and raised to the power as [`MatchOptions::position_weight`] and
    /// [`MatchOptions::cost_power`] say.
    pub cost: f64,
    /// Found by the excess-node step (one-to-many) rather than by the one-to-one search.
    pub excess: bool,
}

/// Outcome of [`match_shapes`].
#[derive(Debug, Clone)]
pub struct MatchResult {
    /// The search's pairs sorted by `a` (one-to-one except with [`Search::Best`]), followed by
    /// excess pairs sorted by `b` (or by `a` when the first object is the larger).
    pub pairs: Vec<MatchPair>,
    /// The final affinity matrix the search used (entries in [0, 1]), rows = nodes of the first
    /// object, original order.
    pub affinity: AffinityMatrix,
    /// Mutual-best (local) matches on the final affinity, under the threshold, whatever `search`.
    pub local_pairs: Vec<(usize, usize)>,
    /// Nodes of the first / second object in no pair.
    pub unmatched_a: Vec<usize>,
    pub unmatched_b: Vec<usize>,
    /// Modes per object used in the features.
    pub n_modes: usize,
    /// Modal affine re-fits actually performed.
    pub refits: usize,
    /// Modal solves of the first object (the second is solved once).
    pub solves: usize,
    /// The affine map `x ↦ M x + t` from the first object's coordinates to the second's that
    /// produced the aligned coordinates of the kept iteration (pre-alignment, then re-fits), in
    /// the callers' units: `transform.apply(a.coords())` equals [`Self::aligned_a`] up to
    /// rounding.
    pub transform: Affine,
    /// The first object's nodes in the second's frame as the search used them (row-major,
    /// `n × dim`, the callers' node order and units).
    pub aligned_a: Vec<f64>,
}

impl MatchResult {
    /// Number of local (mutual-best) matches.
    pub fn local_count(&self) -> usize {
        self.local_pairs.len()
    }
    /// Number of matches from the primary search (the paper's "optimisation" column): one-to-one
    /// except with [`Search::Best`], whose pairs are many-to-one.
    pub fn one_to_one_count(&self) -> usize {
        self.pairs.iter().filter(|p| !p.excess).count()
    }
    /// Number of matches added by the excess-node step.
    pub fn excess_count(&self) -> usize {
        self.pairs.iter().filter(|p| p.excess).count()
    }
}

fn validate(s: &Shape, name: &str) -> Result<(), ModalError> {
    let (n, d) = (s.len(), s.dim());
    if n < 3 {
        return Err(ModalError::InvalidShape(format!(
            "{name} has {n} nodes; at least 3 are needed"
        )));
    }
    let (pts, _, _) = align::normalize(s.coords(), d)
        .map_err(|e| ModalError::InvalidShape(format!("{name}: {}", e_msg(&e))))?;
    // After normalisation the RMS radius is 1, so absolute tolerances are meaningful.
    for i in 0..n {
        for j in i + 1..n {
            let dd: f64 = (0..d)
                .map(|c| (pts[i * d + c] - pts[j * d + c]).powi(2))
                .sum();
            if dd < 1e-18 {
                return Err(ModalError::InvalidShape(format!(
                    "{name}: nodes {i} and {j} coincide"
                )));
            }
        }
    }
    let (_, var) = align::principal_axes(&pts, d);
    if var[1] <= 1e-10 * var[0] {
        return Err(ModalError::InvalidShape(format!(
            "{name}: all nodes are collinear"
        )));
    }
    Ok(())
}

fn e_msg(e: &ModalError) -> String {
    match e {
        ModalError::InvalidShape(s)
        | ModalError::InvalidParameter(s)
        | ModalError::Numerical(s) => s.clone(),
        other => other.to_string(),
    }
}

/// One object prepared for matching: normalised coordinates, counter-clockwise when ordered
/// (`perm` maps back to the caller's numbering), and its topology renumbered to match.
struct Side {
    pts: Vec<f64>,
    perm: Vec<usize>,
    topology: Topology,
    /// The map from the callers' coordinates to `pts`'s normalised frame.
    to_normalized: Affine,
}

fn prepare(s: &Shape, ordered: bool) -> Result<Side, ModalError> {
    let d = s.dim();
    let n = s.len();
    let (mut pts, centroid, scale) = align::normalize(s.coords(), d)?;
    let to_normalized = normalizing_map(d, centroid, scale);
    let mut perm: Vec<usize> = (0..n).collect();
    if ordered {
        let xy: Vec<f64> = pts.chunks_exact(d).flat_map(|p| [p[0], p[1]]).collect();
        if align::signed_area(&xy) < 0.0 {
            perm.reverse();
            pts = perm
                .iter()
                .flat_map(|&i| pts[i * d..(i + 1) * d].to_vec())
                .collect();
        }
    }
    let topology = match s.topology() {
        Topology::ClosedContour if ordered => Topology::ClosedContour,
        Topology::Mesh { triangles } => {
            // perm is the identity unless ordered; remap anyway for safety.
            let mut inv = vec![0; n];
            for (t, &o) in perm.iter().enumerate() {
                inv[o] = t;
            }
            Topology::Mesh {
                triangles: triangles
                    .iter()
                    .map(|t| [inv[t[0]], inv[t[1]], inv[t[2]]])
                    .collect(),
            }
        }
        other => other.clone(),
    };
    Ok(Side {
        pts,
        perm,
        topology,
        to_normalized,
    })
}

fn features_of(
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
        return Err(ModalError::Numerical(format!(
            "the model returned only {avail} modes"
        )));
    }
    ModalFeatures::from_basis(&basis, skip, k.min(avail - skip))
}

/// Matches the nodes of `a` to the nodes of `b` by modal matching.
///
/// # Errors
/// [`ModalError::InvalidShape`] for objects of different dimensions, fewer than 3 nodes,
/// coincident or collinear nodes; [`ModalError::InvalidParameter`] for a mode fraction outside
/// (0, 1], a negative or NaN threshold, or `ordered` on shapes that cannot be contours;
/// model and assignment failures are passed through.
pub fn match_shapes(a: &Shape, b: &Shape, opts: &MatchOptions) -> Result<MatchResult, ModalError> {
    if a.dim() != b.dim() {
        return Err(ModalError::InvalidShape(format!(
            "the objects have different dimensions ({} and {})",
            a.dim(),
            b.dim()
        )));
    }
    validate(a, "first object")?;
    validate(b, "second object")?;
    if !(opts.mode_fraction > 0.0 && opts.mode_fraction <= 1.0) {
        return Err(ModalError::InvalidParameter(format!(
            "mode fraction must be in (0, 1], got {}",
            opts.mode_fraction
        )));
    }
    let threshold = opts.threshold.unwrap_or(f64::INFINITY);
    if threshold.is_nan() || threshold < 0.0 {
        return Err(ModalError::InvalidParameter(format!(
            "threshold must be ≥ 0, got {threshold}"
        )));
    }
    if !(opts.refit_tolerance >= 0.0 && opts.refit_tolerance.is_finite()) {
        return Err(ModalError::InvalidParameter(format!(
            "refit tolerance must be finite and ≥ 0, got {}",
            opts.refit_tolerance
        )));
    }
    if !(opts.cost_power > 0.0 && opts.cost_power.is_finite()) {
        return Err(ModalError::InvalidParameter(format!(
            "cost power must be finite and > 0, got {}",
            opts.cost_power
        )));
    }
    if !(0.0..=1.0).contains(&opts.position_weight) {
        return Err(ModalError::InvalidParameter(format!(
            "position weight must be in [0, 1], got {}",
            opts.position_weight
        )));
    }
    let both_contours = matches!(a.topology(), Topology::ClosedContour)
        && matches!(b.topology(), Topology::ClosedContour);
    let ordered = opts.ordered.unwrap_or(both_contours);
    if ordered
        && (matches!(a.topology(), Topology::Mesh { .. })
            || matches!(b.topology(), Topology::Mesh { .. }))
    {
        return Err(ModalError::InvalidParameter(
            "meshes cannot be treated as ordered contours".into(),
        ));
    }
    let d = a.dim();
    let (n, m) = (a.len(), b.len());
    let skip = if opts.skip_rigid {
        if d == 2 {
            3
        } else {
            6
        }
    } else {
        0
    };
    let total = d * n.min(m);
    // Modes each model has: a reduced Gaussian basis has fewer than its nodes' degrees of freedom.
    let (dof_a, dof_b) = (
        opts.model.degrees_of_freedom(d, n),
        opts.model.degrees_of_freedom(d, m),
    );
    let avail = total.min(dof_a).min(dof_b);
    if skip >= avail {
        return Err(ModalError::InvalidParameter(format!(
            "skipping {skip} rigid modes leaves none of the {avail} available"
        )));
    }
    let k = ((opts.mode_fraction * total as f64).floor() as usize).clamp(1, avail - skip);
    let band = opts.band.min(dof_b - skip - k);

    let sa = prepare(a, ordered)?;
    let sb = prepare(b, ordered)?;
    let mut model = opts.model.clone();
    let common_sigma = opts.common_sigma && model.sigma.is_none();
    let refit_bound = opts.refits > 0 && opts.refit_tolerance > 0.0;
    // B's mean node spacing in its normalised frame: half of the common σ, and the unit of
    // `refit_tolerance`. One O(m²) scan serves both.
    let spacing_b = if common_sigma || refit_bound {
        nearest_neighbour_stats_of(&sb.pts, d).0
    } else {
        0.0
    };
    if common_sigma {
        model.sigma =
            Some(opts.model.kappa * 0.5 * (nearest_neighbour_stats_of(&sa.pts, d).0 + spacing_b));
    }
    let modal = opts.position_weight < 1.0;
    // A's coordinates after the rotation search's map (none with `Prealign::Normalize`), and
    // the map from A's normalised frame to them.
    let in_b_frame = |t: Option<Affine>| match t {
        Some(t) => into_b_frame(t.apply(&sa.pts), d, ordered)
            .map(|(cur, renormalize)| (cur, renormalize.compose(&t))),
        None => Ok((sa.pts.clone(), Affine::identity(d))),
    };
    let robust = opts.prealign == Prealign::Robust;
    let solve_b = || {
        modal
            .then(|| features_of(&sb.pts, d, &sb.topology, &model, skip, k + band))
            .transpose()
    };
    let solve_a = |cur: &[f64]| {
        modal
            .then(|| features_of(cur, d, &sa.topology, &model, skip, k))
            .transpose()
    };
    let (cur, fb, first) = if rayon::current_thread_index().is_some() {
        // On the pool (a whole sequence matches its pairs there; its other worker is busy or
        // about to be): the pre-alignment first, on both cores, then B's modes (solved once)
        // beside A's first solve. rayon::join, not a plain thread: a plain thread joined from
        // inside a rayon worker can deadlock it.
        let cur =
            in_b_frame(robust.then(|| {
                align::robust_prealign(&sa.pts, &sb.pts, d, &opts.rotation_search, ordered)
            }))?;
        let (fb, first) = rayon::join(solve_b, || solve_a(&cur.0));
        (cur, fb, first)
    } else {
        // From outside the pool: this thread does the whole phase in an order that never waits
        // for the pool, and a helper job takes rotation starts and B's solve when it wakes
        // (first_phase.rs).
        let phase = first_phase::FirstPhase::start(
            d,
            robust.then(|| first_phase::Screening {
                a: sa.pts.clone(),
                b: sb.pts.clone(),
                search: opts.rotation_search,
                keep_orientation: ordered,
            }),
            modal.then(|| first_phase::SolveB {
                pts: sb.pts.clone(),
                topology: sb.topology.clone(),
                model: model.clone(),
                skip,
                modes: k + band,
            }),
        );
        let cur = in_b_frame(phase.prealign())?;
        let first = solve_a(&cur.0)?;
        (cur, phase.b_modes(), Ok(first))
    };
    // `to_cur` maps A's normalised frame to `cur`.
    let (fb, mut first_fa, (mut cur, mut to_cur)) = (fb?, first?, cur);
    let band = fb.as_ref().map_or(0, |f| f.n_modes.saturating_sub(k));

    let nbr = if !ordered && opts.excess && opts.search == Search::Global {
        let nb = |s: &Side| match &s.topology {
            Topology::Mesh { triangles } => excess::mesh_rings(s.pts.len() / d, triangles),
            _ => excess::knn(&s.pts, d, 6),
        };
        Some((nb(&sa), nb(&sb)))
    } else {
        None
    };

    let mut prev: Option<Vec<MatchPair>> = None;
    let mut refits = 0;
    let mut solves = 0;
    let mut best: Option<Iteration> = None;
    loop {
        let z = match &fb {
            Some(fb) => {
                let fa = match first_fa.take() {
                    Some(fa) => fa,
                    None => features_of(&cur, d, &sa.topology, &model, skip, k)?,
                };
                solves += 1;
                let nn: Vec<usize> = align::nearest(&cur, &sb.pts, d)
                    .into_iter()
                    .map(|x| x.0)
                    .collect();
                let al = align_modes(&fa, fb, &nn, band, opts.method)?;
                let fb_al = fb.permuted(&al.order, &al.signs);
                AffinityMatrix::from_features(&fa, &fb_al)?.normalized()
            }
            None => position_costs(&cur, &sb.pts, d)?,
        }
        .powered(opts.cost_power);
        let z = if modal && opts.position_weight > 0.0 {
            let w = opts.position_weight;
            let p = position_costs(&cur, &sb.pts, d)?.powered(opts.cost_power);
            let mixed = z
                .as_slice()
                .iter()
                .zip(p.as_slice())
                .map(|(x, y)| (1.0 - w) * x + w * y)
                .collect();
            AffinityMatrix::new(z.rows(), z.cols(), mixed)?.normalized()
        } else {
            z
        };
        let one = match opts.search {
            Search::Global => global_matches(&z, opts.method, threshold, opts.threshold_mode)?,
            Search::Local => local_matches(&z, threshold),
            Search::Best => best_matches(&z, threshold),
        };
        let mut pairs: Vec<MatchPair> = one
            .iter()
            .map(|&(i, j)| MatchPair {
                a: i,
                b: j,
                cost: z.get(i, j),
                excess: false,
            })
            .collect();
        if opts.excess && opts.search == Search::Global {
            let ex = if ordered {
                if n <= m {
                    excess::contour_excess(&z, &one, threshold)
                } else {
                    let sw: Vec<_> = one.iter().map(|&(i, j)| (j, i)).collect();
                    excess::contour_excess(&z.transposed(), &sw, threshold)
                        .into_iter()
                        .map(|(j, i)| (i, j))
                        .collect()
                }
            } else {
                let (na, nb) = nbr.as_ref().expect("neighbours built for unordered excess");
                if n <= m {
                    excess::point_set_excess(&z, &one, threshold, d, &cur, &sb.pts, na, nb)
                } else {
                    let sw: Vec<_> = one.iter().map(|&(i, j)| (j, i)).collect();
                    excess::point_set_excess(
                        &z.transposed(),
                        &sw,
                        threshold,
                        d,
                        &sb.pts,
                        &cur,
                        nb,
                        na,
                    )
                    .into_iter()
                    .map(|(j, i)| (i, j))
                    .collect()
                }
            };
            pairs.extend(ex.into_iter().map(|(i, j)| MatchPair {
                a: i,
                b: j,
                cost: z.get(i, j),
                excess: true,
            }));
        }
        let idx: Vec<(usize, usize)> = pairs.iter().map(|p| (p.a, p.b)).collect();
        let fit = align::fit_affine(&cur, &sb.pts, d, &idx);
        // How well one affine map explains the pairs, measured in B's fixed frame, so the
        // iterations are comparable: wrong pairs do not fit a smooth map. The mean squared
        // residual of all pairs ranks the iterations; the largest of the one-to-one pairs decides
        // whether another re-fit is worth a solve. Excess pairs are left out of that: they are
        // many-to-one by construction, so their offsets along the contour measure the sampling,
        // not the fit.
        let (resid, worst) = fit.as_ref().map_or((f64::INFINITY, f64::INFINITY), |t| {
            let moved = t.apply(&cur);
            let (sum, max) = pairs.iter().fold((0.0, 0.0f64), |(sum, max), p| {
                let r2 = (0..d)
                    .map(|c| (moved[p.a * d + c] - sb.pts[p.b * d + c]).powi(2))
                    .sum::<f64>();
                (sum + r2, if p.excess { max } else { max.max(r2) })
            });
            (sum / pairs.len().max(1) as f64, max)
        });
        let stable = prev.as_ref().is_some_and(|p| same_pairs(p, &pairs));
        let better = !opts.keep_best_fit || best.as_ref().is_none_or(|b| resid < b.resid);
        if better {
            best = Some(Iteration {
                z,
                pairs: pairs.clone(),
                resid,
                aligned: cur.clone(),
                to_aligned: to_cur,
            });
        }
        let explained = worst.sqrt() < opts.refit_tolerance * spacing_b;
        if stable || explained || refits >= opts.refits {
            break;
        }
        let Some(t) = fit else { break };
        // A fit this close to the identity cannot change the pairs: skip the solve.
        let moved = (0..d).any(|r| {
            t.t[r].abs() > 1e-4
                || (0..d).any(|c| (t.m[r][c] - if r == c { 1.0 } else { 0.0 }).abs() > 1e-4)
        });
        if !moved || (ordered && t.det() <= 0.0) {
            break;
        }
        let Ok((next, renormalize)) = into_b_frame(t.apply(&cur), d, ordered) else {
            break;
        };
        cur = next;
        to_cur = renormalize.compose(&t).compose(&to_cur);
        prev = Some(pairs);
        refits += 1;
    }
    let Iteration {
        z,
        pairs,
        aligned,
        to_aligned,
        ..
    } = best.expect("at least one iteration ran");

    // Back to the callers' node numbering.
    let inv = |perm: &[usize]| {
        let mut v = vec![0; perm.len()];
        for (t, &o) in perm.iter().enumerate() {
            v[o] = t;
        }
        v
    };
    let (ia, ib) = (inv(&sa.perm), inv(&sb.perm));
    let affinity = z.reindexed(&ia, &ib);
    let mut out: Vec<MatchPair> = pairs
        .iter()
        .map(|p| MatchPair {
            a: sa.perm[p.a],
            b: sb.perm[p.b],
            ..*p
        })
        .collect();
    out.sort_by_key(|p| (p.excess, if n <= m { (p.b, p.a) } else { (p.a, p.b) }));
    let first_excess = out.iter().position(|p| p.excess).unwrap_or(out.len());
    out[..first_excess].sort_by_key(|p| p.a);
    let local_pairs = {
        let mut l = local_matches(&affinity, threshold);
        l.sort();
        l
    };
    let mut used_a = vec![false; n];
    let mut used_b = vec![false; m];
    for p in &out {
        used_a[p.a] = true;
        used_b[p.b] = true;
    }
    // From B's normalised frame back to B's coordinates, in the callers' node order.
    let from_b_frame = inverse_normalizing_map(&sb.to_normalized);
    let mut aligned_a = vec![0.0; n * d];
    for (t, p) in from_b_frame.apply(&aligned).chunks_exact(d).enumerate() {
        aligned_a[sa.perm[t] * d..(sa.perm[t] + 1) * d].copy_from_slice(p);
    }
    Ok(MatchResult {
        pairs: out,
        affinity,
        local_pairs,
        unmatched_a: (0..n).filter(|&i| !used_a[i]).collect(),
        unmatched_b: (0..m).filter(|&j| !used_b[j]).collect(),
        n_modes: k,
        refits,
        solves,
        transform: from_b_frame.compose(&to_aligned).compose(&sa.to_normalized),
        aligned_a,
    })
}

/// One pass of the search loop, kept when it explains its pairs best.
struct Iteration {
    z: AffinityMatrix,
    pairs: Vec<MatchPair>,
    /// Mean squared residual of the pairs under the affine map fitted to them.
    resid: f64,
    /// A's coordinates the pass matched, in B's normalised frame.
    aligned: Vec<f64>,
    /// The map from A's normalised frame to `aligned`.
    to_aligned: Affine,
}

/// `x ↦ scale · (x − centroid)`, the map [`align::normalize`] applied.
fn normalizing_map(d: usize, centroid: [f64; 3], scale: f64) -> Affine {
    let mut map = Affine::identity(d);
    for a in 0..d {
        map.m[a][a] = scale;
        map.t[a] = -scale * centroid[a];
    }
    map
}

/// The inverse of a [`normalizing_map`]: `y ↦ y / scale + centroid`.
fn inverse_normalizing_map(map: &Affine) -> Affine {
    let mut inv = Affine::identity(map.dim);
    for a in 0..map.dim {
        inv.m[a][a] = 1.0 / map.m[a][a];
        inv.t[a] = -map.t[a] / map.m[a][a];
    }
    inv
}

/// A's coordinates after an affine map into B's normalised frame. A closed outline resampled by
/// arc length has a centroid and RMS radius that hardly depend on where its points fall, so a
/// contour is normalised again, which removes the small bias the fit leaves. A random sampling's
/// centroid wanders by about radius / √n, more than the fit's error, so a point set keeps the
/// map's frame. Measured (bench_match.py): re-normalising point sets cut the nearest-neighbour
/// hits of aligned surfaces from 0.49 to 0.39; not re-normalising contours cost the
/// positions-only baseline 0.946 → 0.940 on 210 severe cases (the modal recipe: no change).
/// An affine map that collapses A is an error either way.
/// Also returns the map the re-normalisation applied (the identity for a point set).
fn into_b_frame(
    moved: Vec<f64>,
    d: usize,
    ordered: bool,
) -> Result<(Vec<f64>, Affine), ModalError> {
    let (normalised, centroid, scale) = align::normalize(&moved, d)?;
    Ok(if ordered {
        (normalised, normalizing_map(d, centroid, scale))
    } else {
        (moved, Affine::identity(d))
    })
}

/// Max-normalised squared distances between aligned coordinates.
fn position_costs(a: &[f64], b: &[f64], d: usize) -> Result<AffinityMatrix, ModalError> {
    let data = a
        .chunks_exact(d)
        .flat_map(|p| {
            b.chunks_exact(d)
                .map(move |q| (0..d).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>())
        })
        .collect();
    Ok(AffinityMatrix::new(a.len() / d, b.len() / d, data)?.normalized())
}

fn same_pairs(x: &[MatchPair], y: &[MatchPair]) -> bool {
    x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.a == q.a && p.b == q.b)
}

/// `a` after the pre-alignment, in `b`'s normalised frame (centroid 0, RMS radius 1), and that
/// normalised `b`: the coordinates [`match_shapes`] starts from. A contour is normalised again
/// after the affine map, a point set keeps the map's frame (see `into_b_frame`). Exposed for
/// diagnostics and for position-only baselines.
pub fn prealign_normalized(
    a: &Shape,
    b: &Shape,
    opts: &MatchOptions,
) -> Result<(Vec<f64>, Vec<f64>), ModalError> {
    if a.dim() != b.dim() {
        return Err(ModalError::InvalidShape(
            "the objects have different dimensions".into(),
        ));
    }
    let ordered = opts.ordered.unwrap_or(
        matches!(a.topology(), Topology::ClosedContour)
            && matches!(b.topology(), Topology::ClosedContour),
    );
    let d = a.dim();
    let (pa, _, _) = align::normalize(a.coords(), d)?;
    let (pb, _, _) = align::normalize(b.coords(), d)?;
    let t = match opts.prealign {
        Prealign::Normalize => Affine::identity(d),
        Prealign::Robust => align::robust_prealign(&pa, &pb, d, &opts.rotation_search, ordered),
    };
    Ok((into_b_frame(t.apply(&pa), d, ordered)?.0, pb))
}
