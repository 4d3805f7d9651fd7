//! A pressure recording: frames, sensor geometry, timing, units, the no-sensor mask and the
//! measures every plate's software shows.

use crate::error::{IoError, Result};
use crate::grid::Grid;
use std::borrow::Cow;

/// The file format a recording came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Tekscan ASCII movie (`.asf`).
    Asf,
    /// novel emed ASCII page export (`.lst`).
    Lst,
    /// A comma/semicolon/tab/space separated grid (one frame).
    Csv,
    /// NumPy `.npy`, 2-D (one frame) or 3-D (T × rows × cols).
    Npy,
    /// PNG images (8- or 16-bit grayscale).
    Png,
    /// TIFF images (8- or 16-bit grayscale).
    Tiff,
    /// Tekscan CSV export: the `.asf` header and frames with every line padded by commas.
    TekscanCsv,
    /// Zebris FDM "pedcad import file" (`.apd`): `[General]`, `[Technical]`, `[Data]` sections.
    Zebris,
    /// RSscan/Materialise footscan text export: `[Data]` peak image, `[Data<k>]` frames.
    Footscan,
    /// NumPy `.npz`: a zip archive of `.npy` arrays (the first 2-D or 3-D one is read).
    Npz,
    /// novel pedar ASCII export (`.asc`/`.txt`): 99 sensors per insole placed on a layout grid.
    Pedar,
    /// Zebris FDM frame-by-frame raw-data export as XML (`<measurement>`, `<clip>`, `<quant>`
    /// frames with their windows), also gzip-compressed.
    ZebrisXml,
    /// The same export converted to JSON by the public TRIPOD dataset (`zebris_raw.json.gz`).
    ZebrisJson,
}

impl Format {
    /// Every format, in the order the README lists them.
    pub const ALL: [Format; 13] = [
        Format::Asf,
        Format::TekscanCsv,
        Format::Lst,
        Format::Pedar,
        Format::Zebris,
        Format::ZebrisXml,
        Format::ZebrisJson,
        Format::Footscan,
        Format::Csv,
        Format::Npy,
        Format::Npz,
        Format::Png,
        Format::Tiff,
    ];

    /// The format of a [`name`](Self::name), if any.
    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The lower-case name used in messages, tables and `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Asf => "asf",
            Format::Lst => "lst",
            Format::Csv => "csv",
            Format::Npy => "npy",
            Format::Png => "png",
            Format::Tiff => "tiff",
            Format::TekscanCsv => "tekscan-csv",
            Format::Zebris => "zebris",
            Format::Footscan => "footscan",
            Format::Npz => "npz",
            Format::Pedar => "pedar",
            Format::ZebrisXml => "zebris-xml",
            Format::ZebrisJson => "zebris-json",
        }
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How much longer than each of the first two axes the last axis of an array must be for the
/// array to look stored time-last ([`TIME_LAST_RULE`]).
pub const TIME_LAST_RATIO: usize = 3;
/// The shortest last axis of an array that looks stored time-last ([`TIME_LAST_RULE`]).
pub const TIME_LAST_MIN_FRAMES: usize = 64;
/// The longest first and second axes of an array that looks stored time-last: sensor grids
/// ([`TIME_LAST_RULE`]).
pub const TIME_LAST_GRID_MAX: usize = 256;

/// When a 3-D array read as (frames, rows, columns) looks stored time-last, (rows, columns,
/// frames), and is refused unless the time axis is given ([`Recording::looks_time_last`]): a
/// recording's frames outnumber the rows and columns of its sensor, so an array whose last axis
/// is much longer than the first two, and whose first two are the size of a sensor grid, was
/// most likely saved time-last (as MATLAB and many lab scripts store a recording).
pub const TIME_LAST_RULE: &str = "its first two axes are each at most 256 (the size of a sensor \
grid), and its last axis is at least 64 long and at least 3 times as long as each of them";

/// A plantar-pressure recording: `T` frames of `rows × cols` values (`f32`).
///
/// Sensors that do not exist (Tekscan `B`, `-1` or NaN in other exports) are recorded in
/// [`sensor_mask`](Self::sensor_mask) and hold 0 in [`data`](Self::data); they never count in
/// areas or means. Zero pressure on an existing sensor is an ordinary 0 with the mask set.
///
/// Pressure frames are mostly zeros (the foot covers a part of the sensor, and a walk has swing
/// phases with no contact at all), so a recording holds only the values that are not 0 with
/// their positions whenever that takes less memory than every value: about a quarter of the
/// memory for a walk. [`frame`](Self::frame) and [`frame_slice`](Self::frame_slice) give whole
/// frames either way.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    n_frames: usize,
    rows: usize,
    cols: usize,
    frames: Frames,
    sensor_mask: Vec<bool>,
    /// Sensor pitch in mm as `[dx, dy]` = `[column spacing, row spacing]`, when the file says so.
    pub pitch_mm: Option<[f64; 2]>,
    /// Area of one sensor in mm², when known (defaults to `dx * dy`).
    pub sensel_area_mm2: Option<f64>,
    /// Time between frames in seconds, when known.
    pub dt_s: Option<f64>,
    /// Pressure units as written by the file (`"kPa"`, `"N/cm²"`, …); empty when unknown.
    pub units: String,
    /// The noise threshold stated by the file (Tekscan `NOISE_THRESHOLD`), in the file's units.
    pub noise_threshold: Option<f64>,
    /// The format this recording was read from, if it was read from a file.
    pub format: Option<Format>,
    /// The file's values below 0 when the values held are not the file's: set to 0
    /// ([`clip_negatives`](Self::clip_negatives)), or not held (a file read frame by frame by a
    /// run that streams). `None`: they are counted in the frames held.
    file_negatives: Option<NegativeValues>,
    /// Whether values below 0 were set to 0; windows of a file read frame by frame
    /// ([`crate::FrameSource`]) are clipped alike.
    negatives_clipped: bool,
    /// Whether the unit options settled which axis of the array is time (checked, kept or
    /// transposed: [`crate::units::UnitOverrides::apply`]), so that a second application does
    /// not transpose it again.
    time_axis_settled: bool,
    /// The columns of each foot when the frames hold both feet apart (pedar's two insoles, side
    /// by side); empty for a single sensor (a plate), whose feet the file does not tell apart.
    pub feet: Vec<FootColumns>,
}

/// The columns of a recording's frames that one foot's sensor covers (one insole): every sensor
/// of that foot, and no other, lies in them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FootColumns {
    /// Which foot.
    pub side: crate::regions::Side,
    /// Its columns, `start..end`.
    pub columns: std::ops::Range<usize>,
}

impl FootColumns {
    /// Whether `x` (in columns, a sensel's centre at its index) lies on this insole: from the
    /// left edge of its first column (included) to the right edge of its last (excluded).
    pub fn holds(&self, x: f64) -> bool {
        (self.columns.start as f64 - 0.5..self.columns.end as f64 - 0.5).contains(&x)
    }
}

/// The values below 0 at existing sensors of a recording, over every frame: a pressure is not
/// negative, so these are an offset, a baseline subtracted by a device or an export, or noise.
/// Measures count only values above 0 (and at or above the noise threshold), so they never
/// enter an area, a force or a peak; they are reported (`pedomatch inspect`, `summary.json`,
/// Python's `Recording.negative_values`) so that an offset does not pass without a word.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NegativeValues {
    /// How many values are below 0.
    pub count: usize,
    /// The lowest of them, `None` when there are none.
    pub min: Option<f64>,
}

impl NegativeValues {
    /// Counts `v` when it is below 0.
    pub(crate) fn add(&mut self, v: f32) {
        if v < 0.0 {
            self.count += 1;
            let v = f64::from(v);
            self.min = Some(self.min.map_or(v, |m| m.min(v)));
        }
    }
}

/// The per-frame measures of a recording (see [`Recording::measures`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMeasures {
    /// Number of existing sensors in contact: a value above 0 and at or above the contact
    /// threshold (the noise threshold sets values below it to 0, so a value equal to it is a
    /// contact, as in the outlines).
    pub contact_sensors: usize,
    /// Contact area: `contact_sensors × sensel area` in mm², or in sensels when the area is
    /// unknown (for a region that covers sensels in part, the covered shares of its contact
    /// sensors; `contact_sensors` is then their sum rounded).
    pub contact_area: f64,
    /// Total force of the contact sensors in N when units and sensel area are known
    /// ([`Recording::force_factor`]); else their sum times the sensel area in mm² when that is
    /// known, else their plain sum.
    pub total_force: f64,
    /// Largest value at an existing sensor, whether above the threshold or not (0 for an empty
    /// frame; never below 0).
    pub peak_pressure: f64,
    /// Centre of pressure `(x, y)` in pixel coordinates (value-weighted mean of sensel centres);
    /// `None` when nothing is above the threshold.
    pub cop: Option<[f64; 2]>,
}

impl Recording {
    /// Builds a recording from frames (`n_frames × rows × cols`, row-major per frame) and a
    /// sensor mask (`rows × cols`, `true` where a sensor exists). Values at masked-out sensors are
    /// forced to 0. Every value at an existing sensor must be finite. Pitch, frame interval and
    /// units start unknown.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `n_frames`, `rows` or `cols` is 0, when `data` does not
    /// hold `n_frames × rows × cols` values or the mask `rows × cols` entries, or when a value
    /// at an existing sensor is NaN or infinite (the message names its frame, row and column,
    /// 0-based).
    ///
    /// ```
    /// use pedo_io::Recording;
    /// // 2 frames of 2 × 3 sensels; there is no sensor at row 0, column 2.
    /// let mask = vec![true, true, false, true, true, true];
    /// let data = vec![
    ///     0.0, 10.0, 99.0, 0.0, 30.0, 0.0, // frame 0 (the 99 has no sensor: dropped)
    ///     0.0, 0.0, 0.0, 0.0, 0.0, 0.0, // frame 1: no contact
    /// ];
    /// let rec = Recording::new(2, 2, 3, data, mask)?.with_pitch_mm([5.0, 5.0])?;
    /// assert_eq!(rec.frame(0)?.get(0, 2), 0.0);
    /// assert_eq!(rec.n_sensors(), 5);
    /// let m = rec.measures(0.0);
    /// assert_eq!(m[0].contact_sensors, 2);
    /// assert_eq!(m[0].contact_area, 50.0); // mm², 25 mm² per sensel
    /// assert_eq!(m[0].cop, Some([1.0, 0.75])); // (x, y) = (column, row), pressure-weighted
    /// assert_eq!(m[1].cop, None);
    /// # Ok::<(), pedo_io::IoError>(())
    /// ```
    pub fn new(
        n_frames: usize,
        rows: usize,
        cols: usize,
        mut data: Vec<f32>,
        sensor_mask: Vec<bool>,
    ) -> Result<Self> {
        let values = data.iter().copied().enumerate();
        let per = validate(n_frames, rows, cols, data.len(), &sensor_mask, values)?;
        for frame in data.chunks_exact_mut(per) {
            for (v, &exists) in frame.iter_mut().zip(&sensor_mask) {
                if !exists {
                    *v = 0.0;
                }
            }
        }
        Ok(Self::of_frames(
            n_frames,
            rows,
            cols,
            Frames::compact(data, per),
            sensor_mask,
        ))
    }

    /// A recording of checked frames with nothing known yet beyond them (no pitch, time step,
    /// units or feet): what [`Recording::new`] and [`Recording::from_sparse`] return.
    fn of_frames(
        n_frames: usize,
        rows: usize,
        cols: usize,
        frames: Frames,
        sensor_mask: Vec<bool>,
    ) -> Self {
        Self {
            n_frames,
            rows,
            cols,
            frames,
            sensor_mask,
            pitch_mm: None,
            sensel_area_mm2: None,
            dt_s: None,
            units: String::new(),
            noise_threshold: None,
            format: None,
            file_negatives: None,
            negatives_clipped: false,
            time_axis_settled: false,
            feet: Vec::new(),
        }
    }

    /// Builds a recording from frames where NaN marks "no sensor". A sensor is missing when it is
    /// NaN in every frame; NaN in only some frames is an error (a value was lost, not a sensor).
    pub fn from_nan_frames(
        n_frames: usize,
        rows: usize,
        cols: usize,
        data: Vec<f32>,
    ) -> Result<Self> {
        let per = rows.saturating_mul(cols);
        if n_frames.checked_mul(per) != Some(data.len()) || per == 0 {
            return Err(IoError::invalid(format!(
                "{n_frames} frames of {rows}x{cols} do not match {} values",
                data.len()
            )));
        }
        let mut mask = vec![true; per];
        for (i, m) in mask.iter_mut().enumerate() {
            let nans = (0..n_frames).filter(|t| data[t * per + i].is_nan()).count();
            if nans == n_frames {
                *m = false;
            } else if nans > 0 {
                return Err(IoError::invalid(format!(
                    "row {}, column {} is NaN in {nans} of {n_frames} frames only",
                    i / cols,
                    i % cols
                )));
            }
        }
        Self::new(n_frames, rows, cols, data, mask)
    }

    /// Builds a recording from any array (`n_frames × rows × cols`, row-major per frame), the way
    /// arrays from MATLAB, HDF5 or NumPy arrive: NaN marks "no sensor" when `mask` is `None`
    /// (see [`from_nan_frames`](Self::from_nan_frames)); with a mask (`rows × cols`, `true`
    /// where a sensor exists) values at missing sensors are ignored. Set the pitch, frame rate
    /// and units with [`with_pitch_mm`](Self::with_pitch_mm),
    /// [`with_frame_rate`](Self::with_frame_rate) and [`with_units`](Self::with_units).
    pub fn from_array(
        n_frames: usize,
        rows: usize,
        cols: usize,
        data: Vec<f32>,
        mask: Option<Vec<bool>>,
    ) -> Result<Self> {
        match mask {
            Some(mask) => Self::new(n_frames, rows, cols, data, mask),
            None => Self::from_nan_frames(n_frames, rows, cols, data),
        }
    }

    /// Sets the sensor pitch `[dx, dy]` in mm (column spacing, row spacing); both must be
    /// finite and positive. A sensel area the file stated is dropped (it belongs to the file's
    /// pitch): areas and forces then use `dx * dy`.
    pub fn with_pitch_mm(mut self, pitch: [f64; 2]) -> Result<Self> {
        if !pitch.iter().all(|p| p.is_finite() && *p > 0.0) {
            return Err(IoError::invalid(format!(
                "pitch must be finite and positive, got {pitch:?} mm"
            )));
        }
        self.set_pitch_mm(pitch);
        Ok(self)
    }

    /// [`with_pitch_mm`](Self::with_pitch_mm) on a checked pitch.
    pub(crate) fn set_pitch_mm(&mut self, pitch: [f64; 2]) {
        self.pitch_mm = Some(pitch);
        // A stated sensel area belongs to the file's pitch, not to the one given here.
        self.sensel_area_mm2 = None;
    }

    /// Sets the frame rate in Hz (stored as the time between frames); finite and positive.
    pub fn with_frame_rate(mut self, hz: f64) -> Result<Self> {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(IoError::invalid(format!(
                "frame rate must be finite and positive, got {hz} Hz"
            )));
        }
        self.dt_s = Some(1.0 / hz);
        Ok(self)
    }

    /// Sets the pressure units as written (`"kPa"`, `"N/cm2"`, …).
    pub fn with_units(mut self, units: impl Into<String>) -> Self {
        self.units = units.into();
        self
    }

    /// The frame rate in Hz, when the time between frames is known.
    pub fn frame_rate(&self) -> Option<f64> {
        self.dt_s.map(|dt| 1.0 / dt)
    }

    /// Number of frames (at least 1); frames are numbered `0..n_frames()`.
    pub fn n_frames(&self) -> usize {
        self.n_frames
    }
    /// Rows of every frame (the y extent, at least 1).
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// Columns of every frame (the x extent, at least 1).
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// All frames, `n_frames × rows × cols` row-major, 0 at missing sensors (built whole when
    /// the recording is held sparsely: prefer [`frame_slice`](Self::frame_slice) for long ones).
    pub fn data(&self) -> Cow<'_, [f32]> {
        match &self.frames {
            Frames::Dense { values: d, .. } => Cow::Borrowed(d),
            Frames::Sparse(_) => {
                let per = self.rows * self.cols;
                let mut out = vec![0.0f32; self.n_frames * per];
                for (t, frame) in out.chunks_exact_mut(per).enumerate() {
                    self.frames.fill(t, per, frame);
                }
                Cow::Owned(out)
            }
        }
    }
    /// `rows × cols`, `true` where a sensor exists.
    pub fn sensor_mask(&self) -> &[bool] {
        &self.sensor_mask
    }
    /// Number of existing sensors.
    pub fn n_sensors(&self) -> usize {
        self.sensor_mask.iter().filter(|&&m| m).count()
    }

    /// Frame `t` as raw values (0 at missing sensors); `None` past the end.
    pub fn frame_slice(&self, t: usize) -> Option<Cow<'_, [f32]>> {
        let per = self.rows * self.cols;
        (t < self.n_frames).then(|| match &self.frames {
            Frames::Dense { values: d, .. } => Cow::Borrowed(&d[t * per..(t + 1) * per]),
            Frames::Sparse(_) => {
                let mut out = vec![0.0f32; per];
                self.frames.fill(t, per, &mut out);
                Cow::Owned(out)
            }
        })
    }

    /// The values frame `t` holds, when the frames are held sparsely (or frame `t` holds no
    /// value: every value `+0.0`, bit for bit); `None` for a frame held whole, or past the end.
    /// A run takes a sparse frame's measures and values from these, and passes over a frame
    /// holding nothing without making it, so that its cost follows the values a file holds,
    /// not the size its header claims (a small file of many empty frames on a large plate).
    pub fn stored_values(&self, t: usize) -> Option<StoredValues<'_>> {
        let per = self.rows * self.cols;
        if t >= self.n_frames {
            return None;
        }
        match &self.frames {
            Frames::Dense { empty, .. } => empty[t].then_some(StoredValues {
                at: Positions::Narrow(&[]),
                values: &[],
                len: per,
                cols: self.cols,
            }),
            Frames::Sparse(s) => Some(s.stored(t, self.cols)),
        }
    }

    /// Frame `t`'s raw values (0 at missing sensors) written into `out`, whose room is reused
    /// from frame to frame; `None` past the end.
    pub fn frame_into<'a>(&'a self, t: usize, out: &'a mut Vec<f32>) -> Option<&'a [f32]> {
        let per = self.rows * self.cols;
        (t < self.n_frames).then(|| match &self.frames {
            Frames::Dense { values: d, .. } => &d[t * per..(t + 1) * per],
            Frames::Sparse(_) => {
                out.resize(per, 0.0);
                self.frames.fill(t, per, out);
                &out[..]
            }
        })
    }

    /// Frame `t` as a [`Grid`] (missing sensors read as 0, i.e. no contact).
    pub fn frame(&self, t: usize) -> Result<Grid> {
        let s = self.frame_slice(t).ok_or_else(|| {
            IoError::invalid(format!(
                "frame {t} out of range (recording has {})",
                self.n_frames
            ))
        })?;
        Grid::new(self.rows, self.cols, s.iter().map(|&v| v as f64).collect())
    }

    /// Whether the frames are held sparsely (only the values that are not 0), see [`Recording`].
    pub fn is_sparse(&self) -> bool {
        matches!(self.frames, Frames::Sparse(_))
    }

    /// Bytes taken by the frames' values (and, held sparsely, their positions).
    pub fn frames_bytes(&self) -> usize {
        match &self.frames {
            Frames::Dense { values: d, .. } => d.len() * 4,
            Frames::Sparse(s) => s.bytes(),
        }
    }

    /// Frames with NaN at missing sensors (the layout the Python binding exposes).
    pub fn frames_with_nan(&self) -> Vec<f32> {
        let per = self.rows * self.cols;
        let mut out = self.data().into_owned();
        self.mark_missing(&mut out, per);
        out
    }

    /// [`frames_with_nan`](Self::frames_with_nan), or an error when the memory for every value
    /// cannot be had (a recording held sparsely may be far larger dense): never an abort.
    pub fn try_frames_with_nan(&self) -> crate::Result<Vec<f32>> {
        let per = self.rows * self.cols;
        let n = self.n_frames.saturating_mul(per);
        let mut out = crate::limits::try_with_capacity::<f32>(n).ok_or_else(|| {
            IoError::invalid(format!(
                "{} frames of {} x {} values take {} MB as one array, more than can be had; \
                 take a range of frames (frame(t), or --frames for a run)",
                self.n_frames,
                self.rows,
                self.cols,
                n.saturating_mul(4) >> 20
            ))
        })?;
        match &self.frames {
            Frames::Dense { values: d, .. } => out.extend_from_slice(d),
            Frames::Sparse(_) => {
                out.resize(n, 0.0);
                for (t, frame) in out.chunks_exact_mut(per).enumerate() {
                    self.frames.fill(t, per, frame);
                }
            }
        }
        self.mark_missing(&mut out, per);
        Ok(out)
    }

    /// Sets the values of missing sensors of `frames` (frames of `per` values) to NaN.
    fn mark_missing(&self, out: &mut [f32], per: usize) {
        for (i, v) in out.iter_mut().enumerate() {
            if !self.sensor_mask[i % per] {
                *v = f32::NAN;
            }
        }
    }

    /// The values below 0 at existing sensors over every frame, as the file held them (before
    /// [`clip_negatives`](Self::clip_negatives), and for a recording read frame by frame as its
    /// first reading counted them).
    pub fn negative_values(&self) -> NegativeValues {
        if let Some(n) = self.file_negatives {
            return n;
        }
        let mut n = NegativeValues::default();
        // Values at missing sensors are 0.
        match &self.frames {
            Frames::Dense { values: d, .. } => d.iter().for_each(|&v| n.add(v)),
            Frames::Sparse(s) => s.values.iter().for_each(|&v| n.add(v)),
        }
        n
    }

    /// Whether values below 0 were set to 0 ([`clip_negatives`](Self::clip_negatives)).
    pub fn negatives_clipped(&self) -> bool {
        self.negatives_clipped
    }

    /// Sets every value below 0 to 0, remembering how many there were and the lowest
    /// ([`negative_values`](Self::negative_values) still reports the file's).
    pub fn clip_negatives(&mut self) {
        let n = self.negative_values();
        self.file_negatives = Some(n);
        self.negatives_clipped = true;
        if n.count == 0 {
            return;
        }
        let per = self.rows * self.cols;
        let mut data = self.data().into_owned();
        data.iter_mut().filter(|v| **v < 0.0).for_each(|v| *v = 0.0);
        self.frames = Frames::compact(data, per);
    }

    /// Marks the values as clipped to 0 already, the file having held `file` below 0 (a
    /// recording restored from a saved state, whose values were clipped when it was read).
    pub fn mark_negatives_clipped(&mut self, file: NegativeValues) {
        self.file_negatives = Some(file);
        self.negatives_clipped = true;
    }

    /// Records the negative values a first reading of a file counted, for a recording that holds
    /// none of its values (read frame by frame).
    pub(crate) fn set_file_negatives(&mut self, n: NegativeValues) {
        self.file_negatives = Some(n);
    }

    /// Whether the unit options settled which axis is time ([`Self::settle_time_axis`]).
    pub(crate) fn time_axis_settled(&self) -> bool {
        self.time_axis_settled
    }

    /// Marks which axis is time as settled (a recording restored from a saved state, whose
    /// axes were settled when it was first read, or one whose time axis is known).
    pub fn settle_time_axis(&mut self) {
        self.time_axis_settled = true;
    }

    /// Whether this recording reads as an array stored time-last: see
    /// [`TIME_LAST_RULE`]. Only arrays (NumPy files and arrays handed over, whose axes no
    /// header names) are asked.
    pub fn looks_time_last(&self) -> bool {
        let (a, b, c) = (self.n_frames, self.rows, self.cols);
        let array = matches!(self.format, None | Some(Format::Npy) | Some(Format::Npz));
        array
            && (2..=TIME_LAST_GRID_MAX).contains(&a)
            && b <= TIME_LAST_GRID_MAX
            && c >= TIME_LAST_MIN_FRAMES
            && c >= TIME_LAST_RATIO * a.max(b)
    }

    /// This recording's array `(a, b, c)`, read as `a` frames of `b × c`, read instead as an
    /// array stored time-last: `c` frames of `a × b` (frame `k`'s value at row `i`, column `j`
    /// is the value at `[i, j, k]`). A sensor is missing when it is NaN (or missing) in every
    /// frame, as [`Recording::from_nan_frames`] says. Pitch, sensel area and frame interval are
    /// dropped (they belonged to the axes as first read); units, noise threshold and format are
    /// kept.
    ///
    /// ```
    /// use pedo_io::Recording;
    /// // 2 rows x 3 columns x 4 frames, value = 100 i + 10 j + k.
    /// let data: Vec<f32> = (0..24).map(|n| (100 * (n / 12) + 10 * (n / 4 % 3) + n % 4) as f32).collect();
    /// let as_read = Recording::new(2, 3, 4, data, vec![true; 12])?;
    /// let r = as_read.time_last_transposed()?;
    /// assert_eq!((r.n_frames(), r.rows(), r.cols()), (4, 2, 3));
    /// assert_eq!(r.frame(3)?.get(1, 2), 123.0);
    /// # Ok::<(), pedo_io::IoError>(())
    /// ```
    pub fn time_last_transposed(&self) -> Result<Recording> {
        let (a, b, c) = (self.n_frames, self.rows, self.cols);
        let old = self.frames_with_nan();
        let mut data = vec![0.0f32; old.len()];
        for k in 0..c {
            for i in 0..a {
                for j in 0..b {
                    data[(k * a + i) * b + j] = old[(i * b + j) * c + k];
                }
            }
        }
        let mut r = Recording::from_nan_frames(c, a, b, data)?;
        r.units = self.units.clone();
        r.noise_threshold = self.noise_threshold;
        r.format = self.format;
        r.time_axis_settled = true;
        Ok(r)
    }

    /// The pressure units the file states ([`Recording::units`]), `None` when it states none:
    /// the value of `summary.json`'s `pressure_units`, the study table's and Python's
    /// `Recording.units`.
    pub fn known_units(&self) -> Option<&str> {
        Some(self.units.as_str()).filter(|u| !u.is_empty())
    }

    /// Area of one sensor in mm²: the stated area, else the pitch product, else `None`.
    pub fn sensel_area(&self) -> Option<f64> {
        self.sensel_area_mm2.or(self.pitch_mm.map(|p| p[0] * p[1]))
    }

    /// Factor turning `sum(values)` into newtons: `kPa × mm² × 1e-3 = N`, scaled by the units.
    /// `None` when the units or the sensor area are unknown.
    pub fn force_factor(&self) -> Option<f64> {
        let kpa = kpa_per_unit(&self.units)?;
        Some(kpa * self.sensel_area()? * 1e-3)
    }

    /// The peak-pressure image: per sensor the maximum over all frames (`rows × cols`).
    pub fn peak_image(&self) -> Grid {
        let per = self.rows * self.cols;
        let mut out = vec![0.0f64; per];
        let mut frame = vec![0.0f32; per];
        for t in 0..self.n_frames {
            // A sparse frame of positive values raises the peak where it holds values only
            // (the same maxima: its zeros change none).
            if let Some(stored) = self.stored_values(t).filter(StoredValues::all_positive) {
                for (i, v) in stored.iter() {
                    out[i] = out[i].max(v as f64);
                }
                continue;
            }
            self.frames.fill(t, per, &mut frame);
            for (o, &v) in out.iter_mut().zip(&frame) {
                *o = o.max(v as f64);
            }
        }
        // Values are finite by construction, so the grid is valid.
        Grid::new(self.rows, self.cols, out).expect("finite values")
    }

    /// Per-frame measures, counting sensors with a value above 0 and at or above `threshold`
    /// (values below the noise threshold are no contact; use 0 for "any load").
    pub fn measures(&self, threshold: f64) -> Vec<FrameMeasures> {
        self.measures_of(threshold, 0..self.n_frames)
    }

    /// [`measures`](Self::measures) of the frames `frames` (within the recording).
    pub fn measures_of(
        &self,
        threshold: f64,
        frames: std::ops::Range<usize>,
    ) -> Vec<FrameMeasures> {
        let per = self.rows * self.cols;
        let mut f = vec![0.0f32; per];
        (frames.start..frames.end.min(self.n_frames))
            .map(|t| {
                let mut sum = MeasureSum::default();
                if let Some(stored) = self.stored_values(t).filter(StoredValues::all_positive) {
                    // The zeros add nothing (bit for bit), positions come in order.
                    for (i, v) in stored.iter().filter(|&(i, _)| self.sensor_mask[i]) {
                        sum.add(v as f64, i / self.cols, i % self.cols, threshold);
                    }
                    return sum.measures(self);
                }
                self.frames.fill(t, per, &mut f);
                for (i, &v) in f.iter().enumerate() {
                    if self.sensor_mask[i] {
                        sum.add(v as f64, i / self.cols, i % self.cols, threshold);
                    }
                }
                sum.measures(self)
            })
            .collect()
    }

    /// The [`measures`](Self::measures) of one region of `frame` (a frame of this recording):
    /// the existing sensors whose centre lies inside the closed `outline` (x = column, y = row,
    /// in sensels), such as one foot's outline in a recording of both feet. An outline of fewer
    /// than three points holds no sensor.
    pub fn region_measures(
        &self,
        frame: &Grid,
        threshold: f64,
        outline: &[[f64; 2]],
    ) -> FrameMeasures {
        let mut sum = MeasureSum::default();
        if outline.len() >= 3 && frame.rows() == self.rows && frame.cols() == self.cols {
            let (lo, hi) = outline.iter().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), p| {
                    (
                        [lo[0].min(p[0]), lo[1].min(p[1])],
                        [hi[0].max(p[0]), hi[1].max(p[1])],
                    )
                },
            );
            let span = |lo: f64, hi: f64, n: usize| {
                let first = lo.ceil().max(0.0) as usize;
                let last = (hi.floor().max(-1.0) + 1.0).min(n as f64) as usize;
                first..last.max(first)
            };
            for r in span(lo[1], hi[1], self.rows) {
                for c in span(lo[0], hi[0], self.cols) {
                    if self.sensor_mask[r * self.cols + c]
                        && crate::contour::point_in_polygon([c as f64, r as f64], outline)
                    {
                        sum.add(frame.get(r, c), r, c, threshold);
                    }
                }
            }
        }
        sum.measures(self)
    }
}

/// The sums behind [`FrameMeasures`], sensor by sensor.
#[derive(Default)]
pub(crate) struct MeasureSum {
    /// Contact sensors counted by weight (whole sensors: a count).
    contact: f64,
    load: f64,
    peak: f64,
    moment: [f64; 2],
}

impl MeasureSum {
    /// Adds an existing sensor's value `v` at row `r`, column `c`.
    pub(crate) fn add(&mut self, v: f64, r: usize, c: usize, threshold: f64) {
        self.add_share(v, r, c, threshold, 1.0);
    }

    /// Adds the share `w` (0..=1) of an existing sensor's value `v` at row `r`, column `c`: the
    /// part of the sensel a region covers counts towards its contact, load and centre of
    /// pressure; its value counts towards the peak when the region covers at least half of it.
    pub(crate) fn add_share(&mut self, v: f64, r: usize, c: usize, threshold: f64, w: f64) {
        if v > 0.0 && v >= threshold {
            self.contact += w;
            self.load += w * v;
            self.moment[0] += w * v * c as f64;
            self.moment[1] += w * v * r as f64;
        }
        if w >= 0.5 {
            self.peak = self.peak.max(v);
        }
    }

    /// The measures in `recording`'s units (see [`FrameMeasures`]).
    pub(crate) fn measures(&self, recording: &Recording) -> FrameMeasures {
        let area = recording.sensel_area().unwrap_or(1.0);
        let force = recording.force_factor().unwrap_or(area);
        FrameMeasures {
            contact_sensors: self.contact.round() as usize,
            contact_area: self.contact * area,
            total_force: self.load * force,
            peak_pressure: self.peak,
            cop: (self.load > 0.0)
                .then(|| [self.moment[0] / self.load, self.moment[1] / self.load]),
        }
    }
}

/// The pressure units a recording may state: canonical name, kPa per unit, other spellings
/// (matched case-insensitively, spaces ignored).
const PRESSURE_UNITS: [(&str, f64, &[&str]); 8] = [
    ("kPa", 1.0, &[]),
    ("Pa", 1e-3, &[]),
    ("MPa", 1e3, &[]),
    ("N/cm²", 10.0, &["n/cm2", "n/cm^2"]),
    ("N/mm²", 1e3, &["n/mm2", "n/mm^2"]),
    ("psi", 6.894_757, &[]),
    ("bar", 100.0, &[]),
    ("mmHg", 0.133_322_4, &[]),
];

/// The entry of [`PRESSURE_UNITS`] that `units` names, if any.
fn pressure_unit(units: &str) -> Option<(&'static str, f64)> {
    let u: String = units
        .chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect();
    PRESSURE_UNITS
        .iter()
        .find(|(name, _, other)| {
            name.chars().flat_map(char::to_lowercase).eq(u.chars()) || other.contains(&u.as_str())
        })
        .map(|&(name, kpa, _)| (name, kpa))
}

/// kPa per unit of the named pressure unit (case-insensitive), `None` if unknown.
pub fn kpa_per_unit(units: &str) -> Option<f64> {
    pressure_unit(units).map(|(_, kpa)| kpa)
}

/// The usual spelling of a pressure unit given in any case (`"kpa"` → `"kPa"`, `"N/cm2"` →
/// `"N/cm²"`), `None` if unknown.
///
/// ```
/// use pedo_io::recording::canonical_units;
/// assert_eq!(canonical_units(" MMHG "), Some("mmHg"));
/// assert_eq!(canonical_units("n/cm^2"), Some("N/cm²"));
/// assert_eq!(canonical_units("stone"), None);
/// ```
pub fn canonical_units(units: &str) -> Option<&'static str> {
    pressure_unit(units).map(|(name, _)| name)
}

/// The units a file states, in their usual spelling when known ([`canonical_units`]), else as
/// written: vendors write `N/cm2` or `N/cm²`, and a study's rows name one unit one way.
///
/// Text exports are read as Latin-1, the vendors' encoding; a file re-saved as UTF-8 (what
/// Windows Notepad now writes) turns `²` into the two characters `Â²`, which are read back here:
/// ```
/// use pedo_io::recording::stated_units;
/// assert_eq!(stated_units("N/cm\u{b2}"), "N/cm²"); // Latin-1
/// assert_eq!(stated_units("N/cm\u{c2}\u{b2}"), "N/cm²"); // UTF-8 read as Latin-1
/// ```
pub fn stated_units(units: &str) -> String {
    let units = utf8_read_as_latin1(units).unwrap_or_else(|| units.to_string());
    canonical_units(&units)
        .map(str::to_string)
        .unwrap_or_else(|| units.trim().to_string())
}

/// `text` decoded as UTF-8, when it is UTF-8 text that was read as Latin-1 (every character a
/// byte, some above 0x7F, and those bytes valid UTF-8); else `None`.
fn utf8_read_as_latin1(text: &str) -> Option<String> {
    let bytes: Vec<u8> = text
        .chars()
        .map(|c| u8::try_from(u32::from(c)).ok())
        .collect::<Option<_>>()?;
    if bytes.is_ascii() {
        return None;
    }
    String::from_utf8(bytes).ok()
}

/// The checks of every recording, [`Recording::new`]'s and [`Recording::from_sparse`]'s, in this
/// order: at least one frame of at least 1x1, a frame size that fits in `usize`, `n_values`
/// values for the frames, frames and values within [`crate::limits`], a mask entry per sensel,
/// and every value at an existing sensor finite.
/// `values` yields `(position across the frames, value)`, the position of frame `t`'s value at
/// sensel `i` being `t × rows × cols + i`; values left out (zeros of sparse frames) pass. Returns
/// the number of values per frame.
fn validate(
    n_frames: usize,
    rows: usize,
    cols: usize,
    n_values: usize,
    sensor_mask: &[bool],
    values: impl Iterator<Item = (usize, f32)>,
) -> Result<usize> {
    if n_frames == 0 || rows == 0 || cols == 0 {
        return Err(IoError::invalid(format!(
            "a recording needs at least one frame of at least 1x1, got {n_frames} x {rows}x{cols}"
        )));
    }
    let per = rows
        .checked_mul(cols)
        .ok_or_else(|| IoError::invalid("frame size overflows".to_string()))?;
    if n_frames.checked_mul(per) != Some(n_values) {
        return Err(IoError::invalid(format!(
            "{n_frames} frames of {rows}x{cols} need {} values, got {n_values}",
            n_frames.saturating_mul(per),
        )));
    }
    crate::limits::frame_sensors("a frame", rows, cols).map_err(IoError::invalid)?;
    crate::limits::frame_count(n_frames, per).map_err(IoError::invalid)?;
    if sensor_mask.len() != per {
        return Err(IoError::invalid(format!(
            "sensor mask has {} entries, expected {per}",
            sensor_mask.len()
        )));
    }
    for (k, v) in values {
        let i = k % per;
        if sensor_mask[i] && !v.is_finite() {
            return Err(IoError::invalid(format!(
                "frame {}, row {}, column {} is not finite ({v})",
                k / per,
                i / cols,
                i % cols
            )));
        }
    }
    Ok(per)
}

/// The values of every frame: all of them, or only those that are not 0 ([`SparseFrames`]),
/// whichever takes less memory (decided from the values alone, so that equal recordings are
/// held alike and compare equal).
#[derive(Debug, Clone, PartialEq)]
enum Frames {
    /// Every value, with whether each frame holds nothing (every value `+0.0`), found once
    /// when the frames are made since a run asks it of every frame more than once.
    Dense {
        values: Vec<f32>,
        empty: Vec<bool>,
    },
    Sparse(SparseFrames),
}

/// The values of each frame that are not 0 (bit for bit: `-0.0` is kept), with their positions
/// in the frame (`u16` for frames of up to 65,536 sensels, every plate and insole there is;
/// `u32` for larger ones, images); frame `t` holds the entries `starts[t]..starts[t + 1]`.
/// A frame of zeros takes the room of one index whatever its size, so that the memory of a
/// recording follows the values its file holds, not the size its header claims.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SparseFrames {
    starts: Vec<usize>,
    /// Positions in frames of at most [`NARROW_MAX`] values.
    at: Vec<u16>,
    /// Positions in larger frames.
    wide: Vec<u32>,
    values: Vec<f32>,
    /// Values per frame.
    per: usize,
}

/// The values one frame holds, by position in increasing order, every other value `+0.0`
/// ([`Recording::stored_values`]).
#[derive(Debug, Clone, Copy)]
pub struct StoredValues<'a> {
    at: Positions<'a>,
    values: &'a [f32],
    len: usize,
    cols: usize,
}

#[derive(Debug, Clone, Copy)]
enum Positions<'a> {
    Narrow(&'a [u16]),
    Wide(&'a [u32]),
}

impl<'a> StoredValues<'a> {
    /// The frame's size (rows × cols), stored or not.
    pub fn frame_len(&self) -> usize {
        self.len
    }
    /// Whether the frame holds no value.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
    /// Whether every value held is finite and above 0 (then the frame's sums, peaks and
    /// contact over its stored values are those over all of its values, bit for bit: the
    /// zeros add nothing and no ±0 or NaN makes a maximum depend on the order).
    pub fn all_positive(&self) -> bool {
        self.values.iter().all(|v| v.is_finite() && *v > 0.0)
    }
    /// `(position, value)` in increasing order of position.
    pub fn iter(&self) -> impl Iterator<Item = (usize, f32)> + 'a {
        let (at, values) = (self.at, self.values);
        values.iter().enumerate().map(move |(k, &v)| match at {
            Positions::Narrow(a) => (a[k] as usize, v),
            Positions::Wide(a) => (a[k] as usize, v),
        })
    }
    /// The smallest window of the frame holding every value held, as a grid (0 elsewhere in
    /// it), with its first row and column in the frame; `None` when the frame holds no value.
    pub fn window(&self) -> Option<(Grid, (usize, usize))> {
        // Positions increase, so the first gives the first row; one pass finds the rest.
        let r0 = self.iter().next()?.0 / self.cols;
        let (r1, c0, c1) = self.iter().fold((r0, self.cols, 0), |(_, lo, hi), (i, _)| {
            (i / self.cols, lo.min(i % self.cols), hi.max(i % self.cols))
        });
        let (rows, cols) = (r1 - r0 + 1, c1 - c0 + 1);
        let mut data = vec![0.0f64; rows * cols];
        for (i, v) in self.iter() {
            data[(i / self.cols - r0) * cols + i % self.cols - c0] = v as f64;
        }
        // Values held are finite (as every recording's), so the grid is valid.
        Some((Grid::new(rows, cols, data).ok()?, (r0, c0)))
    }
    /// The whole frame, every value.
    pub fn to_frame(&self) -> Vec<f32> {
        let mut out = vec![0.0; self.len];
        for (i, v) in self.iter() {
            out[i] = v;
        }
        out
    }
}

/// The most values a frame with `u16` positions may have.
const NARROW_MAX: usize = u16::MAX as usize + 1;

impl SparseFrames {
    /// No frames yet; frames will have `per` values (at most
    /// [`MAX_FRAME_SENSORS`](crate::limits::MAX_FRAME_SENSORS)).
    pub(crate) fn new(per: usize) -> Self {
        Self {
            starts: vec![0],
            at: Vec::new(),
            wide: Vec::new(),
            values: Vec::new(),
            per,
        }
    }

    fn is_wide(&self) -> bool {
        self.per > NARROW_MAX
    }

    /// Appends a frame (its value at every position).
    pub(crate) fn push(&mut self, frame: &[f32]) {
        for (i, &v) in frame.iter().enumerate() {
            if v.to_bits() != 0 {
                self.push_entry(i, v);
            }
        }
        self.end_frame();
    }

    /// Ends the frame being built, and tells the reading limits what the frames now hold
    /// ([`crate::limits::holding`]: the reader's next frame is refused past its budget).
    fn end_frame(&mut self) {
        self.starts.push(self.values.len());
        crate::limits::holding(self.bytes());
    }

    /// Adds the value `v` at position `i` to the frame being built (ended by
    /// [`push_empty`](Self::push_empty)), positions in increasing order.
    fn push_entry(&mut self, i: usize, v: f32) {
        // Positions fit: `per` is within the frame limit, far below `u32::MAX`.
        if self.is_wide() {
            self.wide.push(i as u32);
        } else {
            self.at.push(i as u16);
        }
        self.values.push(v);
    }

    /// Appends a frame given by its values at some positions, every other value 0:
    /// `entries` as `(position, value)`, a later entry at a position replacing an earlier one
    /// (so that a page printing a window of the plate costs its window, not the plate).
    pub(crate) fn push_entries(&mut self, entries: &mut [(usize, f32)]) {
        entries.sort_by_key(|e| e.0);
        for (k, &(i, v)) in entries.iter().enumerate() {
            let replaced = entries.get(k + 1).is_some_and(|next| next.0 == i);
            if !replaced && v.to_bits() != 0 {
                self.push_entry(i, v);
            }
        }
        self.end_frame();
    }

    /// Appends a frame of zeros.
    pub(crate) fn push_empty(&mut self) {
        self.end_frame();
    }

    pub(crate) fn n_frames(&self) -> usize {
        self.starts.len() - 1
    }

    /// The position of stored value `k`.
    fn position(&self, k: usize) -> usize {
        if self.is_wide() {
            self.wide[k] as usize
        } else {
            self.at[k] as usize
        }
    }

    fn stored(&self, t: usize, cols: usize) -> StoredValues<'_> {
        let k = self.starts[t]..self.starts[t + 1];
        StoredValues {
            at: if self.is_wide() {
                Positions::Wide(&self.wide[k.clone()])
            } else {
                Positions::Narrow(&self.at[k.clone()])
            },
            values: &self.values[k],
            len: self.per,
            cols,
        }
    }

    fn entries(&self, t: usize) -> impl Iterator<Item = (usize, f32)> + '_ {
        (self.starts[t]..self.starts[t + 1]).map(|k| (self.position(k), self.values[k]))
    }

    /// Bytes per stored value: the value and its position.
    fn entry_bytes(per: usize) -> usize {
        if per > NARROW_MAX {
            8
        } else {
            6
        }
    }

    fn bytes(&self) -> usize {
        self.starts.len() * std::mem::size_of::<usize>()
            + self.values.len() * Self::entry_bytes(self.per)
    }

    /// Whether `n_frames` frames of `per` values, `stored` of them not 0, take less memory held
    /// sparsely than whole.
    fn pays(n_frames: usize, per: usize, stored: usize) -> bool {
        stored
            .saturating_mul(Self::entry_bytes(per))
            .saturating_add((n_frames + 1) * 8)
            < n_frames.saturating_mul(per).saturating_mul(4)
    }

    fn shrink_to_fit(&mut self) {
        self.at.shrink_to_fit();
        self.wide.shrink_to_fit();
        self.values.shrink_to_fit();
        self.starts.shrink_to_fit();
    }
}

impl Frames {
    /// `data` (frames of `per` values), held sparsely when that takes less memory.
    fn compact(data: Vec<f32>, per: usize) -> Self {
        let n = data.len() / per;
        let stored = data.iter().filter(|v| v.to_bits() != 0).count();
        if !SparseFrames::pays(n, per, stored) {
            return Frames::dense(data, per);
        }
        let mut s = SparseFrames::new(per);
        if s.is_wide() {
            s.wide.reserve_exact(stored);
        } else {
            s.at.reserve_exact(stored);
        }
        s.values.reserve_exact(stored);
        s.starts.reserve_exact(n);
        for frame in data.chunks_exact(per) {
            s.push(frame);
        }
        Frames::Sparse(s)
    }

    /// Frames appended one by one, held whole instead when that takes less memory (then no more
    /// than they take held sparsely).
    fn from_sparse(mut s: SparseFrames, per: usize) -> Self {
        let n = s.n_frames();
        if SparseFrames::pays(n, per, s.values.len()) {
            s.shrink_to_fit();
            return Frames::Sparse(s);
        }
        let mut d = vec![0.0f32; n * per];
        for t in 0..n {
            for (i, v) in s.entries(t) {
                d[t * per + i] = v;
            }
        }
        Frames::dense(d, per)
    }

    /// `values` (frames of `per` values) held whole.
    fn dense(values: Vec<f32>, per: usize) -> Self {
        let empty = values
            .chunks_exact(per)
            .map(|f| f.iter().all(|v| v.to_bits() == 0))
            .collect();
        Frames::Dense { values, empty }
    }

    /// Writes frame `t` (of `per` values) into `out`.
    fn fill(&self, t: usize, per: usize, out: &mut [f32]) {
        match self {
            Frames::Dense { values: d, .. } => out.copy_from_slice(&d[t * per..(t + 1) * per]),
            Frames::Sparse(s) => {
                out.fill(0.0);
                for (i, v) in s.entries(t) {
                    out[i] = v;
                }
            }
        }
    }
}

impl Recording {
    /// This recording (its size, mask, units, feet: the header of a streamed run) holding the
    /// frames `kept`, every frame past the last kept 0 up to this one's frame count.
    ///
    /// # Errors
    /// [`IoError::InvalidInput`] for frames kept past this recording's frame count.
    pub fn holding(&self, kept: FrameStore) -> Result<Recording> {
        let mut frames = kept.frames;
        if frames.n_frames() > self.n_frames {
            return Err(IoError::invalid(format!(
                "{} frames kept of a recording of {}",
                frames.n_frames(),
                self.n_frames
            )));
        }
        while frames.n_frames() < self.n_frames {
            frames.starts.push(frames.values.len());
        }
        let per = self.rows * self.cols;
        let mut r = self.clone_header();
        r.frames = Frames::from_sparse(frames, per);
        Ok(r)
    }

    /// This recording's header (every field but the frames, which hold nothing).
    fn clone_header(&self) -> Recording {
        Recording {
            n_frames: self.n_frames,
            rows: self.rows,
            cols: self.cols,
            frames: Frames::Dense {
                values: Vec::new(),
                empty: Vec::new(),
            },
            sensor_mask: self.sensor_mask.clone(),
            pitch_mm: self.pitch_mm,
            sensel_area_mm2: self.sensel_area_mm2,
            dt_s: self.dt_s,
            units: self.units.clone(),
            noise_threshold: self.noise_threshold,
            format: self.format,
            file_negatives: self.file_negatives,
            negatives_clipped: self.negatives_clipped,
            time_axis_settled: self.time_axis_settled,
            feet: self.feet.clone(),
        }
    }

    /// A recording of `n_frames` frames of this one's size, mask and units (a window of a
    /// recording read frame by frame): `data` holds their values.
    pub(crate) fn like(&self, n_frames: usize, data: Vec<f32>) -> Result<Self> {
        let mut r = Self::new(
            n_frames,
            self.rows,
            self.cols,
            data,
            self.sensor_mask.clone(),
        )?;
        r.pitch_mm = self.pitch_mm;
        r.sensel_area_mm2 = self.sensel_area_mm2;
        r.dt_s = self.dt_s;
        r.units = self.units.clone();
        r.noise_threshold = self.noise_threshold;
        r.format = self.format;
        r.time_axis_settled = self.time_axis_settled;
        r.feet = self.feet.clone();
        if self.negatives_clipped {
            r.clip_negatives();
        }
        Ok(r)
    }

    /// Builds a recording from frames appended one by one to `frames` (so that a long file is
    /// never held whole as dense values), with the checks of [`Recording::new`]: values at
    /// missing sensors are dropped and every other value must be finite.
    pub(crate) fn from_sparse(
        rows: usize,
        cols: usize,
        mut frames: SparseFrames,
        sensor_mask: Vec<bool>,
    ) -> Result<Self> {
        let n_frames = frames.n_frames();
        // The frames hold `frames.per` values each, of which only those not 0 are stored (0 is
        // finite): the positions of the stored ones across the frames, as in `new`'s `data`.
        let stride = frames.per;
        let values =
            (0..n_frames).flat_map(|t| frames.entries(t).map(move |(i, v)| (t * stride + i, v)));
        let n_values = n_frames.saturating_mul(stride);
        let per = validate(n_frames, rows, cols, n_values, &sensor_mask, values)?;
        let dropped = (0..frames.values.len()).any(|k| !sensor_mask[frames.position(k)]);
        if dropped {
            let mut kept = SparseFrames::new(per);
            let mut frame = vec![0.0f32; per];
            for t in 0..n_frames {
                frame.fill(0.0);
                for (i, v) in frames.entries(t) {
                    if sensor_mask[i] {
                        frame[i] = v;
                    }
                }
                kept.push(&frame);
            }
            frames = kept;
        }
        Ok(Self::of_frames(
            n_frames,
            rows,
            cols,
            Frames::from_sparse(frames, per),
            sensor_mask,
        ))
    }
}

impl Recording {
    /// [`Recording::from_nan_frames`] of frames appended one by one to `frames`: a sensor is
    /// missing when it is NaN in every frame; NaN in only some frames is an error.
    pub(crate) fn from_sparse_nan(rows: usize, cols: usize, frames: SparseFrames) -> Result<Self> {
        let (n_frames, per) = (frames.n_frames(), frames.per);
        let mut nans = vec![0usize; per];
        for (k, v) in frames.values.iter().enumerate() {
            if v.is_nan() {
                nans[frames.position(k)] += 1;
            }
        }
        if let Some(i) = nans.iter().position(|&n| n > 0 && n < n_frames) {
            return Err(IoError::invalid(format!(
                "row {}, column {} is NaN in {} of {n_frames} frames only",
                i / cols,
                i % cols,
                nans[i]
            )));
        }
        let mask = nans.iter().map(|&n| n == 0).collect();
        Self::from_sparse(rows, cols, frames, mask)
    }
}

/// Where a streamed run reads frames from when the recording it is given holds none of their
/// values: a header-only [`Recording`] (its size, mask, units and frame count) whose frames are
/// read as the run goes (see [`crate::formats::read_for_streaming`]). The run engine
/// (`pedo_track::stream_sequence`) asks for them window by window.
pub trait FrameSource {
    /// Frames `w0..w1` of `recording` as a recording of `w1 - w0` frames with its size, mask
    /// and units. Windows are asked for in order.
    fn window(&mut self, recording: &Recording, w0: usize, w1: usize) -> Result<Recording>;

    /// Called once a run has read its last window, which may end before the recording's last
    /// frame (a run of some frames): a source that checks what it read (a file's digest) does
    /// so here, so that a run of part of a file still fails when the file changed.
    fn finish(&mut self, recording: &Recording) -> Result<()> {
        let _ = recording;
        Ok(())
    }
}

/// The frames a run kept as the engine handed them (a streamed run, whose recording does not
/// hold its frames), held as a recording holds them: only the values that are not 0, with their
/// positions (6 bytes each on a grid of at most 65,536 sensels). [`Recording::holding`] makes
/// them a recording again, the one the file would have given read whole over those frames.
#[derive(Debug, Clone)]
pub struct FrameStore {
    frames: SparseFrames,
}

impl FrameStore {
    /// No frames yet, for frames of `recording`'s size.
    pub fn new(recording: &Recording) -> Self {
        Self {
            frames: SparseFrames::new(recording.rows * recording.cols),
        }
    }

    /// Keeps frame `t` from the values it holds at some positions, in increasing order (every
    /// other value 0); frames before `t` not kept yet are 0. A frame before one already kept is
    /// refused.
    ///
    /// # Errors
    /// [`IoError::InvalidInput`] for a frame out of order, or a position past the frame.
    pub fn push(&mut self, t: usize, values: impl Iterator<Item = (usize, f32)>) -> Result<()> {
        if t < self.frames.n_frames() {
            return Err(IoError::invalid(format!(
                "frame {t} is kept after frame {}",
                self.frames.n_frames() - 1
            )));
        }
        while self.frames.n_frames() < t {
            self.frames.starts.push(self.frames.values.len());
        }
        for (i, v) in values {
            if i >= self.frames.per {
                return Err(IoError::invalid(format!(
                    "position {i} is past a frame of {} values",
                    self.frames.per
                )));
            }
            if v.to_bits() != 0 {
                self.frames.push_entry(i, v);
            }
        }
        // Not a reader's store: the reading limits are not told (`SparseFrames::end_frame`).
        self.frames.starts.push(self.frames.values.len());
        Ok(())
    }

    /// Bytes taken by the values kept and their positions.
    pub fn bytes(&self) -> usize {
        self.frames.bytes()
    }
}

/// Frames a streamed run holds at a time: a [`FrameSource`] reads at most this many ahead.
pub const FRAME_WINDOW: usize = 64;

#[cfg(test)]
mod tests {
    use super::*;

    fn sparse_of(data: &[f32], per: usize) -> SparseFrames {
        let mut s = SparseFrames::new(per);
        for f in data.chunks(per) {
            s.push(f);
        }
        s
    }

    /// Frames of 5 × 7, mostly 0, holding values of every kind a file may: loaded, below the
    /// threshold, negative (an offset) and `-0.0`.
    fn mostly_zero_frames() -> impl proptest::strategy::Strategy<Value = (Vec<f32>, Vec<bool>)> {
        use proptest::prelude::*;
        let value = prop_oneof![
            6 => Just(0.0f32),
            3 => 0.01f32..50.0,
            1 => Just(-0.0f32),
            1 => -3.0f32..-0.01,
        ];
        (
            proptest::collection::vec(value, 4 * 35),
            proptest::collection::vec(proptest::bool::weighted(0.9), 35),
        )
    }

    proptest::proptest! {
        /// The measures and the peak image taken from a sparse frame's stored values are
        /// those of the whole frame, bit for bit (the oracle: the same frames held whole).
        #[test]
        fn measures_of_stored_values_are_those_of_whole_frames(
            (data, mask) in mostly_zero_frames(),
            threshold in proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0f64..20.0],
        ) {
            let sparse = Recording::new(4, 5, 7, data, mask).unwrap();
            let mut whole = sparse.clone();
            whole.frames = Frames::dense(sparse.data().into_owned(), 35);
            let (a, b) = (sparse.measures(threshold), whole.measures(threshold));
            proptest::prop_assert_eq!(format!("{a:?}"), format!("{b:?}"));
            let (a, b) = (sparse.peak_image(), whole.peak_image());
            proptest::prop_assert_eq!(format!("{a:?}"), format!("{b:?}"));
            for t in 0..4 {
                let stored = sparse.stored_values(t);
                proptest::prop_assert_eq!(
                    stored.map(|s| s.to_frame()),
                    sparse.is_sparse().then(|| whole.frame_slice(t).unwrap().into_owned())
                );
            }
        }
    }

    proptest::proptest! {
        /// A recording's header holding the frames a run kept of it, some given as whole
        /// frames and some as their stored values, frames before the first kept and after the
        /// last left 0, is the recording over those frames, frame for frame, bit for bit.
        #[test]
        fn frames_kept_are_the_recording_s(
            (data, mask) in mostly_zero_frames(),
            first in 0usize..4,
            stored_too in proptest::bool::ANY,
        ) {
            let rec = Recording::new(4, 5, 7, data, mask).unwrap();
            let mut kept = FrameStore::new(&rec);
            let last = (first + 2).min(4);
            for t in first..last {
                let frame = rec.frame_slice(t).unwrap();
                if stored_too && t % 2 == 1 {
                    kept.push(t, frame.iter().copied().enumerate().filter(|e| e.1.to_bits() != 0)).unwrap();
                } else {
                    kept.push(t, frame.iter().copied().enumerate()).unwrap();
                }
            }
            // Out of order, or past a frame: refused.
            proptest::prop_assert!(kept.push(first.saturating_sub(1).min(last - 1), std::iter::empty()).is_err());
            let held = rec.holding(kept).unwrap();
            proptest::prop_assert_eq!(held.n_frames(), 4);
            for t in 0..4 {
                let want: Vec<u32> = if (first..last).contains(&t) {
                    rec.frame_slice(t).unwrap().iter().map(|v| v.to_bits()).collect()
                } else {
                    vec![0; 35]
                };
                let got: Vec<u32> = held.frame_slice(t).unwrap().iter().map(|v| v.to_bits()).collect();
                proptest::prop_assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn a_frame_holding_nothing_is_known_without_making_it() {
        let (rows, cols) = (256, 256);
        let mut data = vec![0.0f32; 3 * rows * cols];
        data[rows * cols + 300] = 4.0;
        let rec = Recording::new(3, rows, cols, data, vec![true; rows * cols]).unwrap();
        assert!(rec.stored_values(0).unwrap().is_empty());
        let one = rec.stored_values(1).unwrap();
        assert_eq!(one.iter().collect::<Vec<_>>(), [(300, 4.0)]);
        let (window, origin) = one.window().unwrap();
        assert_eq!((window.rows(), window.cols(), origin), (1, 1, (1, 44)));
        assert!(rec.stored_values(3).is_none());
        // Held whole, a frame of zeros is still told apart (and a loaded one is not listed).
        let mut whole = rec.clone();
        whole.frames = Frames::dense(rec.data().into_owned(), rows * cols);
        assert!(whole.stored_values(2).unwrap().is_empty());
        assert!(whole.stored_values(1).is_none());
    }

    #[test]
    fn mostly_zero_frames_are_held_sparsely_and_read_back_alike() {
        let (n, rows, cols) = (5, 6, 7);
        let per = rows * cols;
        let mut data = vec![0.0f32; n * per];
        data[3] = 2.5;
        data[per + 10] = -0.0;
        data[4 * per + 41] = 7.0;
        let mask = vec![true; per];
        let rec = Recording::new(n, rows, cols, data.clone(), mask.clone()).unwrap();
        assert!(rec.is_sparse());
        assert!(rec.frames_bytes() < data.len() * 4);
        assert_eq!(&*rec.data(), &data[..]);
        // -0.0 is kept bit for bit.
        assert_eq!(
            rec.frame_slice(1).unwrap()[10].to_bits(),
            (-0.0f32).to_bits()
        );
        assert_eq!(rec.frame(4).unwrap().get(5, 6), 7.0);
        assert_eq!(rec.peak_image().max(), 7.0);
        assert_eq!(rec.measures(0.0)[0].contact_sensors, 1);
        // Built frame by frame, the recording is the same.
        let built = Recording::from_sparse(rows, cols, sparse_of(&data, per), mask.clone());
        assert_eq!(built.unwrap(), rec);
        // Frames mostly loaded are held whole, either way.
        let full = vec![1.0f32; n * per];
        let dense = Recording::new(n, rows, cols, full.clone(), mask.clone()).unwrap();
        assert!(!dense.is_sparse());
        let built = Recording::from_sparse(rows, cols, sparse_of(&full, per), mask);
        assert_eq!(built.unwrap(), dense);
    }

    #[test]
    fn frames_larger_than_u16_positions_are_held_sparsely_with_wide_positions() {
        let (rows, cols) = (300, 300);
        let mut frame = vec![0.0f32; rows * cols];
        frame[rows * cols - 1] = 4.0;
        let mut frames = frame.clone();
        frames.extend(vec![0.0f32; rows * cols]);
        let mask = vec![true; rows * cols];
        let rec = Recording::from_sparse(rows, cols, sparse_of(&frames, rows * cols), mask.clone());
        let rec = rec.unwrap();
        assert!(rec.is_sparse());
        assert!(rec.frames_bytes() < 64, "{}", rec.frames_bytes());
        assert_eq!(rec.frame(0).unwrap().get(rows - 1, cols - 1), 4.0);
        assert_eq!(rec, Recording::new(2, rows, cols, frames, mask).unwrap());
    }

    #[test]
    fn recordings_beyond_the_limits_are_refused() {
        use crate::limits::{MAX_FRAME_SENSORS, MAX_RECORDING_VALUES};
        let side = 1 << 11;
        assert!(side * side > MAX_FRAME_SENSORS);
        let mut one = SparseFrames::new(side * side);
        one.push_empty();
        let e = Recording::from_sparse(side, side, one, vec![])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("more than the 1048576 sensors a frame may have"),
            "{e}"
        );
        let mut empty = SparseFrames::new(1 << 20);
        for _ in 0..(MAX_RECORDING_VALUES >> 20) + 1 {
            empty.push_empty();
        }
        let e = Recording::from_sparse(1 << 10, 1 << 10, empty, vec![true; 1 << 20])
            .unwrap_err()
            .to_string();
        assert!(e.contains("values a recording may hold"), "{e}");
    }

    #[test]
    fn a_region_measures_the_sensors_inside_its_outline() {
        // 4 × 5, a missing sensor at (1, 1); the outline encloses rows 1..=2, columns 0..=2.
        let (rows, cols) = (4, 5);
        let data: Vec<f32> = (0..20).map(|i| i as f32).collect();
        let mut mask = vec![true; 20];
        mask[6] = false;
        let mut rec = Recording::new(1, rows, cols, data, mask).unwrap();
        rec.pitch_mm = Some([2.0, 3.0]);
        rec.units = "kPa".into();
        let frame = rec.frame(0).unwrap();
        let outline = [[-0.5, 0.5], [2.5, 0.5], [2.5, 2.5], [-0.5, 2.5]];
        let m = rec.region_measures(&frame, 6.0, &outline);
        // Sensors 5, 7, 10, 11, 12 (6 is missing); 5 is below the threshold.
        let inside = [7.0, 10.0, 11.0, 12.0];
        let load: f64 = inside.iter().sum();
        assert_eq!(m.contact_sensors, 4);
        assert_eq!(m.contact_area, 4.0 * 6.0);
        assert!(
            (m.total_force - load * 6e-3).abs() < 1e-12,
            "kPa × mm² in N"
        );
        assert_eq!(m.peak_pressure, 12.0);
        let cop_x = (7.0 * 2.0 + 11.0 + 12.0 * 2.0) / load;
        let cop_y = (7.0 + 2.0 * (10.0 + 11.0 + 12.0)) / load;
        let cop = m.cop.unwrap();
        assert!((cop[0] - cop_x).abs() < 1e-12 && (cop[1] - cop_y).abs() < 1e-12);
        // A value equal to the noise threshold is a contact, as in the outlines (the noise
        // threshold sets only the values below it to 0); 0 never is.
        assert_eq!(rec.measures(7.0)[0].contact_sensors, 13);
        assert_eq!(rec.measures(0.0)[0].contact_sensors, 18);
        // The whole sensor inside one outline: the frame's measures, to the bit.
        let all = [[-1.0, -1.0], [5.0, -1.0], [5.0, 4.0], [-1.0, 4.0]];
        assert_eq!(rec.region_measures(&frame, 6.0, &all), rec.measures(6.0)[0]);
        // Outside the sensor, or fewer than three points: nothing.
        let none = rec.region_measures(&frame, 0.0, &[[10.0, 10.0], [12.0, 10.0], [11.0, 12.0]]);
        assert_eq!((none.contact_sensors, none.cop), (0, None));
        assert_eq!(
            rec.region_measures(&frame, 0.0, &outline[..2])
                .contact_sensors,
            0
        );
    }

    #[test]
    fn frames_built_one_by_one_are_checked_like_new() {
        let mut mask = vec![true; 4];
        mask[1] = false;
        let one = |frame: &[f32]| sparse_of(frame, 4);
        let rec = Recording::from_sparse(2, 2, one(&[0.0, 5.0, 0.0, 1.0]), mask.clone()).unwrap();
        assert_eq!(&*rec.data(), &[0.0, 0.0, 0.0, 1.0]);
        let e = Recording::from_sparse(2, 2, one(&[0.0, 0.0, f32::INFINITY, 0.0]), mask)
            .unwrap_err()
            .to_string();
        assert!(e.contains("frame 0, row 1, column 0 is not finite"), "{e}");
        // The shape checks are `new`'s, messages included.
        let same_as_new = |frames: SparseFrames, rows, cols, mask: Vec<bool>, message: &str| {
            let n = frames.n_frames();
            let dense = vec![1.0; n * frames.per];
            let e = Recording::from_sparse(rows, cols, frames, mask.clone());
            let e = e.unwrap_err().to_string();
            assert!(e.contains(message), "{e}");
            let e_new = Recording::new(n, rows, cols, dense, mask);
            assert_eq!(e, e_new.unwrap_err().to_string());
        };
        let all = vec![true; 4];
        same_as_new(
            SparseFrames::new(4),
            2,
            2,
            all.clone(),
            "at least one frame of at least",
        );
        same_as_new(
            one(&[1.0; 4]),
            2,
            3,
            all,
            "1 frames of 2x3 need 6 values, got 4",
        );
        same_as_new(
            one(&[1.0; 4]),
            2,
            2,
            vec![true; 3],
            "sensor mask has 3 entries, expected 4",
        );
    }
}
