//! The parameters of the pipeline and their measured defaults (docs/method.md §7.3).

use super::prealign::{Prealign, RotationSearch};
use super::refine::Refine;
use super::search::{Search, ThresholdMode};
use crate::model::{Material, ModelOptions};

/// The most nodes an object may have by default: a 2-D model of 4096 nodes holds dense
/// matrices of 8192² values (512 MiB each) and takes minutes to solve, while the objects of a
/// recording hold hundreds (a contour at one node per sensel, a surface of 120 nodes).
pub const MAX_NODES: usize = 4096;

/// Parameters of [`match_shapes`](super::match_shapes). The defaults are the measured recipe of docs/method.md §7.3.
#[derive(Debug, Clone, PartialEq)]
pub struct MatchOptions {
    /// Element, material (only ν matters, E and ρ do not change matches), σ rule, exact-rigid
    /// option. `n_modes` is ignored: the pipeline requests exactly the modes it needs.
    pub model: ModelOptions,
    /// Fraction of the `dim · min(n, m)` modes kept: `k = ⌊fraction · dim · min(n, m)⌋` (the
    /// option `modes`: Python keyword and CLI `--modes`).
    pub mode_fraction: f64,
    /// Skip the first 3 (2-D) or 6 (3-D) quasi-rigid modes.
    pub skip_rigid: bool,
    /// Band of the cross-object mode reordering (docs/method.md §5.4); 0 fixes signs only.
    pub band: usize,
    /// How nodes are paired: local (mutual best), global (optimal assignment) or best.
    pub search: Search,
    /// Assignment algorithm of the global search and of the mode alignment.
    pub method: assign::Method,
    /// Reject pairs with normalised `Z` above this (in [0, 1]); `None` keeps everything.
    pub threshold: Option<f64>,
    /// Whether the threshold applies to the pairs as found or keeps the best share of them.
    pub threshold_mode: ThresholdMode,
    /// Match the nodes the one-to-one search leaves over (global search only).
    pub excess: bool,
    /// Treat both objects as ordered closed contours; `None`: when both shapes say so.
    pub ordered: Option<bool>,
    /// How the first object is brought into the second's frame before the modes are compared.
    pub prealign: Prealign,
    /// How the robust pre-alignment searches the rotation (starts, ICP iterations).
    pub rotation_search: RotationSearch,
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
    /// What follows the affine re-fits: nothing more ([`Refine::Affine`], the default), the
    /// modal non-rigid warp of docs/method.md §7.4 ([`Refine::Modal`]), the coherent drift of
    /// §7.5 ([`Refine::Coherent`]) or, for two closed outlines, the drift only for outlines the
    /// rotation search's fit leaves apart ([`Refine::Auto`], [`MatchOptions::for_outlines`]).
    pub refine: Refine,
    /// Most nodes of one object ([`MAX_NODES`] by default): more is refused before a model is
    /// built, as its dense matrices grow with the square of the nodes.
    pub max_nodes: usize,
    /// Modes of the warp's displacement field (the rigid ones included), [`Refine::Modal`] only.
    pub deform_modes: usize,
    /// Weight of the modes' strain energy against the fit of the warp, [`Refine::Modal`] only:
    /// larger values keep the warp closer to the affine alignment.
    pub deform_stiffness: f64,
}

impl Default for MatchOptions {
    fn default() -> Self {
        let model = ModelOptions {
            material: Material {
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
            rotation_search: RotationSearch::default(),
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
            refine: Refine::Affine,
            // Measured on strongly bent contours (bend 0.4, 12 pairs, tests/match_nonrigid.rs
            // seeds): 12 modes and stiffness 100 raised the accuracy from 0.850 to 0.918; 20 or
            // 40 modes, or stiffness 10 or 1000, gained less or lost.
            deform_modes: 12,
            deform_stiffness: 100.0,
            max_nodes: MAX_NODES,
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
    /// 0.29: after the affine pre-alignment these warps leave little that positions miss. See
    /// BENCHMARKS.md, "Surfaces". A Gaussian on every second node only (`center_stride = 2`): with σ
    /// three spacings wide the reduced basis spans the same smooth modes, and on those 90 cases
    /// per severity it scores 0.393 / 0.393 / 0.391 with the solves' order halved (a surface pair
    /// about 1.6× faster). Modes: an eighth of `dim · min(n, m)`, which with a Gaussian on every
    /// second node is a quarter of the model's own modes, the share contours use; the quarter of
    /// `dim · min(n, m)` used before asked for half of the reduced model's modes, and on 30 held-out
    /// cases per severity (mild / moderate / severe) both scored 0.387 / 0.382–0.384 /
    /// 0.372–0.373 one-to-one and 0.500 / 0.493 / 0.473 many-to-one, the solves and the costs
    /// with half the modes taking less time (BENCHMARKS.md, "Speed against CPD").
    pub fn for_surfaces() -> Self {
        let mut o = Self {
            mode_fraction: 0.125,
            refits: 0,
            common_sigma: true,
            position_weight: 0.7,
            cost_power: 0.125,
            ..Self::default()
        };
        o.model.kappa = 3.0;
        o.model.center_stride = 2;
        o
    }

    /// Measured best for two closed planar outlines (contours): the default recipe without the
    /// modal affine re-fits and with one Gaussian width for both outlines.
    ///
    /// Its pre-alignment, the rotation search, ends in the point-to-line fit of the outlines
    /// (docs/method.md §7.1), which leaves the re-fits nothing to add: on 1620 pairs per
    /// severity from bench_match.py's held-out generator (seeds 1001-1018), no re-fit scored
    /// 0.9998 / 0.9984 / 0.9752 (mild / moderate / severe) against 0.9998 / 0.9982 / 0.9728
    /// with up to 2, and a pair takes less time (BENCHMARKS.md). Any other pre-alignment needs
    /// the re-fits to align A: [`MatchParams::to_match_options`](crate::MatchParams) keeps the
    /// default's for it, and a recording's frames, which are not fitted as outlines, start from
    /// [`MatchOptions::default`].
    ///
    /// One width ([`MatchOptions::common_sigma`]): two samplings of one curve at different
    /// densities otherwise get kernels of different widths along it, and their modes differ in
    /// shape. On 810 pairs per severity of the held-out generator (seeds 1001-1003 and
    /// 1010-1015) the worst mild pair rose from 0.939 to 1.000 and the moderate mean from
    /// 0.9984 to 0.9990, and the severe mean held (0.9756 and 0.9755); BENCHMARKS.md has the
    /// sets checked afterwards.
    ///
    /// What follows ([`MatchOptions::refine`]): [`Refine::Auto`], the coherent drift from the
    /// centroid-and-scale start for two outlines that the rotation search's outline fit leaves
    /// apart (two specimens of a shape, whose proportions differ), nothing more for two it lays
    /// on each other (one outline deformed). See docs/method.md §7.5 and BENCHMARKS.md,
    /// "Landmarks on real outlines annotated by others".
    pub fn for_outlines() -> Self {
        Self {
            refits: 0,
            common_sigma: true,
            refine: Refine::Auto,
            ..Self::default()
        }
    }

    /// The measured best setting for a kind of input: [`MatchOptions::for_surfaces`] for
    /// unordered 3-D point sets and meshes (`dim == 3 && !ordered`),
    /// [`MatchOptions::for_outlines`] for closed planar outlines (`dim == 2 && ordered`), the
    /// default recipe for everything else (2-D point sets). What `pymodal.match` and the
    /// `pedomatch` CLI start from.
    ///
    /// ```
    /// use modal_core::MatchOptions;
    /// assert_eq!(MatchOptions::for_input(3, false), MatchOptions::for_surfaces());
    /// assert_eq!(MatchOptions::for_input(2, true), MatchOptions::for_outlines());
    /// assert_eq!(MatchOptions::for_input(2, false), MatchOptions::default());
    /// ```
    pub fn for_input(dim: usize, ordered: bool) -> Self {
        match (dim, ordered) {
            (3, false) => Self::for_surfaces(),
            (2, true) => Self::for_outlines(),
            _ => Self::default(),
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
