//! Self-contained interactive HTML reports: of a whole-recording run ([`run_report`]) and of
//! one matched pair ([`match_report`]).
//!
//! The page embeds plotly.js (from the `plotly` crate's `plotly_embed_js` resources) and the
//! run's data as JSON, so it opens offline from the output folder and makes no network request
//! (a Content-Security-Policy forbids any). It holds a header (input, format, units, options,
//! timings, skipped frames and pairs), a player (pressure image, contours, matches into the next
//! frame coloured by cost, excess matches, unmatched nodes, short track trails) driven by a frame
//! slider and a play button, time series along the recording and the centre-of-pressure path.
//! The player opens on the first frame holding objects within the frames analysed
//! ([`ReportInfo::frames`]), which the header states.
//! For isocontours the player draws each level of the frame, labelled with its pressure. The
//! match page shows both objects, the matches by cost class, excess matches and unmatched nodes,
//! and a 3-D view for 3-D points.
//!
//! Size is bounded whatever the recording's length: the player shows at most
//! [`MAX_PLAYER_FRAMES`] frames, evenly spaced, and at most [`MAX_PLAYER_VALUES`] pressure values
//! (`frames × rows × cols`), keeping every `s`-th frame beyond (the report says so and names each
//! frame by its own number); the time series keep every frame.

use pedo_io::counted;
use pedo_io::{IoError, Recording, Result};
use pedo_track::{PairMatch, RunCounts, SequenceObject, SequenceResult, SequenceSink};
use serde_json::{json, Value};

/// Most pressure values the player embeds (frames × rows × cols); beyond it frames are
/// decimated. At most 5 bytes each: 12.5 MB, plus plotly.js (4.6 MB) and the overlays, under 25 MB.
pub const MAX_PLAYER_VALUES: usize = 2_500_000;

/// Most frames the player embeds, each with its pressure image and overlays (contours, matches,
/// trails: about 10 kB a frame of a walk); beyond it frames are decimated, so that the report of a
/// long recording stays a few megabytes.
pub const MAX_PLAYER_FRAMES: usize = 240;

/// Frames of history drawn as a trail behind each track's node.
const TRAIL_FRAMES: usize = 4;

/// Number of cost classes the matches are coloured by (quantiles of all costs).
const COST_CLASSES: usize = 5;

/// A report that cannot be built: an [`IoError::Output`] on `report.html`.
fn report_error(msg: impl std::fmt::Display) -> IoError {
    IoError::Output {
        path: "report.html".into(),
        msg: msg.to_string(),
    }
}

/// What the report's header states about the run (besides what the recording itself holds:
/// its pitch, frame rate and pressure units).
#[derive(Debug, Clone, Default)]
pub struct ReportInfo {
    /// The input's name as the user gave it.
    pub input: String,
    /// The detected file format (e.g. "asf"), if known.
    pub format: Option<String>,
    /// The pedomatch version.
    pub version: String,
    /// Every option used, as (name, value) text.
    pub options: Vec<(String, String)>,
    /// Time spent per stage, (stage, seconds).
    pub timings: Vec<(String, f64)>,
    /// Sensors above this value count as contact in the time series (the run's noise level).
    pub contact_threshold: f64,
    /// The frames analysed, `start..end` (0-based, `end` excluded; `None`: every frame). The
    /// player still plays the whole recording but opens within this range, and the header and
    /// the time series show it.
    pub frames: Option<(usize, usize)>,
    /// The measures section's data ([`ReportMeasures::to_json`]); `Null`: no such section.
    pub measures: Value,
    /// The material points' round trips (`summary.json`'s `point_round_trip_sensels`), when the
    /// run followed points.
    pub point_round_trips: Option<pedo_track::consistency::RoundTrips>,
}

/// What the report's measures section draws: the peak-pressure image with the regions'
/// outlines (a rule's or the user's masks), the user's regions and the tracks of the user's
/// points over it, the pressure-time-integral image, and the force of every stance over 0–100 %
/// of contact with the mean of the complete stances. Images go as integers of a fixed quantum
/// (three significant digits at their largest value), outlines as the edges between sensels of
/// different labels: the section adds a few tens of kB to a report.
#[derive(Debug, Clone)]
pub struct ReportMeasures<'a> {
    /// The recording's measures.
    pub measures: &'a pedo_io::measures::Measures,
    /// The regions measured and what made them (a rule's name or `"masks"`).
    pub regions: Option<(&'a str, &'a pedo_io::regions::RegionMasks)>,
    /// The user's regions followed through the stance (`--regions`), as drawn on their frame:
    /// name and cells (row-major).
    pub user_regions: Vec<(String, Vec<bool>)>,
    /// The user's points (`--points`): name and positions through the stance (x = column,
    /// y = row, sensels).
    pub points: Vec<(String, Vec<[f64; 2]>)>,
}

impl ReportMeasures<'_> {
    /// The section's data for a recording of sensels `pitch` mm (or sensels) apart.
    pub fn to_json(&self, pitch: [f64; 2]) -> Value {
        let m = self.measures;
        let u = &m.units;
        let encode = |image: &[f64], top: f64| -> (Vec<Option<i64>>, f64) {
            let quantum = if top > 0.0 {
                10f64.powf((top / 1000.0).log10().floor())
            } else {
                1.0
            };
            let values = image
                .iter()
                .map(|&v| v.is_finite().then(|| (v / quantum).round() as i64))
                .collect();
            (values, quantum)
        };
        let (peak, peak_q) = encode(&m.peak, m.values.peak_pressure);
        let (pti, pti_q) = encode(&m.pti, m.values.pti_max);
        let outline =
            |label_of: &dyn Fn(usize) -> u32| label_outlines(label_of, m.rows, m.cols, pitch);
        let regions = self.regions.map(|(rule, masks)| {
            let lines = outline(&|i| u32::from(masks.labels[i]));
            let centres: Vec<Value> = (1..=masks.names.len())
                .filter_map(|k| {
                    let cells: Vec<usize> = (0..masks.labels.len())
                        .filter(|&i| usize::from(masks.labels[i]) == k)
                        .collect();
                    let n = cells.len() as f64;
                    (n > 0.0).then(|| {
                        let cx = cells.iter().map(|&i| (i % m.cols) as f64).sum::<f64>() / n;
                        let cy = cells.iter().map(|&i| (i / m.cols) as f64).sum::<f64>() / n;
                        let name = match masks.side_of(k as u8) {
                            Some(side) => format!("{} {}", side.name(), masks.names[k - 1]),
                            None => masks.names[k - 1].clone(),
                        };
                        json!({"name": name,
                               "x": round3(cx * pitch[0]), "y": round3(cy * pitch[1])})
                    })
                })
                .collect();
            json!({"rule": rule, "outlines": lines, "names": centres})
        });
        let user_regions: Vec<Value> = (self.user_regions.iter())
            .map(|(name, cells)| {
                let lines = outline(&|i| u32::from(cells.get(i).copied().unwrap_or(false)));
                json!({"name": name, "outline": lines})
            })
            .collect();
        let points: Vec<Value> = (self.points.iter())
            .map(|(name, xy)| {
                let x: Vec<f64> = xy.iter().map(|p| round3(p[0] * pitch[0])).collect();
                let y: Vec<f64> = xy.iter().map(|p| round3(p[1] * pitch[1])).collect();
                json!({"name": name, "x": x, "y": y})
            })
            .collect();
        // Both feet apart: each foot's own stances, as curves.csv has them.
        let stances = m.curve_stances();
        let curves: Vec<Vec<f64>> = (stances.iter())
            .map(|s| s.curves.force.iter().map(|&v| round3(v)).collect())
            .collect();
        let complete: Vec<bool> = stances.iter().map(|s| s.stance.complete).collect();
        let chosen: Vec<&[f64]> = (curves.iter().zip(&complete))
            .filter(|(_, c)| **c || !complete.contains(&true))
            .map(|(v, _)| v.as_slice())
            .collect();
        let (mean, sd) = crate::figure::mean_and_sd(&chosen);
        let load = if u.is_force { "force" } else { "load" };
        json!({
            "peak": peak, "peak_quantum": peak_q, "peak_units": u.pressure,
            "pti": pti, "pti_quantum": pti_q, "pti_units": format!("{}·{}", u.pressure, u.time),
            "regions": regions, "user_regions": user_regions, "points": points,
            "stances": {
                "label": format!("{load} ({})", u.force),
                "curves": curves, "complete": complete,
                "mean": mean.iter().map(|&v| round3(v)).collect::<Vec<_>>(),
                "sd": sd.iter().map(|&v| round3(v)).collect::<Vec<_>>(),
                "averaged": chosen.len(),
            },
        })
    }
}

/// The edges between sensels of different labels (`label_of(i)`, 0 = none) around every labelled
/// sensel, as one line piece each (corners at the sensel centres ± half a pitch, in mm or
/// sensels).
fn label_outlines(
    label_of: &dyn Fn(usize) -> u32,
    rows: usize,
    cols: usize,
    pitch: [f64; 2],
) -> Lines {
    let mut lines = Lines::default();
    let at = |c: f64, r: f64| [round3(c * pitch[0]), round3(r * pitch[1])];
    for i in 0..rows * cols {
        let l = label_of(i);
        if l == 0 {
            continue;
        }
        let (r, c) = (i / cols, i % cols);
        let (x, y) = (c as f64, r as f64);
        let differs = |rr: Option<usize>, cc: Option<usize>| match (rr, cc) {
            (Some(rr), Some(cc)) if rr < rows && cc < cols => label_of(rr * cols + cc) != l,
            _ => true,
        };
        if differs(r.checked_sub(1), Some(c)) {
            lines.piece([at(x - 0.5, y - 0.5), at(x + 0.5, y - 0.5)]);
        }
        if differs(Some(r + 1), Some(c)) {
            lines.piece([at(x - 0.5, y + 0.5), at(x + 0.5, y + 0.5)]);
        }
        if differs(Some(r), c.checked_sub(1)) {
            lines.piece([at(x - 0.5, y - 0.5), at(x - 0.5, y + 0.5)]);
        }
        if differs(Some(r), Some(c + 1)) {
            lines.piece([at(x + 0.5, y - 0.5), at(x + 0.5, y + 0.5)]);
        }
    }
    lines
}

impl ReportInfo {
    /// The header of a report on `input` whose summary (`summary.json` of a run, `match.json` of
    /// a pair) is `summary`: every option it records, as text, and its time per stage; this
    /// version. The rest at its default.
    pub fn of_summary(input: String, summary: &Value) -> Self {
        let entries = |key: &str| summary[key].as_object().into_iter().flatten();
        Self {
            input,
            version: env!("CARGO_PKG_VERSION").to_string(),
            options: entries("options")
                .map(|(k, v)| (k.clone(), option_text(v)))
                .collect(),
            timings: entries("timings_s")
                .map(|(k, v)| (k.clone(), v.as_f64().unwrap_or(0.0)))
                .collect(),
            point_round_trips: crate::RoundTripSummary::Points.of_summary(summary),
            ..Default::default()
        }
    }
}

/// An option's value as a report's header shows it (`none` for an unset one).
fn option_text(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The report of one run as a complete HTML page: the run's events gathered
/// ([`ReportGather`]) and the page made of them.
pub fn run_report(
    recording: &Recording,
    result: &SequenceResult,
    info: &ReportInfo,
) -> Result<String> {
    if recording.n_frames() == 0 {
        return Err(report_error("the recording has no frames"));
    }
    let mut gather = ReportGather::new(recording, info.frames);
    pedo_track::replay_result(result, &mut gather)?;
    gather.page(recording, &RunCounts::of(result), info)
}

/// A template filled in: title, header, the shared head, plotly.js and the data, in one pass (a
/// file name holding `{{DATA}}` stays text).
pub(crate) fn page(template: &str, title: &str, header: &str, data: &str) -> String {
    let values = [
        ("{{TITLE}}", html_escape(title)),
        ("{{HEADER}}", header.to_string()),
        ("{{HEAD}}", HEAD.to_string()),
        ("{{PLOTLY}}", plotly_js()),
        ("{{DATA}}", script_safe(data)),
    ];
    let mut out = String::with_capacity(template.len() + PLOTLY_JS.len() + data.len());
    let mut rest = template;
    while let Some(at) = rest.find("{{") {
        out.push_str(&rest[..at]);
        rest = &rest[at..];
        match values.iter().find(|(key, _)| rest.starts_with(key)) {
            Some((key, value)) => {
                out.push_str(value);
                rest = &rest[key.len()..];
            }
            None => {
                out.push_str("{{");
                rest = &rest[2..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// JSON made safe inside an HTML `<script>` element: `<`, `>` and `&` (which JSON holds only
/// inside strings) as `\u` escapes, so that no file name or unit can end the element or open a
/// comment (`</script>`, `<!--`), and U+2028/U+2029, line ends to older JavaScript, too. The JSON
/// reads back the same.
fn script_safe(json: &str) -> String {
    let mut out = String::with_capacity(json.len());
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// One matched pair of objects, for [`match_report`].
#[derive(Debug, Clone, Copy)]
pub struct MatchPairInput<'a> {
    /// Object A, in its coordinate units.
    pub a: &'a modal_core::Shape,
    /// Object B, in the same units as A.
    pub b: &'a modal_core::Shape,
    /// The match of A with B.
    pub result: &'a modal_core::MatchResult,
    /// Millimetres per coordinate unit along x and y; `None`: the axes are in `data_unit`.
    pub pitch_mm: Option<[f64; 2]>,
    /// The coordinates' own unit when the pitch is unknown (`"sensels"`, `"file units"`, ...).
    pub data_unit: &'a str,
    /// How the objects are named in the legend (e.g. their file names and frames).
    pub label_a: &'a str,
    /// B's name in the legend.
    pub label_b: &'a str,
    /// The pressure frames A and B were taken from (`None` for a point file), drawn under the
    /// objects of a 2-D pair; their sensels must be the objects' coordinate units.
    pub underlays: [Option<FrameUnderlay<'a>>; 2],
}

/// A frame of a recording, drawn as a pressure image under the objects taken from it.
#[derive(Debug, Clone, Copy)]
pub struct FrameUnderlay<'a> {
    /// The recording the frame belongs to.
    pub recording: &'a Recording,
    /// 0-based frame index.
    pub frame: usize,
}

impl FrameUnderlay<'_> {
    /// The frame as JSON: `rows`, `cols`, `units` and the pressure as integers of `quantum`
    /// (three significant digits at the frame's peak), row after row, `null` where there is no
    /// sensor; `None` when the frame does not exist.
    fn to_json(self) -> Option<Value> {
        let r = self.recording;
        let values = r.frame_slice(self.frame)?;
        let (kpa, units) = pressure_scale(r);
        let peak = values
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, &v| m.max(v as f64))
            * kpa;
        let quantum = if peak > 0.0 {
            10f64.powf((peak / 1000.0).log10().floor())
        } else {
            1.0
        };
        let z: Vec<Option<i64>> = values
            .iter()
            .zip(r.sensor_mask())
            .map(|(&v, &m)| (m && v.is_finite()).then(|| (v as f64 * kpa / quantum).round() as i64))
            .collect();
        Some(json!({
            "rows": r.rows(), "cols": r.cols(), "units": units, "quantum": quantum,
            "peak": peak, "frame": self.frame, "z": z,
        }))
    }
}

/// The report of one match (`pedomatch match`) as a complete HTML page: a header with `facts`
/// (inputs, result, ... as (name, value) rows), the options and timings of `info`, then both
/// objects in physical units with their matches coloured by cost, excess matches and unmatched
/// nodes, and a rotatable 3-D view for 3-D objects.
pub fn match_report(
    pair: &MatchPairInput,
    info: &ReportInfo,
    facts: &[(String, String)],
) -> Result<String> {
    let data = serde_json::to_string(&match_data(pair))
        .map_err(|e| report_error(format!("cannot encode the report data: {e}")))?;
    let mut rows = facts.to_vec();
    rows.push(("version".into(), format!("pedomatch {}", info.version)));
    if !info.timings.is_empty() {
        rows.push(("timings".into(), timings_text(&info.timings)));
    }
    let header = facts_html(&rows) + &options_html(&info.options);
    Ok(page(MATCH_TEMPLATE, &info.input, &header, &data))
}

/// What the match page draws, as JSON.
fn match_data(pair: &MatchPairInput) -> Value {
    let ([dx, dy], xy_units) = match pair.pitch_mm {
        Some(p) if p.iter().all(|v| v.is_finite() && *v > 0.0) => (p, "mm"),
        _ => ([1.0, 1.0], pair.data_unit),
    };
    let point = |s: &modal_core::Shape, i: usize| -> [f64; 3] {
        let p = s.point(i);
        let z = if s.dim() == 3 { p[2] } else { 0.0 };
        [round6(p[0] * dx), round6(p[1] * dy), round6(z)]
    };
    let object = |s: &modal_core::Shape| {
        let closed = matches!(s.topology(), modal_core::Topology::ClosedContour);
        let mut pts: Vec<[f64; 3]> = (0..s.len()).map(|i| point(s, i)).collect();
        if closed {
            pts.extend(pts.first().copied());
        }
        json!({
            "closed": closed,
            "x": pts.iter().map(|p| p[0]).collect::<Vec<_>>(),
            "y": pts.iter().map(|p| p[1]).collect::<Vec<_>>(),
            "z": pts.iter().map(|p| p[2]).collect::<Vec<_>>(),
        })
    };
    let r = pair.result;
    let classes = cost_classes(r.pairs.iter().map(|m| m.cost).collect());
    let mut by_cost: Vec<Segments> = (0..classes.count()).map(|_| Segments::default()).collect();
    let mut excess = Segments::default();
    for m in &r.pairs {
        let seg = [point(pair.a, m.a), point(pair.b, m.b)];
        if m.excess {
            excess.push(seg);
        } else {
            by_cost[classes.class(m.cost)].push(seg);
        }
    }
    let nodes = |s: &modal_core::Shape, which: &[usize]| {
        let mut l = Lines::default();
        for &i in which {
            let p = point(s, i);
            l.piece([[p[0], p[1]]]);
        }
        l
    };
    json!({
        "dim": pair.a.dim(), "xy_units": xy_units,
        "label_a": pair.label_a, "label_b": pair.label_b,
        "a": object(pair.a), "b": object(pair.b),
        "cost_bounds": classes.bounds, "cost_labels": classes.labels,
        "matches": by_cost.iter().map(|s| &s.xy).collect::<Vec<_>>(),
        "matches3d": by_cost.iter().map(|s| &s.xyz).collect::<Vec<_>>(),
        "excess": excess.xy, "excess3d": excess.xyz,
        "unmatched_a": nodes(pair.a, &r.unmatched_a),
        "unmatched_b": nodes(pair.b, &r.unmatched_b),
        "pitch": [dx, dy],
        // Pressure images only under 2-D objects (a 3-D object's x-y plane is not a frame's).
        "images": pair.underlays.map(|u| u.filter(|_| pair.a.dim() == 2).and_then(|u| u.to_json())),
    })
}

/// Segments for plotly: in the x-y plane and in 3-D, `null` between segments.
struct Segments {
    xy: Lines,
    xyz: Value,
}

impl Default for Segments {
    fn default() -> Self {
        Self {
            xy: Lines::default(),
            xyz: json!({ "x": [], "y": [], "z": [] }),
        }
    }
}

impl Segments {
    fn push(&mut self, [p, q]: [[f64; 3]; 2]) {
        self.xy.piece([[p[0], p[1]], [q[0], q[1]]]);
        for (axis, k) in ["x", "y", "z"].into_iter().zip(0..) {
            let v = self.xyz[axis].as_array_mut().expect("built above");
            if !v.is_empty() {
                v.push(Value::Null);
            }
            v.extend([json!(p[k]), json!(q[k])]);
        }
    }
}

/// The cost classes matches are coloured by: the bounds between them (a cost `c` is in class
/// `k`, the number of bounds below `c`) and each class's legend name.
#[derive(Debug, Clone, PartialEq)]
struct CostClasses {
    bounds: Vec<f64>,
    labels: Vec<String>,
}

impl CostClasses {
    fn class(&self, c: f64) -> usize {
        self.bounds.iter().take_while(|&&b| c > b).count()
    }

    fn count(&self) -> usize {
        self.labels.len()
    }
}

/// Costs closer than this, relative to the largest (1 at least), are the same cost: bounds
/// this close are one bound, and a bound this close to 0 is 0.
const COST_TOLERANCE: f64 = 1e-9;

/// Up to [`COST_CLASSES`] classes of the finite costs, bounded by their quantiles. Bounds that
/// coincide (closer than [`COST_TOLERANCE`]) are one bound, and a bound with no cost
/// meaningfully above it is dropped: near-identical costs make one class (`all costs ≈ 0` when
/// they are all about 0). Each bound is written with the fewest significant digits (2 at least)
/// that tell the bounds apart.
fn cost_classes(mut costs: Vec<f64>) -> CostClasses {
    costs.retain(|c| c.is_finite());
    costs.sort_by(f64::total_cmp);
    let (Some(&lo), Some(&hi)) = (costs.first(), costs.last()) else {
        return CostClasses {
            bounds: vec![],
            labels: vec!["matches".into()],
        };
    };
    let tol = COST_TOLERANCE * lo.abs().max(hi.abs()).max(1.0);
    let snap = |v: f64| if v.abs() < tol { 0.0 } else { v };
    let mut bounds: Vec<f64> = Vec::new();
    for i in 1..COST_CLASSES {
        let b = costs[i * costs.len() / COST_CLASSES];
        if hi - b >= tol && bounds.last().is_none_or(|&last| b - last >= tol) {
            bounds.push(b);
        }
    }
    if bounds.is_empty() {
        let median = snap(costs[costs.len() / 2]);
        let label = if median == 0.0 {
            "all costs ≈ 0".to_string()
        } else {
            format!("all costs ≈ {}", significant(median, 3))
        };
        return CostClasses {
            bounds,
            labels: vec![label],
        };
    }
    let digits = (2..=17)
        .find(|&d| {
            let t: Vec<String> = bounds.iter().map(|&b| significant(snap(b), d)).collect();
            t.windows(2).all(|w| w[0] != w[1])
        })
        .unwrap_or(17);
    let text: Vec<String> = bounds
        .iter()
        .map(|&b| significant(snap(b), digits))
        .collect();
    let mut labels = vec![format!("cost ≤ {}", text[0])];
    labels.extend(
        text.windows(2)
            .map(|w| format!("{} < cost ≤ {}", w[0], w[1])),
    );
    labels.push(format!("cost > {}", text[text.len() - 1]));
    CostClasses { bounds, labels }
}

/// `v` rounded to `digits` significant digits, as plain decimals from 1e-4 to 1e6 and in
/// scientific notation (`1.5e-16`) beyond; never `-0`.
fn significant(v: f64, digits: usize) -> String {
    let r: f64 = format!("{:.*e}", digits.saturating_sub(1), v)
        .parse()
        .unwrap_or(v);
    if r == 0.0 || !r.is_finite() {
        return if r.is_finite() {
            "0".into()
        } else {
            r.to_string()
        };
    }
    let exponent = r.abs().log10().floor();
    if (-4.0..6.0).contains(&exponent) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

/// plotly.js v3.0.1, MIT licence (`assets/LICENSE-plotly.js.txt`), vendored as a file: the
/// `plotly` crate that ships it needs a template engine and a dozen proc-macro crates at build
/// time, for a string.
const PLOTLY_JS: &str = include_str!("../assets/plotly.min.js");

/// The script element every report embeds, so that it opens offline.
fn plotly_js() -> String {
    format!("<script type=\"text/javascript\">{PLOTLY_JS}</script>")
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Physical pressure units: kPa when the recording's units convert, else its own units;
/// `None` when the recording states none.
fn pressure_scale(recording: &Recording) -> (f64, Option<String>) {
    match pedo_io::recording::kpa_per_unit(&recording.units) {
        Some(k) => (k, Some("kPa".to_string())),
        None => (1.0, file_units(recording)),
    }
}

/// The units the recording's values are in, as the file names them (a known unit in its usual
/// spelling, [`pedo_io::recording::stated_units`]); `None` when it names none.
fn file_units(recording: &Recording) -> Option<String> {
    Some(pedo_io::recording::stated_units(&recording.units)).filter(|u| !u.is_empty())
}

/// The header's pressure units, `shown` those of the report's pressures: a file's units that
/// convert are shown in kPa, as the tables give them, and the header says from what.
fn pressure_header(recording: &Recording, shown: Option<String>) -> String {
    match (shown, file_units(recording)) {
        (Some(shown), Some(file)) if shown != file => {
            format!("{shown} (the file's {file}, converted)")
        }
        (Some(shown), _) => shown,
        (None, _) => "units unknown".into(),
    }
}

/// What the time series' load panel plots, named as frames.csv names its column
/// (`total_force_n`, `total_load_mm2`, `total_load_sensels`): newtons when the pressure units
/// convert and the sensel area is known; else the plain sum of the values times the sensel area
/// (the file's units × mm²) or, without a pitch, the plain sum (the file's units × sensels).
pub(crate) fn load_label(recording: &Recording) -> String {
    if recording.force_factor().is_some() {
        return "total force (N)".into();
    }
    let units = file_units(recording).unwrap_or_else(|| "pressure units unknown".into());
    let per = if recording.sensel_area().is_some() {
        "mm²"
    } else {
        "sensels"
    };
    format!("total load ({units} × {per})")
}

/// `1st`, `2nd`, `3rd`, `4th`, ... `11th`, `12th`, `13th`, ... `21st`, `22nd`, ...
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// Round trips as the header states them: `noun` counts them, `what` says what each is.
fn round_trips_text(t: &pedo_track::consistency::RoundTrips, noun: &str, what: &str) -> String {
    format!(
        "round trip {:.3} sensels median, {:.3} at the 95th percentile, {:.1} % over 1 sensel \
         (of {}{what})",
        t.median,
        t.p95,
        t.over_1_percent,
        counted(t.count, noun)
    )
}

fn header_html(recording: &Recording, counts: &RunCounts, info: &ReportInfo) -> String {
    let (_, punits) = pressure_scale(recording);
    let n = recording.n_frames();
    let frames = match info.frames {
        Some((start, end)) if end == start + 1 && n > 1 => format!("{start} of {n} analysed"),
        Some((start, end)) if (start, end) != (0, n) => {
            format!("{}–{} of {n} analysed", start, end.saturating_sub(1))
        }
        _ if n == 1 => "the only one analysed".into(),
        _ => format!("all {n} analysed"),
    };
    let mut rows: Vec<(String, String)> = vec![
        ("input".into(), info.input.clone()),
        (
            "format".into(),
            info.format.clone().unwrap_or_else(|| "unknown".into()),
        ),
        (
            "frames".into(),
            format!(
                "{frames}, {} × {} sensels",
                recording.rows(),
                recording.cols()
            ),
        ),
        (
            "pitch".into(),
            recording
                .pitch_mm
                .map(|p| format!("{} × {} mm", p[0], p[1]))
                .unwrap_or_else(|| "unknown (axes in sensels)".into()),
        ),
        (
            "frame rate".into(),
            recording
                .frame_rate()
                .map(|f| format!("{f} Hz"))
                .unwrap_or_else(|| "unknown (time in frames)".into()),
        ),
        ("pressure".into(), pressure_header(recording, punits)),
        ("version".into(), format!("pedomatch {}", info.version)),
        (
            "result".into(),
            format!(
                "{}, {}, {}",
                counted(counts.objects, "object"),
                counted(counts.pairs, "matched pair"),
                counted(counts.tracks, "track")
            ),
        ),
    ];
    if let (Some(trip), Some(residual)) = (counts.mean_round_trip(), counts.mean_field_residual()) {
        // How far the matches can be trusted, in place of the share of nodes matched (near
        // 100 % by construction).
        rows.push((
            "consistency".into(),
            format!(
                "round trip {trip:.3} sensels, field residual {residual:.3} sensels \
                 (means over {} of the pairs' medians)",
                counted(counts.consistent_pairs, "pair")
            ),
        ));
    }
    // Where the run's round trips stand (each the largest of a track's steps; each a step of a
    // material point), in place of the share of nodes matched.
    let tracks = counts
        .track_round_trips()
        .map(|t| (t, "track", ": the largest of each track's steps"));
    let points = (info.point_round_trips).map(|t| (t, "step", " of the material points"));
    for (name, trips) in [("track consistency", tracks), ("point consistency", points)] {
        if let Some((t, noun, what)) = trips {
            rows.push((name.into(), round_trips_text(&t, noun, what)));
        }
    }
    if !info.timings.is_empty() {
        rows.push(("timings".into(), timings_text(&info.timings)));
    }
    let mut out = facts_html(&rows) + &options_html(&info.options);
    let skipped: Vec<String> = counts
        .skipped_frames
        .iter()
        .map(|s| format!("frame {}: {}", s.frame, s.reason))
        .chain(counts.skipped_pairs.iter().map(|s| {
            let o = &s.objects;
            format!(
                "pair {}→{} (frames {}→{}): {}",
                o.id_a, o.id_b, o.frame_a, o.frame_b, s.reason
            )
        }))
        .map(|s| format!("<li>{}</li>", html_escape(&s)))
        .collect();
    if !skipped.is_empty() {
        out += &format!(
            "<details open class=\"skipped\"><summary>skipped ({})</summary><ul>{}</ul></details>",
            skipped.len(),
            skipped.join("")
        );
    }
    out
}

/// `"read 0.012 s, matching 0.300 s"`.
fn timings_text(timings: &[(String, f64)]) -> String {
    let t: Vec<String> = timings
        .iter()
        .map(|(s, v)| format!("{s} {v:.3} s"))
        .collect();
    t.join(", ")
}

/// (name, value) rows as an HTML table, escaped.
fn table_rows(rows: &[(String, String)]) -> String {
    rows.iter()
        .map(|(k, v)| {
            format!(
                "<tr><th>{}</th><td>{}</td></tr>",
                html_escape(k),
                html_escape(v)
            )
        })
        .collect()
}

pub(crate) fn facts_html(rows: &[(String, String)]) -> String {
    format!("<table class=\"facts\">{}</table>", table_rows(rows))
}

/// Every option used, folded away under a summary line.
fn options_html(options: &[(String, String)]) -> String {
    if options.is_empty() {
        return String::new();
    }
    format!(
        "<details><summary>options used ({})</summary><table class=\"facts\">{}</table></details>",
        options.len(),
        table_rows(options)
    )
}

/// The frame stride of the player of a recording of `n` frames of `sensels` values each: 1, or
/// the smallest that keeps it within [`MAX_PLAYER_FRAMES`] frames and [`MAX_PLAYER_VALUES`]
/// values.
pub fn player_step(n: usize, sensels: usize) -> usize {
    let by_values = (n * sensels).div_ceil(MAX_PLAYER_VALUES);
    let by_frames = n.div_ceil(MAX_PLAYER_FRAMES);
    by_values.max(by_frames).max(1)
}

/// What the report draws of a run, gathered from its events ([`SequenceSink`]) as the engine or
/// [`pedo_track::replay`] hands them over, in memory bounded whatever the recording's length:
/// the overlays of the player's frames only (at most [`MAX_PLAYER_FRAMES`]: contours, matches
/// with their costs, excess matches, unmatched nodes, track trails, the surface pair), a few
/// numbers per pair for the time series, and a sample of the match costs for the cost classes
/// (every cost up to [`COST_SAMPLE`], evenly strided beyond). [`ReportGather::page`] makes the
/// page once the run is over.
pub struct ReportGather {
    /// The player's frame stride ([`player_step`]) and the recording's frame count.
    step: usize,
    n: usize,
    /// Millimetres (or sensels) per sensel along x and y, and the pressure scale to kPa.
    pitch: [f64; 2],
    kpa: f64,
    /// Per frame the player shows (frame `k × step`).
    frames: Vec<ShownFrame>,
    /// Per matched pair: its first frame, local and trackable percentages, mean cost and median
    /// round trip (sensels; none for surfaces).
    pair_frame: Vec<usize>,
    pair_local: Vec<f64>,
    pair_trackable: Vec<f64>,
    pair_cost: Vec<f64>,
    pair_round_trip: Vec<Option<f64>>,
    costs: CostSample,
    /// The analysed frames, `start..end`.
    analysed: (usize, usize),
    /// The first frame within the analysed frames that holds objects.
    first_analysed_object_frame: Option<usize>,
    first_object: Option<(usize, usize)>,
    isocontour: bool,
}

/// The overlays of one frame the player shows, as the events bring them.
#[derive(Default)]
struct ShownFrame {
    objects: bool,
    contours: Lines,
    levels: Vec<Value>,
    /// One-to-one matches into the next frame, with their costs: classed once every cost is in.
    segments: Vec<([f64; 2], [f64; 2], f64)>,
    excess: Lines,
    unmatched: Lines,
    trails: Lines,
    /// The first pair leaving the frame has been seen (its surfaces, for surface runs).
    paired: bool,
    surfaces: Option<Value>,
}

/// Match costs kept for the cost classes' quantiles: every cost up to this many, beyond it every
/// s-th cost (s doubling as the costs come), so that the classes of a long run cost a bounded
/// memory and are still its quantiles within a fraction of a class.
pub const COST_SAMPLE: usize = 1 << 17;

/// An evenly strided sample of the costs handed to it ([`COST_SAMPLE`]).
#[derive(Default)]
struct CostSample {
    kept: Vec<f64>,
    stride: usize,
    seen: usize,
}

impl CostSample {
    fn push(&mut self, c: f64) {
        let stride = self.stride.max(1);
        if self.seen.is_multiple_of(stride) {
            self.kept.push(c);
            if self.kept.len() >= COST_SAMPLE {
                // Keep every other cost: the sample is then every (2 × stride)-th.
                let halved: Vec<f64> = self.kept.iter().step_by(2).copied().collect();
                self.kept = halved;
                self.stride = 2 * stride;
            }
        }
        self.seen += 1;
    }
}

impl ReportGather {
    /// An empty gathering for the report of a run of `recording` whose analysed frames are
    /// `frames` (`start..end`; `None`: every frame), as [`ReportInfo::frames`].
    pub fn new(recording: &Recording, frames: Option<(usize, usize)>) -> Self {
        let n = recording.n_frames();
        let step = player_step(n, recording.rows() * recording.cols());
        let (kpa, _) = pressure_scale(recording);
        let pitch = recording.pitch_mm.unwrap_or([1.0, 1.0]);
        let analysed = frames
            .map(|(s, e)| {
                let last = n.saturating_sub(1);
                (s.min(last), e.clamp(s.min(last) + 1, n.max(1)))
            })
            .unwrap_or((0, n));
        Self {
            step,
            n,
            pitch,
            kpa,
            frames: (0..n)
                .step_by(step)
                .map(|_| ShownFrame::default())
                .collect(),
            pair_frame: Vec::new(),
            pair_local: Vec::new(),
            pair_trackable: Vec::new(),
            pair_round_trip: Vec::new(),
            pair_cost: Vec::new(),
            costs: CostSample::default(),
            analysed,
            first_analysed_object_frame: None,
            first_object: None,
            isocontour: false,
        }
    }

    /// The frames the player shows.
    fn shown(&self) -> Vec<usize> {
        (0..self.n).step_by(self.step).collect()
    }

    /// The overlays of frame `f`, when the player shows it.
    fn shown_frame(&mut self, f: usize) -> Option<&mut ShownFrame> {
        if !f.is_multiple_of(self.step) {
            return None;
        }
        self.frames.get_mut(f / self.step)
    }

    fn mm(&self, p: &[f64]) -> [f64; 2] {
        [round3(p[0] * self.pitch[0]), round3(p[1] * self.pitch[1])]
    }

    /// The report as a complete HTML page, once the run's events are in: `counts` gives its
    /// header's counts and skipped frames and pairs.
    pub fn page(
        &self,
        recording: &Recording,
        counts: &RunCounts,
        info: &ReportInfo,
    ) -> Result<String> {
        if recording.n_frames() == 0 {
            return Err(report_error("the recording has no frames"));
        }
        let data = self.data(recording, info);
        let data = serde_json::to_string(&data)
            .map_err(|e| report_error(format!("cannot encode the report data: {e}")))?;
        Ok(page(
            TEMPLATE,
            &info.input,
            &header_html(recording, counts, info),
            &data,
        ))
    }

    /// The frame the player opens on: the first frame it shows that holds objects within the
    /// analysed frames (an isocontour run has one frame of objects: the shown frame nearest it
    /// when the player is decimated), else the first shown frame of the analysed ones.
    fn open_frame(&self, shown: &[usize]) -> usize {
        let (start, end) = self.analysed;
        let analysed = |f: &usize| (start..end).contains(f);
        let nearest = |target: usize| {
            shown
                .iter()
                .copied()
                .min_by_key(|&f| (f.abs_diff(target), f < target))
        };
        shown
            .iter()
            .zip(&self.frames)
            .find(|(f, s)| s.objects && analysed(f))
            .map(|(&f, _)| f)
            .or_else(|| self.first_analysed_object_frame.and_then(nearest))
            .or_else(|| shown.iter().copied().find(analysed))
            .or_else(|| nearest(start))
            .unwrap_or(0)
    }

    /// Everything the page's script draws, as JSON.
    fn data(&self, recording: &Recording, info: &ReportInfo) -> Value {
        let (n, rows, cols) = (recording.n_frames(), recording.rows(), recording.cols());
        let step = self.step;
        let shown = self.shown();
        let (kpa, punits) = pressure_scale(recording);
        let xy_units = if recording.pitch_mm.is_some() {
            "mm"
        } else {
            "sensels"
        };
        let pitch = self.pitch;
        let rate = recording.frame_rate();

        // Pressure as integers of a fixed quantum: compact JSON and 3 significant digits at the
        // peak. The largest value of any frame (0 at least), frame by frame: a long recording is
        // held sparsely and never built whole.
        let peak_grid = recording.peak_image();
        let peak = peak_grid.max().max(0.0) * kpa;
        let quantum = if peak > 0.0 {
            10f64.powf((peak / 1000.0).log10().floor())
        } else {
            1.0
        };
        let mask = recording.sensor_mask();
        let encode = |values: &[f32]| -> Vec<Option<i64>> {
            values
                .iter()
                .zip(mask)
                .map(|(&v, &m)| {
                    (m && v.is_finite()).then(|| (v as f64 * kpa / quantum).round() as i64)
                })
                .collect()
        };
        let z: Vec<Vec<Option<i64>>> = shown
            .iter()
            .map(|&t| encode(&recording.frame_slice(t).unwrap_or_default()))
            .collect();
        let peak_image: Vec<Option<i64>> = {
            let v: Vec<f32> = peak_grid.data().iter().map(|&v| v as f32).collect();
            encode(&v)
        };

        let mm = |p: &[f64]| -> [f64; 2] { [round3(p[0] * pitch[0]), round3(p[1] * pitch[1])] };
        let classes = cost_classes(self.costs.kept.clone());
        let frames: Vec<Value> = self
            .frames
            .iter()
            .map(|s| {
                let mut by_cost: Vec<Lines> =
                    (0..classes.count()).map(|_| Lines::default()).collect();
                for &(a, b, cost) in &s.segments {
                    by_cost[classes.class(cost)].piece([a, b]);
                }
                json!({
                    "contours": s.contours, "levels": s.levels, "matches": by_cost,
                    "excess": s.excess, "unmatched": s.unmatched, "trails": s.trails,
                    "surfaces": s.surfaces,
                })
            })
            .collect();
        // The frames' values are moved in, not copied (`json!` copies a `Value` it is given).
        let mut overlays = json!({ "cost_bounds": classes.bounds, "cost_labels": classes.labels });
        overlays["frames"] = Value::Array(frames);

        let measures = recording.measures(info.contact_threshold);
        let area_known = recording.sensel_area().is_some();
        let cop: Vec<Option<[f64; 2]>> = measures.iter().map(|m| m.cop.map(|c| mm(&c))).collect();
        let series = json!({
            "frame": (0..n).collect::<Vec<_>>(),
            "area": measures.iter().map(|m| round3(m.contact_area)).collect::<Vec<_>>(),
            "force": measures.iter().map(|m| round3(m.total_force)).collect::<Vec<_>>(),
            "peak": measures.iter().map(|m| round3(m.peak_pressure * kpa)).collect::<Vec<_>>(),
            "cop_path": cop_path(&cop),
            "cop": cop,
            "area_label": if area_known { "contact area (mm²)" } else { "contact area (sensels)" },
            "force_label": load_label(recording),
            "peak_label": format!("peak pressure ({})", punits.as_deref().unwrap_or("units unknown")),
        });
        let pairs = json!({
            "frame": self.pair_frame,
            "local": self.pair_local,
            "trackable": self.pair_trackable,
            "cost": self.pair_cost,
            "round_trip": self.pair_round_trip,
        });
        let (start, end) = self.analysed;
        let decimation = (step > 1).then(|| {
            let why = if n > MAX_PLAYER_FRAMES {
                format!("the recording holds more than {MAX_PLAYER_FRAMES} frames")
            } else {
                format!(
                    "the recording holds more than {MAX_PLAYER_VALUES} pressure values (frames × rows × cols)"
                )
            };
            format!(
                "The player shows every {} frame ({} of {n}, each named by its own number): {why}. \
                 The time series and the tables keep every frame.",
                ordinal(step),
                shown.len()
            )
        });
        let mut data = json!({
            "n_frames": n, "rows": rows, "cols": cols, "step": step, "shown": shown,
            "analysed": [start, end], "decimation": decimation,
            "open_frame": self.open_frame(&shown),
            "frame_rate": rate, "dx": pitch[0], "dy": pitch[1], "xy_units": xy_units,
            "pressure_units": punits, "quantum": quantum, "z": z, "peak_image": peak_image,
            "max_player_values": MAX_PLAYER_VALUES,
            "surface": self.first_object.is_some_and(|(_, dim)| dim == 3),
            "isocontour": self.isocontour,
            "first_object_frame": self.first_object.map(|(f, _)| f),
            "measures": info.measures,
        });
        // Moved in, not copied: the overlays hold every shown frame's outlines and matches.
        data["overlays"] = overlays;
        data["series"] = series;
        data["pairs"] = pairs;
        data
    }
}

impl SequenceSink for ReportGather {
    fn frame_objects(&mut self, frame: usize, objects: &[SequenceObject]) -> Result<()> {
        if let Some(o) = objects.first() {
            self.first_object.get_or_insert((o.frame, o.shape.dim()));
        }
        for o in objects {
            self.isocontour |= o.level.is_some();
            let (start, end) = self.analysed;
            if (start..end).contains(&o.frame) && self.first_analysed_object_frame.is_none() {
                self.first_analysed_object_frame = Some(o.frame);
            }
        }
        let _ = frame;
        // Objects come in frame order, but an isocontour run's one frame holds every level.
        for o in objects {
            let pts: Vec<[f64; 2]> = (0..o.shape.len())
                .map(|i| self.mm(o.shape.point(i)))
                .collect();
            let level_scale = self.kpa;
            let Some(s) = self.shown_frame(o.frame) else {
                continue;
            };
            s.objects = true;
            let Some(&first) = pts.first() else { continue };
            if let Some(level) = o.level {
                let mut pts = pts;
                pts.push(first);
                let mut outline = Lines::default();
                outline.piece(pts);
                let level = round6(level * level_scale);
                s.levels
                    .push(json!({ "level": level, "x": outline.x, "y": outline.y }));
            } else if o.shape.dim() == 2 {
                let mut pts = pts;
                pts.push(first);
                s.contours.piece(pts);
            } else {
                // Surfaces: nodes only, as separate one-point pieces (markers).
                for p in pts {
                    s.contours.piece([p]);
                }
            }
        }
        Ok(())
    }

    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()> {
        self.pair_frame.push(pair.row.objects.frame_a);
        self.pair_local.push(round3(pair.row.local_percent));
        self.pair_trackable.push(round3(pair.row.trackable_percent));
        (self.pair_round_trip).push(pair.row.consistency.map(|c| round6(c.round_trip)));
        self.pair_cost.push(round6(pair.row.mean_cost));
        for m in &pair.result.pairs {
            self.costs.push(m.cost);
        }
        let (pitch, z_scale) = (self.pitch, self.pitch[0]);
        let mm = |p: &[f64]| -> [f64; 2] { [round3(p[0] * pitch[0]), round3(p[1] * pitch[1])] };
        let Some(s) = self.shown_frame(a.frame) else {
            return Ok(());
        };
        let (sa, sb) = (&a.shape, &b.shape);
        for m in &pair.result.pairs {
            let (p, q) = (mm(sa.point(m.a)), mm(sb.point(m.b)));
            if m.excess {
                s.excess.piece([p, q]);
            } else {
                s.segments.push((p, q, m.cost));
            }
        }
        for &u in &pair.result.unmatched_a {
            s.unmatched.piece([mm(sa.point(u))]);
        }
        if !s.paired {
            s.paired = true;
            s.surfaces = surface_pair(pair, a, b, &mm, z_scale);
        }
        Ok(())
    }

    fn track(
        &mut self,
        _: usize,
        steps: &[(&SequenceObject, usize)],
        _: Option<f64>,
    ) -> Result<()> {
        let pitch = self.pitch;
        let mm = |p: &[f64]| -> [f64; 2] { [round3(p[0] * pitch[0]), round3(p[1] * pitch[1])] };
        for (s, (o, _)) in steps.iter().enumerate() {
            let from = s.saturating_sub(TRAIL_FRAMES);
            if s == from {
                continue;
            }
            if let Some(shown) = self.shown_frame(o.frame) {
                shown.trails.piece(
                    steps[from..=s]
                        .iter()
                        .map(|&(o, node)| mm(o.shape.point(node))),
                );
            }
        }
        Ok(())
    }
}

/// The centre-of-pressure path for plotly: x, y and time (frame index) per frame with a centre
/// of pressure, and `null` between runs of such frames, so that the stance phases are separate
/// pieces (a swing has no contact: no line is drawn across it).
fn cop_path(cop: &[Option<[f64; 2]>]) -> Value {
    let (mut x, mut y, mut frame) = (Vec::new(), Vec::new(), Vec::new());
    for (f, c) in cop.iter().enumerate() {
        if let Some([cx, cy]) = c {
            if f > 0 && cop[f - 1].is_none() && !x.is_empty() {
                x.push(None);
                y.push(None);
                frame.push(None);
            }
            x.push(Some(*cx));
            y.push(Some(*cy));
            frame.push(Some(f));
        }
    }
    json!({ "x": x, "y": y, "frame": frame })
}

fn round3(v: f64) -> f64 {
    (v * 1e3).round() / 1e3
}

fn round6(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// Polylines as plotly wants them: x and y lists with `null` between pieces.
#[derive(Default, serde::Serialize)]
struct Lines {
    x: Vec<Option<f64>>,
    y: Vec<Option<f64>>,
}

impl Lines {
    fn piece(&mut self, points: impl IntoIterator<Item = [f64; 2]>) {
        if !self.x.is_empty() {
            self.x.push(None);
            self.y.push(None);
        }
        for p in points {
            self.x.push(Some(p[0]));
            self.y.push(Some(p[1]));
        }
    }
}

/// For the 3-D view: a surface pair's two meshes (x, y in mm or sensels; z the surface's height,
/// pressure rescaled to the footprint, times `z_scale`) and its matches as segments; `None` for
/// 2-D objects.
fn surface_pair(
    pair: &PairMatch,
    a: &SequenceObject,
    b: &SequenceObject,
    mm: &dyn Fn(&[f64]) -> [f64; 2],
    z_scale: f64,
) -> Option<Value> {
    let (sa, sb) = (&a.shape, &b.shape);
    if sa.dim() != 3 || sb.dim() != 3 {
        return None;
    }
    let point = |s: &modal_core::Shape, i: usize| {
        let p = s.point(i);
        let [x, y] = mm(p);
        [x, y, round3(p[2] * z_scale)]
    };
    let mesh = |s: &modal_core::Shape| {
        let pts: Vec<[f64; 3]> = (0..s.len()).map(|i| point(s, i)).collect();
        let tris: &[[usize; 3]] = match s.topology() {
            modal_core::Topology::Mesh { triangles } => triangles,
            _ => &[],
        };
        json!({
            "x": pts.iter().map(|p| p[0]).collect::<Vec<_>>(),
            "y": pts.iter().map(|p| p[1]).collect::<Vec<_>>(),
            "z": pts.iter().map(|p| p[2]).collect::<Vec<_>>(),
            "i": tris.iter().map(|t| t[0]).collect::<Vec<_>>(),
            "j": tris.iter().map(|t| t[1]).collect::<Vec<_>>(),
            "k": tris.iter().map(|t| t[2]).collect::<Vec<_>>(),
        })
    };
    let mut seg: [Vec<Option<f64>>; 3] = Default::default();
    for m in &pair.result.pairs {
        for p in [point(sa, m.a), point(sb, m.b)] {
            for (axis, v) in seg.iter_mut().zip(p) {
                axis.push(Some(v));
            }
        }
        for axis in &mut seg {
            axis.push(None);
        }
    }
    Some(json!({
        "a": mesh(sa), "b": mesh(sb),
        "frames": [a.frame, b.frame],
        "matches": { "x": seg[0], "y": seg[1], "z": seg[2] },
    }))
}

const TEMPLATE: &str = include_str!("html/report.html");
const MATCH_TEMPLATE: &str = include_str!("html/match.html");
/// The security policy, style and error log both pages share.
const HEAD: &str = include_str!("html/head.html");

#[cfg(test)]
mod tests {
    use super::*;
    use pedo_track::{run_sequence, SequenceOptions};

    /// A disc of pressure moving one sensel right per frame.
    fn walking_disc(frames: usize) -> Recording {
        let (rows, cols) = (16, 24);
        let mut data = vec![0.0f32; frames * rows * cols];
        for t in 0..frames {
            for r in 0..rows {
                for c in 0..cols {
                    let (dy, dx) = (r as f64 - 8.0, c as f64 - 6.0 - t as f64);
                    let d2 = dx * dx + dy * dy;
                    if d2 < 20.0 {
                        data[(t * rows + r) * cols + c] = (100.0 - 4.0 * d2) as f32;
                    }
                }
            }
        }
        Recording::from_array(frames, rows, cols, data, None)
            .unwrap()
            .with_pitch_mm([5.0, 4.0])
            .unwrap()
            .with_frame_rate(50.0)
            .unwrap()
            .with_units("kPa")
    }

    /// The frame a report whose player shows `shown` opens on, of run `r` analysed on
    /// `start..end`.
    fn open_frame(r: &SequenceResult, shown: &[usize], start: usize, end: usize) -> usize {
        let step = if shown.len() > 1 {
            shown[1] - shown[0]
        } else {
            1
        };
        let mut g = ReportGather {
            step,
            n: shown.last().map_or(0, |l| l + 1),
            pitch: [1.0, 1.0],
            kpa: 1.0,
            frames: shown.iter().map(|_| ShownFrame::default()).collect(),
            pair_frame: Vec::new(),
            pair_local: Vec::new(),
            pair_trackable: Vec::new(),
            pair_round_trip: Vec::new(),
            pair_cost: Vec::new(),
            costs: CostSample::default(),
            analysed: (start, end),
            first_analysed_object_frame: None,
            first_object: None,
            isocontour: false,
        };
        pedo_track::replay_result(r, &mut g).unwrap();
        g.open_frame(shown)
    }

    fn embedded_data(html: &str) -> Value {
        let start = html.find("id=\"report-data\">").unwrap() + "id=\"report-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        serde_json::from_str(&html[start..end]).unwrap()
    }

    fn info() -> ReportInfo {
        ReportInfo {
            input: "walk </script><b>.npy".into(),
            format: Some("npy".into()),
            version: "9.9.9".into(),
            options: vec![("modes".into(), "0.25".into())],
            timings: vec![("matching".into(), 0.5)],
            contact_threshold: 0.0,
            frames: None,
            measures: Value::Null,
            point_round_trips: None,
        }
    }

    #[test]
    fn the_header_states_the_points_round_trips_that_summary_json_records() {
        let rec = flat(2, "kPa", Some([2.0, 2.0]));
        // Five steps, one NaN (a seed frame's row): four round trips, one over a sensel.
        let trips = [0.2, 0.4, f32::NAN, 0.6, 1.5];
        let mut summary = json!({});
        crate::set_point_round_trips(&mut summary, trips);
        let info = ReportInfo::of_summary("walk".into(), &summary);
        let t = info.point_round_trips.expect("the summary's round trips");
        assert_eq!(t.count, 4);
        // numpy.percentile([0.2, 0.4, 0.6, 1.5], [50, 95]) = 0.5, 1.365.
        assert!(
            (t.median - 0.5).abs() < 1e-6 && (t.p95 - 1.365).abs() < 1e-6,
            "{t:?}"
        );
        let header = header_html(&rec, &RunCounts::default(), &info);
        assert!(
            header.contains(
                "round trip 0.500 sensels median, 1.365 at the 95th percentile, 25.0 % over 1 \
                 sensel (of 4 steps of the material points)"
            ),
            "{header}"
        );
        // No points followed: no row.
        let none =
            ReportInfo::of_summary("walk".into(), &json!({ "point_round_trip_sensels": null }));
        assert!(none.point_round_trips.is_none());
        assert!(!header_html(&rec, &RunCounts::default(), &none).contains("point consistency"));
    }

    /// A recording of `frames` frames of 4 × 5 sensels, every value 10, with `units` and an
    /// optional pitch.
    fn flat(frames: usize, units: &str, pitch: Option<[f64; 2]>) -> Recording {
        let rec = Recording::from_array(frames, 4, 5, vec![10.0; frames * 20], None)
            .unwrap()
            .with_units(units);
        match pitch {
            Some(p) => rec.with_pitch_mm(p).unwrap(),
            None => rec,
        }
    }

    #[test]
    fn the_header_names_the_files_pressure_units_when_it_shows_them_converted() {
        let header = |units: &str| {
            let rec = flat(2, units, Some([2.0, 2.0]));
            pressure_header(&rec, pressure_scale(&rec).1)
        };
        assert_eq!(header("N/cm2"), "kPa (the file's N/cm², converted)");
        assert_eq!(header("KPa"), "kPa");
        assert_eq!(header("raw"), "raw");
        assert_eq!(header(""), "units unknown");
    }

    #[test]
    fn the_load_series_is_named_with_the_files_units_as_frames_csv_names_it() {
        let cases = [
            (
                "kPa",
                Some([2.0, 2.0]),
                "total force (N)",
                json!("kPa"),
                "peak pressure (kPa)",
            ),
            // I-Scan: raw units with a pitch: the plain sum × mm² (frames.csv `total_load_mm2`).
            (
                "raw",
                Some([1.27, 1.27]),
                "total load (raw × mm²)",
                json!("raw"),
                "peak pressure (raw)",
            ),
            // pedar: kPa but no pitch (`total_load_sensels`).
            (
                "KPa",
                None,
                "total load (kPa × sensels)",
                json!("kPa"),
                "peak pressure (kPa)",
            ),
            (
                "Pa",
                None,
                "total load (Pa × sensels)",
                json!("kPa"),
                "peak pressure (kPa)",
            ),
            // .npy/.npz: no units at all.
            (
                "",
                Some([5.0, 5.0]),
                "total load (pressure units unknown × mm²)",
                Value::Null,
                "peak pressure (units unknown)",
            ),
            (
                "",
                None,
                "total load (pressure units unknown × sensels)",
                Value::Null,
                "peak pressure (units unknown)",
            ),
        ];
        for (units, pitch, load, punits, peak) in cases {
            let rec = flat(3, units, pitch);
            let html = run_report(&rec, &SequenceResult::default(), &info()).unwrap();
            let d = embedded_data(&html);
            let what = format!("units {units:?}, pitch {pitch:?}");
            assert_eq!(d["series"]["force_label"], load, "{what}");
            assert_eq!(d["series"]["peak_label"], peak, "{what}");
            assert_eq!(d["pressure_units"], punits, "{what}");
            assert!(!html.contains("units × sensels"), "{what}");
            // The values plotted are frames.csv's: 20 sensels of 10, × the sensel area if known.
            let want = 200.0 * rec.force_factor().or(rec.sensel_area()).unwrap_or(1.0);
            let got = d["series"]["force"][0].as_f64().unwrap();
            assert!((got - want).abs() < 1e-3, "{what}: {got} vs {want}");
            let header_units = pressure_header(&rec, punits.as_str().map(str::to_string));
            assert!(
                html.contains(&format!("<th>pressure</th><td>{header_units}</td>")),
                "{what}"
            );
        }
    }

    #[test]
    fn the_player_opens_on_the_first_analysed_frame_holding_objects() {
        // The disc walks in from frame 3 (frames 0-2 are empty).
        let mut rec = walking_disc(14);
        let per = rec.rows() * rec.cols();
        let mut data: Vec<f32> = (0..14)
            .flat_map(|t| rec.frame_slice(t).unwrap().to_vec())
            .collect();
        data[..3 * per].fill(0.0);
        rec = Recording::from_array(14, rec.rows(), rec.cols(), data, None)
            .unwrap()
            .with_pitch_mm([5.0, 4.0])
            .unwrap()
            .with_units("kPa");
        // The whole recording: the first frame with objects, 3.
        let all = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
        let d = embedded_data(&run_report(&rec, &all, &info()).unwrap());
        assert_eq!(
            (d["open_frame"].as_u64(), d["analysed"].clone()),
            (Some(3), json!([0, 14]))
        );
        // --frames 6..11: opens on frame 6, the header says which frames were analysed, and the
        // whole recording stays playable.
        let options = SequenceOptions {
            frames: Some((6, 11)),
            ..Default::default()
        };
        let part = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        let ranged = ReportInfo {
            frames: Some((6, 11)),
            ..info()
        };
        let html = run_report(&rec, &part, &ranged).unwrap();
        let d = embedded_data(&html);
        assert_eq!(d["open_frame"], 6);
        assert_eq!(d["analysed"], json!([6, 11]));
        assert_eq!(d["shown"].as_array().unwrap().len(), 14);
        assert!(html.contains("<td>6–10 of 14 analysed, 16 × 24 sensels</td>"));
        // No objects in the range: its first frame.
        let d = embedded_data(&run_report(&rec, &SequenceResult::default(), &ranged).unwrap());
        assert_eq!(d["open_frame"], 6);
        // Decimated (every 2nd frame shown): the first shown frame with objects in the range.
        assert_eq!(open_frame(&part, &[0, 2, 4, 6, 8, 10, 12], 7, 11), 8);
        assert_eq!(open_frame(&SequenceResult::default(), &[0, 2, 4], 3, 4), 4);
        let html = run_report(&rec, &all, &info()).unwrap();
        assert!(html.contains("<td>all 14 analysed, 16 × 24 sensels</td>"));
        let one = ReportInfo {
            frames: Some((7, 8)),
            ..info()
        };
        let html = run_report(&rec, &SequenceResult::default(), &one).unwrap();
        assert!(html.contains("<td>7 of 14 analysed, 16 × 24 sensels</td>"));
    }

    #[test]
    fn cost_classes_are_told_apart_or_collapsed() {
        // Near-identical shapes: costs of rounding noise, one class.
        let noise = vec![0.0, -0.0, 1.5e-16, 1.5e-16, 3e-17, 1.5e-16, 0.0, 2e-16];
        let c = cost_classes(noise);
        assert_eq!(c.bounds, Vec::<f64>::new());
        assert_eq!(c.labels, ["all costs ≈ 0"]);
        // The same non-zero cost everywhere.
        assert_eq!(cost_classes(vec![0.25; 9]).labels, ["all costs ≈ 0.25"]);
        // Most costs 0, a few larger: classes for what differs only, 0 written as 0 (never -0).
        let c = cost_classes(vec![-0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.5]);
        assert_eq!(c.labels, ["cost ≤ 0", "0 < cost ≤ 0.3", "cost > 0.3"]);
        assert_eq!(c.class(0.3), 1);
        assert_eq!(c.class(-0.0), 0);
        // Close bounds get the digits that tell them apart.
        let costs: Vec<f64> = (0..10).map(|i| 0.1231 + 1e-4 * i as f64).collect();
        let c = cost_classes(costs);
        assert_eq!(c.count(), COST_CLASSES);
        assert_eq!(
            c.labels,
            [
                "cost ≤ 0.1233",
                "0.1233 < cost ≤ 0.1235",
                "0.1235 < cost ≤ 0.1237",
                "0.1237 < cost ≤ 0.1239",
                "cost > 0.1239"
            ]
        );
        // Bounds apart by less than the tolerance are one bound.
        let mut costs = vec![1.0; 6];
        costs.extend([1.0 + 1e-12, 2.0, 3.0, 4.0]);
        let c = cost_classes(costs);
        assert!(c.bounds.windows(2).all(|w| w[1] - w[0] >= 1e-9), "{c:?}");
        assert_eq!(c.labels.first().unwrap(), "cost ≤ 1");
        // Tiny and huge bounds in scientific notation; no costs: one class.
        assert_eq!(significant(1.5e-16, 2), "1.5e-16");
        assert_eq!(significant(-0.0, 2), "0");
        assert_eq!(significant(2.5e7, 3), "2.5e7");
        assert_eq!(significant(1234.5678, 3), "1230");
        assert_eq!(cost_classes(vec![f64::NAN]).labels, ["matches"]);
    }

    #[test]
    fn ordinals_and_plurals() {
        let o: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 101, 111, 112]
            .into_iter()
            .map(ordinal)
            .collect();
        assert_eq!(
            o,
            [
                "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "23rd",
                "101st", "111th", "112th"
            ]
        );
        assert_eq!(counted(1, "track"), "1 track");
        assert_eq!(counted(0, "track"), "0 tracks");
        // Two frames of the disc: one pair.
        let rec = walking_disc(2);
        let result = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
        let html = run_report(&rec, &result, &info()).unwrap();
        assert!(html.contains("2 objects, 1 matched pair, "));
    }

    #[test]
    fn the_centre_of_pressure_path_has_a_gap_per_swing() {
        // Two stance phases (frames 0-3 and 6-9) around a swing without contact (4, 5), then
        // a single frame of contact (12).
        let mut rec = walking_disc(13);
        let per = rec.rows() * rec.cols();
        let mut data: Vec<f32> = (0..13)
            .flat_map(|t| rec.frame_slice(t).unwrap().to_vec())
            .collect();
        for t in [4, 5, 10, 11] {
            data[t * per..(t + 1) * per].fill(0.0);
        }
        rec = Recording::from_array(13, rec.rows(), rec.cols(), data, None)
            .unwrap()
            .with_pitch_mm([5.0, 4.0])
            .unwrap();
        let d = embedded_data(&run_report(&rec, &SequenceResult::default(), &info()).unwrap());
        let path = &d["series"]["cop_path"];
        let frames: Vec<Option<u64>> = serde_json::from_value(path["frame"].clone()).unwrap();
        let pieces: Vec<Vec<u64>> = frames
            .split(|f| f.is_none())
            .map(|p| p.iter().map(|f| f.unwrap()).collect())
            .collect();
        assert_eq!(pieces, [vec![0, 1, 2, 3], vec![6, 7, 8, 9], vec![12]]);
        let x = path["x"].as_array().unwrap();
        assert_eq!(x.len(), frames.len());
        assert_eq!(x.iter().filter(|v| v.is_null()).count(), 2);
        assert_eq!(x[4], Value::Null);
        assert_eq!(x[0], d["series"]["cop"][0][0]);
    }

    #[test]
    fn names_and_units_cannot_break_out_of_the_page_or_its_script() {
        let units = "</script><!--\u{2028}<script>&\u{2029}x";
        let rec = flat(2, units, None);
        let mut hostile = info();
        hostile.input = "<!--<script>{{DATA}}</script>".into();
        let html = run_report(&rec, &SequenceResult::default(), &hostile).unwrap();
        // The data's script element holds no markup character and no JavaScript line end ...
        let start = html.find("id=\"report-data\">").unwrap() + "id=\"report-data\">".len();
        let data = &html[start..start + html[start..].find("</script>").unwrap()];
        assert!(
            !data.contains(['<', '>', '&', '\u{2028}', '\u{2029}']),
            "{data}"
        );
        // ... and reads back to the very units.
        assert_eq!(embedded_data(&html)["pressure_units"], units);
        // The title is text, its placeholder-like part kept as written (filled in one pass).
        assert!(html.contains(
            "<title>pedomatch report: &lt;!--&lt;script&gt;{{DATA}}&lt;/script&gt;</title>"
        ));
        assert_eq!(html.matches("id=\"report-data\"").count(), 1);
    }

    #[test]
    fn report_embeds_frames_matches_and_measures_in_physical_units() {
        let rec = walking_disc(6);
        let result = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
        assert_eq!(result.pairs.len(), 5);
        let html = run_report(&rec, &result, &info()).unwrap();
        // Self-contained: plotly.js inline, nothing loaded from elsewhere, loads forbidden.
        assert!(html.contains("default-src 'none'"));
        assert!(!html.contains("<script src"));
        assert!(!html.contains("tex-svg") && html.contains("plotly.js"));
        // The header, escaped.
        assert!(html.contains("walk &lt;/script&gt;&lt;b&gt;.npy"));
        assert!(html.contains("5 × 4 mm") && html.contains("50 Hz") && html.contains("npy"));
        let d = embedded_data(&html);
        assert_eq!(d["step"], 1);
        assert_eq!(d["shown"], json!([0, 1, 2, 3, 4, 5]));
        assert_eq!(d["xy_units"], "mm");
        // Pressure decodes back to the recording within half a quantum.
        let q = d["quantum"].as_f64().unwrap();
        let (r, c, t) = (8, 9, 3);
        let coded = d["z"][t][r * 24 + c].as_f64().unwrap();
        let value = rec.frame_slice(t).unwrap()[r * 24 + c] as f64;
        assert!(
            (coded * q - value).abs() <= q / 2.0,
            "{coded} × {q} vs {value}"
        );
        // Every match of the pair leaving frame 2 is drawn as one segment (two points).
        let frame2 = &d["overlays"]["frames"][2];
        let drawn: usize = frame2["matches"]
            .as_array()
            .unwrap()
            .iter()
            .chain([&frame2["excess"]])
            .map(|l| {
                l["x"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|v| !v.is_null())
                    .count()
            })
            .sum();
        let pair = result
            .pairs
            .iter()
            .find(|p| p.row.objects.frame_a == 2)
            .unwrap();
        assert_eq!(drawn, 2 * pair.result.pairs.len());
        // Contours in mm: the disc's nodes lie within its mm extent.
        let xs: Vec<f64> = frame2["contours"]["x"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|v| v.as_f64())
            .collect();
        assert!(
            xs.iter().all(|&x| (5.0 * 3.0..=5.0 * 13.0).contains(&x)),
            "{xs:?}"
        );
        // Time series: the contact area of frame 0 in mm² (20 mm² per sensel).
        let sensels = rec.measures(0.0)[0].contact_sensors as f64;
        assert_eq!(d["series"]["area"][0].as_f64().unwrap(), sensels * 20.0);
    }

    #[test]
    fn isocontour_runs_show_each_level_of_the_frame_with_its_pressure() {
        let rec = walking_disc(6);
        let options = SequenceOptions {
            model: pedo_track::ObjectModel::Isocontour,
            iso_frame: Some(3),
            iso_count: 4,
            ..Default::default()
        };
        let result = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        let expected: Vec<f64> = result.objects.iter().filter_map(|o| o.level).collect();
        assert!(expected.len() >= 3, "{expected:?}");
        let d = embedded_data(&run_report(&rec, &result, &info()).unwrap());
        assert_eq!(d["isocontour"], true);
        assert_eq!(d["first_object_frame"], 3);
        let frame3 = &d["overlays"]["frames"][3];
        let levels = frame3["levels"].as_array().unwrap();
        // One closed outline per level, in increasing pressure, none drawn as a plain contour.
        assert_eq!(levels.len(), expected.len());
        for (l, want) in levels.iter().zip(&expected) {
            assert!((l["level"].as_f64().unwrap() - want).abs() < 1e-6);
            let (x, y) = (l["x"].as_array().unwrap(), l["y"].as_array().unwrap());
            assert!(x.len() > 8 && x.first() == x.last() && y.first() == y.last());
            // Inside the disc (radius √20 sensels around column 9, row 8; 5 × 4 mm sensels).
            for (x, y) in x.iter().zip(y) {
                let (c, r) = (x.as_f64().unwrap() / 5.0, y.as_f64().unwrap() / 4.0);
                assert!((c - 9.0).hypot(r - 8.0) <= 20f64.sqrt() + 0.5, "{c} {r}");
            }
        }
        assert!(expected.windows(2).all(|w| w[0] < w[1]));
        assert!(frame3["contours"]["x"].as_array().unwrap().is_empty());
        assert!(d["overlays"]["frames"][2]["levels"]
            .as_array()
            .unwrap()
            .is_empty());
    }

    fn ellipse(n: usize, scale: f64) -> modal_core::Shape {
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                [10.0 + 3.0 * scale * t.cos(), 8.0 + 2.0 * scale * t.sin()]
            })
            .collect();
        modal_core::Shape::from_points_2d(&pts, modal_core::Topology::ClosedContour).unwrap()
    }

    #[test]
    fn match_report_draws_every_match_in_mm_with_its_facts() {
        let (a, b) = (ellipse(40, 1.0), ellipse(32, 1.1));
        let opts = modal_core::MatchOptions {
            excess: false,
            ..Default::default()
        };
        let r = modal_core::match_shapes(&a, &b, &opts).unwrap();
        assert_eq!((r.pairs.len(), r.unmatched_a.len()), (32, 8));
        let pair = MatchPairInput {
            a: &a,
            b: &b,
            result: &r,
            pitch_mm: Some([2.0, 3.0]),
            data_unit: "sensels",
            label_a: "a.xy",
            label_b: "b.xy",
            underlays: [None, None],
        };
        let facts = [("A".to_string(), "a.xy <1>".to_string())];
        let html = match_report(&pair, &info(), &facts).unwrap();
        assert!(html.contains("default-src 'none'") && !html.contains("<script src"));
        assert!(html.contains("a.xy &lt;1&gt;") && html.contains("pedomatch 9.9.9"));
        assert!(html.contains("matching 0.500 s") && html.contains("<th>modes</th>"));
        let d = embedded_data(&html);
        assert_eq!(
            (d["dim"].as_u64(), d["xy_units"].as_str()),
            (Some(2), Some("mm"))
        );
        // Closed outlines: A's 40 nodes and its first again, in mm.
        assert_eq!(d["a"]["x"].as_array().unwrap().len(), 41);
        assert_eq!(d["a"]["x"][0].as_f64().unwrap(), 2.0 * a.point(0)[0]);
        assert_eq!(d["a"]["y"][0].as_f64().unwrap(), 3.0 * a.point(0)[1]);
        // Every match once, in the cost class its cost falls in; unmatched nodes listed.
        // The bounds as computed: a cost equal to a bound must not flip class through the JSON
        // round trip (serde_json's parsing may be one ulp off).
        let classes = cost_classes(r.pairs.iter().map(|m| m.cost).collect());
        let bounds = &classes.bounds;
        assert_eq!(classes.count(), COST_CLASSES);
        assert_eq!(d["cost_labels"], json!(classes.labels));
        let shown: Vec<f64> = serde_json::from_value(d["cost_bounds"].clone()).unwrap();
        assert_eq!(shown.len(), bounds.len());
        for (s, b) in shown.iter().zip(bounds) {
            assert!((s - b).abs() <= 1e-12 * b.abs().max(1.0), "{s} vs {b}");
        }
        let mut per_class = [0; COST_CLASSES];
        for m in &r.pairs {
            per_class[bounds.iter().take_while(|&&b| m.cost > b).count()] += 1;
        }
        for (k, n) in per_class.iter().enumerate() {
            let drawn = d["matches"][k]["x"].as_array().unwrap();
            assert_eq!(drawn.iter().filter(|v| !v.is_null()).count(), 2 * n);
        }
        let unmatched = d["unmatched_a"]["x"].as_array().unwrap();
        assert_eq!(unmatched.iter().filter(|v| !v.is_null()).count(), 8);
        assert!(d["excess"]["x"].as_array().unwrap().is_empty());
    }

    #[test]
    fn match_report_draws_the_frames_under_2d_objects() {
        // Two frames of 4 × 5 sensels, kPa; one sensel without a sensor (NaN in every frame).
        let (rows, cols) = (4, 5);
        let mut data: Vec<f32> = (0..2 * rows * cols).map(|i| i as f32 * 1.5).collect();
        data[3] = f32::NAN;
        data[rows * cols + 3] = f32::NAN;
        let mut rec = Recording::from_array(2, rows, cols, data.clone(), None).unwrap();
        rec.units = "kPa".into();
        let (a, b) = (ellipse(40, 1.0), ellipse(32, 1.1));
        let r = modal_core::match_shapes(&a, &b, &Default::default()).unwrap();
        let pair = MatchPairInput {
            a: &a,
            b: &b,
            result: &r,
            pitch_mm: Some([2.0, 3.0]),
            data_unit: "sensels",
            label_a: "a",
            label_b: "b",
            underlays: [
                Some(FrameUnderlay {
                    recording: &rec,
                    frame: 0,
                }),
                Some(FrameUnderlay {
                    recording: &rec,
                    frame: 1,
                }),
            ],
        };
        let d = embedded_data(&match_report(&pair, &info(), &[]).unwrap());
        assert_eq!(d["pitch"], json!([2.0, 3.0]));
        for (k, img) in d["images"].as_array().unwrap().iter().enumerate() {
            assert_eq!(
                (img["rows"].as_u64(), img["cols"].as_u64()),
                (Some(4), Some(5))
            );
            assert_eq!(
                (img["units"].as_str(), img["frame"].as_u64()),
                (Some("kPa"), Some(k as u64))
            );
            let q = img["quantum"].as_f64().unwrap();
            let z = img["z"].as_array().unwrap();
            assert_eq!(z.len(), rows * cols);
            assert!(z[3].is_null(), "no sensor: no value");
            // Every other sensel decodes back to the frame within half a quantum.
            for (i, v) in z.iter().enumerate().filter(|(i, _)| *i != 3) {
                let want = data[k * rows * cols + i] as f64;
                assert!(
                    (v.as_f64().unwrap() * q - want).abs() <= 0.5 * q,
                    "sensel {i}"
                );
            }
        }
        // A frame that does not exist draws nothing; 3-D objects get no image.
        let missing = MatchPairInput {
            underlays: [
                Some(FrameUnderlay {
                    recording: &rec,
                    frame: 7,
                }),
                None,
            ],
            ..pair
        };
        let d = embedded_data(&match_report(&missing, &info(), &[]).unwrap());
        assert_eq!(d["images"], json!([null, null]));
    }

    #[test]
    fn match_report_of_3d_points_carries_the_third_coordinate() {
        let coords: Vec<f64> = (0..30)
            .flat_map(|k| {
                let (x, y) = ((k % 6) as f64, (k / 6) as f64);
                [x, y, (-(x - 2.5).powi(2) - (y - 2.0).powi(2)).exp()]
            })
            .collect();
        let a = modal_core::Shape::new(3, coords.clone(), modal_core::Topology::None).unwrap();
        let shifted: Vec<f64> = coords
            .chunks(3)
            .flat_map(|p| [p[0] + 0.2, p[1], p[2]])
            .collect();
        let b = modal_core::Shape::new(3, shifted, modal_core::Topology::None).unwrap();
        let r = modal_core::match_shapes(&a, &b, &Default::default()).unwrap();
        let pair = MatchPairInput {
            a: &a,
            b: &b,
            result: &r,
            pitch_mm: None,
            data_unit: "file units",
            label_a: "a",
            label_b: "b",
            underlays: [None, None],
        };
        let d = embedded_data(&match_report(&pair, &info(), &[]).unwrap());
        assert_eq!(d["dim"], 3);
        assert_eq!(d["xy_units"], "file units");
        assert_eq!(d["a"]["closed"], false);
        let z: Vec<f64> = serde_json::from_value(d["b"]["z"].clone()).unwrap();
        assert_eq!(z.len(), 30);
        assert!((z[14] - b.point(14)[2]).abs() < 1e-6);
        let segments: usize = d["matches3d"]
            .as_array()
            .unwrap()
            .iter()
            .chain([&d["excess3d"]])
            .map(|m| {
                m["z"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|v| !v.is_null())
                    .count()
            })
            .sum();
        assert_eq!(segments, 2 * r.pairs.len());
    }

    #[test]
    fn the_cost_sample_stays_bounded_and_keeps_the_quantiles() {
        let mut sample = CostSample::default();
        let n = 5 * COST_SAMPLE + 17;
        // Costs 0..1 in a scrambled order (a multiplicative walk through the residues).
        let costs: Vec<f64> = (0..n).map(|k| ((k * 7919) % n) as f64 / n as f64).collect();
        for &c in &costs {
            sample.push(c);
        }
        assert!(sample.kept.len() < COST_SAMPLE, "{}", sample.kept.len());
        assert!(sample.kept.len() > COST_SAMPLE / 4, "{}", sample.kept.len());
        let exact = cost_classes(costs);
        let sampled = cost_classes(sample.kept.clone());
        assert_eq!(exact.bounds.len(), sampled.bounds.len());
        for (e, s) in exact.bounds.iter().zip(&sampled.bounds) {
            assert!((e - s).abs() < 0.01, "{e} vs {s}");
        }
        // Below the bound every cost is kept.
        let mut few = CostSample::default();
        (0..1000).for_each(|k| few.push(k as f64));
        assert_eq!(few.kept.len(), 1000);
    }

    #[test]
    fn long_recordings_of_small_frames_show_at_most_the_frame_bound() {
        // 1,000 frames of 4 × 5 sensels: far below the value bound, above the frame bound.
        let frames = 1000;
        let rec = flat(frames, "kPa", Some([5.0, 5.0]));
        let d = embedded_data(&run_report(&rec, &SequenceResult::default(), &info()).unwrap());
        let step = frames.div_ceil(MAX_PLAYER_FRAMES);
        assert_eq!(d["step"], step);
        let shown: Vec<usize> = serde_json::from_value(d["shown"].clone()).unwrap();
        assert!(shown.len() <= MAX_PLAYER_FRAMES, "{}", shown.len());
        // Evenly spaced, named by their own numbers, from the first frame to near the last.
        assert_eq!(shown, (0..frames).step_by(step).collect::<Vec<_>>());
        assert!(frames - 1 - shown[shown.len() - 1] < step);
        assert_eq!(d["z"].as_array().unwrap().len(), shown.len());
        assert_eq!(
            d["overlays"]["frames"].as_array().unwrap().len(),
            shown.len()
        );
        let note = d["decimation"].as_str().unwrap();
        assert!(
            note.contains(&format!("({} of {frames}, ", shown.len()))
                && note.contains(&format!("more than {MAX_PLAYER_FRAMES} frames")),
            "{note}"
        );
        // The time series keep every frame.
        assert_eq!(d["series"]["force"].as_array().unwrap().len(), frames);
        assert_eq!(player_step(MAX_PLAYER_FRAMES, 20), 1);
        assert_eq!(player_step(MAX_PLAYER_FRAMES + 1, 20), 2);
    }

    #[test]
    fn long_recordings_are_decimated_below_the_bound() {
        let (frames, rows, cols) = (301, 100, 100);
        let rec = Recording::from_array(frames, rows, cols, vec![0.0; frames * rows * cols], None)
            .unwrap();
        let result = SequenceResult::default();
        let html = run_report(&rec, &result, &info()).unwrap();
        let d = embedded_data(&html);
        assert_eq!(d["step"], 2);
        let note = d["decimation"].as_str().unwrap();
        assert!(
            note.starts_with("The player shows every 2nd frame (151 of 301, "),
            "{note}"
        );
        assert_eq!(d["shown"].as_array().unwrap().len(), 151);
        assert_eq!(d["series"]["area"].as_array().unwrap().len(), frames);
        assert!(html.len() < 25 << 20, "{} bytes", html.len());
        assert_eq!(d["xy_units"], "sensels");
    }
}
