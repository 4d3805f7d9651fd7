//! A `.npy` array, or a `.npz` archive's, read for a streamed run (`read_for_streaming`): its
//! shape, sensor mask and values below 0 as the whole read finds them, its frames read back
//! window by window equal to the whole read's, in C and Fortran order, several dtypes, stored
//! and deflated members; a bad array refused with the whole read's error; a file that is read
//! whole says why (`why_read_whole`).

use pedo_io::formats::{read_for_streaming, why_read_whole, ReadOptions};
use pedo_io::{read_recording, FrameSource, FRAME_WINDOW};

#[path = "common/files.rs"]
mod files;
use files::temp_dir;
#[path = "common/zip.rs"]
mod zip_file;
use zip_file::zip;

/// A `.npy` file of shape `(t, r, c)` whose value at `[i, j, k]` is `value(i, j, k)`, stored in
/// C or Fortran order as `descr` (`<f4`, `>i2`, `<f8`).
fn npy(
    (t, r, c): (usize, usize, usize),
    descr: &str,
    fortran: bool,
    value: impl Fn(usize, usize, usize) -> f64,
) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': ({t}, {r}, {c}), }}",
        if fortran { "True" } else { "False" }
    );
    let mut header = dict.into_bytes();
    header.resize((10 + header.len() + 1).div_ceil(64) * 64 - 11, b' ');
    header.push(b'\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    let mut index = Vec::new();
    match fortran {
        false => {
            (0..t).for_each(|i| (0..r).for_each(|j| (0..c).for_each(|k| index.push((i, j, k)))))
        }
        true => {
            (0..c).for_each(|k| (0..r).for_each(|j| (0..t).for_each(|i| index.push((i, j, k)))))
        }
    }
    for (i, j, k) in index {
        let v = value(i, j, k);
        match descr {
            "<f4" => out.extend_from_slice(&(v as f32).to_le_bytes()),
            "<f8" => out.extend_from_slice(&v.to_le_bytes()),
            ">i2" => out.extend_from_slice(&(v as i16).to_be_bytes()),
            _ => panic!("no writer for {descr}"),
        }
    }
    out
}

/// A walk-like value: mostly 0, some loaded sensels, a few below 0; NaN at `(1, 2)` in
/// every frame when `nan` (a missing sensor).
fn pressure(nan: bool) -> impl Fn(usize, usize, usize) -> f64 {
    move |i, j, k| {
        if nan && (j, k) == (1, 2) {
            return f64::NAN;
        }
        match (i * 7 + j * 3 + k) % 11 {
            0 => -((i % 5) as f64) - 1.0,
            1..=4 => ((i + j * k) % 90) as f64 + 1.0,
            _ => 0.0,
        }
    }
}

#[test]
fn npy_frames_read_window_by_window_are_the_whole_reads() {
    let dir = temp_dir("npy-stream");
    // More frames than two windows, the last window short.
    let shape = (2 * FRAME_WINDOW + 13, 5, 4);
    let cases = [
        ("<f4", false, false),
        ("<f4", true, false),
        ("<f8", false, true),
        ("<f8", true, true),
        (">i2", true, false),
    ];
    for (descr, fortran, nan) in cases {
        let what = format!("{descr} fortran={fortran} nan={nan}");
        let path = dir.join(format!("a{}.npy", descr.replace(['<', '>'], "")));
        std::fs::write(&path, npy(shape, descr, fortran, pressure(nan))).unwrap();
        let held = read_recording(&path).unwrap();
        assert_eq!(why_read_whole(&path), None, "{what}");
        let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
        let mut frames = frames.unwrap_or_else(|| panic!("{what}: not streamed"));
        assert_eq!(header.n_frames(), held.n_frames(), "{what}");
        assert_eq!(header.sensor_mask(), held.sensor_mask(), "{what}");
        assert_eq!(header.sensor_mask()[6], !nan, "{what}");
        assert_eq!(header.negative_values(), held.negative_values(), "{what}");
        assert!(held.negative_values().count > 0, "{what}");
        assert_eq!(header.format, held.format, "{what}");
        assert!(header.frames_bytes() * 5 < held.frames_bytes(), "{what}");
        let mut back = Vec::new();
        for w0 in (0..shape.0).step_by(FRAME_WINDOW) {
            let w1 = (w0 + FRAME_WINDOW).min(shape.0);
            let window = frames.window(&header, w0, w1).unwrap();
            assert_eq!(window.n_frames(), w1 - w0, "{what}");
            back.extend_from_slice(&window.data());
        }
        assert_eq!(back, held.data().to_vec(), "{what}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_streamed_npy_is_refused_as_the_whole_read_refuses_it() {
    let dir = temp_dir("npy-stream-bad");
    // NaN at one sensor in some frames only, an infinite value: each the whole read's error.
    let some_nan = |i, j, k| match (i, j, k) {
        (70, 1, 1) => f64::NAN,
        _ => 1.0,
    };
    let infinite = |i, _, _| if i == 100 { f64::INFINITY } else { 1.0 };
    for (name, fortran, value) in [
        (
            "nan.npy",
            false,
            &some_nan as &dyn Fn(usize, usize, usize) -> f64,
        ),
        ("nan_f.npy", true, &some_nan),
        ("inf_f.npy", true, &infinite),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, npy((130, 3, 3), "<f8", fortran, value)).unwrap();
        let whole = read_recording(&path).unwrap_err().to_string();
        let e = read_for_streaming(&path, &ReadOptions::default())
            .err()
            .unwrap();
        assert_eq!(e.to_string(), whole, "{name}");
    }
    // A truncated array: the header's error, before any frame.
    let mut cut = npy((130, 3, 3), "<f4", false, |_, _, _| 1.0);
    cut.truncate(cut.len() - 4);
    let path = dir.join("cut.npy");
    std::fs::write(&path, cut).unwrap();
    let e = read_for_streaming(&path, &ReadOptions::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("(truncated)"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn files_read_whole_say_why() {
    let dir = temp_dir("npy-why");
    let gz = files::data("zebris-FrasP01L-26-55.json.gz");
    let why = why_read_whole(&gz).unwrap();
    assert!(why.contains("gzip"), "{why}");
    let (_, frames) = read_for_streaming(&gz, &ReadOptions::default()).unwrap();
    assert!(frames.is_none());
    let xml = why_read_whole(files::data("zebris-FrasP01L-26-55.xml")).unwrap();
    assert!(
        xml.contains("the zebris-xml format is read whole: its frames are held as the windows"),
        "{xml}"
    );
    assert_eq!(why_read_whole(files::data("emed-test-1-10.lst")), None);
    assert_eq!(
        why_read_whole(files::data("pedar-example-3.01-4.00.asc")),
        None
    );
    let asf = files::data("FrasP01L.asf");
    assert_eq!(why_read_whole(asf), None);
    assert!(why_read_whole(&dir).unwrap().contains("folder"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Frames `from..` of the file at `path` read for a streamed run, window by window from
/// `from`, with the recording read so.
fn streamed_frames(path: &std::path::Path, from: usize) -> (pedo_io::Recording, Vec<f32>) {
    let (header, frames) = read_for_streaming(path, &ReadOptions::default()).unwrap();
    let mut frames = frames.expect("streamed");
    let mut back = Vec::new();
    let n = header.n_frames();
    for w0 in (from..n).step_by(FRAME_WINDOW) {
        let w1 = (w0 + FRAME_WINDOW).min(n);
        let window = frames.window(&header, w0, w1).unwrap();
        assert_eq!(window.n_frames(), w1 - w0);
        back.extend_from_slice(&window.data());
    }
    (header, back)
}

#[test]
fn npz_members_read_window_by_window_are_the_whole_reads() {
    let dir = temp_dir("npz-stream");
    let shape = (2 * FRAME_WINDOW + 13, 5, 4);
    // A 1-D member first, which the whole read skips (as the streamed one must).
    let labels = npy_1d();
    for (deflate, zip64, fortran) in [
        (false, false, false),
        (false, true, true),
        (true, false, false),
        (true, true, false),
    ] {
        let what = format!("deflate={deflate} zip64={zip64} fortran={fortran}");
        let array = npy(shape, "<f4", fortran, pressure(true));
        let members = [("labels.npy", labels.clone()), ("frames.npy", array)];
        let path = dir.join("a.npz");
        std::fs::write(&path, zip(&members, deflate, zip64)).unwrap();
        let held = read_recording(&path).unwrap();
        assert_eq!(why_read_whole(&path), None, "{what}");
        let (header, back) = streamed_frames(&path, 0);
        assert_eq!(header.n_frames(), held.n_frames(), "{what}");
        assert_eq!(header.sensor_mask(), held.sensor_mask(), "{what}");
        assert_eq!(header.negative_values(), held.negative_values(), "{what}");
        assert_eq!(header.format, held.format, "{what}");
        assert!(header.frames_bytes() * 5 < held.frames_bytes(), "{what}");
        assert_eq!(back, held.data().to_vec(), "{what}");
        // A run from a later frame: the windows before it skipped (inflated and dropped).
        let from = FRAME_WINDOW + 3;
        let (_, later) = streamed_frames(&path, from);
        assert_eq!(later, held.data()[from * 20..].to_vec(), "{what}");
    }
    // A deflated Fortran-order array is read whole, saying why, with the whole read's frames.
    let array = npy(shape, "<f8", true, pressure(false));
    let path = dir.join("f.npz");
    std::fs::write(&path, zip(&[("frames.npy", array)], true, false)).unwrap();
    let why = why_read_whole(&path).unwrap();
    assert!(
        why.contains("Fortran-order array in a deflated member"),
        "{why}"
    );
    let (rec, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
    assert!(frames.is_none());
    assert_eq!(rec, read_recording(&path).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 1-D `.npy` array of two `<f4` zeros (no recording).
fn npy_1d() -> Vec<u8> {
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), }";
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16 + 1).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.push(b'\n');
    out.extend_from_slice(&[0; 8]);
    out
}

#[test]
fn a_streamed_npz_is_read_or_refused_as_the_whole_read() {
    let dir = temp_dir("npz-stream-bad");
    let some_nan = |i, j, k| match (i, j, k) {
        (70, 1, 1) => f64::NAN,
        _ => 1.0,
    };
    let infinite = |i, _, _| if i == 100 { f64::INFINITY } else { 1.0 };
    let good = npy((130, 3, 3), "<f8", false, pressure(false));
    let mut corrupt = zip(&[("frames.npy", good.clone())], false, false);
    corrupt[200] ^= 0xff;
    let bad = |value: &dyn Fn(usize, usize, usize) -> f64, fortran| {
        npy((130, 3, 3), "<f8", fortran, value)
    };
    let cases = [
        (
            "nan.npz",
            zip(&[("a.npy", bad(&some_nan, false))], false, false),
        ),
        (
            "nan_f.npz",
            zip(&[("a.npy", bad(&some_nan, true))], false, true),
        ),
        (
            "inf.npz",
            zip(&[("a.npy", bad(&infinite, false))], true, false),
        ),
        // Its values flipped: a CRC mismatch, as the whole read finds it.
        ("crc.npz", corrupt),
        // The first array unreadable, the second read: the whole read's choice.
        (
            "second.npz",
            zip(
                &[("a.npy", bad(&infinite, false)), ("b.npy", good)],
                false,
                false,
            ),
        ),
    ];
    for (name, bytes) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let streamed = read_for_streaming(&path, &ReadOptions::default());
        match read_recording(&path) {
            Ok(whole) => assert_eq!(streamed.unwrap().0, whole, "{name}"),
            Err(whole) => {
                let e = streamed.err().unwrap();
                assert_eq!(e.to_string(), whole.to_string(), "{name}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
