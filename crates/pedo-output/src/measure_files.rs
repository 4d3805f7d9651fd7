//! The measures of a run's recording in its folder ([`pedo_io::measures`]): `peak.npy`,
//! `pti.npy`, `mean.npy` (float64 images, rows × columns of the frames, NaN where there is no
//! sensor), `measures.json` (each value with its unit, and how the contact time was found), the
//! figure `pti.png` (or `.svg`; the peak-pressure figure, with the contact outlines, is a summary figure of the run folder), and the values in `summary.json`'s `measures`.

use crate::figure::{FigureAxes, MeasureFigure, MeasureImage};
use crate::outdir::OutDir;
use crate::run_folder::{write_figure, FigureKinds};
use pedo_io::formats::npy::image_to_npy;
use pedo_io::measures::{Measures, RecordingMeasures, CONTACT_FORCE_FRACTION};
use pedo_io::{Recording, Result};
use pedo_track::{SequenceOptions, SequenceSink};
use serde_json::{json, Map, Value};

/// The files of a run folder's measures besides its figures.
pub const MEASURE_FILES: [&str; 4] = ["peak.npy", "pti.npy", "mean.npy", "measures.json"];

/// A sink that takes the measures of a run's frames as the engine hands them (every frame of
/// the run's range, [`SequenceSink::frame_values`]).
pub struct MeasuresSink {
    measures: RecordingMeasures,
}

impl MeasuresSink {
    /// The measures of a run of `recording` with `options`: a sensel is loaded at or above the
    /// run's noise threshold, as in the frames table.
    pub fn new(recording: &Recording, options: &SequenceOptions) -> Result<Self> {
        let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
        Ok(Self {
            measures: RecordingMeasures::new(recording, threshold)?,
        })
    }

    /// The measures of the frames handed ([`RecordingMeasures::finish`]).
    pub fn finish(self) -> Result<Measures> {
        self.measures.finish()
    }
}

impl SequenceSink for MeasuresSink {
    fn wants_frame_values(&self) -> bool {
        true
    }
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        self.measures.add_frame(frame, values)
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
