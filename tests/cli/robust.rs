//! Runs that survive what goes wrong: bad pairs are skipped, interrupted and killed runs leave a
//! whole output or none.

use crate::common::temp_dir;
use crate::gzip_stream::gzip;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn demo(out: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_pedomatch"))
        .arg("demo")
        .arg("--out")
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pedomatch")
}

/// The demo on a third of the walk (frames 40 to 99): reading, matching and writing every
/// output as the whole walk does, at a third of the cost, for tests that run it many times.
fn part_demo(out: &Path, extra: &[&str]) -> Child {
    demo(out, &[&["--frames", "40..100"], extra].concat())
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("kill")
        .success();
    assert!(ok, "kill {sig} failed");
}

/// Every file under `dir`, relative, sorted.
fn listing(dir: &Path) -> Vec<String> {
    fn walk(base: &Path, dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                out.push(p.strip_prefix(base).unwrap().display().to_string());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn staging_folders(parent: &Path) -> Vec<String> {
    std::fs::read_dir(parent)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".pedomatch-tmp-"))
        .collect()
}

#[test]
fn a_killed_run_leaves_the_previous_complete_output_or_none() {
    let base = temp_dir("kill");
    let out = base.join("out");
    let reference = {
        let status = part_demo(&out, &[]).wait().unwrap();
        assert!(status.success());
        listing(&out)
    };
    assert!(reference.iter().any(|f| f == "summary.json"));
    // Kill runs into the same folder at moments spread over reading, matching and writing.
    let full = {
        let t = Instant::now();
        part_demo(&base.join("timing"), &[]).wait().unwrap();
        t.elapsed()
    };
    for k in 1..=6 {
        let mut child = part_demo(&out, &[]);
        std::thread::sleep(full.mul_f64(k as f64 / 7.0));
        signal(&child, "-KILL");
        child.wait().unwrap();
        assert_eq!(listing(&out), reference, "after a kill at {k}/7 of a run");
    }
    // The next run sweeps what the killed ones staged.
    assert!(part_demo(&out, &[]).wait().unwrap().success());
    assert_eq!(staging_folders(&base), Vec::<String>::new());
    assert_eq!(listing(&out), reference);
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn ctrl_c_stops_at_once_with_130_and_leaves_no_staging_folder() {
    let base = temp_dir("sigint");
    let out = base.join("out");
    let full = {
        let t = Instant::now();
        part_demo(&base.join("timing"), &[]).wait().unwrap();
        t.elapsed()
    };
    for k in 1..=3 {
        let mut child = part_demo(&out, &[]);
        std::thread::sleep(full.mul_f64(k as f64 / 4.0));
        signal(&child, "-INT");
        let sent = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            assert!(
                sent.elapsed() < Duration::from_secs(10),
                "still running 10 s after SIGINT"
            );
            std::thread::sleep(Duration::from_millis(10));
        };
        if out.exists() {
            // The run finished before the signal arrived: its output is whole.
            assert!(out.join("summary.json").is_file());
        } else {
            assert_eq!(status.code(), Some(130), "exit code after SIGINT");
        }
        assert_eq!(staging_folders(&base), Vec::<String>::new());
    }
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn the_bar_model_runs_the_whole_bundled_walk() {
    // Every outline of the walk is a rigid bar structure: no pair is lost to a mechanism.
    let base = temp_dir("axial");
    let out = base.join("out");
    let status = demo(&out, &["--element", "axial", "--figures", "none"])
        .wait()
        .unwrap();
    assert!(status.success());
    let pairs = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    let rows: Vec<&str> = pairs.lines().skip(1).collect();
    assert_eq!(rows.len(), 188);
    assert!(rows.iter().all(|r| r.contains(",ok,")), "{pairs}");
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn two_runs_into_one_folder_never_interleave_their_files() {
    let base = temp_dir("concurrent");
    let out = base.join("out");
    // Two different outputs: with figures and without. The folder must end up exactly one of them.
    let with_figures = {
        let o = base.join("with");
        assert!(part_demo(&o, &[]).wait().unwrap().success());
        listing(&o)
    };
    let without = {
        let o = base.join("without");
        assert!(part_demo(&o, &["--figures", "none"])
            .wait()
            .unwrap()
            .success());
        listing(&o)
    };
    assert_ne!(with_figures, without);
    for _ in 0..3 {
        let mut a = part_demo(&out, &[]);
        let mut b = part_demo(&out, &["--figures", "none"]);
        assert!(a.wait().unwrap().success() && b.wait().unwrap().success());
        let got = listing(&out);
        assert!(
            got == with_figures || got == without,
            "mixed output: {got:?}"
        );
        assert_eq!(staging_folders(&base), Vec::<String>::new());
    }
    std::fs::remove_dir_all(&base).unwrap();
}

/// A reader that stops early (`pedomatch inspect … | head -1`) closes the pipe before pedomatch
/// writes: each subcommand then ends quietly with success, its outputs whole, instead of
/// panicking with exit code 101.
#[test]
fn a_reader_that_has_gone_ends_the_output_quietly() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let cost = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/cost.csv");
    let out = temp_dir("closed-reader");
    let out_s = out.to_str().unwrap();
    let commands: [&[&str]; 4] = [
        &["inspect", data],
        &["assign", cost, "--json"],
        &[
            "match",
            data,
            data,
            "--frame",
            "40",
            "--frame-b",
            "41",
            "--json",
            "--figures",
            "none",
            "--report",
            "none",
        ],
        &[
            "run",
            data,
            "--frames",
            "40..45",
            "--out",
            out_s,
            "--figures",
            "none",
            "--report",
            "none",
            "--json",
        ],
    ];
    for args in commands {
        let mut child = Command::new(env!("CARGO_BIN_EXE_pedomatch"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start pedomatch");
        drop(child.stdout.take()); // the reader is gone before anything is written
        let o = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(o.status.code(), Some(0), "{args:?}: {stderr}");
    }
    assert!(out.join("summary.json").is_file() && out.join("tracks.csv").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

// ---------------------------------------------------------------------------------------------
// Hostile inputs: small files that claim huge recordings, expand a thousandfold or nest without
// end are a one-line error (exit 1), never an abort (134) or a panic (101), within a memory
// and time budget measured on the process.

use std::io::{Read as _, Write as _};

/// What a run of `pedomatch` gave: its exit code, standard error, peak resident memory and time.
struct Bounded {
    code: Option<i32>,
    stderr: String,
    peak_kb: i64,
    took: Duration,
    /// User and system CPU time.
    cpu: Duration,
}

/// The address space a run may take (`prlimit --as`, when the tool is there): a failed
/// allocation beyond it would abort the process, which the exit code then shows.
const ADDRESS_SPACE: u64 = 2 << 30;

/// Runs `pedomatch args`, bounded as [`ADDRESS_SPACE`] says, and measures it (wait4's rusage).
// The child is reaped by `wait4`, which gives its rusage, not by `Child::wait`.
#[allow(clippy::zombie_processes)]
fn bounded(args: &[&std::ffi::OsStr]) -> Bounded {
    let bin = env!("CARGO_BIN_EXE_pedomatch");
    let prlimit = Command::new("prlimit").arg("--version").output().is_ok();
    let mut command = match prlimit {
        true => {
            let mut c = Command::new("prlimit");
            c.arg(format!("--as={ADDRESS_SPACE}")).arg(bin);
            c
        }
        false => Command::new(bin),
    };
    let start = Instant::now();
    let mut child = command
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pedomatch");
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    // SAFETY: `rusage` is plain integers, for which all zeros is a value.
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    // SAFETY: `child` is this process's child, not yet waited for (its `Child` is never waited
    // on after this), and `status` and `usage` are valid for writes.
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t, "wait4");
    let code = libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status));
    Bounded {
        code,
        stderr,
        peak_kb: usage.ru_maxrss,
        took: start.elapsed(),
        cpu: [usage.ru_utime, usage.ru_stime]
            .iter()
            .map(|t| Duration::from_secs(t.tv_sec as u64) + Duration::from_micros(t.tv_usec as u64))
            .sum(),
    }
}

/// Checks that `pedomatch run FILE` refuses `file` with one line naming it and saying `says`,
/// within 512 MB and 10 s.
fn refused(file: &Path, says: &str) {
    let out = temp_dir("hostile-out").join("run");
    let r = bounded(&[
        "run".as_ref(),
        file.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    let name = file.display().to_string();
    eprintln!(
        "{name}: exit {:?}, peak {} MB, {:.2?} ({:.2?} CPU): {}",
        r.code,
        r.peak_kb / 1024,
        r.took,
        r.cpu,
        r.stderr.trim_end()
    );
    assert_eq!(r.code, Some(1), "{name}: {}", r.stderr);
    let line = format!("pedomatch: error: {name}");
    assert!(
        r.stderr.starts_with(&line) && r.stderr.contains(says),
        "{}",
        r.stderr
    );
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    assert!(r.peak_kb <= 512 << 10, "{name}: peak {} kB", r.peak_kb);
    assert!(r.took <= Duration::from_secs(10), "{name}: {:?}", r.took);
    assert!(r.cpu <= Duration::from_secs(10), "{name}: {:?} CPU", r.cpu);
    assert!(!out.exists(), "no output for a refused recording");
}

/// A PNG of `side` × `side` 8-bit zeros, compressed as it is written.
fn png_of_zeros(side: u32) -> Vec<u8> {
    let chunk = |out: &mut Vec<u8>, kind: &[u8], data: &[u8]| {
        let mut crc = flate2::Crc::new();
        crc.update(kind);
        crc.update(data);
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        out.extend_from_slice(&crc.sum().to_be_bytes());
    };
    let mut header = [side.to_be_bytes(), side.to_be_bytes()].concat();
    header.extend_from_slice(&[8, 0, 0, 0, 0]);
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    let row = vec![0u8; side as usize + 1];
    for _ in 0..side {
        z.write_all(&row).unwrap();
    }
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    chunk(&mut png, b"IHDR", &header);
    chunk(&mut png, b"IDAT", &z.finish().unwrap());
    chunk(&mut png, b"IEND", &[]);
    png
}

const ZEBRIS_HEAD: &[u8] = b"<measurement><cell_count><x>256</x><y>256</y></cell_count>\
    <movements><movement><clips><clip><cell_size><x>8.467</x><y>8.467</y></cell_size>\
    <frequency>100</frequency><data>";
const ZEBRIS_TAIL: &[u8] = b"</data></clip></clips></movement></movements></measurement>";

#[test]
fn hostile_files_are_one_line_errors_within_memory_and_time() {
    let dir = temp_dir("hostile");
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    // 11.9 KB: 10⁶ empty frames on a 256 × 256 plate (262 GB as dense frames).
    let xml = gzip([(ZEBRIS_HEAD, 1), (b"<quant/>", 1_000_000), (ZEBRIS_TAIL, 1)]);
    let says = "values a recording may hold";
    refused(&write("million.xml.gz", &xml), says);
    // 550 bytes: 32,768 empty frames of 256 × 256, every value a recording may hold (2³¹),
    // and 13 KB: as many frames each loading one sensel. Made frame by frame, their objects
    // and measures took 13.5 s and 20 s of CPU; now they cost what they hold.
    let empty = gzip([(ZEBRIS_HEAD, 1), (b"<quant/>", 32_768), (ZEBRIS_TAIL, 1)]);
    refused(&write("wait.xml.gz", &empty), "no object to match");
    let dot = b"<quant><cell_begin><x>5</x><y>7</y></cell_begin><cell_count><x>1</x><y>1</y>\
        </cell_count><cells>100</cells></quant>";
    let dots = gzip([(ZEBRIS_HEAD, 1), (dot, 32_768), (ZEBRIS_TAIL, 1)]);
    refused(&write("dots.xml.gz", &dots), "no object to match");
    // Nested 10⁶ deep: minutes of quadratic work before.
    let deep = gzip([(ZEBRIS_HEAD, 1), (b"<a>", 1_000_000), (b"</a>", 1_000_000)]);
    refused(&write("deep.xml.gz", &deep), "nested elements");
    // A 57 KB emed .lst asking 30 GB.
    let page = b"Page 1\nMatrix: 10000x10000\n\t1\tForce\n1\t0\t0\nForce\t0\n\x0c";
    let lst = gzip([(page as &[u8], 75), (b"\n", 60_000_000)]);
    refused(&write("walk.lst.gz", &lst), "sensors a frame may have");
    // A 261 KB PNG of 16384² zeros, which aborted in marching squares.
    refused(
        &write("zeros.png", &png_of_zeros(16384)),
        "an image of 16384 x 16384",
    );
    // A 1 GiB one-line CSV (a sparse file: its head is values, the rest a hole).
    let csv = dir.join("line.csv");
    let mut f = std::fs::File::create(&csv).unwrap();
    f.write_all(&b"0,".repeat(8192)).unwrap();
    f.set_len(1 << 30).unwrap();
    drop(f);
    refused(&csv, "a line longer than");
    // A gzipped JSON of 2 × 10⁷ samples.
    let head = b"{\"cell_count\": {\"x\": 256, \"y\": 256}, \"samples\": [";
    let json = gzip([(head as &[u8], 1), (b"{},", 20_000_000), (b"{}]}", 1)]);
    refused(&write("walk.json.gz", &json), says);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_small_file_of_many_frames_holding_little_runs_within_memory_and_time() {
    // 13 KB: 32,768 frames of 256 × 256 (every value a recording may hold), four of them a
    // loaded 12 × 12 patch, the rest one loaded sensel. Every model's run succeeds; frame by
    // frame it took 2.2 s (contour), 5.5 s (isocontour) and 26 s (surface) of CPU.
    let dir = temp_dir("sparse-frames");
    let patch = format!(
        "<quant><cell_begin><x>100</x><y>100</y></cell_begin><cell_count><x>12</x><y>12</y>\
         </cell_count><cells>{}</cells></quant>",
        "100 ".repeat(144)
    );
    let dot = b"<quant><cell_begin><x>5</x><y>7</y></cell_begin><cell_count><x>1</x><y>1</y>\
        </cell_count><cells>100</cells></quant>";
    let xml = gzip([
        (ZEBRIS_HEAD, 1),
        (patch.as_bytes(), 4),
        (dot, 32_764),
        (ZEBRIS_TAIL, 1),
    ]);
    let file = dir.join("patches.xml.gz");
    std::fs::write(&file, xml).unwrap();
    for model in ["contour", "surface", "isocontour"] {
        let out = dir.join(model);
        let r = bounded(&[
            "run".as_ref(),
            file.as_os_str(),
            "--model".as_ref(),
            model.as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ]);
        eprintln!("{model}: peak {} MB, {:.2?} CPU", r.peak_kb / 1024, r.cpu);
        assert_eq!(r.code, Some(0), "{model}: {}", r.stderr);
        assert!(r.peak_kb <= 512 << 10, "{model}: peak {} kB", r.peak_kb);
        assert!(r.cpu <= Duration::from_secs(10), "{model}: {:?} CPU", r.cpu);
        let frames = std::fs::read_to_string(out.join("frames.csv")).unwrap();
        assert_eq!(frames.lines().count(), 32_768 + 1, "{model}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_batch_with_a_hostile_file_beside_good_ones_has_one_error_row() {
    let dir = temp_dir("hostile-batch");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/pedo-io/tests/data");
    let inputs = dir.join("inputs");
    std::fs::create_dir_all(&inputs).unwrap();
    std::fs::copy(data.join("emed-test-1-10.lst"), inputs.join("a.lst")).unwrap();
    let xml = gzip([(ZEBRIS_HEAD, 1), (b"<quant/>", 1_000_000), (ZEBRIS_TAIL, 1)]);
    std::fs::write(inputs.join("b.xml.gz"), xml).unwrap();
    std::fs::copy(data.join("emed-test-1-10.lst"), inputs.join("c.lst")).unwrap();
    let study = dir.join("study");
    let r = bounded(&[
        "batch".as_ref(),
        inputs.as_os_str(),
        "--out".as_ref(),
        study.as_os_str(),
        "--figures".as_ref(),
        "none".as_ref(),
        "--report".as_ref(),
        "none".as_ref(),
    ]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(r.peak_kb <= 512 << 10, "peak {} kB", r.peak_kb);
    let table = std::fs::read_to_string(study.join("study.csv")).unwrap();
    let statuses: Vec<&str> = table
        .lines()
        .skip(1)
        .map(|l| if l.contains(",error,") { "error" } else { "ok" })
        .collect();
    assert_eq!(statuses, ["ok", "error", "ok"], "{table}");
    assert!(table.contains("values a recording may hold"), "{table}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn names_reach_the_terminal_with_their_control_characters_escaped() {
    let dir = temp_dir("names");
    let name = dir.join("\u{1b}[31mred\u{1b}]0;title\u{7}.asf");
    std::fs::write(&name, b"not a recording").unwrap();
    let out = dir.join("out");
    let r = bounded(&[
        "run".as_ref(),
        name.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(!r.stderr.contains(['\u{1b}', '\u{7}']), "{:?}", r.stderr);
    assert!(
        r.stderr.contains("\\u{1b}[31mred\\u{1b}]0;title\\u{7}.asf"),
        "{}",
        r.stderr
    );
    // A batch's error lines too.
    let study = dir.join("study");
    let r = bounded(&[
        "batch".as_ref(),
        dir.as_os_str(),
        "--out".as_ref(),
        study.as_os_str(),
    ]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(!r.stderr.contains(['\u{1b}', '\u{7}']), "{:?}", r.stderr);
    assert!(r.stderr.contains("\\u{1b}[31mred"), "{}", r.stderr);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_unit_a_spreadsheet_would_run_is_text_in_the_study_table() {
    let dir = temp_dir("formula");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/pedo-io/tests/data");
    let asf = std::fs::read_to_string(data.join("tekscan-FrasP01L-11-20.csv")).unwrap();
    let units = "=HYPERLINK(\"http://example.com\",\"x\")";
    let file = dir.join("walk.csv");
    std::fs::write(&file, asf.replace("UNITS KPa", &format!("UNITS {units}"))).unwrap();
    let study = dir.join("study");
    let r = bounded(&[
        "batch".as_ref(),
        file.as_os_str(),
        "--out".as_ref(),
        study.as_os_str(),
        "--figures".as_ref(),
        "none".as_ref(),
        "--report".as_ref(),
        "none".as_ref(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let table = std::fs::read_to_string(study.join("study.csv")).unwrap();
    assert!(
        table.contains("\"'=HYPERLINK(\"\"http://example.com\"\",\"\"x\"\")\""),
        "{table}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Starts `pedomatch batch inputs --out study` on one thread, without figures or report.
fn batch_into(inputs: &Path, study: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_pedomatch"))
        .arg("batch")
        .arg(inputs)
        .arg("--out")
        .arg(study)
        .args(["--jobs", "1", "--figures", "none", "--report", "none"])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pedomatch")
}

/// The recordings (file names) of a study table's rows: `study.csv`'s and `study.json`'s.
fn study_rows(study: &Path) -> (Vec<String>, Vec<String>) {
    let name = |p: &str| p.rsplit('/').next().unwrap().to_string();
    let mut csv: Vec<String> = std::fs::read_to_string(study.join("study.csv"))
        .unwrap_or_default()
        .lines()
        .skip(1)
        .map(|l| name(l.split(',').next().unwrap()))
        .collect();
    let json: serde_json::Value = std::fs::read(study.join("study.json"))
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok())
        .unwrap_or_default();
    let mut rows: Vec<String> = json["rows"]
        .as_array()
        .map(|rows| {
            rows.iter()
                .map(|r| name(r["path"].as_str().unwrap()))
                .collect()
        })
        .unwrap_or_default();
    csv.sort();
    rows.sort();
    (csv, rows)
}

#[test]
fn killed_batches_never_lose_a_row_of_the_study_table() {
    let base = temp_dir("kill-batch");
    let (inputs, study) = (base.join("in"), base.join("study"));
    std::fs::create_dir_all(&inputs).unwrap();
    let lst =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/pedo-io/tests/data/emed-test-1-10.lst");
    let add = |k: usize| std::fs::copy(&lst, inputs.join(format!("r{k:02}.lst"))).unwrap();
    (0..4).for_each(|k| {
        add(k);
    });
    let full = {
        let t = Instant::now();
        assert!(batch_into(&inputs, &study, &[]).wait().unwrap().success());
        t.elapsed()
    };
    let mut listed = study_rows(&study).0;
    assert_eq!(listed.len(), 4);
    // Ten runs, each with one more recording and every folder written again, killed at
    // moments spread over the run: between any two of its renames, the table keeps every row
    // it had, in both files, and the next run lists them all. (Every state between two renames
    // is checked one by one in the next test; these kills are the check on a live process.)
    const KILLS: usize = 10;
    for k in 1..=KILLS {
        add(3 + k);
        // A run's time grows with its recordings: the kills are spread from 40 % to 120 % of it.
        let expected = full.mul_f64((4 + k) as f64 / 4.0);
        let mut child = batch_into(&inputs, &study, &["--force"]);
        std::thread::sleep(expected.mul_f64(0.4 + 0.8 * k as f64 / KILLS as f64));
        signal(&child, "-KILL");
        child.wait().unwrap();
        let (csv, json) = study_rows(&study);
        eprintln!(
            "kill {k}: {} rows in study.csv, {} in study.json",
            csv.len(),
            json.len()
        );
        for row in &listed {
            assert!(
                csv.contains(row) && json.contains(row),
                "kill {k}: {row} lost: {csv:?} {json:?}"
            );
        }
        listed = csv;
    }
    assert!(batch_into(&inputs, &study, &[]).wait().unwrap().success());
    let (csv, json) = study_rows(&study);
    let all: Vec<String> = (0..4 + KILLS).map(|k| format!("r{k:02}.lst")).collect();
    assert_eq!((&csv, &json), (&all, &all));
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn two_batches_into_one_study_at_once_keep_every_row_or_refuse_the_second() {
    let base = temp_dir("two-batches");
    let lst =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/pedo-io/tests/data/emed-test-1-10.lst");
    for (sub, names) in [("a", ["a1", "a2", "a3"]), ("b", ["b1", "b2", "b3"])] {
        std::fs::create_dir_all(base.join(sub)).unwrap();
        for n in names {
            std::fs::copy(&lst, base.join(sub).join(format!("{n}.lst"))).unwrap();
        }
    }
    for trial in 0..5 {
        let study = base.join(format!("study{trial}"));
        let mut a = batch_into(&base.join("a"), &study, &[]);
        let mut b = batch_into(&base.join("b"), &study, &[]);
        let mut refused = 0;
        let mut ran = Vec::new();
        for (name, child) in [("a", &mut a), ("b", &mut b)] {
            let mut stderr = String::new();
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut stderr)
                .unwrap();
            match child.wait().unwrap().code() {
                Some(0) => ran.push(name),
                Some(1) if stderr.contains("in use by another pedomatch batch") => refused += 1,
                code => panic!("trial {trial}, batch {name}: exit {code:?}: {stderr}"),
            }
        }
        eprintln!("trial {trial}: {ran:?} ran, {refused} refused");
        assert!(refused <= 1 && !ran.is_empty(), "trial {trial}");
        let (csv, json) = study_rows(&study);
        let expected: Vec<String> = ran
            .iter()
            .flat_map(|s| (1..=3).map(move |i| format!("{s}{i}.lst")))
            .collect();
        assert_eq!(
            (&csv, &json),
            (&expected, &expected),
            "trial {trial}: {ran:?} ran"
        );
    }
    std::fs::remove_dir_all(&base).unwrap();
}

fn copy_tree(from: &Path, to: &Path) {
    if from.is_dir() {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap().flatten() {
            copy_tree(&e.path(), &to.join(e.file_name()));
        }
    } else {
        std::fs::copy(from, to).unwrap();
    }
}

#[test]
fn a_batch_killed_between_any_two_renames_loses_no_row_on_the_next_run() {
    // Every state a kill can leave while a run adds a recording and writes every folder again:
    // the study before, with the first j renames of the run done (its recordings' folders in
    // the order they run, then study.json, study.csv, study_curves.csv). From each, the next
    // run's table lists every recording, in both files.
    let base = temp_dir("renames");
    let inputs = base.join("in");
    std::fs::create_dir_all(&inputs).unwrap();
    let lst =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/pedo-io/tests/data/emed-test-1-10.lst");
    for k in 0..3 {
        std::fs::copy(&lst, inputs.join(format!("r{k}.lst"))).unwrap();
    }
    let (before, after) = (base.join("before"), base.join("after"));
    assert!(batch_into(&inputs, &before, &[]).wait().unwrap().success());
    copy_tree(&before, &after);
    std::fs::copy(&lst, inputs.join("r3.lst")).unwrap();
    assert!(batch_into(&inputs, &after, &["--force"])
        .wait()
        .unwrap()
        .success());
    let all: Vec<String> = (0..4).map(|k| format!("r{k}.lst")).collect();
    assert_eq!(study_rows(&after).0, all);
    let mut folders: Vec<String> = std::fs::read_dir(&after)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('r') && n.contains(".lst-"))
        .collect();
    folders.sort();
    assert_eq!(folders.len(), 4);
    let renames: Vec<String> = folders
        .into_iter()
        .chain(["study.json", "study.csv", "study_curves.csv"].map(String::from))
        .filter(|n| after.join(n).exists())
        .collect();
    for j in 0..=renames.len() {
        let state = base.join(format!("state{j}"));
        copy_tree(&before, &state);
        for name in &renames[..j] {
            let _ = std::fs::remove_dir_all(state.join(name))
                .or_else(|_| std::fs::remove_file(state.join(name)));
            copy_tree(&after.join(name), &state.join(name));
        }
        assert!(
            batch_into(&inputs, &state, &[]).wait().unwrap().success(),
            "state {j}"
        );
        let (csv, json) = study_rows(&state);
        assert_eq!(
            (&csv, &json),
            (&all, &all),
            "after the first {j} renames: {:?}",
            &renames[..j]
        );
    }
    std::fs::remove_dir_all(&base).unwrap();
}
