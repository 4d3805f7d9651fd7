//! Hostile inputs, generated here (nothing large is committed): small files that claim huge
//! recordings, expand a thousandfold, nest without end or hold one endless line. Each is a typed
//! error naming the file (or a correct recording), within a memory and time budget measured
//! here: the most memory the reading thread held at once (a counting allocator) and its time.

use flate2::write::{GzEncoder, ZlibEncoder};
use flate2::Compression;
#[path = "common/gzip.rs"]
mod gzip_stream;
use gzip_stream::gzip;
use pedo_io::formats::ReadOptions;
use pedo_io::{parse_bytes, read_recording, Format, IoError, Recording};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

/// Counts, per thread, the bytes held and the most held at once (the test harness runs tests
/// on threads of their own, and the readers read on the caller's thread).
struct Counting;

thread_local! {
    static HELD: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn count(delta: isize) {
    let _ = HELD.try_with(|h| {
        h.set(h.get() + delta);
        let _ = PEAK.try_with(|p| p.set(p.get().max(h.get())));
    });
}

// SAFETY: every method forwards to the system allocator with the caller's arguments unchanged,
// so it meets `GlobalAlloc`'s contract exactly as `System` does; `count` only updates
// thread-local counters (no allocation).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's `alloc` contract, forwarded unchanged.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            count(layout.size() as isize);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's `alloc_zeroed` contract, forwarded unchanged.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            count(layout.size() as isize);
        }
        p
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: `ptr` came from this allocator, i.e. from `System` (the caller's contract).
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            count(new_size as isize - layout.size() as isize);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator, i.e. from `System` (the caller's contract).
        unsafe { System.dealloc(ptr, layout) };
        count(-(layout.size() as isize));
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The most memory a reader of a hostile input may hold at once.
const BUDGET: usize = 64 << 20;
/// The most CPU time it may take: a guard against a reader that hangs or goes quadratic on
/// hostile input, not a speed target (reading speed is measured in `benches/io.rs`). CPU time of
/// the process, not wall time, so that a loaded machine never fails it (a 1 GiB decompression
/// took 90 s of wall time with other builds and tests running); generous, as the test binary's
/// other tests run beside it.
const TIME: Duration = Duration::from_secs(60);

/// The process's CPU time so far.
fn cpu_time() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime");
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// Runs `read`; returns what it gave, the most bytes it held at once and the CPU time it took.
fn measured<T>(read: impl FnOnce() -> T) -> (T, usize, Duration) {
    let base = HELD.with(Cell::get);
    PEAK.with(|p| p.set(base));
    let start = cpu_time();
    let out = read();
    let took = cpu_time().saturating_sub(start);
    (out, (PEAK.with(Cell::get) - base).max(0) as usize, took)
}

/// Checks that `read` fails with an error of `kind` naming `name` and saying `says`, within the
/// budget.
fn refused(
    case: &str,
    name: &str,
    says: &str,
    kind: fn(&IoError) -> bool,
    read: impl FnOnce() -> pedo_io::Result<Recording>,
) {
    let (out, peak, took) = measured(read);
    let e = match out {
        Ok(r) => panic!("{case}: read as {} frames", r.n_frames()),
        Err(e) => e,
    };
    let msg = e.to_string();
    eprintln!("{case}: {msg:.160} (peak {} kB, {took:.2?})", peak / 1024);
    assert!(kind(&e), "{case}: {e:?}");
    assert!(msg.starts_with(name) && msg.contains(says), "{case}: {msg}");
    assert!(!msg.contains('\n'), "{case}: one line: {msg}");
    assert!(peak <= BUDGET, "{case}: held {peak} bytes at once");
    assert!(took <= TIME, "{case}: took {took:?}");
}

fn format_error(e: &IoError) -> bool {
    matches!(e, IoError::Format { .. })
}

fn parse_error(e: &IoError) -> bool {
    matches!(e, IoError::Parse { .. })
}

fn once(s: &str) -> (Vec<u8>, usize) {
    (s.as_bytes().to_vec(), 1)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pedo-io-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

const ZEBRIS_HEAD: &str = "<measurement><cell_count><x>256</x><y>256</y></cell_count><movements>\
    <movement><clips><clip><cell_size><x>8.467</x><y>8.467</y></cell_size>\
    <frequency>100</frequency><units>N/cm2</units><data>";
const ZEBRIS_TAIL: &str = "</data></clip></clips></movement></movements></measurement>";

#[test]
fn a_zebris_xml_of_a_million_empty_frames_on_a_large_plate() {
    // 11.9 KB: 10⁶ `<quant/>` on 256 × 256 sensors, 262 GB as dense frames.
    let gz = gzip([
        once(ZEBRIS_HEAD),
        (b"<quant/>".to_vec(), 1_000_000),
        once(ZEBRIS_TAIL),
    ]);
    assert!(gz.len() < 16 << 10, "{}", gz.len());
    let says = "values a recording may hold";
    refused("xml", "z.xml.gz", says, format_error, || {
        parse_bytes(&gz, Format::ZebrisXml, "z.xml.gz")
    });
    // As many empty frames as a recording may hold on the plate read as such, sparsely.
    let frames = (1usize << 31) / (256 * 256);
    let gz = gzip([
        once(ZEBRIS_HEAD),
        (b"<quant/>".to_vec(), frames),
        once(ZEBRIS_TAIL),
    ]);
    let (rec, peak, _) = measured(|| parse_bytes(&gz, Format::ZebrisXml, "z.xml.gz"));
    assert_eq!(rec.unwrap().n_frames(), frames);
    assert!(peak <= BUDGET, "held {peak} bytes");
}

#[test]
fn a_zebris_xml_nested_a_million_deep_is_read_in_linear_time() {
    let open = "<measurement><cell_count><x>4</x><y>3</y></cell_count>";
    let gz = gzip([
        once(open),
        (b"<a>".to_vec(), 1_000_000),
        (b"</a>".to_vec(), 1_000_000),
        once("</measurement>"),
    ]);
    assert!(gz.len() < 16 << 10, "{}", gz.len());
    refused(
        "deep",
        "d.xml",
        "more than 256 nested elements",
        parse_error,
        || parse_bytes(&gz, Format::ZebrisXml, "d.xml"),
    );
    // Nesting within the limit, closed or cut: read at once; the error of a cut file names the
    // open elements, not all of them.
    let nested = |closed: bool| {
        let close = match closed {
            true => "</a>".repeat(200) + "</measurement>",
            false => String::new(),
        };
        gzip([once(open), (b"<a>".to_vec(), 200), once(&close)])
    };
    refused("nested", "d.xml", "no pressure clip", format_error, || {
        parse_bytes(&nested(true), Format::ZebrisXml, "d.xml")
    });
    refused("cut", "d.xml", "(201 elements)", parse_error, || {
        parse_bytes(&nested(false), Format::ZebrisXml, "d.xml")
    });
}

#[test]
fn an_emed_lst_claiming_gigabytes() {
    let page = |k: usize, matrix: &str| {
        format!(
            "Page {k}\nMatrix: {matrix}\nSensor area: 0.25 cm2\nTime/picture: 10 ms\n\
             \t1\tForce\n1\t0\t0\nForce\t0\n\x0c"
        )
    };
    // 57 KB: 75 pages of a 10000 x 10000 matrix, 30 GB as dense frames.
    let mut parts: Vec<(Vec<u8>, usize)> = Vec::new();
    for k in 1..=75 {
        parts.push(once(&page(k, "10000x10000")));
        parts.push((b"\n".to_vec(), 800_000));
    }
    let gz = gzip(parts);
    refused(
        "lst matrix",
        "e.lst",
        "sensors a frame may have",
        parse_error,
        || parse_bytes(&gz, Format::Lst, "e.lst"),
    );
    // A matrix a frame may have, on more pages than a recording may hold.
    let text: String = (1..=3000).map(|k| page(k, "1000x1000")).collect();
    let gz = gzip([(text.into_bytes(), 1)]);
    let says = "values a recording may hold";
    refused("lst pages", "e.lst", says, format_error, || {
        parse_bytes(&gz, Format::Lst, "e.lst")
    });
}

/// A PNG of `side` × `side` 8-bit zeros, compressed as it is written (never held whole).
fn png_of_zeros(side: u32) -> Vec<u8> {
    let chunk = |out: &mut Vec<u8>, kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut crc = crc32fast::Hasher::new();
        crc.update(kind);
        crc.update(data);
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        out.extend_from_slice(&crc.finalize().to_be_bytes());
    };
    let mut header = side.to_be_bytes().to_vec();
    header.extend_from_slice(&side.to_be_bytes());
    header.extend_from_slice(&[8, 0, 0, 0, 0]);
    let mut z = ZlibEncoder::new(Vec::new(), Compression::best());
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

#[test]
fn a_png_of_16384_squared_zeros() {
    // 261 KB that decodes to 268 MB of pixels and asked marching squares for 4.3 GB.
    let png = png_of_zeros(16384);
    assert!(png.len() < 300 << 10, "{}", png.len());
    let says = "an image of 16384 x 16384 sensors is more than the 1048576 sensors";
    refused("png", "p.png", says, format_error, || {
        parse_bytes(&png, Format::Png, "p.png")
    });
    // The largest image a frame may be reads, its zeros held sparsely.
    let png = png_of_zeros(1024);
    let (rec, peak, _) = measured(|| parse_bytes(&png, Format::Png, "p.png"));
    let rec = rec.unwrap();
    assert_eq!((rec.rows(), rec.cols()), (1024, 1024));
    assert!(rec.is_sparse() && peak <= BUDGET, "held {peak} bytes");
}

#[test]
fn a_one_line_csv_of_a_gigabyte() {
    // 1 GiB on disk (sparse: a real head, then a hole read as NULs), and 17 MiB of real values.
    let path = scratch("one-line.csv");
    let mut f = std::fs::File::create(&path).unwrap();
    f.write_all(&b"0,".repeat(8192)).unwrap();
    f.set_len(1 << 30).unwrap();
    drop(f);
    let name = path.display().to_string();
    refused(
        "sparse csv",
        &name,
        "a line longer than",
        format_error,
        || read_recording(&path),
    );
    let real = scratch("one-line-real.csv");
    std::fs::write(&real, b"0,".repeat(17 << 19)).unwrap();
    let name = real.display().to_string();
    refused("csv", &name, "a line longer than", format_error, || {
        read_recording(&real)
    });
    // A grid of more sensors than a frame may have, in short lines.
    let row = format!("{}0\n", "0,".repeat(2047));
    let tall = row.repeat(600);
    refused(
        "csv grid",
        "g.csv",
        "sensors a frame may have",
        parse_error,
        || parse_bytes(tall.as_bytes(), Format::Csv, "g.csv"),
    );
    // A gigabyte of NULs is no text at all, told from its first bytes.
    let nul = scratch("nul.csv");
    std::fs::File::create(&nul)
        .unwrap()
        .set_len(1 << 30)
        .unwrap();
    let (e, peak, _) = measured(|| read_recording(&nul));
    assert!(matches!(e, Err(IoError::UnknownFormat { .. })), "{e:?}");
    assert!(peak <= BUDGET, "held {peak} bytes");
    for p in [path, real, nul] {
        std::fs::remove_file(p).unwrap();
    }
}

#[test]
fn a_zebris_json_of_millions_of_samples() {
    let head =
        "{\"cell_count\": {\"x\": 256, \"y\": 256}, \"cell_size\": {\"x\": 8.5, \"y\": 8.5}, \
                \"frequency\": 100, \"samples\": [";
    // (The reader stops at the limit: 20 million samples show it as well as 700 million.)
    let gz = gzip([once(head), (b"{},".to_vec(), 20_000_000), once("{}]}")]);
    assert!(gz.len() < 2 << 20, "{}", gz.len());
    let says = "values a recording may hold";
    refused("json", "j.json.gz", says, format_error, || {
        parse_bytes(&gz, Format::ZebrisJson, "j.json.gz")
    });
    // Samples before the plate's size are held as their windows only: unloaded ones cost
    // nothing until the plate is known.
    let gz = gzip([
        once("{\"samples\": ["),
        (b"{\"pressure\": []},".to_vec(), 1_000_000),
        once("{}], \"cell_count\": {\"x\": 16, \"y\": 16}}"),
    ]);
    let (rec, peak, _) = measured(|| parse_bytes(&gz, Format::ZebrisJson, "j.json.gz"));
    assert_eq!(rec.unwrap().n_frames(), 1_000_001);
    assert!(peak <= BUDGET, "held {peak} bytes");
    // One endless string.
    let gz = gzip([once("{\"pressure_unit\": \""), (vec![b'a'; 1 << 20], 20)]);
    let says = "JSON between two quotes longer than";
    refused("json string", "j.json.gz", says, format_error, || {
        parse_bytes(&gz, Format::ZebrisJson, "j.json.gz")
    });
}

#[test]
fn a_zebris_json_reads_the_same_whatever_the_order_of_its_fields() {
    let samples = r#""samples": [{}, {"origin": {"x": 1, "y": 0}, "size": {"x": 2, "y": 2},
        "pressure": [1, 2, 3, 4.5], "velocity": 1.1}, null, {"pressure": []}]"#;
    let header = r#""cell_count": {"x": 4, "y": 3}, "cell_size": {"x": 8.5, "y": 8.5},
        "frequency": 100, "pressure_unit": "N/cm2", "sample_count": 4"#;
    let first = parse_bytes(
        format!("{{{header}, {samples}}}").as_bytes(),
        Format::ZebrisJson,
        "a",
    )
    .unwrap();
    let last = parse_bytes(
        format!("{{{samples}, {header}}}").as_bytes(),
        Format::ZebrisJson,
        "b",
    )
    .unwrap();
    assert_eq!(first, last);
    assert_eq!((first.n_frames(), first.rows(), first.cols()), (4, 3, 4));
    assert_eq!(first.frame_slice(1).unwrap()[5..7], [3.0, 4.5]);
    assert_eq!(first.units, "N/cm²");
}

#[test]
fn compressed_text_is_parsed_as_it_is_decompressed() {
    // 45 good lines of a grid, a bad one, then 100 MB more: the error at line 46, at once.
    let gz = gzip([
        (b"0,0,0,0,0\n".to_vec(), 45),
        once("0,0,x,0,0\n"),
        (b"0,0,0,0,0\n".to_vec(), 10_000_000),
    ]);
    assert!(gz.len() < 2 << 20, "{}", gz.len());
    refused(
        "line 46",
        "g.csv.gz",
        "g.csv.gz:46: value 3",
        parse_error,
        || parse_bytes(&gz, Format::Csv, "g.csv.gz"),
    );
    // More than a compressed recording may expand to.
    let blank = [b"\n".to_vec(), vec![b' '; 4095]].concat();
    let mut gz = GzEncoder::new(Vec::new(), Compression::fast());
    gz.write_all(b"Page 1\n").unwrap();
    for _ in 0..(1 << 30) / 4096 + 1 {
        gz.write_all(&blank).unwrap();
    }
    let gz = gz.finish().unwrap();
    refused(
        "cap",
        "b.lst.gz",
        "decompresses to more than",
        format_error,
        || parse_bytes(&gz, Format::Lst, "b.lst.gz"),
    );
}

/// A `.npz` holding one deflated member `frames.npy` of shape `(t, r, c)`, `|u1` zeros.
fn npz_of_zeros(t: usize, r: usize, c: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '|u1', 'fortran_order': False, 'shape': ({t}, {r}, {c}), }}");
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    npy.extend_from_slice(&(dict.len() as u16 + 1).to_le_bytes());
    npy.extend_from_slice(dict.as_bytes());
    npy.push(b'\n');
    let body = t * r * c;
    let mut crc = crc32fast::Hasher::new();
    crc.update(&npy);
    let mut z = flate2::write::DeflateEncoder::new(Vec::new(), Compression::best());
    z.write_all(&npy).unwrap();
    let zeros = vec![0u8; 1 << 20];
    for k in (0..body).step_by(zeros.len()) {
        let n = zeros.len().min(body - k);
        z.write_all(&zeros[..n]).unwrap();
        crc.update(&zeros[..n]);
    }
    let data = z.finish().unwrap();
    let (crc, size, name) = (crc.finalize(), (npy.len() + body) as u32, b"frames.npy");
    let mut zip = Vec::new();
    let header = |sig: &[u8], central: bool| {
        let mut h = sig.to_vec();
        if central {
            h.extend_from_slice(&20u16.to_le_bytes());
        }
        for v in [20u16, 0, 8, 0, 0] {
            h.extend_from_slice(&v.to_le_bytes());
        }
        for v in [crc, data.len() as u32, size] {
            h.extend_from_slice(&v.to_le_bytes());
        }
        h.extend_from_slice(&(name.len() as u16).to_le_bytes());
        h.extend_from_slice(&0u16.to_le_bytes());
        if central {
            h.extend_from_slice(&[0; 14]);
        }
        h.extend_from_slice(name);
        h
    };
    zip.extend(header(b"PK\x03\x04", false));
    zip.extend_from_slice(&data);
    let dir_at = zip.len() as u32;
    let central = header(b"PK\x01\x02", true);
    zip.extend_from_slice(&central);
    zip.extend_from_slice(b"PK\x05\x06\0\0\0\0\x01\0\x01\0");
    zip.extend_from_slice(&(central.len() as u32).to_le_bytes());
    zip.extend_from_slice(&dir_at.to_le_bytes());
    zip.extend_from_slice(&0u16.to_le_bytes());
    zip
}

#[test]
fn an_honest_npz_of_zeros_reads_without_its_data_held() {
    // 100 MB of frames in about 100 KB: read, each frame held sparsely as it is inflated.
    let z = npz_of_zeros(100, 1000, 1000);
    assert!(z.len() < 1 << 20, "{}", z.len());
    let (rec, peak, took) = measured(|| parse_bytes(&z, Format::Npz, "z.npz"));
    let rec = rec.unwrap();
    eprintln!("npz: read, peak {} kB, {took:.2?}", peak / 1024);
    assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (100, 1000, 1000));
    assert!(
        rec.is_sparse() && peak <= BUDGET && took <= TIME,
        "held {peak} bytes"
    );
    // The same archive read from a file.
    let path = scratch("z.npz");
    std::fs::write(&path, &z).unwrap();
    let opts = ReadOptions::default();
    let from_file = pedo_io::read_recording_with(&path, &opts).unwrap();
    assert_eq!(from_file, rec);
    std::fs::remove_file(path).unwrap();
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/")).join(name)
}

#[test]
fn every_limit_is_an_option_and_its_refusal_says_how_to_raise_it() {
    // The bundled walk has 205 frames of 60 x 21 sensors: each limit set just below what it
    // holds refuses it, naming the option; the default reads it.
    let walk = data("FrasP01L.asf");
    assert_eq!(read_recording(&walk).unwrap().n_frames(), 205);
    let d = ReadOptions::default();
    let cases = [
        (
            "--max-frames (Python max_frames=)",
            ReadOptions {
                max_frames: 204,
                ..d.clone()
            },
        ),
        (
            "--max-frame-sensors",
            ReadOptions {
                max_frame_sensors: 60 * 21 - 1,
                ..d.clone()
            },
        ),
        (
            "--max-values",
            ReadOptions {
                max_values: 205 * 60 * 21 - 1,
                ..d.clone()
            },
        ),
    ];
    let name = walk.display().to_string();
    let typed = |e: &IoError| format_error(e) || parse_error(e);
    for (says, opts) in cases {
        refused(says, &name, says, typed, || {
            pedo_io::read_recording_with(&walk, &opts)
        });
        // The limit holds for the read only: the default reads the file again.
        assert_eq!(read_recording(&walk).unwrap().n_frames(), 205);
    }
    // A limit below 1 is refused as an option; a line longer than 1 MiB under a 1 MiB limit.
    assert!(ReadOptions {
        max_text_mb: 0,
        ..d.clone()
    }
    .validate()
    .is_err());
    let long = scratch("long-line.csv");
    std::fs::write(&long, "1,".repeat(600_000) + "1\n").unwrap();
    let opts = ReadOptions {
        max_text_mb: 1,
        ..d.clone()
    };
    let name = long.display().to_string();
    refused("line", &name, "--max-text-mb", typed, || {
        pedo_io::read_recording_with(&long, &opts)
    });
    assert!(read_recording(&long).is_ok());
    // A compressed recording's expansion: 2 MiB of text refused under a 1 MiB limit, read
    // whole under the default.
    let row = "0,".repeat(20) + "0\n";
    let gz = gzip([(row.into_bytes(), 50_000)]);
    let opts = ReadOptions {
        max_decompressed_mb: 1,
        ..ReadOptions::default()
    };
    refused(
        "gzip",
        "g.csv.gz",
        "--max-decompressed-mb",
        format_error,
        || pedo_io::formats::parse_bytes_with(&gz, Format::Csv, "g.csv.gz", &opts),
    );
    // Raised, a limit lets a file through that the default refuses: 300,000 sensors of one
    // frame in a 2.1 MB CSV grid within a 200,000-sensor limit, then within 400,000.
    let grid = ("1 ".repeat(999) + "1\n").repeat(300);
    let tight = ReadOptions {
        max_frame_sensors: 200_000,
        ..ReadOptions::default()
    };
    refused("grid", "grid.csv", "--max-frame-sensors", typed, || {
        pedo_io::formats::parse_bytes_with(grid.as_bytes(), Format::Csv, "grid.csv", &tight)
    });
    let roomy = ReadOptions {
        max_frame_sensors: 400_000,
        ..ReadOptions::default()
    };
    let rec = pedo_io::formats::parse_bytes_with(grid.as_bytes(), Format::Csv, "grid.csv", &roomy);
    assert_eq!(rec.unwrap().n_sensors(), 300_000);
}

#[test]
fn a_small_file_of_dense_frames_is_held_to_its_size() {
    // 200 frames of a 256 x 256 plate, every sensel loaded, in a gzip of about 100 KB: 79 MB of
    // values held. Under a 16 MiB floor they are refused at the frame that passes it, naming
    // the option; under the default (256 MiB, or 128 bytes per byte of the file) they read.
    let quant = format!(
        "<quant><cell_begin><x>0</x><y>0</y></cell_begin><cell_count><x>256</x><y>256</y>\
         </cell_count><cells>{}</cells></quant>",
        "1 ".repeat(65536)
    );
    let gz = gzip([
        once(ZEBRIS_HEAD),
        (quant.clone().into_bytes(), 200),
        once(ZEBRIS_TAIL),
    ]);
    assert!(gz.len() < 200 << 10, "{}", gz.len());
    let tight = ReadOptions {
        max_memory_mb: 16,
        ..ReadOptions::default()
    };
    let says = "more than the 16 MiB a file of";
    let (e, peak, _) =
        measured(|| pedo_io::formats::parse_bytes_with(&gz, Format::ZebrisXml, "d.xml.gz", &tight));
    let e = e.unwrap_err().to_string();
    assert!(e.contains(says) && e.contains("--max-memory-mb"), "{e}");
    assert!(peak <= 64 << 20, "held {peak} bytes");
    let rec = pedo_io::formats::parse_bytes(&gz, Format::ZebrisXml, "d.xml.gz").unwrap();
    assert_eq!((rec.n_frames(), rec.n_sensors()), (200, 65536));
    // The floor is a floor: the same frames as plain text (26 MB) read under it, their
    // budget 128 bytes per byte of the file.
    let plain = [ZEBRIS_HEAD, &quant.repeat(200), ZEBRIS_TAIL].concat();
    let rec =
        pedo_io::formats::parse_bytes_with(plain.as_bytes(), Format::ZebrisXml, "p.xml", &tight);
    assert_eq!(rec.unwrap().n_frames(), 200);
}

#[test]
fn an_xml_comment_or_cdata_section_is_bounded_whatever_bytes_it_holds() {
    // 24 MiB between `<!--` and `-->`, with a `<` and a `>` every few bytes (which end a
    // stretch of text, not a comment), and the same in a CDATA section.
    let head = "<measurement><cell_count><x>4</x><y>3</y></cell_count>";
    for (open, close) in [("<!--", "-->"), ("<a><![CDATA[", "]]></a>")] {
        let gz = gzip([
            once(head),
            once(open),
            (b"<a> b ".to_vec(), 4 << 20),
            once(close),
            once("</measurement>"),
        ]);
        assert!(gz.len() < 1 << 20, "{}", gz.len());
        refused(open, "c.xml", "--max-text-mb", format_error, || {
            parse_bytes(&gz, Format::ZebrisXml, "c.xml")
        });
    }
}

#[test]
fn a_json_string_of_escaped_quotes_is_bounded() {
    // 20 MiB of `\"` inside one string: every other byte a quote, none of them its end.
    let gz = gzip([
        once(r#"{"cell_count": {"x": 4, "y": 3}, "note": ""#),
        (br#"\""#.to_vec(), 10 << 20),
        once(r#""}"#),
    ]);
    refused("escaped", "e.json", "--max-text-mb", format_error, || {
        parse_bytes(&gz, Format::ZebrisJson, "e.json")
    });
}

#[test]
fn a_fifo_or_a_device_is_refused_at_once() {
    let fifo = scratch("named.fifo");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    let mut paths = vec![PathBuf::from("/dev/zero")];
    if made.is_ok_and(|s| s.success()) {
        paths.push(fifo);
    }
    for path in paths {
        // Opening a FIFO for reading waits for a writer: read on a thread, with a deadline.
        let (send, got) = std::sync::mpsc::channel();
        let p = path.clone();
        std::thread::spawn(move || drop(send.send(read_recording(&p).map(|r| r.n_frames()))));
        let out = got.recv_timeout(Duration::from_secs(20));
        let e = out.unwrap_or_else(|_| panic!("{}: no answer in 20 s", path.display()));
        let msg = e.unwrap_err().to_string();
        assert!(msg.contains("not a regular file"), "{msg}");
    }
}

#[test]
fn the_recorded_hash_is_of_the_bytes_parsed_and_a_second_reading_must_agree() {
    use sha2::Digest as _;
    let walk = std::fs::read(data("FrasP01L.asf")).unwrap();
    let want: String = sha2::Sha256::digest(&walk)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let path = scratch("rewritten.asf");
    std::fs::write(&path, &walk).unwrap();
    let opts = ReadOptions::default();
    let (_, sha) = pedo_io::formats::read_hashed(&path, &opts).unwrap();
    assert_eq!(sha.as_deref(), Some(want.as_str()));
    // Streamed: read once, then rewritten to the same size and modification time (one digit
    // of a frame changed) before the frames are read again. The last window fails.
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    assert_eq!(read.sha256.as_deref(), Some(want.as_str()));
    let mut frames = read.frames.expect("a Tekscan file streams");
    let mtime = std::fs::metadata(&path).unwrap().modified().unwrap();
    let text = String::from_utf8_lossy(&walk).into_owned();
    let frame = text.find("Frame 100").unwrap();
    let at = frame + text[frame..].find(",1").unwrap() + 1;
    // Written in place (no moment of a truncated file), one byte, the time set back.
    use std::os::unix::fs::FileExt as _;
    let file = std::fs::File::options().write(true).open(&path).unwrap();
    file.write_at(b"2", at as u64).unwrap();
    file.set_modified(mtime).unwrap();
    drop(file);
    assert_eq!(std::fs::metadata(&path).unwrap().modified().unwrap(), mtime);
    let n = read.recording.n_frames();
    use pedo_io::FrameSource as _;
    let first = frames.window(&read.recording, 0, 64);
    assert!(first.is_ok());
    let last = frames
        .window(&read.recording, 64, n)
        .unwrap_err()
        .to_string();
    assert!(last.contains("changed while it was being read"), "{last}");
    // Unchanged, the same streamed read goes through.
    std::fs::write(&path, &walk).unwrap();
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    let mut frames = read.frames.unwrap();
    assert!(frames.window(&read.recording, 0, n).is_ok());
}

#[test]
fn upsampling_a_large_frame_is_checked_before_it_is_allocated() {
    use pedo_io::preprocess::{upsample, Interpolation};
    // 1024 x 1024 by 64: 4.3 × 10⁹ samples, 34 GB. Refused at once; 4-fold goes through.
    let g = pedo_io::Grid::new(1024, 1024, vec![0.0; 1 << 20]).unwrap();
    let (out, peak, took) = measured(|| upsample(&g, 64, Interpolation::Bilinear));
    let msg = out.unwrap_err().to_string();
    assert!(msg.contains("use a smaller factor"), "{msg}");
    assert!(peak <= BUDGET && took <= TIME, "{peak} bytes, {took:?}");
    let small = pedo_io::Grid::new(64, 64, vec![1.0; 64 * 64]).unwrap();
    let up = upsample(&small, 4, Interpolation::Bilinear).unwrap();
    assert_eq!((up.rows(), up.cols()), (253, 253));
}

/// Writes `byte` at `at` in the file at `path` in place, its modification time set back.
fn rewrite_in_place(path: &std::path::Path, at: u64, byte: u8) {
    use std::os::unix::fs::FileExt as _;
    let mtime = std::fs::metadata(path).unwrap().modified().unwrap();
    let file = std::fs::File::options().write(true).open(path).unwrap();
    file.write_at(&[byte], at).unwrap();
    file.set_modified(mtime).unwrap();
}

#[test]
fn a_run_of_the_first_frames_still_checks_the_whole_files_digest() {
    use pedo_io::FrameSource as _;
    let opts = ReadOptions::default();
    // A Tekscan file changed after frame 100 (same size and time): a run of frames 0..64 asks
    // for none of it, and still fails when it finishes; unchanged, it finishes.
    let walk = std::fs::read(data("FrasP01L.asf")).unwrap();
    let path = scratch("first-frames.asf");
    std::fs::write(&path, &walk).unwrap();
    let text = String::from_utf8_lossy(&walk).into_owned();
    let frame = text.find("Frame 100").unwrap();
    let at = frame + text[frame..].find(",1").unwrap() + 1;
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    let mut frames = read.frames.expect("a Tekscan file streams");
    rewrite_in_place(&path, at as u64, b'2');
    assert!(frames.window(&read.recording, 0, 64).is_ok());
    let e = frames.finish(&read.recording).unwrap_err().to_string();
    assert!(e.contains("changed while it was being read"), "{e}");
    std::fs::write(&path, &walk).unwrap();
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    let mut frames = read.frames.unwrap();
    assert!(frames.window(&read.recording, 0, 64).is_ok());
    assert!(frames.finish(&read.recording).is_ok());
    // A .npy array, read at offsets: one value changed in place after the first reading.
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (130, 4, 5), }";
    let pad = 64 - (10 + dict.len() + 1) % 64;
    let header = format!("{dict}{}\n", " ".repeat(pad));
    npy.extend_from_slice(&(header.len() as u16).to_le_bytes());
    npy.extend_from_slice(header.as_bytes());
    let body = npy.len();
    for k in 0..130 * 20 {
        npy.extend_from_slice(&((k % 7) as f32).to_le_bytes());
    }
    let path = scratch("first-frames.npy");
    std::fs::write(&path, &npy).unwrap();
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    let mut frames = read.frames.expect("a .npy array streams");
    rewrite_in_place(&path, (body + 4 * 20 * 120) as u64, 0x40);
    assert!(frames.window(&read.recording, 0, 64).is_ok());
    let e = frames.finish(&read.recording).unwrap_err().to_string();
    assert!(e.contains("changed while it was being read"), "{e}");
    // The same change under a run of every frame: its last window fails.
    std::fs::write(&path, &npy).unwrap();
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    let mut frames = read.frames.unwrap();
    rewrite_in_place(&path, (body + 4 * 20 * 120) as u64, 0x40);
    let e = frames
        .window(&read.recording, 0, 130)
        .unwrap_err()
        .to_string();
    assert!(e.contains("changed while it was being read"), "{e}");
    std::fs::write(&path, &npy).unwrap();
    let read = pedo_io::formats::read_for_run(&path, &opts).unwrap();
    let mut frames = read.frames.unwrap();
    assert!(frames.window(&read.recording, 0, 130).is_ok());
    assert!(frames.finish(&read.recording).is_ok());
}
