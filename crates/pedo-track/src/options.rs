//! Options of a run: the object model, the frames, the matching options of a run's pairs, and
//! [`RunParams`], the user-facing parameters (CLI, Python, a study) that resolve into
//! [`SequenceOptions`] for one recording.

use crate::*;
use modal_core::{Choice, MatchOptions, MatchParams, OptionError, OptionSpec, OptionValue};
use pedo_io::cancel::Cancel;
use pedo_io::contour::{ContourOptions, Resample};
use pedo_io::recording::Recording;
use pedo_io::Result;

/// Which object model represents a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ObjectModel {
    /// Closed contours of the loaded region (docs/method.md §8.2).
    #[default]
    Contour,
    /// Brightness surfaces: pressure as height over the loaded region (docs/method.md §8.3).
    Surface,
    /// Isobaric contours of a single frame, matched level after level (docs/method.md §8.4).
    Isocontour,
}

/// Parameters of [`run_sequence`].
#[derive(Debug, Clone)]
pub struct SequenceOptions {
    /// What each frame becomes: contours, a surface, or (one frame) isobaric contours.
    pub model: ObjectModel,
    /// Contour extraction (contour model, and the isocontours' preprocessing and resampling).
    pub contour: ContourOptions,
    /// Surface construction (surface model).
    pub surface: pedo_io::surface::SurfaceOptions,
    /// Isocontour model: the frame (0-based index in the recording) whose isobaric contours are
    /// matched; `None`: the frame of largest total load (sum of its values) within
    /// [`frames`](Self::frames). A frame given here is not required to lie within `frames`, only
    /// within the recording (else [`run_sequence`] fails).
    pub iso_frame: Option<usize>,
    /// Isocontour model: the levels, in the recording's pressure units, in the order they are
    /// matched (level `k` with level `k + 1`); `None`: [`iso_count`](Self::iso_count) levels
    /// evenly spaced strictly between 0 and the peak of the thresholded frame
    /// ([`pedo_io::isobar::even_levels`]).
    pub iso_levels: Option<Vec<f64>>,
    /// Isocontour model: the number of levels when [`iso_levels`](Self::iso_levels) is `None`.
    pub iso_count: usize,
    /// Objects with fewer nodes are left out (too small to model); never fewer than 3.
    pub min_nodes: usize,
    /// Frames `start..end` of the recording to use, 0-based with `end` excluded (`None`: all).
    /// The range must be non-empty and within the recording, else [`run_sequence`] and
    /// [`stream_sequence`] fail.
    pub frames: Option<(usize, usize)>,
    /// Frame stride: every this many-th frame of [`frames`](Self::frames) is run, from its
    /// first ([`SequenceOptions::kept_frames`]); 1 runs every frame (0 counts as 1). Objects keep
    /// the recording's own frame numbers; pairs join consecutive kept frames.
    pub every: usize,
    /// How each pair is matched. Default: [`MatchOptions::default`] without the outline fit
    /// (`rotation_search.outline_iterations` 0): a run's frames keep node-to-node ICP.
    pub matching: MatchOptions,
    /// Drift correction: reference frames every this many frames, each object also matched
    /// against its ancestor on the last reference frame ([`crate::drift`]); 0: off.
    pub drift_reference: usize,
    /// Keep each pair's whole [`MatchResult`](modal_core::MatchResult) (affinity matrix, aligned nodes, local pairs).
    /// Off, a pair keeps only what the run's outputs use (its matches, unmatched nodes and
    /// transform): the affinity matrix alone is `n × m` numbers per pair, the bulk of a long
    /// recording's memory. On by default; the CLI and batch runs turn it off.
    pub keep_match_details: bool,
    /// The sensor's row pitch over its column pitch (1 for square sensels; 1.5 for footscan's
    /// 7.62 × 5.08 mm). Pairs are matched with y scaled by it, in the sensor's true proportions,
    /// so that the rotation search, the Gaussian widths and the modes see the foot's true shape;
    /// the objects, the outputs and the matches' transforms stay in sensels. [`RunParams`] sets it
    /// from the recording's pitch; default 1.
    pub sensel_aspect: f64,
    /// Stops the run at its next progress step once cancelled (a frame built, a pair matched):
    /// [`run_sequence`] and [`stream_sequence`] then fail with [`IoError::Cancelled`](pedo_io::IoError::Cancelled)
    /// ([`pedo_io::cancel`]). `None`: the run goes to its end.
    pub cancel: Option<Cancel>,
    /// The points and regions a user gives to follow through the stance ([`crate::follow`]),
    /// read for this recording ([`RunParams::to_options`]); none by default.
    pub inputs: crate::inputs::UserInputs,
}

impl SequenceOptions {
    /// Whether the run corrects the drift of its tracks: reference frames every
    /// [`drift_reference`](Self::drift_reference) ≥ 2 frames, for the contour and surface
    /// models (the isocontour model matches the levels of one frame, which have no drift).
    pub fn drift_corrected(&self) -> bool {
        self.drift_reference >= 2 && self.model != ObjectModel::Isocontour
    }

    /// The frame stride, at least 1 ([`every`](Self::every)).
    pub fn frame_step(&self) -> usize {
        self.every.max(1)
    }

    /// The frames a run over `start..end` builds objects on: every
    /// [`frame_step`](Self::frame_step)-th from `start`.
    pub fn kept_frames(&self, start: usize, end: usize) -> Vec<usize> {
        (start..end).step_by(self.frame_step()).collect()
    }
}

impl Default for SequenceOptions {
    fn default() -> Self {
        Self {
            model: ObjectModel::Contour,
            contour: ContourOptions {
                resample: Resample::Spacing(1.0),
                min_area: 4.0,
                ..ContourOptions::default()
            },
            surface: pedo_io::surface::SurfaceOptions {
                max_nodes: Some(120),
                ..Default::default()
            },
            iso_frame: None,
            iso_levels: None,
            iso_count: 10,
            min_nodes: 8,
            frames: None,
            every: 1,
            matching: for_frames(MatchOptions::default()),
            drift_reference: 0,
            keep_match_details: true,
            sensel_aspect: 1.0,
            inputs: Default::default(),
            cancel: None,
        }
    }
}

/// Matching options for the frames of a recording: the rotation search (reference pairs of drift
/// correction, or `prealign = "robust"`) keeps node-to-node ICP, without the outline fit that
/// ends it for two shapes (`RotationSearch::outline_iterations`). The outline of a pressure
/// region is no material line: fitting the outlines slid frames 50 and 75 of the synthetic walk
/// along them (direct pairs from frame 0: 0.98 and 1.00 of the nodes within a spacing with node
/// ICP, 0.82 and 0.83 with the fit; drift correction every 50 frames: 98 % of the tracks within
/// a spacing after 50 frames, 81 % with it; BENCHMARKS.md, "Tracks against ground truth").
fn for_frames(mut o: MatchOptions) -> MatchOptions {
    o.rotation_search.outline_iterations = 0;
    o
}

modal_core::choice!(ObjectModel, "model", [
    "contour" => ObjectModel::Contour,
    "surface" => ObjectModel::Surface,
    "isocontour" => ObjectModel::Isocontour,
]);

/// The highest rate (frames per second) at which a run's pairs are matched by default: a
/// recording sampled faster is run at every N-th frame, N the smallest stride that brings it to
/// this rate or below ([`FrameStride::Auto`]). At 500 Hz a point of a foot moves about 0.03
/// sensel from one frame to the next and a quarter of consecutive outlines are identical.
pub const MATCH_RATE_HZ: f64 = 250.0;

/// The frame stride of a run ([`RunParams::every`]): every N-th frame, or `auto`, N chosen from
/// the recording's frame rate ([`FrameStride::resolve`]). Written `auto` or a number `N`.
///
/// ```
/// use pedo_track::FrameStride;
/// assert_eq!("auto".parse::<FrameStride>().unwrap(), FrameStride::Auto);
/// assert_eq!("3".parse::<FrameStride>().unwrap().to_string(), "3");
/// assert_eq!(FrameStride::Auto.resolve(Some(500.0), 300, 0), 2);
/// assert_eq!(FrameStride::Auto.resolve(Some(100.0), 300, 0), 1);
/// assert_eq!(FrameStride::Auto.resolve(None, 300, 0), 1);
/// assert_eq!(FrameStride::Every(3).resolve(Some(100.0), 300, 0), 3);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrameStride {
    /// Every frame at rates up to [`MATCH_RATE_HZ`], else the smallest stride that brings the
    /// recording to that rate or below.
    #[default]
    Auto,
    /// Every N-th frame (1: every frame).
    Every(usize),
}

impl FrameStride {
    /// The stride of a run of `frames` frames of a recording at `frame_rate` (frames per second,
    /// `None`: unknown) with drift correction every `drift_reference` frames (0: off). A stride
    /// given is kept as given; `auto` is 1 at an unknown rate or one up to [`MATCH_RATE_HZ`],
    /// else the smallest N with `frame_rate / N <= MATCH_RATE_HZ`, lowered to a divisor of
    /// `drift_reference` (reference frames must be frames run) and so that a run of two or more
    /// frames keeps at least two.
    pub fn resolve(&self, frame_rate: Option<f64>, frames: usize, drift_reference: usize) -> usize {
        let n = match *self {
            FrameStride::Every(n) => return n,
            FrameStride::Auto => match frame_rate {
                // A rate read as 1 / dt may be off in its last bits: 500 Hz is 500, not 3 × 166.7.
                Some(r) if r.is_finite() && r > MATCH_RATE_HZ * (1.0 + 1e-9) => {
                    (r / MATCH_RATE_HZ * (1.0 - 1e-9)).ceil() as usize
                }
                _ => 1,
            },
        };
        let mut n = n.min(frames.saturating_sub(1)).max(1);
        if drift_reference >= 2 {
            while !drift_reference.is_multiple_of(n) {
                n -= 1;
            }
        }
        n
    }
}

impl std::fmt::Display for FrameStride {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameStride::Auto => f.write_str("auto"),
            FrameStride::Every(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for FrameStride {
    type Err = OptionError;
    fn from_str(s: &str) -> std::result::Result<Self, OptionError> {
        let s = s.trim();
        if s == "auto" {
            return Ok(FrameStride::Auto);
        }
        s.parse()
            .map(FrameStride::Every)
            .map_err(|_| OptionError::new("every", s, "auto or an integer >= 1 (1: every frame)"))
    }
}

impl modal_core::options::OptionField for FrameStride {
    fn python_type() -> String {
        "Union[int, Literal[\"auto\"]]".into()
    }
    fn value_name() -> Option<&'static str> {
        Some("N|auto")
    }
    fn read<I: modal_core::options::OptionInput + ?Sized>(
        input: &I,
        option: &'static str,
    ) -> std::result::Result<Self, I::Error> {
        if let Some(text) = input.written() {
            return Ok(text.parse()?);
        }
        // Python: an int, else the word `auto` (a number in a str is no int).
        match input.count(option) {
            Ok(n) => Ok(FrameStride::Every(n)),
            Err(e) => match input.text(option) {
                Ok(text) if text.trim() == "auto" => Ok(FrameStride::Auto),
                Ok(text) => {
                    Err(
                        OptionError::new(option, text, "auto or an integer >= 1 (1: every frame)")
                            .into(),
                    )
                }
                Err(_) => Err(e),
            },
        }
    }
    fn value(&self) -> OptionValue {
        match self {
            FrameStride::Auto => OptionValue::Word("auto".into()),
            FrameStride::Every(n) => OptionValue::Int(*n),
        }
    }
}

/// Frames `start..end` of a recording: 0-based and half-open like a Python slice (`10..60` is
/// frames 10 to 59); an open end runs to the last frame, and a negative index counts back from
/// the end of the recording, as in Python (`-50..` is the last 50 frames, `0..-1` every frame
/// but the last). Written `START..END`, `START..` or `..END`. Negative indices are resolved by
/// [`FrameRange::resolve`] once the frame count is known.
///
/// ```
/// use pedo_track::FrameRange;
/// let r: FrameRange = "10..".parse().unwrap();
/// assert_eq!(r.resolve(100).unwrap(), (10, 100));
/// assert_eq!("..60".parse::<FrameRange>().unwrap().to_string(), "0..60");
/// assert_eq!("-50..".parse::<FrameRange>().unwrap().resolve(205).unwrap(), (155, 205));
/// assert_eq!("0..-1".parse::<FrameRange>().unwrap().resolve(205).unwrap(), (0, 204));
/// assert!("5..3".parse::<FrameRange>().unwrap().resolve(100).is_err());
/// assert!("-300..".parse::<FrameRange>().unwrap().resolve(205).is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameRange {
    /// The first frame (0-based; negative: counted back from the end, `-1` the last frame).
    pub start: isize,
    /// One past the last frame (negative: counted back from the end); `None`: to the end of the
    /// recording.
    pub end: Option<isize>,
}

impl FrameRange {
    /// The frames `start..end` of a recording (0-based, `end` excluded), as a range.
    pub fn new(start: usize, end: usize) -> Self {
        // A frame count fits an `isize` (no allocation holds more than `isize::MAX` bytes).
        let index = |i: usize| isize::try_from(i).unwrap_or(isize::MAX);
        Self {
            start: index(start),
            end: Some(index(end)),
        }
    }

    /// `(start, end)` for a recording of `n_frames`: negative indices counted back from
    /// `n_frames`, then a non-empty range within the recording, `end` excluded. The one place
    /// where a range given to the CLI, to Python or to a study becomes frames.
    ///
    /// # Errors
    ///
    /// An [`OptionError`] on the option `frames`, naming the range and the frame count, when the
    /// resolved range is empty (`start >= end`), starts before the first frame or ends past
    /// `n_frames`.
    pub fn resolve(&self, n_frames: usize) -> std::result::Result<(usize, usize), OptionError> {
        let n = isize::try_from(n_frames).unwrap_or(isize::MAX);
        // n >= 0 and i < 0: no overflow.
        let at = |i: isize| if i < 0 { n + i } else { i };
        let (start, end) = (at(self.start), self.end.map_or(n, at));
        if 0 <= start && start < end && end <= n {
            // Both within 0..=n: non-negative.
            return Ok((start.unsigned_abs(), end.unsigned_abs()));
        }
        let negative = self.start < 0 || self.end.is_some_and(|e| e < 0);
        let resolved = if negative {
            format!("; here {self} is {start}..{end}")
        } else {
            String::new()
        };
        Err(OptionError::new(
            "frames",
            self,
            format!(
                "a non-empty range START..END within the recording's {n_frames} frames \
                 (0..{n_frames}, 0-based, END excluded; a negative index counts back from the \
                 end){resolved}"
            ),
        ))
    }
}

impl std::fmt::Display for FrameRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.end {
            Some(e) => write!(f, "{}..{e}", self.start),
            None => write!(f, "{}..", self.start),
        }
    }
}

impl std::str::FromStr for FrameRange {
    type Err = OptionError;
    fn from_str(s: &str) -> std::result::Result<Self, OptionError> {
        let bad = || {
            OptionError::new(
                "frames",
                s,
                "START..END, 0-based with END excluded (START.. and ..END allowed; a negative \
                 index counts back from the end: -50.. is the last 50 frames)",
            )
        };
        let (a, b) = s.split_once("..").ok_or_else(bad)?;
        let number = |x: &str| x.trim().parse::<isize>().map_err(|_| bad());
        Ok(Self {
            start: if a.trim().is_empty() { 0 } else { number(a)? },
            end: if b.trim().is_empty() {
                None
            } else {
                Some(number(b)?)
            },
        })
    }
}

impl modal_core::options::OptionField for FrameRange {
    fn python_type() -> String {
        "Tuple[Optional[int], Optional[int]]".into()
    }
    fn value_name() -> Option<&'static str> {
        // `-50..` starts with a hyphen: the value's own name lets the command line take it.
        Some("START..END")
    }
    fn read<I: modal_core::options::OptionInput + ?Sized>(
        input: &I,
        option: &'static str,
    ) -> std::result::Result<Self, I::Error> {
        if let Some(text) = input.written() {
            return Ok(text.parse()?);
        }
        let [start, end] = input.bounds(
            option,
            "a (start, end) pair of 0-based frame indices, end excluded (either may be None; a \
             negative index counts back from the end, as in a slice)",
        )?;
        Ok(FrameRange {
            start: start.unwrap_or(0),
            end,
        })
    }
    fn value(&self) -> OptionValue {
        OptionValue::Word(self.to_string())
    }
}

/// The contour node spacing of [`SequenceOptions::default`], the default of
/// [`RunParams::spacing`].
fn default_spacing(d: &SequenceOptions) -> f64 {
    match d.contour.resample {
        Resample::Spacing(s) => s,
        _ => 1.0,
    }
}

modal_core::option_set! {
    /// The user-facing parameters of a sequence run, shared by the CLI, the Python bindings and
    /// a study: the matching options, how each frame becomes objects, and the units overriding
    /// the file's; each option declared here once, its default that of
    /// [`SequenceOptions::default`]. [`RunParams::to_options`] checks them against a recording.
    RunParams {
        nested(
            /// How each pair is matched, as the user gave it; [`RunParams::match_options`] turns
            /// it into the engine's options for a run.
            matching: MatchParams,
            /// Sensor pitch, frame rate and pressure units overriding the file's.
            units: pedo_io::units::UnitOverrides,
            /// Points and regions to follow through the stance (contour model).
            inputs: crate::inputs::RunInputs,
        );
        let d = SequenceOptions::default();
        /// What each frame becomes: contours, a surface, or (one frame) isobaric contours.
        model: ObjectModel = d.model;
            Word(ObjectModel::NAMES), d.model,
            "Object model of each frame: closed contours of the loaded regions, brightness surfaces (pressure as height), or the isobaric contours of one frame matched level after level.";
        /// Frames to use (`None`: all); negative indices count back from the end of each
        /// recording ([`FrameRange::resolve`], called by [`RunParams::to_options`]).
        frames: Option<FrameRange> = None;
            Value, "all",
            "Frames START..END, 0-based with END excluded as in a Python slice (START.. and ..END allowed; a negative index counts back from the end: -50.. is the last 50 frames, 0..-1 all but the last); the range must lie within the recording.";
        /// Frame stride: every this many-th frame of [`frames`](Self::frames), from its first
        /// ([`SequenceOptions::every`]), or `auto` from the recording's frame rate
        /// ([`FrameStride::resolve`]).
        every: FrameStride = FrameStride::Auto;
            Value, FrameStride::Auto,
            "Keep every N-th frame of the frames run, from the first (1: every frame); auto: every frame up to 250 Hz, else the smallest N that brings the recording to 250 Hz or below (2 at 500 Hz). Pairs join consecutive kept frames, and the tables give the recording's own frame numbers and times (frames.csv keeps every frame of the range).";
        /// Noise threshold in the recording's units (`None`: the file's own, else 0).
        noise: Option<f64> = None;
            Value, "the file's noise threshold, else 0",
            "Noise threshold in the recording's pressure units: lower values count as no contact.";
        /// Gaussian smoothing σ in sensels (0: none).
        smooth: f64 = d.contour.preprocess.sigma.unwrap_or(0.0);
            Value, d.contour.preprocess.sigma.unwrap_or(0.0),
            "Gaussian smoothing of each frame, sigma in sensels (0: none; at most 1000).";
        /// Contour node spacing in sensels.
        spacing: f64 = default_spacing(&d);
            Value, default_spacing(&d),
            "Contour node spacing in sensels.";
        /// Node budget of each brightness surface.
        surface_nodes: usize = d.surface.max_nodes.unwrap_or(120);
            Value, d.surface.max_nodes.unwrap_or(120),
            "Node budget of each brightness surface.";
        /// Isocontour model: the frame (0-based, within [`frames`](Self::frames) when given, else
        /// within the recording: [`RunParams::to_options`] fails otherwise; `None`: the frame of
        /// largest load among those run).
        iso_frame: Option<usize> = d.iso_frame;
            Value, "the frame of largest load",
            "Isocontour model: the frame (0-based, within frames when given) whose isobaric contours are matched.";
        /// Isocontour model: the number of levels (at least 2), evenly spaced as
        /// [`SequenceOptions::iso_levels`] says.
        iso_levels: usize = d.iso_count;
            Value, d.iso_count,
            "Isocontour model: the number of isobaric levels.";
        /// Drift correction: frames between reference frames (0: off); see [`crate::drift`].
        drift_reference: usize = d.drift_reference;
            Value, d.drift_reference,
            "Drift correction of tracks: every this many frames is a reference frame, and each object is also matched against its ancestor on the last one; tracks follow those matches first (0: off).";
    }
}

impl RunParams {
    /// The engine's matching options for this run's object model: surfaces are unordered 3-D
    /// meshes and get the measured surface setting, contours and isocontours the contour recipe.
    /// Consecutive frames hardly turn: the rotation search is bounded by
    /// [`modal_core::options::RUN_MAX_ROTATION`] unless `max_rotation` is given. Consecutive
    /// contours share the sensor's coordinates: they are pre-aligned by
    /// [`modal_core::options::RUN_PREALIGN`] unless `prealign` or `paper` is given; isocontours
    /// keep the order of the level lines ([`modal_core::options::RUN_ISOCONTOUR_SOLVER`]) unless
    /// `solver` or `paper` is given. Frames keep
    /// node-to-node ICP, not the outline fit of a pair, and start from the default recipe
    /// ([`MatchOptions::default`]), not from the pair recipe of two outlines
    /// ([`MatchOptions::for_outlines`]).
    pub fn match_options(&self) -> std::result::Result<MatchOptions, OptionError> {
        let surface = self.model == ObjectModel::Surface;
        let base = if self.matching.paper {
            MatchOptions::paper()
        } else if surface {
            MatchOptions::for_surfaces()
        } else {
            // Frames are not fitted as outlines (`for_frames`): the general recipe, with its
            // re-fits, not the pair recipe of two outlines.
            MatchOptions::default()
        };
        let mut o = self.matching.applied_to(base)?;
        if self.matching.max_rotation.is_none() {
            o.rotation_search.max_rotation = Some(modal_core::options::RUN_MAX_ROTATION);
        }
        if self.model == ObjectModel::Contour
            && self.matching.prealign.is_none()
            && !self.matching.paper
        {
            o.prealign = modal_core::options::RUN_PREALIGN;
        }
        if self.model == ObjectModel::Isocontour
            && self.matching.solver.is_none()
            && !self.matching.paper
        {
            o.method = modal_core::options::RUN_ISOCONTOUR_SOLVER;
        }
        Ok(for_frames(o))
    }

    /// Whether a run with these parameters streams ([`streams`]): the contour and surface
    /// models without drift correction, whatever the frame stride, without points or regions
    /// to follow (they need the whole run).
    pub fn streams(&self) -> bool {
        streamable(self.model, self.drift_reference) && !self.inputs.any()
    }

    /// Checks every parameter that does not depend on a recording.
    pub fn validate(&self) -> std::result::Result<(), OptionError> {
        self.matching.validate()?;
        self.units.validate()?;
        let positive = |ok: bool, name: &'static str, v: f64, what: &str| {
            if ok {
                Ok(())
            } else {
                Err(OptionError::new(name, v, what))
            }
        };
        positive(
            self.spacing.is_finite() && self.spacing > 0.0,
            "spacing",
            self.spacing,
            "a number > 0",
        )?;
        // The bound of `preprocess::gaussian`, checked here so that a run fails at once instead
        // of skipping every frame.
        positive(
            self.smooth.is_finite() && (0.0..=1000.0).contains(&self.smooth),
            "smooth",
            self.smooth,
            "a number in [0, 1000] (sensels)",
        )?;
        if let Some(n) = self.noise {
            positive(n.is_finite(), "noise", n, "a finite number")?;
        }
        if self.iso_levels < 2 {
            return Err(OptionError::new(
                "iso_levels",
                self.iso_levels,
                "an integer >= 2",
            ));
        }
        if self.drift_reference == 1 {
            return Err(OptionError::new(
                "drift_reference",
                self.drift_reference,
                "0 (off) or an integer >= 2",
            ));
        }
        // The order-preserving solver needs closed contours: refused here rather than every
        // pair of a run skipped for it.
        if self.matching.solver == Some(assign::Method::Ordered)
            && self.model == ObjectModel::Surface
        {
            return Err(OptionError::new(
                "solver",
                "ordered",
                "jv, hungarian or simplex with the surface model (ordered keeps the cyclic order \
                 of closed contours)",
            ));
        }
        if let FrameStride::Every(every) = self.every {
            if every == 0 {
                return Err(OptionError::new(
                    "every",
                    every,
                    "auto or an integer >= 1 (1: every frame)",
                ));
            }
            // Reference frames must be frames the run keeps, or no object would reach one.
            if self.drift_reference >= 2 && !self.drift_reference.is_multiple_of(every) {
                return Err(OptionError::new(
                    "drift_reference",
                    self.drift_reference,
                    format!(
                        "0 (off) or a multiple of every ({every}), so that reference frames are \
                         frames run"
                    ),
                ));
            }
        }
        if self.surface_nodes < 8 {
            return Err(OptionError::new(
                "surface_nodes",
                self.surface_nodes,
                "an integer >= 8",
            ));
        }
        // A surface may keep its hull's corners beyond its budget; the budget itself must fit.
        if self.surface_nodes > self.matching.max_nodes {
            return Err(OptionError::new(
                "surface_nodes",
                self.surface_nodes,
                format!(
                    "at most max_nodes ({}), the most nodes an object may have",
                    self.matching.max_nodes
                ),
            ));
        }
        Ok(())
    }

    /// Checks every parameter and turns them into [`SequenceOptions`] for `recording` (whose
    /// units should already carry [`RunParams::units`], see [`pedo_io::units::UnitOverrides::apply`]).
    pub fn to_options(&self, recording: &Recording) -> Result<SequenceOptions> {
        self.validate()?;
        let matching = self.match_options()?;
        let n = recording.n_frames();
        let frames = self.frames.map(|r| r.resolve(n)).transpose()?;
        // The isocontour model's frame lies within the frames run, not only the recording.
        let iso_frame = match (self.iso_frame, frames) {
            (Some(f), None) if f >= n => {
                return Err(OptionError::new(
                    "iso_frame",
                    f,
                    format!("a frame in 0..{n} (0-based)"),
                )
                .into());
            }
            (Some(f), Some((start, end))) if !(start..end).contains(&f) => {
                // The range as resolved for this recording, and as given when that differs
                // (negative indices, an open end).
                let given = self.frames.map(|r| r.to_string()).unwrap_or_default();
                let resolved = format!("{start}..{end}");
                let as_given = if given == resolved {
                    String::new()
                } else {
                    format!(" (frames {given} of {n})")
                };
                return Err(OptionError::new(
                    "iso_frame",
                    f,
                    format!("a frame within frames {resolved}{as_given} (0-based), the frames run"),
                )
                .into());
            }
            (other, _) => other,
        };
        let noise = self.noise_threshold(recording);
        let sigma = (self.smooth > 0.0).then_some(self.smooth);
        let (start, end) = frames.unwrap_or((0, n));
        let rate = recording.dt_s.filter(|dt| *dt > 0.0).map(|dt| 1.0 / dt);
        // The isocontour model matches the levels of one frame: a stride would only change
        // which frame is the most loaded, so `auto` keeps every frame there.
        let every = match (self.model, self.every) {
            (ObjectModel::Isocontour, FrameStride::Auto) => 1,
            (_, every) => every.resolve(rate, end - start, self.drift_reference),
        };
        let mut o = SequenceOptions {
            model: self.model,
            matching,
            frames,
            every,
            iso_frame,
            iso_count: self.iso_levels,
            drift_reference: self.drift_reference,
            ..Default::default()
        };
        o.contour.preprocess.threshold = Some(noise);
        o.contour.preprocess.sigma = sigma;
        o.contour.resample = Resample::Spacing(self.spacing);
        o.surface.preprocess.threshold = Some(noise);
        o.surface.preprocess.sigma = sigma;
        o.surface.max_nodes = Some(self.surface_nodes);
        o.sensel_aspect = SenselAspect::of_pitch(recording.pitch_mm).0;
        if self.inputs.any() && self.model != ObjectModel::Contour {
            return Err(pedo_io::IoError::invalid(format!(
                "points and regions are followed on contact outlines: the contour model, not {}",
                self.model
            )));
        }
        o.inputs = crate::inputs::UserInputs::of(&self.inputs, recording)?;
        Ok(o)
    }

    /// The options of the contour run of `recording` with these parameters but the model
    /// (and without the user's points and regions): the contour field that carries the
    /// anatomical regions of a run of any model (a surface or isocontour run's made apart, with
    /// the contour model's matching options).
    pub fn contour_options(&self, recording: &Recording) -> Result<SequenceOptions> {
        RunParams {
            model: ObjectModel::Contour,
            inputs: Default::default(),
            ..self.clone()
        }
        .to_options(recording)
    }

    /// The noise threshold of a run of `recording`: [`noise`](Self::noise) when given, else the
    /// file's own, else 0 (values at or below it count as no contact).
    pub fn noise_threshold(&self, recording: &Recording) -> f64 {
        self.noise.or(recording.noise_threshold).unwrap_or(0.0)
    }

    /// Every option as actually used by `options` (from [`RunParams::to_options`]), defaults and
    /// the recording's values filled in: the matching options, then those of
    /// [`recording_option_specs`].
    pub fn used(
        &self,
        options: &SequenceOptions,
        recording: &Recording,
    ) -> Vec<(&'static str, OptionValue)> {
        let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
        let file = pedo_io::units::UnitOverrides {
            pitch_mm: recording.pitch_mm.map(pedo_io::units::Pitch),
            frame_rate: recording.dt_s.map(|dt| 1.0 / dt),
            units: recording.known_units().map(str::to_string),
            // As given: how the file's values were read.
            ..self.units.clone()
        };
        let every = FrameStride::Every(options.every);
        self.listed(options, FrameRange::new(start, end), every, file)
    }

    /// Every option as given to each recording of a study (`study.json`), listed as
    /// [`RunParams::used`] lists them, defaults included, but with the values each recording
    /// fills in from its file left as given: `frames` `0..` (to each recording's end) unless
    /// given, and `noise`, `pitch_mm`, `frame_rate` and `units` absent unless given (each
    /// recording's own; its `summary.json` has them).
    pub fn given(&self) -> std::result::Result<Vec<(&'static str, OptionValue)>, OptionError> {
        // The options `to_options` makes, but for the values that need a recording.
        let mut options = SequenceOptions {
            model: self.model,
            matching: self.match_options()?,
            iso_frame: self.iso_frame,
            drift_reference: self.drift_reference,
            ..Default::default()
        };
        options.contour.preprocess.threshold = self.noise;
        let file = pedo_io::units::UnitOverrides {
            // Spelled as the recordings will state them (`summary.json`).
            units: (self.units.units.as_deref()).map(pedo_io::recording::stated_units),
            ..self.units.clone()
        };
        Ok(self.listed(&options, self.frames.unwrap_or_default(), self.every, file))
    }

    /// The list of [`RunParams::used`] and [`RunParams::given`]: one list of the options for
    /// both, so that `summary.json` and `study.json` name the same options alike: the values
    /// `options` resolved, the frames run and the units of `file`, named and ordered by the
    /// declarations ([`MatchParams::used`], then `values()` of these parameters as resolved and
    /// of the units).
    fn listed(
        &self,
        options: &SequenceOptions,
        frames: FrameRange,
        every: FrameStride,
        file: pedo_io::units::UnitOverrides,
    ) -> Vec<(&'static str, OptionValue)> {
        let resolved = RunParams {
            matching: self.matching.clone(),
            units: file,
            model: options.model,
            frames: Some(frames),
            every,
            noise: options.contour.preprocess.threshold,
            smooth: self.smooth,
            spacing: self.spacing,
            surface_nodes: self.surface_nodes,
            iso_frame: options.iso_frame,
            iso_levels: self.iso_levels,
            drift_reference: options.drift_reference,
            inputs: self.inputs.clone(),
        };
        let mut v = self.matching.used(&options.matching);
        v.extend(resolved.values());
        v.extend(resolved.units.values());
        v.extend(self.inputs.values());
        v
    }
}

/// The options of a recording run beyond matching (`pedomatch run`/`demo`, `pymodal.run`), in
/// the order of [`RunParams`]' fields, then the unit options ([`pedo_io::units::unit_option_specs`])
/// and the points and regions to follow ([`crate::inputs::RunInputs`]).
pub fn recording_option_specs() -> Vec<OptionSpec> {
    let mut specs = RunParams::specs();
    specs.extend(pedo_io::units::unit_option_specs());
    specs.extend(crate::inputs::RunInputs::specs());
    specs
}

/// The options `recording` is run with: its units applied first (they set the frame interval
/// and sensel size the options are read in), and no affinity matrices kept (a run's outputs
/// need only each pair's matches).
pub fn run_options(
    recording: &mut Recording,
    params: &RunParams,
) -> pedo_io::Result<SequenceOptions> {
    params.units.apply(recording)?;
    let mut options = params.to_options(recording)?;
    options.keep_match_details = false;
    Ok(options)
}
