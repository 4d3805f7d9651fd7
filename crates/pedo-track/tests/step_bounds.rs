//! No track of the surface or isocontour model steps further than the physics allows
//! (docs/method.md §9), on the real F-Scan walk: every step checked against a bound computed
//! here on its own, by brute force over the next object's triangles or outline.

use modal_core::{Shape, Topology};
use pedo_io::read_recording;
use pedo_track::{
    pairing::STEP_SLACK, run_sequence, FrameRange, ObjectModel, RunParams, SequenceResult,
};

fn walk(model: ObjectModel, frames: Option<(usize, usize)>) -> SequenceResult {
    let rec = read_recording(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    ))
    .unwrap();
    let params = RunParams {
        model,
        frames: frames.map(|(start, end)| FrameRange {
            start: start as isize,
            end: Some(end as isize),
        }),
        ..Default::default()
    };
    let options = params.to_options(&rec).unwrap();
    assert_eq!(options.sensel_aspect, 1.0, "the walk's sensels are square");
    run_sequence(&rec, &options, &|_, _, _| {}).unwrap()
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    // Sampled finely along the segment, and the two ends: a bound no tighter than the exact one
    // by more than the sampling step over two.
    let n = 400;
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            dist(p, [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
        })
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to triangle `t` (0 inside, by its barycentric coordinates).
fn to_triangle(p: [f64; 2], [a, b, c]: [[f64; 2]; 3]) -> f64 {
    let det = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
    let l1 = ((b[1] - c[1]) * (p[0] - c[0]) + (c[0] - b[0]) * (p[1] - c[1])) / det;
    let l2 = ((c[1] - a[1]) * (p[0] - c[0]) + (a[0] - c[0]) * (p[1] - c[1])) / det;
    let l3 = 1.0 - l1 - l2;
    if l1 >= -1e-12 && l2 >= -1e-12 && l3 >= -1e-12 {
        return 0.0;
    }
    to_segment(p, a, b)
        .min(to_segment(p, b, c))
        .min(to_segment(p, c, a))
}

fn xy(s: &Shape, k: usize) -> [f64; 2] {
    [s.point(k)[0], s.point(k)[1]]
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The bound of a step from `from` onto the surface `next`: its support's distance plus
/// `STEP_SLACK` median edge lengths.
fn surface_bound(from: [f64; 2], next: &Shape) -> f64 {
    let Topology::Mesh { triangles } = next.topology() else {
        panic!("a surface is a mesh")
    };
    let motion = triangles
        .iter()
        .map(|t| to_triangle(from, t.map(|v| xy(next, v))))
        .fold(f64::INFINITY, f64::min);
    let mut edges: Vec<(usize, usize)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let spacing = median(
        edges
            .iter()
            .map(|&(u, v)| dist(xy(next, u), xy(next, v)))
            .collect(),
    );
    motion + STEP_SLACK * spacing
}

/// Every step of every track as (object, node) → (object, node).
fn steps(run: &SequenceResult) -> Vec<((usize, usize), (usize, usize))> {
    run.all_tracks()
        .flat_map(|t| t.steps.windows(2).map(|w| (w[0], w[1])).collect::<Vec<_>>())
        .collect()
}

#[test]
fn no_surface_track_steps_further_than_the_footprint_moved() {
    // A stance of the walk: heel strike to toe off.
    let run = walk(ObjectModel::Surface, Some((20, 50)));
    let steps = steps(&run);
    assert!(steps.len() > 500, "{} steps", steps.len());
    for ((oa, na), (ob, nb)) in &steps {
        let (a, b) = (&run.objects[*oa].shape, &run.objects[*ob].shape);
        let (p, q) = (xy(a, *na), xy(b, *nb));
        let bound = surface_bound(p, b);
        // The sampled segment distance may exceed the exact one by a 400th of an edge.
        assert!(
            dist(p, q) <= bound + 0.05,
            "objects {oa} → {ob}, nodes {na} → {nb}: step {} > bound {bound}",
            dist(p, q)
        );
    }
    // The bound is not idle on a real stance: some one-to-one matches cross the footprint.
    let cut: usize = (run.pairs.iter())
        .map(|p| p.row.optimisation_matches - p.row.trackable_matches)
        .sum();
    assert!(cut > 0);
    // And most are honest.
    let (kept, all): (usize, usize) = (run.pairs.iter())
        .map(|p| (p.row.trackable_matches, p.row.optimisation_matches))
        .fold((0, 0), |s, x| (s.0 + x.0, s.1 + x.1));
    assert!(kept * 2 > all, "{kept} of {all} matches trackable");
}

/// Whether the point `p` lies inside the closed outline `s` (crossing count).
fn inside(p: [f64; 2], s: &Shape) -> bool {
    let n = s.len();
    let mut c = false;
    for i in 0..n {
        let (a, b) = (xy(s, i), xy(s, (i + 1) % n));
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
        {
            c = !c;
        }
    }
    c
}

#[test]
fn no_isocontour_track_crosses_to_another_region_or_beyond_the_level_lines_motion() {
    let run = walk(ObjectModel::Isocontour, None);
    assert!(run.objects.len() >= 8);
    let steps = steps(&run);
    assert!(steps.len() > 100, "{} steps", steps.len());
    for ((oa, na), (ob, nb)) in &steps {
        let (a, b) = (&run.objects[*oa].shape, &run.objects[*ob].shape);
        // A higher level nests in a lower one: its nodes lie inside the lower level's outline.
        let within = (0..b.len()).filter(|&k| inside(xy(b, k), a)).count();
        assert!(2 * within >= b.len(), "levels {oa} → {ob}: another region");
        let (p, q) = (xy(a, *na), xy(b, *nb));
        let n = b.len();
        let motion = (0..n)
            .map(|k| to_segment(p, xy(b, k), xy(b, (k + 1) % n)))
            .fold(f64::INFINITY, f64::min);
        let spacing = median((0..n).map(|k| dist(xy(b, k), xy(b, (k + 1) % n))).collect());
        let bound = motion + STEP_SLACK * spacing;
        assert!(
            dist(p, q) <= bound + 0.05,
            "levels {oa} → {ob}: {} > {bound}",
            dist(p, q)
        );
    }
}
