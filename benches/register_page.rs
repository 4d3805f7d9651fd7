//! `register.html` for large stacks: the page's size, the image values it embeds and the time to
//! make and write it, against the whole register folder, for stacks of 100 to 2400 trials on the
//! SpeedPP2D grid (63 × 33 sensels). The page embeds at most `MAX_PAGE_VALUES` values: past the
//! bound it shows the first trials that fit, which this checks from the embedded data itself.
//!
//! `cargo bench --bench register_page` (release; a markdown table on stdout); the table is in
//! BENCHMARKS.md ("Footprint registration").
//!
//! The trials are made, not registered (the page does not depend on how): the bundled MUN104
//! template placed on the grid, shifted by a fraction of a sensel and scaled per trial, so that
//! every value has the six significant digits a registered image has.

use pedo_output::figure::FigureAxes;
use pedo_output::register_folder::write_register_folder;
use pedo_output::register_page::{register_page, MAX_PAGE_VALUES};
use pedo_register::footprint::bilinear;
use pedo_register::{mun104, FootImages, MapKept, Registration, StudyRegistration, Template};
use std::time::Instant;

const ROWS: usize = 63;
const COLS: usize = 33;

/// Trial `k`: the template's peak image on the grid, moved by under a sensel and scaled.
fn trial(src: &FootImages, k: usize) -> Registration {
    let (dx, dy) = ((k % 7) as f64 / 7.0 - 0.4, (k % 5) as f64 / 5.0 - 0.4);
    let gain = 0.8 + 0.4 * ((k * 37) % 100) as f64 / 100.0;
    let (r0, c0) = (
        ROWS.saturating_sub(src.rows) / 2,
        COLS.saturating_sub(src.cols) / 2,
    );
    let peak: Vec<f64> = (0..ROWS * COLS)
        .map(|i| {
            let (x, y) = ((i % COLS) as f64 - c0 as f64, (i / COLS) as f64 - r0 as f64);
            gain * bilinear(&src.peak, src.rows, src.cols, x + dx, y + dy)
        })
        .collect();
    Registration {
        mask: peak.iter().map(|&v| v > 0.0).collect(),
        images: FootImages::from_peak(ROWS, COLS, peak).expect("a finite image"),
        affine: [[1.0, 0.0, dx], [0.0, 1.0, dy]],
        turn_deg: 0.0,
        scale: 1.0,
        fallback: false,
        kept: MapKept::Warp,
        residual_sensels: 0.1,
        mask_xor_pct: 10.0,
        correlation: Some(0.95),
    }
}

/// The image values embedded in a page: the template, mean and SD and every shown trial's.
fn embedded_values(html: &str) -> (usize, usize) {
    let tag = "id=\"report-data\">";
    let at = html.find(tag).expect("the page's data") + tag.len();
    let end = at + html[at..].find("</script>").expect("its end");
    let data: serde_json::Value = serde_json::from_str(&html[at..end]).expect("JSON");
    let len = |v: &serde_json::Value| v.as_array().map_or(0, Vec::len);
    let shown = data["shown"].as_array().expect("the shown trials");
    let values = ["template", "mean", "sd"]
        .iter()
        .map(|k| len(&data[*k]))
        .sum::<usize>()
        + shown.iter().map(|t| len(&t["peak"])).sum::<usize>();
    (values, shown.len())
}

fn median_s(mut f: impl FnMut(), repeats: usize) -> f64 {
    let mut t: Vec<f64> = (0..repeats)
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn main() {
    let src = mun104(true);
    let template = Template::of_images(trial(&src, 0).images, 0.0, 64).expect("the template");
    let mut axes = FigureAxes::unscaled("sensels");
    axes.pressure_units = "kPa".into();
    let dir = std::env::temp_dir().join(format!("register-page-bench-{}", std::process::id()));
    println!(
        "| trials | values in the stack | trials shown | values embedded | register.html (MB) | page made (ms) | page written (ms) | whole folder (ms) |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for n in [100, 300, 478, 479, 600, 1200, 2400] {
        let reg = StudyRegistration {
            template: template.clone(),
            trials: (0..n).map(|k| trial(&src, k)).collect(),
        };
        let names: Vec<String> = (0..n).map(|k| format!("trials/trial-{k:04}.npy")).collect();
        let page = || register_page(&names, &reg, &axes, MAX_PAGE_VALUES).expect("the page");
        let make_s = median_s(|| drop(page()), 5);
        let html = page();
        let file = dir.with_extension("html");
        let write_s = median_s(
            || std::fs::write(&file, html.as_bytes()).expect("written"),
            5,
        );
        std::fs::remove_file(&file).ok();
        let folder_s = median_s(
            || {
                write_register_folder(&dir, &names, &reg, &axes).expect("the folder");
                std::fs::remove_dir_all(&dir).expect("removed");
            },
            3,
        );
        let (values, shown) = embedded_values(&html);
        assert!(values <= MAX_PAGE_VALUES, "{values} values embedded");
        println!(
            "| {n} | {} | {shown} | {values} | {:.2} | {:.0} | {:.0} | {:.0} |",
            (n + 3) * ROWS * COLS,
            html.len() as f64 / 1e6,
            1e3 * make_s,
            1e3 * write_s,
            1e3 * folder_s
        );
    }
}
