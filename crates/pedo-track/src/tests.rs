//! Unit tests of the run engine that reach into its parts.

use crate::*;
use modal_core::{match_shapes, OptionValue, Shape};
use pedo_io::recording::{FrameMeasures, Recording};
use std::collections::HashMap;

#[test]
fn negative_frame_indices_count_back_from_the_end_as_in_a_python_slice() {
    let resolve = |s: &str, n: usize| s.parse::<FrameRange>().unwrap().resolve(n);
    assert_eq!(resolve("-50..", 205), Ok((155, 205)), "the last 50 frames");
    assert_eq!(resolve("0..-1", 205), Ok((0, 204)), "all but the last");
    assert_eq!(resolve("..-1", 205), Ok((0, 204)));
    assert_eq!(resolve("-10..-5", 205), Ok((195, 200)));
    assert_eq!(
        resolve("-205..", 205),
        Ok((0, 205)),
        "as far back as frame 0"
    );
    assert_eq!(resolve("3..-2", 6), Ok((3, 4)));
    assert_eq!(
        "-50..-1".parse::<FrameRange>().unwrap().to_string(),
        "-50..-1"
    );
    // Still out of range once resolved: an error naming the range, the frame count and
    // what the negative indices came to.
    let e = resolve("-300..", 205).unwrap_err();
    assert_eq!(e.option, "frames");
    assert_eq!(e.value, "-300..");
    assert!(
        e.expected.contains("205 frames") && e.expected.contains("-300.. is -95..205"),
        "{e}"
    );
    let e = resolve("0..-205", 205).unwrap_err().to_string();
    assert!(
        e.contains("0..-205 is 0..0") && e.contains("205 frames"),
        "{e}"
    );
    let e = resolve("-3..-5", 205).unwrap_err().to_string();
    assert!(e.contains("-3..-5 is 202..200"), "{e}");
    // Positive ranges are checked as before, their message with no resolution.
    let e = resolve("0..999", 205).unwrap_err().to_string();
    assert!(e.contains("205 frames") && !e.contains(" is "), "{e}");
    assert!(resolve("5..5", 205).is_err() && resolve("0..0", 0).is_err());
    assert!("x..-1".parse::<FrameRange>().is_err());
    assert!("--1..".parse::<FrameRange>().is_err());
}

#[test]
fn a_run_resolves_negative_frames_once_for_the_range_the_iso_frame_and_the_summary() {
    let rec = recording(6, |_, r, c| (8..16).contains(&r) && (8..16).contains(&c));
    let params = |frames: &str, iso_frame| RunParams {
        model: ObjectModel::Isocontour,
        frames: Some(frames.parse().unwrap()),
        iso_frame,
        ..RunParams::default()
    };
    let negative = params("-3..-1", None);
    let o = negative.to_options(&rec).unwrap();
    assert_eq!(o.frames, Some((3, 5)));
    assert_eq!(
        o.frames,
        params("3..5", None).to_options(&rec).unwrap().frames
    );
    // summary.json records the frames run, resolved.
    let used = negative.used(&o, &rec);
    let frames = used.iter().find(|(k, _)| *k == "frames").unwrap();
    assert_eq!(frames.1, OptionValue::Word("3..5".into()));
    // iso_frame lies within the resolved range; the error names it both ways.
    assert_eq!(
        params("-3..-1", Some(4))
            .to_options(&rec)
            .unwrap()
            .iso_frame,
        Some(4)
    );
    let e = params("-3..-1", Some(5))
        .to_options(&rec)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("iso_frame") && e.contains("3..5") && e.contains("frames -3..-1 of 6"),
        "{e}"
    );
    let e = params("-9..", None)
        .to_options(&rec)
        .unwrap_err()
        .to_string();
    assert!(e.contains("-9..") && e.contains("6 frames"), "{e}");
}

#[test]
fn a_study_lists_the_options_a_run_uses_with_each_recordings_own_left_open() {
    let mut params = RunParams {
        spacing: 1.5,
        ..RunParams::default()
    };
    let mut rec = recording(6, |_, r, c| (8..16).contains(&r) && (8..16).contains(&c));
    rec.noise_threshold = Some(2.0);
    let run = params.used(&params.to_options(&rec).unwrap(), &rec);
    let given = params.given().unwrap();
    let names = |v: &[(&'static str, OptionValue)]| v.iter().map(|(k, _)| *k).collect::<Vec<_>>();
    assert_eq!(
        names(&given),
        names(&run),
        "the same options, in the same order"
    );
    let value = |v: &[(&'static str, OptionValue)], k: &str| {
        v.iter()
            .find(|(n, _)| *n == k)
            .map(|(_, v)| v.clone())
            .unwrap()
    };
    assert_eq!(value(&given, "spacing"), OptionValue::Float(1.5));
    assert_eq!(value(&run, "noise"), OptionValue::Float(2.0));
    assert_eq!(
        value(&given, "noise"),
        OptionValue::Absent,
        "each file's own"
    );
    assert_eq!(value(&run, "frames"), OptionValue::Word("0..6".into()));
    assert_eq!(value(&given, "frames"), OptionValue::Word("0..".into()));
    params.noise = Some(5.0);
    params.units.units = Some(" N/cm2 ".into());
    let given = params.given().unwrap();
    assert_eq!(value(&given, "noise"), OptionValue::Float(5.0));
    assert_eq!(value(&given, "units"), OptionValue::Word("N/cm²".into()));
}

#[test]
fn the_default_stride_brings_a_fast_recording_to_the_matching_rate_and_no_slower_one() {
    let auto = |rate: f64, frames: usize, drift: usize| {
        FrameStride::Auto.resolve(Some(rate), frames, drift)
    };
    // Brute force: the smallest N with rate / N <= MATCH_RATE_HZ, each rate as 1 / dt reads it.
    for hz in [
        25.0, 31.25, 50.0, 100.0, 200.0, 250.0, 251.0, 300.0, 500.0, 750.0, 1000.0,
    ] {
        let rate = 1.0 / (1.0 / hz);
        let want = (1..).find(|n| hz / *n as f64 <= MATCH_RATE_HZ).unwrap();
        assert_eq!(auto(rate, 1000, 0), want, "{hz} Hz");
    }
    assert_eq!(auto(500.0, 300, 0), 2);
    assert_eq!(auto(1000.0, 300, 0), 4);
    assert_eq!(FrameStride::Auto.resolve(None, 300, 0), 1, "unknown rate");
    assert_eq!(FrameStride::Auto.resolve(Some(f64::NAN), 300, 0), 1);
    // Reference frames of drift correction stay frames run; a short run keeps two frames.
    assert_eq!(auto(500.0, 300, 25), 1);
    assert_eq!(auto(500.0, 300, 50), 2);
    assert_eq!(auto(1000.0, 300, 30), 3);
    assert_eq!(auto(1000.0, 3, 0), 2);
    assert_eq!(auto(500.0, 2, 0), 1);
    assert_eq!(auto(500.0, 1, 0), 1);
    // A stride given is kept as given.
    assert_eq!(FrameStride::Every(1).resolve(Some(500.0), 300, 0), 1);
    assert_eq!(FrameStride::Every(5).resolve(Some(100.0), 3, 0), 5);
    assert_eq!("auto".parse::<FrameStride>(), Ok(FrameStride::Auto));
    assert_eq!(" 4 ".parse::<FrameStride>(), Ok(FrameStride::Every(4)));
    assert!("fast".parse::<FrameStride>().is_err() && "-1".parse::<FrameStride>().is_err());
}

#[test]
fn a_500_hz_recording_runs_every_second_frame_by_default_and_every_frame_on_request() {
    let mut rec = recording(9, |f, r, c| disc(10.0 + 0.2 * f as f64, 12.0, 6.0)(r, c));
    rec.dt_s = Some(0.002);
    let run = |rec: &Recording, every| {
        let params = RunParams {
            every,
            ..RunParams::default()
        };
        let options = params.to_options(rec).unwrap();
        let used = params.used(&options, rec);
        let every = used.iter().find(|(k, _)| *k == "every").unwrap().1.clone();
        let run = run_sequence(rec, &options, &|_, _, _| {}).unwrap();
        let frames: Vec<usize> = run.objects.iter().map(|o| o.frame).collect();
        (frames, every)
    };
    let (auto, recorded) = run(&rec, FrameStride::Auto);
    assert_eq!(auto, [0, 2, 4, 6, 8]);
    assert_eq!(
        recorded,
        OptionValue::Int(2),
        "summary.json records the stride used"
    );
    assert_eq!(run(&rec, FrameStride::Every(2)).0, auto);
    assert_eq!(
        run(&rec, FrameStride::Every(1)).0,
        (0..9).collect::<Vec<_>>()
    );
    // At 100 Hz the default is every frame; a study lists it as given.
    rec.dt_s = Some(0.01);
    assert_eq!(
        run(&rec, FrameStride::Auto),
        ((0..9).collect(), OptionValue::Int(1))
    );
    let given = RunParams::default().given().unwrap();
    let every = given.iter().find(|(k, _)| *k == "every").unwrap();
    assert_eq!(every.1, OptionValue::Word("auto".into()));
    // The isocontour model matches one frame's levels: auto keeps every frame for its choice.
    rec.dt_s = Some(0.002);
    let iso = RunParams {
        model: ObjectModel::Isocontour,
        ..RunParams::default()
    };
    assert_eq!(iso.to_options(&rec).unwrap().every, 1);
}

/// A recording of `frames`, each drawn by `draw(frame, row, col) -> loaded`.
fn recording(frames: usize, draw: impl Fn(usize, usize, usize) -> bool) -> Recording {
    let (rows, cols) = (24, 24);
    let mut data = Vec::with_capacity(frames * rows * cols);
    for f in 0..frames {
        for r in 0..rows {
            for c in 0..cols {
                data.push(if draw(f, r, c) { 100.0 } else { 0.0 });
            }
        }
    }
    Recording::new(frames, rows, cols, data, vec![true; rows * cols]).unwrap()
}

fn disc(cx: f64, cy: f64, radius: f64) -> impl Fn(usize, usize) -> bool {
    move |r, c| (r as f64 - cy).hypot(c as f64 - cx) <= radius
}

#[test]
fn oblong_sensels_are_matched_in_their_true_proportions() {
    // An ellipse turning by 4° a frame on 7.62 × 5.08 mm sensels (footscan's).
    let mut rec = recording(5, |f, r, c| {
        let t = (4.0 * f as f64).to_radians();
        let (x, y) = (c as f64 - 11.5, (r as f64 - 11.5) * 1.5);
        let (u, v) = (x * t.cos() + y * t.sin(), -x * t.sin() + y * t.cos());
        (u / 9.0).powi(2) + (v / 15.0).powi(2) <= 1.0
    });
    rec.pitch_mm = Some([5.08, 7.62]);
    let options = RunParams::default().to_options(&rec).unwrap();
    assert!((options.sensel_aspect - 1.5).abs() < 1e-12);
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    assert_eq!(run.pairs.len(), 4);
    let scaled = |s: &Shape| SenselAspect(1.5).shape(s).unwrap().into_owned();
    for p in &run.pairs {
        let (a, b) = (&run.objects[p.a].shape, &run.objects[p.b].shape);
        // The pairs of the shapes in true proportions, to the bit.
        let truth = match_shapes(&scaled(a), &scaled(b), &options.matching).unwrap();
        assert_eq!(p.result.pairs, truth.pairs);
        // The transform and the aligned nodes are in sensels, and agree.
        let moved = p.result.transform.apply(a.coords());
        for (m, q) in moved.iter().zip(&p.result.aligned_a) {
            assert!((m - q).abs() < 1e-9, "{m} {q}");
        }
        let back = SenselAspect(1.5).back(truth);
        assert_eq!(back.transform, p.result.transform);
    }
    // Square sensels are matched as they are.
    rec.pitch_mm = Some([5.08, 5.08]);
    assert_eq!(
        RunParams::default().to_options(&rec).unwrap().sensel_aspect,
        1.0
    );
}

#[test]
fn each_foot_of_a_recording_of_both_has_its_own_measures() {
    // Two feet side by side, unevenly loaded: each object's measures are those of its own
    // sensors, and together they are the frame's.
    let (left, right) = (disc(6.0, 11.0, 4.0), disc(17.0, 12.0, 5.0));
    let mut rec = recording(3, |_, r, c| left(r, c) || right(r, c));
    let mut data = rec.data().to_vec();
    for (i, v) in data.iter_mut().enumerate() {
        let (r, c) = ((i % 576) / 24, i % 24);
        if right(r, c) {
            *v = 40.0 + c as f32;
        }
    }
    rec = Recording::new(3, 24, 24, data, vec![true; 576]).unwrap();
    for options in [
        SequenceOptions::default(),
        SequenceOptions {
            model: ObjectModel::Isocontour,
            ..SequenceOptions::default()
        },
    ] {
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        if options.model == ObjectModel::Isocontour {
            // The largest region of the lowest level: both feet are one level's regions, so
            // the object is the larger foot alone.
            let m = run.objects[0].measures.as_ref().unwrap();
            let n = (0..576).filter(|&i| right(i / 24, i % 24)).count();
            assert_eq!(m.contact_sensors, n);
            continue;
        }
        let frame = &rec.measures(0.0)[0];
        let objects: Vec<_> = run.objects.iter().filter(|o| o.frame == 0).collect();
        assert_eq!(objects.len(), 2);
        let m: Vec<&FrameMeasures> = objects
            .iter()
            .map(|o| o.measures.as_ref().unwrap())
            .collect();
        let foot = |inside: &dyn Fn(usize, usize) -> bool| {
            let cells = (0..576).filter(|&i| inside(i / 24, i % 24));
            let (n, load, peak, x) = cells.fold((0, 0.0, 0.0f64, 0.0), |(n, l, p, x), i| {
                let v = f64::from(rec.data()[i]);
                (n + 1, l + v, p.max(v), x + v * (i % 24) as f64)
            });
            (n, load, peak, x / load)
        };
        // The larger (right) foot comes first.
        for (m, inside) in m
            .iter()
            .zip([&right as &dyn Fn(usize, usize) -> bool, &left])
        {
            let (n, load, peak, cop_x) = foot(inside);
            assert_eq!(m.contact_sensors, n);
            assert!((m.total_force - load).abs() < 1e-9 * load);
            assert_eq!(m.peak_pressure, peak);
            assert!((m.cop.unwrap()[0] - cop_x).abs() < 1e-9);
        }
        assert_eq!(
            m[0].contact_sensors + m[1].contact_sensors,
            frame.contact_sensors
        );
        assert!((m[0].total_force + m[1].total_force - frame.total_force).abs() < 1e-9);
        assert_eq!(
            m[0].peak_pressure.max(m[1].peak_pressure),
            frame.peak_pressure
        );
    }
    // Surfaces: one object per frame, the frame's measures.
    let surface = SequenceOptions {
        model: ObjectModel::Surface,
        ..SequenceOptions::default()
    };
    let run = run_sequence(&rec, &surface, &|_, _, _| {}).unwrap();
    assert!(run.objects.iter().all(|o| o.measures.is_none()));
}

#[test]
fn a_run_without_match_details_has_the_same_matches_rows_and_tracks() {
    let rec = recording(6, |f, r, c| {
        disc(9.0 + f as f64 * 0.7, 11.0, 5.0 + 0.2 * f as f64)(r, c)
    });
    let full = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
    let lean_options = SequenceOptions {
        keep_match_details: false,
        ..Default::default()
    };
    let lean = run_sequence(&rec, &lean_options, &|_, _, _| {}).unwrap();
    assert_eq!(full.pairs.len(), 5);
    assert_eq!(lean.pairs.len(), full.pairs.len());
    for (f, l) in full.pairs.iter().zip(&lean.pairs) {
        assert_eq!(f.row, l.row);
        assert_eq!(f.result.pairs, l.result.pairs);
        assert_eq!(f.result.unmatched_a, l.result.unmatched_a);
        assert!(f.result.affinity.rows() > 0);
        assert_eq!(l.result.affinity.rows(), 0);
        assert!(l.result.aligned_a.is_empty());
    }
    assert!(full.packed_tracks.is_none() && lean.tracks.is_empty());
    assert!(full.tracks.len() > 5);
    assert_eq!(lean.track_count(), full.tracks.len());
    let unpacked: Vec<Track> = lean.all_tracks().map(|t| t.into_owned()).collect();
    assert_eq!(unpacked, full.tracks);
    assert!(lean
        .track_lengths()
        .eq(full.tracks.iter().map(|t| t.steps.len())));
}

#[test]
fn streamed_tracks_equal_those_chained_whole_on_a_real_walk() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    );
    let rec = pedo_io::read_recording(path).unwrap();
    let options = SequenceOptions {
        // Stance and swing, with the splits and merges of heel strike and toe-off.
        frames: Some((0, 120)),
        keep_match_details: false,
        ..Default::default()
    };
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    // Every node's track held to the end: drift correction's chaining with no reference pairs.
    let want = crate::drift::anchored_tracks(&run.objects, &run.pairs, &[]).unwrap();
    assert!(want.len() > 100 && want.iter().any(|t| t.steps.len() >= 10));
    assert!(!run.splits.is_empty() || !run.merges.is_empty());
    assert_eq!(chain_tracks(&run.objects, &run.pairs).unwrap(), want);
    let packed: Vec<Track> = run.all_tracks().map(|t| t.into_owned()).collect();
    assert_eq!(packed, want);
}

#[test]
fn a_bad_surface_option_is_each_frames_reason_not_a_frame_without_contact() {
    let rec = recording(3, |f, r, c| disc(11.0 + f as f64 * 0.5, 11.0, 6.0)(r, c));
    let mut options = SequenceOptions {
        model: ObjectModel::Surface,
        ..Default::default()
    };
    options.surface.max_nodes = Some(2);
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    assert!(run.objects.is_empty());
    assert_eq!(run.skipped_frames.len(), 3);
    for s in &run.skipped_frames {
        assert!(
            s.reason.contains("max_nodes must be at least 3"),
            "{}",
            s.reason
        );
    }
}

#[test]
fn chaining_a_pair_that_goes_back_or_names_missing_nodes_is_an_error() {
    let rec = recording(3, |f, r, c| disc(11.0 + f as f64 * 0.5, 11.0, 6.0)(r, c));
    let run = run_sequence(&rec, &SequenceOptions::default(), &|_, _, _| {}).unwrap();
    assert_eq!(chain_tracks(&run.objects, &run.pairs).unwrap(), run.tracks);
    let mut back = run.pairs.clone();
    back[1].b = 0;
    let e = chain_tracks(&run.objects, &back).unwrap_err().to_string();
    assert!(e.contains("pair 1 → 0 does not lead forward"), "{e}");
    let mut beyond = run.pairs.clone();
    beyond[0].b = 7;
    let e = chain_tracks(&run.objects, &beyond).unwrap_err().to_string();
    assert!(e.contains("does not lead forward onto objects 0..3"), "{e}");
    let mut node = run.pairs.clone();
    let n = run.objects[1].shape.len();
    node[0].result.pairs[0].b = n;
    node[0].result.pairs[0].excess = false;
    let e = chain_tracks(&run.objects, &node).unwrap_err().to_string();
    assert!(
        e.contains("beyond the objects'") && e.contains(&format!("and {n} nodes")),
        "{e}"
    );
    // Drift-corrected chaining reports the same errors, as pairs or as reference pairs.
    let anchored = |pairs: &[PairMatch], refs: &[PairMatch]| {
        crate::drift::anchored_tracks(&run.objects, pairs, refs)
            .unwrap_err()
            .to_string()
    };
    assert!(anchored(&back, &[]).contains("pair 1 → 0 does not lead forward"));
    assert!(anchored(&run.pairs, &beyond).contains("onto objects 0..3"));
    assert!(anchored(&node, &[]).contains(&format!("and {n} nodes")));
}

#[test]
fn a_pair_that_cannot_be_matched_is_skipped_with_its_reason() {
    let rec = recording(4, |f, r, c| disc(11.0 + f as f64 * 0.5, 11.0, 6.0)(r, c));
    let options = SequenceOptions::default();
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    assert_eq!(run.pairs.len(), 3);
    assert!(run.skipped_pairs.is_empty() && run.skipped_frames.is_empty());
    // Object 2 gets two coincident nodes, as an outline touching itself has.
    let mut objects = run.objects.clone();
    let shape = &objects[2].shape;
    let mut coords = shape.coords().to_vec();
    coords[2] = coords[0];
    coords[3] = coords[1];
    objects[2].shape = Shape::new(2, coords, shape.topology().clone()).unwrap();
    let candidates = [(0, 1), (1, 2), (2, 3)];
    let (pairs, skipped) = match_all(
        &objects,
        &candidates,
        &HashMap::new(),
        &options,
        &|_, _, _| {},
    );
    assert_eq!(
        pairs.iter().map(|p| (p.a, p.b)).collect::<Vec<_>>(),
        vec![(0, 1)]
    );
    assert_eq!(
        skipped.iter().map(|s| (s.a, s.b)).collect::<Vec<_>>(),
        vec![(1, 2), (2, 3)]
    );
    assert!(
        skipped.iter().all(|s| s.reason.contains("coincide")),
        "{skipped:?}"
    );
    // The tracks of what was matched are still chained.
    assert!(!chain_tracks(&objects, &pairs).unwrap().is_empty());
}

/// The order of a run's events, as a sink that follows objects frame by frame relies on it.
#[derive(Default)]
struct EventOrder {
    frames: Vec<usize>,
    objects: Vec<usize>,
    /// The frames handed over when each pair came.
    frames_at_pair: Vec<(usize, Option<usize>)>,
    tracks: Vec<usize>,
}

impl SequenceSink for EventOrder {
    fn frame_objects(&mut self, frame: usize, objects: &[SequenceObject]) -> pedo_io::Result<()> {
        assert!(objects.iter().all(|o| o.frame == frame));
        self.frames.push(frame);
        self.objects.extend(objects.iter().map(|o| o.id));
        Ok(())
    }
    fn pair(
        &mut self,
        _: &PairMatch,
        _: &SequenceObject,
        b: &SequenceObject,
    ) -> pedo_io::Result<()> {
        self.frames_at_pair
            .push((b.frame, self.frames.last().copied()));
        Ok(())
    }
    fn track(
        &mut self,
        index: usize,
        _: &[(&SequenceObject, usize)],
        _: Option<f64>,
    ) -> pedo_io::Result<()> {
        self.tracks.push(index);
        Ok(())
    }
}

#[test]
fn the_engine_hands_every_frame_in_order_before_the_pairs_that_end_on_it() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    );
    let rec = pedo_io::read_recording(path).unwrap();
    // Three windows of frames, with frames without contact at the end of the step.
    let options = SequenceOptions {
        frames: Some((10, 10 + 2 * pedo_io::recording::FRAME_WINDOW + 20)),
        keep_match_details: false,
        ..Default::default()
    };
    let mut events = EventOrder::default();
    let counts = stream_sequence(&rec, None, &options, &|_, _, _| {}, &mut events).unwrap();
    let (start, end) = options.frames.unwrap();
    assert_eq!(events.frames, (start..end).collect::<Vec<_>>());
    assert_eq!(events.objects, (0..counts.objects).collect::<Vec<_>>());
    assert_eq!(events.frames_at_pair.len(), counts.pairs);
    assert!(events
        .frames_at_pair
        .iter()
        .all(|&(frame, handed)| handed.is_some_and(|h| h >= frame)));
    assert_eq!(events.tracks, (0..counts.tracks).collect::<Vec<_>>());
    // The whole run is this engine gathered: the same objects, pairs and tracks.
    let whole = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    assert_eq!(whole.objects.len(), counts.objects);
    assert_eq!(whole.pairs.len(), counts.pairs);
    assert_eq!(whole.track_count(), counts.tracks);
}

#[test]
fn a_strided_run_builds_and_pairs_its_kept_frames_across_windows() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    );
    let rec = pedo_io::read_recording(path).unwrap();
    // A stride that does not divide the window: the kept frames fall at other places of each.
    let options = SequenceOptions {
        frames: Some((10, 10 + 2 * pedo_io::recording::FRAME_WINDOW + 20)),
        every: 3,
        keep_match_details: false,
        ..Default::default()
    };
    assert!(streams(&options), "a strided run streams");
    let (start, end) = options.frames.unwrap();
    let mut events = EventOrder::default();
    let counts = stream_sequence(&rec, None, &options, &|_, _, _| {}, &mut events).unwrap();
    assert_eq!(events.frames, options.kept_frames(start, end));
    assert_eq!(events.objects, (0..counts.objects).collect::<Vec<_>>());
    let whole = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    assert!(whole.objects.iter().all(|o| (o.frame - start) % 3 == 0));
    // Every pair joins kept frames 3 apart, those across a window's edge too.
    assert!(whole.pairs.len() > 20);
    for p in &whole.pairs {
        let (fa, fb) = (whole.objects[p.a].frame, whole.objects[p.b].frame);
        assert_eq!(fb, fa + 3, "pair {} -> {}", p.a, p.b);
    }
    let edge = start + pedo_io::recording::FRAME_WINDOW;
    assert!(whole.pairs.iter().any(|p| {
        let (fa, fb) = (whole.objects[p.a].frame, whole.objects[p.b].frame);
        fa < edge && fb >= edge
    }));
}

/// A recording of `frames` on a 24 × 24 grid, each sensel's value `value(frame, row, col)`.
fn graded(frames: usize, value: impl Fn(usize, usize, usize) -> f32) -> Recording {
    let (rows, cols) = (24, 24);
    let mut data = Vec::with_capacity(frames * rows * cols);
    for f in 0..frames {
        for r in 0..rows {
            for c in 0..cols {
                data.push(value(f, r, c));
            }
        }
    }
    Recording::new(frames, rows, cols, data, vec![true; rows * cols]).unwrap()
}

/// A pressure dome of `peak` at its centre (`cx`, `cy`), falling to half the peak at `radius`
/// and to nothing beyond it.
fn dome(cx: f64, cy: f64, radius: f64, peak: f64) -> impl Fn(usize, usize) -> f32 {
    move |r, c| {
        let d = (r as f64 - cy).hypot(c as f64 - cx);
        if d <= radius {
            (peak * (1.0 - 0.5 * d / radius)) as f32
        } else {
            0.0
        }
    }
}

/// The frames a track passes from and to, step by step.
fn track_frame_steps(run: &SequenceResult) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for t in run.all_tracks() {
        for w in t.steps.windows(2) {
            out.push((run.objects[w[0].0].frame, run.objects[w[1].0].frame));
        }
    }
    out
}

fn surface_run(rec: &Recording) -> SequenceResult {
    let params = RunParams {
        model: ObjectModel::Surface,
        ..RunParams::default()
    };
    let options = params.to_options(rec).unwrap();
    run_sequence(rec, &options, &|_, _, _| {}).unwrap()
}

#[test]
fn a_surface_whose_support_jumps_ends_its_tracks() {
    // Frames 0–2 load the left of the plate, frames 3–5 the right, 14 sensels on: nothing of
    // frame 2's footprint is loaded in frame 3, and the modal matching still pairs every node.
    let rec = graded(6, |f, r, c| {
        let x = if f < 3 { 5.0 } else { 19.0 };
        dome(x, 12.0, 3.5, 100.0)(r, c)
    });
    let run = surface_run(&rec);
    assert_eq!(run.pairs.len(), 5);
    let jump = run
        .pairs
        .iter()
        .find(|p| run.objects[p.a].frame == 2)
        .unwrap();
    assert!(jump.row.optimisation_matches > 10);
    assert_eq!(jump.row.trackable_matches, 0, "{:?}", jump.row);
    assert!(jump.trackable.iter().all(|t| !t));
    let steps = track_frame_steps(&run);
    assert!(!steps.contains(&(2, 3)), "a track crossed the jump");
    // The still frames either side keep their tracks.
    assert!(steps.contains(&(0, 1)) && steps.contains(&(4, 5)));
    for p in run.pairs.iter().filter(|p| run.objects[p.a].frame != 2) {
        assert!(p.row.trackable_percent > 90.0, "{:?}", p.row);
    }
}

#[test]
fn a_moving_surface_keeps_its_tracks() {
    // A dome sliding one sensel a frame to the right: its footprint moves with it.
    let rec = graded(6, |f, r, c| dome(7.0 + f as f64, 12.0, 4.5, 100.0)(r, c));
    let run = surface_run(&rec);
    assert_eq!(run.pairs.len(), 5);
    for p in &run.pairs {
        assert!(p.row.trackable_percent > 50.0, "{:?}", p.row);
    }
    // Some tracks run through every frame.
    let longest = run.all_tracks().map(|t| t.steps.len()).max().unwrap();
    assert_eq!(longest, 6);
}

#[test]
fn an_isocontour_level_whose_largest_region_switches_starts_new_tracks() {
    // One frame: a broad low region on the left (the largest region of the low levels) and a
    // small high peak on the right, the only region of the high levels.
    let broad = dome(7.0, 12.0, 6.0, 40.0);
    let peak = dome(18.0, 12.0, 3.5, 100.0);
    let rec = graded(1, |_, r, c| broad(r, c) + peak(r, c));
    let params = RunParams {
        model: ObjectModel::Isocontour,
        ..RunParams::default()
    };
    let mut options = params.to_options(&rec).unwrap();
    options.iso_levels = Some(vec![10.0, 16.0, 22.0, 60.0, 70.0]);
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    assert_eq!(run.objects.len(), 5);
    assert_eq!(run.pairs.len(), 4);
    // The largest region of levels 0–2 is on the left, of levels 3–4 on the right.
    let x = |o: usize| {
        let s = &run.objects[o].shape;
        (0..s.len()).map(|k| s.point(k)[0]).sum::<f64>() / s.len() as f64
    };
    assert!(x(2) < 12.0 && x(3) > 12.0, "{} {}", x(2), x(3));
    for p in &run.pairs {
        let switched = p.a == 2;
        if switched {
            assert_eq!(p.row.trackable_matches, 0, "{:?}", p.row);
        } else {
            assert!(p.row.trackable_matches > 0, "{:?}", p.row);
        }
    }
    // No track passes from level 2 to level 3; tracks do continue between the other levels.
    let levels: Vec<Vec<usize>> = run
        .all_tracks()
        .map(|t| t.steps.iter().map(|s| s.0).collect())
        .collect();
    assert!(!levels.iter().any(|l| l.windows(2).any(|w| w == [2, 3])));
    assert!(levels.iter().any(|l| l.windows(2).any(|w| w == [0, 1])));
    assert!(levels.iter().any(|l| l.windows(2).any(|w| w == [3, 4])));
}

/// A sink that wants the frames' values: which frames came, and their sum.
#[derive(Default)]
struct Values {
    frames: Vec<usize>,
    sums: Vec<f64>,
}

impl SequenceSink for Values {
    fn wants_frame_values(&self) -> bool {
        true
    }
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> pedo_io::Result<()> {
        self.frames.push(frame);
        self.sums.push(values.iter().map(|&v| f64::from(v)).sum());
        Ok(())
    }
}

#[test]
fn every_frame_of_the_range_is_handed_to_a_sink_that_wants_values_strided_or_replayed() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    );
    let rec = pedo_io::read_recording(path).unwrap();
    let (start, end) = (7, 7 + pedo_io::recording::FRAME_WINDOW + 30);
    let options = SequenceOptions {
        frames: Some((start, end)),
        every: 3,
        keep_match_details: false,
        ..Default::default()
    };
    let want: Vec<f64> = (start..end)
        .map(|t| rec.frame(t).unwrap().data().iter().sum())
        .collect();
    let mut streamed = Values::default();
    stream_sequence(&rec, None, &options, &|_, _, _| {}, &mut streamed).unwrap();
    assert_eq!(streamed.frames, (start..end).collect::<Vec<_>>());
    assert_eq!(streamed.sums, want);
    let whole = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    let mut replayed = Values::default();
    replay(&rec, &options, &whole, &mut replayed).unwrap();
    assert_eq!(replayed.frames, streamed.frames);
    assert_eq!(replayed.sums, want);
}

#[test]
fn pairs_of_identical_shapes_take_the_first_ones_outcome_bit_for_bit() {
    // A disc that holds still for frames on end, as a 500 Hz recording does between moves.
    let at = [0.0, 0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0, 0.0, 0.0, 0.0];
    let rec = recording(at.len(), |f, r, c| disc(10.0 + at[f], 11.0, 6.0)(r, c));
    let options = SequenceOptions {
        keep_match_details: true,
        ..SequenceOptions::default()
    };
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    let objects = &run.objects;
    let candidates: Vec<(usize, usize)> = (1..objects.len()).map(|b| (b - 1, b)).collect();
    let none = HashMap::new();
    let same = crate::matching::same_shapes(objects, &candidates);
    let first = crate::matching::first_of_same(&candidates, &same, &none);
    // Frames 0–2 and 8–10 are one shape, 3–5 another: pairs 1, 8 and 9 repeat pair 0, pair 4
    // repeats pair 3.
    assert_eq!(first, [0, 0, 2, 3, 3, 5, 6, 7, 0, 0]);
    let (pairs, skipped) = match_all(objects, &candidates, &none, &options, &|_, _, _| {});
    assert!(skipped.is_empty());
    assert_eq!(pairs.len(), candidates.len());
    for (p, &(a, b)) in pairs.iter().zip(&candidates) {
        // The pair matched on its own, its objects prepared for it alone.
        let (alone, _) = match_all(objects, &[(a, b)], &none, &options, &|_, _, _| {});
        assert_eq!(
            format!("{p:?}"),
            format!("{:?}", alone[0]),
            "pair {a} → {b}"
        );
        // And the matcher called on the two shapes, nothing prepared or shared.
        let (sa, sb) = (&objects[a].shape, &objects[b].shape);
        let truth = match_shapes(sa, sb, &options.matching).unwrap();
        assert_eq!(
            format!("{:?}", p.result),
            format!("{truth:?}"),
            "pair {a} → {b}"
        );
    }
}

#[test]
fn a_shape_key_tells_apart_what_equal_values_do_not() {
    use crate::matching::ShapeKey;
    use modal_core::Topology;
    let shape = |c: Vec<f64>, t: Topology| Shape::new(2, c, t).unwrap();
    let xy = vec![0.0, 0.0, 2.0, 0.0, 0.0, 2.0];
    let key = |c: &[f64], t: Topology| ShapeKey::of(&shape(c.to_vec(), t));
    assert_eq!(key(&xy, Topology::None), key(&xy, Topology::None));
    let mut negative = xy.clone();
    negative[0] = -0.0;
    assert_eq!(
        shape(negative.clone(), Topology::None),
        shape(xy.clone(), Topology::None)
    );
    assert_ne!(key(&negative, Topology::None), key(&xy, Topology::None));
    assert_ne!(key(&xy, Topology::ClosedContour), key(&xy, Topology::None));
    let mesh = |t: [usize; 3]| Topology::Mesh { triangles: vec![t] };
    assert_ne!(key(&xy, mesh([0, 1, 2])), key(&xy, mesh([0, 2, 1])));
    let mut moved = xy.clone();
    moved[5] = f64::from_bits(2.0f64.to_bits() + 1);
    assert_ne!(key(&moved, Topology::None), key(&xy, Topology::None));
}
