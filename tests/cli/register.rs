//! End-to-end tests of `pedomatch register`: the folder it writes, read back independently, and
//! its errors' exit codes.

use crate::common::{pedomatch, pedomatch_ok, read_csv, temp_dir};
use std::path::Path;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/crates/pedo-io/tests/data");

/// The `.npy` member `name` of a stored `.npz` (as `registered.npz` is written): its header
/// dict and data bytes, found by scanning the local headers.
fn npz_member(bytes: &[u8], name: &str) -> (String, Vec<u8>) {
    let mut at = 0;
    while at + 30 <= bytes.len() && bytes[at..at + 4] == [0x50, 0x4b, 3, 4] {
        let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]) as usize;
        let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
        let size = u32_at(at + 18);
        let (nlen, xlen) = (u16_at(at + 26), u16_at(at + 28));
        let member = std::str::from_utf8(&bytes[at + 30..at + 30 + nlen]).unwrap();
        let data = &bytes[at + 30 + nlen + xlen..at + 30 + nlen + xlen + size];
        if member == name {
            assert_eq!(&data[..6], b"\x93NUMPY");
            let hlen = u16_at(at + 30 + nlen + xlen + 8);
            let header = std::str::from_utf8(&data[10..10 + hlen])
                .unwrap()
                .to_string();
            return (header, data[10 + hlen..].to_vec());
        }
        at += 30 + nlen + xlen + size;
    }
    panic!("no member {name}");
}

#[test]
fn the_template_registered_onto_itself_and_a_shifted_copy() {
    let base = temp_dir("register-cli");
    let input = base.join("in");
    std::fs::create_dir_all(&input).unwrap();
    let text = std::fs::read_to_string(Path::new(DATA).join("MUN104R.csv")).unwrap();
    std::fs::write(input.join("a.csv"), &text).unwrap();
    // The same foot two sensels lower and one to the right (zeros shifted in).
    let rows: Vec<&str> = text.lines().collect();
    let cols = rows[0].split(',').count();
    let mut shifted: Vec<String> = vec![vec!["0"; cols].join(","); 2];
    for r in &rows[..rows.len() - 2] {
        let mut v: Vec<&str> = r.split(',').collect();
        v.pop();
        v.insert(0, "0");
        shifted.push(v.join(","));
    }
    std::fs::write(input.join("b.csv"), shifted.join("\n") + "\n").unwrap();
    let out = base.join("out");
    pedomatch_ok(&[
        "register",
        input.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--template",
        "mun104",
    ]);
    let table = read_csv(&out.join("registration.csv"));
    assert_eq!(table.len(), 2);
    for row in &table {
        let c: f64 = row["correlation"].parse().unwrap();
        let xor: f64 = row["mask_xor_pct"].parse().unwrap();
        assert!(c > 0.99, "{row:?}");
        assert!(xor < 3.0, "{row:?}");
        assert_eq!(row["fallback"], "0");
    }
    // b's map carries the template's grid one sensel right and two down.
    let b = table
        .iter()
        .find(|r| r["trial"].ends_with("b.csv"))
        .unwrap();
    let tx: f64 = b["tx_sensels"].parse().unwrap();
    let ty: f64 = b["ty_sensels"].parse().unwrap();
    assert!((tx - 1.0).abs() < 0.3 && (ty - 2.0).abs() < 0.3, "{b:?}");
    // The stack holds both trials on the template's 63 x 27 grid, equal to it nearly everywhere.
    let npz = std::fs::read(out.join("registered.npz")).unwrap();
    let (header, data) = npz_member(&npz, "peak.npy");
    assert!(header.contains("'shape': (2, 63, 27)"), "{header}");
    let (_, tpl) = npz_member(&npz, "template_peak.npy");
    let f = |b: &[u8]| -> Vec<f64> {
        b.chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let (peak, tpl) = (f(&data), f(&tpl));
    let max = tpl.iter().cloned().fold(0.0, f64::max);
    for k in 0..2 {
        let worst = peak[k * tpl.len()..(k + 1) * tpl.len()]
            .iter()
            .zip(&tpl)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.15 * max, "trial {k}: {worst} of {max}");
    }
    let (names, _) = npz_member(&npz, "trials.npy");
    assert!(names.contains("'shape': (2,)"), "{names}");
    assert!(out.join("registered.png").exists());
    // The page embeds both trials, their images as the stack holds them, and the CSV's rows.
    let html = std::fs::read_to_string(out.join("register.html")).unwrap();
    let at = html.find("id=\"report-data\">").unwrap() + "id=\"report-data\">".len();
    let end = at + html[at..].find("</script>").unwrap();
    let d: serde_json::Value = serde_json::from_str(&html[at..end]).unwrap();
    assert_eq!(d["trials"], 2);
    assert_eq!(
        (d["rows"].as_u64(), d["cols"].as_u64()),
        (Some(63), Some(27))
    );
    let shown = d["shown"].as_array().unwrap();
    assert_eq!(shown.len(), 2);
    for (k, t) in shown.iter().enumerate() {
        let embedded = t["peak"].as_array().unwrap();
        assert_eq!(embedded.len(), tpl.len());
        for (e, v) in embedded.iter().zip(&peak[k * tpl.len()..]) {
            assert!((e.as_f64().unwrap() - v).abs() <= 1e-5 * v.abs(), "{e} {v}");
        }
        assert_eq!(t["name"].as_str(), Some(table[k]["trial"].as_str()));
        let csv: f64 = table[k]["mask_xor_pct"].parse().unwrap();
        let page = d["quality"][k]["mask_xor_pct"].as_f64().unwrap();
        assert!((csv - page).abs() < 1e-3, "{csv} {page}");
    }
}

#[test]
fn errors_have_their_exit_codes() {
    let base = temp_dir("register-cli-errors");
    std::fs::create_dir_all(&base).unwrap();
    let empty = base.join("empty.csv");
    std::fs::write(&empty, "0,0,0\n0,0,0\n0,0,0\n").unwrap();
    let out = base.join("out");
    let o = pedomatch(&[
        "register",
        empty.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("empty.csv"), "{err}");
    assert!(!out.exists());
    let mun = format!("{DATA}/MUN104R.csv");
    let o = pedomatch(&[
        "register",
        &mun,
        "--out",
        out.to_str().unwrap(),
        "--max-turn",
        "400",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
}
