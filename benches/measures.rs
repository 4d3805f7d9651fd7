//! What the recording's measures cost in a default run of the bundled walk: the whole default
//! run (`pedomatch demo`'s: tables, summary figures, report) beside the measures' own work in it
//! (summing the peak, PTI and mean images frame by frame as the run hands its frames, the
//! stances and their curves, `peak.npy`, `pti.npy`, `mean.npy`, `measures.json`, `curves.csv`,
//! `pti.png`, `stance_curves.png`, and the report's measures section).
//!
//! `cargo bench --bench measures` (release, criterion); numbers in BENCHMARKS.md ("What the
//! measures cost").

use criterion::{criterion_group, criterion_main, Criterion};
use pedo_output::html_report::ReportMeasures;
use pedo_output::outdir::OutDir;
use pedo_output::{InputInfo, MeasuresSink, OutputOptions, RunOutputs, RunPlan};
use pedo_track::{RunParams, SequenceSink};
use std::hint::black_box;
use std::path::Path;

const ASF: &[u8] = include_bytes!("../examples/data/FrasP01L.asf");
const NAME: &str = "examples/data/FrasP01L.asf";

fn walk() -> pedo_io::Recording {
    pedo_io::parse_bytes(ASF, pedo_io::Format::Asf, NAME).unwrap()
}

/// The default run of the walk into `out`, as `pedomatch demo --out OUT` makes it.
fn default_run(out: &Path) {
    let mut recording = walk();
    let params = RunParams::default();
    let options = pedo_track::run_options(&mut recording, &params).unwrap();
    let outputs = RunOutputs::of(&OutputOptions::default());
    let input = InputInfo::of_bytes(NAME, ASF);
    let plan = RunPlan {
        input: &input,
        params: &params,
        frames: None,
        folder: Some(out),
        outputs: &outputs,
        timings: &[],
        also: None,
    };
    black_box(pedo_output::run_into_folder(&recording, &options, plan, &|_, _, _| {}).unwrap());
}

/// The measures' share of that run, into `out`: fed every frame as the run feeds them.
fn measures_alone(out: &Path) {
    let mut recording = walk();
    let options = pedo_track::run_options(&mut recording, &RunParams::default()).unwrap();
    let outputs = RunOutputs::of(&OutputOptions::default());
    let mut sink = MeasuresSink::new(&recording, &options).unwrap();
    for t in 0..recording.n_frames() {
        sink.frame_values(t, &recording.frame_slice(t).unwrap())
            .unwrap();
    }
    let measures = sink.finish().unwrap();
    let dir = OutDir::create(out).unwrap();
    pedo_output::write_measures(
        &dir,
        &recording,
        &measures,
        None,
        outputs.figures,
        outputs.tables,
    )
    .unwrap();
    let section = ReportMeasures {
        measures: &measures,
        regions: None,
        user_regions: Vec::new(),
        points: Vec::new(),
    };
    black_box(section.to_json(recording.pitch_mm.unwrap_or([1.0, 1.0])));
    black_box(pedo_output::measure_values_json(&measures));
    dir.commit().unwrap();
}

fn bench(c: &mut Criterion) {
    let tmp = std::env::temp_dir().join(format!("pedomatch-bench-measures-{}", std::process::id()));
    let mut g = c.benchmark_group("walk_default_run");
    g.sample_size(10);
    let mut k = 0usize;
    let mut next = || {
        k += 1;
        tmp.join(k.to_string())
    };
    g.bench_function("whole_run", |b| b.iter(|| default_run(&next())));
    g.bench_function("measures_in_it", |b| b.iter(|| measures_alone(&next())));
    g.finish();
    let _ = std::fs::remove_dir_all(&tmp);
}

criterion_group!(benches, bench);
criterion_main!(benches);
