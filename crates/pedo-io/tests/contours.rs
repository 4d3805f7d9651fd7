//! Contours on synthetic images with known answers and on the real F-Scan recording.

use pedo_io::contour::{point_in_polygon, signed_area, Saddle};
use pedo_io::preprocess::{Interpolation, Preprocess};
use pedo_io::{
    contours, read_recording, ContourMethod, ContourOptions, CoordUnits, Grid, Resample,
};
use std::f64::consts::PI;

/// The smallest window of a frame of `cols` columns holding its values that are not 0, and its
/// first row and column.
fn window_of(data: &[f64], cols: usize) -> (Grid, (usize, usize)) {
    let loaded: Vec<usize> = (0..data.len()).filter(|&i| data[i] != 0.0).collect();
    let (r0, r1) = (loaded[0] / cols, loaded[loaded.len() - 1] / cols);
    let c0 = loaded.iter().map(|i| i % cols).min().unwrap();
    let c1 = loaded.iter().map(|i| i % cols).max().unwrap();
    let (h, w) = (r1 - r0 + 1, c1 - c0 + 1);
    let window = (0..h * w)
        .map(|k| data[(r0 + k / w) * cols + c0 + k % w])
        .collect();
    (Grid::new(h, w, window).unwrap(), (r0, c0))
}

proptest::proptest! {
    /// The contours of a window around a sparse frame's values are the frame's, bit for bit:
    /// a few loaded sensels on a large plate are contoured at the cost of their window.
    #[test]
    fn a_window_around_the_values_has_the_frames_contours(
        blobs in proptest::collection::vec((0usize..40, 0usize..30, 1usize..5, 0.5f64..40.0), 1..4),
        threshold in proptest::option::of(0.0f64..10.0),
        level in proptest::option::of(0.1f64..20.0),
        pixels in proptest::bool::ANY,
    ) {
        let (rows, cols) = (40, 30);
        let mut data = vec![0.0; rows * cols];
        for &(r, c, size, v) in &blobs {
            for (dr, dc) in (0..size).flat_map(|dr| (0..size).map(move |dc| (dr, dc))) {
                if r + dr < rows && c + dc < cols {
                    data[(r + dr) * cols + c + dc] = v + (dr * 3 + dc) as f64 * 0.7;
                }
            }
        }
        let frame = Grid::new(rows, cols, data.clone()).unwrap();
        let opts = ContourOptions {
            level,
            preprocess: Preprocess { threshold, ..Preprocess::default() },
            resample: Resample::Spacing(0.8),
            units: if pixels { CoordUnits::Pixels } else { CoordUnits::Millimetres { dx_mm: 8.4, dy_mm: 7.6 } },
            ..ContourOptions::default()
        };
        proptest::prop_assume!(pedo_io::contour::window_gives_contours(&opts));
        let (window, (r0, c0)) = window_of(&data, cols);
        let whole = contours(&frame, &opts).unwrap();
        let windowed = pedo_io::contour::contours_of_window(&window, (r0, c0), &opts).unwrap();
        proptest::prop_assert_eq!(format!("{whole:?}"), format!("{windowed:?}"));
    }
}

#[test]
fn a_window_is_refused_for_options_that_reach_past_it() {
    let g = Grid::new(2, 2, vec![1.0; 4]).unwrap();
    let smoothed = ContourOptions {
        preprocess: Preprocess {
            sigma: Some(1.0),
            ..Preprocess::default()
        },
        ..ContourOptions::default()
    };
    let e = pedo_io::contour::contours_of_window(&g, (3, 4), &smoothed).unwrap_err();
    assert!(e.to_string().contains("reach past a window"), "{e}");
    let at_zero = ContourOptions {
        level: Some(0.0),
        ..ContourOptions::default()
    };
    assert!(!pedo_io::contour::window_gives_contours(&at_zero));
}

fn cone(rows: usize, cols: usize, centres: &[(f64, f64)], radius: f64) -> Grid {
    // Sum of cones of height `radius` (value = radius - distance, clipped at 0): level sets are circles.
    let mut d = vec![0.0; rows * cols];
    for r in 0..rows {
        for c in 0..cols {
            for &(cx, cy) in centres {
                let dist = ((c as f64 - cx).powi(2) + (r as f64 - cy).powi(2)).sqrt();
                d[r * cols + c] += (radius - dist).max(0.0);
            }
        }
    }
    Grid::new(rows, cols, d).unwrap()
}

#[test]
fn circle_is_recovered_sub_pixel() {
    let g = cone(40, 50, &[(24.3, 19.6)], 15.0);
    // The level-5 set of a cone of height 15 is a circle of radius 10.
    let opts = ContourOptions {
        level: Some(5.0),
        ..Default::default()
    };
    let cs = contours(&g, &opts).unwrap();
    assert_eq!(cs.len(), 1);
    let c = &cs[0];
    assert!(!c.hole);
    assert!(signed_area(&c.points) > 0.0, "counter-clockwise");
    for p in &c.points {
        let r = ((p[0] - 24.3).powi(2) + (p[1] - 19.6).powi(2)).sqrt();
        // Linear interpolation of a cone along grid edges is exact for radial profiles only up to
        // the curvature of the circle across one cell.
        assert!((r - 10.0).abs() < 0.05, "radius {r}");
    }
    assert!((c.area() - PI * 100.0).abs() < 0.01 * PI * 100.0);
    let ctr = c.centroid();
    assert!((ctr[0] - 24.3).abs() < 0.02 && (ctr[1] - 19.6).abs() < 0.02);
}

#[test]
fn several_contours_holes_and_filters() {
    let g = cone(30, 60, &[(15.0, 15.0), (45.0, 15.0)], 8.0);
    let cs = contours(
        &g,
        &ContourOptions {
            level: Some(1.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(cs.len(), 2);
    // A ring: 1 inside an annulus of radii 5..10, 0 elsewhere -> outer contour and a hole.
    let mut d = vec![0.0; 31 * 31];
    for r in 0..31 {
        for c in 0..31 {
            let q = ((r as f64 - 15.0).powi(2) + (c as f64 - 15.0).powi(2)).sqrt();
            if (5.0..=10.0).contains(&q) {
                d[r * 31 + c] = 1.0;
            }
        }
    }
    let ring = Grid::new(31, 31, d).unwrap();
    let cs = contours(&ring, &ContourOptions::default()).unwrap();
    assert_eq!(cs.len(), 2);
    let hole = cs.iter().find(|c| c.hole).unwrap();
    let outer = cs.iter().find(|c| !c.hole).unwrap();
    assert!(signed_area(&hole.points) > 0.0 && signed_area(&outer.points) > 0.0);
    assert!(hole
        .points
        .iter()
        .all(|&p| point_in_polygon(p, &outer.points)));
    let no_holes = contours(
        &ring,
        &ContourOptions {
            include_holes: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(no_holes.len(), 1);
    let big_only = contours(
        &ring,
        &ContourOptions {
            min_area: outer.area() + 1.0,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(big_only.is_empty());
    // Empty frame: no contours, no error.
    assert!(
        contours(&Grid::zeros(5, 5).unwrap(), &ContourOptions::default())
            .unwrap()
            .is_empty()
    );
}

#[test]
fn saddle_rules() {
    // Two diagonal pixels: separate with low-connected, joined with high-connected.
    let g = Grid::new(2, 2, vec![1.0, 0.0, 0.0, 1.0]).unwrap();
    let low = contours(
        &g,
        &ContourOptions {
            level: Some(0.5),
            ..Default::default()
        },
    )
    .unwrap();
    let opts = ContourOptions {
        level: Some(0.5),
        method: ContourMethod::MarchingSquares {
            saddle: Saddle::HighConnected,
        },
        ..Default::default()
    };
    let high = contours(&g, &opts).unwrap();
    assert_eq!((low.len(), high.len()), (2, 1));
}

#[test]
fn resampling_and_units() {
    let g = cone(40, 40, &[(20.0, 20.0)], 15.0);
    let base = ContourOptions {
        level: Some(5.0),
        ..Default::default()
    };
    let c = &contours(
        &g,
        &ContourOptions {
            resample: Resample::Points(64),
            ..base
        },
    )
    .unwrap()[0];
    assert_eq!(c.points.len(), 64);
    let n = c.points.len();
    let seg: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (c.points[i], c.points[(i + 1) % n]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        })
        .collect();
    let mean = seg.iter().sum::<f64>() / n as f64;
    assert!(seg.iter().all(|s| (s - mean).abs() < 0.02 * mean));
    let c2 = &contours(
        &g,
        &ContourOptions {
            resample: Resample::Spacing(2.0),
            ..base
        },
    )
    .unwrap()[0];
    // Perimeter 2 pi 10 ~ 62.8 -> 31 points.
    assert_eq!(c2.points.len(), 31);
    let mm = ContourOptions {
        units: CoordUnits::Millimetres {
            dx_mm: 5.08,
            dy_mm: 5.08,
        },
        ..base
    };
    let cm = &contours(&g, &mm).unwrap()[0];
    let cp = &contours(&g, &base).unwrap()[0];
    assert!((cm.area() - cp.area() * 5.08 * 5.08).abs() < 1e-6 * cm.area());
}

#[test]
fn upsampling_and_smoothing_keep_original_pixel_coordinates() {
    let g = cone(40, 40, &[(20.0, 20.0)], 15.0);
    for interp in [Interpolation::Bilinear, Interpolation::Bicubic] {
        let opts = ContourOptions {
            level: Some(5.0),
            preprocess: Preprocess {
                upsample: Some((4, interp)),
                ..Default::default()
            },
            ..Default::default()
        };
        let c = &contours(&g, &opts).unwrap()[0];
        assert!(
            (c.area() - PI * 100.0).abs() < 0.01 * PI * 100.0,
            "{interp:?} {}",
            c.area()
        );
        assert!(c.points.len() > 200);
    }
}

#[test]
fn chain_method_finds_the_same_objects() {
    let g = cone(30, 60, &[(15.0, 15.0), (45.0, 15.0)], 10.0);
    for refine in [false, true] {
        let opts = ContourOptions {
            level: Some(4.0),
            method: ContourMethod::Chain {
                high: Some(6.0),
                refine,
            },
            ..Default::default()
        };
        let cs = contours(&g, &opts).unwrap();
        assert_eq!(cs.len(), 2);
        for c in &cs {
            assert!(signed_area(&c.points) > 0.0);
            // Boundary pixels of a disc of radius 6 lie between radius 5 and 6 (+1 px refinement).
            let ctr = c.centroid();
            for p in &c.points {
                let r = ((p[0] - ctr[0]).powi(2) + (p[1] - ctr[1]).powi(2)).sqrt();
                assert!((4.5..=7.01).contains(&r), "r {r}");
            }
        }
    }
    // Hysteresis: a weak blob (max below `high`) is dropped.
    let weak = cone(20, 20, &[(10.0, 10.0)], 5.0);
    let opts = ContourOptions {
        level: Some(1.0),
        method: ContourMethod::Chain {
            high: Some(6.0),
            refine: false,
        },
        ..Default::default()
    };
    assert!(contours(&weak, &opts).unwrap().is_empty());
}

#[test]
fn real_frames_give_closed_ccw_contours() {
    let rec = read_recording(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/FrasP01L.asf"
    ))
    .unwrap();
    let mut total = 0;
    for t in 0..rec.n_frames() {
        let g = rec.frame(t).unwrap();
        let cs = contours(&g, &ContourOptions::default()).unwrap();
        let loaded = g.max() > 0.0;
        assert_eq!(cs.is_empty(), !loaded, "frame {t}");
        for c in &cs {
            assert!(c.points.len() >= 3);
            assert!(signed_area(&c.points) > 0.0);
            assert!(c
                .points
                .iter()
                .all(|p| p[0] >= -1.0 && p[0] <= 21.0 && p[1] >= -1.0 && p[1] <= 60.0));
            c.to_shape().unwrap();
        }
        total += cs.len();
    }
    assert!(total > 100);
}

proptest::proptest! {
    /// The surface of a window around a frame's loaded sensels is the frame's, bit for bit.
    #[test]
    fn a_window_around_the_values_has_the_frames_surface(
        blobs in proptest::collection::vec((0usize..30, 0usize..25, 2usize..6, 0.5f64..40.0), 1..3),
        step in 1usize..3,
        max_nodes in proptest::option::of(8usize..30),
        level in 0.0f64..5.0,
    ) {
        let (rows, cols) = (30, 25);
        let mut data = vec![0.0; rows * cols];
        for &(r, c, size, v) in &blobs {
            for (dr, dc) in (0..size).flat_map(|dr| (0..size).map(move |dc| (dr, dc))) {
                if r + dr < rows && c + dc < cols {
                    data[(r + dr) * cols + c + dc] = v + ((dr * 5 + dc * 3) % 7) as f64;
                }
            }
        }
        let opts = pedo_io::surface::SurfaceOptions {
            sample_level: level,
            step,
            max_nodes,
            units: CoordUnits::Millimetres { dx_mm: 8.4, dy_mm: 7.6 },
            ..Default::default()
        };
        let (window, (r0, c0)) = window_of(&data, cols);
        let frame = Grid::new(rows, cols, data).unwrap();
        let whole = pedo_io::surface::surface(&frame, &opts);
        let windowed = pedo_io::surface::surface_of_window(&window, (r0, c0), &opts);
        proptest::prop_assert_eq!(format!("{whole:?}"), format!("{windowed:?}"));
    }
}
