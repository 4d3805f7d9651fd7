//! Property tests: the parsers never panic on arbitrary or mutated bytes, and the geometry
//! never panics on arbitrary frames; and a mutation fuzzer over every reader, seeded with the
//! samples in tests/data, that fails on any panic, hang or outsized allocation.
//!
//! The fuzzer runs `PEDO_FUZZ_EXECS` executions in total (default 20 000, a few seconds), among
//! them size-amplifying mutations (a header's count or dimension multiplied, a block repeated
//! up to 512 kB, the result gzip-compressed); the full campaign, outside CI, is
//! `PEDO_FUZZ_EXECS=1000000 cargo test -p pedo-io --test fuzz mutation_fuzz -- --nocapture`
//! (a debug build, so integer overflows panic too; BENCHMARKS.md has its result).
//! `PEDO_FUZZ_SEED` changes the random sequence.

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

// ---------------------------------------------------------------------------------------------
// Mutation fuzzer.

use pedo_io::sniff_format;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;
use std::time::{Duration, Instant};

/// Records, per thread, the largest single allocation since the last reset, so that a reader
/// trusting a size field ("10⁹ frames") shows up even when the allocation would succeed.
struct LargestAllocation;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: every method forwards to the system allocator with the caller's arguments unchanged,
// so it meets `GlobalAlloc`'s contract exactly as `System` does; `note` only updates a
// thread-local counter (no allocation).
unsafe impl GlobalAlloc for LargestAllocation {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's `alloc` contract, forwarded unchanged.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's `alloc_zeroed` contract, forwarded unchanged.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: `ptr` came from this allocator, i.e. from `System` (the caller's contract).
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from this allocator, i.e. from `System` (the caller's contract).
        unsafe { System.dealloc(ptr, layout) }
    }
}

fn note(size: usize) {
    let _ = LARGEST.try_with(|m| m.set(m.get().max(size)));
}

#[global_allocator]
static ALLOCATOR: LargestAllocation = LargestAllocation;

/// SplitMix64: small, fast and reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens that steer mutations into the readers' structure: markers, sizes, separators.
const TOKENS: &[&[u8]] = &[
    b"\n",
    b"\r\n",
    b"\t",
    b",",
    b";",
    b"=",
    b"-1",
    b"B",
    b"NaN",
    b"0",
    b"@@",
    b"[Data]",
    b"[Data1]",
    b"[Data999999999]",
    b"[Technical]",
    b"SensCountX=",
    b"SensCountY=",
    b"MinIdx=",
    b"MaxIdx=1000000000",
    b"ROWS 100000",
    b"COLS 100000",
    b"END_FRAME ",
    b"ASCII_DATA @@",
    b"Frame ",
    b"Matrix: 10000x10000",
    b"Force",
    b"\x0c",
    b"999999999999",
    b"4294967295",
    b"-9223372036854775808",
    b"1e308",
    b"\xff\xff\xff\xff",
    b"\0\0\0\0",
    b"PK\x01\x02",
    b"PK\x05\x06",
    b"(1000000000, 1000, 1000)",
    b"'shape': (",
];

/// The longest input an amplifying mutation makes: a few hundred kB keeps an execution within
/// milliseconds while a header claiming 10⁶ times the data present is still tried.
const AMPLIFIED_MAX: usize = 512 << 10;

/// Size-amplifying mutations: a number of the input (a header's count, a dimension, a length)
/// multiplied, or a block of it repeated many times, as a hostile file claims or holds far more
/// than its seed.
fn amplify(rng: &mut Rng, v: &mut Vec<u8>) {
    let n = v.len();
    if n == 0 {
        return;
    }
    if rng.below(2) == 0 {
        // Multiply a run of digits (a count, a dimension, a length) by a large factor.
        let i = rng.below(n);
        if let Some(s) = (i..n).find(|&k| v[k].is_ascii_digit()) {
            let e = (s..n).find(|&k| !v[k].is_ascii_digit()).unwrap_or(n);
            let number: u128 = std::str::from_utf8(&v[s..e.min(s + 30)])
                .ok()
                .and_then(|t| t.parse().ok())
                .unwrap_or(1);
            let factor: u128 = [10, 256, 1000, 1 << 16, 1 << 20, 1_000_000_007][rng.below(6)];
            let text = number.max(1).saturating_mul(factor).to_string();
            v.splice(s..e, text.bytes());
        }
        return;
    }
    // Repeat a block: a frame, a row, a page or a tag copied up to the size limit.
    let i = rng.below(n);
    let len = 1 + rng.below((n - i).min(4096));
    let block = v[i..i + len].to_vec();
    let times = 1 + rng.below(AMPLIFIED_MAX / len).min(1 << 14);
    let at = i + len;
    let repeated: Vec<u8> = block
        .iter()
        .copied()
        .cycle()
        .take((times * len).min(AMPLIFIED_MAX.saturating_sub(n)))
        .collect();
    v.splice(at..at, repeated);
}

/// The input gzip-compressed: a text reader's input inflates to many times its size on disk.
fn gzipped(v: &[u8]) -> Vec<u8> {
    use std::io::Write as _;
    let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(v).unwrap();
    z.finish().unwrap()
}

fn mutate_once(rng: &mut Rng, v: &mut Vec<u8>, seeds: &[(String, Format, Vec<u8>)]) {
    let n = v.len();
    match rng.below(10) {
        9 => amplify(rng, v),
        0 if n > 0 => {
            let i = rng.below(n);
            v[i] ^= 1 << rng.below(8);
        }
        1 if n > 0 => {
            let i = rng.below(n);
            v[i] = rng.next() as u8;
        }
        2 => {
            let t = TOKENS[rng.below(TOKENS.len())];
            let i = rng.below(n + 1);
            v.splice(i..i, t.iter().copied());
        }
        3 if n > 0 => {
            let i = rng.below(n);
            let len = 1 + rng.below((n - i).min(64));
            v.drain(i..i + len);
        }
        4 if n > 0 => {
            let i = rng.below(n);
            let len = 1 + rng.below((n - i).min(256));
            let chunk: Vec<u8> = v[i..i + len].to_vec();
            let j = rng.below(n + 1);
            v.splice(j..j, chunk);
        }
        5 => v.truncate(rng.below(n + 1)),
        6 if n > 0 => {
            // Replace a run of digits by a huge or degenerate number.
            let i = rng.below(n);
            if let Some(s) = (i..n).find(|&k| v[k].is_ascii_digit()) {
                let e = (s..n).find(|&k| !v[k].is_ascii_digit()).unwrap_or(n);
                let t: &[u8] =
                    [&b"0"[..], b"1000000000", b"99999999999999999999", b"-1"][rng.below(4)];
                v.splice(s..e, t.iter().copied());
            }
        }
        7 => {
            // Splice in a slice of another seed.
            let other = &seeds[rng.below(seeds.len())].2;
            if !other.is_empty() {
                let i = rng.below(other.len());
                let len = 1 + rng.below((other.len() - i).min(512));
                let j = rng.below(n + 1);
                v.splice(j..j, other[i..i + len].iter().copied());
            }
        }
        _ if n > 0 => {
            // Overwrite 2, 4 or 8 bytes with an extreme integer (binary size fields).
            let w = [2usize, 4, 8][rng.below(3)];
            let i = rng.below(n);
            let val: u64 = [0, u64::MAX, 0xFFFF_FFFF, 1 << 31, rng.next()][rng.below(5)];
            for (k, b) in val.to_le_bytes().iter().take(w).enumerate() {
                if let Some(x) = v.get_mut(i + k) {
                    *x = *b;
                }
            }
        }
        _ => v.extend_from_slice(TOKENS[rng.below(TOKENS.len())]),
    }
}

/// Short, complete excerpts of every sample (each execution stays fast), with their format.
fn fuzz_seeds() -> Vec<(String, Format, Vec<u8>)> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/");
    let read = |n: &str| std::fs::read(format!("{dir}{n}")).unwrap();
    let text = |n: &str| String::from_utf8_lossy(&read(n)).into_owned();
    let tekscan = text("tekscan-FrasP01L-11-20.csv");
    let tekscan = tekscan[..tekscan.find("Frame 14").unwrap()]
        .replace("END_FRAME 20", "END_FRAME 13")
        .into_bytes();
    let footscan = text("footscan-FrasP01L-11-20.txt");
    let footscan = footscan[..footscan.find("[Data3]").unwrap()]
        .replace("MaxIdx=10", "MaxIdx=2")
        .into_bytes();
    // Short excerpts of the real pedar, I-Scan and emed exports (headers stating the counts).
    let pedar = text("pedar-example-3.01-4.00.asc");
    let cut = pedar.find("     3.05000").unwrap();
    let pedar = pedar[..cut]
        .replace("total time [secs]:   1.000", "total time [secs]:   0.040")
        .into_bytes();
    let iscan = text("iscan-test-1-20.csv");
    let iscan = format!("{}@@\n", &iscan[..iscan.find("Frame 3,").unwrap()])
        .replace("END_FRAME 20", "END_FRAME 2")
        .into_bytes();
    let emed = read("emed-test-1-10.lst");
    let second = emed.iter().position(|&b| b == 0x0c).unwrap();
    let emed = emed[..second].to_vec();
    let small = pedo_io::Recording::new(2, 3, 4, (0..24).map(|v| v as f32).collect(), {
        let mut m = vec![true; 12];
        m[5] = false;
        m
    })
    .unwrap();
    let png = pedo_io::formats::images::frame_to_png16(&small, 0, 1.0).unwrap();
    // The first six frames of the Zebris XML sample (four unloaded, two windows).
    let zebris = text("zebris-FrasP01L-26-55.xml");
    let keep = zebris.match_indices("<quant").nth(6).unwrap().0;
    let zebris_xml = format!(
        "{}</data></clip></clips></movement></movements></measurement>\n",
        zebris[..keep].trim_end()
    )
    .replace("<count>30</count>", "<count>6</count>")
    .into_bytes();
    let zebris_json = br#"{"cell_count": {"x": 4, "y": 3}, "cell_size": {"x": 8.5, "y": 8.5},
        "frequency": 100, "pressure_unit": "N/cm2", "sample_count": 2, "begin": 0.0,
        "samples": [{"origin": {"x": null, "y": null}, "size": {"x": 0, "y": 0}, "pressure": []},
        {"origin": {"x": 1, "y": 0}, "size": {"x": 2, "y": 2}, "pressure": [1, 2.5, 3, 4]}]}"#
        .to_vec();
    let seeds = vec![
        ("FrasP01L.asf", Format::Asf, sample("FrasP01L.asf").to_vec()),
        (
            "synthetic-walk.lst",
            Format::Lst,
            sample("synthetic-walk.lst").to_vec(),
        ),
        ("MUN104L.csv", Format::Csv, read("MUN104L.csv")),
        ("MDwalk2.apd", Format::Zebris, read("MDwalk2.apd")),
        ("footscan excerpt", Format::Footscan, footscan),
        ("tekscan csv excerpt", Format::TekscanCsv, tekscan),
        ("small.npy", Format::Npy, npy::recording_to_npy(&small)),
        (
            "numpy stored .npz",
            Format::Npz,
            read("numpy-MUN104L-stored.npz"),
        ),
        (
            "numpy deflated .npz",
            Format::Npz,
            read("numpy-MUN104L-deflated.npz"),
        ),
        ("small.png", Format::Png, png),
        ("pedar excerpt", Format::Pedar, pedar),
        ("iscan excerpt", Format::Asf, iscan),
        ("real emed excerpt", Format::Lst, emed),
        ("zebris xml excerpt", Format::ZebrisXml, zebris_xml),
        ("zebris json excerpt", Format::ZebrisJson, zebris_json),
    ];
    seeds
        .into_iter()
        .map(|(n, f, b)| (n.to_string(), f, b))
        .collect()
}

/// Runs one input through the seed's reader and through whatever the sniffer picks; returns
/// the largest single allocation made.
fn execute(input: &[u8], format: Format) -> usize {
    LARGEST.with(|m| m.set(0));
    if let Ok(r) = parse_bytes(input, format, "fuzz") {
        assert_eq!(r.data().len(), r.n_frames() * r.rows() * r.cols());
    }
    if let Ok(f) = sniff_format(Path::new("fuzz"), input)
        && f != format
    {
        let _ = parse_bytes(input, f, "fuzz");
    }
    LARGEST.with(|m| m.get())
}

#[test]
fn mutation_fuzz_every_reader() {
    let execs: usize = std::env::var("PEDO_FUZZ_EXECS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    let seed: u64 = std::env::var("PEDO_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x5EED);
    let seeds = fuzz_seeds();
    for (name, f, b) in &seeds {
        assert!(parse_bytes(b, *f, name).is_ok(), "seed {name} must parse");
    }
    let mut rng = Rng(seed);
    let mut per_reader = vec![0usize; seeds.len()];
    let (mut slowest, mut largest) = (Duration::ZERO, 0usize);
    let start = Instant::now();
    for i in 0..execs {
        let k = i % seeds.len();
        let (name, format, base) = &seeds[k];
        let mut input = base.clone();
        for _ in 0..1 + rng.below(8) {
            mutate_once(&mut rng, &mut input, &seeds);
        }
        // One input in eight is amplified once more and one in sixteen of those compressed,
        // so that every run tries claims and bodies far beyond the seeds'.
        let mut inflated = input.len();
        if rng.below(8) == 0 {
            amplify(&mut rng, &mut input);
            inflated = input.len();
            if rng.below(16) == 0 {
                input = gzipped(&input);
            }
        }
        let t = Instant::now();
        let outcome = std::panic::catch_unwind(|| execute(&input, *format));
        let took = t.elapsed();
        let keep = || {
            let p = std::env::temp_dir().join(format!("pedo-fuzz-crash-{i}.bin"));
            std::fs::write(&p, &input).unwrap();
            p.display().to_string()
        };
        let big = match outcome {
            Ok(b) => b,
            Err(_) => panic!(
                "execution {i} (seed {name}) panicked; input kept in {}",
                keep()
            ),
        };
        // Every input is at most a few hundred kB: a reader allocating more than 16 MiB plus
        // 512 bytes per input byte trusted a size field it should have capped.
        let cap = (16 << 20) + 512 * inflated.max(input.len());
        assert!(
            big <= cap,
            "execution {i} (seed {name}) allocated {big} bytes at once; input kept in {}",
            keep()
        );
        assert!(
            took < Duration::from_secs(5),
            "execution {i} (seed {name}) took {took:?}; input kept in {}",
            keep()
        );
        per_reader[k] += 1;
        slowest = slowest.max(took);
        largest = largest.max(big);
    }
    eprintln!(
        "mutation fuzz: {execs} executions in {:.1} s, zero panics; slowest {:.1} ms, largest \
         allocation {} kB; per seed: {}",
        start.elapsed().as_secs_f64(),
        slowest.as_secs_f64() * 1e3,
        largest / 1024,
        seeds
            .iter()
            .zip(&per_reader)
            .map(|((n, ..), c)| format!("{n} {c}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
}
