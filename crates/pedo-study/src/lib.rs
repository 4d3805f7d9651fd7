//! A whole study: many recordings, each run like `pedomatch run` into a folder of its own, several
//! at once, summed up in one table (`study.csv` or `study.parquet`, and `study.json`) with a row
//! per recording. The last pipeline crate (docs/architecture.md): it composes the readers
//! (`pedo-io`), the run engine (`pedo-track`) and the writers (`pedo-output`).
//!
//! - [`find_recordings`] turns files, folders (searched recursively) and glob patterns into the
//!   list of recordings;
//! - [`run_study`] runs them on a pool of `jobs` threads, each recording on one thread (its pairs
//!   are matched in order, so the two levels of parallelism never compete for the cores). One
//!   recording that cannot be read or matched becomes an `error` row; the others go on;
//! - with an output folder, a recording whose folder is complete (see [`is_complete`]) is not
//!   run again but reported as `skipped` with its previous numbers, unless `force` is set;
//! - the study table keeps the rows of its previous version for recordings not in this run
//!   ([`kept_rows`]), so that a run on part of a study does not drop the rest; `study.json`
//!   says what produced it ([`study_json`]);
//! - [`write_study_curves`] writes every folder's stance-normalised curves as one long table
//!   (`study_curves.csv`), for 1-D statistics over the curves;
//! - [`run_recording`] is one row of that table, for callers that distribute the recordings
//!   themselves (Python's `pymodal.batch_row`, e.g. on a Dask cluster).
//!
//! The folder of each run is written by [`pedo_output::run_into_folder`], as `pedomatch run` and
//! `pymodal.run(out=...)` write theirs: `report.html` included when the outputs ask for it.

use pedo_io::cancel::Cancel;
use pedo_io::formats::stamp::{FileStamp, Unchanged};
use pedo_io::formats::{has_recording_extension, sniff_format, ReadOptions, SNIFF_BYTES};
use pedo_io::recording::{Format, FrameSource, Recording};
use pedo_io::{IoError, Result};
use pedo_output::outdir::{self};
use pedo_output::{
    pretty, read_for_run, record_outputs, run_into_folder, run_table_files, Cell, InputInfo,
    RoundTripSummary, RunOutputs, RunPlan, Table, TableFormat, SUMMARY_FIGURES,
};
use pedo_track::{run_options, ObjectModel, RunCounts, RunParams, SequenceOptions, Stage};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

mod claim;
pub mod curves;
pub use curves::{study_curves_columns, write_study_curves, STUDY_CURVES, STUDY_CURVES_COLUMNS};

/// Marks a folder as a study output ([`run_study`] writes only into an empty folder or one
/// holding it).
const STUDY_MARKER: &str = ".pedomatch-study";

/// What became of one recording of a study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowStatus {
    /// Run now.
    Ok,
    /// Its folder was complete; not run again.
    Skipped,
    /// It could not be read, matched or written.
    Error,
}

impl RowStatus {
    /// The word in the `status` column.
    pub fn name(self) -> &'static str {
        match self {
            RowStatus::Ok => "ok",
            RowStatus::Skipped => "skipped",
            RowStatus::Error => "error",
        }
    }
}

/// One row of the study table.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRow {
    /// The recording's path as found (an input, or a file in an input folder).
    pub path: String,
    /// Its folder's name under the study folder (`None` without an output folder).
    pub output: Option<String>,
    /// The format read (also for a file that failed to parse, when its content was recognised).
    pub format: Option<String>,
    /// Number of frames of the recording (all of them, not only those run); `None` when it
    /// could not be read.
    pub frames: Option<usize>,
    /// The recording's frame rate, pitch and pressure units, as the run used them (the unit
    /// options applied); unknown ones, and all of them when it could not be read, are `None`.
    pub units: RowUnits,
    /// Matched pairs.
    pub pairs: Option<usize>,
    /// Mean over the matched pairs of [`PairRow::local_percent`](pedo_track::PairRow::local_percent)
    /// (0–100); `None` without pairs or on error.
    pub mean_local_percent: Option<f64>,
    /// Mean over the matched pairs of
    /// [`PairRow::optimisation_percent`](pedo_track::PairRow::optimisation_percent) (0–100);
    /// `None` without pairs or on error.
    pub mean_optimisation_percent: Option<f64>,
    /// Mean over the matched pairs of
    /// [`PairRow::trackable_percent`](pedo_track::PairRow::trackable_percent) (0–100);
    /// `None` without pairs or on error, and on a row of a study written before it was a column.
    pub mean_trackable_percent: Option<f64>,
    /// Mean over the matched pairs of their median round trip through the pair's forward and
    /// backward fields, in sensels ([`pedo_track::consistency`]); `None` without such pairs, on
    /// error, and on a row of a study written before it was a column.
    pub mean_round_trip_sensels: Option<f64>,
    /// Number of tracks; `None` on error.
    pub tracks: Option<usize>,
    /// The median and 95th percentile of the run's track round trips, in sensels
    /// (`summary.json`'s `track_round_trip_sensels`: `tracks.csv`'s `round_trip_sensels`);
    /// `None` when no track has one (surfaces, drift correction), on error, and on a row of a
    /// study written before they were columns.
    pub track_round_trip_sensels: Quantiles,
    /// The median and 95th percentile of the round trips of the run's material points, in
    /// sensels (`summary.json`'s `point_round_trip_sensels`: `points.csv`'s
    /// `round_trip_sensels`); `None` where the run followed no points (surfaces and
    /// isocontours; a run of tables only without points or regions of the user's), on error,
    /// and on a row of a study written before they were columns.
    pub point_round_trip_sensels: Quantiles,
    /// The measures of the recording ([`pedo_io::measures`]) in the study's units; `None` on
    /// error and where the recording cannot give that unit.
    pub measures: StudyMeasures,
    /// Seconds from the start of this recording to its row (for a skipped one: those of the
    /// run that wrote the folder).
    pub wall_time_s: f64,
    /// Run, skipped or failed.
    pub status: RowStatus,
    /// One line: why it failed, why it was skipped, or what the run left out.
    pub message: String,
}

/// The median and 95th percentile of a run's round trips (sensels), as `summary.json` gives
/// them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Quantiles {
    /// The median.
    pub median: Option<f64>,
    /// The 95th percentile.
    pub p95: Option<f64>,
}

impl Quantiles {
    /// Those of the round trips `summary.json` records as `kind` (`None` for `null`).
    fn of_summary(summary: &Value, kind: RoundTripSummary) -> Self {
        let trips = kind.of_summary(summary);
        Self {
            median: trips.map(|t| t.median),
            p95: trips.map(|t| t.p95),
        }
    }
}

/// The units a study row gives of its recording, so that the rows of a study mixing sensors
/// can be told apart: the names and values of `summary.json`'s `recording`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RowUnits {
    /// Frames per second (`frame_rate_hz`).
    pub frame_rate_hz: Option<f64>,
    /// Millimetres per sensel `[x, y]` = `[column spacing, row spacing]` (`pitch_x_mm`,
    /// `pitch_y_mm`: sensels need not be square).
    pub pitch_mm: Option<[f64; 2]>,
    /// The pressure units of the values as the file (or `--units`) names them, in their usual
    /// spelling ([`canonical_units`](pedo_io::recording::canonical_units)), e.g. `kPa`, `N/cm²`
    /// (`pressure_units`).
    pub pressure_units: Option<String>,
}

impl RowUnits {
    /// The units of a recording read (and its unit options applied).
    pub fn of(recording: &Recording) -> Self {
        Self {
            frame_rate_hz: recording.frame_rate(),
            pitch_mm: recording.pitch_mm,
            pressure_units: recording.known_units().map(str::to_string),
        }
    }

    /// The units a `summary.json` records (its `recording`).
    fn of_summary(summary: &Value) -> Self {
        let recording = &summary["recording"];
        let pitch = recording["pitch_mm"]
            .as_array()
            .and_then(|p| match p.as_slice() {
                [x, y] => Some([x.as_f64()?, y.as_f64()?]),
                _ => None,
            });
        Self {
            frame_rate_hz: recording["frame_rate_hz"].as_f64(),
            pitch_mm: pitch,
            pressure_units: recording["pressure_units"].as_str().map(str::to_string),
        }
    }
}

/// The measures of a recording a study row gives ([`pedo_io::measures`], `summary.json`'s
/// `measures`), each in the unit its column names: `None` when the recording cannot give that
/// unit (a value in the file's own units, a time in frames, an area in sensels is left out, so
/// that a column never mixes units), on error, and on a row of a study written before they
/// were columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StudyMeasures {
    /// Peak pressure in kPa (`peak_pressure_kpa`).
    pub peak_pressure_kpa: Option<f64>,
    /// Largest pressure-time integral of a sensel in kPa·s (`pti_max_kpa_s`).
    pub pti_max_kpa_s: Option<f64>,
    /// Peak force in N (`peak_force_n`).
    pub peak_force_n: Option<f64>,
    /// Force-time integral in N·s (`fti_n_s`).
    pub fti_n_s: Option<f64>,
    /// Contact time in s (`contact_time_s`).
    pub contact_time_s: Option<f64>,
    /// Largest contact area of a frame in mm² (`max_contact_area_mm2`).
    pub max_contact_area_mm2: Option<f64>,
}

/// The study columns of [`StudyMeasures`]: column, `summary.json` measure, its unit there.
const MEASURE_COLUMNS: [(&str, &str, &str); 6] = [
    ("peak_pressure_kpa", "peak_pressure", "kPa"),
    ("pti_max_kpa_s", "pti_max", "kPa·s"),
    ("peak_force_n", "peak_force", "N"),
    ("fti_n_s", "fti", "N·s"),
    ("contact_time_s", "contact_time", "s"),
    ("max_contact_area_mm2", "max_contact_area", "mm²"),
];

impl StudyMeasures {
    /// The values in column order.
    fn values(&self) -> [Option<f64>; 6] {
        [
            self.peak_pressure_kpa,
            self.pti_max_kpa_s,
            self.peak_force_n,
            self.fti_n_s,
            self.contact_time_s,
            self.max_contact_area_mm2,
        ]
    }

    /// From the values in column order.
    fn of_values(v: [Option<f64>; 6]) -> Self {
        Self {
            peak_pressure_kpa: v[0],
            pti_max_kpa_s: v[1],
            peak_force_n: v[2],
            fti_n_s: v[3],
            contact_time_s: v[4],
            max_contact_area_mm2: v[5],
        }
    }

    /// The measures a `summary.json` records (its `measures`), those in the columns' units.
    fn of_summary(summary: &Value) -> Self {
        Self::of_values(MEASURE_COLUMNS.map(|(_, name, unit)| {
            let m = &summary["measures"][name];
            if m["unit"].as_str() == Some(unit) {
                m["value"].as_f64()
            } else {
                None
            }
        }))
    }
}

/// The columns of the study table, units in the names.
pub const STUDY_COLUMNS: [&str; 27] = [
    "path",
    "output",
    "format",
    "frames",
    "frame_rate_hz",
    "pitch_x_mm",
    "pitch_y_mm",
    "pressure_units",
    "pairs",
    "mean_local_percent",
    "mean_optimisation_percent",
    "mean_trackable_percent",
    "mean_round_trip_sensels",
    "tracks",
    "track_round_trip_median_sensels",
    "track_round_trip_p95_sensels",
    "point_round_trip_median_sensels",
    "point_round_trip_p95_sensels",
    "peak_pressure_kpa",
    "pti_max_kpa_s",
    "peak_force_n",
    "fti_n_s",
    "contact_time_s",
    "max_contact_area_mm2",
    "wall_time_s",
    "status",
    "message",
];

/// The study table: one row per recording, in the order given.
pub fn study_table(rows: &[StudyRow]) -> Table {
    let text = |s: &Option<String>| s.clone().map_or(Cell::Empty, Cell::Text);
    let int = |v: Option<usize>| v.map_or(Cell::Empty, |v| Cell::Int(v as i64));
    let float = |v: Option<f64>, d| v.map_or(Cell::Empty, |v| Cell::Float(v, d));
    Table {
        header: STUDY_COLUMNS.iter().map(|s| s.to_string()).collect(),
        rows: rows
            .iter()
            .map(|r| {
                let mut cells = vec![
                    Cell::Text(r.path.clone()),
                    text(&r.output),
                    text(&r.format),
                    int(r.frames),
                    float(r.units.frame_rate_hz, 4),
                    float(r.units.pitch_mm.map(|p| p[0]), 4),
                    float(r.units.pitch_mm.map(|p| p[1]), 4),
                    text(&r.units.pressure_units),
                    int(r.pairs),
                    float(r.mean_local_percent, 1),
                    float(r.mean_optimisation_percent, 1),
                    float(r.mean_trackable_percent, 1),
                    float(r.mean_round_trip_sensels, 4),
                    int(r.tracks),
                    float(r.track_round_trip_sensels.median, 4),
                    float(r.track_round_trip_sensels.p95, 4),
                    float(r.point_round_trip_sensels.median, 4),
                    float(r.point_round_trip_sensels.p95, 4),
                ];
                cells.extend(r.measures.values().map(|v| float(v, 4)));
                cells.extend([
                    Cell::Float(r.wall_time_s, 3),
                    Cell::Text(r.status.name().into()),
                    Cell::Text(r.message.clone()),
                ]);
                cells
            })
            .collect(),
    }
}

/// A row back from `study.json` (`None` if it is not one).
fn row_from_json(v: &Value) -> Option<StudyRow> {
    let text = |k: &str| v.get(k).and_then(Value::as_str).map(str::to_string);
    let int = |k: &str| v.get(k).and_then(Value::as_u64).map(|x| x as usize);
    let float = |k: &str| v.get(k).and_then(Value::as_f64);
    Some(StudyRow {
        path: text("path")?,
        output: text("output"),
        format: text("format"),
        frames: int("frames"),
        // Absent from the rows of a study written before they were columns.
        units: RowUnits {
            frame_rate_hz: float("frame_rate_hz"),
            pitch_mm: float("pitch_x_mm")
                .zip(float("pitch_y_mm"))
                .map(|(x, y)| [x, y]),
            pressure_units: text("pressure_units"),
        },
        pairs: int("pairs"),
        mean_local_percent: float("mean_local_percent"),
        mean_optimisation_percent: float("mean_optimisation_percent"),
        mean_trackable_percent: float("mean_trackable_percent"),
        mean_round_trip_sensels: float("mean_round_trip_sensels"),
        tracks: int("tracks"),
        track_round_trip_sensels: Quantiles {
            median: float("track_round_trip_median_sensels"),
            p95: float("track_round_trip_p95_sensels"),
        },
        point_round_trip_sensels: Quantiles {
            median: float("point_round_trip_median_sensels"),
            p95: float("point_round_trip_p95_sensels"),
        },
        measures: StudyMeasures::of_values(MEASURE_COLUMNS.map(|(c, _, _)| float(c))),
        wall_time_s: float("wall_time_s")?,
        status: match text("status")?.as_str() {
            "ok" => RowStatus::Ok,
            "skipped" => RowStatus::Skipped,
            _ => RowStatus::Error,
        },
        message: text("message").unwrap_or_default(),
    })
}

/// The name of a recording's folder under the study folder: its file name and 8 hex digits of
/// the SHA-256 of its absolute path, so that `a/walk.asf` and `b/walk.asf` get different
/// folders and a second run finds the same one. Two recordings whose names would still be the
/// same (the same file name and the same 8 digits) are told apart by [`output_names`].
pub fn output_name(path: &Path) -> String {
    folder_name(path, 0)
}

/// The `k`-th name the folder of the recording at `path` may take ([`output_names`]): its file
/// name and 8 (`k` = 0), 16, 32 or 64 hex digits of the SHA-256 of its absolute path, then the
/// 64 digits and `-2`, `-3`, ….
fn folder_name(path: &Path, k: usize) -> String {
    let absolute = std::fs::canonicalize(path)
        .or_else(|_| std::path::absolute(path))
        .unwrap_or_else(|_| path.to_path_buf());
    let hash = pedo_output::sha256_hex(absolute.to_string_lossy().as_bytes());
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|n| !n.is_empty() && !n.starts_with('.'))
        .unwrap_or_else(|| "recording".into());
    match k {
        0..=3 => format!("{name}-{}", &hash[..8 << k]),
        _ => format!("{name}-{hash}-{}", k - 2),
    }
}

/// Whether a folder name is one the recording at `path` may take ([`folder_name`]); its
/// names are made once.
fn is_folder_name_of(path: &Path) -> impl Fn(&str) -> bool {
    let names: Vec<String> = (0..4).map(|k| folder_name(path, k)).collect();
    move |name| {
        names.iter().any(|n| n == name)
            || name
                .strip_prefix(names[3].as_str())
                .and_then(|rest| rest.strip_prefix('-'))
                .is_some_and(|n| n.parse::<usize>().is_ok_and(|n| n >= 2))
    }
}

/// Whether a study row or folder whose recording was given as `other` is about another file
/// than `file` (the canonical path of a recording): `other` names an existing file, and not
/// that one. A path that no longer resolves (a recording moved, a relative path given from
/// another folder) is taken for the same recording, as before names were checked.
fn is_other_file(other: &str, file: Option<&Path>) -> bool {
    match (Path::new(other).canonicalize().ok(), file) {
        (Some(other), Some(file)) => other != file,
        _ => false,
    }
}

/// The folder names of the recordings at `paths` under study folder `out` (`None`: names
/// only), in order, no two the same: each recording's [`output_name`], unless that name is
/// already taken by an earlier recording of `paths`, by a row of the study's previous table
/// (`previous`) about another file, or by a folder in `out` whose `summary.json` names another
/// file: then a longer one (16, 32, 64 hex digits, then a count). A recording that has a row in
/// `previous` keeps that row's folder, so that a resumed study finds its folders again.
pub fn output_names(out: Option<&Path>, paths: &[PathBuf], previous: &[StudyRow]) -> Vec<String> {
    output_names_with(out, paths, previous, &folder_name)
}

/// [`output_names`], the `k`-th name of a path given by `folder_name` (a test makes every
/// recording's first name the same).
fn output_names_with(
    out: Option<&Path>,
    paths: &[PathBuf],
    previous: &[StudyRow],
    folder_name: &dyn Fn(&Path, usize) -> String,
) -> Vec<String> {
    use std::collections::{HashMap, HashSet};
    // The paths of the previous rows by folder, made once (a study may have thousands).
    let mut by_folder: HashMap<String, Vec<&str>> = HashMap::new();
    let mut by_output: HashMap<&str, Vec<&str>> = HashMap::new();
    for r in previous {
        by_folder.entry(row_folder(r)).or_default().push(&r.path);
        if let Some(output) = &r.output {
            by_output.entry(output).or_default().push(&r.path);
        }
    }
    let mut taken: HashSet<String> = HashSet::new();
    let mut names = Vec::with_capacity(paths.len());
    for path in paths {
        let file = path.canonicalize().ok();
        let claimed_by_other = |name: &str| {
            by_folder.get(name).is_some_and(|rows| {
                rows.iter()
                    .any(|other| is_other_file(other, file.as_deref()))
            }) || out
                .and_then(|out| read_json(&out.join(name).join("summary.json")))
                .is_some_and(|summary| {
                    summary["input"]["file"]
                        .as_str()
                        .is_some_and(|other| is_other_file(other, file.as_deref()))
                })
                || out
                    .and_then(|out| claim::claimant(out, name))
                    .is_some_and(|other| is_other_file(&other, file.as_deref()))
        };
        // The folder of this recording's previous row (as `previous_row` finds it).
        let same_file = |other: &&str| {
            file.is_some() && Path::new(other).canonicalize().ok().as_deref() == file.as_deref()
        };
        let own = (0..)
            .map(|k| (k, folder_name(path, k)))
            .take_while(|(k, name)| *k < 4 || by_output.contains_key(name.as_str()))
            .find(|(_, name)| {
                by_output
                    .get(name.as_str())
                    .is_some_and(|rows| rows.iter().any(same_file))
            })
            .map(|(_, name)| name)
            .or_else(|| {
                let short = folder_name(path, 0);
                by_output
                    .get(short.as_str())
                    .is_some_and(|rows| {
                        rows.iter()
                            .any(|other| !is_other_file(other, file.as_deref()))
                    })
                    .then_some(short)
            })
            .filter(|name| !taken.contains(name));
        let name = own.unwrap_or_else(|| {
            (0..)
                .map(|k| folder_name(path, k))
                .find(|name| !taken.contains(name) && !claimed_by_other(name))
                .unwrap_or_else(|| folder_name(path, 0))
        });
        taken.insert(name.clone());
        names.push(name);
    }
    names
}

/// The recordings named by `inputs`, in order, each once:
///
/// - an existing file is taken as it is (if it is no recording, its row says so);
/// - a folder is searched recursively, in name order, for files whose content sniffs as a
///   recording ([`sniff_format`]) and for files with a recording format's own extension
///   (`.asf`, `.lst`, `.apd`, `.npy`, `.npz`) whatever they hold, so that an empty or corrupt
///   one gets its error row, as does a file that cannot be opened; a text sniffed as a CSV grid
///   that reads as a table of another kind (a first line of names, rows of at most 3 values:
///   `formats::csv::looks_like_a_table`) is passed over; PNG/TIFF images are not
///   recordings on their own there: a folder holding grayscale images is one image-sequence
///   recording, and colour images (a photograph of the foot) are passed over. Hidden folders and pedomatch output
///   folders are not searched. Symbolic links to files and folders are followed (a link back
///   to a folder being searched is passed over); a broken link named as a recording is kept,
///   so that its row says the link is broken. Only regular files are read (no device, FIFO or
///   socket), each its first [`SNIFF_BYTES`] without waiting, and the system's own trees
///   (`/proc`, `/sys`, `/dev`) are never entered;
/// - anything else is a glob pattern (`data/**/*.asf`), each match taken as above.
///
/// A path that does not exist is kept, so that its row reports it missing. Fails on a malformed
/// pattern and on a pattern that matches nothing (its row would only say "No such file").
pub fn find_recordings<S: AsRef<str>>(inputs: &[S]) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for input in inputs {
        let input = input.as_ref();
        let path = Path::new(input);
        if path.exists() {
            add_path(path, &mut found);
            continue;
        }
        let pattern = glob::glob(input)
            .map_err(|e| IoError::invalid(format!("input pattern {input:?}: {e}")))?;
        let matches: Vec<PathBuf> = pattern.flatten().collect();
        if matches.is_empty() {
            if input.contains(['*', '?', '[']) {
                return Err(IoError::invalid(format!(
                    "input pattern {input:?} matches no file"
                )));
            }
            found.push(path.to_path_buf());
        }
        for m in matches {
            add_path(&m, &mut found);
        }
    }
    let mut seen = std::collections::HashSet::new();
    found.retain(|p| seen.insert(std::fs::canonicalize(p).unwrap_or_else(|_| p.clone())));
    Ok(found)
}

fn add_path(path: &Path, found: &mut Vec<PathBuf>) {
    if path.is_dir() {
        search_folder(path, found);
    } else {
        found.push(path.to_path_buf());
    }
}

fn search_folder(root: &Path, found: &mut Vec<PathBuf>) {
    let is_skipped_dir = |e: &walkdir::DirEntry| {
        e.depth() > 0
            && e.file_type().is_dir()
            && (e.file_name().to_string_lossy().starts_with('.')
                || outdir::is_output(e.path())
                || e.path().join(STUDY_MARKER).is_file())
    };
    // The root, and whatever a link leads to, may be in the system's own trees.
    let is_system =
        |e: &walkdir::DirEntry| (e.depth() == 0 || e.path_is_symlink()) && in_system_tree(e.path());
    // Symbolic links are followed (a study folder's recordings are often links into a raw-data
    // store); a link back to a folder being searched is a loop walkdir reports, and is passed
    // over. The same file reached twice is found once (`find_recordings` keeps one path per
    // canonical path).
    let walk = walkdir::WalkDir::new(root)
        .follow_links(true)
        .sort_by_file_name()
        .into_iter()
        .filter_entry(|e| !is_skipped_dir(e) && !is_system(e));
    let mut image_folders = Vec::new();
    for entry in walk {
        let entry = match entry {
            Ok(entry) => entry,
            // A broken link named as a recording gets its error row (the link is broken).
            Err(e) => {
                if let Some(path) = e.path().filter(|p| is_broken_link(p))
                    && e.loop_ancestor().is_none()
                    && has_recording_extension(path)
                    && !path
                        .file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with('.'))
                {
                    found.push(path.to_path_buf());
                }
                continue;
            }
        };
        // Regular files only: a device, FIFO or socket is no recording (and reading one may
        // block forever).
        if !entry.file_type().is_file() || entry.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        match sniff_found_file(entry.path()) {
            Some(Format::Png | Format::Tiff) if !is_pressure_image(entry.path()) => {}
            Some(Format::Png | Format::Tiff) => {
                let folder = entry.path().parent().unwrap_or(root).to_path_buf();
                if !image_folders.contains(&folder) {
                    image_folders.push(folder.clone());
                    found.push(folder);
                }
            }
            Some(_) => found.push(entry.into_path()),
            // An empty or corrupt `walk.asf`, or a file that cannot be read at all, may be a
            // recording: its row says what is wrong with it instead of the file vanishing from
            // the study.
            None if has_recording_extension(entry.path())
                || std::fs::File::open(entry.path()).is_err() =>
            {
                found.push(entry.into_path())
            }
            None => {}
        }
    }
}

/// Whether `path` is a symbolic link whose target does not exist.
fn is_broken_link(path: &Path) -> bool {
    path.symlink_metadata()
        .is_ok_and(|m| m.file_type().is_symlink())
        && std::fs::metadata(path).is_err()
}

/// The error of reading a broken symbolic link: it names the missing target.
fn broken_link_error(path: &Path) -> Option<IoError> {
    if !is_broken_link(path) {
        return None;
    }
    let target = std::fs::read_link(path)
        .map(|t| format!(" to {}", t.display()))
        .unwrap_or_default();
    Some(IoError::Io {
        path: path.display().to_string(),
        source: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("broken symbolic link{target} (its target does not exist)"),
        ),
    })
}

/// Whether an image met in a searched folder may be a pressure frame: a colour image (a
/// photograph of the foot) is not; an image whose header cannot be read is kept, so that its
/// folder's row says what is wrong.
fn is_pressure_image(path: &Path) -> bool {
    pedo_io::formats::images::is_grayscale_image(path).unwrap_or(true)
}

/// Whether `path` leads into the system's own trees (`/proc`, `/sys`, `/dev`): files that are
/// no recordings, some of which block a reader forever (`/proc/kmsg`), and a folder search
/// never enters them.
fn in_system_tree(path: &Path) -> bool {
    std::fs::canonicalize(path).is_ok_and(|p| {
        ["/proc", "/sys", "/dev"]
            .iter()
            .any(|system| p.starts_with(system))
    })
}

/// The first [`SNIFF_BYTES`] of a file, if it can be read: at most that many bytes, and without
/// waiting (a file that has nothing to read yet, such as a FIFO named as an input, reads as
/// empty).
fn read_head(path: &Path) -> Option<Vec<u8>> {
    use std::io::Read;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let mut head = Vec::with_capacity(SNIFF_BYTES);
    let file = options.open(path).ok()?;
    match file.take(SNIFF_BYTES as u64).read_to_end(&mut head) {
        Ok(_) => Some(head),
        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => Some(head),
        Err(_) => None,
    }
}

/// The format of a file by its first bytes, if it is a recording.
fn sniff_file(path: &Path) -> Option<Format> {
    sniff_format(path, &read_head(path)?).ok()
}

/// [`sniff_file`] for a file met in a searched folder: a file whose content has only its format's
/// marker words, not its structure (a `.docx` for an `.npz`, a README mentioning `ASCII_DATA`:
/// [`pedo_io::formats::looks_like_recording`]), and a text sniffed as a CSV grid that reads as a
/// table of another kind (`formats::csv::looks_like_a_table`), are not recordings there.
fn sniff_found_file(path: &Path) -> Option<Format> {
    let head = read_head(path)?;
    match sniff_format(path, &head).ok()? {
        f if !pedo_io::formats::looks_like_recording(f, &head) => None,
        Format::Csv
            if pedo_io::formats::csv::looks_like_a_table(&String::from_utf8_lossy(
                &pedo_io::formats::utf16_to_utf8(&head).unwrap_or_else(|| head.clone()),
            )) =>
        {
            None
        }
        f => Some(f),
    }
}

modal_core::option_set! {
    /// How a study runs its recordings, as a user gives it (`pedomatch batch --jobs N --force`,
    /// `pymodal.batch(..., jobs=N, force=True)`, `pymodal.batch_row(..., force=True)`): each
    /// option declared here once; [`StudyParams::apply`] sets them in [`StudyOptions`].
    StudyParams {
        let _d = ();
        /// Recordings run at once, each on one thread (`None`: one per available core).
        jobs: Option<usize> = None;
            Value, "the available cores",
            "Recordings run at once, each on one thread.";
        /// Run every recording again, even those whose folders are complete.
        force: bool = false;
            Flag, false,
            "Run every recording again, even those whose folders are complete.";
    }
}

impl StudyParams {
    /// Checks every value: at least one recording at a time.
    pub fn validate(&self) -> std::result::Result<(), modal_core::OptionError> {
        if self.jobs == Some(0) {
            return Err(modal_core::OptionError::new(
                "jobs",
                0,
                "an integer >= 1 (none: one per available core)",
            ));
        }
        Ok(())
    }

    /// `opts` with these values, once checked.
    pub fn apply(
        &self,
        opts: &mut StudyOptions,
    ) -> std::result::Result<(), modal_core::OptionError> {
        self.validate()?;
        opts.jobs = self.jobs.unwrap_or(0);
        opts.force = self.force;
        Ok(())
    }
}

/// The study options' declarations ([`StudyParams`]).
pub fn study_option_specs() -> Vec<modal_core::OptionSpec> {
    StudyParams::specs()
}

/// How a study runs.
#[derive(Clone, Default)]
pub struct StudyOptions {
    /// The inputs as given (files, folders, glob patterns), for `study.json`; empty: the paths
    /// run are recorded instead.
    pub inputs: Vec<String>,
    /// The parameters every recording is run with (as `pedomatch run` takes them).
    pub params: RunParams,
    /// How every recording is read.
    pub read: ReadOptions,
    /// The study folder: one folder per recording ([`output_name`]) and the study table. `None`:
    /// nothing is written, the rows are only returned.
    pub out: Option<PathBuf>,
    /// Recordings run at once (0: one per available core).
    pub jobs: usize,
    /// Run recordings again even when their folders are complete.
    pub force: bool,
    /// What each recording's folder holds besides its tables and `summary.json`, and the
    /// format of every table (the study table's too).
    pub outputs: RunOutputs,
    /// Stops the study once cancelled ([`pedo_io::cancel`]): no recording starts after it, the ones
    /// running stop at their next progress step without committing their folders, and
    /// [`run_study`] fails with [`IoError::Cancelled`] without writing the study table; the
    /// folders of the recordings finished before stay. `None`: the study goes to its end.
    pub cancel: Option<Cancel>,
}

/// What [`run_study`] reports as it goes (possibly from several threads).
#[derive(Debug, Clone, Copy)]
pub enum StudyEvent<'a> {
    /// Recording `index` is `fraction` (0 to 1) done: object building is the first half, matching
    /// the second. A run that streams ([`pedo_output::tables_only`] and [`RunParams::streams`]) reports its
    /// frames as matching alone, from 0.5 on.
    Progress {
        /// The recording's index in the `paths` given to [`run_study`] (0-based).
        index: usize,
        /// How much of it is done, from 0 to 1.
        fraction: f64,
    },
    /// Recording `index` is done.
    Finished {
        /// The recording's index in the `paths` given to [`run_study`] (0-based).
        index: usize,
        /// Its row of the study table.
        row: &'a StudyRow,
    },
}

/// What [`run_study`] did: a row per recording run, and the rows of earlier runs that the study
/// table kept.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRun {
    /// One row per recording of this run, in order.
    pub rows: Vec<StudyRow>,
    /// The rows of the previous study table that are not this run's recordings, kept after
    /// `rows` in the table ([`kept_rows`]); none without an output folder.
    pub kept: Vec<StudyRow>,
}

/// Runs every recording of `paths` (see the module docs) and returns one row per recording, in
/// order. With an output folder, writes each recording's folder and `study.csv` (or
/// `study.parquet`, see [`RunOutputs::tables`]) + `study.json` (atomically, after the last
/// recording): this run's rows, then those of earlier runs that it kept ([`kept_rows`]). Fails
/// before any recording runs (invalid options, or an output folder that holds other files), or
/// with [`IoError::Cancelled`] when [`StudyOptions::cancel`] stopped it.
pub fn run_study(
    paths: &[PathBuf],
    opts: &StudyOptions,
    progress: &(dyn Fn(StudyEvent<'_>) + Sync),
) -> Result<StudyRun> {
    opts.params.validate()?;
    // Made before anything runs: options that cannot be listed would fail every recording.
    let provenance = study_provenance(paths, opts)?;
    // Held until the study table is written: a second batch into `out` is refused.
    let (previous_json, _lock) = match &opts.out {
        Some(out) => {
            let lock = lock_study_folder(out)?;
            (prepare_study_folder(out)?, Some(lock))
        }
        None => (None, None),
    };
    let mut previous = previous_json
        .as_ref()
        .map(rows_of_study_json)
        .unwrap_or_default();
    if let Some(out) = &opts.out {
        // Under the lock: what a killed run left is no longer anyone's.
        sweep_staging(out);
        let found = rows_of_unlisted_folders(out, &previous);
        previous.extend(found);
    }
    let jobs = if opts.jobs == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        opts.jobs
    };
    // `jobs` plain threads take the recordings in turn, each running one on its own one-thread
    // pool. Not a rayon pool: a rayon worker waiting for its recording steals the next one and
    // would start it on the same busy pool (or, with a new pool, run more than `jobs` at once).
    let names = output_names(opts.out.as_deref(), paths, &previous);
    if let Some(out) = &opts.out {
        // Under the lock no `batch_row` runs: the claims only tell later ones these names.
        for (path, name) in paths.iter().zip(&names) {
            let _ = claim::claim(out, name, path, &|_| false);
        }
    }
    // The previous rows by folder, for each recording's own (made once: thousands of rows).
    let mut by_folder: std::collections::HashMap<String, Vec<&StudyRow>> = Default::default();
    for r in &previous {
        by_folder.entry(row_folder(r)).or_default().push(r);
    }
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<Option<StudyRow>>> = Mutex::new(vec![None; paths.len()]);
    let cancel = opts.cancel.as_ref();
    let worker = || loop {
        if pedo_io::cancel::cancelled(cancel) {
            break;
        }
        let index = next.fetch_add(1, Ordering::Relaxed);
        let Some(path) = paths.get(index) else { break };
        let name = &names[index];
        let file = path.canonicalize().ok();
        let before = by_folder.get(name).and_then(|rows| {
            rows.iter()
                .copied()
                .find(|r| !is_other_file(&r.path, file.as_deref()))
        });
        let report = |fraction| progress(StudyEvent::Progress { index, fraction });
        let output = opts.out.as_ref().map(|_| name.clone());
        let row = on_one_thread(|| run_recording_as(path, opts, output, before, &report));
        progress(StudyEvent::Finished { index, row: &row });
        done.lock().unwrap_or_else(|e| e.into_inner())[index] = Some(row);
    };
    std::thread::scope(|scope| {
        let started = (0..jobs.min(paths.len()))
            .filter(|_| {
                std::thread::Builder::new()
                    .spawn_scoped(scope, worker)
                    .is_ok()
            })
            .count();
        if started == 0 {
            worker();
        }
    });
    // The rows are incomplete (the recording that was stopped is an error row): no table.
    pedo_io::cancel::check(cancel)?;
    let rows: Vec<StudyRow> = done
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .flatten()
        .collect();
    let kept = match &opts.out {
        Some(out) => kept_rows(out, &previous, paths, &rows),
        None => Vec::new(),
    };
    if let Some(out) = &opts.out
        && !outdir::interrupted()
    {
        let earlier = earlier_runs(previous_json.as_ref(), &kept);
        let json = study_json(provenance, &rows, &kept, earlier);
        let all: Vec<StudyRow> = rows.iter().chain(&kept).cloned().collect();
        write_study_table(out, &all, &json, opts.outputs.tables)?;
        curves::write_study_curves(out, &all, opts.outputs.tables)?;
    }
    Ok(StudyRun { rows, kept })
}

/// The row of recording `path` in a study's previous table: the row of its folder
/// ([`output_names`]), however the path was spelled then (`data/x.asf`, `./data/x.asf`), and
/// not a row of another file that took the same folder name.
pub fn previous_row<'a>(previous: &'a [StudyRow], path: &Path) -> Option<&'a StudyRow> {
    let file = path.canonicalize().ok();
    let same_file =
        |r: &&StudyRow| file.is_some() && Path::new(&r.path).canonicalize().ok() == file;
    let own = is_folder_name_of(path);
    previous
        .iter()
        .find(|r| r.output.as_deref().is_some_and(&own) && same_file(r))
        .or_else(|| {
            let folder = output_name(path);
            previous
                .iter()
                .find(|r| row_folder(r) == folder && !is_other_file(&r.path, file.as_deref()))
        })
}

/// The folder a row is about: its `output`, or, for a row without one (a recording that
/// failed), the folder its recording would get.
fn row_folder(row: &StudyRow) -> String {
    row.output
        .clone()
        .unwrap_or_else(|| output_name(Path::new(&row.path)))
}

/// The rows of the previous study table (`previous`, in its order) that a run of `paths` into
/// study folder `out` keeps: those of recordings not in this run, so that a run on part of a
/// study does not drop the rest. A row is dropped once what it reports is gone: its folder
/// (deleted from `out`) or, for a row without a folder (a recording that failed), its
/// recording. It is also dropped when this run has its recording under another folder name: the
/// same file (a study moved with its recordings: the folder names, hashes of absolute paths,
/// changed), or, its own path gone, the same input (a recording renamed or moved: same SHA-256
/// and layout file as one of this run's `rows`). A kept row's message says it was kept
/// ([`kept_message`]). Rows of a table written before the units were columns get them from
/// their folder's `summary.json`.
pub fn kept_rows(
    out: &Path,
    previous: &[StudyRow],
    paths: &[PathBuf],
    rows: &[StudyRow],
) -> Vec<StudyRow> {
    use std::collections::HashSet;
    let this_run: HashSet<String> = output_names(Some(out), paths, previous)
        .into_iter()
        .collect();
    let files: HashSet<PathBuf> = paths.iter().filter_map(|p| p.canonicalize().ok()).collect();
    // This run's inputs are read from their folders only if a kept row's path is gone.
    let inputs: std::cell::OnceCell<HashSet<Value>> = std::cell::OnceCell::new();
    let in_this_run = |input: Value| {
        let inputs =
            inputs.get_or_init(|| rows.iter().filter_map(|r| folder_input(out, r)).collect());
        inputs.contains(&input)
    };
    previous
        .iter()
        .filter(|r| !this_run.contains(&row_folder(r)))
        .filter_map(|r| {
            let file = Path::new(&r.path).canonicalize().ok();
            let kept = match (&r.output, &file) {
                (_, Some(f)) if files.contains(f) => false,
                (Some(folder), _) if !outdir::is_output(&out.join(folder)) => false,
                (Some(_), None) => !folder_input(out, r).is_some_and(&in_this_run),
                (Some(_), Some(_)) => true,
                (None, found) => found.is_some(),
            };
            kept.then_some((r, file.is_some()))
        })
        .map(|(r, found)| {
            let mut row = with_units_of_folder(out, r);
            // A skipped row's message is the earlier run's "outputs complete": not carried on.
            let earlier = if r.status == RowStatus::Skipped {
                ""
            } else {
                &r.message
            };
            row.message = kept_message(earlier, found);
            row
        })
        .collect()
}

/// What a row's folder under `out` says its input was (`summary.json`'s `input` without its
/// name: the SHA-256 and layout file's SHA-256), `None` without a folder or a SHA-256.
fn folder_input(out: &Path, row: &StudyRow) -> Option<Value> {
    let summary = read_json(&out.join(row.output.as_ref()?).join("summary.json"))?;
    let input = &summary["input"];
    input["sha256"].as_str()?;
    Some(json!([input["sha256"], input["layout"]["sha256"]]))
}

/// How a kept row's message begins.
const KEPT: &str = "kept from an earlier run (";

/// The message of a row kept from an earlier run: that it was kept and why (not among this
/// run's inputs, or its input no longer `found` at its path), then the message of the run that
/// made it.
pub fn kept_message(message: &str, found: bool) -> String {
    let earlier = message
        .strip_prefix(KEPT)
        .and_then(|m| m.split_once(')'))
        .map_or(message, |(_, rest)| rest.trim_start_matches("; "));
    let why = if found {
        "not among this run's inputs"
    } else {
        "its input is no longer at this path"
    };
    if earlier.is_empty() {
        format!("{KEPT}{why})")
    } else {
        format!("{KEPT}{why}); {earlier}")
    }
}

/// `row`, its units and measures read from its folder's `summary.json` if it gives none (a row
/// of a study written before they were columns).
fn with_units_of_folder(out: &Path, row: &StudyRow) -> StudyRow {
    let mut row = row.clone();
    let (no_units, no_measures) = (
        row.units == RowUnits::default(),
        row.measures == StudyMeasures::default(),
    );
    if (no_units || no_measures)
        && let Some(folder) = &row.output
        && let Some(summary) = read_json(&out.join(folder).join("summary.json"))
    {
        if no_units {
            row.units = RowUnits::of_summary(&summary);
        }
        if no_measures {
            row.measures = StudyMeasures::of_summary(&summary);
        }
    }
    row
}

/// A JSON file's value (`None` if it cannot be read or parsed).
fn read_json(path: &Path) -> Option<Value> {
    serde_json::from_slice(&std::fs::read(path).ok()?).ok()
}

/// What produced a study table, for `study.json`: the pedomatch version, the inputs as given
/// (the paths when [`StudyOptions::inputs`] is empty), and every option as given to each
/// recording ([`RunParams::given`], written as `summary.json` writes the options it used, with
/// its `animation` entry).
pub fn study_provenance(paths: &[PathBuf], opts: &StudyOptions) -> Result<Map<String, Value>> {
    let mut options: Map<String, Value> = opts
        .params
        .given()?
        .iter()
        .map(|(k, v)| (k.to_string(), pedo_output::option_json(v)))
        .collect();
    record_outputs(&mut options, &opts.outputs);
    let inputs: Vec<String> = if opts.inputs.is_empty() {
        paths.iter().map(|p| p.display().to_string()).collect()
    } else {
        opts.inputs.clone()
    };
    let mut provenance = Map::new();
    provenance.insert("pedomatch_version".into(), json!(env!("CARGO_PKG_VERSION")));
    provenance.insert("inputs".into(), json!(inputs));
    provenance.insert("options".into(), Value::Object(options));
    Ok(provenance)
}

/// `study.json`: `provenance` ([`study_provenance`]), the counts of this run's `rows` by status
/// ([`status_counts`]), how many rows of earlier runs were `kept`, what produced those
/// (`earlier`, see [`earlier_runs`]), and every row: this run's, then the kept ones.
pub fn study_json(
    provenance: Map<String, Value>,
    rows: &[StudyRow],
    kept: &[StudyRow],
    earlier: Vec<Value>,
) -> Value {
    let mut json = provenance;
    if let Value::Object(counts) = status_counts(rows) {
        json.extend(counts);
    }
    json.insert("kept".into(), json!(kept.len()));
    json.insert("earlier_runs".into(), Value::Array(earlier));
    let all: Vec<StudyRow> = rows.iter().chain(kept).cloned().collect();
    json.insert("rows".into(), study_table(&all).to_json());
    Value::Object(json)
}

/// What produced the `kept` rows, from the previous `study.json`: its own run and the earlier
/// runs it listed, most recent first, each with its `pedomatch_version`, `inputs` and `options`
/// (as [`study_provenance`] gives them) and the `paths` of the kept rows it produced. A row is
/// listed under the most recent run that ran it or found it complete with the same options; a
/// run none of whose rows is kept is left out. Rows of a `study.json` written before runs were
/// recorded (a bare list of rows) are listed under a run whose version, inputs and options are
/// `null`.
pub fn earlier_runs(previous: Option<&Value>, kept: &[StudyRow]) -> Vec<Value> {
    let Some(previous) = previous else {
        return Vec::new();
    };
    let mut runs: Vec<Value> = Vec::new();
    match previous {
        Value::Object(json) => {
            // The previous run's own rows come first in its `rows`: `recordings` of them.
            let own = json.get("recordings").and_then(Value::as_u64).unwrap_or(0) as usize;
            let mut run = Map::new();
            for key in ["pedomatch_version", "inputs", "options"] {
                run.insert(key.into(), json.get(key).cloned().unwrap_or(Value::Null));
            }
            run.insert(
                "paths".into(),
                row_paths(&rows_of_study_json(previous)[..], own),
            );
            runs.push(Value::Object(run));
            if let Some(Value::Array(older)) = json.get("earlier_runs") {
                runs.extend(older.iter().filter(|r| r.is_object()).cloned());
            }
        }
        Value::Array(_) => {
            let rows = rows_of_study_json(previous);
            runs.push(json!({
                "pedomatch_version": null, "inputs": null, "options": null,
                "paths": row_paths(&rows, rows.len()),
            }));
        }
        _ => {}
    }
    let mut unlisted: std::collections::HashSet<&str> =
        kept.iter().map(|r| r.path.as_str()).collect();
    runs.into_iter()
        .filter_map(|mut run| {
            let paths: Vec<Value> = run["paths"]
                .as_array()
                .into_iter()
                .flatten()
                .filter(|p| p.as_str().is_some_and(|p| unlisted.remove(p)))
                .cloned()
                .collect();
            (!paths.is_empty()).then(|| {
                run["paths"] = Value::Array(paths);
                run
            })
        })
        .collect()
}

/// The paths of the first `n` of `rows`, as a JSON list.
fn row_paths(rows: &[StudyRow], n: usize) -> Value {
    rows.iter().take(n).map(|r| json!(r.path)).collect()
}

/// Runs `f` on a rayon pool of one thread: the pairs of one recording are then matched in turn
/// (the recordings are what runs in parallel). The pool is the calling thread's own, created on
/// its first call and kept: a new pool per recording would start a new thread each time, and
/// glibc gives each new thread a new malloc arena that keeps the memory of its recording, so a
/// study's peak memory grew with its number of recordings (about 19 MB per walk). Falls back to
/// the current thread if no thread can be started.
///
/// The pool is also the process's: a child forked after the pool was made (Python's
/// `multiprocessing` on Linux) inherits it without its thread (a fork copies only the calling
/// thread), so work sent to it would wait forever. The pool records the process id it was made
/// in, and a child makes its own.
pub fn on_one_thread<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    /// The pool (`None`: no thread could be started) and the process it belongs to.
    type Owned = (u32, Option<rayon::ThreadPool>);
    thread_local! {
        static POOL: std::cell::RefCell<Option<Owned>> = const { std::cell::RefCell::new(None) };
    }
    let pid = std::process::id();
    POOL.with(|cell| {
        if cell
            .borrow()
            .as_ref()
            .is_none_or(|(owner, _)| *owner != pid)
        {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().ok();
            // A pool inherited through a fork is never dropped: dropping it would signal a thread
            // that this process does not have.
            if let Some(inherited) = cell.replace(Some((pid, pool))) {
                std::mem::forget(inherited);
            }
        }
        let owned = cell.borrow();
        match owned.as_ref() {
            Some((_, Some(pool))) => pool.install(f),
            _ => {
                drop(owned);
                f()
            }
        }
    })
}

/// Creates the study folder `out` (marking it as one) or checks that it is one; returns the rows
/// of its previous table (none if it has none). Fails if `out` holds files and is not a study.
pub fn open_study_folder(out: &Path) -> Result<Vec<StudyRow>> {
    Ok(prepare_study_folder(out)?
        .map(|json| rows_of_study_json(&json))
        .unwrap_or_default())
}

/// [`open_study_folder`], returning the previous `study.json` as it is (`None` if there is
/// none or it cannot be read).
fn prepare_study_folder(out: &Path) -> Result<Option<Value>> {
    let io = |e| IoError::Io {
        path: out.display().to_string(),
        source: e,
    };
    let marker = out.join(STUDY_MARKER);
    match std::fs::read_dir(out).map(|mut entries| entries.next().is_some()) {
        Ok(true) if !marker.is_file() => {
            return Err(IoError::Output {
                path: out.display().to_string(),
                msg: "folder exists and is not a pedomatch study; choose another output folder"
                    .into(),
            });
        }
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            if out.exists() {
                return Err(IoError::Output {
                    path: out.display().to_string(),
                    msg: "exists and is not a folder; choose another output folder".into(),
                });
            }
            return Err(io(e));
        }
        _ => {}
    }
    std::fs::create_dir_all(out).map_err(io)?;
    std::fs::write(&marker, b"written by pedomatch batch\n").map_err(io)?;
    Ok(read_json(&out.join("study.json")))
}

/// The rows of the complete recording folders of study folder `out` that no row of `previous`
/// names (a run killed after writing them but before its `study.json`), in name order, rebuilt
/// from their `summary.json`, so that the next table loses none of them.
fn rows_of_unlisted_folders(out: &Path, previous: &[StudyRow]) -> Vec<StudyRow> {
    use std::collections::HashSet;
    let listed: HashSet<&str> = previous
        .iter()
        .filter_map(|r| r.output.as_deref())
        .collect();
    let Ok(entries) = std::fs::read_dir(out) else {
        return Vec::new();
    };
    let mut names: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.') && !listed.contains(n.as_str()))
        .collect();
    names.sort();
    names
        .into_iter()
        .filter_map(|name| {
            let folder = out.join(&name);
            if !outdir::is_output(&folder) {
                return None;
            }
            let summary = read_json(&folder.join("summary.json"))?;
            let file = summary["input"]["file"].as_str()?;
            let mut row = row_of_summary(Path::new(file), Some(&name), &summary, Instant::now());
            row.wall_time_s = summary["timings_s"]
                .as_object()
                .map_or(0.0, |t| t.values().filter_map(Value::as_f64).sum());
            row.message =
                "found in its folder (the run that wrote it stopped before the study table)".into();
            Some(row)
        })
        .collect()
}

/// Removes what runs killed while writing into study folder `out` left: recording folders
/// being staged (`.NAME.pedomatch-tmp-PID`) and study tables being written
/// (`.study.csv.tmp-PID`, `.study_curves.csv.tmp-PID`, …) of processes that no longer run.
fn sweep_staging(out: &Path) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let pid = name
            .strip_prefix('.')
            .and_then(|n| {
                n.rsplit_once(".pedomatch-tmp-")
                    .or_else(|| n.strip_prefix("study").and_then(|n| n.rsplit_once(".tmp-")))
            })
            .and_then(|(_, pid)| pid.parse::<u32>().ok());
        if let Some(pid) = pid
            && pid != std::process::id()
            && !process_runs(pid)
        {
            let path = entry.path();
            let _ = std::fs::remove_dir_all(&path).or_else(|_| std::fs::remove_file(&path));
        }
    }
}

/// Whether process `pid` runs on this machine (unknown off Unix: taken as ended).
fn process_runs(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return false;
        };
        // SAFETY: signal 0 sends nothing; it only checks that the process exists.
        let r = unsafe { libc::kill(pid, 0) };
        r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        false
    }
}

/// The lock file of a study folder ([`lock_study_folder`]).
const STUDY_LOCK: &str = ".pedomatch-study.lock";

/// Takes the study folder `out` for this process (creating it, and checking that it is a study
/// folder or empty): an advisory lock on its lock file `.pedomatch-study.lock`, which holds the
/// process id of its holder, released when the file returned is dropped (or the process ends,
/// however). Fails at once, naming the folder and the process holding it, when another batch
/// holds it, or while recordings of it run one by one ([`share_study_folder`]).
pub fn lock_study_folder(out: &Path) -> Result<std::fs::File> {
    use std::io::Write;
    let (mut file, path) = open_study_lock(out, false)?;
    file.set_len(0)
        .and_then(|()| writeln!(file, "{}", std::process::id()))
        .map_err(|e| IoError::Io {
            path: path.display().to_string(),
            source: e,
        })?;
    Ok(file)
}

/// Opens the study folder `out` for one recording's run beside others (`batch_row` calls,
/// which may run at once in many processes): a shared lock on its lock file, so that a
/// `batch` into `out` ([`lock_study_folder`]) is refused while any runs, and this is refused
/// while a `batch` runs. Returns the lock (released when dropped) and the rows of the study's
/// previous table ([`open_study_folder`]).
pub fn share_study_folder(out: &Path) -> Result<(std::fs::File, Vec<StudyRow>)> {
    let (file, _) = open_study_lock(out, true)?;
    Ok((file, open_study_folder(out)?))
}

/// The study folder's lock file, opened and locked (`shared` or not); fails at once when
/// another process holds it the other way.
fn open_study_lock(out: &Path, shared: bool) -> Result<(std::fs::File, PathBuf)> {
    prepare_study_folder(out)?;
    let path = out.join(STUDY_LOCK);
    let io = |e| IoError::Io {
        path: path.display().to_string(),
        source: e,
    };
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(io)?;
    let locked = match shared {
        true => file.try_lock_shared(),
        false => file.try_lock(),
    };
    match locked {
        Ok(()) => Ok((file, path)),
        Err(std::fs::TryLockError::WouldBlock) => {
            // The process id a batch wrote (recordings run one by one write none).
            let holder = std::fs::read_to_string(&path)
                .ok()
                .and_then(|s| s.trim().parse::<u32>().ok())
                .filter(|&pid| process_runs(pid));
            // Who holds it: a batch when even a shared lock cannot be had (the process id it
            // writes may not be there yet, just after it took the lock), else rows run one by
            // one. The probe's lock goes with `file`.
            let batch = shared || file.try_lock_shared().is_err();
            let by = match (batch, holder) {
                (true, Some(pid)) => format!("another pedomatch batch (process {pid})"),
                (true, None) => "another pedomatch batch".to_string(),
                (false, _) => "recordings run one by one (batch_row)".to_string(),
            };
            Err(IoError::Output {
                path: out.display().to_string(),
                msg: format!(
                    "study folder in use by {by}; wait for it to end or choose another output folder"
                ),
            })
        }
        Err(std::fs::TryLockError::Error(e)) => Err(io(e)),
    }
}

/// The rows of a `study.json`: its `rows`, or, written by a pedomatch before it recorded what
/// produced them, the bare list of rows it was (an old study folder still resumes).
fn rows_of_study_json(json: &Value) -> Vec<StudyRow> {
    json.get("rows")
        .unwrap_or(json)
        .as_array()
        .map(|rows| rows.iter().filter_map(row_from_json).collect())
        .unwrap_or_default()
}

/// Writes `rows` as `study.csv` (or `study.parquet`) and `json` as `study.json`, each replaced
/// in one rename; the study table of the other format, left by an earlier run, is removed.
fn write_study_table(
    out: &Path,
    rows: &[StudyRow],
    json: &Value,
    tables: TableFormat,
) -> Result<()> {
    let table = study_table(rows);
    let write = |name: &str, bytes: std::io::Result<Vec<u8>>| {
        let tmp = out.join(format!(".{name}.tmp-{}", std::process::id()));
        let target = out.join(name);
        bytes
            .and_then(|bytes| std::fs::write(&tmp, bytes))
            .and_then(|()| std::fs::rename(&tmp, &target))
            .map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                IoError::Io {
                    path: target.display().to_string(),
                    source: e,
                }
            })
    };
    let (name, other) = match tables {
        TableFormat::Csv => ("study.csv", "study.parquet"),
        TableFormat::Parquet => ("study.parquet", "study.csv"),
    };
    let bytes = match tables {
        TableFormat::Csv => Ok(table.to_csv().into_bytes()),
        TableFormat::Parquet => pedo_output::parquet_bytes(&table),
    };
    // `study.json` first: the next run reads its rows from it (and from the folders it lacks),
    // so a run killed between the two renames loses no row.
    write("study.json", Ok(pretty(json).into_bytes()))?;
    write(name, bytes)?;
    let _ = std::fs::remove_file(out.join(other));
    for (name, csv) in [
        (STUDY_REGIONS, study_regions_csv(out, rows)),
        (STUDY_FEET, study_feet_csv(out, rows)),
    ] {
        match csv {
            Some(csv) => write(name, Ok(csv.into_bytes()))?,
            None => {
                let _ = std::fs::remove_file(out.join(name));
            }
        }
    }
    Ok(())
}

/// The table of each two-insole trial's values per foot, beside its study table.
pub const STUDY_FEET: &str = "study_feet.csv";

/// `study_feet.csv`: per trial of both feet apart (a pedar recording of both insoles) and per
/// foot, its values from its folder's `summary.json` `foot_measures`, in the study table's
/// measure columns and units (`trial,foot,peak_pressure_kpa,...`; empty where a value is not in
/// that unit); `None` when no trial has feet, so a study of plates keeps its files.
fn study_feet_csv(out: &Path, rows: &[StudyRow]) -> Option<String> {
    use pedo_output::Cell;
    let mut header = vec!["trial".to_string(), "foot".to_string()];
    header.extend(MEASURE_COLUMNS.iter().map(|(c, _, _)| c.to_string()));
    let mut table = pedo_output::Table {
        header,
        rows: Vec::new(),
    };
    for row in rows.iter().filter(|r| r.status != RowStatus::Error) {
        let Some(folder) = &row.output else { continue };
        let Ok(text) = std::fs::read_to_string(out.join(folder).join("summary.json")) else {
            continue;
        };
        let Ok(summary) = serde_json::from_str::<Value>(&text) else {
            continue;
        };
        let Some(feet) = summary["foot_measures"].as_object() else {
            continue;
        };
        for (foot, values) in feet {
            let m = StudyMeasures::of_summary(&json!({ "measures": values }));
            let mut cells = vec![Cell::Text(row.path.clone()), Cell::Text(foot.clone())];
            cells.extend(
                m.values()
                    .map(|v| v.map_or(Cell::Empty, |v| Cell::Float(v, 4))),
            );
            table.rows.push(cells);
        }
    }
    (!table.rows.is_empty()).then(|| table.to_csv())
}

/// The long table of every region measure of a study's trials, beside its study table.
pub const STUDY_REGIONS: &str = "study_regions.csv";

/// `study_regions.csv`: the rows of each trial's `regions.csv` (region, measure, value, unit)
/// after its path, `trial,region,measure,value,unit`, in the study table's order; `None` when
/// no trial has regions (a study run without a region rule). When a trial's regions are per
/// foot (a pedar recording of both insoles), a `foot` column follows `trial`, empty for the
/// trials of one sensor.
fn study_regions_csv(out: &Path, rows: &[StudyRow]) -> Option<String> {
    use pedo_output::Cell;
    let mut table = pedo_output::Table {
        header: ["trial", "region", "measure", "value", "unit"]
            .map(String::from)
            .to_vec(),
        rows: Vec::new(),
    };
    let mut feet = false;
    for row in rows {
        let Some(folder) = &row.output else { continue };
        if row.status == RowStatus::Error {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(out.join(folder).join("regions.csv")) else {
            continue;
        };
        // A trial's regions per foot have a first column `foot`.
        let per_foot = text.starts_with("foot,");
        for line in text.lines().skip(1) {
            let mut f: Vec<&str> = line.split(',').collect();
            let foot = if per_foot && !f.is_empty() {
                f.remove(0)
            } else {
                ""
            };
            // The fixed regions' rows (a `kind` column after the unit since the regions also
            // move with the foot; the moving rows stay in the trial's regions.csv).
            let fixed = matches!(f.get(4), None | Some(&"fixed"));
            if let [region, measure, value, unit, ..] = f[..]
                && fixed
                && let Ok(v) = value.parse::<f64>()
            {
                feet |= per_foot;
                table.rows.push(vec![
                    Cell::Text(row.path.clone()),
                    Cell::Text(foot.to_string()),
                    Cell::Text(region.to_string()),
                    Cell::Text(measure.to_string()),
                    Cell::Float(v, 6),
                    Cell::Text(unit.to_string()),
                ]);
            }
        }
    }
    if feet {
        table.header.insert(1, "foot".to_string());
    } else {
        // No trial's regions are per foot: the columns of a study of plates.
        for r in &mut table.rows {
            r.remove(1);
        }
    }
    (!table.rows.is_empty()).then(|| table.to_csv())
}

/// The study table's file in study folder `out` when tables are written as `tables`.
pub fn study_table_path(out: &Path, tables: TableFormat) -> PathBuf {
    out.join(tables.file_name("study"))
}

/// One recording of a study: read, run and (with an output folder) written, or skipped when its
/// folder is complete; never fails: what goes wrong is the row's `error` and message.
/// `previous` is its row in the study's previous table (kept for a skipped recording);
/// `progress` gets the fraction done. Runs on the current rayon pool: call it from a pool of one
/// thread to keep the recording on one core.
pub fn run_recording(
    path: &Path,
    opts: &StudyOptions,
    previous: Option<&StudyRow>,
    progress: &(dyn Fn(f64) + Sync),
) -> StudyRow {
    let output = opts.out.as_deref().map(|out| {
        let previous: Vec<StudyRow> = previous.into_iter().cloned().collect();
        claimed_output_name(out, path, &previous, &folder_name)
    });
    run_recording_as(path, opts, output, previous, progress)
}

/// The folder name of the recording at `path` in study folder `out` ([`output_names`], with
/// its `previous` row), claimed for it, so that a run elsewhere of a recording with the same
/// first name, started at the same moment, takes another. A name claimed by another recording
/// is passed over by [`output_names`] from then on, so each refusal moves on; a claim that
/// cannot be written (a read-only folder) leaves the name unclaimed, for the run to fail
/// writing its folder.
fn claimed_output_name(
    out: &Path,
    path: &Path,
    previous: &[StudyRow],
    folder_name: &dyn Fn(&Path, usize) -> String,
) -> String {
    let file = path.canonicalize().ok();
    let is_other = |other: &str| is_other_file(other, file.as_deref());
    loop {
        let name =
            output_names_with(Some(out), &[path.to_path_buf()], previous, folder_name).remove(0);
        if !matches!(claim::claim(out, &name, path, &is_other), Ok(false)) {
            return name;
        }
    }
}

/// [`run_recording`] into folder `output` of the study folder (a name of [`output_names`]).
fn run_recording_as(
    path: &Path,
    opts: &StudyOptions,
    output: Option<String>,
    previous: Option<&StudyRow>,
    progress: &(dyn Fn(f64) + Sync),
) -> StudyRow {
    let started = Instant::now();
    // Set once the recording is read, so that an error row still says its frames and units.
    let mut read = None;
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        process(
            path,
            opts,
            output.as_deref(),
            previous,
            progress,
            started,
            &mut read,
        )
    }));
    let outcome = match outcome {
        Ok(r) => r,
        Err(panic) => Err(IoError::invalid(format!(
            "internal error (please report it): {}",
            panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default()
        ))),
    };
    // A failed run writes nothing: its row names a folder only if an earlier run left one there
    // (kept as it was).
    let existing = |name: &String| {
        opts.out
            .as_ref()
            .is_some_and(|out| outdir::is_output(&out.join(name)))
    };
    let (frames, units) = read.unzip();
    outcome.unwrap_or_else(|e| StudyRow {
        path: path.display().to_string(),
        output: output.filter(existing),
        format: sniff_file(path).map(|f| f.name().to_string()),
        frames,
        units: units.unwrap_or_default(),
        pairs: None,
        mean_local_percent: None,
        mean_optimisation_percent: None,
        mean_trackable_percent: None,
        mean_round_trip_sensels: None,
        tracks: None,
        track_round_trip_sensels: Quantiles::default(),
        point_round_trip_sensels: Quantiles::default(),
        measures: StudyMeasures::default(),
        wall_time_s: started.elapsed().as_secs_f64(),
        status: RowStatus::Error,
        message: one_line(&e.to_string()),
    })
}

fn process(
    path: &Path,
    opts: &StudyOptions,
    output: Option<&str>,
    previous: Option<&StudyRow>,
    progress: &(dyn Fn(f64) + Sync),
    started: Instant,
    read: &mut Option<(usize, RowUnits)>,
) -> Result<StudyRow> {
    opts.params.validate()?;
    if let Some(e) = broken_link_error(path) {
        return Err(e);
    }
    // The SHA-256 recorded must be of the bytes parsed: the input is read, then hashed, and
    // must not change from before the read to after the hash (nor, streamed, to its last frame).
    let stamp = FileStamp::of(path);
    let pedo_io::formats::RunInput {
        mut recording,
        frames: mut file_frames,
        sha256,
    } = read_for_run(path, &opts.read, &opts.params, &opts.outputs)?;
    *read = Some((recording.n_frames(), RowUnits::of(&recording)));
    let input = InputInfo::of_read(path, sha256)?.with_layout(&opts.read, recording.format)?;
    stamp.check(path)?;
    let mut unchanged = file_frames.as_mut().map(|inner| Unchanged {
        inner,
        path,
        stamp: &stamp,
    });
    // The unit options are applied even when the options fail (a frame range beyond the
    // recording): the units an error row gives are those the run would have used.
    let options = run_options(&mut recording, &opts.params).map_err(|e| e.of_input(&input.name));
    *read = Some((recording.n_frames(), RowUnits::of(&recording)));
    let mut options = options?;
    options.cancel = opts.cancel.clone();
    let read_s = started.elapsed().as_secs_f64();
    let folder = opts.out.as_ref().zip(output).map(|(o, n)| o.join(n));
    if let Some(folder) = folder.as_deref().filter(|_| !opts.force) {
        let used = used_options(&opts.params, &options, &recording);
        if let Some(summary) = complete_summary(folder, &input, &used, &options, &opts.outputs) {
            let mut row = row_of_summary(path, output, &summary, started);
            // The wall time of the run that wrote the folder: its row, or (a run interrupted
            // before it wrote the study table) the stages its summary timed.
            row.wall_time_s = match previous {
                Some(p) => p.wall_time_s,
                None => summary["timings_s"]
                    .as_object()
                    .map_or(row.wall_time_s, |t| {
                        t.values().filter_map(Value::as_f64).sum()
                    }),
            };
            row.status = RowStatus::Skipped;
            row.message =
                "outputs complete (same input SHA-256 and options); --force (force=True) runs it again"
                    .into();
            return Ok(row);
        }
    }
    let on_stage = |stage: Stage, done: usize, total: usize| {
        let part = done as f64 / total.max(1) as f64;
        progress(match stage {
            Stage::Objects => 0.45 * part,
            Stage::Matching => 0.45 + 0.45 * part,
            Stage::Output => 0.9 + 0.1 * part,
        })
    };
    let plan = RunPlan {
        input: &input,
        params: &opts.params,
        frames: unchanged.as_mut().map(|f| f as &mut dyn FrameSource),
        folder: folder.as_deref(),
        outputs: &opts.outputs,
        timings: &[("read", read_s)],
        also: None,
    };
    let (summary, counts) = run_into_folder(&recording, &options, plan, &on_stage)?;
    let mut row = row_of_summary(path, output, &summary, started);
    row.message = run_note(&counts, options.model);
    Ok(row)
}

/// The options of a run as `summary.json` records them.
fn used_options(params: &RunParams, options: &SequenceOptions, recording: &Recording) -> Value {
    Value::Object(
        params
            .used(options, recording)
            .iter()
            .map(|(k, v)| (k.to_string(), pedo_output::option_json(v)))
            .collect::<Map<String, Value>>(),
    )
}

/// The summary of `folder` if it is complete: a pedomatch output whose `summary.json` has the
/// input's SHA-256 and the options `used` (with the animation choice of `outputs`, which
/// `summary.json` records among them), with every table a run with `options` writes
/// ([`run_table_files`]: reference_matches too with drift correction), and every output that
/// `outputs` asks for: the measures' files ([`pedo_output::MEASURE_FILES`]), the report, the
/// animation, the tracks, peak and PTI figures and the figure of every matched pair (those of
/// `pairs.json`), in each format asked for.
pub fn is_complete(
    folder: &Path,
    input: &InputInfo,
    used: &Value,
    options: &SequenceOptions,
    outputs: &RunOutputs,
) -> bool {
    complete_summary(folder, input, used, options, outputs).is_some()
}

fn complete_summary(
    folder: &Path,
    input: &InputInfo,
    used: &Value,
    options: &SequenceOptions,
    outputs: &RunOutputs,
) -> Option<Value> {
    if !outdir::is_output(folder) || input.sha256.is_none() {
        return None;
    }
    let summary = read_json(&folder.join("summary.json"))?;
    // A pedar recording read with another layout file (or with none) is another input.
    let layout = input.layout.as_ref().and_then(|l| l.sha256.as_deref());
    let same_input = summary["input"]["sha256"].as_str() == input.sha256.as_deref()
        && summary["input"]["layout"]["sha256"].as_str() == layout;
    let mut used = used.clone();
    if let Some(options) = used.as_object_mut() {
        record_outputs(options, outputs);
    }
    if !same_input || !json_close(&summary["options"], &used) {
        return None;
    }
    let mut files = run_table_files(outputs.tables, options);
    files.extend(pedo_output::MEASURE_FILES.map(String::from));
    if outputs.any_regions() {
        files.push("regions.json".into());
    }
    if outputs.report {
        files.push("report.html".into());
    }
    if outputs.animation {
        files.push("animation.gif".into());
    }
    let extensions = outputs.figures.extensions();
    if !extensions.is_empty() {
        let mut stems: Vec<String> = SUMMARY_FIGURES.iter().map(|s| s.to_string()).collect();
        if outputs.pair_figures {
            let pairs = read_json(&folder.join("pairs.json"))?;
            for pair in pairs.as_array()? {
                if pair["status"] == "ok" {
                    let (a, b) = (pair["id_a"].as_u64()?, pair["id_b"].as_u64()?);
                    stems.push(format!("figures/pair_{a:04}_{b:04}"));
                }
            }
        }
        for stem in &stems {
            files.extend(extensions.iter().map(|ext| format!("{stem}.{ext}")));
        }
    }
    files
        .iter()
        .all(|f| folder.join(f).is_file())
        .then_some(summary)
}

/// Equal JSON values, numbers equal to 12 significant digits (a float written and read back
/// may differ in its last bit).
fn json_close(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) => x == y || (x - y).abs() <= 1e-12 * x.abs().max(y.abs()),
            _ => x == y,
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| json_close(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| json_close(v, w)))
        }
        _ => a == b,
    }
}

fn row_of_summary(
    path: &Path,
    output: Option<&str>,
    summary: &Value,
    started: Instant,
) -> StudyRow {
    let int = |v: &Value| v.as_u64().map(|x| x as usize);
    StudyRow {
        path: path.display().to_string(),
        output: output.map(str::to_string),
        format: summary["input"]["format"].as_str().map(str::to_string),
        frames: int(&summary["recording"]["frames"]),
        units: RowUnits::of_summary(summary),
        pairs: int(&summary["pairs"]),
        mean_local_percent: summary["mean_local_percent"].as_f64(),
        mean_optimisation_percent: summary["mean_optimisation_percent"].as_f64(),
        mean_trackable_percent: summary["mean_trackable_percent"].as_f64(),
        mean_round_trip_sensels: summary["mean_round_trip_sensels"].as_f64(),
        tracks: int(&summary["tracks"]),
        track_round_trip_sensels: Quantiles::of_summary(summary, RoundTripSummary::Tracks),
        point_round_trip_sensels: Quantiles::of_summary(summary, RoundTripSummary::Points),
        measures: StudyMeasures::of_summary(summary),
        wall_time_s: started.elapsed().as_secs_f64(),
        status: RowStatus::Ok,
        message: String::new(),
    }
}

/// What a row of a successful run says (empty if nothing): that it had no pair to match, so no
/// means to report (as `pedomatch run` says), and what it left out: the pairs that could not be
/// matched and the frames (for isocontours, the isobaric levels) that gave no object.
fn run_note(r: &RunCounts, model: ObjectModel) -> String {
    let isocontour = model == ObjectModel::Isocontour;
    let mut parts = Vec::new();
    if r.pairs == 0 {
        parts.push(no_pairs_note(isocontour, r.skipped_pairs.len()).to_string());
    }
    let mut skipped = Vec::new();
    if !r.skipped_pairs.is_empty() {
        skipped.push(pedo_io::counted(r.skipped_pairs.len(), "pair"));
    }
    if !r.skipped_frames.is_empty() {
        let what = if isocontour {
            "isobaric level"
        } else {
            "frame"
        };
        skipped.push(pedo_io::counted(r.skipped_frames.len(), what));
    }
    if !skipped.is_empty() {
        let first = r
            .skipped_pairs
            .first()
            .map(|s| s.reason.as_str())
            .or(r.skipped_frames.first().map(|s| s.reason.as_str()))
            .unwrap_or_default();
        parts.push(format!(
            "{} skipped (first: {first})",
            skipped.join(" and ")
        ));
    }
    one_line(&parts.join("; "))
}

/// Why a run that matched no pair reports no means (`pedomatch run` and a study's row say it):
/// no two objects in consecutive frames (for isocontours, at consecutive isobaric levels), or,
/// when `skipped_pairs` were tried, none that could be matched.
pub fn no_pairs_note(isocontour: bool, skipped_pairs: usize) -> &'static str {
    match (skipped_pairs, isocontour) {
        (1.., _) => "no pair of objects could be matched: no means to report",
        (0, true) => {
            "no pair of objects at consecutive isobaric levels to match: no means to report"
        }
        (0, false) => "no pair of objects in consecutive frames to match: no means to report",
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The counts of a study's rows by status, as `--json` and the closing line report them.
pub fn status_counts(rows: &[StudyRow]) -> Value {
    let count = |s: RowStatus| rows.iter().filter(|r| r.status == s).count();
    json!({
        "recordings": rows.len(),
        "ok": count(RowStatus::Ok),
        "skipped": count(RowStatus::Skipped),
        "error": count(RowStatus::Error),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pedo_track::{require_objects, run_sequence};

    fn row(status: RowStatus) -> StudyRow {
        StudyRow {
            path: "data/s01, left \"walk\".asf".into(),
            output: Some("walk.asf-0123abcd".into()),
            format: Some("asf".into()),
            frames: Some(205),
            units: RowUnits {
                frame_rate_hz: Some(1.0 / 0.032),
                pitch_mm: Some([5.08, 7.62]),
                pressure_units: Some("KPa".into()),
            },
            pairs: Some(150),
            mean_local_percent: Some(61.25),
            mean_optimisation_percent: Some(97.5),
            mean_trackable_percent: Some(88.5),
            mean_round_trip_sensels: Some(0.125),
            tracks: Some(900),
            track_round_trip_sensels: Quantiles {
                median: Some(0.25),
                p95: Some(0.75),
            },
            point_round_trip_sensels: Quantiles {
                median: Some(0.0625),
                p95: None,
            },
            measures: StudyMeasures {
                peak_pressure_kpa: Some(812.5),
                pti_max_kpa_s: Some(190.25),
                peak_force_n: Some(1012.0),
                fti_n_s: Some(402.5),
                contact_time_s: Some(0.64),
                max_contact_area_mm2: None,
            },
            wall_time_s: 1.5,
            status,
            message: String::new(),
        }
    }

    #[test]
    fn a_row_takes_the_round_trip_quantiles_of_its_summary() {
        // As the run writes them: the tracks' round trips, no points followed.
        let trips = pedo_track::consistency::RoundTrips {
            count: 9,
            median: 0.5,
            p95: 1.25,
            max: 2.0,
            over_1_percent: 22.2,
        };
        let mut summary =
            json!({ "track_round_trip_sensels": RoundTripSummary::Tracks.json(Some(trips)) });
        pedo_output::set_point_round_trips(&mut summary, []);
        assert!(summary["point_round_trip_sensels"].is_null());
        let r = row_of_summary(Path::new("x.lst"), None, &summary, Instant::now());
        assert_eq!(
            r.track_round_trip_sensels,
            Quantiles {
                median: Some(0.5),
                p95: Some(1.25)
            }
        );
        assert_eq!(r.point_round_trip_sensels, Quantiles::default());
        let table = study_table(&[r]);
        let col = |c: &str| STUDY_COLUMNS.iter().position(|&k| k == c).unwrap();
        let cells = &table.rows[0];
        assert_eq!(
            cells[col("track_round_trip_p95_sensels")],
            Cell::Float(1.25, 4)
        );
        assert_eq!(cells[col("point_round_trip_median_sensels")], Cell::Empty);
    }

    #[test]
    fn a_row_survives_the_study_json() {
        for status in [RowStatus::Ok, RowStatus::Skipped, RowStatus::Error] {
            let r = row(status);
            let json = study_table(std::slice::from_ref(&r)).to_json();
            assert_eq!(row_from_json(&json[0]), Some(r));
        }
        // Through the file's text: a resumed study keeps its rows to the last bit. A wall time of
        // 1_535_625_782 ns is written with 17 digits, which serde_json's default parser rounds
        // twice (one ulp off); the `float_roundtrip` feature parses it exactly.
        let nanos = std::time::Duration::from_nanos;
        for wall_time_s in [
            nanos(1_535_625_782).as_secs_f64(),
            0.1 + 0.2,
            12345.678901234567,
        ] {
            let r = StudyRow {
                wall_time_s,
                ..row(RowStatus::Ok)
            };
            let text = pretty(&study_table(std::slice::from_ref(&r)).to_json());
            let back: Value = serde_json::from_str(&text).unwrap();
            assert_eq!(row_from_json(&back[0]), Some(r));
        }
        let csv = study_table(&[row(RowStatus::Ok)]).to_csv();
        assert_eq!(csv.lines().next().unwrap(), STUDY_COLUMNS.join(","));
        // Reading knows it for pedomatch's own, and refuses it as a recording naming it.
        let own = pedo_io::formats::own_tables::own_table(&csv).map(|t| t.file);
        assert_eq!(own, Some("study.csv"));
        assert!(
            csv.contains("\"data/s01, left \"\"walk\"\".asf\","),
            "free text is quoted: {csv}"
        );
    }

    #[test]
    fn study_json_is_read_as_an_object_and_as_the_bare_list_it_was() {
        let rows = [row(RowStatus::Ok), row(RowStatus::Error)];
        let mut provenance = Map::new();
        provenance.insert("inputs".into(), json!(["data/"]));
        let json = study_json(provenance, &rows[..1], &rows[1..], Vec::new());
        assert_eq!((&json["recordings"], &json["kept"]), (&json!(1), &json!(1)));
        assert_eq!((&json["ok"], &json["error"]), (&json!(1), &json!(0)));
        assert_eq!(rows_of_study_json(&json), rows);
        let bare = study_table(&rows).to_json();
        assert_eq!(rows_of_study_json(&bare), rows);
        // A row written before the units were columns: no units.
        let mut old = bare[0].clone();
        for c in [
            "frame_rate_hz",
            "pitch_x_mm",
            "pitch_y_mm",
            "pressure_units",
        ] {
            old.as_object_mut().unwrap().remove(c);
        }
        let read = row_from_json(&old).unwrap();
        assert_eq!(read.units, RowUnits::default());
        assert_eq!(read.frames, rows[0].frames);
        assert!(rows_of_study_json(&json!({"rows": "?"})).is_empty());
    }

    #[test]
    fn an_isocontour_run_without_objects_says_why() {
        // A foot of 100 kPa with one stuck sensel at 5000: the levels, up to the peak, all lie
        // above the foot.
        let (rows, cols) = (24, 16);
        let mut data: Vec<f32> = (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64 - 12.0, (i % cols) as f64 - 8.0);
                if (r / 9.0).powi(2) + (c / 5.0).powi(2) <= 1.0 {
                    100.0
                } else {
                    0.0
                }
            })
            .collect();
        data[0] = 5000.0;
        let rec = Recording::new(1, rows, cols, data, vec![true; rows * cols]).unwrap();
        let options = SequenceOptions {
            model: ObjectModel::Isocontour,
            ..SequenceOptions::default()
        };
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        assert!(run.objects.is_empty());
        let e = require_objects(0, &rec, &options).unwrap_err().to_string();
        assert!(
            e.contains("no isobaric level of the frame of largest load")
                && e.contains("hot or stuck sensel")
                && e.contains("iso_levels"),
            "{e}"
        );
    }

    #[test]
    fn a_kept_rows_message_says_so_once_and_keeps_the_earlier_message() {
        let once = kept_message("2 pairs skipped", true);
        assert_eq!(
            once,
            "kept from an earlier run (not among this run's inputs); 2 pairs skipped"
        );
        assert_eq!(kept_message(&once, true), once);
        assert_eq!(
            kept_message(&once, false),
            "kept from an earlier run (its input is no longer at this path); 2 pairs skipped"
        );
        assert_eq!(
            kept_message("", true),
            "kept from an earlier run (not among this run's inputs)"
        );
        assert_eq!(
            kept_message(&kept_message("", false), true),
            kept_message("", true)
        );
    }

    #[test]
    fn kept_rows_are_listed_under_the_latest_run_that_made_them() {
        let at = |path: &str| StudyRow {
            path: path.into(),
            ..row(RowStatus::Ok)
        };
        let (x, y, z, w) = (at("x"), at("y"), at("z"), at("w"));
        let mut provenance = Map::new();
        provenance.insert("options".into(), json!({"spacing": 1.5}));
        // The previous run ran x and y; before it, a run with spacing 1 made y (since re-run),
        // z and w.
        let older = json!([{"options": {"spacing": 1.0}, "paths": ["y", "z", "w"]}, "?"]);
        let mut previous = study_json(provenance, &[x.clone(), y.clone()], &[z.clone(), w], vec![]);
        previous["earlier_runs"] = older;
        // This run keeps x and z (it re-ran y; w's folder is gone).
        let earlier = earlier_runs(Some(&previous), &[x, z]);
        assert_eq!(
            earlier,
            [
                json!({"pedomatch_version": null, "inputs": null, "options": {"spacing": 1.5}, "paths": ["x"]}),
                json!({"options": {"spacing": 1.0}, "paths": ["z"]}),
            ]
        );
        // A bare list of rows: one run of which nothing is known.
        let bare = study_table(&[at("x"), at("y")]).to_json();
        assert_eq!(
            earlier_runs(Some(&bare), &[at("y")]),
            [json!({"pedomatch_version": null, "inputs": null, "options": null, "paths": ["y"]})]
        );
        assert!(earlier_runs(None, &[at("y")]).is_empty());
    }

    #[test]
    fn one_thread_per_caller_is_kept_across_recordings() {
        // A new thread per recording made a study's memory grow with its recordings (each new
        // thread got a malloc arena of its own); the caller's pool and its one thread are kept.
        let worker =
            || on_one_thread(|| (std::thread::current().id(), rayon::current_num_threads()));
        let (first, threads) = worker();
        assert_eq!(threads, 1);
        assert_ne!(first, std::thread::current().id());
        for _ in 0..5 {
            assert_eq!(worker().0, first);
        }
        let other = std::thread::spawn(move || worker().0).join().unwrap();
        assert_ne!(other, first, "each calling thread has its own pool");
    }

    /// Frames of a recording, the file at `path` appended to before each window (another
    /// program still writing it).
    struct Appending<'a>(&'a Path);

    impl FrameSource for Appending<'_> {
        fn window(&mut self, recording: &Recording, w0: usize, w1: usize) -> Result<Recording> {
            use std::io::Write;
            let mut f = std::fs::OpenOptions::new()
                .append(true)
                .open(self.0)
                .unwrap();
            f.write_all(b"0,0\n").unwrap();
            Recording::new(
                w1 - w0,
                recording.rows(),
                recording.cols(),
                vec![0.0; (w1 - w0) * recording.rows() * recording.cols()],
                vec![true; recording.rows() * recording.cols()],
            )
        }
    }

    #[test]
    fn a_file_changed_during_a_streamed_run_fails_it() {
        let dir = std::env::temp_dir().join(format!("pedo-study-stamp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("walk.csv");
        std::fs::write(&path, "1,2\n3,4\n").unwrap();
        let recording = Recording::new(4, 2, 2, vec![1.0; 16], vec![true; 4]).unwrap();
        let stamp = FileStamp::of(&path);
        stamp.check(&path).unwrap();
        // Unchanged: the windows go through.
        let mut still = Appending(&dir.join("other.csv"));
        std::fs::write(dir.join("other.csv"), "").unwrap();
        let mut frames = Unchanged {
            inner: &mut still,
            path: &path,
            stamp: &stamp,
        };
        assert_eq!(frames.window(&recording, 0, 2).unwrap().n_frames(), 2);
        // Appended to while its frames are read: the window fails, naming the file.
        let mut appending = Appending(&path);
        let mut frames = Unchanged {
            inner: &mut appending,
            path: &path,
            stamp: &stamp,
        };
        let e = frames.window(&recording, 2, 4).unwrap_err().to_string();
        assert!(e.contains("changed while it was being read"), "{e}");
        assert!(e.contains("walk.csv"), "{e}");
        assert!(stamp.check(&path).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn recordings_forced_to_one_folder_name_get_different_folders() {
        // Every recording's first name the same: the later ones get their longer names.
        let forced = |p: &Path, k: usize| match k {
            0 => "walk.asf-00000000".to_string(),
            k => folder_name(p, k),
        };
        let paths: Vec<PathBuf> = ["a/walk.asf", "b/walk.asf", "c/walk.asf"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let names = output_names_with(None, &paths, &[], &forced);
        assert_eq!(names[0], "walk.asf-00000000");
        assert_eq!(names[1], folder_name(&paths[1], 1));
        assert_eq!(names[2], folder_name(&paths[2], 1));
        assert_eq!(names[1].len(), "walk.asf-".len() + 16);
        assert_ne!(names[1], names[2]);
        // Every name taken but the counted ones: a count tells them apart.
        let all_same = |_: &Path, k: usize| match k {
            0..=3 => "walk.asf-x".to_string(),
            k => format!("walk.asf-y-{}", k - 2),
        };
        let names = output_names_with(None, &paths, &[], &all_same);
        assert_eq!(names, ["walk.asf-x", "walk.asf-y-2", "walk.asf-y-3"]);
        // A name of a longer form is one of the path's own.
        let own = is_folder_name_of(&paths[1]);
        assert!(own(&folder_name(&paths[1], 2)));
        assert!(own(&folder_name(&paths[1], 5)));
        assert!(!own(&folder_name(&paths[0], 1)));
        assert!(!own(&format!("{}-1", folder_name(&paths[1], 3))));
    }

    #[test]
    fn recordings_run_at_once_under_one_first_name_claim_different_folders() {
        // Eight recordings whose first names are the same, named at once by eight threads as
        // `batch_row` calls in eight processes would: each gets its own folder, and asked
        // again (a resumed call), the same one.
        let base = std::env::temp_dir().join(format!("pedo-claims-{}", std::process::id()));
        let out = base.join("study");
        std::fs::create_dir_all(&out).unwrap();
        let paths: Vec<PathBuf> = (0..8)
            .map(|i| {
                let dir = base.join(format!("trial{i}"));
                std::fs::create_dir_all(&dir).unwrap();
                std::fs::write(dir.join("walk.asf"), b"").unwrap();
                dir.join("walk.asf")
            })
            .collect();
        let forced = |p: &Path, k: usize| match k {
            0 => "walk.asf-00000000".to_string(),
            k => folder_name(p, k),
        };
        let barrier = std::sync::Barrier::new(paths.len());
        let names: Vec<String> = std::thread::scope(|s| {
            let runs: Vec<_> = paths
                .iter()
                .map(|p| {
                    s.spawn(|| {
                        barrier.wait();
                        claimed_output_name(&out, p, &[], &forced)
                    })
                })
                .collect();
            runs.into_iter().map(|r| r.join().unwrap()).collect()
        });
        let distinct: std::collections::HashSet<&String> = names.iter().collect();
        assert_eq!(distinct.len(), paths.len(), "{names:?}");
        assert_eq!(
            names.iter().filter(|n| *n == "walk.asf-00000000").count(),
            1
        );
        for (p, name) in paths.iter().zip(&names) {
            assert_eq!(&claimed_output_name(&out, p, &[], &forced), name);
        }
        // A batch names them as the claims say (none takes another's).
        let batch = output_names_with(Some(&out), &paths, &[], &forced);
        let claimed_first =
            paths[names.iter().position(|n| n == "walk.asf-00000000").unwrap()].clone();
        for (p, name) in paths.iter().zip(&batch) {
            assert_eq!(
                name == "walk.asf-00000000",
                *p == claimed_first,
                "{batch:?}"
            );
        }
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn a_batch_and_recordings_run_one_by_one_exclude_each_other() {
        let out = std::env::temp_dir().join(format!("pedo-shared-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let (row_a, _) = share_study_folder(&out).unwrap();
        let (row_b, _) = share_study_folder(&out).expect("rows run beside each other");
        let refused = lock_study_folder(&out).unwrap_err().to_string();
        assert!(
            refused.contains("in use by recordings run one by one"),
            "{refused}"
        );
        drop((row_a, row_b));
        let batch = lock_study_folder(&out).unwrap();
        let refused = share_study_folder(&out).unwrap_err().to_string();
        assert!(
            refused.contains(&format!(
                "another pedomatch batch (process {})",
                std::process::id()
            )),
            "{refused}"
        );
        drop(batch);
        assert!(share_study_folder(&out).is_ok());
        // Just after a batch takes the lock, before it has written its process id: a second
        // batch is told it is a batch, not rows run one by one.
        let taken = std::fs::File::create(out.join(STUDY_LOCK)).unwrap();
        taken.try_lock().unwrap();
        let refused = lock_study_folder(&out).unwrap_err().to_string();
        assert!(
            refused.contains("in use by another pedomatch batch;"),
            "{refused}"
        );
        drop(taken);
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn same_file_names_in_different_folders_get_different_stable_folders() {
        let a = output_name(Path::new("a/walk.asf"));
        let b = output_name(Path::new("b/walk.asf"));
        assert!(a.starts_with("walk.asf-") && b.starts_with("walk.asf-"));
        assert_ne!(a, b);
        assert_eq!(a, output_name(Path::new("a/walk.asf")));
        assert_eq!(a.len(), "walk.asf-".len() + 8);
    }

    #[test]
    fn options_read_back_compare_equal_to_the_last_bits() {
        let used = json!({"spacing": 0.1 + 0.2, "model": "contour", "pitch_mm": [5.08, 5.08]});
        let mut read_back = used.clone();
        read_back["spacing"] = json!(0.30000000000000004_f64.next_down());
        assert!(json_close(&used, &read_back));
        read_back["spacing"] = json!(0.3001);
        assert!(!json_close(&used, &read_back));
        read_back["spacing"] = used["spacing"].clone();
        read_back["model"] = json!("surface");
        assert!(!json_close(&used, &read_back));
    }
}

#[cfg(test)]
mod feet_tests {
    use super::*;

    #[test]
    fn a_pedar_trial_gives_its_feet_rows_and_foot_column_and_a_plate_trial_none() {
        let out = std::env::temp_dir().join(format!("pedo-study-feet-{}", std::process::id()));
        let plate_regions = "region,measure,value,unit,kind\nheel,fti,2,N·s,fixed\n";
        let pedar_regions = "foot,region,measure,value,unit,kind\n\
                             left,heel,fti,3,N·s,fixed\nright,heel,fti,4,N·s,fixed\n";
        let value = |v: f64, u: &str| json!({"value": v, "unit": u});
        let pedar_summary = json!({"foot_measures": {
            "left": {"peak_pressure": value(300.0, "kPa"), "contact_time": value(0.57, "s")},
            "right": {"peak_pressure": value(400.0, "kPa"), "contact_time": value(70.0, "frames")},
        }});
        let mut rows = Vec::new();
        for (name, regions, summary) in [
            ("plate", plate_regions, json!({"measures": {}})),
            ("pedar", pedar_regions, pedar_summary),
        ] {
            std::fs::create_dir_all(out.join(name)).unwrap();
            std::fs::write(out.join(name).join("regions.csv"), regions).unwrap();
            std::fs::write(out.join(name).join("summary.json"), summary.to_string()).unwrap();
            let row = json!({"path": name, "output": name, "wall_time_s": 0.0, "status": "ok"});
            rows.push(row_from_json(&row).unwrap());
        }
        let regions = study_regions_csv(&out, &rows).unwrap();
        assert_eq!(
            regions,
            "trial,foot,region,measure,value,unit\nplate,,heel,fti,2.000000,N·s\n\
             pedar,left,heel,fti,3.000000,N·s\npedar,right,heel,fti,4.000000,N·s\n"
        );
        // Only the plate: the columns of a study without feet, and no table of feet.
        let plate = &rows[..1];
        assert!(study_regions_csv(&out, plate)
            .unwrap()
            .starts_with("trial,region,measure,value,unit\nplate,heel,"));
        assert_eq!(study_feet_csv(&out, plate), None);
        let feet = study_feet_csv(&out, &rows).unwrap();
        let lines: Vec<&str> = feet.lines().collect();
        assert_eq!(
            lines[0],
            "trial,foot,peak_pressure_kpa,pti_max_kpa_s,peak_force_n,fti_n_s,contact_time_s,max_contact_area_mm2"
        );
        // A value in another unit than its column's is left empty (a time in frames).
        assert_eq!(
            lines[1..],
            [
                "pedar,left,300.0000,,,,0.5700,",
                "pedar,right,400.0000,,,,,"
            ]
        );
        std::fs::remove_dir_all(&out).unwrap();
    }
}
