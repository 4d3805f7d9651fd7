//! Property tests: the parsers never panic on arbitrary or mutated bytes, and the geometry
//! never panics on arbitrary frames.

use pedo_io::formats::{asf, csv, lst, npy};
use pedo_io::surface::{surface, SurfaceOptions};
use pedo_io::{contours, parse_bytes, ContourMethod, ContourOptions, Format, Grid, Resample};
use proptest::prelude::*;
use std::sync::OnceLock;

fn sample(name: &str) -> &'static [u8] {
    static ASF: OnceLock<Vec<u8>> = OnceLock::new();
    static LST: OnceLock<Vec<u8>> = OnceLock::new();
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/");
    let cell = if name.ends_with("asf") { &ASF } else { &LST };
    // Short but complete excerpts (3 frames / 3 pages) keep each case fast while covering
    // headers, data, the closing @@ and page breaks.
    cell.get_or_init(|| {
        let text =
            String::from_utf8_lossy(&std::fs::read(format!("{dir}{name}")).unwrap()).into_owned();
        if name.ends_with("asf") {
            let end = text.find("Frame 4").unwrap();
            format!("{}@@\r\n", &text[..end])
                .replace("END_FRAME 205", "END_FRAME 3")
                .into_bytes()
        } else {
            let third = text.match_indices('\x0c').nth(2).unwrap().0;
            text[..third].bytes().collect()
        }
    })
}

fn mutate(base: &[u8], edits: &[(usize, u8)], cut: usize) -> Vec<u8> {
    let mut v = base.to_vec();
    for &(i, b) in edits {
        let n = v.len();
        if n > 0 {
            v[i % n] = b;
        }
    }
    v.truncate(cut % (base.len() + 1));
    v
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]

    #[test]
    fn parsers_survive_arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let _ = asf::parse_asf(&bytes, "f");
        let _ = lst::parse_lst(&bytes, "f");
        let _ = csv::parse_csv(&bytes, "f");
        let _ = npy::parse_npy(&bytes, "f");
        for f in [Format::Png, Format::Tiff] {
            let _ = parse_bytes(&bytes, f, "f");
        }
    }

    #[test]
    fn parsers_survive_text_like_bytes(s in "[0-9B,;.\\t \\r\\n@a-zA-Z:x\\-]{0,400}") {
        let b = s.as_bytes();
        let _ = asf::parse_asf(b, "f");
        let _ = lst::parse_lst(b, "f");
        if let Ok(r) = csv::parse_csv(b, "f") {
            prop_assert!(r.rows() * r.cols() == r.data().len());
        }
    }

    #[test]
    fn excerpts_parse_and_mutations_never_panic(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..6), cut in any::<usize>()) {
        for (name, fmt) in [("FrasP01L.asf", Format::Asf), ("synthetic-walk.lst", Format::Lst)] {
            prop_assert_eq!(parse_bytes(sample(name), fmt, name).unwrap().n_frames(), 3);
            let v = mutate(sample(name), &edits, cut);
            if let Ok(r) = parse_bytes(&v, fmt, name) {
                // A recording that parses is complete: every frame has every value.
                prop_assert_eq!(r.data().len(), r.n_frames() * r.rows() * r.cols());
            }
        }
    }

    #[test]
    fn npy_header_mutations_never_panic(edits in proptest::collection::vec((0usize..128, any::<u8>()), 0..4), cut in any::<usize>()) {
        let rec = pedo_io::Recording::new(2, 3, 4, (0..24).map(|v| v as f32).collect(), vec![true; 12]).unwrap();
        let v = mutate(&npy::recording_to_npy(&rec), &edits, cut);
        let _ = npy::parse_npy(&v, "f.npy");
    }

    #[test]
    fn geometry_never_panics(rows in 1usize..9, cols in 1usize..9, vals in proptest::collection::vec(0u8..6, 81), level in 0.0f64..6.0, chain in any::<bool>(), nodes in 3usize..20) {
        let data: Vec<f64> = vals[..rows * cols].iter().map(|&v| v as f64).collect();
        let g = Grid::new(rows, cols, data).unwrap();
        let method = if chain { ContourMethod::Chain { high: None, refine: true } } else { ContourMethod::default() };
        let opts = ContourOptions { level: Some(level), method, resample: Resample::Points(8), ..Default::default() };
        for c in contours(&g, &opts).unwrap() {
            prop_assert_eq!(c.points.len(), 8);
        }
        let so = SurfaceOptions { max_nodes: Some(nodes), ..Default::default() };
        if let Ok(s) = surface(&g, &so) {
            prop_assert!(s.euler_characteristic() == 1);
            prop_assert!((0..s.triangles.len()).all(|t| s.triangle_area_xy(t) > 0.0));
        }
    }
}
