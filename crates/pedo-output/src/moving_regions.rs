//! The anatomical regions of a run that move with the foot ([`pedo_track::moving_regions`]):
//! their rows in `region_series.csv` beside the fixed masks', their values in `regions.csv`
//! (`kind` `moving`) and `regions.json` (`moving`).

use crate::run_tables::{region_series_row, RegionId};
use crate::table::Table;
use pedo_io::measures::Measures;
use pedo_io::recording::FootColumns;
use pedo_io::regions::Side;
use pedo_io::regions::{MovingRegionSeries, RegionMasks, RegionValues};
use pedo_io::stances::Stance;
use pedo_io::{IoError, Recording, Result};
use pedo_track::moving_regions::{follow_masks, MovingRegion};
use pedo_track::result::SkippedPair;
use pedo_track::{
    ObjectModel, PairMatch, RunParams, SequenceObject, SequenceOptions, SequenceResult,
    SequenceSink,
};
use serde_json::{json, Map, Value};
use std::borrow::Cow;

/// The anatomical regions carried through a run's stances and their values over its frames.
#[derive(Debug, Clone)]
pub struct MovingAnatomy {
    /// One per stance and region, in stance order, then label order.
    pub regions: Vec<MovingRegion>,
    /// Each region's values over the run's frames (0 force outside the stances), in the
    /// masks' label order, the share of the fixed regions' impulse.
    pub values: Vec<RegionValues>,
}

/// The moving regions of a run, or why there are none (a run not of contours, a footprint that
/// could not be divided).
pub type MovingOutcome = std::result::Result<MovingAnatomy, IoError>;

/// The regions of `masks` carried through each stance of `measures` by the contour field
/// ([`follow_masks`]), and their values over the frames of `measures` ([`MovingRegionSeries`]),
/// the shares of the impulse of the `fixed` regions' values. `options` are those of a contour
/// run of `recording` ([`pedo_track::RunParams::contour_options`] for a run of another model),
/// and the field is `run`, that contour run's objects and pairs, or, with `None` (a surface or
/// isocontour run, or a run whose objects and pairs were not kept), made here
/// ([`contour_field`]).
///
/// # Errors
/// Those of [`follow_masks`], [`contour_field`] and [`MovingRegionSeries`]; a frame the
/// recording does not hold.
pub fn follow_anatomy(
    recording: &Recording,
    run: Option<&SequenceResult>,
    options: &SequenceOptions,
    measures: &Measures,
    masks: &RegionMasks,
    fixed: &[RegionValues],
) -> Result<MovingAnatomy> {
    let made;
    let run = match run {
        Some(r) => r,
        None => {
            made = contour_field(recording, options)?;
            &made
        }
    };
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let regions = if masks.sides.is_empty() {
        let stances: Vec<Stance> = measures.stances.iter().map(|s| s.stance).collect();
        follow_masks(run, options, recording, masks, &stances, threshold, None)?
    } else {
        // Each foot's regions through its own stances, on its own insole.
        let mut all = Vec::new();
        for foot in &measures.feet {
            let stances: Vec<Stance> = (foot.measures.stances.iter()).map(|s| s.stance).collect();
            let columns = FootColumns {
                side: foot.side,
                columns: foot.columns.clone(),
            };
            all.extend(follow_masks(
                run,
                options,
                recording,
                masks,
                &stances,
                threshold,
                Some(&columns),
            )?);
        }
        all
    };
    let (rows, cols) = (recording.rows(), recording.cols());
    let mut series = MovingRegionSeries::new(recording, threshold, &masks.names)?;
    for t in measures.frames.clone() {
        let values = recording
            .frame_slice(t)
            .ok_or_else(|| IoError::invalid(format!("frame {t} is not held to measure on")))?;
        let shares: Vec<Option<Vec<f64>>> = (1..=masks.names.len())
            .map(|label| {
                let r = regions.iter().find(|r| {
                    usize::from(r.label) == label && (r.frames.0..=r.frames.1).contains(&t)
                })?;
                r.shares(t, rows, cols)
            })
            .collect();
        series.add_frame(&values, &shares)?;
    }
    let values = if masks.sides.is_empty() {
        series.finish(fixed.iter().map(|v| v.fti).sum())?
    } else {
        // A foot's moving regions share its fixed regions' impulse.
        let foot_total = |side: Option<Side>| -> f64 {
            (fixed.iter())
                .filter(|v| v.foot == side)
                .map(|v| v.fti)
                .sum()
        };
        let feet: Vec<Option<Side>> = (1..=masks.names.len())
            .map(|k| masks.side_of(k as u8))
            .collect();
        let totals: Vec<f64> = feet.iter().map(|&f| foot_total(f)).collect();
        series.finish_each(&totals, &feet)?
    };
    Ok(MovingAnatomy { regions, values })
}

/// The options of the contour field that carries the anatomical regions of a run of
/// `recording` with `options` (made from `params`): a contour run's own (its objects and pairs
/// are the field); for a surface or isocontour run those of the contour run of its frames
/// ([`RunParams::contour_options`]), with the run's cancel token, keeping each pair's matches
/// only (what [`follow_masks`] reads).
///
/// # Errors
/// Those of [`RunParams::contour_options`].
pub fn carrying_options<'a>(
    params: &RunParams,
    recording: &Recording,
    options: &'a SequenceOptions,
) -> Result<Cow<'a, SequenceOptions>> {
    if options.model == ObjectModel::Contour {
        return Ok(Cow::Borrowed(options));
    }
    let mut o = params.contour_options(recording)?;
    o.cancel = options.cancel.clone();
    o.keep_match_details = false;
    Ok(Cow::Owned(o))
}

/// The contour field of `recording`: the objects and pairs of its contour run with `options`
/// ([`carrying_options`]), what carries the anatomical regions of a surface or isocontour run
/// (made only when regions are asked). Only what [`follow_masks`] reads is kept: the objects,
/// each pair's matches and the pairs skipped; the tracks and the pairs' match details are
/// dropped as the run hands them over.
///
/// # Errors
/// [`IoError::InvalidInput`] for options not of the contour model; those of
/// [`pedo_track::stream_sequence`] (a cancelled run among them).
pub fn contour_field(recording: &Recording, options: &SequenceOptions) -> Result<SequenceResult> {
    if options.model != ObjectModel::Contour {
        return Err(IoError::invalid(format!(
            "the regions are carried by the contour field, not by a {} run",
            options.model
        )));
    }
    let mut field = Field::default();
    let counts = pedo_track::stream_sequence(recording, None, options, &|_, _, _| {}, &mut field)?;
    field.0.skipped_pairs = (counts.skipped_pairs.into_iter())
        .map(|s| SkippedPair {
            a: s.objects.id_a,
            b: s.objects.id_b,
            reason: s.reason,
        })
        .collect();
    Ok(field.0)
}

/// Gathers a contour run's field ([`contour_field`]) as the engine hands it over: its objects
/// and its pairs without their match details (the pairs skipped come with the run's counts).
#[derive(Default)]
struct Field(SequenceResult);

impl SequenceSink for Field {
    fn frame_objects(&mut self, _: usize, objects: &[SequenceObject]) -> Result<()> {
        self.0.objects.extend_from_slice(objects);
        Ok(())
    }
    fn pair(&mut self, pair: &PairMatch, _: &SequenceObject, _: &SequenceObject) -> Result<()> {
        self.0.pairs.push(pair.without_details()?);
        Ok(())
    }
}

/// Appends to `t` ([`crate::region_series_header`]) the rows of the moving anatomical regions:
/// for each stance, region and frame of the stance, `kind` `moving` (the share of each sensel the
/// region's followed outlines cover; empty measures on a frame it was not followed to) and `fixed`
/// (the mask drawn on the peak image, left in place), with the region's label, `name` and
/// `stance`. A region off the contact has 0 force, not a missing row.
///
/// # Errors
/// A frame the recording cannot give.
pub fn anatomy_rows(
    t: &mut Table,
    recording: &Recording,
    masks: &RegionMasks,
    moving: &MovingAnatomy,
    threshold: f64,
) -> Result<()> {
    let (rows, cols) = (recording.rows(), recording.cols());
    for r in &moving.regions {
        let fixed: Vec<f64> = (masks.labels.iter())
            .map(|&l| f64::from(u8::from(l == r.label)))
            .collect();
        for frame in r.frames.0..=r.frames.1 {
            let grid = recording.frame(frame)?;
            let shares = r.shares(frame, rows, cols);
            for (kind, cells) in [("moving", shares.as_deref()), ("fixed", Some(&fixed[..]))] {
                let id = RegionId {
                    label: usize::from(r.label),
                    kind,
                    name: Some(&r.name),
                    stance: Some(r.stance),
                    foot: r.foot,
                };
                let at = cells.map(|c| (&grid, c));
                t.rows
                    .push(region_series_row(recording, &id, frame, at, threshold));
            }
        }
    }
    Ok(())
}

/// `regions.json`'s `moving`: how the regions were carried (the reference frame's rule), each
/// stance's reference frame and per region its sensels there and parts (found, followed), and
/// each region's values with their units; or why there are none.
pub fn moving_json(m: &Measures, outcome: &MovingOutcome) -> Value {
    let moving = match outcome {
        Ok(found) => found,
        Err(e) => return json!({"error": e.to_string()}),
    };
    let mut stances: Vec<Value> = Vec::new();
    let mut last: Option<(Option<Side>, usize)> = None;
    for r in &moving.regions {
        if last != Some((r.foot, r.stance)) {
            last = Some((r.foot, r.stance));
            let mut stance = json!({
                "stance": r.stance,
                "frames": [r.frames.0, r.frames.1],
                "reference_frame": r.reference_frame,
                "regions": {},
            });
            if let Some(side) = r.foot {
                stance["foot"] = json!(side.name());
            }
            stances.push(stance);
        }
        if let Some(s) = stances.last_mut() {
            s["regions"][&r.name] = json!({
                "reference_sensels": r.reference_cells.iter().filter(|&&c| c).count(),
                "parts": r.parts.0,
                "parts_followed": r.parts.1,
            });
        }
    }
    let mut per: Map<String, Value> = Map::new();
    for q in crate::region_quantities(m, &moving.values) {
        let entry = per.entry(q.key()).or_insert_with(|| json!({}));
        entry[q.measure] = json!({"value": q.value, "unit": q.unit});
    }
    let mut out = json!({
        "rule": "each stance's frame of largest contact area is its reference frame; a region there is the mask's sensels in contact, each connected part followed by its outline forwards and backwards through the stance; on a frame the region is the sensels whose centres lie inside its followed outlines",
        "stances": stances,
        "regions": per,
    });
    if moving.regions.iter().any(|r| r.foot.is_some()) {
        out["feet"] = json!("each foot's regions through its own stances (numbered per foot, as curves.csv's), its reference frame the one of most sensels in contact on its insole, carried by its insole's contour objects only; its regions' impulse shares of its own fixed regions' impulse");
    }
    out
}
