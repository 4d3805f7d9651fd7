//! A pressure recording: frames, sensor geometry, timing, units, the no-sensor mask and the
//! measures every plate's software shows.

use crate::error::{IoError, Result};
use crate::grid::Grid;

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

/// A plantar-pressure recording: `T` frames of `rows × cols` values (`f32`).
///
/// Sensors that do not exist (Tekscan `B`, `-1` or NaN in other exports) are recorded in
/// [`sensor_mask`](Self::sensor_mask) and hold 0 in [`data`](Self::data); they never count in
/// areas or means. Zero pressure on an existing sensor is an ordinary 0 with the mask set.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    n_frames: usize,
    rows: usize,
    cols: usize,
    data: Vec<f32>,
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
}

/// The per-frame measures of a recording (see [`Recording::measures`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMeasures {
    /// Number of existing sensors with a value above the contact threshold.
    pub contact_sensors: usize,
    /// Contact area: `contact_sensors × sensel area` in mm², or in sensels when the area is unknown.
    pub contact_area: f64,
    /// Total force in N when units and sensel area are known ([`Recording::force_factor`]), else the
    /// plain sum of the values times the area factor.
    pub total_force: f64,
    /// Largest value in the frame (0 for an empty frame).
    pub peak_pressure: f64,
    /// Centre of pressure `(x, y)` in pixel coordinates (value-weighted mean of sensel centres);
    /// `None` when nothing is above the threshold.
    pub cop: Option<[f64; 2]>,
}

impl Recording {
    /// Builds a recording from frames (`n_frames × rows × cols`, row-major per frame) and a
    /// sensor mask (`rows × cols`, `true` where a sensor exists). Values at masked-out sensors are
    /// forced to 0. Every value at an existing sensor must be finite.
    pub fn new(
        n_frames: usize,
        rows: usize,
        cols: usize,
        mut data: Vec<f32>,
        sensor_mask: Vec<bool>,
    ) -> Result<Self> {
        if n_frames == 0 || rows == 0 || cols == 0 {
            return Err(IoError::invalid(format!(
                "a recording needs at least one frame of at least 1x1, got {n_frames} x {rows}x{cols}"
            )));
        }
        let per = rows
            .checked_mul(cols)
            .ok_or_else(|| IoError::invalid("frame size overflows".to_string()))?;
        if n_frames.checked_mul(per) != Some(data.len()) {
            return Err(IoError::invalid(format!(
                "{n_frames} frames of {rows}x{cols} need {} values, got {}",
                n_frames.saturating_mul(per),
                data.len()
            )));
        }
        if sensor_mask.len() != per {
            return Err(IoError::invalid(format!(
                "sensor mask has {} entries, expected {per}",
                sensor_mask.len()
            )));
        }
        for (i, v) in data.iter_mut().enumerate() {
            if !sensor_mask[i % per] {
                *v = 0.0;
            } else if !v.is_finite() {
                return Err(IoError::invalid(format!(
                    "frame {}, row {}, column {} is not finite ({v})",
                    i / per,
                    (i % per) / cols,
                    i % cols
                )));
            }
        }
        Ok(Self {
            n_frames,
            rows,
            cols,
            data,
            sensor_mask,
            pitch_mm: None,
            sensel_area_mm2: None,
            dt_s: None,
            units: String::new(),
            noise_threshold: None,
            format: None,
        })
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
    /// finite and positive.
    pub fn with_pitch_mm(mut self, pitch: [f64; 2]) -> Result<Self> {
        if !pitch.iter().all(|p| p.is_finite() && *p > 0.0) {
            return Err(IoError::invalid(format!(
                "pitch must be finite and positive, got {pitch:?} mm"
            )));
        }
        self.pitch_mm = Some(pitch);
        Ok(self)
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

    pub fn n_frames(&self) -> usize {
        self.n_frames
    }
    pub fn rows(&self) -> usize {
        self.rows
    }
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// All frames, `n_frames × rows × cols` row-major, 0 at missing sensors.
    pub fn data(&self) -> &[f32] {
        &self.data
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
    pub fn frame_slice(&self, t: usize) -> Option<&[f32]> {
        let per = self.rows * self.cols;
        (t < self.n_frames).then(|| &self.data[t * per..(t + 1) * per])
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

    /// Frames with NaN at missing sensors (the layout the Python binding exposes).
    pub fn frames_with_nan(&self) -> Vec<f32> {
        let per = self.rows * self.cols;
        self.data
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                if self.sensor_mask[i % per] {
                    v
                } else {
                    f32::NAN
                }
            })
            .collect()
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
        for t in 0..self.n_frames {
            for (o, &v) in out.iter_mut().zip(&self.data[t * per..(t + 1) * per]) {
                *o = o.max(v as f64);
            }
        }
        // Values are finite by construction, so the grid is valid.
        Grid::new(self.rows, self.cols, out).expect("finite values")
    }

    /// Per-frame measures, counting sensors with a value strictly above `threshold` (use 0 for
    /// "any load").
    pub fn measures(&self, threshold: f64) -> Vec<FrameMeasures> {
        let per = self.rows * self.cols;
        let area = self.sensel_area().unwrap_or(1.0);
        let force = self.force_factor().unwrap_or(area);
        (0..self.n_frames)
            .map(|t| {
                let f = &self.data[t * per..(t + 1) * per];
                let (mut n, mut sum, mut peak, mut sx, mut sy) = (0usize, 0.0f64, 0.0f64, 0.0, 0.0);
                for (i, &v) in f.iter().enumerate() {
                    let v = v as f64;
                    if self.sensor_mask[i] && v > threshold {
                        n += 1;
                        sum += v;
                        sx += v * (i % self.cols) as f64;
                        sy += v * (i / self.cols) as f64;
                    }
                    if self.sensor_mask[i] {
                        peak = peak.max(v);
                    }
                }
                FrameMeasures {
                    contact_sensors: n,
                    contact_area: n as f64 * area,
                    total_force: sum * force,
                    peak_pressure: peak,
                    cop: (sum > 0.0).then(|| [sx / sum, sy / sum]),
                }
            })
            .collect()
    }
}

/// kPa per unit of the named pressure unit (case-insensitive), `None` if unknown.
pub fn kpa_per_unit(units: &str) -> Option<f64> {
    let u: String = units
        .trim()
        .to_ascii_lowercase()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    Some(match u.as_str() {
        "kpa" => 1.0,
        "pa" => 1e-3,
        "mpa" => 1e3,
        "n/cm²" | "n/cm2" | "n/cm^2" => 10.0,
        "n/mm²" | "n/mm2" | "n/mm^2" => 1e3,
        "psi" => 6.894_757,
        "bar" => 100.0,
        "mmhg" => 0.133_322_4,
        _ => return None,
    })
}
