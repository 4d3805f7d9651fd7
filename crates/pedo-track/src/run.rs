//! Whole recordings: the objects of every frame, matched pair by pair, chained into node tracks.
//!
//! This is the job of Tables 1–3 of Tavares & Bastos (2005): for a contour or surface model, the objects of
//! consecutive frames (paired by [`crate::pairing`]) are matched; for the isocontour model, the
//! isobaric contours of one frame are matched level after level (docs/method.md §9). Each matched pair
//! yields one [`PairRow`] with the paper's columns, and the matches are chained into [`Track`]s.

use crate::*;
use modal_core::Prealign;
use pedo_io::recording::Recording;
use pedo_io::{IoError, Result};
use std::collections::HashMap;
use std::time::Instant;

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
/// use pedo_track::{run_sequence, FrameRange, RunParams};
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
            pedo_io::counted(recording.n_frames(), "frame")
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
    pedo_io::cancel::check(options.cancel.as_ref())?;
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
    pedo_io::cancel::check(options.cancel.as_ref())?;
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
    let refs = crate::drift::reference_pairs_every(
        objects,
        candidates,
        start,
        options.drift_reference,
        options.frame_step(),
    );
    // Reference pairs lie frames apart: the sensor prior is for consecutive frames.
    let mut apart = options.clone();
    if apart.matching.prealign == Prealign::Sensor {
        apart.matching.prealign = Prealign::Robust;
    }
    let (matched, _) = match_all(objects, &refs, &HashMap::new(), &apart, &|_, _, _| {});
    matched
}

/// A run that found no object in any of its frames has nothing to match or report: an error
/// (no output is written), not an empty success. Every front end calls it after a run
/// (`objects` is the number of objects the run found), so the CLI, `batch` and Python agree.
pub fn require_objects(
    objects: usize,
    recording: &Recording,
    options: &SequenceOptions,
) -> Result<()> {
    if objects > 0 {
        return Ok(());
    }
    let (a, b) = options.frames.unwrap_or((0, recording.n_frames()));
    let min = options.min_nodes.max(3);
    if options.model == ObjectModel::Isocontour {
        let frame = match options.iso_frame {
            Some(f) => format!("frame {f}"),
            None => format!("the frame of largest load in {a}..{b}"),
        };
        return Err(IoError::no_object(format!(
            "no isobaric level of {frame} gives an object of at least {min} nodes: the levels run up to that frame's peak, so a single hot or stuck sensel can put them all above the foot (see the iso_frame and iso_levels options)"
        )));
    }
    Err(IoError::no_object(format!(
        "no object to match in frames {a}..{b}: no frame holds an object of at least {min} nodes above the noise threshold (see the noise and frames options)"
    )))
}
