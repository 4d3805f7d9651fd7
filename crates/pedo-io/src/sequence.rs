//! Whole recordings: the objects of every frame, matched pair by pair, chained into node tracks.
//!
//! This is the job of Tables 1–3 of Tavares & Bastos (2005): for a contour or surface model, the objects of
//! consecutive frames (paired by [`crate::track`]) are matched; for the isocontour model, the
//! isobaric contours of one frame are matched level after level (docs/method.md §9). Each matched pair
//! yields one [`PairRow`] with the paper's columns, and the matches are chained into [`Track`]s.

use crate::cancel::Cancel;
use crate::contour::{contours, Contour, ContourOptions, Resample};
use crate::error::{IoError, Result};
use crate::recording::{FrameMeasures, Recording};
use crate::track::PairingMethod;
use modal_core::{
    match_prepared, match_shapes, prepare, AffinityMatrix, MatchOptions, MatchParams, MatchResult,
    ModalError, OptionError, OptionSpec, OptionValue, Parallelism, Prealign, PreparedShape, Search,
    Shape, Side, Topology,
};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

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
    pub surface: crate::surface::SurfaceOptions,
    /// Isocontour model: the frame (0-based index in the recording) whose isobaric contours are
    /// matched; `None`: the frame of largest total load (sum of its values) within
    /// [`frames`](Self::frames). A frame given here is not required to lie within `frames`, only
    /// within the recording (else [`run_sequence`] fails).
    pub iso_frame: Option<usize>,
    /// Isocontour model: the levels, in the recording's pressure units, in the order they are
    /// matched (level `k` with level `k + 1`); `None`: [`iso_count`](Self::iso_count) levels
    /// evenly spaced strictly between 0 and the peak of the thresholded frame
    /// ([`crate::isobar::even_levels`]).
    pub iso_levels: Option<Vec<f64>>,
    /// Isocontour model: the number of levels when [`iso_levels`](Self::iso_levels) is `None`.
    pub iso_count: usize,
    /// Objects with fewer nodes are left out (too small to model); never fewer than 3.
    pub min_nodes: usize,
    /// Frames `start..end` of the recording to use, 0-based with `end` excluded (`None`: all).
    /// The range must be non-empty and within the recording, else [`run_sequence`] and
    /// [`stream_sequence`] fail.
    pub frames: Option<(usize, usize)>,
    /// How each pair is matched. Default: [`MatchOptions::default`] without the outline fit
    /// (`rotation_search.outline_iterations` 0): a run's frames keep node-to-node ICP.
    pub matching: MatchOptions,
    /// Drift correction: reference frames every this many frames, each object also matched
    /// against its ancestor on the last reference frame ([`crate::drift`]); 0: off.
    pub drift_reference: usize,
    /// Keep each pair's whole [`MatchResult`] (affinity matrix, aligned nodes, local pairs).
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
    /// [`run_sequence`] and [`stream_sequence`] then fail with [`IoError::Cancelled`]
    /// ([`crate::cancel`]). `None`: the run goes to its end.
    pub cancel: Option<Cancel>,
}

impl SequenceOptions {
    /// Whether the run corrects the drift of its tracks: reference frames every
    /// [`drift_reference`](Self::drift_reference) ≥ 2 frames, for the contour and surface
    /// models (the isocontour model matches the levels of one frame, which have no drift).
    pub fn drift_corrected(&self) -> bool {
        self.drift_reference >= 2 && self.model != ObjectModel::Isocontour
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
            surface: crate::surface::SurfaceOptions {
                max_nodes: Some(120),
                ..Default::default()
            },
            iso_frame: None,
            iso_levels: None,
            iso_count: 10,
            min_nodes: 8,
            frames: None,
            matching: for_frames(MatchOptions::default()),
            drift_reference: 0,
            keep_match_details: true,
            sensel_aspect: 1.0,
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

/// Frames `start..end` of a recording: 0-based and half-open like a Python slice (`10..60` is
/// frames 10 to 59); an open end runs to the last frame, and a negative index counts back from
/// the end of the recording, as in Python (`-50..` is the last 50 frames, `0..-1` every frame
/// but the last). Written `START..END`, `START..` or `..END`. Negative indices are resolved by
/// [`FrameRange::resolve`] once the frame count is known.
///
/// ```
/// use pedo_io::sequence::FrameRange;
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

/// The user-facing parameters of a sequence run, shared by the CLI and the Python bindings:
/// the matching options and how each frame becomes objects. [`RunParams::to_options`] checks
/// them against a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct RunParams {
    /// How each pair is matched, as the user gave it; [`RunParams::match_options`] turns it into
    /// the engine's options for a run.
    pub matching: MatchParams,
    /// What each frame becomes: contours, a surface, or (one frame) isobaric contours.
    pub model: ObjectModel,
    /// Frames to use (`None`: all); negative indices count back from the end of each recording
    /// ([`FrameRange::resolve`], called by [`RunParams::to_options`]).
    pub frames: Option<FrameRange>,
    /// Noise threshold in the recording's units (`None`: the file's own, else 0).
    pub noise: Option<f64>,
    /// Gaussian smoothing σ in sensels (0: none).
    pub smooth: f64,
    /// Contour node spacing in sensels.
    pub spacing: f64,
    /// Node budget of each brightness surface.
    pub surface_nodes: usize,
    /// Isocontour model: the frame (0-based, within [`frames`](Self::frames) when given, else
    /// within the recording: [`RunParams::to_options`] fails otherwise; `None`: the frame of
    /// largest load among those run).
    pub iso_frame: Option<usize>,
    /// Isocontour model: the number of levels (at least 2), evenly spaced as
    /// [`SequenceOptions::iso_levels`] says.
    pub iso_levels: usize,
    /// Sensor pitch, frame rate and pressure units overriding the file's.
    pub units: crate::units::UnitOverrides,
    /// Drift correction: frames between reference frames (0: off); see [`crate::drift`].
    pub drift_reference: usize,
}

impl Default for RunParams {
    /// The defaults of [`SequenceOptions::default`] and [`MatchParams::default`], written there.
    fn default() -> Self {
        let d = SequenceOptions::default();
        let spacing = match d.contour.resample {
            Resample::Spacing(s) => s,
            _ => 1.0,
        };
        Self {
            matching: MatchParams::default(),
            model: d.model,
            frames: None,
            noise: None,
            smooth: d.contour.preprocess.sigma.unwrap_or(0.0),
            spacing,
            surface_nodes: d.surface.max_nodes.unwrap_or(120),
            iso_frame: d.iso_frame,
            iso_levels: d.iso_count,
            units: Default::default(),
            drift_reference: d.drift_reference,
        }
    }
}

impl RunParams {
    /// The engine's matching options for this run's object model: surfaces are unordered 3-D
    /// meshes and get the measured surface setting, contours and isocontours the contour recipe.
    /// Consecutive frames hardly turn: the rotation search is bounded by
    /// [`modal_core::options::RUN_MAX_ROTATION`] unless `max_rotation` is given. Consecutive
    /// contours share the sensor's coordinates: they are pre-aligned by
    /// [`modal_core::options::RUN_PREALIGN`] unless `prealign` or `paper` is given. Frames keep
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
        Ok(for_frames(o))
    }

    /// Whether a run with these parameters streams ([`streams`]): the contour and surface
    /// models without drift correction.
    pub fn streams(&self) -> bool {
        streamable(self.model, self.drift_reference)
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
        if self.surface_nodes < 8 {
            return Err(OptionError::new(
                "surface_nodes",
                self.surface_nodes,
                "an integer >= 8",
            ));
        }
        Ok(())
    }

    /// Checks every parameter and turns them into [`SequenceOptions`] for `recording` (whose
    /// units should already carry [`RunParams::units`], see [`crate::units::UnitOverrides::apply`]).
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
        let noise = self.noise.or(recording.noise_threshold).unwrap_or(0.0);
        let sigma = (self.smooth > 0.0).then_some(self.smooth);
        let mut o = SequenceOptions {
            model: self.model,
            matching,
            frames,
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
        Ok(o)
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
        self.listed(
            options,
            FileValues {
                frames: FrameRange::new(start, end),
                pitch_mm: recording.pitch_mm,
                frame_rate: recording.dt_s.map(|dt| 1.0 / dt),
                units: recording.known_units().map(str::to_string),
            },
        )
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
        Ok(self.listed(
            &options,
            FileValues {
                frames: self.frames.unwrap_or_default(),
                pitch_mm: self.units.pitch_mm,
                frame_rate: self.units.frame_rate,
                // Spelled as the recordings will state them (`summary.json`).
                units: self
                    .units
                    .units
                    .as_deref()
                    .map(crate::recording::stated_units),
            },
        ))
    }

    /// The list of [`RunParams::used`] and [`RunParams::given`]: one list of the options for
    /// both, so that `summary.json` and `study.json` name the same options alike.
    fn listed(
        &self,
        options: &SequenceOptions,
        file: FileValues,
    ) -> Vec<(&'static str, OptionValue)> {
        use OptionValue::{Absent, Float, Int, Numbers, Word};
        let mut v = self.matching.used(&options.matching);
        v.extend([
            ("model", Word(options.model.to_string())),
            ("frames", Word(file.frames.to_string())),
            (
                "noise",
                options.contour.preprocess.threshold.map_or(Absent, Float),
            ),
            ("smooth", Float(self.smooth)),
            ("spacing", Float(self.spacing)),
            ("surface_nodes", Int(self.surface_nodes)),
            ("iso_frame", options.iso_frame.map_or(Absent, Int)),
            ("iso_levels", Int(self.iso_levels)),
            ("drift_reference", Int(options.drift_reference)),
            (
                "pitch_mm",
                file.pitch_mm.map_or(Absent, |p| Numbers(p.to_vec())),
            ),
            ("frame_rate", file.frame_rate.map_or(Absent, Float)),
            ("units", file.units.map_or(Absent, Word)),
        ]);
        v
    }
}

/// The values of [`RunParams::listed`] that a recording sets: the frames run, and the pitch,
/// frame rate and pressure units (`None`: unknown, or left to each recording).
struct FileValues {
    frames: FrameRange,
    pitch_mm: Option<[f64; 2]>,
    frame_rate: Option<f64>,
    units: Option<String>,
}

/// The options of a recording run beyond matching (`pedomatch run`/`demo`, `pymodal.run`), in
/// the order of [`RunParams`]' fields, then the unit options ([`crate::units::unit_option_specs`]).
pub fn recording_option_specs() -> Vec<OptionSpec> {
    use modal_core::OptionKind::Value;
    let d = RunParams::default();
    let mut specs = vec![
        OptionSpec::choice(
            d.model,
            "Object model of each frame: closed contours of the loaded regions, brightness surfaces (pressure as height), or the isobaric contours of one frame matched level after level.",
        ),
        OptionSpec::new(
            "frames",
            Value,
            "all",
            "Frames START..END, 0-based with END excluded as in a Python slice (START.. and ..END allowed; a negative index counts back from the end: -50.. is the last 50 frames, 0..-1 all but the last); the range must lie within the recording.",
        ),
        OptionSpec::new(
            "noise",
            Value,
            "the file's noise threshold, else 0",
            "Noise threshold in the recording's pressure units: lower values count as no contact.",
        ),
        OptionSpec::new(
            "smooth",
            Value,
            d.smooth,
            "Gaussian smoothing of each frame, sigma in sensels (0: none; at most 1000).",
        ),
        OptionSpec::new(
            "spacing",
            Value,
            d.spacing,
            "Contour node spacing in sensels.",
        ),
        OptionSpec::new(
            "surface_nodes",
            Value,
            d.surface_nodes,
            "Node budget of each brightness surface.",
        ),
        OptionSpec::new(
            "iso_frame",
            Value,
            "the frame of largest load",
            "Isocontour model: the frame (0-based, within frames when given) whose isobaric contours are matched.",
        ),
        OptionSpec::new(
            "iso_levels",
            Value,
            d.iso_levels,
            "Isocontour model: the number of isobaric levels.",
        ),
        OptionSpec::new(
            "drift_reference",
            Value,
            d.drift_reference,
            "Drift correction of tracks: every this many frames is a reference frame, and each object is also matched against its ancestor on the last one; tracks follow those matches first (0: off).",
        ),
    ];
    specs.extend(crate::units::unit_option_specs());
    specs
}

/// One object of the sequence.
#[derive(Debug, Clone)]
pub struct SequenceObject {
    /// Identifier in sequence order: the object's index in [`SequenceResult::objects`].
    pub id: usize,
    /// Frame index (0-based) in the recording.
    pub frame: usize,
    /// Index of the object within its frame (or the level index for isocontours).
    pub index: usize,
    /// The isobaric level for isocontours, in the recording's pressure units; `None` for the
    /// other models.
    pub level: Option<f64>,
    /// The object's nodes, x = column and y = row in the units of the options (sensels unless
    /// [`ContourOptions::units`] or [`SurfaceOptions::units`](crate::surface::SurfaceOptions::units)
    /// say otherwise; always sensels from [`RunParams`]): a closed 2-D contour (contour and
    /// isocontour models) or a triangulated 3-D surface whose z is the rescaled pressure
    /// (surface model, see [`crate::surface::ZScale`]).
    pub shape: Shape,
    /// The measures of the sensors inside the object's outline (contour and isocontour models,
    /// [`Recording::region_measures`] with the contour threshold): one foot's contact area,
    /// force, peak pressure and centre of pressure in a recording of both feet. `None` for the
    /// surface model, whose one object per frame has the frame's measures.
    pub measures: Option<FrameMeasures>,
}

/// The two objects of a pair as the pairs table and `summary.json` name them: ids, frames and
/// node counts (the leading columns of a row, matched or skipped).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PairObjects {
    /// Id of the first object (its index in [`SequenceResult::objects`]).
    pub id_a: usize,
    /// Id of the second object (larger than `id_a`).
    pub id_b: usize,
    /// Frame of the first object (0-based).
    pub frame_a: usize,
    /// Frame of the second object (0-based; the same frame for isocontour levels).
    pub frame_b: usize,
    /// Number of nodes of the first object (`n`).
    pub nodes_a: usize,
    /// Number of nodes of the second object (`m`).
    pub nodes_b: usize,
}

impl PairObjects {
    /// The pair of `oa` and `ob`.
    pub fn of(oa: &SequenceObject, ob: &SequenceObject) -> Self {
        Self {
            id_a: oa.id,
            id_b: ob.id,
            frame_a: oa.frame,
            frame_b: ob.frame,
            nodes_a: oa.shape.len(),
            nodes_b: ob.shape.len(),
        }
    }
}

/// One row of the per-pair table: the paper's columns.
#[derive(Debug, Clone, PartialEq)]
pub struct PairRow {
    /// Which objects were matched.
    pub objects: PairObjects,
    /// Local (mutual-best) matches on the final affinity, whatever the search.
    pub local_matches: usize,
    /// `local_matches` as a percentage (0–100) of `min(n, m)`, the node counts of the two
    /// objects.
    pub local_percent: f64,
    /// Matches of the optimisation (global) search, excess matches aside: one-to-one except
    /// with [`Search::Best`]. 0 when the search is [`Search::Local`], which has no optimisation
    /// step.
    pub optimisation_matches: usize,
    /// `optimisation_matches` as a percentage (0–100) of `min(n, m)`.
    pub optimisation_percent: f64,
    /// Total matches after the excess-node step (one-to-one plus excess; the papers' "excess
    /// nodes matching" count).
    pub matches_after_excess: usize,
    /// Mean normalised modal cost ([`modal_core::MatchPair::cost`], in [0, 1]) of the matches
    /// that are not excess; 0 when there are none.
    pub mean_cost: f64,
    /// One-to-one matches that node tracks may follow: within the step rule of
    /// [`crate::track::step_allowed`] (`matches.csv`'s `trackable`). A one-to-one assignment
    /// pairs every node of the smaller object, so `optimisation_percent` is near 100 by
    /// construction; this says how many of those pairs a track may take.
    pub trackable_matches: usize,
    /// `trackable_matches` as a percentage (0–100) of `min(n, m)`.
    pub trackable_percent: f64,
}

/// Matches of one pair of objects (indices into [`SequenceResult::objects`]).
#[derive(Debug, Clone)]
pub struct PairMatch {
    /// The first object (earlier in sequence order: `a < b`).
    pub a: usize,
    /// The second object.
    pub b: usize,
    /// The engine's result; its node indices are those of the two objects' shapes. Without
    /// match details ([`SequenceOptions::keep_match_details`] off) only the pairs, unmatched
    /// nodes and transform are kept: the affinity matrix is 0 × 0 and `aligned_a` and
    /// `local_pairs` are empty.
    pub result: MatchResult,
    /// The pair's row of the pairs table.
    pub row: PairRow,
}

impl PairMatch {
    /// Fails unless the pair leads forward (`a < b`) onto an object of `onto`: the chaining of
    /// tracks visits objects in sequence order.
    pub(crate) fn check_forward(&self, onto: std::ops::Range<usize>) -> Result<()> {
        if self.a < self.b && onto.contains(&self.b) {
            return Ok(());
        }
        Err(IoError::invalid(format!(
            "pair {} → {} does not lead forward onto objects {}..{}",
            self.a, self.b, onto.start, onto.end
        )))
    }

    /// The error for match `m`, whose nodes lie beyond the two objects' `len_a` and `len_b`
    /// nodes.
    pub(crate) fn beyond_nodes(
        &self,
        m: &modal_core::MatchPair,
        len_a: usize,
        len_b: usize,
    ) -> IoError {
        IoError::invalid(format!(
            "pair {} → {} matches node {} to node {}, beyond the objects' {len_a} and {len_b} nodes",
            self.a, self.b, m.a, m.b
        ))
    }
}

/// One node followed across objects: `(object index, node index)` steps in sequence order.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// `(object index, node index)` of each step: the object an index into
    /// [`SequenceResult::objects`], the node an index into that object's shape. Objects
    /// increase along a track, which passes through one node per object at most; a track has
    /// at least one step.
    pub steps: Vec<(usize, usize)>,
}

/// Wall-clock time per stage.
#[derive(Debug, Clone, Copy, Default)]
pub struct StageTimings {
    /// Building the objects of every frame (reading the frames too, when streamed).
    pub objects: Duration,
    /// Matching the pairs (with drift correction, the pairs of consecutive frames only: the
    /// reference pairs count as chaining).
    pub matching: Duration,
    /// Chaining the matches into tracks.
    pub tracks: Duration,
}

/// The tracks of a run held compactly: the steps of every track one after the other, object and
/// node numbers as `u32`. A run without match details ([`SequenceOptions::keep_match_details`]
/// off: the CLI's and batch runs) keeps its tracks so, in [`SequenceResult::packed_tracks`]:
/// a long recording has hundreds of thousands of short tracks, each a vector of its own in
/// [`SequenceResult::tracks`].
#[derive(Debug, Clone, PartialEq)]
pub struct PackedTracks {
    /// Track `k` is `steps[starts[k]..starts[k + 1]]`.
    starts: Vec<usize>,
    steps: Vec<(u32, u32)>,
}

impl Default for PackedTracks {
    fn default() -> Self {
        Self {
            starts: vec![0],
            steps: Vec::new(),
        }
    }
}

impl PackedTracks {
    /// Appends a track.
    pub fn push(&mut self, track: &Track) {
        let small = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        self.steps
            .extend(track.steps.iter().map(|&(o, n)| (small(o), small(n))));
        self.starts.push(self.steps.len());
    }
    /// Number of tracks.
    pub fn len(&self) -> usize {
        self.starts.len() - 1
    }
    /// Whether there is no track.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Number of steps of track `k`.
    fn steps_of(&self, k: usize) -> usize {
        self.starts[k + 1] - self.starts[k]
    }
    /// Track `k`, if there is one.
    pub fn get(&self, k: usize) -> Option<Track> {
        (k < self.len()).then(|| Track {
            steps: self.steps[self.starts[k]..self.starts[k + 1]]
                .iter()
                .map(|&(o, n)| (o as usize, n as usize))
                .collect(),
        })
    }
    /// Every track, in order.
    pub fn iter(&self) -> impl Iterator<Item = Track> + '_ {
        (0..self.len()).filter_map(|k| self.get(k))
    }
    fn shrink_to_fit(&mut self) {
        self.starts.shrink_to_fit();
        self.steps.shrink_to_fit();
    }
}

impl FromIterator<Track> for PackedTracks {
    fn from_iter<I: IntoIterator<Item = Track>>(iter: I) -> Self {
        let mut p = PackedTracks::default();
        for t in iter {
            p.push(&t);
        }
        p.shrink_to_fit();
        p
    }
}

/// Everything [`run_sequence`] produces (`Default`: a run with nothing in it).
#[derive(Debug, Clone, Default)]
pub struct SequenceResult {
    /// Every object in sequence order (by frame, then by index within the frame; isocontours
    /// by level): object `i` has id `i`.
    pub objects: Vec<SequenceObject>,
    /// The matched pairs, in the order they were proposed (frame order); the pairs that could
    /// not be matched are in [`skipped_pairs`](Self::skipped_pairs) instead.
    pub pairs: Vec<PairMatch>,
    /// With drift correction ([`SequenceOptions::drift_corrected`]): the reference pairs
    /// matched, each object against its ancestor on the last reference frame
    /// ([`crate::drift::reference_pairs`]), in object order; a track steps through their
    /// matches first ([`crate::drift::anchored_tracks`]), so a step of a track need not be a
    /// match of [`pairs`](Self::pairs). [`reference_tracked`](Self::reference_tracked) says
    /// which matches a track took. Their rows ([`PairMatch::row`]) count trackable matches by
    /// the step rule of consecutive frames, which tracks do not apply to them. A reference pair
    /// that cannot be matched is left out (the tracks follow the predecessors there). Empty
    /// without drift correction.
    pub reference_pairs: Vec<PairMatch>,
    /// The tracks, unless they are in [`packed_tracks`](Self::packed_tracks) (runs without
    /// match details): read them with [`all_tracks`](Self::all_tracks) to cover both.
    pub tracks: Vec<Track>,
    /// Runs without match details ([`SequenceOptions::keep_match_details`] off) hold their
    /// tracks here, packed, and leave [`tracks`](Self::tracks) empty.
    pub packed_tracks: Option<PackedTracks>,
    /// Contour model: object `i` continues as several objects of the next frame (object
    /// indices).
    pub splits: Vec<(usize, Vec<usize>)>,
    /// Contour model: several objects continue as one object of the next frame (object
    /// indices).
    pub merges: Vec<(Vec<usize>, usize)>,
    /// Frames whose objects could not be built, with the reason; the run goes on without them.
    pub skipped_frames: Vec<SkippedFrame>,
    /// Pairs that could not be matched (degenerate objects, a structure with too many
    /// zero-energy modes, ...), with the reason; the run goes on without them.
    pub skipped_pairs: Vec<SkippedPair>,
    /// Wall-clock time of each stage.
    pub timings: StageTimings,
}

/// A frame left out of a run: its objects could not be built (for isocontours, one entry per
/// isobaric level of the frame that gives no object, the level in the reason).
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedFrame {
    /// Frame index (0-based) in the recording.
    pub frame: usize,
    /// The error, as one line.
    pub reason: String,
}

/// A pair of objects (indices into [`SequenceResult::objects`]) that could not be matched.
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedPair {
    /// The first object.
    pub a: usize,
    /// The second object.
    pub b: usize,
    /// The matching error, as one line.
    pub reason: String,
}

/// What [`run_sequence`] and [`stream_sequence`] report to a progress callback
/// `progress(stage, done, total)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Building the objects: `done` of `total` frames, or of `total` isobaric levels for the
    /// isocontour model. Not reported by a run that [`stream_sequence`] streams ([`streams`]).
    Objects,
    /// Matching: `done` of `total` pairs ([`run_sequence`]), or of `total` frames (a run that
    /// [`stream_sequence`] streams, which reports no [`Stage::Objects`]).
    Matching,
}

impl SequenceResult {
    /// Every track in order, from [`tracks`](Self::tracks) or, packed, one at a time from
    /// [`packed_tracks`](Self::packed_tracks).
    pub fn all_tracks(&self) -> Box<dyn Iterator<Item = std::borrow::Cow<'_, Track>> + '_> {
        match &self.packed_tracks {
            Some(p) => Box::new(p.iter().map(std::borrow::Cow::Owned)),
            None => Box::new(self.tracks.iter().map(std::borrow::Cow::Borrowed)),
        }
    }

    /// Number of tracks (held or packed).
    pub fn track_count(&self) -> usize {
        self.packed_tracks
            .as_ref()
            .map_or(self.tracks.len(), PackedTracks::len)
    }

    /// Number of steps of every track, in order (held or packed).
    pub fn track_lengths(&self) -> Box<dyn Iterator<Item = usize> + '_> {
        match &self.packed_tracks {
            Some(p) => Box::new((0..p.len()).map(|k| p.steps_of(k))),
            None => Box::new(self.tracks.iter().map(|t| t.steps.len())),
        }
    }

    /// For each of the [`reference_pairs`](Self::reference_pairs), in order, and each of its
    /// matches (`result.pairs`, in order): whether a track took it, i.e. the match is not an
    /// excess match and its two nodes are on the same track. Such a track reached the node of
    /// the second object through this match, from its step on the first object (an earlier
    /// step of the same track, on the reference frame).
    pub fn reference_tracked(&self) -> Vec<Vec<bool>> {
        if self.reference_pairs.is_empty() {
            return Vec::new();
        }
        let track_of = self.track_of_nodes();
        let on = |o: usize, n: usize| {
            track_of
                .get(o)
                .and_then(|row| row.get(n))
                .copied()
                .flatten()
        };
        self.reference_pairs
            .iter()
            .map(|p| {
                p.result
                    .pairs
                    .iter()
                    .map(|m| !m.excess && on(p.a, m.a).is_some_and(|t| Some(t) == on(p.b, m.b)))
                    .collect()
            })
            .collect()
    }

    /// The track of every node, by object and node (`None`: on no track, which a run's own
    /// tracks never leave).
    fn track_of_nodes(&self) -> Vec<Vec<Option<usize>>> {
        let mut track_of: Vec<Vec<Option<usize>>> = self
            .objects
            .iter()
            .map(|o| vec![None; o.shape.len()])
            .collect();
        for (k, t) in self.all_tracks().enumerate() {
            for &(o, n) in &t.steps {
                if let Some(slot) = track_of.get_mut(o).and_then(|row| row.get_mut(n)) {
                    *slot = Some(k);
                }
            }
        }
        track_of
    }

    /// Coordinates of the steps of `track` as `(frame, x, y[, z])` rows.
    pub fn track_points(&self, track: &Track) -> Vec<(usize, Vec<f64>)> {
        track
            .steps
            .iter()
            .map(|&(o, n)| {
                let obj = &self.objects[o];
                (obj.frame, obj.shape.point(n).to_vec())
            })
            .collect()
    }
}

/// A pair that could not be matched, as the pairs table and `summary.json` report it.
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedPairRow {
    /// Which objects could not be matched.
    pub objects: PairObjects,
    /// The matching error, as one line.
    pub reason: String,
}

impl SkippedPairRow {
    /// The row of skipped pair `s` of run `r`.
    pub fn of(r: &SequenceResult, s: &SkippedPair) -> Self {
        Self::of_objects(&r.objects[s.a], &r.objects[s.b], &s.reason)
    }

    fn of_objects(oa: &SequenceObject, ob: &SequenceObject, reason: &str) -> Self {
        Self {
            objects: PairObjects::of(oa, ob),
            reason: reason.to_string(),
        }
    }
}

/// What a run's summary needs of it: counts, sums and what was left out, without the objects,
/// matches and tracks themselves. [`stream_sequence`] returns it; [`RunCounts::of`] reads it
/// off a whole [`SequenceResult`]. Object ids are their indices.
#[derive(Debug, Clone)]
pub struct RunCounts {
    /// Objects built.
    pub objects: usize,
    /// Pairs matched (the skipped ones aside).
    pub pairs: usize,
    /// Sum over the matched pairs, in order, of [`PairRow::local_percent`].
    pub local_percent_sum: f64,
    /// Sum over the matched pairs, in order, of [`PairRow::optimisation_percent`].
    pub optimisation_percent_sum: f64,
    /// Sum over the matched pairs, in order, of [`PairRow::mean_cost`].
    pub cost_sum: f64,
    /// Sum over the matched pairs, in order, of [`PairRow::trackable_percent`].
    pub trackable_percent_sum: f64,
    /// Tracks chained.
    pub tracks: usize,
    /// Tracks of 3 steps or more.
    pub tracks_3_or_more: usize,
    /// As [`SequenceResult::splits`].
    pub splits: Vec<(usize, Vec<usize>)>,
    /// As [`SequenceResult::merges`].
    pub merges: Vec<(Vec<usize>, usize)>,
    /// As [`SequenceResult::skipped_frames`].
    pub skipped_frames: Vec<SkippedFrame>,
    /// The skipped pairs as the pairs table reports them.
    pub skipped_pairs: Vec<SkippedPairRow>,
    /// Wall-clock time of each stage.
    pub timings: StageTimings,
}

impl Default for RunCounts {
    fn default() -> Self {
        // The sums start as `Iterator::sum` starts, so that adding the pairs one by one gives
        // the sum of the whole list to the last bit.
        let zero = || std::iter::empty::<f64>().sum::<f64>();
        Self {
            objects: 0,
            pairs: 0,
            local_percent_sum: zero(),
            optimisation_percent_sum: zero(),
            cost_sum: zero(),
            trackable_percent_sum: zero(),
            tracks: 0,
            tracks_3_or_more: 0,
            splits: Vec::new(),
            merges: Vec::new(),
            skipped_frames: Vec::new(),
            skipped_pairs: Vec::new(),
            timings: StageTimings::default(),
        }
    }
}

impl RunCounts {
    /// The counts of a whole run.
    pub fn of(r: &SequenceResult) -> Self {
        let mut c = RunCounts {
            objects: r.objects.len(),
            splits: r.splits.clone(),
            merges: r.merges.clone(),
            skipped_frames: r.skipped_frames.clone(),
            skipped_pairs: r
                .skipped_pairs
                .iter()
                .map(|s| SkippedPairRow::of(r, s))
                .collect(),
            timings: r.timings,
            ..Default::default()
        };
        for p in &r.pairs {
            c.add_pair(&p.row);
        }
        for n in r.track_lengths() {
            c.add_track(n);
        }
        c
    }

    fn add_pair(&mut self, row: &PairRow) {
        self.pairs += 1;
        self.local_percent_sum += row.local_percent;
        self.optimisation_percent_sum += row.optimisation_percent;
        self.cost_sum += row.mean_cost;
        self.trackable_percent_sum += row.trackable_percent;
    }

    fn add_track(&mut self, steps: usize) {
        self.tracks += 1;
        if steps >= 3 {
            self.tracks_3_or_more += 1;
        }
    }

    /// `None` without pairs: a mean over nothing is not a number to report.
    fn mean(&self, sum: f64) -> Option<f64> {
        (self.pairs > 0).then(|| sum / self.pairs as f64)
    }
    /// Mean local matches over the matched pairs, in % (`None` without pairs).
    pub fn mean_local_percent(&self) -> Option<f64> {
        self.mean(self.local_percent_sum)
    }
    /// Mean optimisation matches over the matched pairs, in % (`None` without pairs).
    pub fn mean_optimisation_percent(&self) -> Option<f64> {
        self.mean(self.optimisation_percent_sum)
    }
    /// Mean over the matched pairs of their mean cost (`None` without pairs).
    pub fn mean_cost(&self) -> Option<f64> {
        self.mean(self.cost_sum)
    }
    /// Mean trackable matches over the matched pairs, in % (`None` without pairs).
    pub fn mean_trackable_percent(&self) -> Option<f64> {
        self.mean(self.trackable_percent_sum)
    }
}

/// Where [`stream_sequence`] reads frames from when the recording it is given holds none of
/// their values (see [`crate::formats::read_for_streaming`]).
pub trait FrameSource {
    /// Frames `w0..w1` of `recording` as a recording of `w1 - w0` frames with its size, mask
    /// and units. Windows are asked for in order.
    fn window(&mut self, recording: &Recording, w0: usize, w1: usize) -> Result<Recording>;
}

/// Where [`stream_sequence`] hands a run's results as they are made, each kind in the order of
/// the [`SequenceResult`] that [`run_sequence`] would return.
pub trait SequenceSink {
    /// The measures of frames `first..first + measures.len()` (counting values above the
    /// run's noise threshold, as the frames table does), in frame order, once each.
    fn frames(&mut self, first: usize, measures: &[crate::recording::FrameMeasures]) -> Result<()>;
    /// An object, in id order.
    fn object(&mut self, object: &SequenceObject) -> Result<()>;
    /// A matched pair with its two objects, in the order of [`SequenceResult::pairs`].
    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()>;
    /// Track number `index` (in order from 0): its steps as object and node.
    fn track(&mut self, index: usize, steps: &[(&SequenceObject, usize)]) -> Result<()>;
    /// A reference pair of drift correction with its two objects, in the order of
    /// [`SequenceResult::reference_pairs`], after every track; `tracked` as
    /// [`SequenceResult::reference_tracked`] gives it for this pair. A run without drift
    /// correction hands none.
    fn reference_pair(
        &mut self,
        pair: &PairMatch,
        a: &SequenceObject,
        b: &SequenceObject,
        tracked: &[bool],
    ) -> Result<()>;
}

/// Frames whose objects are built, matched and chained at a time by [`stream_sequence`].
pub const FRAME_WINDOW: usize = 64;

/// [`run_sequence`] without holding the run: the frames go in windows of [`FRAME_WINDOW`];
/// each window's objects are built, handed to `sink`, their pairs matched and handed over,
/// their matches chained into tracks and each track handed over as soon as it has ended and
/// every track before it has gone. Only the open tracks and the objects they pass through are
/// held, so memory does not grow with the recording's length (only with its longest track).
/// Contour and surface models without drift correction; the isocontour model (one frame) and
/// drift correction (reference pairs across windows) run whole and are handed over after.
/// The results handed to `sink` are those of [`run_sequence`] with the same options (with
/// [`SequenceOptions::keep_match_details`] off: the pairs hold only their matches);
/// `progress` reports [`Stage::Matching`] in frames done.
pub fn stream_sequence(
    recording: &Recording,
    mut source: Option<&mut dyn FrameSource>,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
    sink: &mut dyn SequenceSink,
) -> Result<RunCounts> {
    let measures_threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    if !streams(options) {
        if source.is_some() {
            return Err(IoError::invalid(
                "this run needs the whole recording (isocontour model or drift correction)",
            ));
        }
        let r = run_sequence(recording, options, progress)?;
        let counts = replay(&r, sink)?;
        sink.frames(
            start,
            &recording.measures_of(measures_threshold, start..end),
        )?;
        return Ok(counts);
    }
    if start >= end || end > recording.n_frames() {
        return Err(IoError::invalid(format!(
            "frame range {start}..{end} is empty or beyond the {} of the recording",
            crate::report::counted(recording.n_frames(), "frame")
        )));
    }
    let mut options = options.clone();
    options.keep_match_details = false;
    let options = &options;
    let mut counts = RunCounts::default();
    let mut held = Held::default();
    let mut chain = Chainer::default();
    // The last frame built: its first object and (contour model) its contours, or (surface
    // model) its object, if any.
    let mut last_contours: Option<(usize, Vec<Contour>)> = None;
    let mut last_surface: Option<(usize, usize)> = None;
    let threshold = options.surface.preprocess.threshold.unwrap_or(0.0);
    let keep = |s: &Shape| s.len() >= options.min_nodes.max(3);
    let mut w0 = start;
    while w0 < end {
        let w1 = (w0 + FRAME_WINDOW).min(end);
        let t0 = Instant::now();
        // The window's frames: those of `recording`, or read from `source` (numbered from w0).
        let read = match source.as_mut() {
            Some(s) => Some(s.window(recording, w0, w1)?),
            None => None,
        };
        let (frames, offset) = match &read {
            Some(r) => (r, w0),
            None => (recording, 0),
        };
        let first_new = held.end();
        // The window's candidate pairs (ids), splits and merges.
        let mut candidates: Vec<(usize, usize)> = Vec::new();
        let (mut splits, mut merges) = (Vec::new(), Vec::new());
        match options.model {
            ObjectModel::Contour => {
                let per_frame: Vec<FrameObjects> = per_frame_or_skipped(
                    w0..w1,
                    &mut counts.skipped_frames,
                    options.cancel.as_ref(),
                    |t| frame_contours(frames, t - offset, options),
                )?;
                for (k, (cs, shapes)) in per_frame.into_iter().enumerate() {
                    let first = held.end();
                    for (index, (shape, measures)) in shapes.into_iter().enumerate() {
                        held.push(SequenceObject {
                            id: held.end(),
                            frame: w0 + k,
                            index,
                            level: None,
                            shape,
                            measures: Some(measures),
                        });
                    }
                    if let Some((fa, previous)) = &last_contours {
                        let (fa, fb) = (*fa, first);
                        let p =
                            crate::track::pair_contours(previous, &cs, PairingMethod::default())?;
                        candidates.extend(p.pairs.iter().map(|&(i, j)| (fa + i, fb + j)));
                        splits.extend(
                            p.splits
                                .iter()
                                .map(|(i, js)| (fa + i, js.iter().map(|j| fb + j).collect())),
                        );
                        merges.extend(
                            p.merges
                                .iter()
                                .map(|(is, j)| (is.iter().map(|i| fa + i).collect(), fb + j)),
                        );
                    }
                    last_contours = Some((first, cs));
                }
            }
            ObjectModel::Surface | ObjectModel::Isocontour => {
                let per_frame: Vec<Option<Shape>> = per_frame_or_skipped(
                    w0..w1,
                    &mut counts.skipped_frames,
                    options.cancel.as_ref(),
                    |t| frame_surface(frames, t - offset, threshold, options, &keep),
                )?;
                for (k, shape) in per_frame.into_iter().enumerate() {
                    let frame = w0 + k;
                    match shape {
                        Some(shape) => {
                            let o = held.end();
                            if let Some((p, pf)) = last_surface
                                && pf + 1 == frame
                            {
                                candidates.push((p, o));
                            }
                            held.push(SequenceObject {
                                id: o,
                                frame,
                                index: 0,
                                level: None,
                                shape,
                                measures: None,
                            });
                            last_surface = Some((o, frame));
                        }
                        None => last_surface = None,
                    }
                }
            }
        }
        sink.frames(
            w0,
            &frames.measures_of(measures_threshold, w0 - offset..w1 - offset),
        )?;
        drop(read);
        for id in first_new..held.end() {
            sink.object(held.get(id)?)?;
        }
        counts.objects = held.end();
        let t1 = Instant::now();

        // The window's pairs, matched on the held objects (numbered from `held.base`).
        let base = held.base;
        let local = |id: usize| id - base;
        let local_candidates: Vec<(usize, usize)> = candidates
            .iter()
            .map(|&(a, b)| (local(a), local(b)))
            .collect();
        let local_splits: Vec<(usize, Vec<usize>)> = splits
            .iter()
            .map(|(i, js): &(usize, Vec<usize>)| {
                (local(*i), js.iter().map(|&j| local(j)).collect())
            })
            .collect();
        let local_merges: Vec<(Vec<usize>, usize)> = merges
            .iter()
            .map(|(is, j): &(Vec<usize>, usize)| {
                (is.iter().map(|&i| local(i)).collect(), local(*j))
            })
            .collect();
        let parts = parts_of_wholes(&local_candidates, &local_splits, &local_merges);
        let objects = held.objects.make_contiguous();
        let (mut pairs, skipped) =
            match_all(objects, &local_candidates, &parts, options, &|_, _, _| {});
        crate::cancel::check(options.cancel.as_ref())?;
        for p in &mut pairs {
            p.a += base;
            p.b += base;
        }
        for s in skipped {
            let (oa, ob) = (held.get(s.a + base)?, held.get(s.b + base)?);
            counts
                .skipped_pairs
                .push(SkippedPairRow::of_objects(oa, ob, &s.reason));
        }
        for p in &pairs {
            sink.pair(p, held.get(p.a)?, held.get(p.b)?)?;
            counts.add_pair(&p.row);
        }
        counts.splits.extend(splits);
        counts.merges.extend(merges);
        let t2 = Instant::now();

        // Every pair leaving an object before the window's last frame is known now.
        let last_first = match options.model {
            ObjectModel::Contour => last_contours.as_ref().map_or(held.end(), |l| l.0),
            _ => last_surface.map_or(held.end(), |l| l.0),
        };
        chain.chain(
            &held,
            first_new..held.end(),
            &pairs,
            last_first,
            &mut |k, track| {
                counts.add_track(track.steps.len());
                sink.track(k, &held_steps(&held, &track)?)
            },
        )?;
        drop(pairs);
        // The objects before both the first open track and the last frame are done.
        held.drop_below(chain.first_object().unwrap_or(usize::MAX).min(last_first));
        let t3 = Instant::now();
        counts.timings.objects += t1 - t0;
        counts.timings.matching += t2 - t1;
        counts.timings.tracks += t3 - t2;
        progress(Stage::Matching, w1 - start, end - start);
        w0 = w1;
    }
    let t = Instant::now();
    chain.finish(&mut |k, track| {
        counts.add_track(track.steps.len());
        sink.track(k, &held_steps(&held, &track)?)
    })?;
    counts.timings.tracks += t.elapsed();
    Ok(counts)
}

/// Whether [`stream_sequence`] streams a run with these options (the contour and surface
/// models without drift correction) rather than running it whole.
pub fn streams(options: &SequenceOptions) -> bool {
    streamable(options.model, options.drift_reference)
}

/// The rule of [`streams`] and [`RunParams::streams`]: the isocontour model matches the levels
/// of one frame, and drift correction pairs frames across windows, so both run whole.
fn streamable(model: ObjectModel, drift_reference: usize) -> bool {
    model != ObjectModel::Isocontour && drift_reference < 2
}

/// Hands a whole run to `sink`, as [`stream_sequence`] would have (the frames' measures
/// aside), its reference pairs last, and returns its counts.
pub fn replay(r: &SequenceResult, sink: &mut dyn SequenceSink) -> Result<RunCounts> {
    for o in &r.objects {
        sink.object(o)?;
    }
    for p in &r.pairs {
        sink.pair(p, &r.objects[p.a], &r.objects[p.b])?;
    }
    for (k, t) in r.all_tracks().enumerate() {
        let steps: Vec<(&SequenceObject, usize)> =
            t.steps.iter().map(|&(o, n)| (&r.objects[o], n)).collect();
        sink.track(k, &steps)?;
    }
    for (p, tracked) in r.reference_pairs.iter().zip(r.reference_tracked()) {
        sink.reference_pair(p, &r.objects[p.a], &r.objects[p.b], &tracked)?;
    }
    Ok(RunCounts::of(r))
}

/// The objects of a streamed run still needed: ids `base..base + objects.len()`.
#[derive(Default)]
struct Held {
    base: usize,
    objects: std::collections::VecDeque<SequenceObject>,
}

impl Held {
    /// One past the last object's id.
    fn end(&self) -> usize {
        self.base + self.objects.len()
    }
    fn push(&mut self, o: SequenceObject) {
        self.objects.push_back(o);
    }
    fn get(&self, id: usize) -> Result<&SequenceObject> {
        id.checked_sub(self.base)
            .and_then(|k| self.objects.get(k))
            .ok_or_else(|| {
                IoError::invalid(format!(
                    "internal error (please report it): object {id} no longer held"
                ))
            })
    }
    /// Lets go of the objects before `id`.
    fn drop_below(&mut self, id: usize) {
        while self.base < id && self.objects.pop_front().is_some() {
            self.base += 1;
        }
    }
}

/// A track's steps with their objects, as a [`SequenceSink`] takes them.
fn held_steps<'h>(held: &'h Held, track: &Track) -> Result<Vec<(&'h SequenceObject, usize)>> {
    track
        .steps
        .iter()
        .map(|&(o, n)| held.get(o).map(|obj| (obj, n)))
        .collect()
}

/// The objects [`Chainer`] reads by id: a whole run's, or the window a stream holds.
trait ObjectsById {
    fn object(&self, id: usize) -> Result<&SequenceObject>;
}

impl ObjectsById for Held {
    fn object(&self, id: usize) -> Result<&SequenceObject> {
        self.get(id)
    }
}

impl ObjectsById for [SequenceObject] {
    fn object(&self, id: usize) -> Result<&SequenceObject> {
        self.get(id).ok_or_else(|| {
            IoError::invalid(format!(
                "a pair names object {id}, beyond the {} objects chained",
                self.len()
            ))
        })
    }
}

/// Chains pair matches into tracks ([`chain_tracks`]), fed all at once (a whole run) or a
/// window at a time ([`stream_sequence`]); only the open tracks are held.
#[derive(Default)]
struct Chainer {
    /// The number of the front pending track.
    first: usize,
    /// The tracks not handed over yet, each with whether it has ended.
    pending: std::collections::VecDeque<(Track, bool)>,
    /// The track of each node of the objects a pair may still leave (`NO_TRACK`: none).
    rows: std::collections::BTreeMap<usize, Vec<u32>>,
    /// The last object a known pair leaves each object of `rows` for.
    last_use: HashMap<usize, usize>,
}

const NO_TRACK: u32 = u32::MAX;

/// Where [`Chainer`] hands each track: its number and the track.
type EmitTrack<'a> = dyn FnMut(usize, Track) -> Result<()> + 'a;

impl Chainer {
    /// The first object of the front open track (all objects before it are done with).
    fn first_object(&self) -> Option<usize> {
        self.pending
            .front()
            .and_then(|(t, _)| t.steps.first())
            .map(|s| s.0)
    }

    /// Ends the tracks of `row` whose last step is on object `x`.
    fn end_at(&mut self, x: usize, row: &[u32]) {
        for &t in row {
            let t = t as usize;
            if t >= self.first
                && let Some((track, ended)) = self.pending.get_mut(t - self.first)
                && track.steps.last().map(|s| s.0) == Some(x)
            {
                *ended = true;
            }
        }
    }

    /// Chains the objects `new` through `pairs` (those that end on them, in order). Every pair
    /// leaving an object before `settled` is among those given so far.
    fn chain(
        &mut self,
        objects: &(impl ObjectsById + ?Sized),
        new: std::ops::Range<usize>,
        pairs: &[PairMatch],
        settled: usize,
        emit: &mut EmitTrack<'_>,
    ) -> Result<()> {
        let mut incoming: Vec<Vec<&PairMatch>> = vec![Vec::new(); new.len()];
        for p in pairs {
            // Objects are in sequence order and every pair goes forward, so visiting the
            // objects in order sees each predecessor before its successors.
            p.check_forward(new.clone())?;
            incoming[p.b - new.start].push(p);
            let u = self.last_use.entry(p.a).or_insert(0);
            *u = (*u).max(p.b);
        }
        // Objects of earlier windows that no pair leaves end their tracks.
        let idle: Vec<usize> = self
            .rows
            .keys()
            .copied()
            .filter(|x| *x < new.start && !self.last_use.contains_key(x))
            .collect();
        for x in idle {
            if let Some(row) = self.rows.remove(&x) {
                self.end_at(x, &row);
            }
        }
        for o in new.clone() {
            let row = self.continue_tracks(objects, o, &incoming[o - new.start])?;
            // A predecessor whose last pair this was ends the tracks still ending on it; so
            // does this object when no pair leaves it.
            for p in &incoming[o - new.start] {
                if self.last_use.get(&p.a) == Some(&o) {
                    self.last_use.remove(&p.a);
                    if let Some(done) = self.rows.remove(&p.a) {
                        self.end_at(p.a, &done);
                    }
                }
            }
            if o >= settled || self.last_use.get(&o).is_some_and(|&u| u > o) {
                self.rows.insert(o, row);
            } else {
                self.end_at(o, &row);
            }
            self.emit_ended(emit)?;
        }
        Ok(())
    }

    /// The track of each node of object `o`: the track its one-to-one partner in a predecessor
    /// (`incoming`, in order) is on, or a new one.
    fn continue_tracks(
        &mut self,
        objects: &(impl ObjectsById + ?Sized),
        o: usize,
        incoming: &[&PairMatch],
    ) -> Result<Vec<u32>> {
        let id = |t: usize| u32::try_from(t).unwrap_or(NO_TRACK - 1);
        let ob = objects.object(o)?;
        let mut row = vec![NO_TRACK; ob.shape.len()];
        for p in incoming {
            let oa = objects.object(p.a)?;
            let Some(from) = self.rows.get(&p.a) else {
                continue;
            };
            for mp in p.result.pairs.iter().filter(|mp| !mp.excess) {
                let (Some(&t), Some(&slot)) = (from.get(mp.a), row.get(mp.b)) else {
                    return Err(p.beyond_nodes(mp, from.len(), row.len()));
                };
                if slot != NO_TRACK || !honest_step_of(oa, mp.a, ob, mp.b) {
                    continue;
                }
                let t = t as usize;
                // A track can pass through one node per object only: a split keeps the first
                // continuation. (A track already handed over has ended elsewhere.)
                if t >= self.first
                    && let Some((track, _)) = self.pending.get_mut(t - self.first)
                    && track.steps.last().map(|s| s.0) == Some(p.a)
                {
                    track.steps.push((o, mp.b));
                    row[mp.b] = id(t);
                }
            }
        }
        for (node, slot) in row.iter_mut().enumerate() {
            if *slot == NO_TRACK {
                *slot = id(self.first + self.pending.len());
                self.pending.push_back((
                    Track {
                        steps: vec![(o, node)],
                    },
                    false,
                ));
            }
        }
        Ok(row)
    }

    /// Hands over the front tracks that have ended.
    fn emit_ended(&mut self, emit: &mut EmitTrack<'_>) -> Result<()> {
        while self.pending.front().is_some_and(|(_, ended)| *ended) {
            if let Some((mut track, _)) = self.pending.pop_front() {
                track.steps.shrink_to_fit();
                self.first += 1;
                emit(self.first - 1, track)?;
            }
        }
        Ok(())
    }

    /// Hands over every track left.
    fn finish(&mut self, emit: &mut EmitTrack<'_>) -> Result<()> {
        for (_, ended) in &mut self.pending {
            *ended = true;
        }
        self.rows.clear();
        self.last_use.clear();
        self.emit_ended(emit)
    }
}

/// Builds the objects of the recording, matches them pair by pair (in parallel) and chains the
/// matches into tracks. `progress(stage, done, total)` is called as work completes, possibly
/// from several threads.
///
/// A frame whose objects cannot be built and a pair that cannot be matched do not fail the run:
/// they are reported in [`SequenceResult::skipped_frames`] and
/// [`SequenceResult::skipped_pairs`].
///
/// # Errors
///
/// [`IoError::InvalidInput`] when [`SequenceOptions::frames`] is empty or reaches past the
/// recording, or the isocontour frame is not in the recording; errors of the isocontour
/// model's options (levels, preprocessing) and of the contour pairing.
///
/// ```
/// use pedo_io::sequence::{run_sequence, FrameRange, RunParams};
/// use pedo_io::synthetic::SyntheticWalk;
/// let recording = SyntheticWalk::default().recording()?;
/// // The first 3 frames: one foot outline each, matched 0 → 1 → 2.
/// let params = RunParams {
///     frames: Some(FrameRange { start: 0, end: Some(3) }),
///     ..RunParams::default()
/// };
/// let options = params.to_options(&recording)?;
/// let run = run_sequence(&recording, &options, &|_, _, _| {})?;
/// assert_eq!(run.objects.len(), 3);
/// assert_eq!((run.pairs[0].a, run.pairs[0].b), (0, 1));
/// assert_eq!(run.pairs.len(), 2);
/// // Every node of frame 0 starts a track; most of them go on through frames 1 and 2.
/// let from_0 = run.tracks.iter().filter(|t| t.steps[0].0 == 0).count();
/// assert_eq!(from_0, run.objects[0].shape.len());
/// let through = run.tracks.iter().filter(|t| t.steps.len() == 3).count();
/// assert!(through * 10 >= from_0 * 9, "{through} of {from_0}");
/// # Ok::<(), pedo_io::IoError>(())
/// ```
pub fn run_sequence(
    recording: &Recording,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<SequenceResult> {
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    if start >= end || end > recording.n_frames() {
        return Err(IoError::invalid(format!(
            "frame range {start}..{end} is empty or beyond the {} of the recording",
            crate::report::counted(recording.n_frames(), "frame")
        )));
    }
    let t0 = Instant::now();
    let Built {
        objects,
        pairs: candidate_pairs,
        splits,
        merges,
        skipped_frames,
    } = build_objects(recording, options, start, end, progress)?;
    let t1 = Instant::now();

    let parts = parts_of_wholes(&candidate_pairs, &splits, &merges);
    let (pairs, skipped_pairs) = match_all(&objects, &candidate_pairs, &parts, options, progress);
    // A cancelled run's pairs are incomplete (those not matched are skipped as "cancelled").
    crate::cancel::check(options.cancel.as_ref())?;
    let t2 = Instant::now();
    let reference_pairs = if options.drift_corrected() {
        reference_matches(&objects, &candidate_pairs, start, options)
    } else {
        Vec::new()
    };
    let drift_tracks = || crate::drift::anchored_tracks(&objects, &pairs, &reference_pairs);
    let (tracks, packed_tracks) = match (options.drift_corrected(), options.keep_match_details) {
        (true, true) => (drift_tracks()?, None),
        (true, false) => (Vec::new(), Some(drift_tracks()?.into_iter().collect())),
        (false, true) => (chain_tracks(&objects, &pairs)?, None),
        (false, false) => {
            // Packed as they are chained: the tracks of a long run are never all held as
            // vectors of their own.
            let mut packed = PackedTracks::default();
            chain_tracks_with(&objects, &pairs, &mut |t| {
                packed.push(&t);
                Ok(())
            })?;
            packed.shrink_to_fit();
            (Vec::new(), Some(packed))
        }
    };
    // Drift correction matches its reference pairs after the run's pairs.
    crate::cancel::check(options.cancel.as_ref())?;
    let timings = StageTimings {
        objects: t1 - t0,
        matching: t2 - t1,
        tracks: t2.elapsed(),
    };
    Ok(SequenceResult {
        objects,
        pairs,
        reference_pairs,
        tracks,
        packed_tracks,
        splits,
        merges,
        skipped_frames,
        skipped_pairs,
        timings,
    })
}

/// The reference pairs of drift correction ([`crate::drift::reference_pairs`] for frames from
/// `start`) matched; those that cannot be matched are left out.
fn reference_matches(
    objects: &[SequenceObject],
    candidates: &[(usize, usize)],
    start: usize,
    options: &SequenceOptions,
) -> Vec<PairMatch> {
    let refs = crate::drift::reference_pairs(objects, candidates, start, options.drift_reference);
    // Reference pairs lie frames apart: the sensor prior is for consecutive frames.
    let mut apart = options.clone();
    if apart.matching.prealign == Prealign::Sensor {
        apart.matching.prealign = Prealign::Robust;
    }
    let (matched, _) = match_all(objects, &refs, &HashMap::new(), &apart, &|_, _, _| {});
    matched
}

/// Matches every candidate pair (in parallel). One pair that cannot be matched never sinks the
/// recording: it is reported with its reason and left out.
fn match_all(
    objects: &[SequenceObject],
    candidates: &[(usize, usize)],
    parts: &HashMap<(usize, usize), PartOfWhole>,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> (Vec<PairMatch>, Vec<SkippedPair>) {
    // The pairs go in windows of MATCH_WINDOW, in order: only the objects of the current window
    // are prepared (a prepared object holds its n × n modes), so memory does not grow with the
    // recording's length. An object on a window's edge is prepared in both windows, identically.
    let done = AtomicUsize::new(0);
    let mut pairs = Vec::with_capacity(candidates.len());
    let mut skipped = Vec::new();
    for window in candidates.chunks(MATCH_WINDOW) {
        if crate::cancel::cancelled(options.cancel.as_ref()) {
            break;
        }
        let prepared = prepare_objects(
            objects,
            window,
            &options.matching,
            SenselAspect::of(options),
        );
        let outcomes: Vec<std::result::Result<PairMatch, SkippedPair>> = window
            .par_iter()
            .map(|&(a, b)| {
                if crate::cancel::cancelled(options.cancel.as_ref()) {
                    // Not matched: the run fails once the window is done.
                    return Err(SkippedPair {
                        a,
                        b,
                        reason: "cancelled".into(),
                    });
                }
                let part = parts.get(&(a, b));
                let r =
                    match_pair(objects, &prepared, a, b, part, options).map_err(|e| SkippedPair {
                        a,
                        b,
                        reason: e.to_string(),
                    });
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(Stage::Matching, n, candidates.len());
                r
            })
            .collect();
        // Only the window's outcomes are held twice while they are sorted out.
        for outcome in outcomes {
            match outcome {
                Ok(p) => pairs.push(p),
                Err(s) => skipped.push(s),
            }
        }
    }
    (pairs, skipped)
}

/// Pairs matched per window of [`match_all`]: enough to keep every core busy, few enough that
/// the prepared objects of one window stay small.
const MATCH_WINDOW: usize = 128;

/// The objects prepared for matching, by index.
type Prepared = HashMap<usize, std::result::Result<PreparedShape, ModalError>>;

/// Every object of the pairs `window` prepared once (in parallel): as the second object of the
/// pair with its predecessor and the first of the pair with its successor. An object that
/// cannot be prepared keeps its error for the pairs that need it.
fn prepare_objects(
    objects: &[SequenceObject],
    window: &[(usize, usize)],
    options: &MatchOptions,
    aspect: SenselAspect,
) -> Prepared {
    let mut ids: Vec<usize> = window.iter().flat_map(|&(a, b)| [a, b]).collect();
    ids.sort_unstable();
    ids.dedup();
    ids.into_par_iter()
        .map(|o| {
            let shape = aspect.shape(&objects[o].shape);
            (o, shape.and_then(|s| prepare(&s, options)))
        })
        .collect()
}

/// The coordinates pairs are matched in: y scaled by the sensor's row pitch over its column
/// pitch ([`SequenceOptions::sensel_aspect`]), x in sensels, so that a grid of oblong sensels
/// is matched in its true proportions. Square sensels (1) leave every shape as it is.
///
/// ```
/// use pedo_io::sequence::SenselAspect;
/// use modal_core::{Shape, Topology};
/// let aspect = SenselAspect::of_pitch(Some([5.08, 7.62])); // footscan: 1.5
/// let s = Shape::new(2, vec![0.0, 0.0, 2.0, 0.0, 0.0, 2.0], Topology::ClosedContour)?;
/// assert_eq!(aspect.shape(&s)?.coords(), &[0.0, 0.0, 2.0, 0.0, 0.0, 3.0]);
/// # Ok::<(), modal_core::ModalError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SenselAspect(f64);

impl SenselAspect {
    /// Square sensels: shapes are matched as they are.
    pub const SQUARE: Self = Self(1.0);

    /// The aspect of a sensor whose pitch is `pitch_mm` (x, y); square when unknown.
    pub fn of_pitch(pitch_mm: Option<[f64; 2]>) -> Self {
        Self::checked(pitch_mm.map_or(1.0, |[x, y]| y / x))
    }

    fn of(options: &SequenceOptions) -> Self {
        Self::checked(options.sensel_aspect)
    }

    fn checked(a: f64) -> Self {
        Self(if a.is_finite() && a > 0.0 { a } else { 1.0 })
    }

    /// `shape` in matching coordinates (an error only if scaling took a coordinate beyond
    /// the range of `f64`).
    pub fn shape<'s>(
        self,
        shape: &'s Shape,
    ) -> std::result::Result<std::borrow::Cow<'s, Shape>, ModalError> {
        if self.0 == 1.0 {
            return Ok(std::borrow::Cow::Borrowed(shape));
        }
        let d = shape.dim();
        let mut coords = shape.coords().to_vec();
        coords
            .iter_mut()
            .skip(1)
            .step_by(d)
            .for_each(|y| *y *= self.0);
        let scaled = Shape::new(d, coords, shape.topology().clone())?;
        Ok(std::borrow::Cow::Owned(scaled))
    }

    /// A result matched in matching coordinates, with its transform and aligned nodes back in
    /// sensels (the pairs are node indices, the same in both).
    pub fn back(self, mut r: MatchResult) -> MatchResult {
        if self.0 == 1.0 {
            return r;
        }
        let d = r.transform.dim;
        let s = |i: usize| if i == 1 { self.0 } else { 1.0 };
        for i in 0..d {
            for j in 0..d {
                r.transform.m[i][j] *= s(j) / s(i);
            }
            r.transform.t[i] /= s(i);
        }
        r.aligned_a
            .iter_mut()
            .skip(1)
            .step_by(d)
            .for_each(|y| *y /= self.0);
        r
    }
}

fn match_pair(
    objects: &[SequenceObject],
    prepared: &Prepared,
    a: usize,
    b: usize,
    part: Option<&PartOfWhole>,
    options: &SequenceOptions,
) -> Result<PairMatch> {
    let (oa, ob) = (&objects[a], &objects[b]);
    let aspect = SenselAspect::of(options);
    // The pairs run in parallel on the pool, so each pair runs on one thread.
    let result = match (part, prepared.get(&a), prepared.get(&b)) {
        (Some(part), _, _) => {
            match_part_with_whole(objects, prepared, part, b, &options.matching, aspect)
        }
        (None, Some(Ok(pa)), Some(Ok(pb))) => {
            match_prepared(pa, pb, &options.matching, Parallelism::Serial)
        }
        // The error names the object's role in the pair, as the one-call form words it.
        _ => aspect
            .shape(&oa.shape)
            .and_then(|sa| match_shapes(&sa, aspect.shape(&ob.shape)?.as_ref(), &options.matching)),
    }
    .map(|r| aspect.back(r))
    .map_err(|e| {
        IoError::invalid(format!(
            "matching object {} (frame {}) with object {} (frame {}): {e}",
            oa.id, oa.frame, ob.id, ob.frame
        ))
    })?;
    let (n, m) = (oa.shape.len(), ob.shape.len());
    let min = n.min(m).max(1) as f64;
    let one_to_one: Vec<_> = result.pairs.iter().filter(|p| !p.excess).collect();
    // Mutual-best matches on the final affinity are counted whatever the search.
    let local = result.local_count();
    let optimisation = if options.matching.search == Search::Local {
        0
    } else {
        one_to_one.len()
    };
    let trackable = one_to_one
        .iter()
        .filter(|p| honest_step_of(oa, p.a, ob, p.b))
        .count();
    let mean_cost = if one_to_one.is_empty() {
        0.0
    } else {
        one_to_one.iter().map(|p| p.cost).sum::<f64>() / one_to_one.len() as f64
    };
    let row = PairRow {
        objects: PairObjects::of(oa, ob),
        local_matches: local,
        local_percent: 100.0 * local as f64 / min,
        optimisation_matches: optimisation,
        optimisation_percent: 100.0 * optimisation as f64 / min,
        matches_after_excess: result.pairs.len(),
        mean_cost,
        trackable_matches: trackable,
        trackable_percent: 100.0 * trackable as f64 / min,
    };
    let mut result = result;
    if !options.keep_match_details {
        result.affinity = AffinityMatrix::new(0, 0, Vec::new())?;
        result.aligned_a = Vec::new();
        result.local_pairs = Vec::new();
        result.pairs.shrink_to_fit();
        result.unmatched_a.shrink_to_fit();
        result.unmatched_b.shrink_to_fit();
    }
    Ok(PairMatch { a, b, result, row })
}

/// A part of a region paired with the whole region at a merge or a split (contour model): a heel
/// outline whose next frame's outline is the whole foot, or the other way round. The part is
/// matched to its own portion of the whole ([`portion_of_whole`]), never normalised onto it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PartOfWhole {
    part: usize,
    whole: usize,
    /// The other parts of the same merge or split.
    siblings: Vec<usize>,
}

/// How far from a part, in node spacings of the whole, a node of the whole may lie and still
/// belong to the part's portion: the boundary's motion between two frames plus a margin.
pub const PORTION_REACH: f64 = 5.0;

/// The pairs among `pairs` that join a part and a whole: `(i, j)` with `i` among the objects that
/// merge into `j`, or `j` among the objects `i` splits into.
fn parts_of_wholes(
    pairs: &[(usize, usize)],
    splits: &[(usize, Vec<usize>)],
    merges: &[(Vec<usize>, usize)],
) -> HashMap<(usize, usize), PartOfWhole> {
    let others = |all: &[usize], one: usize| all.iter().copied().filter(|&k| k != one).collect();
    let mut out = HashMap::new();
    for &(a, b) in pairs {
        let merged = merges.iter().find(|(is, j)| *j == b && is.contains(&a));
        let split = splits.iter().find(|(i, js)| *i == a && js.contains(&b));
        let part = match (merged, split) {
            (Some((is, _)), _) => PartOfWhole {
                part: a,
                whole: b,
                siblings: others(is, a),
            },
            (None, Some((_, js))) => PartOfWhole {
                part: b,
                whole: a,
                siblings: others(js, b),
            },
            (None, None) => continue,
        };
        out.insert((a, b), part);
    }
    out
}

/// The nodes of the whole (in its order) that form the part's portion: within
/// [`PORTION_REACH`] node spacings of the part's outline, and no nearer to a sibling's outline.
pub(crate) fn portion_of_whole(part: &Shape, whole: &Shape, siblings: &[&Shape]) -> Vec<usize> {
    let spacing = crate::track::outline_distance(whole.coords(), [0.0, 0.0]).1;
    let reach = PORTION_REACH * spacing;
    (0..whole.len())
        .filter(|&w| {
            let p = whole.point(w);
            let near = |s: &Shape| crate::track::outline_distance(s.coords(), [p[0], p[1]]).0;
            let to_part = near(part);
            to_part <= reach && siblings.iter().all(|s| near(s) >= to_part)
        })
        .collect()
}

/// Matches a part with its portion of the whole (the portion closed into an outline, as the
/// region the part covers), and reports the result in the whole's numbering: the whole's nodes
/// outside the portion stay unmatched. `b` is the pair's second object.
fn match_part_with_whole(
    objects: &[SequenceObject],
    prepared: &Prepared,
    part: &PartOfWhole,
    b: usize,
    opts: &MatchOptions,
    aspect: SenselAspect,
) -> std::result::Result<MatchResult, ModalError> {
    let whole = aspect.shape(&objects[part.whole].shape)?;
    let siblings = part
        .siblings
        .iter()
        .map(|&s| aspect.shape(&objects[s].shape))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let siblings: Vec<&Shape> = siblings.iter().map(|s| s.as_ref()).collect();
    let own = aspect.shape(&objects[part.part].shape)?;
    let (whole, own) = (whole.as_ref(), own.as_ref());
    let portion = portion_of_whole(own, whole, &siblings);
    let whole_is_b = part.whole == b;
    if portion.len() < 3 {
        // The portion of the whole that the part covers is too small to be modelled.
        let side = if whole_is_b { Side::B } else { Side::A };
        let too_few = ModalError::TooFewNodes {
            nodes: portion.len(),
            min: 3,
        };
        return Err(too_few.of(side));
    }
    let coords = portion
        .iter()
        .flat_map(|&w| whole.point(w).to_vec())
        .collect();
    let sub = prepare(&Shape::new(2, coords, Topology::ClosedContour)?, opts)?;
    let own = match prepared.get(&part.part) {
        Some(Ok(p)) => p.clone(),
        _ => prepare(own, opts)?,
    };
    let r = if whole_is_b {
        match_prepared(&own, &sub, opts, Parallelism::Serial)?
    } else {
        match_prepared(&sub, &own, opts, Parallelism::Serial)?
    };
    in_whole_numbering(r, &portion, whole, whole_is_b)
}

/// A match against a portion of the whole, renumbered to the whole: pairs, local pairs and the
/// affinity (the columns or rows of the nodes outside the portion at the largest cost, 1).
fn in_whole_numbering(
    r: MatchResult,
    portion: &[usize],
    whole: &Shape,
    whole_is_b: bool,
) -> std::result::Result<MatchResult, ModalError> {
    let z = &r.affinity;
    let (rows, cols) = if whole_is_b {
        (z.rows(), whole.len())
    } else {
        (whole.len(), z.cols())
    };
    let mut data = vec![1.0; rows * cols];
    for i in 0..z.rows() {
        for j in 0..z.cols() {
            let (ri, cj) = if whole_is_b {
                (i, portion[j])
            } else {
                (portion[i], j)
            };
            data[ri * cols + cj] = z.get(i, j);
        }
    }
    let renumber = |(i, j): (usize, usize)| {
        if whole_is_b {
            (i, portion[j])
        } else {
            (portion[i], j)
        }
    };
    let pairs: Vec<modal_core::MatchPair> = r
        .pairs
        .iter()
        .map(|p| {
            let (a, b) = renumber((p.a, p.b));
            modal_core::MatchPair { a, b, ..*p }
        })
        .collect();
    let unmatched = |n: usize, used: &dyn Fn(usize) -> bool| (0..n).filter(|&k| !used(k)).collect();
    let aligned_a = if whole_is_b {
        r.aligned_a.clone()
    } else {
        r.transform.apply(whole.coords())
    };
    Ok(MatchResult {
        unmatched_a: unmatched(rows, &|k| pairs.iter().any(|p| p.a == k)),
        unmatched_b: unmatched(cols, &|k| pairs.iter().any(|p| p.b == k)),
        local_pairs: r.local_pairs.iter().copied().map(renumber).collect(),
        affinity: AffinityMatrix::new(rows, cols, data)?,
        pairs,
        aligned_a,
        ..r
    })
}

/// Chains matches into tracks. A node continues the track of the node it is matched to one-to-one
/// in the previous object; excess (one-to-many) matches never extend a track, since a track must
/// stay a single path, and neither does a match between frames that moves further than
/// [`crate::track::step_allowed`] allows. Nodes with no such predecessor start a new track.
/// Every pair must lead forward (`a < b`) between the `objects` and name nodes they have.
pub fn chain_tracks(objects: &[SequenceObject], pairs: &[PairMatch]) -> Result<Vec<Track>> {
    let mut tracks = Vec::new();
    chain_tracks_with(objects, pairs, &mut |t| {
        tracks.push(t);
        Ok(())
    })?;
    Ok(tracks)
}

/// [`chain_tracks`], handing the tracks to `emit` one by one in order (track 0 first), each as
/// soon as it can grow no more and every track before it has gone: only the open tracks are
/// held (those through the last frames chained), not every track of the run.
pub fn chain_tracks_with(
    objects: &[SequenceObject],
    pairs: &[PairMatch],
    emit: &mut dyn FnMut(Track) -> Result<()>,
) -> Result<()> {
    let mut chain = Chainer::default();
    let mut emit = |_, track| emit(track);
    chain.chain(objects, 0..objects.len(), pairs, objects.len(), &mut emit)?;
    chain.finish(&mut emit)
}

/// Whether the match of node `na` of object `a` with node `nb` of object `b` may extend a track:
/// between frames, [`crate::track::step_allowed`]; within a frame (isocontour levels), always.
pub(crate) fn honest_step(
    objects: &[SequenceObject],
    a: usize,
    na: usize,
    b: usize,
    nb: usize,
) -> bool {
    honest_step_of(&objects[a], na, &objects[b], nb)
}

/// [`honest_step`] with the two objects given.
pub(crate) fn honest_step_of(
    oa: &SequenceObject,
    na: usize,
    ob: &SequenceObject,
    nb: usize,
) -> bool {
    oa.frame == ob.frame
        || crate::track::step_allowed(oa.shape.point(na), ob.shape.point(nb), &ob.shape)
}

/// A pressure of the file's `units` as the outputs state it: in kPa when the units say how,
/// else in the file's units ("units unknown" when it names none).
fn pressure_text(value: f64, units: &str) -> String {
    match crate::recording::kpa_per_unit(units) {
        Some(k) => format!("{:.1} kPa", value * k),
        None if units.is_empty() => format!("{value:.1}, units unknown"),
        None => format!("{value:.1} {units}"),
    }
}

/// Objects in sequence order (numbered from 0), the pairs to match (indices into the objects)
/// and, for contours, the splits and merges between consecutive frames.
struct Built {
    objects: Vec<SequenceObject>,
    pairs: Vec<(usize, usize)>,
    splits: Vec<(usize, Vec<usize>)>,
    merges: Vec<(Vec<usize>, usize)>,
    skipped_frames: Vec<SkippedFrame>,
}

/// A contour's points in sensels (x = column, y = row), whatever units it was extracted in.
fn outline_in_sensels(
    c: &Contour,
    units: crate::grid::CoordUnits,
) -> std::borrow::Cow<'_, [[f64; 2]]> {
    match units {
        crate::grid::CoordUnits::Pixels => std::borrow::Cow::Borrowed(&c.points),
        crate::grid::CoordUnits::Millimetres { dx_mm, dy_mm } => c
            .points
            .iter()
            .map(|p| [p[0] / dx_mm, p[1] / dy_mm])
            .collect(),
    }
}

/// An object's shape and the measures of the sensors inside its outline.
type MeasuredShape = (Shape, FrameMeasures);

/// A frame's outlines that make objects, and their shapes and measures.
type FrameObjects = (Vec<Contour>, Vec<MeasuredShape>);

/// The outer contours of frame `t` worth modelling, largest first (so object 0 of a frame is its
/// main region), each with its shape and the measures of the sensors inside it: only contours
/// that make a valid shape become objects.
fn frame_contours(
    recording: &Recording,
    t: usize,
    options: &SequenceOptions,
) -> Result<FrameObjects> {
    let frame = recording.frame(t)?;
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let mut cs: Vec<(Contour, MeasuredShape)> = contours(&frame, &options.contour)?
        .into_iter()
        .filter(|c| !c.hole && c.points.len() >= options.min_nodes.max(3))
        .filter_map(|c| {
            let shape = c.to_shape().ok()?;
            let outline = outline_in_sensels(&c, options.contour.units);
            let measures = recording.region_measures(&frame, threshold, &outline);
            Some((c, (shape, measures)))
        })
        .collect();
    cs.sort_by(|a, b| b.0.area().total_cmp(&a.0.area()));
    Ok(cs.into_iter().unzip())
}

fn build_objects(
    recording: &Recording,
    options: &SequenceOptions,
    start: usize,
    end: usize,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<Built> {
    let mut built = Built {
        objects: Vec::new(),
        pairs: Vec::new(),
        splits: Vec::new(),
        merges: Vec::new(),
        skipped_frames: Vec::new(),
    };
    let done = AtomicUsize::new(0);
    let tick = |total: usize| {
        progress(
            Stage::Objects,
            done.fetch_add(1, Ordering::Relaxed) + 1,
            total,
        )
    };
    let build = match options.model {
        ObjectModel::Contour => contour_objects,
        ObjectModel::Surface => surface_objects,
        ObjectModel::Isocontour => isocontour_objects,
    };
    build(&mut built, recording, options, (start, end), &tick)?;
    Ok(built)
}

/// Every frame's contours as objects, paired across consecutive frames by overlap (with their
/// splits and merges); `tick(total)` reports each frame done.
fn contour_objects(
    built: &mut Built,
    recording: &Recording,
    options: &SequenceOptions,
    (start, end): (usize, usize),
    tick: &(dyn Fn(usize) + Sync),
) -> Result<()> {
    let (per_frame, shapes): (Vec<Vec<Contour>>, Vec<Vec<MeasuredShape>>) = per_frame_or_skipped(
        start..end,
        &mut built.skipped_frames,
        options.cancel.as_ref(),
        |t| {
            let cs = frame_contours(recording, t, options);
            tick(end - start);
            cs
        },
    )?
    .into_iter()
    .unzip();
    let pairings = crate::track::track(&per_frame, PairingMethod::default())?;
    let mut first = Vec::with_capacity(per_frame.len());
    for (k, frame_shapes) in shapes.into_iter().enumerate() {
        first.push(built.objects.len());
        for (index, (shape, measures)) in frame_shapes.into_iter().enumerate() {
            let id = built.objects.len();
            built.objects.push(SequenceObject {
                id,
                frame: start + k,
                index,
                level: None,
                shape,
                measures: Some(measures),
            });
        }
    }
    for (k, p) in pairings.iter().enumerate() {
        let (fa, fb) = (first[k], first[k + 1]);
        built
            .pairs
            .extend(p.pairs.iter().map(|&(i, j)| (fa + i, fb + j)));
        built.splits.extend(
            p.splits
                .iter()
                .map(|(i, js)| (fa + i, js.iter().map(|j| fb + j).collect())),
        );
        built.merges.extend(
            p.merges
                .iter()
                .map(|(is, j)| (is.iter().map(|i| fa + i).collect(), fb + j)),
        );
    }
    Ok(())
}

/// Every frame's pressure surface as an object, paired with the previous frame's.
fn surface_objects(
    built: &mut Built,
    recording: &Recording,
    options: &SequenceOptions,
    (start, end): (usize, usize),
    tick: &(dyn Fn(usize) + Sync),
) -> Result<()> {
    let keep = |s: &Shape| s.len() >= options.min_nodes.max(3);
    let threshold = options.surface.preprocess.threshold.unwrap_or(0.0);
    let per_frame: Vec<Option<Shape>> = per_frame_or_skipped(
        start..end,
        &mut built.skipped_frames,
        options.cancel.as_ref(),
        |t| {
            let shape = frame_surface(recording, t, threshold, options, &keep);
            tick(end - start);
            shape
        },
    )?;
    let mut previous: Option<usize> = None;
    for (k, shape) in per_frame.into_iter().enumerate() {
        match shape {
            Some(shape) => {
                let o = built.objects.len();
                if let Some(p) = previous
                    && built.objects[p].frame + 1 == start + k
                {
                    built.pairs.push((p, o));
                }
                built.objects.push(SequenceObject {
                    id: o,
                    frame: start + k,
                    index: 0,
                    level: None,
                    shape,
                    measures: None,
                });
                previous = Some(o);
            }
            None => previous = None,
        }
    }
    Ok(())
}

/// The isobaric contours of one frame (the `iso_frame`, else the most loaded one) as objects,
/// each level paired with the next.
fn isocontour_objects(
    built: &mut Built,
    recording: &Recording,
    options: &SequenceOptions,
    (start, end): (usize, usize),
    tick: &(dyn Fn(usize) + Sync),
) -> Result<()> {
    let t = match options.iso_frame {
        Some(t) => t,
        None => (start..end)
            .max_by(|&a, &b| frame_load(recording, a).total_cmp(&frame_load(recording, b)))
            .unwrap_or(start),
    };
    let frame = recording.frame(t)?;
    let base = match options.contour.preprocess.threshold {
        Some(th) => crate::preprocess::threshold(&frame, th)?,
        None => frame.clone(),
    };
    let levels = match &options.iso_levels {
        Some(l) => l.clone(),
        None => crate::isobar::even_levels(&base, options.iso_count),
    };
    let iso = crate::isobar::IsoOptions {
        preprocess: options.contour.preprocess,
        resample: options.contour.resample,
        include_holes: false,
        ..Default::default()
    };
    for (index, &level) in levels.iter().enumerate() {
        let cs = crate::isobar::isocontours(&frame, &[level], &iso)?;
        // The seed models one isobaric contour per level: the largest region's outline.
        let largest = cs.iter().max_by(|a, b| a.area().total_cmp(&b.area()));
        let shape = largest.map(Contour::to_shape).transpose()?;
        match level_object(shape, options.min_nodes.max(3)) {
            Ok(shape) => {
                let o = built.objects.len();
                if o > 0 {
                    built.pairs.push((o - 1, o));
                }
                let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
                let measures = largest.map(|c| {
                    let outline = outline_in_sensels(c, options.contour.units);
                    recording.region_measures(&frame, threshold, &outline)
                });
                built.objects.push(SequenceObject {
                    id: o,
                    frame: t,
                    index,
                    level: Some(level),
                    shape,
                    measures,
                });
            }
            Err(why) => built.skipped_frames.push(SkippedFrame {
                frame: t,
                reason: format!(
                    "isobaric level {} of {} ({}): {why}",
                    index + 1,
                    levels.len(),
                    pressure_text(level, &recording.units)
                ),
            }),
        }
        tick(levels.len());
    }
    Ok(())
}

/// An isobaric level's object, its largest region's outline, or why it has none: no region
/// reaches the level, or the outline has fewer than `min_nodes` nodes.
fn level_object(shape: Option<Shape>, min_nodes: usize) -> std::result::Result<Shape, String> {
    match shape {
        None => Err("no region reaches this level; no object".into()),
        Some(s) if s.len() < min_nodes => Err(format!(
            "its largest region's outline has {} nodes, fewer than the {min_nodes} an object needs",
            s.len()
        )),
        Some(s) => Ok(s),
    }
}

/// `build(t)` for every frame of `frames`, in parallel. A frame whose objects cannot be built is
/// recorded in `skipped` with its reason and gets no objects (`T::default()`); the run goes on.
/// Once `cancel` is cancelled the frames not started are not built, and the whole fails with
/// [`IoError::Cancelled`].
fn per_frame_or_skipped<T: Send + Default>(
    frames: std::ops::Range<usize>,
    skipped: &mut Vec<SkippedFrame>,
    cancel: Option<&Cancel>,
    build: impl Fn(usize) -> Result<T> + Sync,
) -> Result<Vec<T>> {
    let outcomes: Vec<Result<T>> = frames
        .clone()
        .into_par_iter()
        .map(|t| {
            crate::cancel::check(cancel)?;
            build(t)
        })
        .collect();
    crate::cancel::check(cancel)?;
    Ok(frames
        .zip(outcomes)
        .map(|(frame, outcome)| {
            outcome.unwrap_or_else(|e| {
                skipped.push(SkippedFrame {
                    frame,
                    reason: e.to_string(),
                });
                T::default()
            })
        })
        .collect())
}

/// The brightness surface of frame `t`, or `None` when the frame has no contact or too few
/// loaded sensels to triangulate (like a frame with no contact).
fn frame_surface(
    recording: &Recording,
    t: usize,
    threshold: f64,
    options: &SequenceOptions,
    keep: &dyn Fn(&Shape) -> bool,
) -> Result<Option<Shape>> {
    let frame = recording.frame(t)?;
    if frame.max() <= threshold {
        return Ok(None);
    }
    // Only "nothing there" is a frame without an object; a bad option or a mesh that failed is
    // that frame's skipped reason, so a run never ends on a bare "no object" that hides it.
    match crate::surface::surface(&frame, &options.surface) {
        Ok(s) => Ok(Some(s.to_shape()?).filter(|s| keep(s))),
        Err(IoError::NoObject(_)) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Sum of the frame's values: the load the isocontour model picks its frame by.
fn frame_load(recording: &Recording, t: usize) -> f64 {
    recording
        .frame_slice(t)
        .map_or(0.0, |f| f.iter().map(|&v| v as f64).sum())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn negative_frame_indices_count_back_from_the_end_as_in_a_python_slice() {
        let resolve = |s: &str, n: usize| s.parse::<FrameRange>().unwrap().resolve(n);
        assert_eq!(resolve("-50..", 205), Ok((155, 205)), "the last 50 frames");
        assert_eq!(resolve("0..-1", 205), Ok((0, 204)), "all but the last");
        assert_eq!(resolve("..-1", 205), Ok((0, 204)));
        assert_eq!(resolve("-10..-5", 205), Ok((195, 200)));
        assert_eq!(
            resolve("-205..", 205),
            Ok((0, 205)),
            "as far back as frame 0"
        );
        assert_eq!(resolve("3..-2", 6), Ok((3, 4)));
        assert_eq!(
            "-50..-1".parse::<FrameRange>().unwrap().to_string(),
            "-50..-1"
        );
        // Still out of range once resolved: an error naming the range, the frame count and
        // what the negative indices came to.
        let e = resolve("-300..", 205).unwrap_err();
        assert_eq!(e.option, "frames");
        assert_eq!(e.value, "-300..");
        assert!(
            e.expected.contains("205 frames") && e.expected.contains("-300.. is -95..205"),
            "{e}"
        );
        let e = resolve("0..-205", 205).unwrap_err().to_string();
        assert!(
            e.contains("0..-205 is 0..0") && e.contains("205 frames"),
            "{e}"
        );
        let e = resolve("-3..-5", 205).unwrap_err().to_string();
        assert!(e.contains("-3..-5 is 202..200"), "{e}");
        // Positive ranges are checked as before, their message with no resolution.
        let e = resolve("0..999", 205).unwrap_err().to_string();
        assert!(e.contains("205 frames") && !e.contains(" is "), "{e}");
        assert!(resolve("5..5", 205).is_err() && resolve("0..0", 0).is_err());
        assert!("x..-1".parse::<FrameRange>().is_err());
        assert!("--1..".parse::<FrameRange>().is_err());
    }

    #[test]
    fn a_run_resolves_negative_frames_once_for_the_range_the_iso_frame_and_the_summary() {
        let rec = recording(6, |_, r, c| (8..16).contains(&r) && (8..16).contains(&c));
        let params = |frames: &str, iso_frame| RunParams {
            model: ObjectModel::Isocontour,
            frames: Some(frames.parse().unwrap()),
            iso_frame,
            ..RunParams::default()
        };
        let negative = params("-3..-1", None);
        let o = negative.to_options(&rec).unwrap();
        assert_eq!(o.frames, Some((3, 5)));
        assert_eq!(
            o.frames,
            params("3..5", None).to_options(&rec).unwrap().frames
        );
        // summary.json records the frames run, resolved.
        let used = negative.used(&o, &rec);
        let frames = used.iter().find(|(k, _)| *k == "frames").unwrap();
        assert_eq!(frames.1, OptionValue::Word("3..5".into()));
        // iso_frame lies within the resolved range; the error names it both ways.
        assert_eq!(
            params("-3..-1", Some(4))
                .to_options(&rec)
                .unwrap()
                .iso_frame,
            Some(4)
        );
        let e = params("-3..-1", Some(5))
            .to_options(&rec)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("iso_frame") && e.contains("3..5") && e.contains("frames -3..-1 of 6"),
            "{e}"
        );
        let e = params("-9..", None)
            .to_options(&rec)
            .unwrap_err()
            .to_string();
        assert!(e.contains("-9..") && e.contains("6 frames"), "{e}");
    }

    #[test]
    fn a_study_lists_the_options_a_run_uses_with_each_recordings_own_left_open() {
        let mut params = RunParams {
            spacing: 1.5,
            ..RunParams::default()
        };
        let mut rec = recording(6, |_, r, c| (8..16).contains(&r) && (8..16).contains(&c));
        rec.noise_threshold = Some(2.0);
        let run = params.used(&params.to_options(&rec).unwrap(), &rec);
        let given = params.given().unwrap();
        let names =
            |v: &[(&'static str, OptionValue)]| v.iter().map(|(k, _)| *k).collect::<Vec<_>>();
        assert_eq!(
            names(&given),
            names(&run),
            "the same options, in the same order"
        );
        let value = |v: &[(&'static str, OptionValue)], k: &str| {
            v.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.clone())
                .unwrap()
        };
        assert_eq!(value(&given, "spacing"), OptionValue::Float(1.5));
        assert_eq!(value(&run, "noise"), OptionValue::Float(2.0));
        assert_eq!(
            value(&given, "noise"),
            OptionValue::Absent,
            "each file's own"
        );
        assert_eq!(value(&run, "frames"), OptionValue::Word("0..6".into()));
        assert_eq!(value(&given, "frames"), OptionValue::Word("0..".into()));
        params.noise = Some(5.0);
        params.units.units = Some(" N/cm2 ".into());
        let given = params.given().unwrap();
        assert_eq!(value(&given, "noise"), OptionValue::Float(5.0));
        assert_eq!(value(&given, "units"), OptionValue::Word("N/cm²".into()));
    }

    /// A recording of `frames`, each drawn by `draw(frame, row, col) -> loaded`.
    fn recording(frames: usize, draw: impl Fn(usize, usize, usize) -> bool) -> Recording {
        let (rows, cols) = (24, 24);
        let mut data = Vec::with_capacity(frames * rows * cols);
        for f in 0..frames {
            for r in 0..rows {
                for c in 0..cols {
                    data.push(if draw(f, r, c) { 100.0 } else { 0.0 });
                }
            }
        }
        Recording::new(frames, rows, cols, data, vec![true; rows * cols]).unwrap()
    }

    fn disc(cx: f64, cy: f64, radius: f64) -> impl Fn(usize, usize) -> bool {
        move |r, c| (r as f64 - cy).hypot(c as f64 - cx) <= radius
    }

    #[test]
    fn oblong_sensels_are_matched_in_their_true_proportions() {
        // An ellipse turning by 4° a frame on 7.62 × 5.08 mm sensels (footscan's).
        let mut rec = recording(5, |f, r, c| {
            let t = (4.0 * f as f64).to_radians();
            let (x, y) = (c as f64 - 11.5, (r as f64 - 11.5) * 1.5);
            let (u, v) = (x * t.cos() + y * t.sin(), -x * t.sin() + y * t.cos());
            (u / 9.0).powi(2) + (v / 15.0).powi(2) <= 1.0
        });
        rec.pitch_mm = Some([5.08, 7.62]);
        let options = RunParams::default().to_options(&rec).unwrap();
        assert!((options.sensel_aspect - 1.5).abs() < 1e-12);
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        assert_eq!(run.pairs.len(), 4);
        let scaled = |s: &Shape| SenselAspect(1.5).shape(s).unwrap().into_owned();
        for p in &run.pairs {
            let (a, b) = (&run.objects[p.a].shape, &run.objects[p.b].shape);
            // The pairs of the shapes in true proportions, to the bit.
            let truth = match_shapes(&scaled(a), &scaled(b), &options.matching).unwrap();
            assert_eq!(p.result.pairs, truth.pairs);
            // The transform and the aligned nodes are in sensels, and agree.
            let moved = p.result.transform.apply(a.coords());
            for (m, q) in moved.iter().zip(&p.result.aligned_a) {
                assert!((m - q).abs() < 1e-9, "{m} {q}");
            }
            let back = SenselAspect(1.5).back(truth);
            assert_eq!(back.transform, p.result.transform);
        }
        // Square sensels are matched as they are.
        rec.pitch_mm = Some([5.08, 5.08]);
        assert_eq!(
            RunParams::default().to_options(&rec).unwrap().sensel_aspect,
            1.0
        );
    }

    #[test]
    fn each_foot_of_a_recording_of_both_has_its_own_measures() {
        // Two feet side by side, unevenly loaded: each object's measures are those of its own
        // sensors, and together they are the frame's.
        let (left, right) = (disc(6.0, 11.0, 4.0), disc(17.0, 12.0, 5.0));
        let mut rec = recording(3, |_, r, c| left(r, c) || right(r, c));
        let mut data = rec.data().to_vec();
        for (i, v) in data.iter_mut().enumerate() {
            let (r, c) = ((i % 576) / 24, i % 24);
            if right(r, c) {
                *v = 40.0 + c as f32;
            }
        }
        rec = Recording::new(3, 24, 24, data, vec![true; 576]).unwrap();
        for options in [
            SequenceOptions::default(),
            SequenceOptions {
                model: ObjectModel::Isocontour,
                ..SequenceOptions::default()
            },
        ] {
            let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
            if options.model == ObjectModel::Isocontour {
                // The largest region of the lowest level: both feet are one level's regions, so
                // the object is the larger foot alone.
                let m = run.objects[0].measures.as_ref().unwrap();
                let n = (0..576).filter(|&i| right(i / 24, i % 24)).count();
                assert_eq!(m.contact_sensors, n);
                continue;
            }
            let frame = &rec.measures(0.0)[0];
            let objects: Vec<_> = run.objects.iter().filter(|o| o.frame == 0).collect();
            assert_eq!(objects.len(), 2);
            let m: Vec<&FrameMeasures> = objects
                .iter()
                .map(|o| o.measures.as_ref().unwrap())
                .collect();
            let foot = |inside: &dyn Fn(usize, usize) -> bool| {
                let cells = (0..576).filter(|&i| inside(i / 24, i % 24));
                let (n, load, peak, x) = cells.fold((0, 0.0, 0.0f64, 0.0), |(n, l, p, x), i| {
                    let v = f64::from(rec.data()[i]);
                    (n + 1, l + v, p.max(v), x + v * (i % 24) as f64)
                });
                (n, load, peak, x / load)
            };
            // The larger (right) foot comes first.
            for (m, inside) in m
                .iter()
                .zip([&right as &dyn Fn(usize, usize) -> bool, &left])
            {
                let (n, load, peak, cop_x) = foot(inside);
                assert_eq!(m.contact_sensors, n);
                assert!((m.total_force - load).abs() < 1e-9 * load);
                assert_eq!(m.peak_pressure, peak);
                assert!((m.cop.unwrap()[0] - cop_x).abs() < 1e-9);
            }
            assert_eq!(
                m[0].contact_sensors + m[1].contact_sensors,
                frame.contact_sensors
            );
            assert!((m[0].total_force + m[1].total_force - frame.total_force).abs() < 1e-9);
            assert_eq!(
                m[0].peak_pressure.max(m[1].peak_pressure),
                frame.peak_pressure
            );
        }
        // Surfaces: one object per frame, the frame's measures.
        let surface = SequenceOptions {
            model: ObjectModel::Surface,
            ..SequenceOptions::default()
        };
        let run = run_sequence(&rec, &surface, &|_, _, _| {}).unwrap();
        assert!(run.objects.iter().all(|o| o.measures.is_none()));
    }

    #[test]
    fn a_run_without_match_details_has_the_same_matches_rows_and_tracks() {
        let rec = recording(6, |f, r, c| {
            disc(9.0 + f as f64 * 0.7, 11.0, 5.0 + 0.2 * f as f64)(r, c)
        });
        let full = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
        let lean_options = SequenceOptions {
            keep_match_details: false,
            ..Default::default()
        };
        let lean = run_sequence(&rec, &lean_options, &|_, _, _| {}).unwrap();
        assert_eq!(full.pairs.len(), 5);
        assert_eq!(lean.pairs.len(), full.pairs.len());
        for (f, l) in full.pairs.iter().zip(&lean.pairs) {
            assert_eq!(f.row, l.row);
            assert_eq!(f.result.pairs, l.result.pairs);
            assert_eq!(f.result.unmatched_a, l.result.unmatched_a);
            assert!(f.result.affinity.rows() > 0);
            assert_eq!(l.result.affinity.rows(), 0);
            assert!(l.result.aligned_a.is_empty());
        }
        assert!(full.packed_tracks.is_none() && lean.tracks.is_empty());
        assert!(full.tracks.len() > 5);
        assert_eq!(lean.track_count(), full.tracks.len());
        let unpacked: Vec<Track> = lean.all_tracks().map(|t| t.into_owned()).collect();
        assert_eq!(unpacked, full.tracks);
        assert!(lean
            .track_lengths()
            .eq(full.tracks.iter().map(|t| t.steps.len())));
        let csv = |r: &SequenceResult| crate::report::matches_table(&rec, r).to_csv();
        assert_eq!(csv(&full), csv(&lean));
        let tracks = |r: &SequenceResult| crate::report::tracks_table(&rec, r).to_csv();
        assert_eq!(tracks(&full), tracks(&lean));
    }

    #[test]
    fn streamed_tracks_equal_those_chained_whole_on_a_real_walk() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/FrasP01L.asf");
        let rec = crate::read_recording(path).unwrap();
        let options = SequenceOptions {
            // Stance and swing, with the splits and merges of heel strike and toe-off.
            frames: Some((0, 120)),
            keep_match_details: false,
            ..Default::default()
        };
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        // Every node's track held to the end: drift correction's chaining with no reference pairs.
        let want = crate::drift::anchored_tracks(&run.objects, &run.pairs, &[]).unwrap();
        assert!(want.len() > 100 && want.iter().any(|t| t.steps.len() >= 10));
        assert!(!run.splits.is_empty() || !run.merges.is_empty());
        assert_eq!(chain_tracks(&run.objects, &run.pairs).unwrap(), want);
        let packed: Vec<Track> = run.all_tracks().map(|t| t.into_owned()).collect();
        assert_eq!(packed, want);
    }

    #[test]
    fn a_bad_surface_option_is_each_frames_reason_not_a_frame_without_contact() {
        let rec = recording(3, |f, r, c| disc(11.0 + f as f64 * 0.5, 11.0, 6.0)(r, c));
        let mut options = SequenceOptions {
            model: ObjectModel::Surface,
            ..Default::default()
        };
        options.surface.max_nodes = Some(2);
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        assert!(run.objects.is_empty());
        assert_eq!(run.skipped_frames.len(), 3);
        for s in &run.skipped_frames {
            assert!(
                s.reason.contains("max_nodes must be at least 3"),
                "{}",
                s.reason
            );
        }
    }

    #[test]
    fn chaining_a_pair_that_goes_back_or_names_missing_nodes_is_an_error() {
        let rec = recording(3, |f, r, c| disc(11.0 + f as f64 * 0.5, 11.0, 6.0)(r, c));
        let run = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
        assert_eq!(chain_tracks(&run.objects, &run.pairs).unwrap(), run.tracks);
        let mut back = run.pairs.clone();
        back[1].b = 0;
        let e = chain_tracks(&run.objects, &back).unwrap_err().to_string();
        assert!(e.contains("pair 1 → 0 does not lead forward"), "{e}");
        let mut beyond = run.pairs.clone();
        beyond[0].b = 7;
        let e = chain_tracks(&run.objects, &beyond).unwrap_err().to_string();
        assert!(e.contains("does not lead forward onto objects 0..3"), "{e}");
        let mut node = run.pairs.clone();
        let n = run.objects[1].shape.len();
        node[0].result.pairs[0].b = n;
        node[0].result.pairs[0].excess = false;
        let e = chain_tracks(&run.objects, &node).unwrap_err().to_string();
        assert!(
            e.contains("beyond the objects'") && e.contains(&format!("and {n} nodes")),
            "{e}"
        );
        // Drift-corrected chaining reports the same errors, as pairs or as reference pairs.
        let anchored = |pairs: &[PairMatch], refs: &[PairMatch]| {
            crate::drift::anchored_tracks(&run.objects, pairs, refs)
                .unwrap_err()
                .to_string()
        };
        assert!(anchored(&back, &[]).contains("pair 1 → 0 does not lead forward"));
        assert!(anchored(&run.pairs, &beyond).contains("onto objects 0..3"));
        assert!(anchored(&node, &[]).contains(&format!("and {n} nodes")));
    }

    #[test]
    fn a_pair_that_cannot_be_matched_is_skipped_with_its_reason() {
        let rec = recording(4, |f, r, c| disc(11.0 + f as f64 * 0.5, 11.0, 6.0)(r, c));
        let options = SequenceOptions::default();
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        assert_eq!(run.pairs.len(), 3);
        assert!(run.skipped_pairs.is_empty() && run.skipped_frames.is_empty());
        // Object 2 gets two coincident nodes, as an outline touching itself has.
        let mut objects = run.objects.clone();
        let shape = &objects[2].shape;
        let mut coords = shape.coords().to_vec();
        coords[2] = coords[0];
        coords[3] = coords[1];
        objects[2].shape = Shape::new(2, coords, shape.topology().clone()).unwrap();
        let candidates = [(0, 1), (1, 2), (2, 3)];
        let (pairs, skipped) = match_all(
            &objects,
            &candidates,
            &HashMap::new(),
            &options,
            &|_, _, _| {},
        );
        assert_eq!(
            pairs.iter().map(|p| (p.a, p.b)).collect::<Vec<_>>(),
            vec![(0, 1)]
        );
        assert_eq!(
            skipped.iter().map(|s| (s.a, s.b)).collect::<Vec<_>>(),
            vec![(1, 2), (2, 3)]
        );
        assert!(
            skipped.iter().all(|s| s.reason.contains("coincide")),
            "{skipped:?}"
        );
        // The tracks of what was matched are still chained.
        assert!(!chain_tracks(&objects, &pairs).unwrap().is_empty());
    }
}
