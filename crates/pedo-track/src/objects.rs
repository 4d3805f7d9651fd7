//! The objects of every frame: contours, brightness surfaces or isobaric contours, each with
//! its frame's measures, or the reason a frame has none.

use crate::*;
use modal_core::Shape;
use pedo_io::cancel::Cancel;
use pedo_io::contour::{contours, Contour};
use pedo_io::recording::{FrameMeasures, Recording};
use pedo_io::{IoError, Result};
use rayon::prelude::*;

/// A pressure of the file's `units` as the outputs state it: in kPa when the units say how,
/// else in the file's units ("units unknown" when it names none).
fn pressure_text(value: f64, units: &str) -> String {
    match pedo_io::recording::kpa_per_unit(units) {
        Some(k) => format!("{:.1} kPa", value * k),
        None if units.is_empty() => format!("{value:.1}, units unknown"),
        None => format!("{value:.1} {units}"),
    }
}

/// The objects of the isocontour model's frame (numbered from 0), the pairs of consecutive
/// levels to match (indices into the objects) and the levels that give no object.
pub(crate) struct Levels {
    pub(crate) objects: Vec<SequenceObject>,
    pub(crate) pairs: Vec<(usize, usize)>,
    pub(crate) skipped_frames: Vec<SkippedFrame>,
}

/// A contour's points in sensels (x = column, y = row), whatever units it was extracted in.
fn outline_in_sensels(
    c: &Contour,
    units: pedo_io::grid::CoordUnits,
) -> std::borrow::Cow<'_, [[f64; 2]]> {
    match units {
        pedo_io::grid::CoordUnits::Pixels => std::borrow::Cow::Borrowed(&c.points),
        pedo_io::grid::CoordUnits::Millimetres { dx_mm, dy_mm } => c
            .points
            .iter()
            .map(|p| [p[0] / dx_mm, p[1] / dy_mm])
            .collect(),
    }
}

/// An object's shape and the measures of the sensors inside its outline.
type MeasuredShape = (Shape, FrameMeasures);

/// A frame's outlines that make objects, and their shapes and measures.
pub(crate) type FrameObjects = (Vec<Contour>, Vec<MeasuredShape>);

/// The outer contours of frame `t` worth modelling, largest first (so object 0 of a frame is its
/// main region), each with its shape and the measures of the sensors inside it: only contours
/// that make a valid shape become objects.
pub(crate) fn frame_contours(
    recording: &Recording,
    t: usize,
    options: &SequenceOptions,
) -> Result<FrameObjects> {
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    // A frame held sparsely is contoured on the window of its values (the same contours): a
    // few loaded sensels on a large plate cost their window, and the whole frame is made only
    // for the measures of an object, if it has one.
    let window = recording
        .stored_values(t)
        .filter(|_| pedo_io::contour::window_gives_contours(&options.contour))
        .and_then(|s| s.window());
    let (found, frame) = match window {
        Some((w, origin)) => (
            pedo_io::contour::contours_of_window(&w, origin, &options.contour)?,
            None,
        ),
        None => {
            let frame = recording.frame(t)?;
            (contours(&frame, &options.contour)?, Some(frame))
        }
    };
    // Refused here, before a model of it is built: its matrices grow with the nodes' square.
    let most = options.matching.max_nodes;
    if let Some(c) = found.iter().find(|c| !c.hole && c.points.len() > most) {
        return Err(IoError::invalid(format!(
            "a contour of {} nodes is more than the {most} an object may have; a larger \
             --spacing (Python spacing=) makes fewer, or raise --max-nodes (Python max_nodes=)",
            c.points.len()
        )));
    }
    let kept: Vec<Contour> = found
        .into_iter()
        .filter(|c| !c.hole && c.points.len() >= options.min_nodes.max(3))
        .collect();
    if kept.is_empty() {
        return Ok(FrameObjects::default());
    }
    let frame = match frame {
        Some(f) => f,
        None => recording.frame(t)?,
    };
    let mut cs: Vec<(Contour, MeasuredShape)> = kept
        .into_iter()
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

/// The isobaric contours of one frame (the `iso_frame`, else the most loaded one) as objects,
/// each level paired with the next.
/// `progress` reports [`Stage::Objects`] in levels done.
pub(crate) fn isocontour_objects(
    recording: &Recording,
    options: &SequenceOptions,
    (start, end): (usize, usize),
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<Levels> {
    let mut built = Levels {
        objects: Vec::new(),
        pairs: Vec::new(),
        skipped_frames: Vec::new(),
    };
    let t = match options.iso_frame {
        Some(t) => t,
        None => (options.kept_frames(start, end).into_iter())
            .max_by(|&a, &b| frame_load(recording, a).total_cmp(&frame_load(recording, b)))
            .unwrap_or(start),
    };
    let frame = recording.frame(t)?;
    let base = match options.contour.preprocess.threshold {
        Some(th) => pedo_io::preprocess::threshold(&frame, th)?,
        None => frame.clone(),
    };
    let levels = match &options.iso_levels {
        Some(l) => l.clone(),
        None => pedo_io::isobar::even_levels(&base, options.iso_count),
    };
    let iso = pedo_io::isobar::IsoOptions {
        preprocess: options.contour.preprocess,
        resample: options.contour.resample,
        include_holes: false,
        ..Default::default()
    };
    for (index, &level) in levels.iter().enumerate() {
        let cs = pedo_io::isobar::isocontours(&frame, &[level], &iso)?;
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
        progress(Stage::Objects, index + 1, levels.len());
    }
    Ok(built)
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

/// `build(t)` for every frame of `frames` (a run's kept frames, in order), in parallel. A frame whose objects cannot be built is
/// recorded in `skipped` with its reason and gets no objects (`T::default()`); the run goes on.
/// Once `cancel` is cancelled the frames not started are not built, and the whole fails with
/// [`IoError::Cancelled`].
pub(crate) fn per_kept_frame<T: Send + Default>(
    frames: &[usize],
    skipped: &mut Vec<SkippedFrame>,
    cancel: Option<&Cancel>,
    build: impl Fn(usize) -> Result<T> + Sync,
) -> Result<Vec<T>> {
    let outcomes: Vec<Result<T>> = frames
        .par_iter()
        .map(|&t| {
            pedo_io::cancel::check(cancel)?;
            build(t)
        })
        .collect();
    pedo_io::cancel::check(cancel)?;
    Ok(frames
        .iter()
        .copied()
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
pub(crate) fn frame_surface(
    recording: &Recording,
    t: usize,
    threshold: f64,
    options: &SequenceOptions,
    keep: &dyn Fn(&Shape) -> bool,
) -> Result<Option<Shape>> {
    // A sparse frame of positive values is meshed on the window of its values (the same
    // surface, and the same largest value): its cost is its window's, not the plate's.
    let window = recording
        .stored_values(t)
        .filter(|s| s.all_positive() && pedo_io::surface::window_gives_surface(&options.surface))
        .and_then(|s| s.window());
    let made = match window {
        Some((w, origin)) => {
            if w.max() <= threshold {
                return Ok(None);
            }
            pedo_io::surface::surface_of_window(&w, origin, &options.surface)
        }
        None => {
            let frame = recording.frame(t)?;
            if frame.max() <= threshold {
                return Ok(None);
            }
            pedo_io::surface::surface(&frame, &options.surface)
        }
    };
    // Only "nothing there" is a frame without an object; a bad option or a mesh that failed is
    // that frame's skipped reason, so a run never ends on a bare "no object" that hides it.
    match made {
        Ok(s) => Ok(Some(s.to_shape()?).filter(|s| keep(s))),
        Err(IoError::NoObject(_)) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Sum of the frame's values: the load the isocontour model picks its frame by.
fn frame_load(recording: &Recording, t: usize) -> f64 {
    // A sparse frame of positive values sums to the same from its stored values alone.
    if let Some(stored) = recording.stored_values(t).filter(|s| s.all_positive()) {
        return stored.iter().fold(0.0, |sum, (_, v)| sum + v as f64);
    }
    recording
        .frame_slice(t)
        .map_or(0.0, |f| f.iter().map(|&v| v as f64).sum())
}
