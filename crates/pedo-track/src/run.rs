//! Whole recordings: the objects of every frame, matched pair by pair, chained into node tracks.
//!
//! This is the job of Tables 1–3 of Tavares & Bastos (2005): for a contour or surface model, the objects of
//! consecutive frames (paired by [`crate::pairing`]) are matched; for the isocontour model, the
//! isobaric contours of one frame are matched level after level (docs/method.md §9). Each matched pair
//! yields one [`PairRow`] with the paper's columns, and the matches are chained into [`Track`]s.

use crate::*;
use pedo_io::recording::Recording;
use pedo_io::{IoError, Result};

/// Builds the objects of the recording, matches them pair by pair (in parallel) and chains the
/// matches into tracks, all held in the result: the run of [`stream_sequence`] gathered by a
/// [`Collect`] (one engine for whole and streamed runs). `progress(stage, done, total)` is
/// called as work completes, possibly from several threads (see [`stream_sequence`]).
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
    // The one engine, gathering what it hands over.
    let mut whole = Collect::new(options.keep_match_details);
    let counts = stream_sequence(recording, None, options, progress, &mut whole)?;
    Ok(whole.into_result(counts))
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
