//! The measures of a run's recording in its folder ([`pedo_io::measures`]): `peak.npy`,
//! `pti.npy`, `mean.npy` (float64 images, rows × columns of the frames, NaN where there is no
//! sensor), `measures.json` (each value with its unit, and how the contact time was found), the
//! figure `pti.png` (or `.svg`; the peak-pressure figure, with the contact outlines, is a summary figure of the run folder), and the values in `summary.json`'s `measures`;
//! with a region rule ([`pedo_io::regions`]), `regions.json`, `regions.csv`, `regions.npy` and
//! the figure `regions.png`.

use crate::figure::{FigureAxes, MeasureFigure, MeasureImage};
use crate::outdir::OutDir;
use crate::run_folder::{write_figure, FigureKinds};
use pedo_io::formats::npy::image_to_npy;
use pedo_io::measures::{Measures, RecordingMeasures, CONTACT_FORCE_FRACTION};
use pedo_io::regions::{
    masks_of_measures, RegionMasks, RegionRule, RegionSeries, RegionValues, HALLUX_BOUND,
    LENGTH_BOUNDS, METATARSAL_BOUNDS,
};
use pedo_io::{IoError, Recording, Result};
use pedo_track::{SequenceOptions, SequenceSink};
use serde_json::{json, Map, Value};

/// The files of a run folder's measures besides its figures.
pub const MEASURE_FILES: [&str; 4] = ["peak.npy", "pti.npy", "mean.npy", "measures.json"];

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
    /// The loaded sensels of every frame (index, value), for the regions of a streamed run,
    /// whose recording holds no frames to measure the regions on once their masks are known.
    kept: Option<Vec<Vec<(u32, f32)>>>,
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

    /// Keeps the loaded sensels of every frame (8 bytes each), for the regions of a run whose
    /// recording does not hold its frames (a streamed run).
    pub fn keeping_frames(mut self) -> Self {
        self.kept = Some(Vec::new());
        self
    }

    /// The measures of the frames handed ([`RecordingMeasures::finish`]).
    pub fn finish(self) -> Result<Measures> {
        self.measures.finish()
    }

    /// The measures of the frames handed and, with a `rule`, the regions of their footprint
    /// (masks from the measures' images and the centre of pressure's path) with their values:
    /// measured on the frames kept ([`keeping_frames`](Self::keeping_frames)), else on those of
    /// `recording`.
    ///
    /// # Errors
    ///
    /// Those of [`RecordingMeasures::finish`]; a footprint that cannot be divided is the
    /// [`RegionOutcome`]'s error, not this one's.
    pub fn finish_with_regions(
        self,
        recording: &Recording,
        rule: Option<RegionRule>,
    ) -> Result<(Measures, Option<RegionOutcome>)> {
        let Self {
            measures,
            threshold,
            cop,
            kept,
            ..
        } = self;
        let measures = measures.finish()?;
        let Some(rule) = rule else {
            return Ok((measures, None));
        };
        let outcome = regions_of(recording, &measures, threshold, &cop, kept.as_deref(), rule);
        Ok((measures, Some(outcome)))
    }
}

/// The regions of `measures` by `rule` and their values, measured on the frames `kept` (the
/// loaded sensels of each) or, without them, on those of `recording`.
fn regions_of(
    recording: &Recording,
    measures: &Measures,
    threshold: f64,
    cop: &[Option<[f64; 2]>],
    kept: Option<&[Vec<(u32, f32)>]>,
    rule: RegionRule,
) -> RegionOutcome {
    let masks = masks_of_measures(recording, measures, Some(cop), rule)?;
    let mut series = RegionSeries::new(recording, threshold, &masks)?;
    match kept {
        Some(frames) => {
            let mut dense = vec![0.0f32; masks.labels.len()];
            for frame in frames {
                dense.fill(0.0);
                for &(i, v) in frame {
                    dense[i as usize] = v;
                }
                series.add_frame(&dense)?;
            }
        }
        None => {
            for t in measures.frames.clone() {
                let values = recording.frame_slice(t).ok_or_else(|| {
                    IoError::invalid(format!("frame {t} is not held to measure the regions on"))
                })?;
                series.add_frame(&values)?;
            }
        }
    }
    let values = series.finish(measures)?;
    Ok((masks, values))
}

impl SequenceSink for MeasuresSink {
    fn wants_frame_values(&self) -> bool {
        true
    }
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        self.measures.add_frame(frame, values)?;
        let (mut load, mut mx, mut my) = (0.0f64, 0.0f64, 0.0f64);
        let mut loaded = Vec::new();
        for (i, &v) in values.iter().enumerate() {
            let x = f64::from(v);
            if self.mask[i] && x > 0.0 && x >= self.threshold {
                load += x;
                mx += x * (i % self.cols) as f64;
                my += x * (i / self.cols) as f64;
                if self.kept.is_some() {
                    loaded.push((i as u32, v));
                }
            }
        }
        self.cop.push((load > 0.0).then(|| [mx / load, my / load]));
        if let Some(kept) = self.kept.as_mut() {
            kept.push(loaded);
        }
        Ok(())
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

/// `measures.json`: the frames measured, the thresholds, the values with their units and what
/// each image file holds.
pub fn measures_json(m: &Measures) -> Value {
    let u = &m.units;
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
        "images": {
            "peak.npy": format!("peak pressure per sensel ({})", u.pressure),
            "pti.npy": format!("pressure-time integral per sensel ({}·{})", u.pressure, u.time),
            "mean.npy": format!("mean pressure per sensel over the frames it is loaded ({})", u.pressure),
        },
    })
}

/// Writes the measures' files into `dir` ([`MEASURE_FILES`]) and their figures as `kinds` says
/// (`pti.png` or `.svg`).
pub fn write_measures(
    dir: &OutDir,
    recording: &Recording,
    m: &Measures,
    kinds: FigureKinds,
) -> Result<()> {
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
    Ok(())
}

/// The values of each region with their names and units, in the units of `m` (as
/// [`Measures::quantities`] names them): `(region, measure, value, unit)`.
pub fn region_quantities(
    m: &Measures,
    values: &[RegionValues],
) -> Vec<(String, &'static str, f64, String)> {
    let u = &m.units;
    let (force, fti) = if u.is_force {
        ("peak_force", "fti")
    } else {
        ("peak_load", "load_time_integral")
    };
    let mut out = Vec::new();
    for v in values {
        let name = || v.name.clone();
        out.push((name(), "peak_pressure", v.peak_pressure, u.pressure.clone()));
        out.push((
            name(),
            "pti_max",
            v.pti_max,
            format!("{}·{}", u.pressure, u.time),
        ));
        out.push((name(), force, v.peak_force, u.force.clone()));
        out.push((name(), fti, v.fti, format!("{}·{}", u.force, u.time)));
        out.push((
            name(),
            "max_contact_area",
            v.max_contact_area,
            u.area.clone(),
        ));
        out.push((name(), "contact_time", v.contact_time, u.time.clone()));
        out.push((name(), "impulse_share", v.impulse_share, "%".to_string()));
    }
    out
}

/// `regions.csv`: one row per region and measure, `region,measure,value,unit`.
pub fn regions_csv(m: &Measures, values: &[RegionValues]) -> String {
    let mut csv = String::from("region,measure,value,unit\n");
    for (region, measure, value, unit) in region_quantities(m, values) {
        csv.push_str(&format!("{region},{measure},{value},{unit}\n"));
    }
    csv
}

/// `regions.json`: the rule, the label of each region in `regions.npy`, the foot's axis and
/// side, the bounds used and each region's values; or, when the footprint could not be
/// divided, why.
pub fn regions_json(m: &Measures, rule: RegionRule, outcome: &RegionOutcome) -> Value {
    let (masks, values) = match outcome {
        Ok(found) => found,
        Err(e) => return json!({"rule": rule.name(), "error": e.to_string()}),
    };
    let labels: Map<String, Value> = (masks.names.iter().enumerate())
        .map(|(k, n)| ((k + 1).to_string(), json!(n)))
        .collect();
    let mut per: Map<String, Value> = Map::new();
    for (region, measure, value, unit) in region_quantities(m, values) {
        let entry = per.entry(region).or_insert_with(|| json!({}));
        entry[measure] = json!({"value": value, "unit": unit});
    }
    for v in values {
        if let Some(e) = per.get_mut(&v.name) {
            e["sensels"] = json!(v.sensels);
        }
    }
    let axis = masks.axis.as_ref().map(|a| {
        json!({
            "side": a.side.name(),
            "heel_toe_cue": a.heel_toe_cue.name(),
            "heel_mm": a.heel,
            "toe_mm": a.toe,
            "direction": a.direction,
            "medial": a.medial,
            "length_mm": a.length,
        })
    });
    json!({
        "rule": rule.name(),
        "labels": labels,
        "label_image": "regions.npy: per sensel 0 outside the footprint, else the region's label",
        "foot": axis,
        "bounds": {
            "length_fractions": LENGTH_BOUNDS,
            "metatarsal_width_fractions": METATARSAL_BOUNDS,
            "hallux_width_fraction": HALLUX_BOUND,
        },
        "regions": per,
    })
}

/// Writes the regions' files into `dir` ([`REGION_FILES`]: the CSV and the label image only
/// when the footprint was divided) and their figure `regions.png` (or `.svg`) as `kinds` says.
pub fn write_regions(
    dir: &OutDir,
    recording: &Recording,
    m: &Measures,
    rule: RegionRule,
    outcome: &RegionOutcome,
    kinds: FigureKinds,
) -> Result<()> {
    let json = crate::run_folder::pretty(&regions_json(m, rule, outcome));
    dir.write("regions.json", json.as_bytes())?;
    let Ok((masks, values)) = outcome else {
        return Ok(());
    };
    dir.write("regions.csv", regions_csv(m, values).as_bytes())?;
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
