//! The limits every reader checks before it allocates.
//!
//! What a file claims (its frames, the sensors of a frame, what it decompresses to) is checked
//! against the bytes actually present and against these limits before anything of that size is
//! allocated, so that no file, however small or hostile, makes a reader abort, hang or take
//! memory out of proportion to what a real export of its size takes: frames are held sparsely
//! (only their values that are not 0), compressed files are read as a stream, and a refusal is an
//! [`IoError`] naming the file and the claim. Each limit is far above the largest real export.

use crate::error::{IoError, Result};

/// Sensors of one frame (rows × columns): 1,048,576, a 1024 × 1024 grid. The largest plates hold
/// tens of thousands (emed-xl 25,344 sensors, Zebris platforms about 12,000, a Tekscan walkway of
/// several tiles some 10⁴–10⁵); a frame's contours and surfaces are computed on the whole grid.
pub const MAX_FRAME_SENSORS: usize = 1 << 20;

/// Frames of one recording: 16,777,216 (46 hours at 100 Hz, 6 hours at 750 Hz, the fastest
/// insole systems).
pub const MAX_FRAMES: usize = 1 << 24;

/// Values of one recording, frames × sensors per frame: 2³¹ (2.1 × 10⁹). An hour of a Tekscan
/// insole at 100 Hz holds 4.5 × 10⁸, a minute of a walkway of 30,000 sensors 1.8 × 10⁸; every
/// frame of a run is visited whole, so the limit also bounds a run's time.
pub const MAX_RECORDING_VALUES: usize = 1 << 31;

/// Bytes a gzip-compressed recording (or a deflated `.npz` member) may expand to: 1 GiB. The
/// largest compressed exports, TRIPOD's Zebris JSON of a treadmill walk, expand to a few hundred
/// MB; what is decompressed is parsed as it comes, never held whole.
pub const MAX_DECOMPRESSED: u64 = 1 << 30;

/// The longest stretch of a text export a reader holds at once: a line of a text format, the
/// text between two XML tags, JSON between two quotes: 16 MiB. A real export's longest line (a
/// frame's row of a large plate, a Zebris frame's `<cells>`) takes well under 1 MB.
pub const MAX_TOKEN_BYTES: usize = 16 << 20;

/// Bytes of frame values a read may hold whatever its file's size: 256 MiB. A read may also hold
/// [`HELD_PER_FILE_BYTE`] bytes of values per byte of its file, so that a real export of any
/// size reads, while a small file that expands to dense values (a gzip of a million frames of
/// ones) is refused long before it takes the memory its frames would.
pub const MAX_HELD_BYTES: u64 = 256 << 20;

/// Bytes of frame values a read may hold per byte of its file on disk: 128. A text export holds
/// 1–3 bytes of values per byte of text; its gzip is 6–25 times smaller than the text (the
/// exports of the test data), so a real compressed export holds at most ~75 per byte.
pub const HELD_PER_FILE_BYTE: u64 = 128;

/// The limits a read is held to: the constants above by default, raised (or lowered) by the
/// reading options (`ReadOptions`: `--max-frames`, Python `max_frames=`, ...) for a file a user
/// knows to be larger than any export they were sized for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Sensors of one frame ([`MAX_FRAME_SENSORS`]).
    pub frame_sensors: usize,
    /// Frames of one recording ([`MAX_FRAMES`]).
    pub frames: usize,
    /// Values of one recording ([`MAX_RECORDING_VALUES`]).
    pub values: usize,
    /// Bytes a compressed recording may expand to ([`MAX_DECOMPRESSED`]).
    pub decompressed: u64,
    /// The longest stretch of text held at once ([`MAX_TOKEN_BYTES`]).
    pub text: usize,
    /// Bytes of frame values a read may hold beyond [`HELD_PER_FILE_BYTE`] per byte of its
    /// file ([`MAX_HELD_BYTES`]).
    pub held: u64,
}

impl Limits {
    /// The documented limits, the constants of this module.
    pub const DEFAULT: Limits = Limits {
        frame_sensors: MAX_FRAME_SENSORS,
        frames: MAX_FRAMES,
        values: MAX_RECORDING_VALUES,
        decompressed: MAX_DECOMPRESSED,
        text: MAX_TOKEN_BYTES,
        held: MAX_HELD_BYTES,
    };

    /// Runs `f` with these limits as the readers' on this thread, the previous ones restored
    /// afterwards (also when `f` unwinds). A scope rather than an argument of every reader: the
    /// checks sit deep in each format's parser, and a read never leaves its thread (a streamed
    /// file's second pass sets the limits of its own thread).
    pub fn apply<T>(self, f: impl FnOnce() -> T) -> T {
        struct Restore(Limits);
        impl Drop for Restore {
            fn drop(&mut self) {
                CURRENT.with(|c| c.set(self.0));
            }
        }
        let _restore = Restore(CURRENT.with(|c| c.replace(self)));
        f()
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

thread_local! {
    static CURRENT: std::cell::Cell<Limits> = const { std::cell::Cell::new(Limits::DEFAULT) };
    /// The size on disk of the file being read on this thread; `None` outside a read.
    static FILE_BYTES: std::cell::Cell<Option<u64>> = const { std::cell::Cell::new(None) };
    /// The bytes of values the frames being read on this thread hold so far.
    static HELD: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Runs `f`, a read of a file (or folder of files) of `bytes` bytes on disk, the values its
/// frames may hold sized by it ([`Limits::held`]); the previous size restored afterwards.
pub(crate) fn reading<T>(bytes: u64, f: impl FnOnce() -> T) -> T {
    struct Restore(Option<u64>, u64);
    impl Drop for Restore {
        fn drop(&mut self) {
            FILE_BYTES.with(|c| c.set(self.0));
            HELD.with(|c| c.set(self.1));
        }
    }
    let _restore = Restore(
        FILE_BYTES.with(|c| c.replace(Some(bytes))),
        HELD.with(|c| c.replace(0)),
    );
    f()
}

/// Records that the frames being read hold `bytes` bytes of values (a reader's store, after
/// each frame); 0 when the store is handed on or dropped.
pub(crate) fn holding(bytes: usize) {
    if FILE_BYTES.with(|c| c.get()).is_some() {
        HELD.with(|c| c.set(bytes as u64));
    }
}

/// Whether the read may hold `more` bytes of values besides the frames it holds (data that
/// must be held whole, as a Fortran-ordered array's); `Err` says why not.
pub(crate) fn may_hold(more: u64) -> std::result::Result<(), String> {
    over_budget(&current(), more).map_or(Ok(()), |(held, over)| {
        Err(format!("its values would take {held} MiB, {over}"))
    })
}

/// When the frames held and `more` bytes pass the read's budget ([`held_budget`]): the MiB
/// they take and the end of the refusal that says so (the budget, the file's size, the option).
fn over_budget(limits: &Limits, more: u64) -> Option<(u64, String)> {
    let budget = held_budget(limits);
    let held = HELD.with(|c| c.get()).saturating_add(more);
    if held <= budget {
        return None;
    }
    let file = FILE_BYTES.with(|c| c.get()).unwrap_or(0);
    let over = format!(
        "more than the {} MiB a file of {file} bytes may expand to; {}",
        budget >> 20,
        raise("max_memory_mb")
    );
    Some((held.div_ceil(1 << 20), over))
}

/// The bytes of values the frames read may hold: [`Limits::held`], or [`HELD_PER_FILE_BYTE`]
/// per byte of the file being read when that is more.
fn held_budget(limits: &Limits) -> u64 {
    let file = FILE_BYTES.with(|c| c.get()).unwrap_or(0);
    limits.held.max(file.saturating_mul(HELD_PER_FILE_BYTE))
}

/// The limits of a read on this thread: [`Limits::DEFAULT`] unless a [`Limits::apply`] holds.
pub fn current() -> Limits {
    CURRENT.with(|c| c.get())
}

/// How a refusal says to raise the limit it hit: the option of the reading options that sets it.
pub fn raise(option: &str) -> String {
    format!(
        "raise it with --{} (Python {option}=) if the file is genuine",
        option.replace('_', "-")
    )
}

/// A frame of `rows` × `cols` sensors within [`Limits::frame_sensors`]: its number of sensors,
/// or what is wrong (`what` names the claim: `"ROWS x COLS"`, `"Matrix"`, `"an image"`).
pub fn frame_sensors(what: &str, rows: usize, cols: usize) -> std::result::Result<usize, String> {
    let most = current().frame_sensors;
    match rows.checked_mul(cols) {
        Some(per) if per <= most => Ok(per),
        _ => Err(format!(
            "{what} of {rows} x {cols} sensors is more than the {most} sensors a frame may have; \
             {}",
            raise("max_frame_sensors")
        )),
    }
}

/// Whether a recording may hold `n_frames` frames of `per` sensors ([`Limits::frames`],
/// [`Limits::values`]); `Err` says why not.
pub fn frame_count(n_frames: usize, per: usize) -> std::result::Result<(), String> {
    let limits = current();
    if n_frames > limits.frames {
        return Err(format!(
            "{n_frames} frames are more than the {} a recording may have; {}",
            limits.frames,
            raise("max_frames")
        ));
    }
    if let Some((held, over)) = over_budget(&limits, 0) {
        let read = n_frames.saturating_sub(1);
        return Err(format!(
            "its first {read} frames hold {held} MiB of values, {over}"
        ));
    }
    if n_frames.checked_mul(per).is_none_or(|n| n > limits.values) {
        return Err(format!(
            "{n_frames} frames of {per} sensors are more than the {} values a recording may \
             hold; {}",
            limits.values,
            raise("max_values")
        ));
    }
    Ok(())
}

/// [`frame_sensors`] as a reader's error about the file `name`.
pub(crate) fn check_frame(name: &str, what: &str, rows: usize, cols: usize) -> Result<usize> {
    frame_sensors(what, rows, cols).map_err(|msg| IoError::format(name, msg))
}

/// [`frame_count`] as a reader's error about the file `name`: a reader asks before it adds a
/// frame (`n_frames` counting it).
pub(crate) fn check_frames(name: &str, n_frames: usize, per: usize) -> Result<()> {
    frame_count(n_frames, per).map_err(|msg| IoError::format(name, msg))
}

/// An empty vector with room for `n` elements, or `None` when the memory cannot be had: an
/// allocation whose size comes from a file must be an error, never an abort.
pub(crate) fn try_with_capacity<T>(n: usize) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok()?;
    Some(v)
}

/// `n` copies of `value`, allocated as [`try_with_capacity`] does.
pub(crate) fn try_filled<T: Clone>(n: usize, value: T) -> Option<Vec<T>> {
    let mut v = try_with_capacity(n)?;
    v.resize(n, value);
    Some(v)
}
