//! Reading the real recordings in tests/data and round-tripping the writable formats.

use pedo_io::formats::{asf, csv, images, lst, npy};
use pedo_io::{parse_bytes, read_recording, Format, IoError, Recording};

#[path = "common/files.rs"]
mod files;
use files::data;

#[test]
fn fscan_asf_header_shape_and_values() {
    let rec = read_recording(data("FrasP01L.asf")).unwrap();
    assert_eq!(rec.format, Some(Format::Asf));
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (205, 60, 21));
    assert_eq!(rec.pitch_mm, Some([5.08, 5.08]));
    assert_eq!(rec.dt_s, Some(0.032));
    assert_eq!(rec.units, "kPa");
    assert_eq!(rec.noise_threshold, Some(3.0));
    assert!((rec.sensel_area().unwrap() - 25.8064).abs() < 1e-9);
    // 305 of the 1260 sensels are `B` in frame 1 (counted independently with a regex).
    assert_eq!(rec.n_sensors(), 1260 - 305);
    // The first frame's first row: B x9, 0 x7, B x5.
    let m = rec.sensor_mask();
    assert!(
        m[..9].iter().all(|&x| !x) && m[9..16].iter().all(|&x| x) && m[16..21].iter().all(|&x| !x)
    );
    let max = rec.data().iter().copied().fold(0.0f32, f32::max);
    let min = rec.data().iter().copied().fold(f32::MAX, f32::min);
    assert_eq!((min, max), (0.0, 760.0));
    let nan = rec.frames_with_nan();
    assert_eq!(nan.iter().filter(|v| v.is_nan()).count(), 205 * 305);
}

#[test]
fn fscan_measures_are_consistent() {
    let rec = read_recording(data("FrasP01L.asf")).unwrap();
    let ms = rec.measures(0.0);
    assert_eq!(ms.len(), 205);
    let peak = rec.peak_image();
    let peak_max = peak.max();
    let max_of_peaks = ms.iter().map(|m| m.peak_pressure).fold(0.0, f64::max);
    assert_eq!(peak_max, max_of_peaks);
    for (t, m) in ms.iter().enumerate() {
        let f = rec.frame_slice(t).unwrap();
        let sum: f64 = f.iter().map(|&v| v as f64).sum();
        let n = f.iter().filter(|&&v| v > 0.0).count();
        assert_eq!(m.contact_sensors, n);
        assert!((m.contact_area - n as f64 * 25.8064).abs() < 1e-6);
        // kPa * mm^2 * 1e-3 = N
        assert!((m.total_force - sum * 25.8064e-3).abs() < 1e-6 * (1.0 + sum));
        match m.cop {
            None => assert_eq!(sum, 0.0),
            Some([x, y]) => assert!((0.0..21.0).contains(&x) && (0.0..60.0).contains(&y)),
        }
    }
    // Walking: several stance phases, so both loaded and unloaded frames exist; a loaded in-shoe
    // frame carries a body-weight order of magnitude (hundreds of newtons at most ~2 kN).
    let fmax = ms.iter().map(|m| m.total_force).fold(0.0, f64::max);
    assert!(ms.iter().any(|m| m.cop.is_none()));
    assert!(fmax > 200.0 && fmax < 2000.0, "max force {fmax}");
}

#[test]
fn emed_lst_pages_and_forces() {
    let bytes = std::fs::read(data("synthetic-walk.lst")).unwrap();
    let (rec, forces) = lst::parse_lst(&bytes, "synthetic-walk.lst").unwrap();
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (40, 95, 64));
    assert_eq!(rec.pitch_mm, Some([5.0, 5.0]));
    assert_eq!(rec.sensel_area(), Some(25.0));
    assert_eq!(rec.dt_s, Some(0.01));
    assert_eq!(forces.len(), 40);
    let ms = rec.measures(0.0);
    for (t, (m, f)) in ms.iter().zip(&forces).enumerate() {
        let printed: f64 = f.column_forces.iter().sum();
        // Each printed force is rounded to 0.01 N.
        let tol = 0.005 * f.column_forces.len() as f64 + 1e-9;
        assert!(
            (m.total_force - printed).abs() <= tol,
            "picture {}: {} vs {printed}",
            t + 1,
            m.total_force
        );
    }
    // Pages whose index line ends with `Force` print row forces too; check them row by row.
    let with_rows = forces.iter().filter(|f| !f.row_forces.is_empty()).count();
    assert_eq!(with_rows, 20);
    // Page 1: row 21 is 10+10+15*6+10+10 = 130 kPa -> 3.25 N, and nothing outside the window.
    let f0 = rec.frame_slice(0).unwrap();
    let row21: f32 = f0[20 * 64..21 * 64].iter().sum();
    assert_eq!(row21, 130.0);
    assert_eq!(forces[0].row_forces[1], 3.25);
    let read = read_recording(data("synthetic-walk.lst")).unwrap();
    assert_eq!(read, rec);
}

/// German exports write decimal commas in the header too: `Time/picture:12,5 ms` is 12.5 ms (it
/// was read as 12 ms, a frame rate 4 % off), `Sensor area: 0,25` 0.25 cm²; a value that cannot be
/// read is named in the error.
#[test]
fn emed_lst_header_with_decimal_commas() {
    let text =
        String::from_utf8_lossy(&std::fs::read(data("synthetic-walk.lst")).unwrap()).into_owned();
    let german = text
        .replace("Time/picture:10.0 ms", "Time/picture:12,5 ms")
        .replace("Sensor area: 0.25", "Sensor area: 0,25")
        .replace("Sensor size: 0.500x0.500", "Sensor size: 0,500x0,500");
    assert_ne!(german, text);
    let (rec, _) = lst::parse_lst(german.as_bytes(), "german.lst").unwrap();
    assert_eq!(rec.dt_s, Some(0.0125));
    assert_eq!(rec.sensel_area(), Some(25.0));
    assert_eq!(rec.pitch_mm, Some([5.0, 5.0]));
    let bad = text.replacen("Sensor area: 0.25", "Sensor area: n/a", 1);
    let err = lst::parse_lst(bad.as_bytes(), "bad.lst")
        .unwrap_err()
        .to_string();
    assert!(err.contains("bad Sensor area \"n/a"), "{err}");
}

/// `UNITS N/cm²` reads the same from a Latin-1 export and from one re-saved as UTF-8.
#[test]
fn units_read_the_same_in_latin1_and_utf8() {
    let bytes = std::fs::read(data("FrasP01L.asf")).unwrap();
    let with_units = |units: &[u8]| {
        let text = bytes.split(|&b| b == b'\n').map(|line| {
            if line.starts_with(b"UNITS") {
                [b"UNITS ".as_slice(), units].concat()
            } else {
                line.to_vec()
            }
        });
        let file: Vec<u8> = text.collect::<Vec<_>>().join(&b'\n');
        asf::parse_asf(&file, "units.asf").unwrap()
    };
    let latin1 = with_units(b"N/cm\xb2");
    let utf8 = with_units("N/cm\u{b2}".as_bytes());
    assert_eq!(
        (latin1.units.as_str(), utf8.units.as_str()),
        ("N/cm²", "N/cm²")
    );
    assert_eq!(utf8.force_factor(), latin1.force_factor());
}

/// A frame lost from the middle of a file is named where the numbering jumps, with or without a
/// frame count in the header (without one, every later frame's time was silently early).
#[test]
fn a_gap_in_the_frame_numbers_is_named_where_it_is() {
    let text = String::from_utf8_lossy(&std::fs::read(data("FrasP01L.asf")).unwrap())
        .replace("\r\n", "\n");
    let (start, end) = (
        text.find("\nFrame 51\n").unwrap(),
        text.find("\nFrame 52\n").unwrap(),
    );
    let line_of = |pos: usize| text[..pos].matches('\n').count() + 2;
    let dropped = format!("{}{}", &text[..start], &text[end..]);
    let no_count: String = dropped
        .lines()
        .filter(|l| !l.starts_with("START_FRAME") && !l.starts_with("END_FRAME"))
        .map(|l| format!("{l}\n"))
        .collect();
    for file in [&dropped, &no_count] {
        let err = asf::parse_asf(file.as_bytes(), "gap.asf")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("Frame 52 follows Frame 50") && err.contains("frame 51 is missing"),
            "{err}"
        );
    }
    let err = asf::parse_asf(dropped.as_bytes(), "gap.asf")
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(&format!("gap.asf:{}:", line_of(start))),
        "{err}"
    );
    let renumbered = text.replace("\nFrame 51\n", "\nFrame 7\n");
    let err = asf::parse_asf(renumbered.as_bytes(), "renumbered.asf")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("Frame 7 follows Frame 50") && err.contains("expected Frame 51"),
        "{err}"
    );
}

/// A header line above a grid is passed over whatever it holds (a title, names with another
/// separator, a name that is also a missing-sensor mark): the separator is the data's; a tab
/// or space grid may have decimal commas from its first row on.
#[test]
fn a_grid_header_does_not_choose_the_separator() {
    let grid = std::fs::read_to_string(data("MUN104L.csv")).unwrap();
    let plain = csv::parse_csv(grid.as_bytes(), "plain.csv").unwrap();
    for header in ["pressure", "Patient: Mueller", "subject;foot", "a\tb\tc"] {
        let with = format!("{header}\n{grid}");
        let rec = csv::parse_csv(with.as_bytes(), "with-header.csv")
            .unwrap_or_else(|e| panic!("{header:?}: {e}"));
        assert_eq!(rec, plain, "{header:?}");
    }
    for sep in ["\t", " "] {
        let german = ["0|12,5|30,25", "7,5|40,5|0"].join("\n").replace('|', sep);
        let rec = csv::parse_csv(german.as_bytes(), "german.txt").unwrap();
        assert_eq!(
            &rec.frame_slice(0).unwrap()[..],
            [0.0, 12.5, 30.25, 7.5, 40.5, 0.0]
        );
    }
}

#[test]
fn mun104_csv() {
    let rec = read_recording(data("MUN104L.csv")).unwrap();
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (1, 63, 27));
    assert_eq!(rec.n_sensors(), 63 * 27);
    let max = rec.data().iter().copied().fold(0.0f32, f32::max);
    assert!(max <= 402.0 && max > 300.0);
    assert!(rec.data().iter().all(|&v| v >= 0.0 && v.fract() == 0.0));
}

#[test]
fn csv_round_trip_with_missing_sensors() {
    let rec = read_recording(data("FrasP01L.asf")).unwrap();
    for t in [0, 57, 204] {
        let s = csv::frame_to_csv(&rec, t).unwrap();
        let back = csv::parse_csv(s.as_bytes(), "mem.csv").unwrap();
        assert_eq!(back.sensor_mask(), rec.sensor_mask());
        assert_eq!(back.data(), rec.frame_slice(t).unwrap());
    }
    // Non-integer values survive exactly.
    let r = Recording::new(1, 2, 2, vec![0.1, 1e-7, 123.456, 3.0e5], vec![true; 4]).unwrap();
    let back = csv::parse_csv(csv::frame_to_csv(&r, 0).unwrap().as_bytes(), "m").unwrap();
    assert_eq!(back.data(), r.data());
}

#[test]
fn npy_round_trip_keeps_everything() {
    let rec = read_recording(data("FrasP01L.asf")).unwrap();
    let bytes = npy::recording_to_npy(&rec);
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let back = parse_bytes(&bytes, Format::Npy, "mem.npy").unwrap();
    assert_eq!(back.data(), rec.data());
    assert_eq!(back.sensor_mask(), rec.sensor_mask());
    let dir = std::env::temp_dir().join(format!("pedo-io-npy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("rec.bin");
    npy::write_npy(&rec, &p).unwrap();
    // Detected from the magic bytes despite the extension.
    assert_eq!(read_recording(&p).unwrap().data(), rec.data());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn npy_bytes(descr: &str, fortran: bool, shape: &str, body: &[u8]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}\n",
        if fortran { "True" } else { "False" }
    );
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend_from_slice(body);
    out
}

#[test]
fn npy_dtypes_and_fortran_order() {
    // Values 0..6 of a (2, 3) array in C order.
    let vals = [0i64, 1, 2, 3, 4, 5];
    let expect: Vec<f32> = vals.iter().map(|&v| v as f32).collect();
    let enc = |descr: &str, f: &dyn Fn(i64) -> Vec<u8>| {
        let body: Vec<u8> = vals.iter().flat_map(|&v| f(v)).collect();
        npy_bytes(descr, false, "(2, 3)", &body)
    };
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("<f4", enc("<f4", &|v| (v as f32).to_le_bytes().to_vec())),
        ("<f8", enc("<f8", &|v| (v as f64).to_le_bytes().to_vec())),
        ("<i2", enc("<i2", &|v| (v as i16).to_le_bytes().to_vec())),
        ("<i4", enc("<i4", &|v| (v as i32).to_le_bytes().to_vec())),
        ("<i8", enc("<i8", &|v| v.to_le_bytes().to_vec())),
        ("|u1", enc("|u1", &|v| vec![v as u8])),
        ("<u2", enc("<u2", &|v| (v as u16).to_le_bytes().to_vec())),
        (">f8", enc(">f8", &|v| (v as f64).to_be_bytes().to_vec())),
    ];
    for (d, b) in cases {
        let r = npy::parse_npy(&b, d).unwrap_or_else(|e| panic!("{d}: {e}"));
        assert_eq!((r.n_frames(), r.rows(), r.cols()), (1, 2, 3), "{d}");
        assert_eq!(r.data(), &expect[..], "{d}");
    }
    // A float64 beyond float32's range is named as such, not turned into an infinity.
    let huge: Vec<u8> = [0.0f64, 1e39, 0.0, 0.0, 0.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let e = npy::parse_npy(&npy_bytes("<f8", false, "(2, 3)", &huge), "huge.npy")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("array holds 1e39, beyond the float32 range"),
        "{e}"
    );
    // Fortran order: a (2, 2, 3) array a[t, r, c] = 100 t + 10 r + c stored column-major.
    let mut body = Vec::new();
    for c in 0..3 {
        for r in 0..2 {
            for t in 0..2 {
                body.extend_from_slice(&((100 * t + 10 * r + c) as f32).to_le_bytes());
            }
        }
    }
    let rec = npy::parse_npy(&npy_bytes("<f4", true, "(2, 2, 3)", &body), "f").unwrap();
    for t in 0..2 {
        for r in 0..2 {
            for c in 0..3 {
                assert_eq!(
                    rec.data()[(t * 2 + r) * 3 + c],
                    (100 * t + 10 * r + c) as f32
                );
            }
        }
    }
    // NaN in every frame = missing sensor; in some frames only = error.
    let mut body = Vec::new();
    for v in [f32::NAN, 1.0, f32::NAN, 2.0] {
        body.extend_from_slice(&v.to_le_bytes());
    }
    let r = npy::parse_npy(&npy_bytes("<f4", false, "(2, 1, 2)", &body), "n").unwrap();
    assert_eq!(r.sensor_mask(), &[false, true]);
    let mut body = Vec::new();
    for v in [f32::NAN, 1.0, 3.0, 2.0] {
        body.extend_from_slice(&v.to_le_bytes());
    }
    assert!(npy::parse_npy(&npy_bytes("<f4", false, "(2, 1, 2)", &body), "n").is_err());
    // Truncated data and bad shapes are errors naming the file.
    let good = npy_bytes("<f4", false, "(2, 3)", &[0u8; 24]);
    let e = npy::parse_npy(&good[..good.len() - 1], "cut.npy")
        .unwrap_err()
        .to_string();
    assert!(e.contains("cut.npy") && e.contains("truncated"), "{e}");
    assert!(npy::parse_npy(&npy_bytes("<f4", false, "(24,)", &[0u8; 96]), "x").is_err());
    assert!(npy::parse_npy(&npy_bytes("<c8", false, "(1, 1)", &[0u8; 8]), "x").is_err());
}

#[test]
fn png16_round_trip_and_folder_and_sequence() {
    let rec = read_recording(data("MUN104L.csv")).unwrap();
    let png = images::frame_to_png16(&rec, 0, 1.0).unwrap();
    let back = parse_bytes(&png, Format::Png, "mem.png").unwrap();
    assert_eq!(back.data(), rec.data());
    assert_eq!(back.format, Some(Format::Png));
    // Scaled values: 0.5 steps written at scale 2.
    let r = Recording::new(1, 1, 3, vec![0.5, 1.0, 300.5], vec![true; 3]).unwrap();
    let b = parse_bytes(
        &images::frame_to_png16(&r, 0, 2.0).unwrap(),
        Format::Png,
        "m",
    )
    .unwrap();
    assert_eq!(&*b.data(), &[1.0, 2.0, 601.0]);
    assert!(images::frame_to_png16(&r, 0, 1.0).is_err());

    let asf = read_recording(data("FrasP01L.asf")).unwrap();
    let dir = std::env::temp_dir().join(format!("pedo-io-png-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for t in 0..12 {
        images::write_png16(&asf, 60 + t, 1.0, dir.join(format!("f_{}.png", t + 1))).unwrap();
    }
    let folder = read_recording(&dir).unwrap();
    let seq = read_recording(dir.join("f_%d.png")).unwrap();
    assert_eq!(folder.n_frames(), 12);
    assert_eq!(folder, seq);
    for t in 0..12 {
        // Natural order: f_2 before f_10. Missing sensors become 0 in PNG.
        assert_eq!(
            folder.frame_slice(t).unwrap(),
            asf.frame_slice(60 + t).unwrap()
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn assert_names(e: IoError, file: &str) {
    let s = e.to_string();
    assert!(s.contains(file), "{s}");
}

#[test]
fn corrupt_and_truncated_files_give_located_errors() {
    let asf = std::fs::read(data("FrasP01L.asf")).unwrap();
    let text = String::from_utf8(asf.clone()).unwrap();
    // Cut in the middle of the data, at a frame boundary and just before the closing @@.
    for cut in [
        asf.len() / 2,
        text.find("Frame 100").unwrap(),
        text.rfind("@@").unwrap(),
        200,
    ] {
        let e = parse_bytes(&asf[..cut], Format::Asf, "cut.asf").unwrap_err();
        assert!(
            matches!(e, IoError::Parse { .. } | IoError::Format { .. }),
            "{e}"
        );
        assert_names(e, "cut.asf");
    }
    // Cut inside a row, after a comma or inside a number: a truncated file, with its complete
    // frames counted, not a bad value.
    let row = text.find("\nFrame 72").unwrap() + 200;
    let after_comma = row + text[row..].find(',').unwrap() + 1;
    for cut in [after_comma, after_comma - 2, 200_000] {
        let e = parse_bytes(&asf[..cut], Format::Asf, "cut.asf").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("truncated: the file ends after") && msg.contains("complete frames"),
            "cut at {cut}: {msg}"
        );
    }
    // A bad value names the line.
    let bad = text.replacen("B,B,B,B,B,B,B,B,B,0,0", "B,B,B,B,B,B,B,B,B,x,0", 1);
    let e = parse_bytes(bad.as_bytes(), Format::Asf, "bad.asf").unwrap_err();
    match e {
        IoError::Parse { line, .. } => assert_eq!(line, 32),
        other => panic!("{other}"),
    }
    // A short row.
    let bad = text.replacen(
        "B,B,B,B,B,B,B,B,B,0,0,0,0,0,0,0,B,B,B,B,B\r\n",
        "B,B,B\r\n",
        1,
    );
    assert!(matches!(
        parse_bytes(bad.as_bytes(), Format::Asf, "b").unwrap_err(),
        IoError::Parse { line: 32, .. }
    ));

    let lst = std::fs::read(data("synthetic-walk.lst")).unwrap();
    let last_force = lst.windows(6).rposition(|w| w == b"\nForce").unwrap();
    for cut in [lst.len() / 3, last_force, 100] {
        assert_names(
            parse_bytes(&lst[..cut], Format::Lst, "cut.lst").unwrap_err(),
            "cut.lst",
        );
    }
    let csv = b"1,2,3\n4,5\n";
    match csv::parse_csv(csv, "short.csv").unwrap_err() {
        IoError::Parse { line, path, .. } => assert_eq!((line, path.as_str()), (2, "short.csv")),
        other => panic!("{other}"),
    }
    assert!(csv::parse_csv(b"1,2\n3,zz\n", "z.csv").is_err());
    // A header numbering the columns is no row of pressures; a row that only starts like one is.
    for header in ["1,2,3,4,5", "0;1;2;3;4"] {
        let text = format!("{header}\n0,5,7,1,0\n0,9,2,3,0\n").replace(';', ",");
        let rec = csv::parse_csv(text.as_bytes(), "h.csv").unwrap();
        assert_eq!((rec.rows(), rec.cols()), (2, 5), "{header}");
    }
    let rec = csv::parse_csv(b"1,2,3,4,4\n0,5,7,1,0\n", "d.csv").unwrap();
    assert_eq!(rec.rows(), 2);
    // A European export: semicolons between values, decimal commas.
    let rec = csv::parse_csv("p1;p2;p3\n0,5;12,25;-1\n3;0;1,0\n".as_bytes(), "eu.csv").unwrap();
    assert_eq!((rec.rows(), rec.cols()), (2, 3));
    assert_eq!(
        &*rec.frame_slice(0).unwrap(),
        &[0.5f32, 12.25, 0.0, 3.0, 0.0, 1.0][..]
    );
    assert!(!rec.sensor_mask()[2], "-1 is no sensor");
    assert_names(
        read_recording(data("does-not-exist.asf")).unwrap_err(),
        "does-not-exist.asf",
    );
}

#[test]
fn format_detection_by_content() {
    use pedo_io::detect_format;
    use std::path::Path;
    let asf = std::fs::read(data("FrasP01L.asf")).unwrap();
    let lst = std::fs::read(data("synthetic-walk.lst")).unwrap();
    let csv = std::fs::read(data("MUN104L.csv")).unwrap();
    assert_eq!(
        detect_format(Path::new("x.dat"), &asf[..4096]),
        Some(Format::Asf)
    );
    assert_eq!(
        detect_format(Path::new("x.dat"), &lst[..4096]),
        Some(Format::Lst)
    );
    assert_eq!(detect_format(Path::new("x"), &csv), Some(Format::Csv));
    assert_eq!(
        detect_format(Path::new("x.csv"), b"\x93NUMPY\x01\x00"),
        Some(Format::Npy)
    );
    assert_eq!(detect_format(Path::new("x"), b"\x00\x01\xff"), None);
}

#[test]
fn eight_bit_png_and_sixteen_bit_tiff() {
    use image::{ImageBuffer, ImageFormat, Luma};
    let px8: Vec<u8> = (0..6 * 5).map(|i| (i * 7 % 256) as u8).collect();
    let img8: ImageBuffer<Luma<u8>, Vec<u8>> = ImageBuffer::from_raw(6, 5, px8.clone()).unwrap();
    let mut png = std::io::Cursor::new(Vec::new());
    img8.write_to(&mut png, ImageFormat::Png).unwrap();
    let r = parse_bytes(png.get_ref(), Format::Png, "a.png").unwrap();
    assert_eq!((r.rows(), r.cols()), (5, 6));
    assert_eq!(
        r.data(),
        &px8.iter().map(|&v| v as f32).collect::<Vec<_>>()[..]
    );

    let px16: Vec<u16> = (0..4 * 3).map(|i| (i * 5000) as u16).collect();
    let img16: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_raw(4, 3, px16.clone()).unwrap();
    let mut tif = std::io::Cursor::new(Vec::new());
    img16.write_to(&mut tif, ImageFormat::Tiff).unwrap();
    let dir = std::env::temp_dir().join(format!("pedo-io-tif-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("x.tif");
    std::fs::write(&p, tif.get_ref()).unwrap();
    let r = read_recording(&p).unwrap();
    assert_eq!(r.format, Some(Format::Tiff));
    assert_eq!(
        r.data(),
        &px16.iter().map(|&v| v as f32).collect::<Vec<_>>()[..]
    );
    std::fs::remove_dir_all(&dir).unwrap();
    // Colour images are refused, not silently converted.
    let rgb: ImageBuffer<image::Rgb<u8>, Vec<u8>> =
        ImageBuffer::from_raw(2, 2, vec![0; 12]).unwrap();
    let mut c = std::io::Cursor::new(Vec::new());
    rgb.write_to(&mut c, ImageFormat::Png).unwrap();
    assert!(parse_bytes(c.get_ref(), Format::Png, "rgb.png").is_err());
}
