//! The measures of a run's recording in its folder ([`pedo_io::measures`]): `peak.npy`,
//! `pti.npy`, `mean.npy` (float64 images, rows × columns of the frames, NaN where there is no
//! sensor), `measures.json` (each value with its unit, and how the contact time was found), the
//! figure `pti.png` (or `.svg`; the peak-pressure figure, with the contact outlines, is a summary figure of the run folder), and the values in `summary.json`'s `measures`;
//! and the stances' curves, `curves.csv` (or `.parquet`, [`curves_table`]), with each stance's
//! values in `measures.json`'s `stances`.
//! with a region rule ([`pedo_io::regions`]), `regions.json`, `regions.csv`, `regions.npy` and
//! the figure `regions.png`.

use crate::figure::{FigureAxes, MeasureFigure, MeasureImage};
use crate::outdir::OutDir;
use crate::run_folder::{write_figure, FigureKinds};
use crate::table::{Cell, Table};
use crate::TableFormat;
use pedo_io::formats::npy::image_to_npy;
use pedo_io::measures::{Measures, RecordingMeasures, StanceMeasures, CONTACT_FORCE_FRACTION};
use pedo_io::regions::{
    masks_of_measures, RegionMasks, RegionRule, RegionValues, HALLUX_BOUND, LENGTH_BOUNDS,
    METATARSAL_BOUNDS,
};
use pedo_io::stances::{ASSUMED_RATE_HZ, CURVE_POINTS, MIN_GAP_S, MIN_STANCE_S};
use pedo_io::{FrameStore, IoError, Recording, Result, StoredValues};
use pedo_track::{SequenceOptions, SequenceSink};
use serde_json::{json, Map, Value};

/// The files of a run folder's measures besides its figures.
pub const MEASURE_FILES: [&str; 4] = ["peak.npy", "pti.npy", "mean.npy", "measures.json"];

/// The figure of the stances' curves (`stance_curves.png` or `.svg`,
/// [`crate::figure::StanceCurvesFigure`]), written with the measures whenever figures are.
pub const STANCE_CURVES_FIGURE: &str = "stance_curves";

/// The table of the stances' curves ([`curves_table`]), one of [`crate::RUN_TABLES`].
pub const CURVES: &str = "curves";

/// The files of a run folder's regions besides their figure: `regions.json` always (it says
/// why there are no regions when the footprint could not be divided), `regions.csv` and
/// `regions.npy` when there are.
pub const REGION_FILES: [&str; 3] = ["regions.json", "regions.csv", "regions.npy"];

/// A sink that takes the measures of a run's frames as the engine hands them (every frame of
/// the run's range, [`SequenceSink::frame_values`]), and each frame's centre of pressure (what
/// tells the heel from the toes of the regions).
pub struct MeasuresSink {
    measures: RecordingMeasures,
    threshold: f64,
    cols: usize,
    mask: Vec<bool>,
    cop: Vec<Option<[f64; 2]>>,
    /// The frames as handed, for the regions of a streamed run, whose recording holds no frames
    /// to measure the regions on once their masks are known, nor to carry them through the
    /// stances.
    kept: Option<FrameStore>,
}

/// The regions of a run: their masks and values, or why the footprint could not be divided.
pub type RegionOutcome = std::result::Result<(RegionMasks, Vec<RegionValues>), IoError>;

impl MeasuresSink {
    /// The measures of a run of `recording` with `options`: a sensel is loaded at or above the
    /// run's noise threshold, as in the frames table.
    pub fn new(recording: &Recording, options: &SequenceOptions) -> Result<Self> {
        let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
        Ok(Self {
            measures: RecordingMeasures::new(recording, threshold)?,
            threshold,
            cols: recording.cols(),
            mask: recording.sensor_mask().to_vec(),
            cop: Vec::new(),
            kept: None,
        })
    }

    /// Keeps the frames of `recording` as they are handed (their values that are not 0, as a
    /// recording holds them: [`FrameStore`]), for the regions of a run whose recording does not
    /// hold its frames (a streamed run).
    pub fn keeping_frames(mut self, recording: &Recording) -> Self {
        self.kept = Some(FrameStore::new(recording));
        self
    }

    /// The measures of the frames handed ([`RecordingMeasures::finish`]).
    pub fn finish(self) -> Result<Measures> {
        self.measures.finish()
    }

    /// The measures of the frames handed and, with regions `asked`, the regions of their
    /// footprint (by a rule: masks from the measures' images and the centre of pressure's path;
    /// or the user's masks) with their values: measured on the frames kept
    /// ([`keeping_frames`](Self::keeping_frames)), else on those of `recording`. With frames
    /// kept, also `recording` holding them ([`Recording::holding`]), to carry the regions on.
    ///
    /// # Errors
    ///
    /// Those of [`RecordingMeasures::finish`]; a footprint that cannot be divided is the
    /// [`RegionOutcome`]'s error, not this one's.
    pub fn finish_with_regions(
        self,
        recording: &Recording,
        asked: Option<RegionsAsked>,
    ) -> Result<(Measures, Option<RegionOutcome>, Option<Recording>)> {
        let Self {
            measures,
            threshold,
            cop,
            kept,
            ..
        } = self;
        let measures = measures.finish()?;
        let held = kept.map(|k| recording.holding(k)).transpose()?;
        let Some(asked) = asked else {
            return Ok((measures, None, held));
        };
        let on = held.as_ref().unwrap_or(recording);
        let outcome = regions_of(on, &measures, threshold, &cop, asked);
        Ok((measures, Some(outcome), held))
    }
}

/// The regions a run measures: found by a rule, or the user's masks.
#[derive(Debug, Clone, PartialEq)]
pub enum RegionsAsked {
    /// Found from the footprint by a rule ([`pedo_io::regions::automatic_masks`]).
    Rule(RegionRule),
    /// The user's masks over the peak image ([`pedo_io::user_masks`]), boxed: they hold a
    /// label per sensel and each foot's frame.
    Masks(Box<RegionMasks>),
}

impl RegionsAsked {
    /// What `regions.json` names as the regions' rule: the rule's name, or `"masks"`.
    pub fn name(&self) -> &'static str {
        match self {
            RegionsAsked::Rule(r) => r.name(),
            RegionsAsked::Masks(_) => "masks",
        }
    }
}

/// The regions of `measures` `asked` and their values, measured on the frames of `recording`.
fn regions_of(
    recording: &Recording,
    measures: &Measures,
    threshold: f64,
    cop: &[Option<[f64; 2]>],
    asked: RegionsAsked,
) -> RegionOutcome {
    let masks = match asked {
        RegionsAsked::Rule(rule) => masks_of_measures(recording, measures, Some(cop), rule)?,
        RegionsAsked::Masks(m) => *m,
    };
    let values = pedo_io::regions::region_values(recording, threshold, &masks, measures)?;
    Ok((masks, values))
}

/// The regions `asked` of a recording held whole, and their values over the frames of
/// `measures` (above `threshold`): what a run's folder measures, for a run without one.
pub fn recording_regions(
    recording: &Recording,
    measures: &Measures,
    threshold: f64,
    asked: RegionsAsked,
) -> RegionOutcome {
    match asked {
        RegionsAsked::Rule(rule) => {
            pedo_io::regions::regions_of_measures(recording, threshold, measures, rule)
        }
        RegionsAsked::Masks(masks) => {
            let values = pedo_io::regions::region_values(recording, threshold, &masks, measures)?;
            Ok((*masks, values))
        }
    }
}

impl SequenceSink for MeasuresSink {
    fn wants_frame_values(&self) -> bool {
        true
    }
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        self.measures.add_frame(frame, values)?;
        if let Some(kept) = self.kept.as_mut() {
            kept.push(frame, values.iter().copied().enumerate())?;
        }
        self.add_centre(values.iter().copied().enumerate());
        Ok(())
    }
    fn stored_frame_values(&mut self, frame: usize, stored: StoredValues<'_>) -> Result<()> {
        if stored.frame_len() != self.mask.len() || !stored.all_positive() {
            return self.frame_values(frame, &stored.to_frame());
        }
        self.measures.add_stored(frame, stored)?;
        if let Some(kept) = self.kept.as_mut() {
            kept.push(frame, stored.iter())?;
        }
        // The zeros a stored frame leaves out add nothing to the sums.
        self.add_centre(stored.iter());
        Ok(())
    }
}

impl MeasuresSink {
    /// A frame's centre of pressure from its sensels `(position, value)` in order of position.
    fn add_centre(&mut self, sensels: impl Iterator<Item = (usize, f32)>) {
        let (mut load, mut mx, mut my) = (0.0f64, 0.0f64, 0.0f64);
        for (i, v) in sensels {
            let x = f64::from(v);
            if self.mask[i] && x > 0.0 && x >= self.threshold {
                load += x;
                mx += x * (i % self.cols) as f64;
                my += x * (i / self.cols) as f64;
            }
        }
        self.cop.push((load > 0.0).then(|| [mx / load, my / load]));
    }
}

/// The values as `summary.json`'s `measures` holds them: `{name: {"value": v, "unit": u}}`.
pub fn measure_values_json(m: &Measures) -> Value {
    let values: Map<String, Value> = m
        .quantities()
        .into_iter()
        .map(|q| {
            (
                q.name.to_string(),
                json!({"value": q.value, "unit": q.unit}),
            )
        })
        .collect();
    Value::Object(values)
}

/// Sets `summary.json`'s `measures` ([`measure_values_json`]) and, for a recording of both feet
/// apart, its `foot_measures`: per foot (`left`, `right`) its own values, as `measures` holds
/// the whole recording's.
pub fn set_summary_measures(summary: &mut Value, m: &Measures) {
    summary["measures"] = measure_values_json(m);
    if !m.feet.is_empty() {
        let feet: Map<String, Value> = (m.feet.iter())
            .map(|f| (f.side.name().to_string(), measure_values_json(&f.measures)))
            .collect();
        summary["foot_measures"] = Value::Object(feet);
    }
}

/// The table of stance-normalised curves (`curves.csv`): one row per stance and per cent of
/// contact (0..=100): `stance` (0-based, in frame order), `complete` (1, or 0 for a stance the
/// recording may cut, on its first or last frame), `percent`, then the frames table's measures
/// at that point of the stance, in its columns and units (contact area, total force, peak
/// pressure, centre of pressure in sensels and in mm), then with `regions` (a region rule or
/// the user's masks) each region's force and peak pressure ([`region_curve_columns`]). More
/// measures are more columns. A recording of both feet apart ([`Recording::feet`]) has a
/// `foot` column first and each foot's stances, numbered per foot, measured on its sensels
/// alone (the left foot's, then the right's); its rows hold their own foot's regions' curves,
/// in the columns of the regions' names (empty where that foot has no such region).
pub fn curves_table(
    recording: &Recording,
    m: &Measures,
    regions: Option<&[RegionValues]>,
) -> Table {
    let mut t = curves_header(recording, regions);
    let regions = regions.unwrap_or_default();
    if recording.feet.is_empty() {
        let own: Vec<Option<&RegionValues>> = regions.iter().map(Some).collect();
        for (k, s) in m.stances.iter().enumerate() {
            stance_rows(&mut t, recording, None, k, s, &own);
        }
    }
    let names = region_names(regions);
    for foot in &m.feet {
        let own: Vec<Option<&RegionValues>> = (names.iter())
            .map(|n| {
                let on_foot = |r: &&RegionValues| r.foot == Some(foot.side) && r.name == *n;
                regions.iter().find(on_foot)
            })
            .collect();
        for (k, s) in foot.measures.stances.iter().enumerate() {
            stance_rows(&mut t, recording, Some(foot.side.name()), k, s, &own);
        }
    }
    t
}

/// The regions' names in their order, each once (both feet's regions share their names).
fn region_names(regions: &[RegionValues]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for r in regions {
        if !names.contains(&r.name.as_str()) {
            names.push(&r.name);
        }
    }
    names
}

/// The rows of stance `k`, `s`, of [`curves_table`], with its `foot` when the table has one.
fn stance_rows(
    t: &mut Table,
    recording: &Recording,
    foot: Option<&str>,
    k: usize,
    s: &StanceMeasures,
    regions: &[Option<&RegionValues>],
) {
    let c = &s.curves;
    for p in 0..CURVE_POINTS {
        let mut row: Vec<Cell> = foot
            .map(|f| Cell::Text(f.to_string()))
            .into_iter()
            .collect();
        row.extend([
            Cell::int(k),
            Cell::int(usize::from(s.stance.complete)),
            Cell::int(p),
            Cell::Float(c.area[p], 4),
            Cell::Float(c.force[p], 4),
            Cell::Float(c.peak_pressure[p], 4),
            Cell::opt(c.cop_x[p], 4),
            Cell::opt(c.cop_y[p], 4),
        ]);
        if recording.pitch_mm.is_some() {
            let xy = c.cop_x[p]
                .zip(c.cop_y[p])
                .and_then(|(x, y)| recording.to_mm(x, y));
            row.push(Cell::opt(xy.map(|v| v[0]), 4));
            row.push(Cell::opt(xy.map(|v| v[1]), 4));
        }
        for r in regions {
            let curve = r.and_then(|r| r.curves.get(k));
            row.push(Cell::opt(curve.map(|c| c.force[p]), 4));
            row.push(Cell::opt(curve.map(|c| c.peak_pressure[p]), 4));
        }
        t.rows.push(row);
    }
}

/// The columns of region `name`'s curves in [`curves_table`] for `recording`: its force and its
/// peak pressure, named as the frames table's with the region's name in front of them
/// (`forefoot_force_n`, `forefoot_peak_pressure_kpa`; `forefoot_load_mm2` when the load is no
/// force, `forefoot_peak_pressure` in unknown units).
pub fn region_curve_columns(recording: &Recording, name: &str) -> [String; 2] {
    let u = crate::run_tables::measure_units(recording);
    let force = u.force.strip_prefix("total_").unwrap_or(u.force);
    [format!("{name}_{force}"), format!("{name}_{}", u.peak.0)]
}

/// The columns of [`curves_table`] (no rows).
pub fn curves_header(recording: &Recording, regions: Option<&[RegionValues]>) -> Table {
    let u = crate::run_tables::measure_units(recording);
    let feet = !recording.feet.is_empty();
    let mut t = if feet {
        Table::new(&["foot", "stance", "complete", "percent"])
    } else {
        Table::new(&["stance", "complete", "percent"])
    };
    for c in [u.area.0, u.force, u.peak.0, "cop_x", "cop_y"] {
        t.push_column(c);
    }
    if recording.pitch_mm.is_some() {
        t.push_column("cop_x_mm");
        t.push_column("cop_y_mm");
    }
    for name in region_names(regions.unwrap_or_default()) {
        for c in region_curve_columns(recording, name) {
            t.push_column(&c);
        }
    }
    t
}

/// `measures.json`'s `stances`: each stance's frames, whether it is complete, and its values
/// with their units.
pub fn stances_json(m: &Measures) -> Value {
    let stances: Vec<Value> = m
        .stances
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let values: Map<String, Value> = s
                .quantities(&m.units)
                .into_iter()
                .map(|q| {
                    (
                        q.name.to_string(),
                        json!({"value": q.value, "unit": q.unit}),
                    )
                })
                .collect();
            json!({
                "stance": k,
                "frames": [s.stance.first, s.stance.last],
                "complete": s.stance.complete,
                "values": values,
            })
        })
        .collect();
    Value::Array(stances)
}

/// `measures.json`'s `feet`, for a recording of both feet apart: per foot (the left, then the
/// right) its name, its columns in the images, its contact force threshold and frames, its
/// values and its stances, as the whole recording's.
pub fn feet_json(m: &Measures) -> Value {
    let feet = m.feet.iter().map(|f| {
        let fm = &f.measures;
        json!({
            "foot": f.side.name(),
            "columns": [f.columns.start, f.columns.end],
            "contact_force_threshold": {
                "value": fm.values.contact_force_threshold,
                "unit": fm.units.force,
            },
            "contact_frames": [fm.values.contact_frames.0, fm.values.contact_frames.1],
            "values": measure_values_json(fm),
            "stances": stances_json(fm),
        })
    });
    Value::Array(feet.collect())
}

/// `measures.json`: the frames measured, the thresholds, the values with their units and what
/// each image file holds; the stances, their rule and values; with both feet apart, each
/// foot's ([`feet_json`]).
pub fn measures_json(m: &Measures) -> Value {
    let mut out = whole_measures_json(m);
    if !m.feet.is_empty() {
        out["feet"] = feet_json(m);
    }
    out
}

/// [`measures_json`] without the feet.
fn whole_measures_json(m: &Measures) -> Value {
    let u = &m.units;
    let r = &m.stance_rule;
    json!({
        "frames": [m.frames.start, m.frames.end],
        "contact_threshold": m.threshold,
        "contact_force_threshold": {
            "value": m.values.contact_force_threshold,
            "unit": u.force,
            "rule": format!(
                "min + {CONTACT_FORCE_FRACTION} x (max - min) of the frames' force (pressuRe's threshold_event, auto)"
            ),
        },
        "contact_frames": [m.values.contact_frames.0, m.values.contact_frames.1],
        "values": measure_values_json(m),
        "stance_rule": {
            "min_gap_frames": r.min_gap,
            "min_stance_frames": r.min_frames,
            "rule": format!(
                "frames whose force exceeds the contact force threshold; gaps shorter than {MIN_GAP_S} s joined, \
                 stances shorter than {MIN_STANCE_S} s dropped (counted at {ASSUMED_RATE_HZ} Hz without a frame rate); \
                 a stance on the first or last frame is not complete"
            ),
        },
        "stances": stances_json(m),
        "images": {
            "peak.npy": format!("peak pressure per sensel ({})", u.pressure),
            "pti.npy": format!("pressure-time integral per sensel ({}·{})", u.pressure, u.time),
            "mean.npy": format!("mean pressure per sensel over the frames it is loaded ({})", u.pressure),
        },
    })
}

/// Writes the measures' files into `dir` ([`MEASURE_FILES`]), the curves table as `tables`
/// says (`curves.csv` or `curves.parquet`, with the curves of `regions` when given) and their
/// figures as `kinds` says (`pti.png` and `stance_curves.png`, or `.svg`).
pub fn write_measures(
    dir: &OutDir,
    recording: &Recording,
    m: &Measures,
    regions: Option<&[RegionValues]>,
    kinds: FigureKinds,
    tables: TableFormat,
) -> Result<()> {
    crate::write_table(dir, tables, CURVES, &curves_table(recording, m, regions))?;
    dir.write("peak.npy", &image_to_npy(m.rows, m.cols, &m.peak)?)?;
    dir.write("pti.npy", &image_to_npy(m.rows, m.cols, &m.pti)?)?;
    dir.write("mean.npy", &image_to_npy(m.rows, m.cols, &m.mean)?)?;
    let json = crate::run_folder::pretty(&measures_json(m));
    dir.write("measures.json", json.as_bytes())?;
    let axes = FigureAxes::of_recording(recording);
    // The peak-pressure image is a summary figure of its own, with the contact outlines.
    let fig = MeasureFigure {
        measures: m,
        image: MeasureImage::Pti,
        axes: &axes,
    };
    let stem = MeasureImage::Pti.stem();
    write_figure(dir, stem, kinds, || fig.to_png(), || fig.to_svg())?;
    let curves = crate::figure::StanceCurvesFigure { measures: m };
    write_figure(
        dir,
        STANCE_CURVES_FIGURE,
        kinds,
        || curves.to_png(),
        || curves.to_svg(),
    )?;
    Ok(())
}

/// One value of one region, with its unit ([`region_quantities`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RegionQuantity {
    /// The region's foot (`"left"`, `"right"`), for a recording of both feet apart.
    pub foot: Option<&'static str>,
    /// The region's name.
    pub region: String,
    /// The measure's name, as [`Measures::quantities`] names it.
    pub measure: &'static str,
    /// Its value.
    pub value: f64,
    /// Its unit.
    pub unit: String,
}

impl RegionQuantity {
    /// The region's key where regions are named once: its name, after its foot's
    /// (`left/hindfoot`) for a foot's region.
    pub fn key(&self) -> String {
        match self.foot {
            Some(f) => format!("{f}/{}", self.region),
            None => self.region.clone(),
        }
    }
}

/// The values of each region with their names and units, in the units of `m` (as
/// [`Measures::quantities`] names them), region by region.
pub fn region_quantities(m: &Measures, values: &[RegionValues]) -> Vec<RegionQuantity> {
    let mut out = Vec::new();
    for v in values {
        for (measure, value, unit) in region_values_of(m, v) {
            out.push(RegionQuantity {
                foot: v.foot.map(|s| s.name()),
                region: v.name.clone(),
                measure,
                value,
                unit,
            });
        }
    }
    out
}

/// The values of region `v`, `(measure, value, unit)`, in the units of `m`.
fn region_values_of(m: &Measures, v: &RegionValues) -> Vec<(&'static str, f64, String)> {
    let u = &m.units;
    let mut out = vec![
        ("peak_pressure", v.peak_pressure, u.pressure.clone()),
        ("pti_max", v.pti_max, format!("{}·{}", u.pressure, u.time)),
    ];
    for l in u.load_quantities(v.peak_force, v.fti) {
        out.push((l.name, l.value, l.unit));
    }
    out.push(("max_contact_area", v.max_contact_area, u.area.clone()));
    out.push(("contact_time", v.contact_time, u.time.clone()));
    out.push(("impulse_share", v.impulse_share, "%".to_string()));
    out
}

/// `regions.csv`: one row per region and measure, `region,measure,value,unit,kind`: the fixed
/// regions' rows (`kind` `fixed`, the masks over the peak image), then, when the regions were
/// carried through the stances, the moving regions' (`kind` `moving`,
/// [`crate::moving_regions`]). A recording of both feet apart has a first column `foot`
/// (`left`, `right`): each foot's regions.
pub fn regions_csv(
    m: &Measures,
    values: &[RegionValues],
    moving: Option<&[RegionValues]>,
) -> String {
    let feet = values.iter().any(|v| v.foot.is_some());
    let mut csv = String::from(if feet { "foot," } else { "" });
    csv.push_str("region,measure,value,unit,kind\n");
    for (kind, q) in region_rows(m, values, moving) {
        if feet {
            csv.push_str(q.foot.unwrap_or_default());
            csv.push(',');
        }
        let RegionQuantity {
            region,
            measure,
            value,
            unit,
            ..
        } = q;
        csv.push_str(&format!("{region},{measure},{value},{unit},{kind}\n"));
    }
    csv
}

/// The rows of `regions.csv`, each with its `kind`: the fixed regions' (`values`), then the
/// moving regions' when they were carried.
fn region_rows<'a>(
    m: &'a Measures,
    values: &'a [RegionValues],
    moving: Option<&'a [RegionValues]>,
) -> impl Iterator<Item = (&'static str, RegionQuantity)> + 'a {
    [("fixed", Some(values)), ("moving", moving)]
        .into_iter()
        .filter_map(|(kind, v)| Some((kind, v?)))
        .flat_map(move |(kind, v)| region_quantities(m, v).into_iter().map(move |q| (kind, q)))
}

/// `regions.csv` as a [`Table`] (its columns; values to 6 decimals), what a run returns without
/// a folder: the fixed regions' rows, then the moving regions' when they were carried. `feet`
/// (a recording of both feet apart) adds the first column `foot`, with or without rows.
pub fn region_values_table(
    m: &Measures,
    values: &[RegionValues],
    moving: Option<&[RegionValues]>,
    feet: bool,
) -> Table {
    let mut header: Vec<String> = ["region", "measure", "value", "unit", "kind"]
        .map(String::from)
        .to_vec();
    if feet {
        header.insert(0, "foot".to_string());
    }
    let rows = region_rows(m, values, moving)
        .map(|(kind, q)| {
            let mut row = Vec::with_capacity(header.len());
            if feet {
                row.push(Cell::Text(q.foot.unwrap_or_default().into()));
            }
            row.extend([
                Cell::Text(q.region),
                Cell::Text(q.measure.to_string()),
                Cell::Float(q.value, 6),
                Cell::Text(q.unit),
                Cell::Text(kind.to_string()),
            ]);
            row
        })
        .collect();
    Table { header, rows }
}

/// `regions.json`: the rule (or `"masks"` for the user's), the label of each region in `regions.npy`, the foot's axis and
/// side, the bounds used and each region's values; or, when the footprint could not be
/// divided, why.
pub fn regions_json(
    m: &Measures,
    rule: &str,
    outcome: &RegionOutcome,
    moving: Option<&crate::moving_regions::MovingOutcome>,
) -> Value {
    let (masks, values) = match outcome {
        Ok(found) => found,
        Err(e) => return json!({"rule": rule, "error": e.to_string()}),
    };
    let labels: Map<String, Value> = (masks.names.iter().enumerate())
        .map(|(k, n)| {
            let label = match masks.sides.get(k) {
                Some(side) => json!({"foot": side.name(), "region": n}),
                None => json!(n),
            };
            ((k + 1).to_string(), label)
        })
        .collect();
    let mut per: Map<String, Value> = Map::new();
    for q in region_quantities(m, values) {
        let entry = per.entry(q.key()).or_insert_with(|| json!({}));
        entry[q.measure] = json!({"value": q.value, "unit": q.unit});
    }
    for v in values {
        let key = match v.foot {
            Some(f) => format!("{}/{}", f.name(), v.name),
            None => v.name.clone(),
        };
        if let Some(e) = per.get_mut(&key) {
            e["sensels"] = json!(v.sensels);
        }
    }
    let axis_json = |a: &pedo_io::regions::FootAxis| {
        json!({
            "side": a.side.name(),
            "heel_toe_cue": a.heel_toe_cue.name(),
            "heel_mm": a.heel,
            "toe_mm": a.toe,
            "direction": a.direction,
            "medial": a.medial,
            "length_mm": a.length,
        })
    };
    let axis = masks.axis.as_ref().map(axis_json);
    let mut out = json!({
        "rule": rule,
        "labels": labels,
        "label_image": "regions.npy: per sensel 0 outside the footprint, else the region's label",
        "foot": axis,
        "bounds": {
            "length_fractions": LENGTH_BOUNDS,
            "metatarsal_width_fractions": METATARSAL_BOUNDS,
            "hallux_width_fraction": HALLUX_BOUND,
        },
        "regions": per,
    });
    if !masks.foot_axes.is_empty() {
        let feet: Vec<Value> = (masks.foot_axes.iter())
            .map(|(_, a)| axis_json(a))
            .collect();
        out["feet"] = Value::Array(feet);
    }
    if let Some(moving) = moving {
        out["moving"] = crate::moving_regions::moving_json(m, moving);
    }
    out
}

/// Writes the regions' files into `dir` ([`REGION_FILES`]: the CSV and the label image only
/// when the footprint was divided; with `moving`, the moving regions' values and rows too) and
/// their figure `regions.png` (or `.svg`) as `kinds` says; `rule` is what `regions.json` names
/// as their rule ([`RegionsAsked::name`]).
pub fn write_regions(
    dir: &OutDir,
    recording: &Recording,
    m: &Measures,
    rule: &str,
    outcome: &RegionOutcome,
    moving: Option<&crate::moving_regions::MovingOutcome>,
    kinds: FigureKinds,
) -> Result<()> {
    let json = crate::run_folder::pretty(&regions_json(m, rule, outcome, moving));
    dir.write("regions.json", json.as_bytes())?;
    let Ok((masks, values)) = outcome else {
        return Ok(());
    };
    let moving_values = moving.and_then(|o| o.as_ref().ok()).map(|a| &a.values[..]);
    dir.write(
        "regions.csv",
        regions_csv(m, values, moving_values).as_bytes(),
    )?;
    let labels: Vec<f64> = masks.labels.iter().map(|&l| f64::from(l)).collect();
    dir.write(
        "regions.npy",
        &image_to_npy(masks.rows, masks.cols, &labels)?,
    )?;
    let axes = FigureAxes::of_recording(recording);
    let fig = crate::figure::RegionFigure {
        measures: m,
        masks,
        axes: &axes,
    };
    write_figure(dir, "regions", kinds, || fig.to_png(), || fig.to_svg())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_curves_table_has_a_row_per_stance_and_percent_in_the_frames_tables_units() {
        // 12 frames of 1 × 2 sensels at 100 Hz in kPa, 2 mm pitch: frames 1..=10 in contact,
        // the right sensel rising 0, 100, …, 900 kPa beside 1000 kPa.
        let n = 12;
        let mut data = vec![0.0f32; 2 * n];
        for t in 1..=10 {
            data[2 * t] = 1000.0;
            data[2 * t + 1] = 100.0 * (t - 1) as f32;
        }
        let rec = Recording::new(n, 1, 2, data, vec![true; 2])
            .unwrap()
            .with_pitch_mm([2.0, 2.0])
            .unwrap()
            .with_frame_rate(100.0)
            .unwrap()
            .with_units("kPa");
        let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
        let t = curves_table(&rec, &m, None);
        assert_eq!(
            t.header,
            [
                "stance",
                "complete",
                "percent",
                "contact_area_mm2",
                "total_force_n",
                "peak_pressure_kpa",
                "cop_x",
                "cop_y",
                "cop_x_mm",
                "cop_y_mm"
            ]
        );
        assert_eq!(t.rows.len(), 101);
        // 50 %: frame 1 + 4.5, the force (1000 + 450) kPa × 4 mm² = 5.8 N, the peak 1000 kPa.
        let row = &t.rows[50];
        assert_eq!(row[..3], [Cell::Int(0), Cell::Int(1), Cell::Int(50)]);
        assert!(
            matches!(row[4], Cell::Float(f, 4) if (f - 5.8).abs() < 1e-9),
            "{row:?}"
        );
        assert!(matches!(row[5], Cell::Float(f, 4) if f == 1000.0));
        // x of the centre of pressure in mm: twice that in sensels.
        let (Cell::Float(x, _), Cell::Float(xm, _)) = (&row[6], &row[8]) else {
            panic!("{row:?}")
        };
        assert!((xm - 2.0 * x).abs() < 1e-12);
        let json = measures_json(&m);
        assert_eq!(json["stances"][0]["frames"], json!([1, 10]));
        assert_eq!(json["stances"][0]["complete"], json!(true));
        assert_eq!(json["stances"][0]["values"]["contact_time"]["unit"], "s");
        assert_eq!(json["stance_rule"]["min_gap_frames"], 5);
        // A recording of one sensor has no feet.
        assert!(json.get("feet").is_none());
    }

    #[test]
    fn both_insoles_of_a_pedar_walk_have_their_own_stances_and_curves() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../pedo-io/tests/data/pedar-example-3.01-4.00.asc"
        );
        let rec = pedo_io::read_recording(path).unwrap();
        let m = Measures::of_recording(&rec, 0.0, 0..rec.n_frames()).unwrap();
        let t = curves_table(&rec, &m, None);
        assert_eq!(t.header[..2], ["foot", "stance"]);
        let feet: Vec<(&str, usize)> = (m.feet.iter())
            .map(|f| (f.side.name(), f.measures.stances.len()))
            .collect();
        assert!(feet.iter().all(|f| f.1 > 0), "{feet:?}");
        // The left foot's rows, then the right's, stances numbered per foot.
        let want: Vec<(&str, i64)> = (feet.iter())
            .flat_map(|&(side, n)| (0..n).flat_map(move |k| [(side, k as i64); 101]))
            .collect();
        let got: Vec<(&str, i64)> = (t.rows.iter())
            .map(|r| match (&r[0], &r[1]) {
                (Cell::Text(f), Cell::Int(k)) => (f.as_str(), *k),
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(got, want);
        let json = measures_json(&m);
        let feet_json = json["feet"].as_array().unwrap();
        assert_eq!(feet_json.len(), 2);
        assert_eq!(feet_json[1]["foot"], "right");
        let left = &m.feet[0].measures.values;
        assert_eq!(
            feet_json[0]["values"]["contact_time"]["value"],
            json!(left.contact_time)
        );
        // No regions, no region columns beside a foot's curves.
        assert_eq!(curves_header(&rec, Some(&[])).header, t.header);
    }
}
