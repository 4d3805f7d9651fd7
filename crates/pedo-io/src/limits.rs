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

/// A frame of `rows` × `cols` sensors within [`MAX_FRAME_SENSORS`]: its number of sensors, or
/// what is wrong (`what` names the claim: `"ROWS x COLS"`, `"Matrix"`, `"an image"`).
pub fn frame_sensors(what: &str, rows: usize, cols: usize) -> std::result::Result<usize, String> {
    match rows.checked_mul(cols) {
        Some(per) if per <= MAX_FRAME_SENSORS => Ok(per),
        _ => Err(format!(
            "{what} of {rows} x {cols} sensors is more than the {MAX_FRAME_SENSORS} sensors a \
             frame may have"
        )),
    }
}

/// Whether a recording may hold `n_frames` frames of `per` sensors ([`MAX_FRAMES`],
/// [`MAX_RECORDING_VALUES`]); `Err` says why not.
pub fn frame_count(n_frames: usize, per: usize) -> std::result::Result<(), String> {
    if n_frames > MAX_FRAMES {
        return Err(format!(
            "{n_frames} frames are more than the {MAX_FRAMES} a recording may have"
        ));
    }
    if n_frames
        .checked_mul(per)
        .is_none_or(|n| n > MAX_RECORDING_VALUES)
    {
        return Err(format!(
            "{n_frames} frames of {per} sensors are more than the {MAX_RECORDING_VALUES} values \
             a recording may hold"
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
