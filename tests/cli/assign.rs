//! End-to-end tests of `pedomatch assign`.

use crate::common::{pedomatch, pedomatch_ok};

fn write_temp(name: &str, contents: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("pedomatch-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

#[test]
fn bundled_example_has_known_optimum_for_every_method() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/cost.csv");
    for method in ["jv", "hungarian", "simplex"] {
        let out = pedomatch_ok(&["assign", example, "--solver", method, "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["total_cost"].as_f64().unwrap(), 6.0, "method {method}");
        let pairs: Vec<(usize, usize)> = serde_json::from_value(v["pairs"].clone()).unwrap();
        assert_eq!(pairs, vec![(0, 1), (1, 0), (2, 2), (3, 4)]);
    }
}

#[test]
fn maximize_and_table_output() {
    let path = write_temp("max.csv", "1,2\n3,4\n");
    let out = pedomatch_ok(&["assign", path.to_str().unwrap(), "--maximize"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("total cost: 5 (2 pairs)"), "{text}");
}

#[test]
fn bad_input_gives_one_clear_line_and_failure() {
    let ragged = write_temp("ragged.csv", "1,2\n3\n");
    let out = pedomatch(&["assign", ragged.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("ragged.csv:2") && err.lines().count() == 1,
        "{err}"
    );

    let infeasible = write_temp("inf.csv", "inf,inf\n1,2\n");
    let out = pedomatch(&["assign", infeasible.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8(out.stderr)
        .unwrap()
        .contains("infeasible"));

    let missing = pedomatch(&["assign", "/nonexistent/cost.csv"]);
    assert!(!missing.status.success());

    // An empty file (or one of comments only) is no matrix, not an empty assignment.
    for (name, text) in [("empty.csv", ""), ("comments.csv", "# nothing\n\n")] {
        let path = write_temp(name, text);
        let out = pedomatch(&["assign", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(
            err.contains(name) && err.contains("no cost matrix") && err.lines().count() == 1,
            "{err}"
        );
    }
}
