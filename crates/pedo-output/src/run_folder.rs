//! The folder of one run: its tables, `pairs.json`, figures, `summary.json`, `report.html` and
//! `animation.gif`, written whole or not at all ([`crate::outdir`]). Every run folder is written
//! by one path, from the run's events ([`pedo_track::SequenceSink`]) as the engine
//! (`pedo_track::stream_sequence`) makes them, or as `pedo_track::replay` hands over a result
//! already made (`pymodal.run(out=...)`): [`FolderSink`] writes the tables as the events come
//! ([`TablesSink`]), gathers what the summary figures and the report draw from the same events in
//! bounded memory ([`FrameCurves`], [`TracksGather`], [`ReportGather`]), and gathers every object
//! and pair ([`pedo_track::Collect`]) only for what needs them all: the material points of a
//! contour run, the pair figures and the animation. `summary.json` is made from the counts the
//! events add up to.

use crate::figure::{
    Curve, CurvesFigure, FigureAxes, MatchFigure, ObjectLabel, PeakFigure, TracksGather,
};
use crate::html_report::ReportGather;
use crate::outdir::OutDir;
use crate::TableFormat;
use crate::{Cell, InputInfo};
use modal_core::{Choice, OptionSpec, PathOrRows};
use pedo_io::cancel::Cancel;
use pedo_io::formats::ReadOptions;
use pedo_io::recording::FrameMeasures;
use pedo_io::recording::Recording;
use pedo_io::FrameSource;
use pedo_io::{IoError, Result, StoredValues};
use pedo_track::follow::FollowSink;
use pedo_track::{
    replay, require_objects, stream_sequence, Collect, NoSink, ObjectModel, PairMatch, RunCounts,
    RunParams, SequenceObject, SequenceOptions, SequenceResult, SequenceSink, Stage,
};
use rayon::prelude::*;
use serde_json::{json, Map, Value};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// The tables every run folder holds (besides `summary.json` and `pairs.json`), by name: each
/// written as `NAME.csv` or `NAME.parquet` ([`TableFormat`]).
pub const RUN_TABLES: [&str; 6] = ["pairs", "objects", "matches", "tracks", "frames", "curves"];

/// The table of material points ([`crate::points_table`]) a whole contour run writes beside
/// [`RUN_TABLES`].
pub const POINTS: &str = "points";

/// The table of the user's regions ([`crate::regions_table`]) a contour run given regions
/// writes beside [`POINTS`].
pub const REGION_SERIES: &str = "region_series";

/// The table a run with drift correction ([`SequenceOptions::drift_corrected`]) writes besides
/// [`RUN_TABLES`]: the matches of its reference pairs ([`crate::reference_matches_table`]).
pub const REFERENCE_MATCHES: &str = "reference_matches";

/// The tables a run with these options writes, by name: [`RUN_TABLES`], and
/// [`REFERENCE_MATCHES`] with drift correction.
pub fn run_table_names(options: &SequenceOptions) -> Vec<&'static str> {
    let mut names = RUN_TABLES.to_vec();
    if options.drift_corrected() {
        names.push(REFERENCE_MATCHES);
    }
    names
}

/// The table files of a run folder whose tables are written as `tables` by a run with these
/// options: those of [`run_table_names`] and `pairs.json`.
pub fn run_table_files(tables: TableFormat, options: &SequenceOptions) -> Vec<String> {
    let mut files: Vec<String> = run_table_names(options)
        .iter()
        .map(|t| tables.file_name(t))
        .collect();
    files.insert(1, "pairs.json".into());
    files
}

/// Which figures a run draws (`--figures`, `figures=`): the summary figures (the tracks over
/// the peak pressure, the force and contact-area curves, the peak-pressure image with its
/// outlines), those and a match figure per pair, or none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FigureSet {
    /// The summary figures: `tracks`, `curves` and `peak`, a few files whatever the
    /// recording's length.
    #[default]
    Summary,
    /// The summary figures and a match figure per pair (`figures/pair_*`).
    Pairs,
    /// No figures.
    None,
}

modal_core::choice!(FigureSet, "figures", [
    "summary" => FigureSet::Summary,
    "pairs" => FigureSet::Pairs,
    "none" => FigureSet::None,
]);

/// Which anatomical regions a run divides the footprint into (`--region-rule`,
/// `region_rule=`; [`pedo_io::regions`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RegionChoice {
    /// No regions.
    #[default]
    None,
    /// Hindfoot, midfoot, forefoot, toes.
    Coarse,
    /// Medial and lateral heel, midfoot, first, second and lateral metatarsal heads, hallux,
    /// lesser toes.
    Fine,
}

modal_core::choice!(RegionChoice, "region_rule", [
    "none" => RegionChoice::None,
    "coarse" => RegionChoice::Coarse,
    "fine" => RegionChoice::Fine,
]);

impl RegionChoice {
    /// The rule of [`pedo_io::regions`], `None` for no regions.
    pub fn rule(self) -> Option<pedo_io::regions::RegionRule> {
        match self {
            RegionChoice::None => None,
            RegionChoice::Coarse => Some(pedo_io::regions::RegionRule::Coarse),
            RegionChoice::Fine => Some(pedo_io::regions::RegionRule::Fine),
        }
    }
}

/// The file format of a run's figures (`--figure-format`, `figure_format=`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FigureFormat {
    /// PNG images.
    #[default]
    Png,
    /// SVG drawings.
    Svg,
}

modal_core::choice!(FigureFormat, "figure_format", [
    "png" => FigureFormat::Png,
    "svg" => FigureFormat::Svg,
]);

/// The interactive report of a run (`--report`, `report=`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReportFormat {
    /// A self-contained `report.html` that opens offline.
    #[default]
    Html,
    /// No report.
    None,
}

modal_core::choice!(ReportFormat, "report", [
    "html" => ReportFormat::Html,
    "none" => ReportFormat::None,
]);

/// The recording played back (`--animation`, `animation=`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AnimationFormat {
    /// `animation.gif`: the pressure frames with their contours and matches.
    Gif,
    /// No animation.
    #[default]
    None,
}

modal_core::choice!(AnimationFormat, "animation", [
    "gif" => AnimationFormat::Gif,
    "none" => AnimationFormat::None,
]);

modal_core::option_set! {
    /// The output options of a run or study (`pedomatch run`/`demo`/`batch`,
    /// `pymodal.run(out=...)`, `pymodal.batch`; `pedomatch match` takes `figures` and `report`),
    /// in the order the front ends list them: what a run folder holds besides its tables and
    /// `summary.json`, and the tables' format. [`RunOutputs::of`] turns them into the outputs.
    OutputOptions {
        let _d = ();
        /// Which figures a run draws.
        figures: FigureSet = FigureSet::default();
            Word(<FigureSet as Choice>::NAMES), FigureSet::default(),
            "Figures: summary (tracks.*, the tracks over the peak pressure; curves.*, total force and contact area over time; peak.*, the peak-pressure image with its outlines), pairs (those and a match figure of every matched pair, under figures/) or none.";
        /// The figures' file format.
        figure_format: FigureFormat = FigureFormat::default();
            Word(<FigureFormat as Choice>::NAMES), FigureFormat::default(),
            "File format of the figures: png or svg.";
        /// The tables' file format.
        tables: TableFormat = TableFormat::default();
            Word(<TableFormat as Choice>::NAMES), TableFormat::default(),
            "File format of the tables (pairs, objects, matches, tracks, frames, and reference_matches with drift correction; a batch's study table): csv, or parquet (typed, snappy-compressed columns with the CSV's names and values, for pandas, polars or Dask).";
        /// The interactive report.
        report: ReportFormat = ReportFormat::default();
            Word(<ReportFormat as Choice>::NAMES), ReportFormat::default(),
            "The interactive report: html writes a self-contained report.html that opens offline; none writes none.";
        /// The recording played back.
        animation: AnimationFormat = AnimationFormat::default();
            Word(<AnimationFormat as Choice>::NAMES), AnimationFormat::default(),
            "The recording played back: gif writes animation.gif (pressure frames with their contours and matches; long runs decimated to at most 150 frames); none writes none.";
        /// The anatomical regions of the footprint.
        region_rule: RegionChoice = RegionChoice::default();
            Word(<RegionChoice as Choice>::NAMES), RegionChoice::default(),
            "Anatomical regions of the footprint, found from the peak image and the centre of pressure's path, with each region's peak pressure, PTI, FTI, contact area, contact time and share of the impulse (regions.csv, regions.json, regions.npy, regions.png): coarse (hindfoot, midfoot, forefoot, toes), fine (medial and lateral heel, midfoot, first, second and lateral metatarsal heads, hallux, lesser toes) or none. Each insole of a two-insole pedar recording is divided and carried on its own; a streamed run keeps its frames for them. Each region is also carried through every stance with the foot (moving, beside the fixed masks: regions.csv's kind, region_series.csv), by the contour field: a surface or isocontour run makes the contour run of its frames for it.";
        /// The user's region masks over the peak image.
        masks: Option<PathOrRows> = None;
            Value, "none",
            "Region masks drawn over the peak image, measured as the automatic regions (regions.csv, regions.json, regions.npy, regions.png, and each region's curves in curves.csv): a label image of the recording's rows x columns (.npy, a CSV grid or an image; Python also takes a 2-D array; 0 = no region, label k named region_k), or a CSV of polygons region,x_mm,y_mm (or region,x,y in sensels), one vertex a line, named by their region column. Instead of region_rule; they are carried through every stance as the rule's are.";
    }
}

impl OutputOptions {
    /// The regions come from a rule or from the user's masks, not both.
    pub fn validate(&self) -> std::result::Result<(), modal_core::OptionError> {
        if self.masks.is_some() && self.region_rule != RegionChoice::None {
            return Err(modal_core::OptionError::new(
                "masks",
                "masks with a region_rule",
                "region_rule none when masks are given (the masks are the regions measured)",
            ));
        }
        Ok(())
    }
}

/// The output options' declarations ([`OutputOptions`]).
pub fn output_option_specs() -> Vec<OptionSpec> {
    OutputOptions::specs()
}

/// Which figure files a run writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FigureKinds {
    /// Write PNG figures (`tracks.png`, ..., `figures/pair_*.png`).
    pub png: bool,
    /// Write SVG figures (`tracks.svg`, ..., `figures/pair_*.svg`).
    pub svg: bool,
}

impl FigureKinds {
    /// The files of `set` in `format`: none for [`FigureSet::None`].
    pub fn of(set: FigureSet, format: FigureFormat) -> Self {
        let drawn = set != FigureSet::None;
        Self {
            png: drawn && format == FigureFormat::Png,
            svg: drawn && format == FigureFormat::Svg,
        }
    }

    /// Whether any figure file is written.
    pub fn any(&self) -> bool {
        self.png || self.svg
    }

    /// The file extensions written (`"png"`, `"svg"`).
    pub fn extensions(&self) -> Vec<&'static str> {
        [(self.png, "png"), (self.svg, "svg")]
            .into_iter()
            .filter_map(|(asked, ext)| asked.then_some(ext))
            .collect()
    }
}

/// The summary figures of a run, by stem (written as `STEM.png` or `STEM.svg`): the tracks
/// over the peak pressure, the force and contact-area curves, the peak-pressure image (with the
/// contact outlines) and the pressure-time-integral image ([`crate::write_measures`]).
pub const SUMMARY_FIGURES: [&str; 4] = ["tracks", "curves", "peak", "pti"];

/// A finished run of one recording, as the writers of its folder see it.
pub struct RunRecord<'a> {
    /// The input's name and SHA-256, for the summary.
    pub input: &'a InputInfo,
    /// The recording run, its unit overrides applied ([`pedo_track::run_options`]).
    pub recording: &'a Recording,
    /// The parameters the options came from.
    pub params: &'a RunParams,
    /// The options the run used.
    pub options: &'a SequenceOptions,
    /// What the run produced.
    pub result: &'a SequenceResult,
}

/// What a run folder holds besides its tables and `summary.json`.
#[derive(Debug, Clone, Default)]
pub struct RunOutputs {
    /// The figure files to write: the summary figures ([`SUMMARY_FIGURES`]) in these formats.
    pub figures: FigureKinds,
    /// With [`figures`](Self::figures): a match figure per pair too (`figures/pair_*`).
    pub pair_figures: bool,
    /// Write `report.html`, the interactive report ([`report_page`]).
    pub report: bool,
    /// `animation.gif`: the frames with their contours and matches (`--animation gif`).
    pub animation: bool,
    /// The file format of the tables (and of a study's table).
    pub tables: TableFormat,
    /// The rule of the footprint's anatomical regions (`regions.*`), `None` for none.
    pub regions: Option<pedo_io::regions::RegionRule>,
    /// The user's region masks over the peak image (`regions.*` instead of a rule's), read for
    /// each recording ([`user_masks_for`]).
    pub masks: Option<std::sync::Arc<PathOrRows>>,
}

impl RunOutputs {
    /// Whether the run measures regions: by a rule or the user's masks.
    pub fn any_regions(&self) -> bool {
        self.regions.is_some() || self.masks.is_some()
    }
}

/// The user's masks of `outputs` read for `recording` (`None` without masks).
///
/// # Errors
///
/// Those of [`pedo_io::user_masks::read_user_masks`] and
/// [`pedo_io::user_masks::user_masks_of_rows`]: a file that cannot be read, masks of another
/// shape than the recording's frames, polygons that overlap or hold no sensel. On a recording
/// of both feet apart each region is divided per foot ([`RegionMasks::per_foot`]).
///
/// [`RegionMasks::per_foot`]: pedo_io::regions::RegionMasks::per_foot
pub fn user_masks_for(
    outputs: &RunOutputs,
    recording: &Recording,
) -> Result<Option<pedo_io::regions::RegionMasks>> {
    use pedo_io::user_masks::{read_user_masks, user_masks_of_rows};
    let (rows, cols) = (recording.rows(), recording.cols());
    outputs
        .masks
        .as_deref()
        .map(|m| match m {
            PathOrRows::Path(p) => read_user_masks(p, rows, cols, recording.pitch_mm),
            PathOrRows::Rows(values) => user_masks_of_rows(values, rows, cols),
        })
        .transpose()?
        // On a recording of both feet apart each region is measured per foot.
        .map(|m| m.per_foot(&recording.feet))
        .transpose()
}

/// The regions `outputs` ask to measure on `recording`: the user's masks (read and checked
/// against the recording's grid), else the rule's, else none.
///
/// # Errors
///
/// Those of [`user_masks_for`].
pub fn regions_asked(
    outputs: &RunOutputs,
    recording: &Recording,
) -> Result<Option<crate::RegionsAsked>> {
    Ok(
        match (outputs.regions, user_masks_for(outputs, recording)?) {
            (_, Some(masks)) => Some(crate::RegionsAsked::Masks(Box::new(masks))),
            (Some(rule), None) => Some(crate::RegionsAsked::Rule(rule)),
            (None, None) => None,
        },
    )
}

impl RunOutputs {
    /// The outputs the option values name ([`OutputOptions`]): the one place a front end's
    /// words become outputs.
    pub fn of(o: &OutputOptions) -> Self {
        Self {
            figures: FigureKinds::of(o.figures, o.figure_format),
            pair_figures: o.figures == FigureSet::Pairs,
            report: o.report == ReportFormat::Html,
            animation: o.animation == AnimationFormat::Gif,
            tables: o.tables,
            regions: o.region_rule.rule(),
            masks: o.masks.clone().map(std::sync::Arc::new),
        }
    }
}

/// Whether a run writes only its tables and `summary.json` (no figures, report or animation):
/// such a run streams ([`stream_run_folder`]), and its memory does not grow with the
/// recording's length.
pub fn tables_only(outputs: &RunOutputs) -> bool {
    !outputs.figures.any() && !outputs.report && !outputs.animation
}

/// The recording at `path` read for a run with these parameters and outputs: a run that
/// streams (tables only, and [`RunParams::streams`]) reads a file's frames as it goes when its
/// format allows ([`pedo_io::formats::read_for_run`]), never held whole; any other run reads it
/// whole. Either way with the SHA-256 of the bytes parsed.
pub fn read_for_run(
    path: &Path,
    read: &ReadOptions,
    params: &RunParams,
    outputs: &RunOutputs,
) -> Result<pedo_io::formats::RunInput> {
    match run_reads_whole(params, outputs) {
        None => pedo_io::formats::read_for_run(path, read),
        Some(_) => {
            let (recording, sha256) = pedo_io::formats::read_hashed(path, read)?;
            Ok(pedo_io::formats::RunInput {
                recording,
                frames: None,
                sha256,
            })
        }
    }
}

/// Why a run with these parameters and outputs reads its recording whole whatever its format,
/// `None` when it reads a file's frames as it goes if the format allows
/// ([`pedo_io::formats::why_read_whole`]).
fn run_reads_whole(params: &RunParams, outputs: &RunOutputs) -> Option<&'static str> {
    if !tables_only(outputs) {
        Some("the figures, the report or the animation are drawn from the whole recording")
    } else if !params.streams() {
        Some("the isocontour model, drift correction, points and regions need the whole run")
    } else if params.units.time_axis == Some(pedo_io::units::TimeAxis::Last) {
        // The frames of a time-last array are spread over all of it.
        Some("an array transposed from time-last is read whole")
    } else {
        None
    }
}

/// `summary.json`'s `input.read_whole`: why a run that did not read its file's frames as it
/// went (`streamed`, `input.streamed`) read them whole (the first reason that applies), `None`
/// when it streamed. `also`: the run's whole result is returned too ([`RunPlan::also`]).
fn read_whole(run: &RunOf<'_>, outputs: &RunOutputs, streamed: bool, also: bool) -> Value {
    let why = match () {
        _ if streamed => None,
        _ => match run_reads_whole(run.params, outputs) {
            Some(why) => Some(why.to_string()),
            None if also => Some("the whole result is returned".to_string()),
            None => (run.input.why_read_whole()).or(Some("the recording was read whole".into())),
        },
    };
    json!(why)
}

/// The tables of a run folder written as [`stream_sequence`] makes them: every row goes to its
/// file at once (the skipped pairs, few, are kept for the end of the pairs table).
pub struct TablesSink<'a> {
    dir: &'a OutDir,
    recording: &'a Recording,
    format: TableFormat,
    pairs: crate::TableWriter,
    pairs_json: std::io::BufWriter<std::fs::File>,
    json_rows: crate::JsonRows,
    objects: crate::TableWriter,
    matches: crate::TableWriter,
    frames: crate::TableWriter,
    /// With drift correction: the matches of the reference pairs.
    reference_matches: Option<crate::TableWriter>,
    /// Started with the first track: its columns depend on the objects' dimension.
    tracks: Option<crate::TableWriter>,
    /// The dimension of the first object.
    dim: Option<usize>,
}

impl<'a> TablesSink<'a> {
    /// Starts the tables of a run of `recording` with `options` in `dir` ([`run_table_names`]).
    pub fn create(
        dir: &'a OutDir,
        recording: &'a Recording,
        options: &SequenceOptions,
        format: TableFormat,
    ) -> Result<Self> {
        let pairs_header = crate::pairs_header(recording).header;
        let reference_header = crate::matches_header(recording, "tracked").header;
        let reference_matches = options
            .drift_corrected()
            .then(|| crate::TableWriter::create(dir, format, REFERENCE_MATCHES, &reference_header))
            .transpose()?;
        Ok(Self {
            dir,
            recording,
            format,
            pairs: crate::TableWriter::create(dir, format, "pairs", &pairs_header)?,
            pairs_json: dir.create_file("pairs.json")?,
            json_rows: crate::JsonRows::new(&pairs_header),
            objects: crate::TableWriter::create(
                dir,
                format,
                "objects",
                &crate::objects_header(recording).header,
            )?,
            matches: crate::TableWriter::create(
                dir,
                format,
                "matches",
                &crate::matches_header(recording, "trackable").header,
            )?,
            frames: crate::TableWriter::create(
                dir,
                format,
                "frames",
                &crate::frames_header(recording).header,
            )?,
            reference_matches,
            tracks: None,
            dim: None,
        })
    }

    fn pair_row(&mut self, cells: &[Cell]) -> Result<()> {
        self.pairs.push(self.dir, cells)?;
        self.json_rows
            .push(&mut self.pairs_json, cells)
            .map_err(|e| self.dir.failed("pairs.json", e))
    }

    fn tracks_writer(&mut self) -> Result<&mut crate::TableWriter> {
        if self.tracks.is_none() {
            let header = crate::tracks_header_of(self.recording, self.dim.unwrap_or(2)).header;
            self.tracks = Some(crate::TableWriter::create(
                self.dir,
                self.format,
                "tracks",
                &header,
            )?);
        }
        self.tracks
            .as_mut()
            .ok_or_else(|| IoError::invalid("tracks table not started"))
    }

    /// Ends the tables: the skipped pairs of `counts` close the pairs table.
    pub fn finish(mut self, counts: &RunCounts) -> Result<()> {
        for s in &counts.skipped_pairs {
            let cells = crate::skipped_pair_cells(self.recording, s);
            self.pair_row(&cells)?;
        }
        self.tracks_writer()?;
        let dir = self.dir;
        self.pairs.finish(dir)?;
        let failed = |e| dir.failed("pairs.json", e);
        self.json_rows
            .finish(&mut self.pairs_json)
            .map_err(failed)?;
        std::io::Write::flush(&mut self.pairs_json).map_err(failed)?;
        self.objects.finish(dir)?;
        self.matches.finish(dir)?;
        self.frames.finish(dir)?;
        if let Some(t) = self.tracks {
            t.finish(dir)?;
        }
        if let Some(t) = self.reference_matches {
            t.finish(dir)?;
        }
        Ok(())
    }
}

impl SequenceSink for TablesSink<'_> {
    fn frames(&mut self, first: usize, measures: &[FrameMeasures]) -> Result<()> {
        let (dir, frames) = (self.dir, &mut self.frames);
        crate::measures_rows(self.recording, first, measures, &mut |cells| {
            frames.push(dir, &cells)
        })
    }

    fn frame_objects(&mut self, _: usize, objects: &[SequenceObject]) -> Result<()> {
        for object in objects {
            self.dim.get_or_insert(object.shape.dim());
            self.objects
                .push(self.dir, &crate::object_cells(self.recording, object))?;
        }
        Ok(())
    }

    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()> {
        let cells = crate::pair_cells(self.recording, &pair.row);
        self.pair_row(&cells)?;
        let (dir, matches) = (self.dir, &mut self.matches);
        crate::pair_match_rows(self.recording, pair, a, b, &mut |cells| {
            matches.push(dir, &cells)
        })
    }

    fn track(
        &mut self,
        index: usize,
        steps: &[(&SequenceObject, usize)],
        round_trip: Option<f64>,
    ) -> Result<()> {
        let dim = self.dim.unwrap_or(2);
        let (dir, recording) = (self.dir, self.recording);
        let tracks = self.tracks_writer()?;
        crate::track_rows(recording, index, steps, dim, round_trip, &mut |cells| {
            tracks.push(dir, &cells)
        })
    }

    fn reference_pair(
        &mut self,
        pair: &PairMatch,
        a: &SequenceObject,
        b: &SequenceObject,
        tracked: &[bool],
    ) -> Result<()> {
        let (dir, recording) = (self.dir, self.recording);
        let Some(writer) = self.reference_matches.as_mut() else {
            return Err(IoError::invalid(
                "a reference pair handed to the tables of a run without drift correction",
            ));
        };
        crate::reference_pair_rows(recording, pair, a, b, tracked, &mut |cells| {
            writer.push(dir, &cells)
        })
    }
}

/// What one run is, besides its recording and options: where its frames come from, who it is
/// for, and what it writes.
pub struct RunPlan<'a> {
    /// The input's name and SHA-256, for the summary.
    pub input: &'a InputInfo,
    /// The parameters the options came from ([`pedo_track::run_options`]).
    pub params: &'a RunParams,
    /// Reads the frames as the run goes when the recording holds none (see
    /// [`pedo_io::formats::read_for_streaming`]).
    pub frames: Option<&'a mut dyn FrameSource>,
    /// The run's folder; `None` writes nothing (the summary is still made).
    pub folder: Option<&'a Path>,
    /// What the folder holds besides its tables and `summary.json`; only figures, a report or
    /// an animation make the run whole instead of streamed ([`tables_only`]).
    pub outputs: &'a RunOutputs,
    /// Stages measured before the run (e.g. reading), for the summary.
    pub timings: &'a [(&'a str, f64)],
    /// A sink that hears every event of the run besides the folder's own, e.g. a
    /// [`Collect`] gathering the result `pymodal.run(out=...)` returns: one run feeds both, so
    /// the folder is the one the command line writes; `None` for the others.
    pub also: Option<&'a mut dyn SequenceSink>,
}

/// Runs `recording` and writes its folder as `plan` says: the engine
/// ([`stream_sequence`]) hands the run's events to the folder's sinks ([`FolderSink`]) as it
/// makes them, whatever the outputs (a run with tables only holds nothing of the run; one with
/// figures, a report or an animation gathers what they need). Returns the summary
/// (`summary.json`) and the run's counts. What `pedomatch run` and every recording of a study
/// do after reading.
pub fn run_into_folder(
    recording: &Recording,
    options: &SequenceOptions,
    plan: RunPlan<'_>,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<(Value, RunCounts)> {
    let RunPlan {
        input,
        params,
        frames,
        folder,
        outputs,
        timings,
        also,
    } = plan;
    let run = RunOf {
        input,
        recording,
        params,
        options,
    };
    match folder {
        Some(folder) => write_folder(
            folder,
            &run,
            outputs,
            timings,
            Feed::Run {
                frames,
                progress,
                also,
            },
        ),
        None => {
            let streamed = frames.is_some();
            let read_whole = read_whole(&run, outputs, streamed, also.is_some());
            let mut measures = crate::MeasuresSink::new(recording, options)?;
            let mut none = NoSink;
            let also = also.unwrap_or(&mut none);
            let mut sink = WithMeasures {
                measures: &mut measures,
                also,
            };
            let counts = stream_sequence(recording, frames, options, progress, &mut sink)?;
            require_objects(counts.objects, recording, options)?;
            let mut summary =
                crate::run_summary_of(input, recording, params, options, &counts, timings);
            crate::set_summary_measures(&mut summary, &measures.finish()?);
            summary["input"]["streamed"] = json!(streamed);
            summary["input"]["read_whole"] = read_whole;
            Ok((summary, counts))
        }
    }
}

/// A run without a folder: its measures taken, every event handed on to the caller's sink.
struct WithMeasures<'a> {
    measures: &'a mut crate::MeasuresSink,
    also: &'a mut dyn SequenceSink,
}

impl SequenceSink for WithMeasures<'_> {
    fn frames(&mut self, first: usize, measures: &[FrameMeasures]) -> Result<()> {
        self.also.frames(first, measures)
    }
    fn wants_frame_values(&self) -> bool {
        true
    }
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        self.measures.frame_values(frame, values)?;
        if self.also.wants_frame_values() {
            self.also.frame_values(frame, values)?;
        }
        Ok(())
    }
    fn stored_frame_values(&mut self, frame: usize, stored: StoredValues<'_>) -> Result<()> {
        self.measures.stored_frame_values(frame, stored)?;
        if self.also.wants_frame_values() {
            self.also.stored_frame_values(frame, stored)?;
        }
        Ok(())
    }
    fn frame_objects(&mut self, frame: usize, objects: &[SequenceObject]) -> Result<()> {
        self.also.frame_objects(frame, objects)
    }
    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()> {
        self.also.pair(pair, a, b)
    }
    fn skipped_pair(&mut self, a: &SequenceObject, b: &SequenceObject, reason: &str) -> Result<()> {
        self.also.skipped_pair(a, b, reason)
    }
    fn settled(&mut self, object: usize) -> Result<()> {
        self.also.settled(object)
    }
    fn track(
        &mut self,
        index: usize,
        steps: &[(&SequenceObject, usize)],
        round_trip: Option<f64>,
    ) -> Result<()> {
        self.also.track(index, steps, round_trip)
    }
    fn reference_pair(
        &mut self,
        pair: &PairMatch,
        a: &SequenceObject,
        b: &SequenceObject,
        tracked: &[bool],
    ) -> Result<()> {
        self.also.reference_pair(pair, a, b, tracked)
    }
}

/// Runs `recording` as [`stream_sequence`] and writes the folder `out` of a run with tables
/// only ([`tables_only`]), whole or not at all, by the one writer of every run folder
/// ([`run_into_folder`]): the tables are written as the run makes them, so neither the run nor
/// its tables are ever held. `frames` reads the frames when `recording` holds none (see
/// [`pedo_io::formats::read_for_streaming`]). `timings` are the stages measured before (e.g.
/// reading). Returns the summary and the run's counts.
#[allow(clippy::too_many_arguments)]
pub fn stream_run_folder(
    out: &Path,
    input: &InputInfo,
    recording: &Recording,
    frames: Option<&mut dyn FrameSource>,
    params: &RunParams,
    options: &SequenceOptions,
    tables: TableFormat,
    timings: &[(&str, f64)],
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<(Value, RunCounts)> {
    let run = RunOf {
        input,
        recording,
        params,
        options,
    };
    let outputs = RunOutputs {
        tables,
        ..RunOutputs::default()
    };
    let also = None;
    let feed = Feed::Run {
        frames,
        progress,
        also,
    };
    write_folder(out, &run, &outputs, timings, feed)
}

/// A run's recording, options and provenance, without its results.
struct RunOf<'a> {
    input: &'a InputInfo,
    recording: &'a Recording,
    params: &'a RunParams,
    options: &'a SequenceOptions,
}

/// Where a folder's events come from: the engine running the recording, or a run already made.
enum Feed<'f, 'p> {
    /// [`stream_sequence`], reading the frames from `frames` when the recording holds none,
    /// its events also handed to `also` ([`RunPlan::also`]).
    Run {
        frames: Option<&'f mut dyn FrameSource>,
        progress: &'p (dyn Fn(Stage, usize, usize) + Sync),
        also: Option<&'f mut dyn SequenceSink>,
    },
    /// [`replay`] of a whole result ([`write_run_folder`]: a result already made, which the
    /// tests compare a streamed folder with).
    Replay(&'p SequenceResult),
}

/// The sinks of a run folder: the tables, written as the events come ([`TablesSink`]); for the
/// figures and the report, what they draw gathered from the events in memory bounded whatever
/// the recording's length ([`FrameCurves`], [`TracksGather`], [`ReportGather`]); and, only for
/// what needs the run's every object and pair (the material points of a contour run, the pair
/// figures of `--figures pairs`, the animation), those objects and pairs ([`Collect`], each pair
/// without its match details, no tracks); and the caller's own sink, if any ([`RunPlan::also`]).
pub struct FolderSink<'a, 's> {
    tables: TablesSink<'a>,
    whole: Option<Collect>,
    /// The material points of a contour run, followed as the events come.
    points: Option<FollowSink<'a>>,
    /// The caller's own sink, if any ([`RunPlan::also`]): every event, as it comes.
    also: Option<&'s mut dyn SequenceSink>,
    /// The recording's measures (`peak.npy`, `pti.npy`, `mean.npy`, `measures.json`), summed
    /// as the frames come.
    measures: crate::MeasuresSink,
    /// For the curves figure: each frame's total force and contact area (a few numbers a frame).
    curves: Option<FrameCurves>,
    /// For the tracks figure: its longest tracks.
    tracks: Option<TracksGather>,
    /// For `report.html`: its player's frames and the time series.
    report: Option<ReportGather>,
}

/// The total force and contact area of every frame of a run, as the `frames` events hand them
/// over: what the curves figure draws.
#[derive(Debug, Clone, Default)]
pub struct FrameCurves {
    /// The frames, in order.
    pub frames: Vec<usize>,
    /// Total force (or load) per frame, as `frames.csv` gives it.
    pub force: Vec<f64>,
    /// Contact area per frame (mm², or sensels without a pitch).
    pub area: Vec<f64>,
}

impl SequenceSink for FrameCurves {
    fn frames(&mut self, first: usize, measures: &[FrameMeasures]) -> Result<()> {
        for (k, m) in measures.iter().enumerate() {
            self.frames.push(first + k);
            self.force.push(m.total_force);
            self.area.push(m.contact_area);
        }
        Ok(())
    }
}

impl<'a> FolderSink<'a, '_> {
    /// The sinks `outputs` asks for in `dir`, for a run of `run`: the tables always; the whole
    /// run when `gather`; what the figures and the report draw; the measures, which keep the
    /// frames when the run is `streamed` and regions are carried. No material points and no
    /// caller's sink yet (the fields `points` and `also`).
    fn for_folder(
        dir: &'a OutDir,
        run: &RunOf<'a>,
        outputs: &RunOutputs,
        gather: bool,
        streamed: bool,
    ) -> Result<Self> {
        let figures = outputs.figures.any();
        let measures = crate::MeasuresSink::new(run.recording, run.options)?;
        Ok(FolderSink {
            tables: TablesSink::create(dir, run.recording, run.options, outputs.tables)?,
            whole: gather.then(|| Collect::new(false)),
            points: None,
            also: None,
            curves: figures.then(FrameCurves::default),
            tracks: figures.then(|| TracksGather::new(TRACKS_MIN_STEPS, TRACKS_SHOWN)),
            report: (outputs.report).then(|| ReportGather::new(run.recording, run.options.frames)),
            measures: if streamed && outputs.any_regions() {
                measures.keeping_frames(run.recording)
            } else {
                measures
            },
        })
    }

    /// The caller's own sink, if any ([`RunPlan::also`]).
    fn also(&mut self) -> Option<&mut dyn SequenceSink> {
        self.also
            .as_mut()
            .map(|a| &mut **a as &mut dyn SequenceSink)
    }
}

impl SequenceSink for FolderSink<'_, '_> {
    fn frames(&mut self, first: usize, measures: &[FrameMeasures]) -> Result<()> {
        if let Some(c) = self.curves.as_mut() {
            c.frames(first, measures)?;
        }
        self.tables.frames(first, measures)?;
        self.also().map_or(Ok(()), |s| s.frames(first, measures))
    }
    fn wants_frame_values(&self) -> bool {
        true
    }
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        self.measures.frame_values(frame, values)?;
        match self.also() {
            Some(s) if s.wants_frame_values() => s.frame_values(frame, values),
            _ => Ok(()),
        }
    }
    fn stored_frame_values(&mut self, frame: usize, stored: StoredValues<'_>) -> Result<()> {
        self.measures.stored_frame_values(frame, stored)?;
        match self.also() {
            Some(s) if s.wants_frame_values() => s.stored_frame_values(frame, stored),
            _ => Ok(()),
        }
    }
    fn frame_objects(&mut self, frame: usize, objects: &[SequenceObject]) -> Result<()> {
        self.tables.frame_objects(frame, objects)?;
        if let Some(t) = self.tracks.as_mut() {
            t.frame_objects(frame, objects)?;
        }
        if let Some(r) = self.report.as_mut() {
            r.frame_objects(frame, objects)?;
        }
        if let Some(w) = self.whole.as_mut() {
            w.frame_objects(frame, objects)?;
        }
        if let Some(p) = self.points.as_mut() {
            p.frame_objects(frame, objects)?;
        }
        self.also()
            .map_or(Ok(()), |s| s.frame_objects(frame, objects))
    }
    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()> {
        self.tables.pair(pair, a, b)?;
        if let Some(r) = self.report.as_mut() {
            r.pair(pair, a, b)?;
        }
        if let Some(w) = self.whole.as_mut() {
            w.pair(pair, a, b)?;
        }
        if let Some(p) = self.points.as_mut() {
            p.pair(pair, a, b)?;
        }
        self.also().map_or(Ok(()), |s| s.pair(pair, a, b))
    }
    fn skipped_pair(&mut self, a: &SequenceObject, b: &SequenceObject, reason: &str) -> Result<()> {
        if let Some(p) = self.points.as_mut() {
            p.skipped_pair(a, b, reason)?;
        }
        self.also().map_or(Ok(()), |s| s.skipped_pair(a, b, reason))
    }
    fn settled(&mut self, object: usize) -> Result<()> {
        if let Some(p) = self.points.as_mut() {
            p.settled(object)?;
        }
        self.also().map_or(Ok(()), |s| s.settled(object))
    }
    fn track(
        &mut self,
        index: usize,
        steps: &[(&SequenceObject, usize)],
        round_trip: Option<f64>,
    ) -> Result<()> {
        self.tables.track(index, steps, round_trip)?;
        if let Some(t) = self.tracks.as_mut() {
            t.track(index, steps, round_trip)?;
        }
        if let Some(r) = self.report.as_mut() {
            r.track(index, steps, round_trip)?;
        }
        self.also()
            .map_or(Ok(()), |s| s.track(index, steps, round_trip))
    }
    fn reference_pair(
        &mut self,
        pair: &PairMatch,
        a: &SequenceObject,
        b: &SequenceObject,
        tracked: &[bool],
    ) -> Result<()> {
        self.tables.reference_pair(pair, a, b, tracked)?;
        self.also()
            .map_or(Ok(()), |s| s.reference_pair(pair, a, b, tracked))
    }
}

/// Writes the folder `out` of `run`, whole or not at all, from the events of `feed`: the one
/// writer of every run folder, streamed or whole, from the command line, a study or Python.
/// A folder with figures, a report or an animation, whose outputs draw the whole run (gathered
/// from the engine, or the result replayed), also holds the material points (`points`, contour
/// model: [`pedo_track::follow::run_points`], followed beside the figures on a second thread);
/// a folder with tables only writes none, from any front end, since a streamed run holds
/// nothing to follow them on (so `pymodal.run(out=...)` and a study's folder stay the same).
/// `timings` are the stages measured before (e.g. reading); the time spent writing is added
/// as `output`.
fn write_folder(
    out: &Path,
    run: &RunOf<'_>,
    outputs: &RunOutputs,
    timings: &[(&str, f64)],
    feed: Feed<'_, '_>,
) -> Result<(Value, RunCounts)> {
    let started = Instant::now();
    let (streamed, read_whole) = match &feed {
        Feed::Run { frames, also, .. } => {
            let streamed = frames.is_some();
            (streamed, read_whole(run, outputs, streamed, also.is_some()))
        }
        Feed::Replay(_) => (false, json!("the run was made whole first")),
    };
    // The user's masks are read (and checked against the recording) before the run.
    let asked = regions_asked(outputs, run.recording)?;
    let dir = OutDir::create(out)?;
    // The material points of a contour run are followed as the events come (with any output
    // besides the tables; the user's points and regions whatever the outputs). A replayed run
    // is whole already; a run of the engine gathers its objects and pairs only for what needs
    // them all: the pair figures, the animation and the anatomical regions carried (by a
    // contour run's own objects and pairs).
    let points = run.options.model == ObjectModel::Contour
        && (!tables_only(outputs) || !run.options.inputs.is_empty());
    let pair_figures = outputs.figures.any() && outputs.pair_figures;
    // The anatomical regions are carried through the stances by the contour field: a contour
    // run's own objects and pairs, gathered as they come (streamed or not); for a run of
    // another model, the contour run of its frames, made once the run is done
    // (`follow_anatomy`). A streamed run keeps its frames for them (`keeping_frames`).
    let anatomy = outputs.any_regions();
    let carried = anatomy && run.options.model == ObjectModel::Contour;
    let gather = matches!(feed, Feed::Run { .. }) && (pair_figures || outputs.animation || carried);
    let progress = match &feed {
        Feed::Run { progress, .. } => *progress,
        Feed::Replay(_) => &|_, _, _| {},
    };
    let mut points_table = points
        .then(|| PointsTable::create(&dir, run.recording, run.options, outputs.tables))
        .transpose()?;
    let mut sink = FolderSink::for_folder(&dir, run, outputs, gather, streamed)?;
    sink.points = (points_table.as_mut()).map(|t| FollowSink::new(run.options, t));
    let (counts, ran, replayed) = match feed {
        Feed::Run {
            frames,
            progress,
            also,
        } => {
            sink.also = also;
            let c = stream_sequence(run.recording, frames, run.options, progress, &mut sink)?;
            (c, true, None)
        }
        Feed::Replay(r) => (
            replay(run.recording, run.options, r, &mut sink)?,
            false,
            Some(r),
        ),
    };
    require_objects(counts.objects, run.recording, run.options)?;
    let FolderSink {
        tables,
        whole,
        points: follow,
        curves,
        tracks,
        report,
        measures,
        ..
    } = sink;
    tables.finish(&counts)?;
    let cancel = run.options.cancel.as_ref();
    let gathered = whole.map(|w| w.into_result(counts.clone()));
    // What needs every object and pair: the gathered run, or the one replayed.
    let whole = if pair_figures || outputs.animation || carried {
        replayed.or(gathered.as_ref())
    } else {
        None
    };
    let steps = OutputSteps {
        progress,
        total: output_count(&counts, outputs, points),
        done: AtomicUsize::new(0),
    };
    if let Some(follow) = follow {
        follow.finish()?;
        steps.step();
    }
    let (followed, point_trips) = match points_table.map(PointsTable::finish).transpose()? {
        Some((kept, trips)) => (Some(kept), Some(trips)),
        None => (None, None),
    };
    let rule_name = asked.as_ref().map(crate::RegionsAsked::name);
    let (measures, regions, held) = measures.finish_with_regions(run.recording, asked)?;
    // The frames the regions are carried on: those the run kept, or the recording's own.
    let frames = held.as_ref().unwrap_or(run.recording);
    let moving = match &regions {
        Some(Ok((masks, values))) if anatomy => Some(carry_anatomy(
            run,
            frames,
            whole.filter(|_| carried),
            &measures,
            masks,
            values,
        )),
        _ => None,
    };
    let region_values = match &regions {
        Some(Ok((_, values))) => Some(values.as_slice()),
        _ => None,
    };
    crate::write_measures(
        &dir,
        run.recording,
        &measures,
        region_values,
        outputs.figures,
        outputs.tables,
    )?;
    if let (Some(rule), Some(outcome)) = (rule_name, &regions) {
        crate::write_regions(
            &dir,
            run.recording,
            &measures,
            rule,
            outcome,
            moving.as_ref(),
            outputs.figures,
        )?;
    }
    if outputs.figures.any() {
        steps.step();
    }
    let drawn = Drawn {
        whole,
        curves: curves.unwrap_or_default(),
        tracks,
    };
    let anatomy = match (&regions, &moving) {
        (Some(Ok((masks, _))), Some(Ok(a))) => Some((masks, a, frames)),
        _ => None,
    };
    let user_points = write_figures_and_points(
        &dir,
        run,
        &drawn,
        outputs,
        followed.as_deref(),
        anatomy,
        cancel,
        &steps,
    )?;
    // The run's own stages, when it ran here, are not the output's time.
    let t = counts.timings;
    let run_time = if ran {
        t.objects + t.matching + t.tracks
    } else {
        Default::default()
    };
    let mut stages = timings.to_vec();
    stages.push((
        "output",
        started.elapsed().saturating_sub(run_time).as_secs_f64(),
    ));
    let (i, rec) = (run.input, run.recording);
    let mut summary = crate::run_summary_of(i, rec, run.params, run.options, &counts, &stages);
    if let Some(trips) = point_trips {
        crate::set_point_round_trips(&mut summary, trips);
    }
    summary["input"]["streamed"] = json!(streamed);
    summary["input"]["read_whole"] = read_whole;
    crate::set_summary_measures(&mut summary, &measures);
    if let Some(options) = summary["options"].as_object_mut() {
        record_outputs(options, outputs);
    }
    dir.write("summary.json", pretty(&summary).as_bytes())?;
    if let Some(report) = &report {
        let shown = crate::html_report::ReportMeasures {
            measures: &measures,
            regions: match (rule_name, &regions) {
                (Some(rule), Some(Ok((masks, _)))) => Some((rule, masks)),
                _ => None,
            },
            user_regions: (run.options.inputs.regions.iter())
                .map(|r| (format!("region {}", r.label), r.cells.clone()))
                .collect(),
            points: user_points,
        };
        write_report(&dir, run, report, &summary, &counts, &shown)?;
        steps.step();
    }
    if outputs.animation {
        write_animation(&dir, run, whole)?;
        steps.step();
    }
    // A cancelled run leaves the previous folder (or none), as if it had not run.
    pedo_io::cancel::check(cancel)?;
    dir.commit()?;
    Ok((summary, counts))
}

/// `report.html` of a run: the gathered player and series, the `summary`'s figures and the
/// measures, regions and points `shown`.
fn write_report(
    dir: &OutDir,
    run: &RunOf<'_>,
    report: &ReportGather,
    summary: &Value,
    counts: &RunCounts,
    shown: &crate::html_report::ReportMeasures<'_>,
) -> Result<()> {
    let mut info = report_info(run, summary);
    info.measures = shown.to_json(run.recording.pitch_mm.unwrap_or([1.0, 1.0]));
    let page = report.page(run.recording, counts, &info)?;
    dir.write("report.html", page.as_bytes())
}

/// `animation.gif` of the whole run `whole` (gathered or replayed), over the run's frames.
fn write_animation(dir: &OutDir, run: &RunOf<'_>, whole: Option<&SequenceResult>) -> Result<()> {
    let r = whole.ok_or_else(|| IoError::invalid("the animation needs the whole run"))?;
    let axes = crate::figure::FigureAxes::of_recording(run.recording);
    let animation = crate::figure::Animation {
        recording: run.recording,
        result: r,
        axes: &axes,
        frames: run.options.frames.unwrap_or((0, run.recording.n_frames())),
    };
    dir.write("animation.gif", &animation.to_gif()?)
}

/// What the figures of a run folder are drawn from: the run's objects and pairs when gathered
/// (or replayed), the frames' curves and the longest tracks.
struct Drawn<'r> {
    whole: Option<&'r SequenceResult>,
    curves: FrameCurves,
    tracks: Option<TracksGather>,
}

/// A user's point through the stance, for the report: its name and positions (sensels).
type UserTrack = (String, Vec<[f64; 2]>);

/// A point followed with the frame of each of its steps.
type PointFrames = (pedo_track::follow::FollowedPoint, Vec<usize>);

/// The `points` table of a contour run, written as [`FollowSink`] hands the points over
/// ([`crate::points_table`]'s rows); the user's points and the points of the user's regions
/// (a few) are kept for the report and `region_series`.
struct PointsTable<'a> {
    dir: &'a OutDir,
    writer: crate::TableWriter,
    rows: crate::PointRows<'a>,
    kept: Vec<PointFrames>,
}

impl<'a> PointsTable<'a> {
    fn create(
        dir: &'a OutDir,
        recording: &'a Recording,
        options: &'a SequenceOptions,
        format: TableFormat,
    ) -> Result<Self> {
        let header = crate::points_header(recording).header;
        Ok(Self {
            dir,
            writer: crate::TableWriter::create(dir, format, POINTS, &header)?,
            rows: crate::PointRows::new(recording, &options.inputs),
            kept: Vec::new(),
        })
    }

    /// Ends the table; returns the points kept and the rows' round trips.
    fn finish(self) -> Result<(Vec<PointFrames>, Vec<f32>)> {
        self.writer.finish(self.dir)?;
        Ok((self.kept, self.rows.round_trips))
    }
}

impl pedo_track::follow::PointsSink for PointsTable<'_> {
    fn point(
        &mut self,
        _: usize,
        p: &pedo_track::follow::FollowedPoint,
        frames: &[usize],
    ) -> Result<()> {
        let (writer, dir) = (&mut self.writer, self.dir);
        self.rows
            .point(p, frames, &mut |cells| writer.push(dir, &cells))?;
        if p.kind != pedo_track::follow::Seeded::Outline {
            self.kept.push((p.clone(), frames.to_vec()));
        }
        Ok(())
    }
}

/// The regions `masks` (of values `fixed`) of `run` carried through its stances on the frames of
/// `frames` ([`crate::moving_regions::follow_anatomy`]): by `whole`, the contour run's own objects
/// and pairs, or for a run of another model by the contour field
/// ([`crate::moving_regions::carrying_options`]).
fn carry_anatomy(
    run: &RunOf<'_>,
    frames: &Recording,
    whole: Option<&SequenceResult>,
    measures: &pedo_io::measures::Measures,
    masks: &pedo_io::regions::RegionMasks,
    fixed: &[pedo_io::regions::RegionValues],
) -> crate::moving_regions::MovingOutcome {
    let options = crate::moving_regions::carrying_options(run.params, run.recording, run.options)?;
    crate::moving_regions::follow_anatomy(frames, whole, &options, measures, masks, fixed)
}

/// The figures asked for; then, from the user's points and regions followed (`followed`), the
/// `region_series` table with the anatomical regions carried (`anatomy`). Returns the user's
/// points through the stance (for the report).
#[allow(clippy::too_many_arguments)]
fn write_figures_and_points(
    dir: &OutDir,
    run: &RunOf<'_>,
    drawn: &Drawn<'_>,
    outputs: &RunOutputs,
    followed: Option<&[PointFrames]>,
    anatomy: Option<(
        &pedo_io::regions::RegionMasks,
        &crate::moving_regions::MovingAnatomy,
        &Recording,
    )>,
    cancel: Option<&Cancel>,
    steps: &OutputSteps<'_>,
) -> Result<Vec<UserTrack>> {
    if let Some(tracks) = &drawn.tracks {
        write_figures(
            dir,
            run.recording,
            run.options,
            drawn.whole,
            tracks,
            &drawn.curves,
            outputs,
            cancel,
            &|| steps.step(),
        )?;
    }
    let (rec, inputs) = (run.recording, &run.options.inputs);
    let threshold = run.options.contour.preprocess.threshold.unwrap_or(0.0);
    let followed = followed.unwrap_or_default();
    let user_tracks: Vec<UserTrack> = (followed.iter())
        .filter_map(|(p, _)| match p.kind {
            pedo_track::follow::Seeded::Point(i) => {
                let name = (inputs.points.get(i)).map_or(format!("p{}", i + 1), |u| u.name.clone());
                Some((name, p.steps.iter().map(|&(_, xy)| xy).collect()))
            }
            _ => None,
        })
        .collect();
    let mut series = None;
    if !inputs.regions.is_empty() && !followed.is_empty() {
        let frame_of: std::collections::HashMap<usize, usize> = (followed.iter())
            .flat_map(|(p, frames)| p.steps.iter().map(|s| s.0).zip(frames.iter().copied()))
            .collect();
        let points = pedo_track::follow::FollowedPoints {
            points: followed.iter().map(|(p, _)| p.clone()).collect(),
            anchors: 0,
        };
        let frame = |o: usize| frame_of.get(&o).copied().unwrap_or_default();
        series = Some(crate::regions_table(
            rec, &frame, &points, inputs, threshold,
        )?);
    }
    if let Some((masks, anatomy, frames)) = anatomy {
        let t = series.get_or_insert_with(|| crate::region_series_header(run.recording));
        crate::moving_regions::anatomy_rows(t, frames, masks, anatomy, threshold)?;
    }
    if let Some(series) = series {
        crate::write_table(dir, outputs.tables, REGION_SERIES, &series)?;
    }
    Ok(user_tracks)
}

/// The header of `report.html` of `run`: what its `summary` (`summary.json`) records, the
/// options used and the time spent per stage.
fn report_info(run: &RunOf<'_>, summary: &Value) -> crate::html_report::ReportInfo {
    crate::html_report::ReportInfo {
        format: run.recording.format.map(|f| f.name().to_string()),
        contact_threshold: run.options.contour.preprocess.threshold.unwrap_or(0.0),
        frames: run.options.frames,
        ..crate::html_report::ReportInfo::of_summary(run.input.name.clone(), summary)
    }
}

/// Writes the figures `outputs` asks for: the summary figures ([`SUMMARY_FIGURES`]: the
/// `tracks` gathered from the run's events, the force and contact-area `curves` of its frames,
/// the recording's peak pressure with its contact outlines) and, with
/// [`RunOutputs::pair_figures`], the match figure of every pair of the whole run `whole` (in
/// parallel on the current rayon pool) under `figures/`, as PNG or SVG. Fails with
/// [`IoError::Cancelled`] at the next figure once `cancel` is cancelled, and when pair figures
/// are asked without the whole run. `drawn` is called once per figure written (for a progress
/// bar).
#[allow(clippy::too_many_arguments)]
pub fn write_figures(
    dir: &OutDir,
    recording: &Recording,
    options: &SequenceOptions,
    whole: Option<&SequenceResult>,
    tracks: &TracksGather,
    curves: &FrameCurves,
    outputs: &RunOutputs,
    cancel: Option<&Cancel>,
    drawn: &(dyn Fn() + Sync),
) -> Result<()> {
    let kinds = outputs.figures;
    if !kinds.any() {
        return Ok(());
    }
    let axes = FigureAxes::of_recording(recording);
    if outputs.pair_figures {
        let r = whole.ok_or_else(|| IoError::invalid("pair figures need the whole run"))?;
        r.pairs.par_iter().try_for_each(|p| -> Result<()> {
            pedo_io::cancel::check(cancel)?;
            let (oa, ob) = (&r.objects[p.a], &r.objects[p.b]);
            let fig = MatchFigure {
                a: &oa.shape,
                b: &ob.shape,
                pairs: &p.result.pairs,
                axes: &axes,
                label_a: object_label(oa, recording),
                label_b: object_label(ob, recording),
            };
            let stem = format!("figures/pair_{:04}_{:04}", oa.id, ob.id);
            write_figure(dir, &stem, kinds, || fig.to_png(), || fig.to_svg())?;
            drawn();
            Ok(())
        })?;
    }
    pedo_io::cancel::check(cancel)?;
    let background = tracks.background(recording)?;
    write_figure(
        dir,
        "tracks",
        kinds,
        || tracks.to_png(&background, &axes),
        || tracks.to_svg(&background, &axes),
    )?;
    drawn();
    write_summary_figures(dir, recording, options, curves, kinds, cancel, drawn)
}

/// The summary figures drawn from the recording and the frames' measures alone: `curves.*`
/// (total force and contact area over time) and `peak.*` (the peak-pressure image with the
/// outlines of its contact regions).
fn write_summary_figures(
    dir: &OutDir,
    recording: &Recording,
    options: &SequenceOptions,
    curves: &FrameCurves,
    kinds: FigureKinds,
    cancel: Option<&Cancel>,
    drawn: &(dyn Fn() + Sync),
) -> Result<()> {
    pedo_io::cancel::check(cancel)?;
    let axes = FigureAxes::of_recording(recording);
    if !curves.frames.is_empty() {
        let area_label = if recording.sensel_area().is_some() {
            "contact area (mm²)"
        } else {
            "contact area (sensels)"
        };
        let figure = CurvesFigure {
            frames: &curves.frames,
            curves: vec![
                Curve {
                    label: crate::html_report::load_label(recording),
                    values: &curves.force,
                },
                Curve {
                    label: area_label.to_string(),
                    values: &curves.area,
                },
            ],
            axes: &axes,
        };
        write_figure(dir, "curves", kinds, || figure.to_png(), || figure.to_svg())?;
    }
    drawn();
    pedo_io::cancel::check(cancel)?;
    let peak = recording.peak_image();
    let outlines = peak_outlines(&peak, options)?;
    let figure = PeakFigure {
        peak: &peak,
        outlines: &outlines,
        axes: &axes,
        frames: (0, recording.n_frames()),
    };
    write_figure(dir, "peak", kinds, || figure.to_png(), || figure.to_svg())?;
    drawn();
    Ok(())
}

/// The output stage's progress ([`Stage::Output`]): `done` of `total` outputs, told to the run's
/// progress callback as each is written (figures from several threads).
struct OutputSteps<'p> {
    progress: &'p (dyn Fn(Stage, usize, usize) + Sync),
    total: usize,
    done: AtomicUsize,
}

impl OutputSteps<'_> {
    fn step(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        (self.progress)(Stage::Output, done.min(self.total), self.total);
    }
}

/// How many outputs a folder of a run with these `counts` writes after the run, as
/// [`OutputSteps`] counts them: each figure, the material points (when `points`), the report and
/// the animation.
fn output_count(counts: &RunCounts, outputs: &RunOutputs, points: bool) -> usize {
    let figures = if outputs.figures.any() {
        SUMMARY_FIGURES.len()
            + if outputs.pair_figures {
                counts.pairs
            } else {
                0
            }
    } else {
        0
    };
    figures + usize::from(points) + usize::from(outputs.report) + usize::from(outputs.animation)
}

/// The tracks figure draws the [`TRACKS_SHOWN`] longest tracks spanning at least this many
/// objects.
pub const TRACKS_MIN_STEPS: usize = 3;
/// The most tracks the tracks figure draws.
pub const TRACKS_SHOWN: usize = 40;

/// The outlines of the contact regions of the peak-pressure image `peak`, as the run's contour
/// options draw a frame's (threshold, smoothing; no resampling), in sensels; holes left out.
pub fn peak_outlines(
    peak: &pedo_io::Grid,
    options: &SequenceOptions,
) -> Result<Vec<Vec<[f64; 2]>>> {
    let opts = pedo_io::ContourOptions {
        resample: pedo_io::Resample::None,
        units: pedo_io::CoordUnits::Pixels,
        include_holes: false,
        ..options.contour
    };
    Ok(pedo_io::contours(peak, &opts)?
        .into_iter()
        .filter(|c| !c.hole && c.points.len() > 2)
        .map(|c| c.points)
        .collect())
}

/// An object as a figure's title names it: `object 12`, and for an isocontour its level
/// (`object 3 at 180 kPa`), the pairs of an isocontour run all being in one frame.
fn object_label(o: &SequenceObject, recording: &Recording) -> ObjectLabel {
    let mut label = ObjectLabel::object(o.id, o.frame);
    if let Some(level) = o.level {
        label.name = format!("{} at {level:.0} {}", label.name, recording.units)
            .trim_end()
            .to_string();
    }
    label
}

/// Writes `{stem}.png` and/or `{stem}.svg`.
pub fn write_figure(
    dir: &OutDir,
    stem: &str,
    kinds: FigureKinds,
    to_png: impl FnOnce() -> Result<Vec<u8>>,
    to_svg: impl FnOnce() -> Result<String>,
) -> Result<()> {
    let named = |e: IoError| IoError::Figure(format!("{stem}: {e}"));
    if kinds.png {
        dir.write(&format!("{stem}.png"), &to_png().map_err(named)?)?;
    }
    if kinds.svg {
        dir.write(&format!("{stem}.svg"), to_svg().map_err(named)?.as_bytes())?;
    }
    Ok(())
}

/// Pretty JSON with a final newline.
pub fn pretty(v: &Value) -> String {
    let mut s = serde_json::to_string_pretty(v).unwrap_or_else(|_| v.to_string());
    s.push('\n');
    s
}

/// Writes the folder `out` of a run already made, whole or not at all (see [`crate::outdir`]):
/// its events replayed ([`replay`]) into the sinks every run folder is written by
/// ([`run_into_folder`]). `timings` are the stages measured before the sequence run (e.g.
/// reading); the time spent here is added as `output`. Returns the summary.
pub fn write_run_folder(
    out: &Path,
    run: &RunRecord<'_>,
    outputs: &RunOutputs,
    timings: &[(&str, f64)],
) -> Result<Value> {
    let of = RunOf {
        input: run.input,
        recording: run.recording,
        params: run.params,
        options: run.options,
    };
    let feed = Feed::Replay(run.result);
    Ok(write_folder(out, &of, outputs, timings, feed)?.0)
}

/// Adds to the options a run records in `summary.json` the outputs that are options of their
/// own, so that a study resumed with another choice runs the folder again (`pedo_study::is_complete`):
/// `animation` (`"gif"`) when `animation.gif` is written. A run without an animation records
/// nothing, so its folder reads as before (and a streamed run's is the same, byte for byte).
pub fn record_outputs(options: &mut Map<String, Value>, outputs: &RunOutputs) {
    if outputs.animation {
        options.insert("animation".into(), json!("gif"));
    }
    if let Some(rule) = outputs.regions {
        options.insert("region_rule".into(), json!(rule.name()));
    }
    match outputs.masks.as_deref() {
        Some(PathOrRows::Path(p)) => {
            options.insert("masks".into(), json!(p));
        }
        Some(PathOrRows::Rows(rows)) => {
            options.insert("masks".into(), json!(rows));
        }
        None => {}
    }
}

/// The HTML page `report.html` of a run, its header stating what `summary` (`summary.json`)
/// records: the options used and the time spent per stage.
pub fn report_page(run: &RunRecord<'_>, summary: &Value) -> Result<String> {
    let info = crate::html_report::ReportInfo {
        format: run.recording.format.map(|f| f.name().to_string()),
        contact_threshold: run.options.contour.preprocess.threshold.unwrap_or(0.0),
        frames: run.options.frames,
        ..crate::html_report::ReportInfo::of_summary(run.input.name.clone(), summary)
    };
    crate::html_report::run_report(run.recording, run.result, &info)
}

/// The folder a run writes into when no folder is named (`pedomatch run` without `--out`).
pub const DEFAULT_RUN_FOLDER: &str = "pedomatch-out";

/// Refuses to replace `folder` when it holds the output of another input than `input`: what a
/// run into the default folder ([`DEFAULT_RUN_FOLDER`]) checks, so that two runs of two
/// recordings without `--out` never silently replace each other's results. A folder that does
/// not exist, holds no `summary.json`, or holds the output of the same bytes (same SHA-256) is
/// fine; a folder named explicitly is replaced by the usual rules of [`OutDir`].
///
/// # Errors
/// [`IoError::Output`] naming the folder, the other input and how to keep both.
pub fn refuse_other_input(folder: &Path, input: &InputInfo) -> Result<()> {
    let Ok(bytes) = std::fs::read(folder.join("summary.json")) else {
        return Ok(());
    };
    let Ok(summary) = serde_json::from_slice::<Value>(&bytes) else {
        return Ok(());
    };
    let earlier = &summary["input"];
    let (Some(sha), Some(ours)) = (earlier["sha256"].as_str(), input.sha256.as_deref()) else {
        return Ok(());
    };
    if sha == ours {
        return Ok(());
    }
    let name = earlier["file"].as_str().unwrap_or("another recording");
    Err(IoError::Output {
        path: folder.display().to_string(),
        msg: format!(
            "holds the results of another input ({name}); give --out DIR to keep both, or \
             --out {} to replace them",
            folder.display()
        ),
    })
}
