//! End-to-end tests of `pedomatch run --points FILE --regions FILE`: the user's points and
//! regions followed through a synthetic walk, written to points.csv and region_series.csv.

use crate::common::{pedomatch, pedomatch_ok, read_csv, temp_dir};
use std::collections::HashMap;
use std::path::Path;

fn num(row: &HashMap<String, String>, k: &str) -> f64 {
    row[k]
        .parse()
        .unwrap_or_else(|_| panic!("{k} = {:?}", row[k]))
}

#[test]
fn run_follows_given_points_and_regions_into_their_tables() {
    let dir = temp_dir("user-points");
    let walk = pedo_io::synthetic::SyntheticWalk {
        frames: 20,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let npy = dir.join("walk.npy");
    pedo_io::formats::npy::write_npy(&rec, &npy).unwrap();
    let c = walk.centre();
    let points = dir.join("points.csv");
    std::fs::write(
        &points,
        format!("name,x,y\nforefoot,{},{}\n", c[0], c[1] - 10.0),
    )
    .unwrap();
    // The forefoot: the loaded sensels of frame 0 above row 30, label 1; a CSV grid.
    let g = rec.frame(0).unwrap();
    let label = |r: usize, c: usize| u8::from(r < 30 && g.get(r, c) >= 10.0);
    let grid: String = (0..rec.rows())
        .map(|r| {
            let row: Vec<String> = (0..rec.cols()).map(|c| label(r, c).to_string()).collect();
            row.join(",") + "\n"
        })
        .collect();
    let mask = dir.join("mask.csv");
    std::fs::write(&mask, grid).unwrap();
    let out = dir.join("out");
    let arg = |p: &Path| p.to_str().unwrap().to_string();
    // Tables only: the user's points and regions are followed all the same.
    pedomatch_ok(&[
        "run",
        &arg(&npy),
        "--noise",
        "10",
        "--points",
        &arg(&points),
        "--regions",
        &arg(&mask),
        "--figures",
        "none",
        "--report",
        "none",
        "--out",
        &arg(&out),
    ]);
    let rows = read_csv(&out.join("points.csv"));
    let user: Vec<_> = rows.iter().filter(|r| r["kind"] == "user").collect();
    assert_eq!(user.len(), 20, "one row a frame");
    assert!(user.iter().all(|r| r["name"] == "forefoot"));
    assert!(rows
        .iter()
        .any(|r| r["kind"] == "outline" && r["name"].is_empty()));
    for r in &user {
        let t = num(r, "frame") as usize;
        let truth = walk.true_position(t, [c[0], c[1] - 10.0]);
        let e = (num(r, "x") - truth[0]).hypot(num(r, "y") - truth[1]);
        assert!(e < 1.0, "frame {t}: {e:.3} sensels off");
        assert!(num(r, "pressure") > 10.0);
    }
    let regions = read_csv(&out.join("region_series.csv"));
    assert_eq!(regions.len(), 40, "moving and fixed rows on 20 frames");
    // Oracle: the fixed region's load on frame 0 is the sum of the mask's loaded values (no
    // pitch, no units in a .npy: the plain sum), and the moving region starts as the mask.
    let want: f64 = (0..rec.rows())
        .flat_map(|r| (0..rec.cols()).map(move |c| (r, c)))
        .filter(|&(r, c)| label(r, c) == 1)
        .map(|(r, c)| g.get(r, c))
        .sum();
    let at0: Vec<_> = regions.iter().filter(|r| r["frame"] == "0").collect();
    for r in &at0 {
        let got = num(r, "total_load_sensels");
        assert!(
            (got - want).abs() < 1e-3 * want,
            "{} {got} vs {want}",
            r["kind"]
        );
    }
    assert_eq!(at0[0]["sensels"], at0[1]["sensels"]);
    // A point outside every object: exit 1, the point named, no folder.
    std::fs::write(&points, "name,x,y\ncorner,0.5,0.5\n").unwrap();
    let bad = dir.join("bad");
    let o = pedomatch(&[
        "run",
        &arg(&npy),
        "--noise",
        "10",
        "--points",
        &arg(&points),
        "--out",
        &arg(&bad),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("\"corner\"") && err.contains("no object"),
        "{err}"
    );
    assert!(!bad.exists());
}
