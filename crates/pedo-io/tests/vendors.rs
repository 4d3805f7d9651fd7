//! Vendor exports (Zebris `.apd`, footscan, Tekscan CSV, NumPy `.npz`), content sniffing and the
//! refusals of files that are not recordings. Samples and their sources: tests/data/README.md.

use pedo_io::formats::{asf, npz, pedcad};
use pedo_io::{parse_bytes, read_recording, sniff_format, Format, IoError, Recording};
use std::path::{Path, PathBuf};

#[path = "common/files.rs"]
mod files;
use files::data;
#[path = "common/zip.rs"]
mod zip_file;
use zip_file::zip;

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

/// A scratch folder removed when dropped.
struct Scratch(PathBuf);
impl Scratch {
    fn new(tag: &str) -> Self {
        let p = std::env::temp_dir().join(format!("pedo-io-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&p).unwrap();
        Scratch(p)
    }
    fn write(&self, name: &str, b: &[u8]) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, b).unwrap();
        p
    }
}
impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The `[Data]` grid of a pedcad file as numbers, read independently of the library.
fn pedcad_grid(text: &str, section: &str) -> Vec<Vec<f64>> {
    let start = text.find(&format!("[{section}]\n")).unwrap() + section.len() + 3;
    text[start..]
        .lines()
        .take_while(|l| !l.trim().is_empty() && !l.starts_with('['))
        .map(|l| l.split('\t').map(|v| v.parse().unwrap()).collect())
        .collect()
}

#[test]
fn zebris_apd_real_sample() {
    // Real Zebris FDM export, BMClab/BMC data/MDwalk2.apd (MIT).
    let rec = read_recording(data("MDwalk2.apd")).unwrap();
    assert_eq!(rec.format, Some(Format::Zebris));
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (1, 32, 15));
    assert_eq!(rec.pitch_mm, Some([8.46591, 8.46591]));
    assert_eq!(rec.units, "N/cm²");
    assert_eq!(rec.dt_s, None);
    // N/cm² = 10 kPa; kPa × mm² × 1e-3 = N.
    let f = rec.force_factor().unwrap();
    assert!((f - 10.0 * 8.46591 * 8.46591 * 1e-3).abs() < 1e-12);
    let text = String::from_utf8(bytes("MDwalk2.apd")).unwrap();
    let grid = pedcad_grid(&text, "Data");
    assert_eq!((grid.len(), grid[0].len()), (32, 15));
    let flat: Vec<f64> = grid.concat();
    let sensors = flat.iter().filter(|&&v| v != -1.0).count();
    assert_eq!(rec.n_sensors(), sensors);
    for (i, &v) in flat.iter().enumerate() {
        assert_eq!(rec.sensor_mask()[i], v != -1.0);
        assert_eq!(rec.data()[i] as f64, if v == -1.0 { 0.0 } else { v });
    }
    assert_eq!(rec.peak_image().max(), 36.5);
    assert_eq!((rec.data()[2], rec.data()[3]), (1.0, 3.0));
}

#[test]
fn a_known_format_under_another_extension_reads_the_same() {
    let s = Scratch::new("ext");
    for (sample, format) in [
        ("MDwalk2.apd", Format::Zebris),
        ("FrasP01L.asf", Format::Asf),
        ("synthetic-walk.lst", Format::Lst),
        ("tekscan-FrasP01L-11-20.csv", Format::TekscanCsv),
        ("footscan-FrasP01L-11-20.txt", Format::Footscan),
        ("pedar-example-3.01-4.00.asc", Format::Pedar),
        ("iscan-test-1-20.csv", Format::Asf),
        ("emed-test-1-10.lst", Format::Lst),
        ("numpy-MUN104L-deflated.npz", Format::Npz),
        ("MUN104L.csv", Format::Csv),
        ("zebris-FrasP01L-26-55.xml", Format::ZebrisXml),
        ("zebris-FrasP01L-26-55.json.gz", Format::ZebrisJson),
    ] {
        let want = read_recording(data(sample)).unwrap();
        assert_eq!(want.format, Some(format), "{sample}");
        for ext in ["csv", "txt", "dat", "asf", "npy"] {
            let p = s.write(&format!("renamed.{ext}"), &bytes(sample));
            let got = read_recording(&p).unwrap_or_else(|e| panic!("{sample} as .{ext}: {e}"));
            assert_eq!(got, want, "{sample} as .{ext}");
        }
    }
}

#[test]
fn tekscan_csv_export_matches_the_asf_frames() {
    let asf = read_recording(data("FrasP01L.asf")).unwrap();
    let rec = read_recording(data("tekscan-FrasP01L-11-20.csv")).unwrap();
    assert_eq!(rec.format, Some(Format::TekscanCsv));
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (10, 60, 21));
    assert_eq!((rec.pitch_mm, rec.dt_s), (asf.pitch_mm, asf.dt_s));
    assert_eq!(
        (rec.units.as_str(), rec.noise_threshold),
        ("kPa", Some(3.0))
    );
    assert_eq!(rec.sensor_mask(), asf.sensor_mask());
    for t in 0..10 {
        assert_eq!(rec.frame_slice(t), asf.frame_slice(10 + t), "frame {t}");
    }
    assert!(
        rec.peak_image().max() > 0.0,
        "the excerpt holds a loaded frame"
    );
    // Cut inside frame 6: the error names both counts.
    let b = bytes("tekscan-FrasP01L-11-20.csv");
    let text = String::from_utf8(b.clone()).unwrap();
    let cut = text.find("Frame 16").unwrap() + 300;
    let e = parse_bytes(&b[..cut], Format::TekscanCsv, "cut.csv").unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("cut.csv") && m.contains("after 5 complete frames") && m.contains("states 10"),
        "{m}"
    );
}

#[test]
fn footscan_export_frames_peak_and_mask() {
    let asf = read_recording(data("FrasP01L.asf")).unwrap();
    let rec = read_recording(data("footscan-FrasP01L-11-20.txt")).unwrap();
    assert_eq!(rec.format, Some(Format::Footscan));
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (10, 60, 21));
    assert_eq!(rec.pitch_mm, Some([5.08, 5.08]));
    assert_eq!(rec.dt_s, Some(0.032));
    assert_eq!(rec.units, "N/cm²");
    // -1 marks exactly the sensels the Tekscan file marks B.
    assert_eq!(rec.sensor_mask(), asf.sensor_mask());
    for t in 0..10 {
        let (a, b) = (
            rec.frame_slice(t).unwrap(),
            asf.frame_slice(10 + t).unwrap(),
        );
        for (x, y) in a.iter().zip(b.iter()) {
            assert!((x - y / 10.0).abs() < 1e-4, "frame {t}: {x} vs {y} kPa");
        }
    }
    // The file's [Data] peak image is the maximum over its frames.
    let text = String::from_utf8(bytes("footscan-FrasP01L-11-20.txt")).unwrap();
    let peak: Vec<f64> = pedcad_grid(&text, "Data").concat();
    for (p, q) in peak.iter().zip(rec.peak_image().data()) {
        assert!((p.max(0.0) - q).abs() < 1e-4);
    }
    // Drop the last frame: the error names the frames found and the frames promised.
    let cut = text.find("[Data10]").unwrap();
    let e = pedcad::parse_pedcad(&text.as_bytes()[..cut], "cut.txt").unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("after 9 frames") && m.contains("states 10"),
        "{m}"
    );
    // Cut inside a grid: the section is named as truncated.
    let e = pedcad::parse_pedcad(&text.as_bytes()[..cut - 200], "cut.txt").unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
}

#[test]
fn npz_stored_and_deflated() {
    let asf = read_recording(data("FrasP01L.asf")).unwrap();
    let npy = pedo_io::formats::npy::recording_to_npy(&asf);
    // A 1-D member first: not a recording, skipped for the frames after it.
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), }";
    let mut label = b"\x93NUMPY\x01\x00".to_vec();
    label.extend_from_slice(&(dict.len() as u16 + 1).to_le_bytes());
    label.extend_from_slice(dict.as_bytes());
    label.push(b'\n');
    label.extend_from_slice(&[0; 8]);
    for deflate in [false, true] {
        for zip64 in [false, true] {
            let z = zip(
                &[("labels.npy", label.clone()), ("frames.npy", npy.clone())],
                deflate,
                zip64,
            );
            let rec = parse_bytes(&z, Format::Npz, "x.npz").unwrap();
            assert_eq!(rec.format, Some(Format::Npz));
            assert_eq!(
                (rec.data(), rec.sensor_mask()),
                (asf.data(), asf.sensor_mask())
            );
            let s = Scratch::new(&format!("npz{deflate}{zip64}"));
            assert_eq!(read_recording(s.write("walk.dat", &z)).unwrap(), rec);
            // Truncated archives and flipped bytes are errors naming the file, never panics.
            for cut in [z.len() - 1, z.len() / 2, 30] {
                let e = npz::parse_npz(&z[..cut], "cut.npz").unwrap_err();
                assert!(e.to_string().contains("cut.npz"), "{e}");
            }
        }
    }
    let z = zip(&[("a.txt", b"hello".to_vec())], false, false);
    let e = npz::parse_npz(&z, "a.npz").unwrap_err().to_string();
    assert!(e.contains("without .npy members"), "{e}");
    // A corrupted member fails its CRC.
    let mut z = zip(&[("f.npy", npy.clone())], false, false);
    let i = z.len() / 2;
    z[i] ^= 0x55;
    assert!(npz::parse_npz(&z, "crc.npz").is_err());
}

#[test]
fn files_that_are_not_recordings_are_named_and_refused() {
    let s = Scratch::new("unknown");
    let cases: [(&str, &[u8], &str); 6] = [
        (
            "notes.csv",
            b"Dear user,\nthis is a letter, not a grid.\n",
            "neither a known export",
        ),
        ("data.json", b"{\"frames\": [1, 2, 3]}\n", "JSON"),
        (
            "blob.asf.bin",
            b"\x00\x01\x02\xff\xfe\x00\x00",
            "binary data",
        ),
        ("empty.csv", b"", "empty"),
        (
            "walk.asc",
            b"pedar ASCII export\nscanning rate: 50 Hz\ntime\t1\t2\t3\n",
            "pedar",
        ),
        ("page.html", b"<html><body>hi</body></html>\n", "XML/HTML"),
    ];
    for (file, content, what) in cases {
        let e = read_recording(s.write(file, content)).unwrap_err();
        let m = e.to_string();
        assert!(matches!(e, IoError::UnknownFormat { .. }), "{file}: {m}");
        assert!(m.contains(file) && m.contains(what), "{file}: {m}");
        assert!(
            m.contains("Zebris .apd") && m.contains("NumPy"),
            "lists formats: {m}"
        );
        assert!(!m.contains('\n'), "one line: {m}");
    }
}

#[test]
fn sniffing_decides_by_content_and_extension_breaks_ties() {
    let head = |n: &str| bytes(n);
    assert_eq!(
        sniff_format(Path::new("a.csv"), &head("MDwalk2.apd")),
        Ok(Format::Zebris)
    );
    assert_eq!(
        sniff_format(Path::new("a.apd"), &head("MUN104L.csv")),
        Ok(Format::Csv)
    );
    assert_eq!(
        sniff_format(Path::new("a.lst"), &head("FrasP01L.asf")),
        Ok(Format::Asf)
    );
    // A header cut before its markers: the extension picks the parser, which names the line.
    let cut = &head("FrasP01L.asf")[..120];
    assert_eq!(sniff_format(Path::new("a.asf"), cut), Ok(Format::Asf));
    assert!(sniff_format(Path::new("a.txt"), cut).is_err());
    let e = parse_bytes(cut, Format::Asf, "cut.asf")
        .unwrap_err()
        .to_string();
    assert!(e.contains("cut.asf") && e.contains("ASCII_DATA"), "{e}");
}

#[test]
fn headers_claiming_huge_sizes_allocate_nothing() {
    // Each would need gigabytes if believed; each must fail at once.
    let asf = b"ROWS 100000\nCOLS 100000\nSTART_FRAME 1\nEND_FRAME 1000000000\nASCII_DATA @@\nFrame 1\n0\n";
    assert!(asf::parse_asf(asf, "huge.asf")
        .unwrap_err()
        .to_string()
        .contains("more than the file"));
    let csv = b"ROWS 50000,,\nCOLS 50000,,\nEND_FRAME 1000000000,,\nFrame 1,,\n0,0\n";
    assert!(asf::parse_tekscan_csv(csv, "huge.csv").is_err());
    let apd = b"[Technical]\nSensCountX=100000\nSensCountY=100000\nMinIdx=1\nMaxIdx=1000000000\n[Data1]\n1\t2\n";
    assert!(pedcad::parse_pedcad(apd, "huge.apd").is_err());
    let lst = b"Page 1\nMatrix: 10000x10000\n1\t2\tForce\n1\t0\t0\t0\nForce\t0\t0\n";
    assert!(parse_bytes(lst, Format::Lst, "huge.lst").is_err());
    let npy = b"\x93NUMPY\x01\x00\x46\x00{'descr': '<f4', 'fortran_order': False, 'shape': (1000000000, 1000, 1000), }\n";
    assert!(parse_bytes(npy, Format::Npy, "huge.npy").is_err());
    // A deflated member claiming 4 GiB from a few bytes.
    let mut z = zip(&[("f.npy", vec![0u8; 64])], true, true);
    let at = z.windows(4).position(|w| w == b"PK\x01\x02").unwrap();
    let extra = at + 46 + 5 + 4;
    z[extra..extra + 8].copy_from_slice(&(4u64 << 30).to_le_bytes());
    assert!(npz::parse_npz(&z, "bomb.npz").is_err());
}

#[test]
fn recording_from_array_with_pitch_rate_units_and_mask() {
    let rec = Recording::from_array(
        2,
        2,
        2,
        vec![1.0, f32::NAN, 3.0, 4.0, 5.0, f32::NAN, 7.0, 8.0],
        None,
    )
    .unwrap()
    .with_pitch_mm([5.0, 7.62])
    .unwrap()
    .with_frame_rate(100.0)
    .unwrap()
    .with_units("kPa");
    assert_eq!(rec.sensor_mask(), &[true, false, true, true]);
    assert_eq!(rec.pitch_mm, Some([5.0, 7.62]));
    assert_eq!(rec.frame_rate(), Some(100.0));
    assert_eq!(rec.dt_s, Some(0.01));
    assert_eq!(rec.force_factor(), Some(5.0 * 7.62 * 1e-3));
    let masked =
        Recording::from_array(1, 1, 3, vec![1.0, 99.0, 2.0], Some(vec![true, false, true]))
            .unwrap();
    assert_eq!(&*masked.data(), &[1.0, 0.0, 2.0]);
    assert!(masked.clone().with_pitch_mm([0.0, 1.0]).is_err());
    assert!(masked.clone().with_frame_rate(f64::NAN).is_err());
    assert!(Recording::from_array(2, 1, 3, vec![1.0; 3], None).is_err());
}

#[test]
fn npz_written_by_numpy() {
    // np.savez and np.savez_compressed of MUN104L and its half, NaN where the template is 0.
    let grid = read_recording(data("MUN104L.csv")).unwrap();
    for file in ["numpy-MUN104L-stored.npz", "numpy-MUN104L-deflated.npz"] {
        let rec = read_recording(data(file)).unwrap();
        assert_eq!(rec.format, Some(Format::Npz), "{file}");
        assert_eq!(
            (rec.n_frames(), rec.rows(), rec.cols()),
            (2, 63, 27),
            "{file}"
        );
        let g = grid.frame_slice(0).unwrap();
        for (i, &v) in g.iter().enumerate() {
            assert_eq!(rec.sensor_mask()[i], v != 0.0, "{file}");
            assert_eq!(rec.data()[i], v);
            assert_eq!(rec.data()[g.len() + i], v / 2.0);
        }
    }
}

/// The 198 sensor columns of a pedar export, read independently: per frame `(time, values)`.
fn pedar_rows(text: &str) -> Vec<(f64, Vec<f64>)> {
    text.lines()
        .skip_while(|l| !l.starts_with("time["))
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            (v[0], v[1..].to_vec())
        })
        .collect()
}

#[test]
fn pedar_export_on_the_bundled_layout() {
    use pedo_io::formats::pedar::{self, Insole, PedarLayout};
    // Real pedar-X export (pressuRe inst/extdata/pedar_example.asc, MIT), frames 301-400.
    let text = String::from_utf8(bytes("pedar-example-3.01-4.00.asc")).unwrap();
    let rows = pedar_rows(&text);
    assert_eq!((rows.len(), rows[0].1.len()), (100, 198));
    let rec = read_recording(data("pedar-example-3.01-4.00.asc")).unwrap();
    assert_eq!(rec.format, Some(Format::Pedar));
    assert_eq!(rec.n_frames(), 100);
    assert_eq!(
        (rec.dt_s, rec.units.as_str(), rec.pitch_mm),
        (Some(0.01), "kPa", None)
    );
    // Every sensor's value sits in its cells: with the layout's cell map, each frame's image
    // reproduces the 198 columns exactly, and no cell outside a sensor is a sensor.
    let layout = PedarLayout::bundled();
    assert_eq!(layout.sensors.len(), 198);
    let d = pedar::parse_pedar_data(text.as_bytes(), "p").unwrap();
    assert_eq!(d.columns[0], (Insole::Left, 1));
    assert_eq!(d.columns[99], (Insole::Right, 1));
    for (t, (_, vals)) in rows.iter().enumerate() {
        let img = rec.frame_slice(t).unwrap();
        let file_max = vals.iter().copied().fold(0.0, f64::max);
        let img_max = img.iter().fold(0.0f32, |a, &b| a.max(b)) as f64;
        assert_eq!(img_max, file_max, "frame {t}");
        // The image holds only the file's values (and 0).
        for &v in img.iter() {
            assert!(
                v == 0.0 || rows[t].1.contains(&(v as f64)),
                "frame {t}: {v}"
            );
        }
    }
    // Each sensor covers some cells: at least 198 sensor cells, all sensors distinguishable.
    assert!(rec.n_sensors() >= 198, "{}", rec.n_sensors());
    // Left and right insoles are separate objects: frame 50 loads both (left 4262, right 792 kPa
    // summed in the file), and the contours at level 0 fall on both sides of the gap.
    let t = (0..100)
        .find(|&t| {
            rows[t].1[..99].iter().sum::<f64>() > 500.0
                && rows[t].1[99..].iter().sum::<f64>() > 500.0
        })
        .unwrap();
    let g = rec.frame(t).unwrap();
    let cs = pedo_io::contours(
        &g,
        &pedo_io::ContourOptions {
            level: Some(0.0),
            ..Default::default()
        },
    )
    .unwrap();
    let (left, right) = pedar::parse_pedar_insoles(text.as_bytes(), "p", layout).unwrap();
    let split = left.cols() as f64 + 0.5; // the two empty columns after the left insole
    let xs: Vec<f64> = cs
        .iter()
        .map(|c| c.points.iter().map(|p| p[0]).sum::<f64>() / c.points.len() as f64)
        .collect();
    assert!(
        xs.iter().any(|&x| x < split) && xs.iter().any(|&x| x > split),
        "{xs:?}"
    );
    // Each insole alone: 99 sensors' values, the same frames.
    for (r, off) in [(&left, 0), (&right, 99)] {
        assert_eq!(r.n_frames(), 100);
        let m = r.peak_image().max();
        let want = rows
            .iter()
            .flat_map(|(_, v)| v[off..off + 99].iter().copied())
            .fold(0.0, f64::max);
        assert_eq!(m, want);
    }
    assert_eq!(left.rows(), rec.rows());
    assert_eq!(left.cols() + 2 + right.cols(), rec.cols());
}

#[test]
fn pedar_truncation_layout_files_and_options() {
    use pedo_io::formats::pedar::{self, PedarLayout};
    use pedo_io::{read_recording_with, ReadOptions};
    let b = bytes("pedar-example-3.01-4.00.asc");
    let text = String::from_utf8(b.clone()).unwrap();
    // Cut inside frame 61: the error names the frames found and the frames the header states.
    let cut = text.find("     3.62000").unwrap() + 50;
    let e = parse_bytes(&b[..cut], Format::Pedar, "cut.asc")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cut.asc") && e.contains("after 61 frames") && e.contains("states 100"),
        "{e}"
    );
    // A layout file in millimetres gives the recording a pitch of half a sensor.
    let s = Scratch::new("layout");
    let mut mm = String::from("# unit: mm\ninsole,sensor,x1,y1,x2,y2,x3,y3,x4,y4\n");
    for side in ["L", "R"] {
        for k in 0..99 {
            let (x, y) = ((k % 9) as f64 * 10.0, (k / 9) as f64 * 20.0);
            mm += &format!(
                "{side},{},{x},{y},{},{y},{},{},{x},{}\n",
                k + 1,
                x + 10.0,
                x + 10.0,
                y + 20.0,
                y + 20.0
            );
        }
    }
    let p = s.write("grid-layout.csv", mm.as_bytes());
    let rec = read_recording_with(
        data("pedar-example-3.01-4.00.asc"),
        &ReadOptions {
            layout: Some(p.clone()),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(rec.pitch_mm, Some([5.0, 10.0]));
    // 9 x 11 sensors of 2 x 2 cells each, per insole, two empty columns between.
    assert_eq!((rec.rows(), rec.cols()), (22, 18 + 2 + 18));
    assert_eq!(rec.n_sensors(), 2 * 99 * 4);
    // Left sensor 1 is the bottom-left 2 x 2 block (heel at the bottom row).
    let rows = pedar_rows(&text);
    assert_eq!(rec.frame_slice(0).unwrap()[21 * 38], rows[0].1[0] as f32);
    // Bad layouts are errors naming the file and line.
    let bad = s.write("bad.csv", b"L,1,0,0,1,0,1,1\n");
    let e = read_recording_with(
        data("pedar-example-3.01-4.00.asc"),
        &ReadOptions {
            layout: Some(bad),
            ..ReadOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("bad.csv:1") && e.contains("expected 10"), "{e}");
    let partial = s.write("partial.csv", b"L,1,0,0,1,0,1,1,0,1\n");
    let e =
        pedar::parse_pedar(&b, "p.asc", &PedarLayout::from_file(&partial).unwrap()).unwrap_err();
    assert!(e.to_string().contains("not in the layout"), "{e}");
}

#[test]
fn iscan_csv_export_with_timed_frame_lines() {
    // Real Tekscan I-Scan export saved as .csv (pressuRe inst/extdata/iscan_test.csv, MIT),
    // frames 1-20: `Frame 1, 0,, 12/2/2019 6:21:52.34PM,,,Raw Sum=,,310` lines.
    let rec = read_recording(data("iscan-test-1-20.csv")).unwrap();
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (20, 28, 28));
    assert_eq!(rec.pitch_mm, Some([1.27, 1.27]));
    assert_eq!((rec.dt_s, rec.units.as_str()), (Some(0.1), "raw"));
    let text = String::from_utf8(bytes("iscan-test-1-20.csv")).unwrap();
    // The Raw Sum printed on each frame line is the frame's sum.
    for (t, line) in text.lines().filter(|l| l.starts_with("Frame ")).enumerate() {
        let printed: f64 = line.rsplit(',').next().unwrap().trim().parse().unwrap();
        let sum: f64 = rec.frame_slice(t).unwrap().iter().map(|&v| v as f64).sum();
        assert_eq!(sum, printed, "frame {t}");
    }
}

#[test]
fn real_emed_export_with_total_force() {
    // Real novel emed export (pressuRe inst/extdata/emed_test.lst, MIT), pages 1-10; its Force
    // lines end with the page's total force.
    let b = bytes("emed-test-1-10.lst");
    let (rec, forces) = pedo_io::formats::lst::parse_lst(&b, "emed").unwrap();
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (10, 95, 64));
    assert_eq!(
        (rec.pitch_mm, rec.dt_s, rec.sensel_area()),
        (Some([5.0, 5.0]), Some(0.01), Some(25.0))
    );
    let ms = rec.measures(0.0);
    for (t, (m, f)) in ms.iter().zip(&forces).enumerate() {
        // Force [N] = sum(kPa) x 0.25 cm² / 10; printed forces are rounded to 0.01 N.
        let printed: f64 = f.column_forces.iter().sum();
        let tol = 0.005 * f.column_forces.len() as f64 + 1e-9;
        assert!(
            (m.total_force - printed).abs() <= tol,
            "page {t}: {} vs {printed}",
            m.total_force
        );
    }
    assert!(ms.iter().any(|m| m.total_force > 10.0));
}

/// The Zebris raw-data samples hold frames 26..55 of the F-Scan walk, in N/cm², placed on a
/// 30 x 80 plate with the image's top-left sensel at column 5, row 10 (see reconstruct.py).
fn check_zebris_raw(rec: &Recording, format: Format) {
    let asf = read_recording(data("FrasP01L.asf")).unwrap();
    assert_eq!(rec.format, Some(format));
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (30, 80, 30));
    assert_eq!(rec.pitch_mm, Some([5.08, 5.08]));
    assert_eq!(rec.dt_s, Some(1.0 / 31.25));
    assert_eq!(rec.units, "N/cm²");
    assert_eq!(rec.n_sensors(), 80 * 30, "every sensor of a plate exists");
    let (oy, ox) = (10, 5);
    for t in 0..30 {
        // asf frame numbers start at 1: frame 26 is index 25.
        let want = asf.frame_slice(25 + t).unwrap();
        let got = rec.frame_slice(t).unwrap();
        for r in 0..80 {
            for c in 0..30 {
                let inside = (oy..oy + 60).contains(&r) && (ox..ox + 21).contains(&c);
                let expect = if inside {
                    let v = want[(r - oy) * 21 + (c - ox)] as f64 / 10.0;
                    (v * 10.0).round() / 10.0
                } else {
                    0.0
                };
                let g = got[r * 30 + c] as f64;
                assert!(
                    (g - expect).abs() < 1e-4,
                    "frame {t} row {r} col {c}: {g} vs {expect}"
                );
            }
        }
    }
    let loads: Vec<f64> = (0..30)
        .map(|t| rec.frame_slice(t).unwrap().iter().map(|&v| v as f64).sum())
        .collect();
    assert!(
        loads[..4].iter().all(|&l| l == 0.0),
        "swing before heel strike"
    );
    assert!(loads[4] > 0.0 && loads[20] > loads[4]);
}

#[test]
fn zebris_raw_xml_export_places_each_window_on_the_plate() {
    let rec = read_recording(data("zebris-FrasP01L-26-55.xml")).unwrap();
    check_zebris_raw(&rec, Format::ZebrisXml);
    // The same file gzip-compressed reads the same (sniffed through the compression).
    let s = Scratch::new("zebris-gz");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut gz, &bytes("zebris-FrasP01L-26-55.xml")).unwrap();
    let p = s.write("zebris_raw.xml.gz", &gz.finish().unwrap());
    assert_eq!(read_recording(&p).unwrap(), rec);
}

#[test]
fn zebris_raw_json_form_reads_like_the_xml() {
    let rec = read_recording(data("zebris-FrasP01L-26-55.json.gz")).unwrap();
    check_zebris_raw(&rec, Format::ZebrisJson);
    let xml = read_recording(data("zebris-FrasP01L-26-55.xml")).unwrap();
    assert_eq!(rec.data(), xml.data());
}

fn zebris_xml(count: usize, quants: &str) -> Vec<u8> {
    format!(
        "<measurement><cell_count><x>4</x><y>3</y></cell_count><movements><movement><clips>\
         <clip><units>km/h</units><data><quant>1.0</quant></data></clip>\
         <clip><cell_size><x>8.5</x><y>8.5</y></cell_size><frequency>100</frequency>\
         <units>N/cm&#178;</units><count>{count}</count><data>{quants}</data></clip>\
         </clips></movement></movements></measurement>"
    )
    .into_bytes()
}

const WINDOW: &str = "<quant><cell_begin><x>1</x><y>0</y></cell_begin>\
    <cell_count><x>2</x><y>2</y></cell_count><cells>1 2 3 4</cells></quant>";

#[test]
fn zebris_raw_xml_variants_and_refusals() {
    // The velocity clip may come first; empty frames may be written either way; y points up.
    let empty = "<quant><cells></cells></quant><quant/>";
    let rec = parse_bytes(
        &zebris_xml(3, &format!("{WINDOW}{empty}")),
        Format::ZebrisXml,
        "v.xml",
    )
    .unwrap();
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (3, 3, 4));
    assert_eq!(rec.units, "N/cm²");
    assert_eq!(rec.dt_s, Some(0.01));
    #[rustfmt::skip]
    assert_eq!(&*rec.frame_slice(0).unwrap(), &[0., 0., 0., 0.,
                                    0., 3., 4., 0.,
                                    0., 1., 2., 0.]);
    assert!(rec
        .frame_slice(1)
        .unwrap()
        .iter()
        .chain(rec.frame_slice(2).unwrap().iter())
        .all(|&v| v == 0.0));

    let refuse = |quants: &str, count: usize, needle: &str| {
        let e = parse_bytes(&zebris_xml(count, quants), Format::ZebrisXml, "bad.xml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.xml") && e.contains(needle),
            "{e:?} lacks {needle:?}"
        );
    };
    refuse(WINDOW, 2, "holds 1 frames, its <count> states 2");
    refuse(
        &WINDOW.replace("<x>1</x><y>0</y>", "<x>3</x><y>0</y>"),
        1,
        "leaves the 4 x 3 plate",
    );
    refuse(
        &WINDOW.replace("1 2 3 4", "1 2 3"),
        1,
        "3 values for a window of 2 x 2",
    );
    refuse(
        &WINDOW.replace("1 2 3 4", "1 x 3 4"),
        1,
        "value 1 is not a number",
    );
    refuse(&WINDOW.replace("1 2 3 4", "1 -2 3 4"), 1, "negative");
    refuse(
        &WINDOW.replace("<cell_begin><x>1</x><y>0</y></cell_begin>", ""),
        1,
        "without its window",
    );
    let cut = zebris_xml(1, WINDOW);
    let e = parse_bytes(&cut[..cut.len() - 40], Format::ZebrisXml, "cut.xml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("truncated XML"), "{e}");
    let at = String::from_utf8_lossy(&cut).find("</data>").unwrap();
    let e = parse_bytes(&cut[..at], Format::ZebrisXml, "cut.xml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("truncated: the file ends inside <measurement>"),
        "{e}"
    );
    let huge = b"<measurement><cell_count><x>100000</x><y>100000</y></cell_count><clip>\
        <cell_size><x>1</x><y>1</y></cell_size><data><quant/></data></clip></measurement>";
    let e = parse_bytes(huge, Format::ZebrisXml, "huge.xml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("100000 x 100000"), "{e}");
    // XML that is not a Zebris export is named for what it is, not parsed.
    assert!(
        sniff_format(Path::new("a.xml"), b"<html><body>hi</body></html>")
            .unwrap_err()
            .contains("XML")
    );
}

#[test]
fn a_pitch_set_on_a_file_replaces_its_stated_sensel_area() {
    // FrasP01L.asf states 5.08 mm sensels and their area, 25.8064 mm².
    let rec = read_recording(data("FrasP01L.asf")).unwrap();
    assert_eq!(rec.sensel_area(), Some(25.8064));
    let area = |r: &Recording| r.measures(0.0)[40].contact_area;
    let sensels = rec.measures(0.0)[40].contact_sensors as f64;
    assert!((area(&rec) - 25.8064 * sensels).abs() < 1e-9);
    // Set through the builder or as a user override, the new pitch gives the area.
    let wider = rec.clone().with_pitch_mm([10.0, 10.0]).unwrap();
    assert_eq!(wider.sensel_area(), Some(100.0));
    assert!((area(&wider) - 100.0 * sensels).abs() < 1e-9);
    let mut overridden = rec.clone();
    let units = pedo_io::units::UnitOverrides {
        pitch_mm: Some(pedo_io::units::Pitch([10.0, 10.0])),
        ..Default::default()
    };
    units.apply(&mut overridden).unwrap();
    assert_eq!(overridden.sensel_area(), Some(100.0));
}

#[test]
fn a_pedar_layout_with_an_unknown_unit_is_an_error_naming_file_line_and_units() {
    use pedo_io::formats::pedar::PedarLayout;
    let sensor = "L,1,0,0,10,0,10,20,0,20\n";
    // An unknown unit used to leave the recording without a pitch, silently.
    let e = PedarLayout::parse(&format!("# unit: inches\n{sensor}"), "in.csv")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("in.csv:1") && e.contains("inches") && e.contains("mm") && e.contains("cm"),
        "{e}"
    );
    // A later unknown unit line used to cancel an earlier `mm`.
    let e = PedarLayout::parse(
        &format!("# unit: mm\n{sensor}# unit: furlongs\n"),
        "two.csv",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("two.csv:3") && e.contains("furlongs"), "{e}");
    // Two different known units contradict each other.
    let e = PedarLayout::parse(&format!("# unit: mm\n# unit: cm\n{sensor}"), "both.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("both.csv:2") && e.contains("mm"), "{e}");
    // The accepted units still work, in any case, repeated alike.
    for (unit, mm) in [("mm", Some(1.0)), ("CM", Some(10.0)), ("normalised", None)] {
        let l =
            PedarLayout::parse(&format!("# unit: {unit}\n# unit: {unit}\n{sensor}"), "ok").unwrap();
        assert_eq!(l.mm_per_unit, mm, "{unit}");
    }
    assert_eq!(PedarLayout::bundled().mm_per_unit, None);
}

/// What a foot's measures must be, from the export's own columns (`cols` of each row) and the
/// number of image cells each of those sensors covers (`cells`): peak pressure, PTI maximum,
/// FTI and contact time by their definitions (docs/measures.md), in kPa, kPa·s, kPa·cell·s, s.
fn foot_oracle(rows: &[(f64, Vec<f64>)], cols: std::ops::Range<usize>, cells: &[f64]) -> [f64; 4] {
    let dt = 0.01;
    let peak = rows
        .iter()
        .flat_map(|r| &r.1[cols.clone()])
        .fold(0.0, |a, &b| f64::max(a, b));
    let pti = cols
        .clone()
        .map(|k| rows.iter().map(|r| r.1[k] * dt).sum::<f64>());
    let force: Vec<f64> = rows
        .iter()
        .map(|r| cols.clone().map(|k| r.1[k] * cells[k]).sum())
        .collect();
    let (lo, hi) = force
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &f| (l.min(f), h.max(f)));
    let above: Vec<usize> = (0..force.len())
        .filter(|&t| force[t] > lo + 0.1 * (hi - lo))
        .collect();
    let contact = (above[above.len() - 1] - above[0] + 1) as f64 * dt;
    [
        peak,
        pti.fold(0.0, f64::max),
        force.iter().sum::<f64>() * dt,
        contact,
    ]
}

#[test]
fn pedar_insoles_are_measured_per_foot_as_their_own_columns_say() {
    use pedo_io::measures::Measures;
    use pedo_io::regions::Side;
    let text = String::from_utf8(bytes("pedar-example-3.01-4.00.asc")).unwrap();
    let rows = pedar_rows(&text);
    let rec = read_recording(data("pedar-example-3.01-4.00.asc")).unwrap();
    let (cols, n) = (rec.cols(), rec.n_frames());
    let sides: Vec<_> = rec.feet.iter().map(|f| f.side).collect();
    assert_eq!(sides, [Side::Left, Side::Right]);
    let (left, right) = (rec.feet[0].columns.clone(), rec.feet[1].columns.clone());
    assert!(
        left.end + 2 == right.start && right.end == cols,
        "{left:?} {right:?}"
    );
    // Each image cell of a sensor is one of the export's columns over every frame: which one
    // (found by its values), and so how many cells each sensor covers. A cell's sensor is of
    // the insole whose columns it lies in.
    let frames: Vec<Vec<f32>> = (0..n)
        .map(|t| rec.frame_slice(t).unwrap().to_vec())
        .collect();
    let mut cells = vec![0.0; 198];
    for i in 0..rec.rows() * cols {
        let series: Vec<f64> = frames.iter().map(|f| f64::from(f[i])).collect();
        if series.iter().all(|&v| v == 0.0) {
            continue;
        }
        let k = (0..198)
            .find(|&k| rows.iter().zip(&series).all(|(r, &v)| r.1[k] == v))
            .unwrap_or_else(|| panic!("cell {i} holds no sensor's values"));
        let (foot, offset) = if k < 99 { (&left, 0) } else { (&right, 99) };
        assert!(
            foot.contains(&(i % cols)),
            "cell {i} of sensor {} of the other insole",
            k - offset + 1
        );
        cells[k] += 1.0;
    }
    let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
    assert_eq!(m.feet.len(), 2);
    for (foot, sensors) in m.feet.iter().zip([0..99, 99..198]) {
        let want = foot_oracle(&rows, sensors, &cells);
        let v = &foot.measures.values;
        let got = [v.peak_pressure, v.pti_max, v.fti, v.contact_time];
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g - w).abs() <= 1e-9 * w.max(1.0),
                "{:?}: {got:?} vs {want:?}",
                foot.side
            );
        }
        // Its images are the whole recording's on its columns, NaN elsewhere.
        for i in 0..rec.rows() * cols {
            let mine = foot.columns.contains(&(i % cols));
            let (a, b) = (foot.measures.pti[i], m.pti[i]);
            assert!(
                if mine {
                    a.to_bits() == b.to_bits()
                } else {
                    a.is_nan()
                },
                "{i}"
            );
        }
    }
    // The feet share the whole recording's load: their FTIs sum to its FTI.
    let fti: f64 = m.feet.iter().map(|f| f.measures.values.fti).sum();
    assert!(
        (fti - m.values.fti).abs() <= 1e-9 * fti,
        "{fti} vs {}",
        m.values.fti
    );
    // A plate's recording has no feet.
    assert!(read_recording(data("emed-test-1-10.lst"))
        .unwrap()
        .feet
        .is_empty());
}

#[test]
fn each_pedar_insole_is_divided_into_regions_of_its_own() {
    use pedo_io::measures::Measures;
    use pedo_io::regions::{masks_of_measures, region_values, RegionRule, Side};
    let rec = read_recording(data("pedar-example-3.01-4.00.asc")).unwrap();
    let (cols, n) = (rec.cols(), rec.n_frames());
    let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
    for rule in [RegionRule::Coarse, RegionRule::Fine] {
        let masks = masks_of_measures(&rec, &m, None, rule).unwrap();
        let per_foot = rule.names().len();
        assert_eq!(masks.names.len(), 2 * per_foot);
        assert_eq!(masks.sides[..per_foot], [Side::Left; 8][..per_foot]);
        assert_eq!(masks.sides[per_foot..], [Side::Right; 8][..per_foot]);
        for foot in &rec.feet {
            // The foot's footprint (its sensels loaded in some frame), and no other sensel,
            // carries its regions' labels.
            for i in 0..rec.rows() * cols {
                let printed = m.pti[i] > 0.0 && foot.columns.contains(&(i % cols));
                let label = masks.labels[i];
                let mine = label > 0 && masks.side_of(label) == Some(foot.side);
                assert_eq!(printed, mine, "{rule:?} {:?} sensel {i}", foot.side);
            }
            // Row 0 is the toe end; the medial side faces the other insole.
            let centre = |name: &str| {
                let k = (0..masks.names.len())
                    .find(|&k| masks.names[k] == name && masks.sides[k] == foot.side)
                    .unwrap();
                let cells: Vec<usize> = (0..masks.labels.len())
                    .filter(|&i| usize::from(masks.labels[i]) == k + 1)
                    .collect();
                let c = cells.len() as f64;
                let x = cells.iter().map(|&i| (i % cols) as f64).sum::<f64>() / c;
                let y = cells.iter().map(|&i| (i / cols) as f64).sum::<f64>() / c;
                let medial = if foot.side == Side::Left { x } else { -x };
                (y, medial)
            };
            if rule == RegionRule::Coarse {
                let rows: Vec<f64> = ["hindfoot", "midfoot", "forefoot", "toes"]
                    .iter()
                    .map(|r| centre(r).0)
                    .collect();
                assert!(
                    rows.windows(2).all(|w| w[0] > w[1]),
                    "{:?} {rows:?}",
                    foot.side
                );
            } else {
                assert!(centre("heel_medial").1 > centre("heel_lateral").1);
                assert!(centre("mh1").1 > centre("mh2").1);
                assert!(centre("mh2").1 > centre("mh3_5").1);
                assert!(centre("hallux").1 > centre("lesser_toes").1);
                assert!(centre("hallux").0 < centre("mh1").0);
            }
        }
        // Each foot's regions share its own impulse, and their FTIs sum to the foot's.
        let values = region_values(&rec, 0.0, &masks, &m).unwrap();
        for foot in &m.feet {
            let mine: Vec<_> = values
                .iter()
                .filter(|v| v.foot == Some(foot.side))
                .collect();
            assert_eq!(mine.len(), per_foot);
            let share: f64 = mine.iter().map(|v| v.impulse_share).sum();
            assert!((share - 100.0).abs() < 1e-9, "{share}");
            let fti: f64 = mine.iter().map(|v| v.fti).sum();
            let want = foot.measures.values.fti;
            assert!((fti - want).abs() <= 1e-9 * want, "{fti} vs {want}");
            // Their curves are over the foot's own stances.
            assert!(mine
                .iter()
                .all(|v| v.curves.len() == foot.measures.stances.len()));
        }
    }
}
