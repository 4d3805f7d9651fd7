//! pedo-io throughput: a whole 205-frame F-Scan recording (60 × 21 sensels) read, turned into
//! contours, brightness surfaces and isobaric contours.
//!
//! `cargo bench --bench io` (release, criterion); numbers in BENCHMARKS.md ("I/O and object extraction").

use criterion::{criterion_group, criterion_main, Criterion};
use pedo_io::isobar::{isocontours, IsoOptions};
use pedo_io::preprocess::Preprocess;
use pedo_io::surface::{surface, SurfaceOptions};
use pedo_io::{contours, read_recording, ContourOptions, Recording, Resample};
use std::hint::black_box;

const ASF: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/crates/pedo-io/tests/data/FrasP01L.asf"
);

fn all_contours(rec: &Recording) -> usize {
    let opts = ContourOptions {
        resample: Resample::Points(64),
        min_area: 1.0,
        ..Default::default()
    };
    (0..rec.n_frames())
        .map(|t| contours(&rec.frame(t).unwrap(), &opts).unwrap().len())
        .sum()
}

fn surface_options() -> SurfaceOptions {
    SurfaceOptions {
        preprocess: Preprocess {
            threshold: Some(3.0),
            sigma: Some(1.0),
            upsample: None,
        },
        sample_level: 3.0,
        max_nodes: Some(120),
        ..Default::default()
    }
}

fn all_surfaces(rec: &Recording) -> usize {
    let opts = surface_options();
    // Frames without load have no surface (an error by design); count the ones built.
    (0..rec.n_frames())
        .filter_map(|t| surface(&rec.frame(t).unwrap(), &opts).ok())
        .map(|s| s.points.len())
        .sum()
}

fn all_isocontours(rec: &Recording) -> usize {
    let opts = IsoOptions {
        preprocess: Preprocess {
            threshold: Some(3.0),
            sigma: Some(1.0),
            upsample: None,
        },
        ..Default::default()
    };
    let levels: Vec<f64> = (1..=10).map(|i| 20.0 * i as f64).collect();
    (0..rec.n_frames())
        .map(|t| {
            isocontours(&rec.frame(t).unwrap(), &levels, &opts)
                .unwrap()
                .len()
        })
        .sum()
}

fn bench(c: &mut Criterion) {
    let rec = read_recording(ASF).unwrap();
    let mut g = c.benchmark_group("fscan_205_frames");
    g.sample_size(10);
    g.bench_function("read_asf", |b| {
        b.iter(|| black_box(read_recording(black_box(ASF)).unwrap()))
    });
    g.bench_function("contours_marching_64pts", |b| {
        b.iter(|| black_box(all_contours(black_box(&rec))))
    });
    g.bench_function("surfaces_sigma1_120nodes", |b| {
        b.iter(|| black_box(all_surfaces(black_box(&rec))))
    });
    g.bench_function("isocontours_10_levels", |b| {
        b.iter(|| black_box(all_isocontours(black_box(&rec))))
    });
    g.bench_function("read_contours_surfaces", |b| {
        b.iter(|| {
            let r = read_recording(black_box(ASF)).unwrap();
            black_box(all_contours(&r) + all_surfaces(&r))
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
