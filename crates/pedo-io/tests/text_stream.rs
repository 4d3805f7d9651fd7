//! A text export read for a streamed run (`read_for_streaming`) as it is parsed again, frame by
//! frame: an emed `.lst`'s frames, sensor mask, values below 0 and metadata as the whole read
//! finds them, a truncated file refused with the whole read's error, and a file rewritten
//! between the two readings refused.

use pedo_io::formats::{read_for_streaming, why_read_whole, ReadOptions};
use pedo_io::{read_recording, FrameSource, FRAME_WINDOW};

#[path = "common/files.rs"]
mod files;
use files::temp_dir;

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
        let mut back = Vec::new();
        let n = held.n_frames();
        for w0 in (from..n).step_by(FRAME_WINDOW) {
            let w1 = (w0 + FRAME_WINDOW).min(n);
            back.extend_from_slice(&frames.window(&header, w0, w1).unwrap().data());
        }
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
