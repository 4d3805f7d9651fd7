//! `run_study` runs at most `jobs` recordings at once, each on one thread, and returns the rows in
//! input order.

use pedo_output::RunOutputs;
use pedo_study::{run_study, StudyEvent, StudyOptions};
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::Mutex;

fn recordings(n: usize) -> Vec<PathBuf> {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data");
    let files = [
        "emed-test-1-10.lst",
        "tekscan-FrasP01L-11-20.csv",
        "footscan-FrasP01L-11-20.txt",
    ];
    (0..n).map(|i| data.join(files[i % files.len()])).collect()
}

/// The largest number of recordings seen in flight (started, not finished) during a study.
fn most_in_flight(jobs: usize, paths: &[PathBuf]) -> (usize, Vec<String>) {
    let opts = StudyOptions {
        inputs: Vec::new(),
        params: Default::default(),
        read: Default::default(),
        out: None,
        jobs,
        force: false,
        cancel: None,
        outputs: RunOutputs {
            figures: Default::default(),
            pair_figures: false,
            report: false,
            animation: false,
            tables: Default::default(),
            regions: None,
            masks: None,
        },
    };
    let state = Mutex::new((BTreeSet::new(), BTreeSet::new(), 0usize));
    let rows = run_study(paths, &opts, &|event| {
        let mut s = state.lock().unwrap();
        match event {
            StudyEvent::Progress { index, .. } if !s.1.contains(&index) => {
                s.0.insert(index);
            }
            StudyEvent::Finished { index, .. } => {
                s.0.remove(&index);
                s.1.insert(index);
            }
            _ => {}
        }
        s.2 = s.2.max(s.0.len());
    })
    .unwrap()
    .rows;
    assert!(rows
        .iter()
        .all(|r| r.message.is_empty() || r.frames.is_some()));
    (
        state.into_inner().unwrap().2,
        rows.into_iter().map(|r| r.path).collect(),
    )
}

#[test]
fn at_most_jobs_recordings_run_at_once_and_rows_keep_the_input_order() {
    let paths = recordings(6);
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let (one, rows) = most_in_flight(1, &paths);
    assert_eq!(one, 1, "--jobs 1 ran recordings side by side");
    assert_eq!(rows, names);
    let (two, rows) = most_in_flight(2, &paths);
    assert!(
        (1..=2).contains(&two),
        "--jobs 2 had {two} recordings in flight"
    );
    assert_eq!(rows, names);
}

/// A photograph of the foot (a colour PNG or TIFF) beside a recording is passed over, in the
/// recording's folder as in a folder of its own; a folder of grayscale frames is one recording.
#[test]
fn a_search_passes_over_colour_photographs_and_keeps_grayscale_frames() {
    use image::{ImageBuffer, ImageFormat, Luma, Rgb};
    let dir = std::env::temp_dir().join(format!("pedo-io-photo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for sub in ["s01", "photos", "frames"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let asf = recordings(1).remove(0);
    std::fs::copy(&asf, dir.join("s01/walk.lst")).unwrap();
    let photo: ImageBuffer<Rgb<u8>, Vec<u8>> =
        ImageBuffer::from_fn(8, 6, |x, y| Rgb([x as u8, y as u8, 7]));
    photo
        .save_with_format(dir.join("s01/foot.png"), ImageFormat::Png)
        .unwrap();
    photo
        .save_with_format(dir.join("photos/foot.tif"), ImageFormat::Tiff)
        .unwrap();
    let frame: ImageBuffer<Luma<u8>, Vec<u8>> = ImageBuffer::from_fn(8, 6, |x, _| Luma([x as u8]));
    for k in 1..=2 {
        frame
            .save_with_format(dir.join(format!("frames/f{k}.png")), ImageFormat::Png)
            .unwrap();
    }
    let found = pedo_study::find_recordings(&[dir.to_str().unwrap()]).unwrap();
    let names: Vec<_> = found
        .iter()
        .map(|p| p.strip_prefix(&dir).unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["frames", "s01/walk.lst"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(unix)]
#[test]
fn a_search_reads_regular_files_only_and_never_enters_the_system_trees() {
    use std::os::unix::fs::symlink;
    let dir = std::env::temp_dir().join(format!("pedo-io-special-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(&recordings(1)[0], dir.join("walk.lst")).unwrap();
    // A FIFO (reading it waits for a writer), a socket, a device, and links into /proc (whose
    // /proc/kmsg blocks a reader) and /sys.
    let fifo = std::process::Command::new("mkfifo")
        .arg(dir.join("pipe.asf"))
        .status();
    let _socket = std::os::unix::net::UnixListener::bind(dir.join("socket.asf")).unwrap();
    symlink("/dev/zero", dir.join("zero.asf")).unwrap();
    symlink("/proc", dir.join("proc")).unwrap();
    symlink("/sys", dir.join("sys")).unwrap();
    symlink("/proc/kmsg", dir.join("kmsg.asf")).unwrap();
    let (send, found) = std::sync::mpsc::channel();
    let input = dir.to_str().unwrap().to_string();
    std::thread::spawn(move || send.send(pedo_study::find_recordings(&[input])));
    let found = found
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("the search ends")
        .unwrap();
    assert_eq!(found, [dir.join("walk.lst")], "mkfifo: {fifo:?}");
    // A search of the system trees themselves finds nothing, at once.
    let proc = pedo_study::find_recordings(&["/proc/self"]).unwrap();
    assert!(proc.is_empty(), "{proc:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
