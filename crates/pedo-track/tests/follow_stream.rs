//! Material points followed as a run streams (`FollowSink`, what a run folder writes) are the
//! points followed on the whole run made first (`run_points`): the same points in the same
//! order, every step the same to the bit, handed over in order with their frames; and the
//! objects the sink holds do not grow with the recording's length.

use modal_core::PathOrRows;
use pedo_io::synthetic::SyntheticWalk;
use pedo_io::{read_recording, Recording};
use pedo_track::follow::{run_points, FollowSink, FollowedPoint, PointsSink};
use pedo_track::{
    run_sequence, stream_sequence, FrameRange, RunInputs, RunParams, SequenceOptions, SequenceSink,
};

/// The points handed over, in the order handed, with their index and frames.
#[derive(Default)]
struct Handed(Vec<(usize, FollowedPoint, Vec<usize>)>);

impl PointsSink for Handed {
    fn point(&mut self, index: usize, p: &FollowedPoint, frames: &[usize]) -> pedo_io::Result<()> {
        self.0.push((index, p.clone(), frames.to_vec()));
        Ok(())
    }
}

/// The points streamed and the points of the whole run, compared; returns how many.
fn streamed_equals_whole(rec: &Recording, params: RunParams) -> usize {
    let options: SequenceOptions = params.to_options(rec).unwrap();
    let whole = run_sequence(rec, &options, &|_, _, _| {}).unwrap();
    let expected = run_points(&whole, &options)
        .unwrap()
        .expect("a contour run");
    let mut handed = Handed::default();
    let mut sink = FollowSink::new(&options, &mut handed);
    stream_sequence(
        rec,
        None,
        &options,
        &|_, _, _| {},
        &mut sink as &mut dyn SequenceSink,
    )
    .unwrap();
    sink.finish().unwrap();
    assert_eq!(handed.0.len(), expected.points.len());
    for (k, ((index, p, frames), e)) in handed.0.iter().zip(&expected.points).enumerate() {
        assert_eq!(*index, k, "handed over in order");
        assert_eq!(p, e, "point {k}");
        let truth: Vec<usize> = (e.steps.iter())
            .map(|&(o, _)| whole.objects[o].frame)
            .collect();
        assert_eq!(frames, &truth, "point {k}'s frames");
    }
    expected.points.len()
}

#[test]
fn points_followed_as_the_walk_streams_are_the_whole_runs() {
    let rec = read_recording(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    ))
    .unwrap();
    // Frames 30..110: heel strike to toe-off, with splits and merges (part_to_whole.rs).
    let params = RunParams {
        frames: Some(FrameRange {
            start: 30,
            end: Some(110),
        }),
        ..Default::default()
    };
    let n = streamed_equals_whole(&rec, params);
    assert!(n > 100, "{n} points");
}

#[test]
fn the_users_points_and_regions_streamed_are_the_whole_runs() {
    // Two windows of frames (64 and 36), so that points and the region cross a window's end.
    let walk = SyntheticWalk {
        frames: 100,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let c = walk.centre();
    let points = vec![vec![c[0], c[1] - 10.0], vec![c[0] + 2.0, c[1] + 12.0]];
    // A region of 5 × 5 sensels about the centre, drawn on frame 70 (in the second window).
    let mask: Vec<Vec<f64>> = (0..rec.rows())
        .map(|r| {
            (0..rec.cols())
                .map(|col| {
                    let inside = (r as f64 - c[1]).abs() <= 2.0 && (col as f64 - c[0]).abs() <= 2.0;
                    f64::from(u8::from(inside))
                })
                .collect()
        })
        .collect();
    let params = RunParams {
        inputs: RunInputs {
            points: Some(PathOrRows::Rows(points)),
            regions: Some(PathOrRows::Rows(mask)),
            regions_frame: Some(70),
            ..Default::default()
        },
        ..Default::default()
    };
    let n = streamed_equals_whole(&rec, params);
    assert!(n > 10, "{n} points");
}
