//! A text export read for a streamed run (`read_for_streaming`) as it is parsed again, frame by
//! frame: an emed `.lst`'s frames, sensor mask, values below 0 and metadata as the whole read
//! finds them, a truncated file refused with the whole read's error, and a file rewritten
//! between the two readings refused.

use pedo_io::formats::{read_for_streaming, why_read_whole, ReadOptions};
use pedo_io::{read_recording, FrameSource, Recording, FRAME_WINDOW};

#[path = "common/files.rs"]
mod files;
use files::temp_dir;

/// Frames `from..` of a streamed file, read window by window as a run reads them.
fn read_back(frames: &mut impl FrameSource, header: &Recording, from: usize) -> Vec<f32> {
    let mut back = Vec::new();
    let n = header.n_frames();
    for w0 in (from..n).step_by(FRAME_WINDOW) {
        let w1 = (w0 + FRAME_WINDOW).min(n);
        back.extend_from_slice(&frames.window(header, w0, w1).unwrap().data());
    }
    back
}

/// The synthetic emed walk's pages repeated `k` times (40 pictures each), one value set below
/// 0 (an offset): more pictures than two windows.
fn long_lst(k: usize) -> Vec<u8> {
    let one = std::fs::read(files::data("synthetic-walk.lst")).unwrap();
    let mut out = Vec::new();
    for _ in 0..k {
        out.extend_from_slice(&one);
        if !out.ends_with(b"\x0c") {
            out.push(b'\x0c');
        }
    }
    out
}

#[test]
fn lst_frames_read_as_they_are_parsed_are_the_whole_reads() {
    let dir = temp_dir("lst-stream");
    let path = dir.join("walk.lst");
    std::fs::write(&path, long_lst(4)).unwrap();
    let held = read_recording(&path).unwrap();
    assert!(held.n_frames() > 2 * FRAME_WINDOW, "{}", held.n_frames());
    assert_eq!(why_read_whole(&path), None);
    for from in [0, FRAME_WINDOW + 5] {
        let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
        let mut frames = frames.expect("an emed .lst streams");
        assert_eq!(header.n_frames(), held.n_frames());
        assert_eq!(header.sensor_mask(), held.sensor_mask());
        assert_eq!(header.negative_values(), held.negative_values());
        assert_eq!(
            (header.pitch_mm, header.dt_s, header.sensel_area_mm2),
            (held.pitch_mm, held.dt_s, held.sensel_area_mm2)
        );
        assert_eq!((&header.units, header.format), (&held.units, held.format));
        assert!(header.frames_bytes() * 5 < held.frames_bytes());
        let back = read_back(&mut frames, &header, from);
        let per = held.rows() * held.cols();
        assert_eq!(
            back,
            held.data()[from * per..].to_vec(),
            "from frame {from}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_streamed_lst_is_refused_as_the_whole_read_refuses_it() {
    let dir = temp_dir("lst-stream-bad");
    let text = long_lst(2);
    // Cut inside the last page: its closing Force line missing.
    let cut = &text[..text.len() - 300];
    let path = dir.join("cut.lst");
    std::fs::write(&path, cut).unwrap();
    let whole = read_recording(&path).unwrap_err().to_string();
    let e = read_for_streaming(&path, &ReadOptions::default())
        .err()
        .unwrap();
    assert_eq!(e.to_string(), whole);
    // Rewritten between the readings, to the same length, in a page the second reading has not
    // reached (it reads a window ahead): its digest differs.
    let text = long_lst(4);
    let path = dir.join("changed.lst");
    std::fs::write(&path, &text).unwrap();
    let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
    let mut frames = frames.unwrap();
    let at = text.windows(6).rposition(|w| w == b"Force\t").unwrap() + 6;
    let mut changed = text.clone();
    changed[at] = if changed[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(&path, &changed).unwrap();
    let n = header.n_frames();
    let mut failed = None;
    for w0 in (0..n).step_by(FRAME_WINDOW) {
        if let Err(e) = frames.window(&header, w0, (w0 + FRAME_WINDOW).min(n)) {
            failed = Some(e.to_string());
            break;
        }
    }
    let failed = failed.expect("a rewritten file is refused");
    assert!(failed.contains("changed"), "{failed}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A footscan export of `n` frames of 6 x 5 sensors: column 4 of row 0 is no sensor (-1 in every
/// grid), row 5 column 0 is -1 in the first frames only (an unloaded sensor), one value is below
/// 0 and `odd` is written at frame 3, row 2, column 2.
fn footscan(n: usize, odd: &str) -> String {
    let mut out = String::from(
        "[General]\nUnitDistance=mm\nUnitPressure=kPa\nUnitTime=ms\n\n[Technical]\nSensCountX=6\n",
    );
    out += &format!("SensCountY=5\nLDistX=7.62\nLDistY=5.08\nTimeDiff=2\nMinIdx=1\nMaxIdx={n}\n");
    let grid = |t: usize| -> String {
        let mut g = String::new();
        for r in 0..6 {
            let row: Vec<String> = (0..5)
                .map(|c| match (r, c) {
                    (0, 4) => "-1".to_string(),
                    (5, 0) if t < 10 => "-1".to_string(),
                    (2, 2) if t == 3 => odd.to_string(),
                    (1, 1) if t == 7 => "-2.5".to_string(),
                    _ => format!("{}", (t * 7 + r * 5 + c * 3) % 11),
                })
                .collect();
            g += &row.join("\t");
            g.push('\n');
        }
        g
    };
    out += &format!("\n[Data]\n{}", grid(0));
    for t in 0..n {
        out += &format!("\n[Data{}]\n{}", t + 1, grid(t));
    }
    out
}

#[test]
fn footscan_frames_read_as_they_are_parsed_are_the_whole_reads() {
    let dir = temp_dir("footscan-stream");
    let path = dir.join("trial.txt");
    std::fs::write(&path, footscan(2 * FRAME_WINDOW + 9, "4")).unwrap();
    let held = read_recording(&path).unwrap();
    assert_eq!(why_read_whole(&path), None);
    let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
    let mut frames = frames.expect("a footscan export streams");
    assert_eq!(header.n_frames(), held.n_frames());
    assert_eq!(header.sensor_mask(), held.sensor_mask());
    assert_eq!(held.n_sensors(), 29);
    assert_eq!(header.negative_values(), held.negative_values());
    assert_eq!(held.negative_values().count, 1);
    assert_eq!(
        (header.pitch_mm, header.dt_s, &header.units, header.format),
        (held.pitch_mm, held.dt_s, &held.units, held.format)
    );
    assert_eq!(read_back(&mut frames, &header, 0), held.data().to_vec());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_streamed_footscan_or_apd_file_is_refused_or_read_as_the_whole_read() {
    let dir = temp_dir("footscan-stream-bad");
    // A value too large for the frames' numbers, and a file cut inside its last frame.
    let text = footscan(20, "1e39");
    let cut = footscan(20, "4");
    for (name, text) in [("huge.txt", &text[..]), ("cut.txt", &cut[..cut.len() - 12])] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let whole = read_recording(&path).unwrap_err().to_string();
        let e = read_for_streaming(&path, &ReadOptions::default()).err();
        assert_eq!(e.map(|e| e.to_string()), Some(whole), "{name}");
    }
    // A Zebris .apd of its peak image only: its one frame.
    let apd = "[General]\nSource=<<zebris>>\nUnitDistance=cm\n[Technical]\nSensCountX=2\n\
               SensCountY=3\nLDistX=0.846\nLDistY=0.846\n[Data]\n1\t-1\t3\n0\t5\t6\n";
    let path = dir.join("peak.apd");
    std::fs::write(&path, apd).unwrap();
    let held = read_recording(&path).unwrap();
    let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
    assert_eq!(header.sensor_mask(), held.sensor_mask());
    assert_eq!(header.format, held.format);
    let window = frames
        .expect("an .apd streams")
        .window(&header, 0, 1)
        .unwrap();
    assert_eq!(window.data(), held.data());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The pedar sample's 100 frames repeated `k` times (its header's total time made to agree),
/// one value set below 0 (an offset).
fn long_pedar(k: usize) -> String {
    let one = std::fs::read_to_string(files::data("pedar-example-3.01-4.00.asc")).unwrap();
    let (head, data) = one.split_at(one.find("time[secs]").unwrap());
    let (columns, rows) = data.split_at(data.find('\n').unwrap() + 1);
    let head = head.replace(
        "total time [secs]:   1.000",
        &format!("total time [secs]:   {k}.000"),
    );
    let mut rows = rows.repeat(k);
    let at = rows.find("  0.000").unwrap();
    rows.replace_range(at..at + 7, " -1.500");
    format!("{head}{columns}{rows}")
}

#[test]
fn pedar_frames_read_as_they_are_parsed_are_the_whole_reads() {
    let dir = temp_dir("pedar-stream");
    let path = dir.join("trial.asc");
    std::fs::write(&path, long_pedar(3)).unwrap();
    let held = read_recording(&path).unwrap();
    assert_eq!(held.n_frames(), 300);
    assert_eq!(why_read_whole(&path), None);
    let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
    let mut frames = frames.expect("a pedar export streams");
    assert_eq!(header.n_frames(), held.n_frames());
    assert_eq!(header.sensor_mask(), held.sensor_mask());
    assert_eq!(header.negative_values(), held.negative_values());
    // The value below 0 is counted in each cell of the image its sensor covers.
    assert!(held.negative_values().count >= 1);
    assert_eq!((&header.feet, held.feet.len()), (&held.feet, 2));
    assert_eq!(
        (header.pitch_mm, header.dt_s, &header.units, header.format),
        (held.pitch_mm, held.dt_s, &held.units, held.format)
    );
    assert!(header.frames_bytes() * 5 < held.frames_bytes());
    assert_eq!(read_back(&mut frames, &header, 0), held.data().to_vec());
    // Cut inside its last line and short of the frames its header states: the whole read's
    // error; rewritten between the readings: refused.
    let text = long_pedar(3);
    let cut = dir.join("cut.asc");
    std::fs::write(&cut, &text[..text.len() - 40]).unwrap();
    let whole = read_recording(&cut).unwrap_err().to_string();
    let e = read_for_streaming(&cut, &ReadOptions::default()).err();
    assert_eq!(e.map(|e| e.to_string()), Some(whole));
    let (header, frames) = read_for_streaming(&path, &ReadOptions::default()).unwrap();
    let mut frames = frames.unwrap();
    let mut changed = text.clone().into_bytes();
    let at = text.rfind("  0.000").unwrap() + 2;
    changed[at] = b'1';
    std::fs::write(&path, &changed).unwrap();
    let n = header.n_frames();
    let failed = (0..n)
        .step_by(FRAME_WINDOW)
        .find_map(|w0| frames.window(&header, w0, (w0 + FRAME_WINDOW).min(n)).err())
        .expect("a rewritten file is refused");
    assert!(failed.to_string().contains("changed"), "{failed}");
    let _ = std::fs::remove_dir_all(&dir);
}
