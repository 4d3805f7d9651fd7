//! A run's options resolved against a real recording.

use pedo_io::read_recording;
use pedo_track::{FrameRange, ObjectModel, RunParams};

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::data;

#[test]
fn iso_frame_outside_the_frames_range_is_an_option_error_naming_both() {
    let rec = read_recording(data("synthetic-walk.lst")).unwrap();
    assert!(rec.n_frames() > 8);
    let params = |iso_frame| RunParams {
        model: ObjectModel::Isocontour,
        frames: Some(FrameRange {
            start: 3,
            end: Some(6),
        }),
        iso_frame: Some(iso_frame),
        ..Default::default()
    };
    for outside in [0, 2, 6, 8] {
        let e = params(outside).to_options(&rec).unwrap_err().to_string();
        assert!(
            e.contains("iso_frame") && e.contains(&outside.to_string()) && e.contains("3..6"),
            "{e}"
        );
        assert!(e.contains("frames"), "{e}");
    }
    for inside in 3..6 {
        let o = params(inside).to_options(&rec).unwrap();
        assert_eq!(o.iso_frame, Some(inside));
    }
}

#[test]
fn isocontours_keep_the_level_lines_order_unless_a_solver_is_given() {
    let solver = |model, solver| {
        let mut p = RunParams {
            model,
            ..Default::default()
        };
        p.matching.solver = solver;
        p.match_options().unwrap().method
    };
    use assign::Method::{JonkerVolgenant, Ordered};
    assert_eq!(solver(ObjectModel::Isocontour, None), Ordered);
    assert_eq!(
        solver(ObjectModel::Isocontour, Some(JonkerVolgenant)),
        JonkerVolgenant
    );
    assert_eq!(solver(ObjectModel::Contour, None), JonkerVolgenant);
    assert_eq!(solver(ObjectModel::Surface, None), JonkerVolgenant);
    // The paper's literal setting keeps its own solver.
    let mut paper = RunParams {
        model: ObjectModel::Isocontour,
        ..Default::default()
    };
    paper.matching.paper = true;
    assert_eq!(paper.match_options().unwrap().method, JonkerVolgenant);
}
