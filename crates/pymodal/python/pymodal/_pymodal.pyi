# Type stubs of the compiled module (crates/pymodal/src). The runtime signatures are the
# source of truth: tests/test_stubs.py checks every name, parameter and default against them.
import os
from typing import Any, Literal, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

# What `pymodal.run` returns (a dict subclass defined in Python, wrapping this module's dict).
from pymodal import RunResult

__version__: str

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]
Material = Union[
    None,
    Literal["rubber", "steel", "aluminium", "cork", "unit"],
    str,
    Mapping[str, float],
    Tuple[float, float, float],
]
Path = Union[str, os.PathLike]
Element = Literal["gaussian", "axial"]
Solver = Literal["jv", "hungarian", "simplex", "ordered"]
Search = Literal["global", "local", "best"]
Prealign = Literal["robust", "normalize", "sensor"]
ThresholdMode = Literal["after", "during"]
Pitch = Union[float, Tuple[float, float]]
# The tables' file format (batch, batch_row): "parquet" writes typed, compressed columns.
Tables = Literal["csv", "parquet"]

# The exception hierarchy (crates/pymodal/src/errors.rs). Every class but the root is also a
# ValueError; a missing file raises the builtin FileNotFoundError, other OS errors OSError.
# An int parameter below is a count, size or index: a negative value raises OptionError naming it.
class PedomatchError(Exception): ...
class FormatError(PedomatchError, ValueError): ...
class DegenerateShapeError(PedomatchError, ValueError): ...
class InputError(PedomatchError, ValueError): ...
class OptionError(InputError): ...
class InfeasibleError(PedomatchError, ValueError): ...
class NumericalError(PedomatchError, ValueError): ...

class ModalModel:
    def __init__(
        self,
        points: ArrayLike,
        *,
        element: Optional[Element] = None,
        material: Material = None,
        sigma: Optional[float] = None,
        edges: Optional[ArrayLike] = None,
        triangles: Optional[ArrayLike] = None,
        kappa: float = 1.0,
        n_modes: Optional[int] = None,
        exact_rigid: bool = False,
        plane: Literal["stress", "strain"] = "stress",
        center_stride: int = 1,
    ) -> None: ...
    @property
    def eigenvalues(self) -> FloatArray: ...
    @property
    def frequencies(self) -> FloatArray: ...
    @property
    def modes(self) -> FloatArray: ...
    @property
    def sigma(self) -> Optional[float]: ...
    @property
    def dim(self) -> int: ...
    @property
    def n_nodes(self) -> int: ...
    @property
    def element(self) -> Element: ...
    def features(self, k: int) -> FloatArray: ...
    def mass(self) -> FloatArray: ...
    def stiffness(self) -> FloatArray: ...

class Match:
    @property
    def pairs(self) -> IntArray: ...
    @property
    def costs(self) -> FloatArray: ...
    @property
    def excess(self) -> BoolArray: ...
    @property
    def affinity(self) -> FloatArray: ...
    @property
    def unmatched_a(self) -> IntArray: ...
    @property
    def unmatched_b(self) -> IntArray: ...
    @property
    def local_pairs(self) -> IntArray: ...
    @property
    def local_count(self) -> int: ...
    @property
    def optimisation_count(self) -> int: ...
    @property
    def excess_count(self) -> int: ...
    @property
    def crossings(self) -> Optional[int]: ...
    @property
    def n_modes(self) -> int: ...
    @property
    def refits(self) -> int: ...
    @property
    def transform(self) -> FloatArray: ...
    @property
    def aligned_a(self) -> FloatArray: ...
    @property
    def outline_images(self) -> Optional[FloatArray]:
        """Where a's nodes land on b's outline, as positions j + t along b's numbering (two
        closed contours; after the coherent drift finer than b's nodes, and with refine="auto"
        taken both ways: a's drift onto b averaged with b's onto a read backwards)."""
        ...
    @property
    def drifted(self) -> bool:
        """Whether the coherent drift moved a's nodes (aligned_a then holds the moved nodes)."""
        ...
    def field(self, a: ArrayLike, b: ArrayLike, *, smoothing: float = 0.0) -> Field:
        """The thin-plate spline field of this match's one-to-one pairs (excess pairs left out);
        after the coherent drift, of a's nodes and their images: the points of b's outline at
        outline_images for two closed contours, else their moved positions (aligned_a)."""
        ...
    def _repr_html_(self) -> str: ...
    def __len__(self) -> int: ...

class Field:
    """A smooth map of the plane (thin-plate spline with an affine part) fitted to a pair's
    one-to-one matches: scipy's RBFInterpolator(kernel="thin_plate_spline", smoothing=...)."""

    def __init__(self, a: ArrayLike, b: ArrayLike, pairs: ArrayLike, *, smoothing: float = 0.0) -> None: ...
    def apply(self, points: ArrayLike) -> FloatArray:
        """The images of (k, 2) points of a's plane in b's, a new (k, 2) array."""
        ...
    def inverse(self) -> Field:
        """The field fitted the other way (b to a) to the same pairs and smoothing."""
        ...
    @property
    def pairs(self) -> IntArray:
        """(k, 2) (source node, target node) of the pairs fitted."""
        ...
    @property
    def residuals(self) -> FloatArray:
        """(k,) distance from each matched node's image to its partner."""
        ...
    @property
    def smoothing(self) -> float:
        """The weight of the bending energy."""
        ...

class SyntheticWalk:
    """A foot-like pressure field warped smoothly in time (translation towards the toes, rotation,
    widening of the forefoot) with the true map from frame-0 coordinates to frame ``t`` known."""

    def __init__(
        self,
        *,
        frames: Optional[int] = None,
        rows: Optional[int] = None,
        cols: Optional[int] = None,
        translation: Optional[Tuple[float, float]] = None,
        rotation: Optional[float] = None,
        spread: Optional[float] = None,
        noise: Optional[float] = None,
        pitch_mm: Optional[float] = None,
        frame_rate: Optional[float] = None,
    ) -> None: ...
    def recording(self) -> Recording:
        """The synthetic recording (kPa, with pitch, frame rate and noise threshold)."""
        ...
    def true_positions(self, t: int, points: ArrayLike) -> FloatArray:
        """Where the frame-0 points (n, 2; x = column, y = row) lie in frame ``t``."""
        ...
    def reference_positions(self, t: int, points: ArrayLike) -> FloatArray:
        """Where the frame-``t`` points (n, 2) lay in frame 0."""
        ...
    @property
    def frames(self) -> int:
        """Number of frames of the recording."""
        ...

class Recording:
    @staticmethod
    def from_array(
        frames: ArrayLike,
        *,
        # @generated keywords of Recording.from_array: tests/generated.rs, from the option tables
        pitch_mm: Optional[Pitch] = None,
        frame_rate: Optional[float] = None,
        units: Optional[str] = None,
        time_axis: Optional[Literal["first", "last"]] = None,
        clip_negative: Optional[bool] = None,
        # @end generated
        mask: Optional[ArrayLike] = None,
    ) -> Recording: ...
    @property
    def frames(self) -> npt.NDArray[np.float32]: ...
    @property
    def sensor_mask(self) -> BoolArray: ...
    @property
    def pitch_mm(self) -> Optional[Tuple[float, float]]: ...
    @property
    def dt_s(self) -> Optional[float]: ...
    @property
    def units(self) -> Optional[str]: ...
    @property
    def sensel_area_mm2(self) -> Optional[float]: ...
    @property
    def noise_threshold(self) -> Optional[float]: ...
    @property
    def negative_values(self) -> dict[str, Any]: ...
    @property
    def feet(self) -> dict[str, Tuple[int, int]]: ...
    @property
    def format(self) -> Optional[str]: ...
    @property
    def n_frames(self) -> int: ...
    @property
    def shape(self) -> Tuple[int, int, int]: ...
    @property
    def peak_image(self) -> FloatArray: ...
    @property
    def contact_area(self) -> FloatArray: ...
    @property
    def total_force(self) -> FloatArray: ...
    @property
    def peak_pressure(self) -> FloatArray: ...
    @property
    def cop(self) -> FloatArray: ...
    def measures(self, threshold: float = 0.0) -> dict[str, npt.NDArray[Any]]: ...
    def gait_measures(
        self, threshold: float = 0.0, frames: Optional[Tuple[int, int]] = None
    ) -> dict[str, Any]: ...
    def regions(
        self,
        rule: Literal["coarse", "fine"] = "fine",
        threshold: float = 0.0,
        frames: Optional[Tuple[int, int]] = None,
    ) -> dict[str, Any]: ...
    def __len__(self) -> int: ...

class Surface:
    @property
    def points(self) -> FloatArray: ...
    @property
    def triangles(self) -> IntArray: ...

def match(
    a: ArrayLike,
    b: ArrayLike,
    *,
    # @generated keywords of match: tests/generated.rs, from the option tables
    element: Optional[Literal["gaussian", "axial"]] = None,
    modes: Optional[float] = None,
    search: Optional[Literal["global", "local", "best"]] = None,
    solver: Optional[Literal["jv", "hungarian", "simplex", "ordered"]] = None,
    threshold: Optional[float] = None,
    threshold_mode: Optional[Literal["after", "during"]] = None,
    excess: Optional[bool] = None,
    paper: Optional[bool] = None,
    prealign: Optional[Literal["robust", "normalize", "sensor"]] = None,
    max_rotation: Optional[float] = None,
    refits: Optional[int] = None,
    refit_tolerance: Optional[float] = None,
    refine: Optional[Literal["affine", "modal", "coherent", "auto"]] = None,
    deform_modes: Optional[int] = None,
    deform_stiffness: Optional[float] = None,
    kappa: Optional[float] = None,
    center_stride: Optional[int] = None,
    position_weight: Optional[float] = None,
    cost_power: Optional[float] = None,
    common_sigma: Optional[bool] = None,
    skip_rigid: Optional[bool] = None,
    band: Optional[int] = None,
    material: Optional[Material] = None,
    max_nodes: Optional[int] = None,
    ordered: Optional[bool] = None,
    # @end generated
    triangles_a: Optional[ArrayLike] = None,
    triangles_b: Optional[ArrayLike] = None,
) -> Match: ...
def eigh(
    k: ArrayLike, m: ArrayLike, *, n_modes: Optional[int] = None
) -> Tuple[FloatArray, FloatArray]: ...
def linear_sum_assignment(
    cost_matrix: ArrayLike,
    maximize: bool = False,
    *,
    solver: Optional[Solver] = None,
    method: Optional[Solver] = None,
) -> Tuple[IntArray, IntArray]: ...
def linear_sum_assignment_threshold(
    cost_matrix: ArrayLike,
    tau: float,
    maximize: bool = False,
    *,
    solver: Optional[Solver] = None,
    method: Optional[Solver] = None,
) -> Tuple[IntArray, IntArray]: ...
def read_recording(
    path: Path,
    *,
    # @generated keywords of read_recording: tests/generated.rs, from the option tables
    pitch_mm: Optional[Pitch] = None,
    frame_rate: Optional[float] = None,
    units: Optional[str] = None,
    time_axis: Optional[Literal["first", "last"]] = None,
    clip_negative: Optional[bool] = None,
    layout: Optional[Path] = None,
    max_frame_sensors: Optional[int] = None,
    max_frames: Optional[int] = None,
    max_values: Optional[int] = None,
    max_decompressed_mb: Optional[int] = None,
    max_text_mb: Optional[int] = None,
    max_memory_mb: Optional[int] = None,
    # @end generated
) -> Recording: ...
def contours(
    frame: ArrayLike,
    *,
    level: Optional[float] = None,
    n_points: Optional[int] = None,
    spacing: Optional[float] = None,
    smooth: Optional[float] = None,
    threshold: Optional[float] = None,
    upsample: Optional[int] = None,
    interpolation: Literal["bilinear", "bicubic"] = "bilinear",
    method: Literal["marching", "chain"] = "marching",
    high: Optional[float] = None,
    fully_connected: Literal["low", "high"] = "low",
    include_holes: bool = True,
    min_area: float = 0.0,
) -> list[FloatArray]: ...
def isocontours(
    frame: ArrayLike,
    levels: Sequence[float],
    *,
    smooth: Optional[float] = None,
    threshold: Optional[float] = None,
    three_d: bool = False,
    n_points: Optional[int] = None,
    spacing: Optional[float] = None,
    include_holes: bool = True,
    fully_connected: Literal["low", "high"] = "low",
) -> list[Tuple[float, FloatArray]]: ...
def surface(
    frame: ArrayLike,
    *,
    threshold: Optional[float] = None,
    max_nodes: Optional[int] = None,
    smooth: Optional[float] = None,
    step: int = 1,
    keep_hull: bool = True,
    laplacian_iterations: int = 20,
    relaxation: float = 0.01,
    z_scale: Literal["xy", "keep"] = "xy",
) -> Surface: ...
# run's result (RunResult, a dict) holds, besides table, matches, objects, tracks, track_steps,
# track_round_trips (a FloatArray, one round trip in sensels per track, NaN where none),
# frames, curves (the rows of curves.csv as dicts: stance, complete, percent and the frames
# table's measures at 0..100 % of each stance's contact, and each region's with region_rule
# or masks), summary and timings,
# "reference_matches": with drift correction, one ReferenceMatch
# per reference pair (an empty list without); and for the contour model "points" (per material
# point followed by anchored registration, a FloatArray of rows frame, x, y in pixels) with
# "point_steps" (an IntArray of rows object id, seed node; -1 for no node) and
# "point_round_trips" (a FloatArray, each step's round trip in sensels, NaN on its seed frame),
# empty lists for the other models.
# A reference pair of drift correction: id_a, id_b and frame_a, frame_b (int), match (Match) and
# tracked (BoolArray aligned with match.pairs: True where a track took the match).
ReferenceMatch = dict[str, Any]

def run(
    recording: Union[Recording, Path, ArrayLike],
    *,
    # @generated keywords of run: tests/generated.rs, from the option tables
    element: Optional[Literal["gaussian", "axial"]] = None,
    modes: Optional[float] = None,
    search: Optional[Literal["global", "local", "best"]] = None,
    solver: Optional[Literal["jv", "hungarian", "simplex", "ordered"]] = None,
    threshold: Optional[float] = None,
    threshold_mode: Optional[Literal["after", "during"]] = None,
    excess: Optional[bool] = None,
    paper: Optional[bool] = None,
    prealign: Optional[Literal["robust", "normalize", "sensor"]] = None,
    max_rotation: Optional[float] = None,
    refits: Optional[int] = None,
    refit_tolerance: Optional[float] = None,
    refine: Optional[Literal["affine", "modal", "coherent", "auto"]] = None,
    deform_modes: Optional[int] = None,
    deform_stiffness: Optional[float] = None,
    kappa: Optional[float] = None,
    center_stride: Optional[int] = None,
    position_weight: Optional[float] = None,
    cost_power: Optional[float] = None,
    common_sigma: Optional[bool] = None,
    skip_rigid: Optional[bool] = None,
    band: Optional[int] = None,
    material: Optional[Material] = None,
    max_nodes: Optional[int] = None,
    model: Optional[Literal["contour", "surface", "isocontour"]] = None,
    frames: Optional[Tuple[Optional[int], Optional[int]]] = None,
    every: Optional[Union[int, Literal["auto"]]] = None,
    noise: Optional[float] = None,
    smooth: Optional[float] = None,
    spacing: Optional[float] = None,
    surface_nodes: Optional[int] = None,
    iso_frame: Optional[int] = None,
    iso_levels: Optional[int] = None,
    drift_reference: Optional[int] = None,
    pitch_mm: Optional[Pitch] = None,
    frame_rate: Optional[float] = None,
    units: Optional[str] = None,
    time_axis: Optional[Literal["first", "last"]] = None,
    clip_negative: Optional[bool] = None,
    points: Optional[Union[Path, ArrayLike]] = None,
    points_frame: Optional[int] = None,
    regions: Optional[Union[Path, ArrayLike]] = None,
    regions_frame: Optional[int] = None,
    # @end generated
    out: Optional[Path] = None,
    # @generated keywords of run output: tests/generated.rs, from the option tables
    figures: Optional[Literal["summary", "pairs", "none"]] = None,
    figure_format: Optional[Literal["png", "svg"]] = None,
    tables: Optional[Literal["csv", "parquet"]] = None,
    report: Optional[Literal["html", "none"]] = None,
    animation: Optional[Literal["gif", "none"]] = None,
    region_rule: Optional[Literal["none", "coarse", "fine"]] = None,
    masks: Optional[Union[Path, ArrayLike]] = None,
    layout: Optional[Path] = None,
    max_frame_sensors: Optional[int] = None,
    max_frames: Optional[int] = None,
    max_values: Optional[int] = None,
    max_decompressed_mb: Optional[int] = None,
    max_text_mb: Optional[int] = None,
    max_memory_mb: Optional[int] = None,
    # @end generated
) -> RunResult: ...

# A row of a study table (batch, batch_row): path, output, format, frames, frame_rate_hz,
# pitch_x_mm, pitch_y_mm, pressure_units, pairs, mean_local_percent, mean_optimisation_percent,
# mean_trackable_percent, mean_round_trip_sensels, tracks, track_round_trip_median_sensels,
# track_round_trip_p95_sensels, point_round_trip_median_sensels, point_round_trip_p95_sensels,
# peak_pressure_kpa, pti_max_kpa_s, peak_force_n, fti_n_s,
# contact_time_s, max_contact_area_mm2, wall_time_s, status ("ok", "skipped", "error") and message,
# the columns of study.csv (or study.parquet).
StudyRow = dict[str, Any]

def find_recordings(inputs: Union[Path, Sequence[Path]]) -> list[str]:
    """The recordings named by files, folders (searched recursively) and glob patterns, in order, each once."""
    ...

def batch(
    paths: Union[Path, Sequence[Path]],
    out: Optional[Path] = None,
    # @generated keywords of batch study: tests/generated.rs, from the option tables
    jobs: Optional[int] = None,
    force: Optional[bool] = None,
    # @end generated
    *,
    # @generated keywords of batch output: tests/generated.rs, from the option tables
    figures: Optional[Literal["summary", "pairs", "none"]] = None,
    figure_format: Optional[Literal["png", "svg"]] = None,
    tables: Optional[Literal["csv", "parquet"]] = None,
    report: Optional[Literal["html", "none"]] = None,
    animation: Optional[Literal["gif", "none"]] = None,
    region_rule: Optional[Literal["none", "coarse", "fine"]] = None,
    masks: Optional[Union[Path, ArrayLike]] = None,
    layout: Optional[Path] = None,
    max_frame_sensors: Optional[int] = None,
    max_frames: Optional[int] = None,
    max_values: Optional[int] = None,
    max_decompressed_mb: Optional[int] = None,
    max_text_mb: Optional[int] = None,
    max_memory_mb: Optional[int] = None,
    # @end generated
    **options: Any,
) -> list[StudyRow]:
    """Run every recording like :func:`run` (several at once); return the study table, one dict per recording.

    Raises :class:`InputError` when ``paths`` name no recording at all (nothing is written)."""
    ...

def batch_row(
    path: Path,
    out: Optional[Path] = None,
    *,
    # @generated keywords of batch_row: tests/generated.rs, from the option tables
    force: Optional[bool] = None,
    # @end generated
    # @generated keywords of batch_row output: tests/generated.rs, from the option tables
    figures: Optional[Literal["summary", "pairs", "none"]] = None,
    figure_format: Optional[Literal["png", "svg"]] = None,
    tables: Optional[Literal["csv", "parquet"]] = None,
    report: Optional[Literal["html", "none"]] = None,
    animation: Optional[Literal["gif", "none"]] = None,
    region_rule: Optional[Literal["none", "coarse", "fine"]] = None,
    masks: Optional[Union[Path, ArrayLike]] = None,
    layout: Optional[Path] = None,
    max_frame_sensors: Optional[int] = None,
    max_frames: Optional[int] = None,
    max_values: Optional[int] = None,
    max_decompressed_mb: Optional[int] = None,
    max_text_mb: Optional[int] = None,
    max_memory_mb: Optional[int] = None,
    # @end generated
    **options: Any,
) -> StudyRow:
    """One row of :func:`batch`'s table: one recording on one thread (for Dask or a job queue)."""
    ...

def register(
    inputs: Union[Path, Sequence[Path], npt.ArrayLike],
    out: Optional[Path] = None,
    template_image: Optional[npt.ArrayLike] = None,
    *,
    # @generated keywords of register: tests/generated.rs, from the option tables
    template: Optional[str] = None,
    mirror_left: Optional[bool] = None,
    max_turn: Optional[float] = None,
    outline_nodes: Optional[int] = None,
    field_smoothing: Optional[float] = None,
    template_rounds: Optional[int] = None,
    refine_intensity: Optional[bool] = None,
    warp_spacing: Optional[float] = None,
    warp_smoothing: Optional[float] = None,
    foot_threshold: Optional[float] = None,
    # @end generated
    # @generated keywords of register read: tests/generated.rs, from the option tables
    layout: Optional[Path] = None,
    max_frame_sensors: Optional[int] = None,
    max_frames: Optional[int] = None,
    max_values: Optional[int] = None,
    max_decompressed_mb: Optional[int] = None,
    max_text_mb: Optional[int] = None,
    max_memory_mb: Optional[int] = None,
    # @end generated
) -> dict[str, Any]:
    """Register footprints onto one template: the registered stack, masks, template and a table per trial."""
    ...
