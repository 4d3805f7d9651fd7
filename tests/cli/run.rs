//! End-to-end tests of `pedomatch run`, `demo` and `match`.

use crate::common::{pedomatch, pedomatch_ok, read_csv, read_json, temp_dir};
use std::path::{Path, PathBuf};

fn num(row: &std::collections::HashMap<String, String>, k: &str) -> f64 {
    row[k]
        .parse()
        .unwrap_or_else(|_| panic!("{k} = {:?}", row[k]))
}

fn dist3(p: [f64; 3], q: [f64; 3]) -> f64 {
    (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
}

fn assert_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    assert!(
        bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
        "{} is not a PNG",
        path.display()
    );
    let img = image::load_from_memory(&bytes).unwrap();
    assert!(img.width() > 16 && img.height() > 16);
}

/// An elliptical pressure blob (semi-axes 5 × 8 sensels) moving by `VELOCITY` sensels per frame.
const VELOCITY: [f64; 2] = [0.5, 1.0];

fn synthetic_recording(dir: &Path) -> PathBuf {
    let (t, rows, cols) = (10, 40, 26);
    let mut data = Vec::with_capacity(t * rows * cols);
    for f in 0..t {
        let (cx, cy) = (12.0 + VELOCITY[0] * f as f64, 12.0 + VELOCITY[1] * f as f64);
        for r in 0..rows {
            for c in 0..cols {
                let q = ((c as f64 - cx) / 5.0).powi(2) + ((r as f64 - cy) / 8.0).powi(2);
                data.push((200.0 * (1.0 - q)).max(0.0) as f32);
            }
        }
    }
    let rec = pedo_io::Recording::new(t, rows, cols, data, vec![true; rows * cols]).unwrap();
    let path = dir.join("blob.npy");
    pedo_io::formats::npy::write_npy(&rec, &path).unwrap();
    path
}

/// `pedomatch run` on a fresh synthetic recording with `extra` options; the output folder.
fn run_synthetic(name: &str, extra: &[&str]) -> PathBuf {
    let dir = temp_dir(name);
    let rec = synthetic_recording(&dir);
    let out = dir.join("out");
    let mut args = vec!["run", rec.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    pedomatch_ok(&args);
    out
}

/// Every step of a track is one frame, most nodes are chained, and the median step is the
/// synthetic recording's known velocity.
fn assert_tracks_follow_the_motion(tracks: &[std::collections::HashMap<String, String>]) {
    let mut steps = Vec::new();
    for w in tracks.windows(2) {
        if w[0]["track"] == w[1]["track"] {
            assert_eq!(num(&w[1], "frame") - num(&w[0], "frame"), 1.0);
            steps.push([
                num(&w[1], "x") - num(&w[0], "x"),
                num(&w[1], "y") - num(&w[0], "y"),
            ]);
        }
    }
    assert!(
        steps.len() > 200,
        "tracks should chain most nodes, got {} steps",
        steps.len()
    );
    for k in 0..2 {
        let mut v: Vec<f64> = steps.iter().map(|s| s[k]).collect();
        v.sort_by(f64::total_cmp);
        let median = v[v.len() / 2];
        assert!(
            (median - VELOCITY[k]).abs() < 0.25,
            "median step {k} = {median}"
        );
    }
}

#[test]
fn run_on_synthetic_motion_gives_complete_matches_and_true_tracks() {
    let out = run_synthetic(
        "synthetic",
        &["--figures", "pairs", "--figure-format", "svg"],
    );

    let rows = read_csv(&out.join("pairs.csv"));
    assert_eq!(rows.len(), 9, "one pair per consecutive frame");
    let objects = read_csv(&out.join("objects.csv"));
    assert_eq!(objects.len(), 10);
    for row in &rows {
        let (n, m) = (num(row, "nodes_a"), num(row, "nodes_b"));
        let id_a = row["id_a"].clone();
        let nodes_a = objects.iter().find(|o| o["id"] == id_a).unwrap();
        assert_eq!(num(nodes_a, "nodes"), n);
        // Without a threshold the optimisation saturates the smaller object and the excess step
        // brings the total to the larger one.
        assert_eq!(num(row, "optimisation_matches"), n.min(m));
        assert_eq!(num(row, "optimisation_percent"), 100.0);
        assert_eq!(num(row, "matches_after_excess"), n.max(m));
        assert!(num(row, "local_matches") <= n.min(m));
    }
    let json = read_json(&out.join("pairs.json"));
    assert_eq!(json.as_array().unwrap().len(), 9);

    // Tracks follow the known motion: each step moves by VELOCITY (contour nodes slide along the
    // outline, so compare the median over all steps).
    let tracks = read_csv(&out.join("tracks.csv"));
    assert_tracks_follow_the_motion(&tracks);
    let longest = tracks.iter().map(|r| num(r, "step")).fold(0.0, f64::max);
    assert!(longest >= 9.0, "some node is tracked through all 10 frames");

    for name in [
        "tracks.png",
        "curves.png",
        "peak.png",
        "figures/pair_0000_0001.png",
    ] {
        assert!(
            !out.join(name).exists(),
            "--figure-format svg writes no {name}"
        );
    }
    for name in ["tracks.svg", "curves.svg", "peak.svg"] {
        assert!(out.join(name).is_file(), "no {name}");
    }
    let pair_figures = std::fs::read_dir(out.join("figures")).unwrap().count();
    assert_eq!(pair_figures, 9, "one figure per pair");
    let svg = std::fs::read_to_string(out.join("figures/pair_0000_0001.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    // An .npy states no pitch and no frame rate: axes in sensels, frames without times.
    assert!(svg.contains("x (sensels)") && !svg.contains("(mm)"));
    assert!(svg.contains("object 0 (frame 0) \u{2192} object 1 (frame 1)"));
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["pairs"], 9);
}

#[test]
fn run_with_a_reduced_gaussian_basis_still_tracks_the_motion() {
    let out = run_synthetic("stride", &["--center-stride", "2", "--figures", "none"]);
    assert_tracks_follow_the_motion(&read_csv(&out.join("tracks.csv")));
}

#[test]
fn demo_on_bundled_recording() {
    let dir = temp_dir("demo");
    let out = dir.join("out");
    let o = pedomatch_ok(&[
        "demo",
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "0..70",
        "--timings",
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("timings:"));
    let rows = read_csv(&out.join("pairs.csv"));
    assert!(
        rows.len() >= 10,
        "the first 70 frames hold at least one stance phase"
    );
    // A part paired with a whole at a merge or split is matched to its own portion of the whole,
    // whose other nodes stay unmatched; every other pair is matched in full.
    let summary = read_json(&out.join("summary.json"));
    let mut joined = std::collections::HashSet::new();
    for m in summary["merges"].as_array().unwrap() {
        for i in m["ids"].as_array().unwrap() {
            joined.insert((i.as_u64().unwrap(), m["into"].as_u64().unwrap()));
        }
    }
    for m in summary["splits"].as_array().unwrap() {
        for j in m["into"].as_array().unwrap() {
            joined.insert((m["id"].as_u64().unwrap(), j.as_u64().unwrap()));
        }
    }
    let mut parts = 0;
    for row in &rows {
        let (n, m) = (num(row, "nodes_a"), num(row, "nodes_b"));
        assert!(n >= 8.0 && m >= 8.0);
        let ids = (num(row, "id_a") as u64, num(row, "id_b") as u64);
        if joined.contains(&ids) {
            parts += 1;
            assert!(num(row, "matches_after_excess") <= n.max(m));
        } else {
            assert_eq!(num(row, "optimisation_matches"), n.min(m));
            assert_eq!(num(row, "matches_after_excess"), n.max(m));
        }
        assert!(num(row, "frame_b") > num(row, "frame_a"));
    }
    assert!(parts > 0, "the first 70 frames hold a merge or a split");
    // The default figures: the summary set, no figure per pair.
    for name in ["tracks.png", "curves.png", "peak.png"] {
        assert_png(&out.join(name));
    }
    assert!(
        !out.join("figures").exists(),
        "pair figures only with --figures pairs"
    );

    // matches.csv marks the matches node tracks follow: exactly the steps of tracks.csv.
    let mut steps = std::collections::HashSet::new();
    let tracks = read_csv(&out.join("tracks.csv"));
    for w in tracks.windows(2).filter(|w| w[0]["track"] == w[1]["track"]) {
        let node = |r: &std::collections::HashMap<String, String>| {
            (num(r, "object_id") as u64, num(r, "node") as u64)
        };
        steps.insert((node(&w[0]), node(&w[1])));
    }
    let (mut trackable, mut refused) = (std::collections::HashSet::new(), 0);
    for r in read_csv(&out.join("matches.csv")) {
        let ends = (
            (num(&r, "id_a") as u64, num(&r, "node_a") as u64),
            (num(&r, "id_b") as u64, num(&r, "node_b") as u64),
        );
        match (r["excess"].as_str(), r["trackable"].as_str()) {
            ("0", "1") => assert!(trackable.insert(ends)),
            ("0", "0") => refused += 1,
            ("1", t) => assert_eq!(t, "0", "an excess match is never trackable: {r:?}"),
            other => panic!("excess, trackable = {other:?}"),
        }
    }
    assert_eq!(trackable, steps);
    // pairs.csv counts them per pair.
    let mut per_pair = std::collections::HashMap::new();
    for ((a, _), (b, _)) in &trackable {
        *per_pair.entry((*a, *b)).or_insert(0.0) += 1.0;
    }
    for row in &rows {
        let ids = (num(row, "id_a") as u64, num(row, "id_b") as u64);
        let n = per_pair.get(&ids).copied().unwrap_or(0.0);
        assert_eq!(num(row, "trackable_matches"), n, "{ids:?}");
        let min = num(row, "nodes_a").min(num(row, "nodes_b"));
        assert!((num(row, "trackable_percent") - 100.0 * n / min).abs() <= 0.05);
    }
    assert!(
        refused > 0,
        "some matches of these frames step further than the rule allows"
    );
}

#[test]
fn demo_figures_have_mm_axes_times_and_a_pressure_scale() {
    let dir = temp_dir("demo-svg");
    let out = dir.join("out");
    let args = [
        "demo",
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "1..12",
        "--figures",
        "pairs",
        "--figure-format",
        "svg",
    ];
    pedomatch_ok(&args);
    let pairs = read_csv(&out.join("pairs.csv"));
    let first = &pairs[0];
    let id = |k: &str| first[k].parse::<usize>().unwrap();
    let stem = format!("figures/pair_{:04}_{:04}", id("id_a"), id("id_b"));
    let svg = std::fs::read_to_string(out.join(format!("{stem}.svg"))).unwrap();
    assert!(!out.join(format!("{stem}.png")).exists());
    // The Tekscan file states 5.08 mm sensels and 0.032 s per frame.
    assert!(svg.contains("x (mm)") && svg.contains("y (mm)"));
    assert!(
        svg.contains(" s) \u{2192} object "),
        "no times in the title"
    );
    for entry in [
        "A contour",
        "B contour",
        "matched (",
        "excess (",
        "unmatched (",
    ] {
        assert!(svg.contains(entry), "legend lacks {entry:?}");
    }
    let tracks = std::fs::read_to_string(out.join("tracks.svg")).unwrap();
    assert!(
        tracks.contains("peak pressure (kPa)"),
        "no pressure scale with units"
    );
    // The curves: time in seconds (0.032 s a frame), force in N, area in mm², frames 1 to 11.
    let curves = std::fs::read_to_string(out.join("curves.svg")).unwrap();
    for text in [
        "time (s)",
        "total force (N)",
        "contact area (mm²)",
        "frames 1\u{2013}11 (0.032\u{2013}0.352 s)",
        "11 frames",
    ] {
        assert!(curves.contains(text), "the curves lack {text:?}");
    }
    let peak = std::fs::read_to_string(out.join("peak.svg")).unwrap();
    assert!(peak.contains("peak pressure (kPa)") && peak.contains("contact outline"));
}

/// Skipped levels (or frames) are not rows of pairs.csv: the run points to summary.json alone.
#[test]
fn skipped_levels_point_to_where_their_reasons_are() {
    let dir = temp_dir("iso-skipped");
    let walk = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/FrasP01L.asf");
    let out = dir.join("iso");
    let o = pedomatch_ok(&[
        "run",
        walk.to_str().unwrap(),
        "--model",
        "isocontour",
        "--figures",
        "none",
        "--report",
        "none",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("skipped"))
        .expect("a skipped level");
    assert!(line.contains("(reasons in summary.json;"), "{line}");
    assert!(read_csv(&out.join("pairs.csv"))
        .iter()
        .all(|r| r["status"] == "ok"));
}

#[test]
fn isocontour_and_surface_models_run() {
    let dir = temp_dir("models");
    let rec = synthetic_recording(&dir);
    let out = dir.join("iso");
    pedomatch_ok(&[
        "run",
        rec.to_str().unwrap(),
        "--model",
        "isocontour",
        "--iso-levels",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    let rows = read_csv(&out.join("pairs.csv"));
    assert_eq!(rows.len(), 4, "5 nested levels give 4 consecutive pairs");
    for w in rows.windows(2) {
        assert!(
            num(&w[0], "nodes_a") >= num(&w[1], "nodes_a"),
            "higher levels are smaller"
        );
    }
    let out = dir.join("surface");
    pedomatch_ok(&[
        "run",
        rec.to_str().unwrap(),
        "--model",
        "surface",
        "--surface-nodes",
        "40",
        "--frames",
        "0..4",
        "--out",
        out.to_str().unwrap(),
    ]);
    let rows = read_csv(&out.join("pairs.csv"));
    assert_eq!(rows.len(), 3);
    for row in &rows {
        assert!(num(row, "nodes_a") <= 40.0 && num(row, "nodes_a") >= 8.0);
        assert_eq!(
            num(row, "optimisation_matches"),
            num(row, "nodes_a").min(num(row, "nodes_b"))
        );
    }
    assert!(read_csv(&out.join("tracks.csv"))[0].contains_key("z"));
}

#[test]
fn surface_model_matches_the_moving_blob() {
    // The blob translates by VELOCITY, so a node of frame t at (x, y, z) truly corresponds to
    // (x, y, z) + VELOCITY in frame t + 1; each frame's 60 surface nodes are sampled afresh.
    let out = run_synthetic(
        "surface-truth",
        &["--model", "surface", "--surface-nodes", "60"],
    );
    let mut pos = std::collections::HashMap::new();
    let mut coords: std::collections::HashMap<usize, Vec<f64>> = Default::default();
    for r in read_csv(&out.join("tracks.csv")) {
        let (object, p) = (
            num(&r, "object_id") as usize,
            [num(&r, "x"), num(&r, "y"), num(&r, "z")],
        );
        pos.insert((object, num(&r, "node") as usize), p);
        coords.entry(object).or_default().extend(p);
    }
    // Mean nearest-neighbour distance of each object's nodes: the tolerance of a hit.
    let spacing: std::collections::HashMap<usize, f64> = coords
        .iter()
        .map(|(&o, c)| (o, modal_core::shape::nearest_neighbour_stats_of(c, 3).0))
        .collect();
    let (mut hits, mut total) = (0, 0);
    for r in read_csv(&out.join("matches.csv")) {
        if r["excess"] == "1" {
            continue;
        }
        let (ia, ib) = (num(&r, "id_a") as usize, num(&r, "id_b") as usize);
        let pa = pos[&(ia, num(&r, "node_a") as usize)];
        let pb = pos[&(ib, num(&r, "node_b") as usize)];
        let truth = [pa[0] + VELOCITY[0], pa[1] + VELOCITY[1], pa[2]];
        total += 1;
        hits += usize::from(dist3(pb, truth) <= spacing[&ib]);
    }
    let acc = hits as f64 / total as f64;
    // Measured: 0.435 with the surface setting, 0.306 with the contour recipe on these meshes.
    assert!(total == 9 * 60, "{total} one-to-one matches");
    assert!(
        acc >= 0.38,
        "{hits}/{total} within one spacing of the true position"
    );
}

#[test]
fn match_two_point_files() {
    let dir = temp_dir("match");
    let n = 40;
    let ring = |scale: f64, shift: usize| -> String {
        let mut s = String::from("x,y\n");
        for k in 0..n {
            let t = 2.0 * std::f64::consts::PI * ((k + shift) % n) as f64 / n as f64;
            s += &format!(
                "{},{}\n",
                scale * 3.0 * t.cos(),
                scale * (2.0 * t.sin() + 0.5 * (2.0 * t).sin())
            );
        }
        s
    };
    std::fs::write(dir.join("a.csv"), ring(1.0, 0)).unwrap();
    std::fs::write(dir.join("b.csv"), ring(1.1, 5)).unwrap();
    let out = dir.join("out");
    pedomatch_ok(&[
        "match",
        dir.join("a.csv").to_str().unwrap(),
        dir.join("b.csv").to_str().unwrap(),
        "--closed",
        "--out",
        out.to_str().unwrap(),
    ]);
    // b's node k is a's node k + 5: the true match of a's node i is b's node (i - 5) mod n.
    let rows = read_csv(&out.join("matches.csv"));
    assert_eq!(rows.len(), n);
    let correct = rows
        .iter()
        .filter(|r| (num(r, "node_a") as usize + n - 5) % n == num(r, "node_b") as usize)
        .count();
    assert!(correct >= n - 2, "{correct}/{n} correct");
    assert_png(&out.join("match.png"));

    // A point file with a bad coordinate is still a point file: its error, not a pressure grid
    // of two columns. A byte-order mark loses no point.
    let bad = ring(1.0, 0).replacen("\n3,", "\nnan,", 1);
    std::fs::write(dir.join("nan.csv"), &bad).unwrap();
    let o = pedomatch(&[
        "match",
        dir.join("nan.csv").to_str().unwrap(),
        dir.join("b.csv").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("nan.csv:2: coordinate NaN is not finite"),
        "{err}"
    );
    std::fs::write(dir.join("bom.csv"), format!("\u{feff}{}", ring(1.0, 0))).unwrap();
    let o = pedomatch(&[
        "match",
        dir.join("bom.csv").to_str().unwrap(),
        dir.join("b.csv").to_str().unwrap(),
        "--json",
    ]);
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["nodes_a"], n);

    // The report: self-contained, its header the content of match.json, every match drawn.
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_self_contained(&html);
    let summary = read_json(&out.join("match.json"));
    for (k, v) in summary["options"].as_object().unwrap() {
        assert!(
            html.contains(&format!("<th>{k}</th>")),
            "option {k} = {v} not shown"
        );
    }
    assert!(summary["timings_s"]["matching"].as_f64().unwrap() > 0.0);
    assert!(html.contains("matching ") && html.contains(env!("CARGO_PKG_VERSION")));
    let data = embedded_json(&html);
    let drawn: usize = data["matches"]
        .as_array()
        .unwrap()
        .iter()
        .chain([&data["excess"]])
        .map(|l| {
            l["x"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|v| !v.is_null())
                .count()
        })
        .sum();
    assert_eq!(drawn, 2 * rows.len(), "one segment per match");
    assert_eq!(data["a"]["closed"], true);
    assert_eq!(data["xy_units"], "file units");
    assert_eq!(
        data["images"],
        serde_json::json!([null, null]),
        "point files: no image"
    );

    let none = dir.join("none");
    pedomatch_ok(&[
        "match",
        dir.join("a.csv").to_str().unwrap(),
        dir.join("b.csv").to_str().unwrap(),
        "--out",
        none.to_str().unwrap(),
        "--report",
        "none",
    ]);
    assert!(none.join("matches.csv").exists() && !none.join("report.html").exists());
}

#[test]
fn match_report_of_two_frames_draws_their_pressure_under_the_outlines() {
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let out = temp_dir("match-frames").join("out");
    let o = pedomatch_ok(&[
        "match",
        walk,
        walk,
        "--frame",
        "40",
        "--frame-b",
        "41",
        "--figures",
        "none",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8(o.stdout).unwrap();
    // With --out (no --json): the counts and where the files are, not the JSON.
    assert!(!stdout.contains('{'), "{stdout}");
    assert!(
        stdout.contains("nodes:") && stdout.contains(&format!("{}/ (", out.display())),
        "{stdout}"
    );
    assert!(stdout.contains("match.json") && stdout.contains("report.html"));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    let summary = read_json(&out.join("match.json"));
    assert_eq!(
        (summary["frame_a"].as_u64(), summary["frame_b"].as_u64()),
        (Some(40), Some(41))
    );
    assert_ne!(summary["time_a_s"], summary["time_b_s"]);
    let data = embedded_json(&std::fs::read_to_string(out.join("report.html")).unwrap());
    assert_eq!(data["xy_units"], "mm");
    assert_eq!(data["pitch"], serde_json::json!([5.08, 5.08]));
    let images = data["images"].as_array().unwrap();
    let frames: Vec<_> = images.iter().map(|i| i["frame"].as_u64()).collect();
    assert_eq!(frames, [Some(40), Some(41)]);
    for img in images {
        assert_eq!(
            (img["rows"].as_u64(), img["cols"].as_u64()),
            (Some(60), Some(21))
        );
        assert_eq!(img["units"].as_str(), Some("kPa"));
        // The frame's peak, decoded from the embedded integers, is the stated peak.
        let q = img["quantum"].as_f64().unwrap();
        let max = img["z"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|v| v.as_f64())
            .fold(0.0, f64::max);
        let peak = img["peak"].as_f64().unwrap();
        assert!(
            peak > 0.0 && (max * q - peak).abs() <= 0.5 * q,
            "{max} × {q} vs {peak}"
        );
    }
}

/// A page that loads nothing from elsewhere: plotly.js inline, no http(s) source or link in the
/// markup (script bodies, plotly.js among them, are code, not markup: left out of the search).
fn assert_self_contained(html: &str) {
    let mut markup = String::new();
    let mut rest = html.to_ascii_lowercase();
    while let Some(open) = rest.find("<script") {
        let body = open + rest[open..].find('>').unwrap() + 1;
        markup.push_str(&rest[..body]);
        let close = body + rest[body..].find("</script>").unwrap();
        rest = rest[close..].to_string();
    }
    markup.push_str(&rest);
    let lower = markup;
    for attr in [
        "src=\"http",
        "href=\"http",
        "src='http",
        "href='http",
        "<script src",
    ] {
        assert!(!lower.contains(attr), "the page loads {attr}...");
    }
    assert!(html.contains("default-src 'none'") && html.contains("plotly.js"));
}

/// The report's embedded data.
fn embedded_json(html: &str) -> serde_json::Value {
    let tag = "id=\"report-data\">";
    let start = html.find(tag).unwrap() + tag.len();
    let end = start + html[start..].find("</script>").unwrap();
    serde_json::from_str(&html[start..end]).unwrap()
}

#[test]
fn animation_gif_plays_every_frame_at_the_recording_rate() {
    use image::AnimationDecoder;
    let out = run_synthetic(
        "animation",
        &[
            "--animation",
            "gif",
            "--figures",
            "none",
            "--frame-rate",
            "20",
        ],
    );
    let bytes = std::fs::read(out.join("animation.gif")).unwrap();
    assert!(bytes.starts_with(b"GIF89a"));
    let decoder = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(&bytes)).unwrap();
    let frames = decoder.into_frames().collect_frames().unwrap();
    // 10 frames, under the decimation bound: all shown, each 1/20 s.
    assert_eq!(frames.len(), 10);
    for f in &frames {
        assert_eq!(f.delay().numer_denom_ms(), (50, 1));
    }
    // Composited frames differ: the blob moves.
    assert_ne!(frames[0].buffer(), frames[9].buffer());
    assert!(out.join("report.html").exists());
    let none = run_synthetic("no-animation", &["--figures", "none"]);
    assert!(!none.join("animation.gif").exists());
}

#[test]
fn match_search_best_pairs_every_surface_node_with_its_cheapest() {
    // Two independent samplings of one smooth pressure bump as (x, y, z) point files, the second
    // moved by SHIFT: a surface pair, for which `best` reads out many-to-one matches.
    const SHIFT: [f64; 2] = [0.7, -0.4];
    let dir = temp_dir("match-best");
    let mut seed = 99u64;
    let mut unit = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    // Lopsided on purpose (a heel and a smaller forefoot peak): a symmetric bump has several
    // equally good alignments.
    let height = |x: f64, y: f64| {
        6.0 * (-((x - 1.0).powi(2) / 10.0 + y * y / 6.0)).exp()
            + 4.0 * (-((x + 3.5).powi(2) + (y - 1.5).powi(2)) / 3.0).exp()
    };
    let mut sample = |n: usize, shift: [f64; 2]| -> Vec<[f64; 3]> {
        let mut pts = Vec::with_capacity(n);
        while pts.len() < n {
            let (x, y) = (unit() * 14.0 - 7.0, unit() * 10.0 - 5.0);
            let z = height(x, y);
            if z > 1.0 {
                pts.push([x + shift[0], y + shift[1], z]);
            }
        }
        pts
    };
    let (a, b) = (sample(110, [0.0, 0.0]), sample(118, SHIFT));
    let write = |name: &str, pts: &[[f64; 3]]| {
        let text: String = pts
            .iter()
            .map(|p| format!("{},{},{}\n", p[0], p[1], p[2]))
            .collect();
        std::fs::write(dir.join(name), format!("x,y,z\n{text}")).unwrap();
    };
    write("a.xyz", &a);
    write("b.xyz", &b);
    let tol = modal_core::shape::nearest_neighbour_stats_of(&b.concat(), 3).0;
    let hits = |search: &str| -> (Vec<usize>, f64) {
        let out = dir.join(search);
        pedomatch_ok(&[
            "match",
            dir.join("a.xyz").to_str().unwrap(),
            dir.join("b.xyz").to_str().unwrap(),
            "--search",
            search,
            "--out",
            out.to_str().unwrap(),
        ]);
        let rows: Vec<_> = read_csv(&out.join("matches.csv"))
            .into_iter()
            .filter(|r| r["excess"] == "0")
            .collect();
        let near = rows
            .iter()
            .filter(|r| {
                let (p, q) = (a[num(r, "node_a") as usize], b[num(r, "node_b") as usize]);
                let t = [p[0] + SHIFT[0], p[1] + SHIFT[1], p[2]];
                dist3(q, t) <= tol
            })
            .count();
        let nodes = rows.iter().map(|r| num(r, "node_a") as usize).collect();
        (nodes, near as f64 / a.len() as f64)
    };
    let (global_nodes, global) = hits("global");
    let (best_nodes, best) = hits("best");
    // Every node of A once, in order; B's nodes may repeat.
    assert_eq!(best_nodes, (0..a.len()).collect::<Vec<_>>());
    assert_eq!(global_nodes.len(), a.len());
    let summary = std::fs::read_to_string(dir.join("best").join("match.json")).unwrap();
    assert!(summary.contains("\"search\": \"best\""), "{summary}");
    // Measured: best 0.500, global 0.418; the nearest point of B to every true position 0.573.
    assert!(best > global + 0.05, "best {best:.3} vs global {global:.3}");
}

#[test]
fn run_errors_are_one_line() {
    let dir = temp_dir("errors");
    let bad = dir.join("bad.asf");
    std::fs::write(&bad, "ROWS 2\nCOLS 2\nASCII_DATA @@\nFrame 1\n1,2\n3\n").unwrap();
    let o = pedomatch(&[
        "run",
        bad.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("bad.asf"), "{err}");
    assert!(
        !dir.join("o").join("pairs.csv").exists(),
        "nothing written on failure"
    );

    let rec = synthetic_recording(&dir);
    let o = pedomatch(&["run", rec.to_str().unwrap(), "--frames", "5..3"]);
    assert!(!o.status.success());
    let o = pedomatch(&["run", rec.to_str().unwrap(), "--modes", "1.5"]);
    assert!(!o.status.success());
    assert!(String::from_utf8(o.stderr).unwrap().contains("modes"));
    let o = pedomatch(&["run", rec.to_str().unwrap(), "--center-stride", "0"]);
    assert!(!o.status.success());
    assert!(String::from_utf8(o.stderr)
        .unwrap()
        .contains("center_stride"));
}

#[test]
fn a_run_with_tables_only_writes_the_tables_of_a_run_with_figures() {
    // Tables only: the run streams (the .asf read frame by frame, windows of frames matched and
    // written as they go); with figures it is held whole. The tables are the same bytes.
    let dir = temp_dir("lean-vs-full");
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "run",
            walk,
            "--out",
            out.to_str().unwrap(),
            "--frames",
            "5..140",
        ];
        args.extend_from_slice(extra);
        let o = pedomatch_ok(&args);
        (out, String::from_utf8_lossy(&o.stdout).into_owned())
    };
    for tables in ["csv", "parquet"] {
        let (lean, lean_said) = run(
            &format!("lean-{tables}"),
            &["--figures", "none", "--report", "none", "--tables", tables],
        );
        let (full, full_said) = run(
            &format!("full-{tables}"),
            &[
                "--figures",
                "pairs",
                "--figure-format",
                "svg",
                "--report",
                "none",
                "--tables",
                tables,
            ],
        );
        // The same counts; the closing line lists what each folder holds.
        let counts = |said: &str| said.lines().take(2).collect::<Vec<_>>().join("\n");
        assert_eq!(counts(&lean_said), counts(&full_said));
        let files =
            format!("frames.{tables}, matches.{tables}, mean.npy, measures.json, objects.{tables}");
        assert!(
            lean_said.contains(&files) && !lean_said.contains("figures/"),
            "{lean_said}"
        );
        assert!(
            full_said.contains("figures/") && full_said.contains("tracks.svg"),
            "{full_said}"
        );
        let mut files = vec!["pairs.json".to_string()];
        files.extend(
            ["pairs", "objects", "matches", "tracks", "frames", "curves"]
                .map(|t| format!("{t}.{tables}")),
        );
        // The measures, taken frame by frame as the streamed run reads them, are the same too.
        files.extend(pedo_output::MEASURE_FILES.map(String::from));
        assert!(full.join("peak.svg").is_file() && !lean.join("peak.svg").exists());
        for f in &files {
            let (a, b) = (
                std::fs::read(lean.join(f)).unwrap(),
                std::fs::read(full.join(f)).unwrap(),
            );
            assert!(a == b, "{f} differs");
        }
        let mut a = read_json(&lean.join("summary.json"));
        let mut b = read_json(&full.join("summary.json"));
        a.as_object_mut().unwrap().remove("timings_s");
        b.as_object_mut().unwrap().remove("timings_s");
        // Only how the file was read differs: the lean run streamed it, the other read it whole.
        assert_eq!(a["input"]["streamed"], true);
        assert_eq!(b["input"]["streamed"], false);
        assert!(b["input"]["read_whole"]
            .as_str()
            .unwrap()
            .contains("figures"));
        // And the material points are followed only where figures are drawn: the lean run has
        // no point round trips to summarise.
        assert!(a["point_round_trip_sensels"].is_null());
        assert!(b["point_round_trip_sensels"]["steps"].as_u64().unwrap() > 100);
        // The summary line states them as summary.json records them, and only where they are.
        let p = |k: &str| b["point_round_trip_sensels"][k].as_f64().unwrap();
        let line = format!(
            "material points' round trip {:.3} sensels median, {:.3} at the 95th percentile ({:.1} % over 1 sensel)",
            p("median"),
            p("p95"),
            p("over_1_percent")
        );
        assert!(full_said.contains(&line), "{full_said}");
        assert!(!lean_said.contains("material points'"), "{lean_said}");
        for s in [&mut a, &mut b] {
            let input = s["input"].as_object_mut().unwrap();
            input.remove("streamed");
            input.remove("read_whole");
            s.as_object_mut()
                .unwrap()
                .remove("point_round_trip_sensels");
        }
        assert_eq!(a, b);
        assert!(a["tracks"].as_u64().unwrap() > 100);
    }
}

#[test]
fn match_warns_of_an_object_matched_with_itself() {
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    // The same frame twice: every node onto itself, and a warning that says how to ask for two.
    let o = pedomatch_ok(&["match", walk, walk, "--frame", "40"]);
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(
        err.contains("warning") && err.contains("the same object") && err.contains("--frame-b"),
        "{err}"
    );
    let frame = pedomatch(&["match", walk, walk, "--frame-b", "999"]);
    assert_eq!(frame.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&frame.stderr).contains("frame = 999"));
}

#[test]
fn match_warns_that_a_frame_does_not_apply_to_a_point_file() {
    let dir = temp_dir("frame-points");
    let (a, b) = (dir.join("a.xy"), dir.join("b.xy"));
    let circle = |r: f64| -> String {
        (0..24)
            .map(|k| {
                let t = k as f64 * std::f64::consts::TAU / 24.0;
                format!("{} {}\n", r * t.cos(), 0.7 * r * t.sin())
            })
            .collect()
    };
    std::fs::write(&a, circle(10.0)).unwrap();
    std::fs::write(&b, circle(11.0)).unwrap();
    let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
    let o = pedomatch_ok(&["match", a, b, "--frame", "3"]);
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(
        err.contains("--frame 3 does not apply to") && err.contains("a.xy") && err.contains("b.xy"),
        "{err}"
    );
    let quiet = pedomatch(&["match", a, b]);
    assert!(!String::from_utf8_lossy(&quiet.stderr).contains("does not apply"));
}

#[test]
fn a_run_whose_frames_hold_no_object_fails_and_writes_nothing() {
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let out = temp_dir("no-object").join("out");
    let o = pedomatch(&[
        "run",
        walk,
        "--frames",
        "204..205",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(
        err.starts_with(&format!(
            "pedomatch: error: {walk}: no object to match in frames 204..205"
        )) && err.lines().count() == 1,
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn an_isobaric_level_without_an_object_is_reported_not_dropped() {
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let out = temp_dir("iso-levels").join("out");
    pedomatch_ok(&[
        "run",
        walk,
        "--model",
        "isocontour",
        "--iso-levels",
        "10",
        "--figures",
        "none",
        "--report",
        "none",
        "--out",
        out.to_str().unwrap(),
    ]);
    let summary = read_json(&out.join("summary.json"));
    let skipped = summary["skipped"]["frames"].as_array().unwrap();
    // Every level is an object or a skipped entry naming it.
    assert_eq!(
        summary["objects"].as_u64().unwrap() as usize + skipped.len(),
        10
    );
    assert!(!skipped.is_empty(), "{summary}");
    for s in skipped {
        let reason = s["reason"].as_str().unwrap();
        assert!(
            reason.starts_with("isobaric level ")
                && reason.contains(" of 10 (")
                && reason.contains(" kPa): "),
            "{reason}"
        );
    }
    // The levels in kPa, as frames.csv's peak pressure (the file's units are kPa already).
    let objects = read_csv(&out.join("objects.csv"));
    let levels: Vec<f64> = objects.iter().map(|r| num(r, "level_kpa")).collect();
    assert!(levels.windows(2).all(|w| w[0] < w[1]), "{levels:?}");
    let peak = read_csv(&out.join("frames.csv"))
        .iter()
        .map(|r| num(r, "peak_pressure_kpa"))
        .fold(0.0, f64::max);
    assert!(
        levels.last().is_some_and(|&l| l < peak),
        "{levels:?} {peak}"
    );
}

#[test]
fn isobaric_levels_of_a_file_in_n_per_cm2_are_stated_in_kpa() {
    let txt = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/pedo-io/tests/data/footscan-FrasP01L-11-20.txt"
    );
    let out = temp_dir("iso-kpa").join("out");
    pedomatch_ok(&[
        "run",
        txt,
        "--model",
        "isocontour",
        "--figures",
        "none",
        "--report",
        "none",
        "--out",
        out.to_str().unwrap(),
    ]);
    // The file is in N/cm² (10 kPa each): the first of the evenly spaced levels is a tenth of
    // the frame's peak less a step, in kPa like the peak of frames.csv.
    let levels: Vec<f64> = read_csv(&out.join("objects.csv"))
        .iter()
        .map(|r| num(r, "level_kpa"))
        .collect();
    let peak = num(&read_csv(&out.join("frames.csv"))[0], "peak_pressure_kpa");
    assert!(
        levels[0] > 0.05 * peak && levels[0] < 0.15 * peak,
        "{levels:?} {peak}"
    );
}

#[test]
fn units_pitch_and_rate_given_for_an_npy_give_forces_in_newtons() {
    // 200 kPa at most on 5 × 5 mm sensels: the frames table states newtons and kPa.
    let out = run_synthetic(
        "npy-units",
        &[
            "--units",
            "kPa",
            "--pitch-mm",
            "5",
            "--frame-rate",
            "100",
            "--figures",
            "none",
        ],
    );
    let frames = read_csv(&out.join("frames.csv"));
    let row = &frames[0];
    assert!(
        row.contains_key("total_force_n") && row.contains_key("peak_pressure_kpa"),
        "{row:?}"
    );
    // Force = sum of the values (kPa) × 25 mm² × 1e-3; the area in mm².
    let sensors = num(row, "contact_sensors");
    assert!((num(row, "contact_area_mm2") - 25.0 * sensors).abs() < 1e-6);
    assert!(num(row, "total_force_n") > 0.0 && num(row, "peak_pressure_kpa") <= 200.0);
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["recording"]["pressure_units"], "kPa");
    let o = pedomatch(&["run", "x.npy", "--units", "furlongs"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("units = furlongs"));
}

#[test]
fn match_reads_a_footscan_text_export_as_a_recording() {
    // A .txt is a point file only when laid out as points: a footscan export is a recording.
    let txt = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/pedo-io/tests/data/footscan-FrasP01L-11-20.txt"
    );
    let o = pedomatch_ok(&[
        "match",
        txt,
        txt,
        "--frame",
        "0",
        "--frame-b",
        "1",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["optimisation_matches"].as_u64().unwrap() >= 8, "{v}");
    // A .txt of points is still a point file.
    let dir = temp_dir("match-txt");
    let ring: String = (0..30)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 30.0;
            format!("{} {}\n", 3.0 * t.cos(), 2.0 * t.sin())
        })
        .collect();
    std::fs::write(dir.join("a.txt"), &ring).unwrap();
    let a = dir.join("a.txt");
    let o = pedomatch_ok(&["match", a.to_str().unwrap(), a.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["optimisation_matches"], 30, "{v}");
}

#[test]
fn the_run_report_opens_in_the_analysed_frames_and_breaks_the_cop_path_at_swings() {
    // Frames 55..100 of the walk start in a swing (no contact until frame 64).
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let out = temp_dir("report-frames").join("out");
    pedomatch_ok(&[
        "run",
        walk,
        "--frames",
        "55..100",
        "--figures",
        "none",
        "--out",
        out.to_str().unwrap(),
    ]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("<th>frames</th><td>55–99 of 205 analysed, 60 × 21 sensels</td>"),
        "the header does not state the analysed frames"
    );
    let d = embedded_json(&html);
    assert_eq!(d["analysed"], serde_json::json!([55, 100]));
    // The player opens on the first frame holding objects, and plays the whole recording.
    let first = read_csv(&out.join("objects.csv"))
        .iter()
        .map(|r| num(r, "frame") as u64)
        .min()
        .unwrap();
    assert!((64..100).contains(&first), "{first}");
    assert_eq!(d["open_frame"], first);
    assert_eq!(d["shown"].as_array().unwrap().len(), 205);
    // The centre-of-pressure path: one piece per run of frames with contact, none across a swing.
    let area: Vec<f64> = serde_json::from_value(d["series"]["area"].clone()).unwrap();
    let frames: Vec<Option<usize>> =
        serde_json::from_value(d["series"]["cop_path"]["frame"].clone()).unwrap();
    let pieces: Vec<Vec<usize>> = frames
        .split(|f| f.is_none())
        .map(|p| p.iter().map(|f| f.unwrap()).collect())
        .collect();
    let contact: Vec<usize> = (0..area.len()).filter(|&f| area[f] > 0.0).collect();
    let runs: Vec<Vec<usize>> = contact
        .chunk_by(|a, b| b - a == 1)
        .map(|r| r.to_vec())
        .collect();
    assert!(runs.len() >= 7, "{} stance phases", runs.len());
    assert_eq!(pieces, runs);
}

#[test]
fn the_run_reports_load_series_is_the_frames_csv_load_with_its_units() {
    // The synthetic .npy states no units: without a pitch the load is the plain sum of the
    // values (frames.csv `total_load_sensels`), with one × mm² (`total_load_mm2`); with kPa and
    // a pitch it is a force in newtons (`total_force_n`).
    for (name, extra, column, label) in [
        (
            "load-sensels",
            &[][..],
            "total_load_sensels",
            "total load (pressure units unknown × sensels)",
        ),
        (
            "load-mm2",
            &["--pitch-mm", "5"][..],
            "total_load_mm2",
            "total load (pressure units unknown × mm²)",
        ),
        (
            "load-n",
            &["--pitch-mm", "5", "--units", "kPa"][..],
            "total_force_n",
            "total force (N)",
        ),
    ] {
        let mut args = vec!["--figures", "none"];
        args.extend_from_slice(extra);
        let out = run_synthetic(name, &args);
        let frames = read_csv(&out.join("frames.csv"));
        let d = embedded_json(&std::fs::read_to_string(out.join("report.html")).unwrap());
        assert_eq!(d["series"]["force_label"], label, "{name}");
        for (f, row) in frames.iter().enumerate() {
            let (csv, shown) = (num(row, column), d["series"]["force"][f].as_f64().unwrap());
            assert!(
                (csv - shown).abs() <= 1e-3 * csv.abs().max(1.0),
                "{name} frame {f}"
            );
        }
        let peak = d["series"]["peak_label"].as_str().unwrap();
        assert!(!peak.contains("(units)"), "{peak}");
    }
}

#[test]
fn two_frames_of_oblong_sensels_are_matched_in_their_true_proportions() {
    // footscan's sensels are 7.62 mm tall and 5.08 mm wide: `match` on two frames of such a
    // grid gives the matches of the two outlines with y scaled by 1.5, as `run` does.
    let walk = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let dir = temp_dir("match-oblong");
    let rec = pedo_io::formats::read_recording(Path::new(walk)).unwrap();
    let opts = pedo_io::ContourOptions {
        resample: pedo_io::Resample::Spacing(1.0),
        include_holes: false,
        ..Default::default()
    };
    for (frame, name) in [(40, "a.xy"), (41, "b.xy")] {
        let cs = pedo_io::contours(&rec.frame(frame).unwrap(), &opts).unwrap();
        let largest = cs
            .iter()
            .max_by(|x, y| x.area().total_cmp(&y.area()))
            .unwrap();
        let text: String = largest
            .points
            .iter()
            .map(|p| format!("{:?} {:?}\n", p[0], p[1] * 1.5))
            .collect();
        std::fs::write(dir.join(name), text).unwrap();
    }
    let matches = |args: &[&str], out: &str| {
        let out = dir.join(out);
        pedomatch_ok(
            &[
                args,
                &[
                    "--report",
                    "none",
                    "--figures",
                    "none",
                    "--out",
                    out.to_str().unwrap(),
                ],
            ]
            .concat(),
        );
        let csv = std::fs::read_to_string(out.join("matches.csv")).unwrap();
        // node_a, node_b and excess (the costs are normalised alike, but written rounded).
        csv.lines()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                format!("{},{},{}", f[0], f[1], f[3])
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (dir.join("a.xy"), dir.join("b.xy"));
    let scaled = matches(
        &["match", a.to_str().unwrap(), b.to_str().unwrap()],
        "scaled",
    );
    // Two files (a copy of the walk): the pair defaults, as for the point files. (One file
    // would be matched with the run's settings, its objects the run's.)
    let copy = dir.join("copy.asf");
    std::fs::copy(walk, &copy).unwrap();
    let frames = [
        "match",
        walk,
        copy.to_str().unwrap(),
        "--frame",
        "40",
        "--frame-b",
        "41",
    ];
    let oblong = matches(
        &[&frames[..], &["--pitch-mm", "5.08x7.62"]].concat(),
        "oblong",
    );
    assert!(scaled.len() > 50);
    assert_eq!(oblong, scaled);
    let square = matches(&frames, "square");
    assert_ne!(square, scaled, "the proportions change the matches");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_ordered_solver_runs_contours_without_crossings_and_refuses_surfaces() {
    let out = run_synthetic("ordered", &["--solver", "ordered", "--figures", "none"]);
    let rows = read_csv(&out.join("pairs.csv"));
    assert_eq!(rows.len(), 9);
    for row in &rows {
        assert_eq!(row["status"], "ok");
        assert_eq!(num(row, "crossings"), 0.0);
        assert_eq!(
            num(row, "optimisation_matches"),
            num(row, "nodes_a").min(num(row, "nodes_b"))
        );
    }
    assert_tracks_follow_the_motion(&read_csv(&out.join("tracks.csv")));
    // The default solver's pairs carry the count too.
    let jv = run_synthetic("ordered-jv", &["--figures", "none"]);
    assert!(read_csv(&jv.join("pairs.csv"))
        .iter()
        .all(|r| r["crossings"].parse::<usize>().is_ok()));

    let dir = temp_dir("ordered-surface");
    let rec = synthetic_recording(&dir);
    let args = [
        "run",
        rec.to_str().unwrap(),
        "--model",
        "surface",
        "--solver",
        "ordered",
    ];
    let o = pedomatch(&args);
    assert!(!o.status.success());
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("solver") && err.contains("closed contours"),
        "{err}"
    );
}

#[test]
fn the_measures_of_the_walk_agree_with_its_frames_table() {
    // measures.json against the frames table's own per-frame force, peak and area.
    let dir = temp_dir("measures");
    let out = dir.join("walk");
    pedomatch_ok(&["demo", "--out", out.to_str().unwrap(), "--report", "none"]);
    let m = read_json(&out.join("measures.json"));
    let frames = read_csv(&out.join("frames.csv"));
    let col = |k: &str| frames.iter().map(|r| num(r, k)).collect::<Vec<f64>>();
    let (force, peak, area) = (
        col("total_force_n"),
        col("peak_pressure_kpa"),
        col("contact_area_mm2"),
    );
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let value = |k: &str, unit: &str| {
        assert_eq!(m["values"][k]["unit"], unit, "{k}");
        m["values"][k]["value"].as_f64().unwrap()
    };
    let close = |a: f64, b: f64, rel: f64| (a - b).abs() <= rel * b.abs();
    let dt = 0.032;
    assert!(close(value("peak_force", "N"), max(&force), 1e-4));
    assert!(close(value("peak_pressure", "kPa"), max(&peak), 1e-6));
    assert!(close(value("max_contact_area", "mm²"), max(&area), 1e-6));
    let fti: f64 = force.iter().sum::<f64>() * dt;
    assert!(close(value("fti", "N·s"), fti, 1e-4));
    // Contact time: the first and last frames above 10 % of the force range.
    let lo = force.iter().copied().fold(f64::INFINITY, f64::min);
    let threshold = lo + 0.1 * (max(&force) - lo);
    let first = force.iter().position(|&f| f > threshold).unwrap();
    let last = force.iter().rposition(|&f| f > threshold).unwrap();
    assert_eq!(m["contact_frames"], serde_json::json!([first, last]));
    assert!(close(
        value("contact_time", "s"),
        (last - first + 1) as f64 * dt,
        1e-9
    ));
    assert!(value("pti_max", "kPa·s") > 0.0);
    for f in ["peak.npy", "pti.npy", "mean.npy"] {
        let bytes = std::fs::read(out.join(f)).unwrap();
        assert!(bytes.starts_with(b"\x93NUMPY\x01\x00"), "{f}");
        // Header, then 60 × 21 float64.
        assert_eq!((bytes.len() - 128) / 8, 60 * 21, "{f}");
        let header = String::from_utf8_lossy(&bytes[10..128]).into_owned();
        assert!(
            header.contains("'descr': '<f8'") && header.contains("(60, 21)"),
            "{header}"
        );
    }
    assert_png(&out.join("peak.png"));
    assert_png(&out.join("pti.png"));
}

#[test]
fn a_run_without_out_never_replaces_the_results_of_another_input() {
    let dir = temp_dir("default-out");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let walk = root.join("examples/data/FrasP01L.asf");
    let emed = root.join("crates/pedo-io/tests/data/emed-test-1-10.lst");
    let run = |args: &[&std::ffi::OsStr]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_pedomatch"))
            .current_dir(&dir)
            .arg("run")
            .args(args)
            .args(["--figures", "none", "--report", "none"])
            .output()
            .unwrap()
    };
    let out = dir.join("pedomatch-out");
    let first = run(&[emed.as_os_str()]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = std::fs::read(out.join("summary.json")).unwrap();
    // The same input again replaces its own results.
    let again = run(&[emed.as_os_str()]);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    // Another input is refused, with one line naming the earlier input, the folder untouched.
    let other = run(&[walk.as_os_str()]);
    assert_eq!(other.status.code(), Some(1));
    let err = String::from_utf8_lossy(&other.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("emed-test-1-10.lst") && err.contains("--out"),
        "{err}"
    );
    let summary = read_json(&out.join("summary.json"));
    assert!(summary["input"]["file"]
        .as_str()
        .unwrap()
        .ends_with("emed-test-1-10.lst"));
    assert_eq!(
        summary["input"],
        serde_json::from_slice::<serde_json::Value>(&before).unwrap()["input"]
    );
    // Naming the folder replaces it, as with any --out.
    let named = run(&[walk.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(
        named.status.success(),
        "{}",
        String::from_utf8_lossy(&named.stderr)
    );
    let summary = read_json(&out.join("summary.json"));
    assert!(summary["input"]["file"]
        .as_str()
        .unwrap()
        .ends_with("FrasP01L.asf"));
    let _ = std::fs::remove_dir_all(&dir);
}
