//! pedomatch's own outputs, recognised so that one given as a recording is refused naming it:
//! a results table such as `frames.csv` has a header row of names and rows of numbers, which a
//! CSV grid reader would otherwise take for a pressure grid (its rows for sensor rows) and run.
//!
//! The tables are written by `pedo-output` (and `pedo-study`, and `pedomatch match`), which
//! come after this crate: the names that tell each table apart are listed here, where reading
//! sees them, and `pedo-output`'s tests check that every table a run writes is recognised as
//! itself ([`own_table`]).

/// One of pedomatch's result tables: its file name, what it holds, and the column names its
/// header row always has (whatever the recording's units: a header holding all of them is that
/// table's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OwnTable {
    /// The file name pedomatch writes it under (`frames.csv`).
    pub file: &'static str,
    /// What it holds, for the message.
    pub what: &'static str,
    /// The columns its header always has.
    pub columns: &'static [&'static str],
}

/// Every table pedomatch writes as CSV, with the columns that tell it apart. A header that holds
/// the columns of several (`pedomatch match`'s `matches.csv` is a part of a run's) is the one
/// with the most.
pub const OWN_TABLES: [OwnTable; 16] = [
    OwnTable {
        file: "frames.csv",
        what: "the per-frame measures of a run",
        columns: &["frame", "contact_sensors", "cop_x", "cop_y"],
    },
    OwnTable {
        file: "objects.csv",
        what: "the objects of a run",
        columns: &["id", "frame", "index", "nodes", "centroid_x", "centroid_y"],
    },
    OwnTable {
        file: "pairs.csv",
        what: "the matched pairs of a run",
        columns: &[
            "id_a",
            "id_b",
            "frame_a",
            "frame_b",
            "nodes_a",
            "nodes_b",
            "local_matches",
            "status",
        ],
    },
    OwnTable {
        file: "matches.csv",
        what: "the node matches of a run",
        columns: &[
            "id_a",
            "id_b",
            "node_a",
            "node_b",
            "cost",
            "excess",
            "trackable",
            "distance",
        ],
    },
    OwnTable {
        file: "reference_matches.csv",
        what: "the reference matches of a drift-corrected run",
        columns: &[
            "id_a", "id_b", "node_a", "node_b", "cost", "excess", "tracked", "distance",
        ],
    },
    OwnTable {
        file: "tracks.csv",
        what: "the node tracks of a run",
        columns: &["track", "step", "frame", "object_id", "node", "x", "y"],
    },
    OwnTable {
        file: "points.csv",
        what: "the material points of a run",
        columns: &["point", "step", "frame", "object_id", "seed_node", "x", "y"],
    },
    OwnTable {
        file: "matches.csv",
        what: "the matches of pedomatch match",
        columns: &["node_a", "node_b", "cost", "excess"],
    },
    OwnTable {
        file: "curves.csv",
        what: "the stance-normalised curves of a run",
        columns: &["stance", "complete", "percent"],
    },
    OwnTable {
        file: "region_series.csv",
        what: "the followed regions of a run",
        columns: &["region", "kind", "frame", "sensels"],
    },
    OwnTable {
        file: "regions.csv",
        what: "the anatomical regions of a run",
        columns: &["region", "measure", "value", "unit"],
    },
    OwnTable {
        file: "study_curves.csv",
        what: "a study's stance-normalised curves",
        columns: &["path", "output", "stance", "complete", "percent"],
    },
    OwnTable {
        file: "study_regions.csv",
        what: "a study's anatomical regions",
        columns: &["trial", "region", "measure", "value", "unit"],
    },
    OwnTable {
        file: "study_feet.csv",
        what: "a study's values per foot of its two-insole trials",
        columns: &["trial", "foot", "peak_pressure_kpa", "contact_time_s"],
    },
    OwnTable {
        file: "study.csv",
        what: "a study's table of runs",
        columns: &[
            "path",
            "output",
            "format",
            "frames",
            "pairs",
            "tracks",
            "wall_time_s",
            "status",
        ],
    },
    OwnTable {
        file: "registration.csv",
        what: "the per-trial maps and quality of a footprint registration",
        columns: &[
            "trial",
            "fallback",
            "turn_deg",
            "residual_sensels",
            "mask_xor_pct",
        ],
    },
];

/// The table of [`OWN_TABLES`] whose header row `text` (a file's first characters) starts with,
/// if any: every column of the table among the first line's names (separated by commas,
/// semicolons or tabs, a byte-order mark and quotes aside).
///
/// ```
/// use pedo_io::formats::own_tables::own_table;
/// let frames = "frame,time_s,contact_sensors,contact_area_mm2,total_force_n,peak_pressure_kpa,cop_x,cop_y\n0,0,0,0,0,0,,\n";
/// assert_eq!(own_table(frames).map(|t| t.file), Some("frames.csv"));
/// assert_eq!(own_table("node_a,node_b,cost,excess\n0,1,0.5,0\n").map(|t| t.what), Some("the matches of pedomatch match"));
/// assert_eq!(own_table("0,1,2,3\n4,5,6,7\n"), None);
/// ```
pub fn own_table(text: &str) -> Option<&'static OwnTable> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let first = text.lines().map(str::trim).find(|l| !l.is_empty())?;
    let names: Vec<&str> = first
        .split([',', ';', '\t'])
        .map(|n| n.trim().trim_matches('"'))
        .collect();
    OWN_TABLES
        .iter()
        .filter(|t| t.columns.iter().all(|c| names.contains(c)))
        .max_by_key(|t| t.columns.len())
}

/// What a file holding one of pedomatch's own outputs is, when `head` (its first bytes) shows
/// one: a results table ([`own_table`]), a Parquet table, or a record (`summary.json`,
/// `match.json`, `study.json`, which name `pedomatch_version`).
pub fn own_output(head: &[u8]) -> Option<String> {
    if head.starts_with(b"PAR1") {
        return Some(
            "a Parquet table (as pedomatch writes its results with --tables parquet), not a \
             recording"
                .into(),
        );
    }
    let head = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    let text = String::from_utf8_lossy(head);
    if let Some(t) = own_table(&text) {
        return Some(format!(
            "this is pedomatch's own {} (a results table: {}), not a recording; give the \
             recording it was made from",
            t.file, t.what
        ));
    }
    let json = text.trim_start().starts_with('{');
    (json && text.contains("\"pedomatch_version\"")).then(|| {
        "this is pedomatch's own record of a run or match (summary.json, match.json or \
         study.json), not a recording"
            .into()
    })
}
