//! Brightness surfaces, isobaric contours and contour pairing.

use pedo_io::contour::{point_in_polygon, Contour};
use pedo_io::isobar::{isocontours, IsoOptions};
use pedo_io::preprocess::Preprocess;
use pedo_io::surface::{surface, Laplacian, Surface, SurfaceOptions, ZScale};
use pedo_io::{contours, read_recording, ContourOptions, Grid, Recording};
use pedo_track::pairing::{pair_contours, pair_contours_by, track, PairingMethod};
use std::collections::HashMap;

fn fscan() -> Recording {
    read_recording(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    ))
    .unwrap()
}

/// A valid triangulated disc: positive triangles, manifold edges with opposite orientations,
/// one boundary loop, Euler characteristic 1, and no point of the plane covered twice.
fn assert_valid(s: &Surface) {
    assert!(!s.triangles.is_empty());
    for t in 0..s.triangles.len() {
        let a = s.triangle_area_xy(t);
        assert!(a > 1e-9, "triangle {t} degenerate or flipped: {a}");
    }
    let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
    for t in &s.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    assert!(
        directed.values().all(|&c| c == 1),
        "an oriented edge is used twice"
    );
    let boundary: Vec<(usize, usize)> = directed
        .keys()
        .filter(|&&(a, b)| !directed.contains_key(&(b, a)))
        .copied()
        .collect();
    // One boundary loop.
    let next: HashMap<usize, usize> = boundary.iter().copied().collect();
    assert_eq!(
        next.len(),
        boundary.len(),
        "boundary vertex with two outgoing boundary edges"
    );
    let start = boundary[0].0;
    let (mut v, mut steps) = (next[&start], 1);
    while v != start {
        v = next[&v];
        steps += 1;
        assert!(steps <= boundary.len());
    }
    assert_eq!(steps, boundary.len(), "more than one boundary loop");
    assert_eq!(s.euler_characteristic(), 1);
    // Coverage: points inside the bounding box lie in at most one triangle.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &s.points {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let mut state = 0x2545F4914F6CDD1Du64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..1500 {
        let q = [
            lo[0] + rnd() * (hi[0] - lo[0]),
            lo[1] + rnd() * (hi[1] - lo[1]),
        ];
        let n = s
            .triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| s.points[i]);
                let e = |u: [f64; 3], v: [f64; 3]| {
                    (v[0] - u[0]) * (q[1] - u[1]) - (v[1] - u[1]) * (q[0] - u[0])
                };
                e(a, b) > 0.0 && e(b, c) > 0.0 && e(c, a) > 0.0
            })
            .count();
        assert!(n <= 1, "point {q:?} covered by {n} triangles");
    }
}

/// Linear interpolation of the surface's z at (x, y), if inside.
fn interp(s: &Surface, q: [f64; 2]) -> Option<f64> {
    for t in &s.triangles {
        let [a, b, c] = t.map(|i| s.points[i]);
        let d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        let l1 = ((b[0] - q[0]) * (c[1] - q[1]) - (c[0] - q[0]) * (b[1] - q[1])) / d;
        let l2 = ((c[0] - q[0]) * (a[1] - q[1]) - (a[0] - q[0]) * (c[1] - q[1])) / d;
        let l3 = 1.0 - l1 - l2;
        if l1 >= -1e-9 && l2 >= -1e-9 && l3 >= -1e-9 {
            return Some(l1 * a[2] + l2 * b[2] + l3 * c[2]);
        }
    }
    None
}

fn cone(rows: usize, cols: usize, cx: f64, cy: f64, h: f64) -> Grid {
    let d = (0..rows * cols)
        .map(|i| {
            let (r, c) = ((i / cols) as f64, (i % cols) as f64);
            (h - ((c - cx).powi(2) + (r - cy).powi(2)).sqrt()).max(0.0)
        })
        .collect();
    Grid::new(rows, cols, d).unwrap()
}

#[test]
fn raw_surface_keeps_samples_exactly() {
    let g = cone(30, 30, 14.6, 15.2, 10.0);
    let opts = SurfaceOptions {
        laplacian: None,
        z_scale: ZScale::Keep,
        ..Default::default()
    };
    let s = surface(&g, &opts).unwrap();
    let n_pos = g.data().iter().filter(|&&v| v > 0.0).count();
    assert_eq!(s.points.len(), n_pos);
    for p in &s.points {
        assert_eq!(p[2], g.get(p[1] as usize, p[0] as usize));
    }
    assert_valid(&s);
    s.to_shape().unwrap();
}

#[test]
fn decimation_reaches_target_and_error_falls_with_nodes() {
    let g = cone(40, 40, 19.5, 20.3, 15.0);
    let mut prev = f64::INFINITY;
    for target in [20, 60, 100, 300] {
        // 20 is below the number of hull corners of the digital disc: only without them.
        let keep_hull = target > 20;
        let opts = SurfaceOptions {
            max_nodes: Some(target),
            keep_hull,
            laplacian: None,
            z_scale: ZScale::Keep,
            ..Default::default()
        };
        let s = surface(&g, &opts).unwrap();
        assert!(s.points.len() <= target, "{} > {target}", s.points.len());
        assert_valid(&s);
        // Max deviation from the original samples inside the surface.
        let mut err = 0.0f64;
        for r in 0..40 {
            for c in 0..40 {
                if g.get(r, c) > 0.0
                    && let Some(z) = interp(&s, [c as f64, r as f64])
                {
                    err = err.max((z - g.get(r, c)).abs());
                }
            }
        }
        if keep_hull {
            assert!(
                err < prev,
                "error {err} with {target} nodes, {prev} with fewer"
            );
            prev = err;
        }
    }
    // A plane is represented exactly by its hull corners.
    let d = (0..20 * 30)
        .map(|i| 1.0 + 0.5 * (i % 30) as f64 + 0.25 * (i / 30) as f64)
        .collect();
    let plane = Grid::new(20, 30, d).unwrap();
    let opts = SurfaceOptions {
        max_nodes: Some(3),
        laplacian: None,
        z_scale: ZScale::Keep,
        ..Default::default()
    };
    let s = surface(&plane, &opts).unwrap();
    assert_eq!(s.points.len(), 4);
    assert_valid(&s);
    for r in 0..20 {
        for c in 0..30 {
            let z = interp(&s, [c as f64, r as f64]).unwrap();
            assert!((z - plane.get(r, c)).abs() < 1e-9);
        }
    }
}

#[test]
fn real_frames_give_valid_surfaces() {
    let rec = fscan();
    let ms = rec.measures(0.0);
    let mut done = 0;
    for t in (0..rec.n_frames())
        .filter(|&t| ms[t].contact_sensors >= 30)
        .step_by(7)
    {
        let g = rec.frame(t).unwrap();
        let opts = SurfaceOptions {
            preprocess: Preprocess {
                threshold: Some(3.0),
                sigma: Some(1.0),
                upsample: None,
            },
            sample_level: 3.0,
            max_nodes: Some(120),
            ..Default::default()
        };
        let s = surface(&g, &opts).unwrap();
        assert!(
            s.points.len() <= 120 && s.points.len() >= 20,
            "frame {t}: {}",
            s.points.len()
        );
        assert_valid(&s);
        // z rescaled to the x-y range.
        let zr = s
            .points
            .iter()
            .map(|p| p[2])
            .fold(f64::NEG_INFINITY, f64::max)
            - s.points.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
        let xr = s
            .points
            .iter()
            .map(|p| p[0])
            .fold(f64::NEG_INFINITY, f64::max)
            - s.points.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
        let yr = s
            .points
            .iter()
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max)
            - s.points.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        assert!((zr - xr.max(yr)).abs() < 1e-9 * zr);
        let shape = s.to_shape().unwrap();
        assert_eq!(shape.dim(), 3);
        done += 1;
    }
    assert!(done >= 5);
}

#[test]
fn laplacian_follows_vtk_semantics() {
    let g = cone(20, 20, 9.5, 9.5, 8.0);
    let base = SurfaceOptions {
        laplacian: None,
        z_scale: ZScale::Keep,
        ..Default::default()
    };
    let raw = surface(&g, &base).unwrap();
    let lap = Laplacian {
        iterations: 1,
        relaxation: 0.5,
        boundary_smoothing: false,
        edge_angle_deg: 15.0,
    };
    let sm = surface(
        &g,
        &SurfaceOptions {
            laplacian: Some(lap),
            ..base
        },
    )
    .unwrap();
    assert_eq!(raw.triangles, sm.triangles);
    // One iteration: interior vertices move halfway to their neighbour mean; boundary stays.
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); raw.points.len()];
    let mut count: HashMap<(usize, usize), usize> = HashMap::new();
    for t in &raw.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut boundary = vec![false; raw.points.len()];
    for (&(a, b), &c) in &count {
        nb[a].push(b);
        nb[b].push(a);
        if c == 1 {
            boundary[a] = true;
            boundary[b] = true;
        }
    }
    for v in 0..raw.points.len() {
        for k in 0..3 {
            let expect = if boundary[v] {
                raw.points[v][k]
            } else {
                let m = nb[v].iter().map(|&j| raw.points[j][k]).sum::<f64>() / nb[v].len() as f64;
                raw.points[v][k] + 0.5 * (m - raw.points[v][k])
            };
            assert!((sm.points[v][k] - expect).abs() < 1e-12);
        }
    }
    // Defaults keep a valid mesh.
    assert_valid(&surface(&g, &SurfaceOptions::default()).unwrap());
    assert!(surface(&Grid::zeros(4, 4).unwrap(), &SurfaceOptions::default()).is_err());
}

fn region_contains(cs: &[&Contour], p: [f64; 2]) -> bool {
    cs.iter().filter(|c| point_in_polygon(p, &c.points)).count() % 2 == 1
}

#[test]
fn isocontours_nest_by_level() {
    let rec = fscan();
    let ms = rec.measures(0.0);
    let t = (0..rec.n_frames())
        .max_by(|&a, &b| ms[a].total_force.total_cmp(&ms[b].total_force))
        .unwrap();
    let g = rec.frame(t).unwrap();
    let opts = IsoOptions {
        preprocess: Preprocess {
            threshold: Some(3.0),
            sigma: Some(1.0),
            upsample: None,
        },
        include_holes: true,
        ..Default::default()
    };
    let levels = [10.0, 30.0, 60.0, 100.0, 150.0];
    let cs = isocontours(&g, &levels, &opts).unwrap();
    for w in levels.windows(2) {
        let lower: Vec<&Contour> = cs.iter().filter(|c| c.level == w[0]).collect();
        let upper: Vec<&Contour> = cs.iter().filter(|c| c.level == w[1]).collect();
        assert!(!lower.is_empty() && !upper.is_empty(), "levels {w:?}");
        for c in &upper {
            for &p in &c.points {
                assert!(
                    region_contains(&lower, p),
                    "level {} point {p:?} outside level {}",
                    w[1],
                    w[0]
                );
            }
        }
        let area = |v: &[&Contour]| {
            v.iter()
                .map(|c| if c.hole { -c.area() } else { c.area() })
                .sum::<f64>()
        };
        assert!(area(&upper) < area(&lower));
    }
    let s3 = cs[0].to_shape_3d().unwrap();
    assert_eq!((s3.dim(), s3.point(0)[2]), (3, 10.0));
}

#[test]
fn pairing_reports_pairs_splits_and_merges() {
    // Frame A: one elongated blob; frame B: it has split into two.
    let bar = |gap: bool| {
        let mut d = vec![0.0; 20 * 40];
        for r in 8..12 {
            for c in 5..35 {
                if !(gap && (18..22).contains(&c)) {
                    d[r * 40 + c] = 10.0;
                }
            }
        }
        Grid::new(20, 40, d).unwrap()
    };
    let a = contours(&bar(false), &ContourOptions::default()).unwrap();
    let b = contours(&bar(true), &ContourOptions::default()).unwrap();
    assert_eq!((a.len(), b.len()), (1, 2));
    for method in [
        PairingMethod::default(),
        PairingMethod::Centroid { max_distance: 10.0 },
    ] {
        let p = pair_contours(&a, &b, method).unwrap();
        assert_eq!(p.splits.len(), 1, "{method:?}");
        assert_eq!(p.splits[0].0, 0);
        assert_eq!(p.pairs.len(), 1);
        let back = pair_contours(&b, &a, method).unwrap();
        assert_eq!(back.merges.len(), 1);
        assert_eq!(back.merges[0].1, 0);
    }
    // Far apart: nothing linked.
    let far = contours(&cone(20, 80, 70.0, 10.0, 5.0), &ContourOptions::default()).unwrap();
    let p = pair_contours(&a, &far, PairingMethod::default()).unwrap();
    assert_eq!((p.vanished, p.appeared), (vec![0], vec![0]));

    // On the real walk: consecutive loaded frames are mostly continuations.
    let rec = fscan();
    let seq: Vec<Vec<Contour>> = (0..rec.n_frames())
        .map(|t| {
            contours(
                &rec.frame(t).unwrap(),
                &ContourOptions {
                    min_area: 2.0,
                    ..Default::default()
                },
            )
            .unwrap()
        })
        .collect();
    let tr = track(&seq, PairingMethod::default()).unwrap();
    assert_eq!(tr.len(), 204);
    let pairs: usize = tr.iter().map(|p| p.pairs.len()).sum();
    let objects: usize = seq
        .iter()
        .map(|c| c.iter().filter(|c| !c.hole).count())
        .sum();
    assert!(
        pairs as f64 > 0.7 * objects as f64,
        "{pairs} pairs for {objects} objects"
    );
}

#[test]
fn at_a_merge_the_largest_region_carries_on() {
    // A foot-sized region and a toe blob merge into one region. Both lie wholly inside it, so
    // both overlap it by the whole of the smaller region; the foot, which covers most of the
    // merged region, is its continuation wherever the blob lies (before or after the foot in
    // the contours' order) and in both directions (a merge, and read backwards a split).
    let grid = |cells: &[(std::ops::Range<usize>, std::ops::Range<usize>)]| {
        let mut d = vec![0.0; 30 * 50];
        for (rows, cols) in cells {
            for r in rows.clone() {
                for c in cols.clone() {
                    d[r * 50 + c] = 10.0;
                }
            }
        }
        Grid::new(30, 50, d).unwrap()
    };
    for (foot, blob, merged) in [
        ((5..25, 5..30), (8..12, 33..37), (5..25, 5..37)),
        ((5..25, 15..40), (8..12, 8..12), (5..25, 8..40)),
    ] {
        let a = contours(&grid(&[foot.clone(), blob]), &ContourOptions::default()).unwrap();
        let b = contours(&grid(&[merged]), &ContourOptions::default()).unwrap();
        assert_eq!((a.len(), b.len()), (2, 1));
        let big = if a[0].area() > a[1].area() { 0 } else { 1 };
        let p = pair_contours(&a, &b, PairingMethod::default()).unwrap();
        assert_eq!(p.merges.len(), 1, "{foot:?}");
        assert_eq!(p.pairs, vec![(big, 0)], "{foot:?}");
        let back = pair_contours(&b, &a, PairingMethod::default()).unwrap();
        assert_eq!(back.splits.len(), 1);
        assert_eq!(back.pairs, vec![(0, big)], "{foot:?}");
    }
}

#[test]
fn predicted_centroid_tracking_follows_a_fast_object() {
    // A blob accelerating to the right (steps of 2, 4, 6, 8, 10 px) and a static blob: plain
    // centroid linking with a 4.5 px gate loses the moving one from the third step, the
    // constant-velocity prediction (error 2 px per step) keeps it.
    let frames: Vec<Vec<Contour>> = (0..6)
        .map(|t| {
            let mut d = vec![0.0; 20 * 80];
            for r in 0..20 {
                for c in 0..80 {
                    let moving = ((c as f64 - (5.0 + (t * (t + 1)) as f64)).powi(2)
                        + (r as f64 - 6.0).powi(2))
                    .sqrt();
                    let fixed = ((c as f64 - 40.0).powi(2) + (r as f64 - 15.0).powi(2)).sqrt();
                    d[r * 80 + c] = (3.0 - moving).max(0.0) + (3.0 - fixed).max(0.0);
                }
            }
            let g = Grid::new(20, 80, d).unwrap();
            let mut cs = contours(
                &g,
                &ContourOptions {
                    level: Some(0.5),
                    ..Default::default()
                },
            )
            .unwrap();
            cs.sort_by(|a, b| a.centroid()[1].total_cmp(&b.centroid()[1])); // 0 = moving, 1 = fixed
            cs
        })
        .collect();
    let plain = track(&frames, PairingMethod::Centroid { max_distance: 4.5 }).unwrap();
    let pred = track(
        &frames,
        PairingMethod::PredictedCentroid { max_distance: 4.5 },
    )
    .unwrap();
    for t in 0..5 {
        assert_eq!(
            plain[t].pairs.contains(&(0, 0)),
            t < 2,
            "step {t}: {:?}",
            plain[t].pairs
        );
        assert!(plain[t].pairs.contains(&(1, 1)));
        assert!(
            pred[t].pairs.contains(&(0, 0)),
            "step {t}: {:?}",
            pred[t].pairs
        );
        assert!(pred[t].pairs.contains(&(1, 1)));
    }
}

#[test]
fn pairing_by_a_custom_cost_takes_the_cheapest() {
    // Two blobs of different sizes swap places: by position they would cross-link, by an
    // area-difference cost (a stand-in for a deformation energy) each keeps its identity.
    let blobs = |swap: bool| {
        let (a, b) = if swap {
            ((45.0, 10.0), (15.0, 10.0))
        } else {
            ((15.0, 10.0), (45.0, 10.0))
        };
        let mut d = vec![0.0; 20 * 60];
        for r in 0..20 {
            for c in 0..60 {
                let da = ((c as f64 - a.0).powi(2) + (r as f64 - a.1).powi(2)).sqrt();
                let db = ((c as f64 - b.0).powi(2) + (r as f64 - b.1).powi(2)).sqrt();
                d[r * 60 + c] = (3.0 - da).max(0.0) + (7.0 - db).max(0.0);
            }
        }
        let mut cs = contours(
            &Grid::new(20, 60, d).unwrap(),
            &ContourOptions {
                level: Some(0.5),
                ..Default::default()
            },
        )
        .unwrap();
        cs.sort_by(|x, y| x.area().total_cmp(&y.area())); // 0 = small, 1 = large
        cs
    };
    let (a, b) = (blobs(false), blobs(true));
    let p = pair_contours_by(&a, &b, |x, y| Some((x.area() - y.area()).abs())).unwrap();
    assert_eq!(p.pairs, vec![(0, 0), (1, 1)]);
    let near = pair_contours(&a, &b, PairingMethod::Centroid { max_distance: 5.0 }).unwrap();
    assert_eq!(near.pairs, vec![(0, 1), (1, 0)]);
    assert!(pair_contours_by(&a, &b, |_, _| Some(f64::NAN)).is_err());
}

/// Every frame of a real walk gives a valid surface under default settings, or the error that
/// says there is no surface (no contact, or fewer than 3 non-collinear samples). Smoothing used
/// to fold thin triangles along the hull of some frames.
fn every_frame_valid_with_defaults(rec: &Recording) -> (usize, usize) {
    let (mut surfaces, mut empty) = (0, 0);
    for t in 0..rec.n_frames() {
        let g = rec.frame(t).unwrap();
        match surface(&g, &SurfaceOptions::default()) {
            Ok(s) => {
                assert_valid(&s);
                surfaces += 1;
            }
            Err(e) => {
                let m = e.to_string();
                assert!(
                    m.contains("no sample above") || m.contains("non-collinear"),
                    "frame {t}: {m}"
                );
                empty += 1;
            }
        }
    }
    (surfaces, empty)
}

/// Frames with at least 3 loaded sensels that are not all on one line, counted directly.
fn frames_with_a_surface(rec: &Recording) -> usize {
    (0..rec.n_frames())
        .filter(|&t| {
            let f = rec.frame_slice(t).unwrap();
            let p: Vec<(i64, i64)> = (0..f.len())
                .filter(|&i| f[i] > 0.0)
                .map(|i| ((i % rec.cols()) as i64, (i / rec.cols()) as i64))
                .collect();
            p.len() >= 3
                && p.iter().any(|&(x, y)| {
                    (p[1].0 - p[0].0) * (y - p[0].1) != (x - p[0].0) * (p[1].1 - p[0].1)
                })
        })
        .count()
}

#[test]
fn every_real_frame_gives_a_valid_surface_with_defaults() {
    let rec = fscan();
    let (surfaces, empty) = every_frame_valid_with_defaults(&rec);
    assert_eq!(surfaces + empty, 205);
    assert_eq!(surfaces, frames_with_a_surface(&rec));
    // More walks (e.g. the right foot of the same trial): PEDO_SURFACE_EXTRA=a.asf:b.asf.
    if let Ok(list) = std::env::var("PEDO_SURFACE_EXTRA") {
        for path in list.split(':').filter(|p| !p.is_empty()) {
            let r = read_recording(path).unwrap();
            let (s, _) = every_frame_valid_with_defaults(&r);
            assert_eq!(s, frames_with_a_surface(&r), "{path}");
            eprintln!("{path}: {s} valid surfaces of {} frames", r.n_frames());
        }
    }
}

#[test]
fn smoothing_that_would_fold_keeps_the_mesh_valid() {
    // Frame 48 of the walk: thin triangles along the hull folded under VTK's rule.
    let g = fscan().frame(48).unwrap();
    let s = surface(&g, &SurfaceOptions::default()).unwrap();
    assert_valid(&s);
    // Without smoothing the same triangles come out: smoothing moves points, never topology.
    let raw = surface(
        &g,
        &SurfaceOptions {
            laplacian: None,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(raw.triangles, s.triangles);
    // Far harsher smoothing than the defaults on a cone and on the real frame: still valid.
    let harsh = Laplacian {
        iterations: 200,
        relaxation: 1.0,
        ..Default::default()
    };
    for g in [cone(15, 9, 4.0, 7.0, 5.0), g] {
        let s = surface(
            &g,
            &SurfaceOptions {
                laplacian: Some(harsh),
                ..Default::default()
            },
        );
        assert_valid(&s.unwrap());
    }
}

/// The same frame gives the same surface to the last bit, every time (the smoothing's sums run in
/// a fixed order; neighbour lists built from a randomly seeded hash map made the last digits of a
/// run's costs differ from run to run).
#[test]
fn surfaces_are_bit_for_bit_reproducible() {
    let rec = fscan();
    let opts = SurfaceOptions {
        max_nodes: Some(60),
        ..Default::default()
    };
    for t in [40, 80, 120] {
        let g = rec.frame(t).unwrap();
        let first = surface(&g, &opts).unwrap();
        for _ in 0..4 {
            let again = surface(&g, &opts).unwrap();
            assert_eq!(first.triangles, again.triangles, "frame {t}");
            let bits = |s: &Surface| -> Vec<u64> {
                s.points.iter().flatten().map(|x| x.to_bits()).collect()
            };
            assert_eq!(bits(&first), bits(&again), "frame {t}");
        }
    }
}
