//! What a run says about itself: where its input came from ([`InputInfo`]), a description of a
//! recording ([`describe`], `pedomatch inspect`) and the provenance summary of a run
//! (`summary.json`, [`run_summary`]).

use crate::*;
use modal_core::OptionValue;
use pedo_io::formats::ReadOptions;
use pedo_io::recording::{Format, Recording};
use pedo_io::{IoError, Result};
use pedo_track::consistency::RoundTrips;
use pedo_track::{RunCounts, RunParams, SequenceOptions, SequenceResult};
use serde_json::{json, Map, Value};
use sha2::{Digest, Sha256};

/// Where a recording came from: a name (the path as given) and, for files, the SHA-256 of its
/// bytes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InputInfo {
    /// The input's name: its path as given, or the name given to in-memory data.
    pub name: String,
    /// Lower-case hex SHA-256 of the input's bytes; `None` for in-memory arrays.
    pub sha256: Option<String>,
    /// The pedar sensor-layout file a pedar recording was read with (`--layout`), its name and
    /// SHA-256 ([`InputInfo::with_layout`]); `None` for the bundled layout and other formats.
    pub layout: Option<Box<InputInfo>>,
}

impl InputInfo {
    /// Why a run that streams (tables only) reads this input whole, `None` when it reads its
    /// frames as it goes ([`pedo_io::formats::why_read_whole`]).
    pub fn why_read_whole(&self) -> Option<String> {
        // A file, a folder or a numbered pattern of images (which has no hash): else data
        // given in memory (an array, the demo's bytes).
        let path = std::path::Path::new(&self.name);
        if path.exists() || self.name.contains('%') {
            pedo_io::formats::why_read_whole(path)
        } else {
            Some("the recording was given in memory".to_string())
        }
    }

    /// The name and hash of bytes read from `name`.
    pub fn of_bytes(name: &str, bytes: &[u8]) -> Self {
        Self {
            name: name.to_string(),
            sha256: Some(sha256_hex(bytes)),
            layout: None,
        }
    }

    /// The input read from `path` whose parser's bytes hashed to `sha256`
    /// ([`pedo_io::formats::RunInput::sha256`]); without a digest (a folder of images), the
    /// hash of its files ([`InputInfo::of_path`]).
    pub fn of_read(path: &std::path::Path, sha256: Option<String>) -> Result<Self> {
        match sha256 {
            Some(sha256) => Ok(Self {
                name: path.display().to_string(),
                sha256: Some(sha256),
                layout: None,
            }),
            None => Self::of_path(path),
        }
    }

    /// This input with the layout file of `read` when the recording read is a pedar one
    /// (`format`): its sensors' places, and so every result, depend on that file's content.
    pub fn with_layout(mut self, read: &ReadOptions, format: Option<Format>) -> Result<Self> {
        if format == Some(Format::Pedar)
            && let Some(layout) = &read.layout
        {
            self.layout = Some(Box::new(Self::of_path(layout)?));
        }
        Ok(self)
    }

    /// The name and hash of a file, or of every file of a folder in name order (an image
    /// sequence), hashed in that order. A numbered-sequence pattern (`walk_%03d.png`) names no
    /// single file and gets no hash.
    pub fn of_path(path: &std::path::Path) -> Result<Self> {
        if !path.exists() {
            return Ok(Self {
                name: path.display().to_string(),
                ..Self::default()
            });
        }
        let io = |e| IoError::Io {
            path: path.display().to_string(),
            source: e,
        };
        let mut hasher = Sha256::new();
        if path.is_dir() {
            let mut files: Vec<_> = std::fs::read_dir(path)
                .map_err(io)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect();
            files.sort();
            for f in files {
                hash_file(&mut hasher, &f).map_err(io)?;
            }
        } else {
            hash_file(&mut hasher, path).map_err(io)?;
        }
        Ok(Self {
            name: path.display().to_string(),
            sha256: Some(hex(&hasher.finalize())),
            layout: None,
        })
    }
}

/// Feeds a file to `hasher` piece by piece (a long recording is not read twice into memory).
fn hash_file(hasher: &mut Sha256, path: &std::path::Path) -> std::io::Result<()> {
    use std::io::Read;
    let mut file = std::fs::File::open(path)?;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => hasher.update(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Lower-case hex SHA-256 of `bytes`.
///
/// ```
/// assert_eq!(
///     pedo_output::sha256_hex(b"abc"),
///     "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
/// );
/// ```
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// An option value as JSON.
pub fn option_json(v: &OptionValue) -> Value {
    match v {
        OptionValue::Absent => Value::Null,
        OptionValue::Bool(b) => json!(b),
        OptionValue::Int(i) => json!(i),
        OptionValue::Float(f) => json!(f),
        OptionValue::Word(w) => json!(w),
        OptionValue::Numbers(v) => json!(v),
    }
}

fn min_mean_max(values: impl Iterator<Item = f64>) -> Value {
    let v: Vec<f64> = values.collect();
    if v.is_empty() {
        return Value::Null;
    }
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    json!({"min": min, "mean": v.iter().sum::<f64>() / v.len() as f64, "max": max})
}

/// What a recording holds: format, size, pitch, frame rate, units, noise threshold and the
/// min / mean / max over all frames of the per-frame measures at or above `threshold` (as in
/// [`frames_table`]; the unit is in each measure's name).
pub fn describe(recording: &Recording, input: &InputInfo, threshold: f64) -> Value {
    let u = measure_units(recording);
    let m = recording.measures(threshold);
    let loaded = m.iter().filter(|x| x.contact_sensors > 0).count();
    let read_whole = input.why_read_whole();
    let mut measures = Map::new();
    measures.insert(
        u.area.0.into(),
        min_mean_max(m.iter().map(|x| x.contact_area * u.area.1)),
    );
    measures.insert(
        u.force.into(),
        min_mean_max(m.iter().map(|x| x.total_force)),
    );
    measures.insert(
        u.peak.0.into(),
        min_mean_max(m.iter().map(|x| x.peak_pressure * u.peak.1)),
    );
    json!({
        "file": input.name,
        "sha256": input.sha256,
        "format": recording.format.map(|f| f.name()),
        "frames": recording.n_frames(),
        "rows": recording.rows(),
        "cols": recording.cols(),
        "sensors": recording.n_sensors(),
        "pitch_mm": recording.pitch_mm,
        "sensel_area_mm2": recording.sensel_area(),
        "frame_rate_hz": recording.frame_rate(),
        "duration_s": recording.dt_s.map(|dt| dt * recording.n_frames() as f64),
        "pressure_units": recording.known_units(),
        "noise_threshold": recording.noise_threshold,
        "negative_values": negative_values(recording),
        "streams": read_whole.is_none(),
        "read_whole": read_whole,
        "measures_threshold": threshold,
        "loaded_frames": loaded,
        "measures": measures,
    })
}

/// The values below 0 of a recording's existing sensors over every frame, as the file held
/// them: `{"count", "min", "clipped"}` (`min` null without any; `clipped`: set to 0 by
/// `clip_negative`). Measures count only values above 0, so these never enter one; they are
/// reported so that an offset in the data does not pass without a word.
pub fn negative_values(recording: &Recording) -> Value {
    let n = recording.negative_values();
    json!({"count": n.count, "min": n.min, "clipped": recording.negatives_clipped()})
}

/// The provenance and outcome of a run, as written to `summary.json` and returned by
/// `pymodal.run`: the pedomatch version, the input (name, SHA-256, format), the recording's
/// size and units, every option actually used (defaults included), the counts and means of the
/// results, and the seconds spent in each stage (`timings`: the stages measured outside the
/// sequence run, e.g. reading, are passed in and come first).
pub fn run_summary(
    input: &InputInfo,
    recording: &Recording,
    params: &RunParams,
    options: &SequenceOptions,
    r: &SequenceResult,
    timings: &[(&str, f64)],
) -> Value {
    run_summary_of(
        input,
        recording,
        params,
        options,
        &RunCounts::of(r),
        timings,
    )
}

/// The two summaries of round trips `summary.json` records, each an object with its count,
/// `median`, `p95`, `max` and `over_1_percent` (the share over one sensel), or `null` without
/// any. Written and read here only, so that every reader agrees with the writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoundTripSummary {
    /// `track_round_trip_sensels`: one round trip per track (`tracks.csv`'s
    /// `round_trip_sensels`), counted as `tracks`.
    Tracks,
    /// `point_round_trip_sensels`: one per step of a material point (`points.csv`'s
    /// `round_trip_sensels`, [`pedo_track::follow::FollowedPoint::round_trips`]), counted as
    /// `steps`; `null` where no points were followed, or none stepped through a matched pair.
    Points,
}

impl RoundTripSummary {
    /// Both, in the order the summary line states them.
    pub const ALL: [Self; 2] = [Self::Tracks, Self::Points];

    /// The summary's key.
    pub const fn key(self) -> &'static str {
        match self {
            Self::Tracks => "track_round_trip_sensels",
            Self::Points => "point_round_trip_sensels",
        }
    }

    /// The key of the count in the object.
    const fn count_key(self) -> &'static str {
        match self {
            Self::Tracks => "tracks",
            Self::Points => "steps",
        }
    }

    /// The object recording `trips` (`null` for `None`).
    pub fn json(self, trips: Option<RoundTrips>) -> Value {
        match trips {
            Some(t) => json!({
                (self.count_key()): t.count, "median": t.median, "p95": t.p95, "max": t.max,
                "over_1_percent": t.over_1_percent,
            }),
            None => Value::Null,
        }
    }

    /// The round trips `summary` records (`None` without any, or in a summary written before
    /// they were recorded).
    pub fn of_summary(self, summary: &Value) -> Option<RoundTrips> {
        let t = &summary[self.key()];
        let f = |k: &str| t[k].as_f64();
        Some(RoundTrips {
            count: usize::try_from(t[self.count_key()].as_u64()?).ok()?,
            median: f("median")?,
            p95: f("p95")?,
            max: f("max")?,
            over_1_percent: f("over_1_percent")?,
        })
    }
}

/// Records in `summary` the round trips of the rows of `points.csv` ([`point_round_trips`]) as
/// [`RoundTripSummary::Points`].
pub fn set_point_round_trips(summary: &mut Value, trips: impl IntoIterator<Item = f32>) {
    let points = RoundTripSummary::Points;
    summary[points.key()] = points.json(RoundTrips::of(trips));
}

/// The round trips of the points of `points.csv` (not the user's regions' outline points),
/// step by step ([`set_point_round_trips`]).
pub fn point_round_trips(
    points: &pedo_track::follow::FollowedPoints,
) -> impl Iterator<Item = f32> + '_ {
    use pedo_track::follow::Seeded;
    (points.points.iter())
        .filter(|p| !matches!(p.kind, Seeded::Region(_)))
        .flat_map(|p| p.round_trips.iter().flatten().copied())
}

/// [`run_summary`] from the counts of a run ([`RunCounts`]: what a streamed run keeps).
pub fn run_summary_of(
    input: &InputInfo,
    recording: &Recording,
    params: &RunParams,
    options: &SequenceOptions,
    c: &RunCounts,
    timings: &[(&str, f64)],
) -> Value {
    let used: Map<String, Value> = params
        .used(options, recording)
        .iter()
        .map(|(k, v)| (k.to_string(), option_json(v)))
        .collect();
    let mut stages: Map<String, Value> = timings
        .iter()
        .map(|(k, v)| (k.to_string(), json!(v)))
        .collect();
    stages.insert("objects".into(), json!(c.timings.objects.as_secs_f64()));
    stages.insert("matching".into(), json!(c.timings.matching.as_secs_f64()));
    stages.insert("tracks".into(), json!(c.timings.tracks.as_secs_f64()));
    // Object ids are their indices.
    json!({
        "pedomatch_version": env!("CARGO_PKG_VERSION"),
        "input": {
            "file": input.name,
            "sha256": input.sha256,
            "format": recording.format.map(|f| f.name()),
            "layout": input.layout.as_ref().map(|l| json!({"file": l.name, "sha256": l.sha256})),
        },
        "recording": {
            "frames": recording.n_frames(),
            "rows": recording.rows(),
            "cols": recording.cols(),
            "pitch_mm": recording.pitch_mm,
            "frame_rate_hz": recording.frame_rate(),
            "pressure_units": recording.known_units(),
            "negative_values": negative_values(recording),
        },
        "options": used,
        "objects": c.objects,
        "pairs": c.pairs,
        "tracks": c.tracks,
        "tracks_3_or_more": c.tracks_3_or_more,
        "splits": c.splits.iter().map(|(i, js)| json!({
            "id": i, "into": js,
        })).collect::<Vec<_>>(),
        "merges": c.merges.iter().map(|(is, j)| json!({
            "ids": is, "into": j,
        })).collect::<Vec<_>>(),
        "skipped": {
            "frames": c.skipped_frames.iter().map(|s| json!({
                "frame": s.frame, "reason": s.reason,
            })).collect::<Vec<_>>(),
            "pairs": c.skipped_pairs.iter().map(|s| json!({
                "id_a": s.objects.id_a, "id_b": s.objects.id_b,
                "frame_a": s.objects.frame_a, "frame_b": s.objects.frame_b,
                "reason": s.reason,
            })).collect::<Vec<_>>(),
        },
        "mean_local_percent": c.mean_local_percent(),
        "mean_optimisation_percent": c.mean_optimisation_percent(),
        "mean_cost": c.mean_cost(),
        "mean_trackable_percent": c.mean_trackable_percent(),
        "mean_round_trip_sensels": c.mean_round_trip(),
        "mean_field_residual_sensels": c.mean_field_residual(),
        (RoundTripSummary::Tracks.key()): RoundTripSummary::Tracks.json(c.track_round_trips()),
        // Set where the points are followed (`set_point_round_trips`).
        (RoundTripSummary::Points.key()): Value::Null,
        "timings_s": stages,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_read_back_as_written_under_their_own_keys() {
        let trips = RoundTrips::of([0.25, 0.5, f32::NAN, 2.0]).expect("three finite trips");
        let mut summary = json!({});
        for kind in RoundTripSummary::ALL {
            summary[kind.key()] = kind.json(Some(trips));
        }
        assert_eq!(summary["track_round_trip_sensels"]["tracks"], 3);
        assert_eq!(summary["point_round_trip_sensels"]["steps"], 3);
        for kind in RoundTripSummary::ALL {
            assert_eq!(kind.of_summary(&summary), Some(trips), "{kind:?}");
        }
        // `null`, an absent key or a summary without the count: none.
        set_point_round_trips(&mut summary, []);
        assert_eq!(RoundTripSummary::Points.of_summary(&summary), None);
        assert_eq!(RoundTripSummary::Tracks.of_summary(&json!({})), None);
        let old = json!({ "track_round_trip_sensels": { "median": 0.5, "p95": 1.0 } });
        assert_eq!(RoundTripSummary::Tracks.of_summary(&old), None);
    }
}
