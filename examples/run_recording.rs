//! Runs a whole recording through the library, as `pedomatch run` does without writing files:
//! the contours of frames 40..80 of the bundled walk (or of the file given as the first
//! argument), matched pair by pair and chained into node tracks.
//!
//! Run: `cargo run --release --example run_recording [-- FILE]`

use pedo_track::{run_sequence, RunParams};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/data/FrasP01L.asf")
        });
    let recording = pedo_io::read_recording(&path)?;

    // The defaults of `pedomatch run` (contour model, Gaussian element, global search), checked
    // against this recording; then frames 40..80 (0-based, end excluded).
    let mut options = RunParams::default().to_options(&recording)?;
    let end = recording.n_frames().min(80);
    options.frames = Some((end.saturating_sub(40), end));
    let result = run_sequence(&recording, &options, &|_, _, _| {})?;

    println!(
        "{} objects, {} matched pairs, {} tracks ({} spanning 3+ objects)",
        result.objects.len(),
        result.pairs.len(),
        result.tracks.len(),
        result.tracks.iter().filter(|t| t.steps.len() >= 3).count()
    );
    println!("frame_a frame_b nodes_a nodes_b local% optimisation% with_excess mean_cost");
    for p in result.pairs.iter().take(8) {
        let r = &p.row;
        println!(
            "{:7} {:7} {:7} {:7} {:6.1} {:13.1} {:11} {:9.4}",
            r.objects.frame_a,
            r.objects.frame_b,
            r.objects.nodes_a,
            r.objects.nodes_b,
            r.local_percent,
            r.optimisation_percent,
            r.matches_after_excess,
            r.mean_cost
        );
    }
    let longest = result.tracks.iter().max_by_key(|t| t.steps.len());
    if let Some(track) = longest {
        let points = result.track_points(track);
        let (first, last) = (&points[0], &points[points.len() - 1]);
        println!(
            "longest track: {} steps, frame {} at ({:.2}, {:.2}) to frame {} at ({:.2}, {:.2})",
            points.len(),
            first.0,
            first.1[0],
            first.1[1],
            last.0,
            last.1[0],
            last.1[1]
        );
    }
    println!(
        "time: objects {:.3} s, matching {:.3} s, tracks {:.3} s",
        result.timings.objects.as_secs_f64(),
        result.timings.matching.as_secs_f64(),
        result.timings.tracks.as_secs_f64()
    );
    Ok(())
}
