//! The measures gait researchers report of a whole recording (or of a run's frames): the
//! peak-pressure, pressure-time-integral and mean-pressure images, and the values peak pressure,
//! PTI maximum, peak force, force-time integral, contact time and maximum contact area.
//!
//! [`RecordingMeasures`] takes the frames one at a time, as a streamed run reads them, and
//! [`finish`](RecordingMeasures::finish)es into [`Measures`]; a whole recording is every frame
//! fed in ([`Measures::of_recording`]). Definitions (docs/measures.md):
//!
//! * a sensel is *loaded* in a frame when its value is above 0 and at or above the contact
//!   threshold (as in [`Recording::measures`]);
//! * **peak image**: per sensel the largest value over the frames;
//! * **PTI image**: per sensel `Σ p·Δt` over the frames where it is loaded (the rectangle rule
//!   of novel's pressure-time integral, pressuRe's `pti_1`);
//! * **mean image**: per sensel the mean of its values over the frames where it is loaded
//!   (0 where it never is);
//! * **force** of a frame: the load of its loaded sensels as [`FrameMeasures::total_force`]
//!   (N when the pressure units and the sensel area are known);
//! * **FTI**: `Σ F·Δt` over the frames; **peak force**: the largest `F`;
//! * **contact time**: from the first to the last frame whose force exceeds
//!   `min F + 10 % × (max F − min F)` ([`CONTACT_FORCE_FRACTION`], the automatic threshold of
//!   pressuRe's `threshold_event`), both counted whole: `(last − first + 1) × Δt`;
//! * **maximum contact area**: the largest number of loaded sensels in a frame × sensel area;
//! * **stances** ([`crate::stances`]): the foot contacts among the frames, each with the values
//!   above over its own frames ([`StanceValues`]) and its force, contact area, peak pressure and
//!   centre of pressure resampled to 0–100 % of contact ([`StanceCurves`]);
//! * **feet**: for a recording of both feet apart ([`Recording::feet`], pedar's two insoles),
//!   all of the above again for each foot on its sensels alone ([`FootMeasures`]): in walking
//!   one foot is nearly always down, so the stances of both feet's summed force are no foot's.
//!
//! Pressures are in kPa when the recording's units are known, else in the file's own units;
//! force in N when units and sensel area are known, else the load in the file's units × mm² (or
//! × sensels without a pitch); time in s when the frame rate is known, else in frames. Each value
//! carries its unit ([`Measures::quantities`]) and is named by what it is (`peak_load`, not
//! `peak_force`, when it is no force). Sensors that do not exist are NaN in the images.
//!
//! [`FrameMeasures::total_force`]: crate::recording::FrameMeasures::total_force

use crate::error::{IoError, Result};
use crate::recording::{canonical_units, kpa_per_unit, FootColumns, Recording, StoredValues};
use crate::regions::Side;
use crate::stances::{find_stances, resample, Stance, StanceRule};
use std::ops::Range;

/// The fraction of the force range above the smallest force of the frames that a frame's force
/// must exceed to count in the contact time (pressuRe, `threshold_event`, `threshold = "auto"`:
/// `min + 0.1 × (max − min)`).
pub const CONTACT_FORCE_FRACTION: f64 = 0.1;

/// When a force series (one value per frame) is in contact: its largest force, the contact
/// force threshold (`min + CONTACT_FORCE_FRACTION × (max − min)`) and the first and last frame
/// above it (both 0 when none is: a series of zeros or of one constant force).
pub(crate) struct ForceContact {
    pub(crate) peak: f64,
    pub(crate) threshold: f64,
    pub(crate) first: usize,
    pub(crate) last: usize,
}

impl ForceContact {
    pub(crate) fn of(forces: &[f64]) -> Self {
        let (lo, hi) = (forces.iter()).fold((f64::INFINITY, 0.0f64), |(lo, hi), &f| {
            (lo.min(f), hi.max(f))
        });
        let threshold = lo + CONTACT_FORCE_FRACTION * (hi - lo);
        let above = |f: &f64| *f > threshold;
        let first = forces.iter().position(above).unwrap_or(0);
        let last = forces.iter().rposition(above).unwrap_or(first);
        ForceContact {
            peak: hi,
            threshold,
            first,
            last,
        }
    }

    /// The contact time: the frames from the first to the last above the threshold, `dt`
    /// each; 0 for a series without force.
    pub(crate) fn time(&self, dt: f64) -> f64 {
        if self.peak > 0.0 {
            (self.last - self.first + 1) as f64 * dt
        } else {
            0.0
        }
    }
}

/// The units the measures of a recording are given in (see the [module](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct MeasureUnits {
    /// `"kPa"` when the recording's units are known, else its units as written (`"file units"`
    /// when it states none).
    pub pressure: String,
    /// `"N"`, or `"<pressure>·mm²"` / `"<pressure>·sensel"` when the load is no force.
    pub force: String,
    /// `"s"`, or `"frame"` without a frame rate.
    pub time: String,
    /// `"mm²"`, or `"sensel"` without a sensel area.
    pub area: String,
    /// Whether `force` is newtons (the values are then named `peak_force` and `fti`).
    pub is_force: bool,
}

impl MeasureUnits {
    /// The peak load and its time integral as named quantities: `peak_force` (N) and `fti`
    /// (N·s) when the load is a force, else `peak_load` and `load_time_integral` in the file's
    /// units (never named a force unless it is one).
    pub fn load_quantities(&self, peak: f64, integral: f64) -> [Quantity; 2] {
        let (peak_name, integral_name) = if self.is_force {
            ("peak_force", "fti")
        } else {
            ("peak_load", "load_time_integral")
        };
        [
            Quantity {
                name: peak_name,
                value: peak,
                unit: self.force.clone(),
            },
            Quantity {
                name: integral_name,
                value: integral,
                unit: format!("{}·{}", self.force, self.time),
            },
        ]
    }

    /// The units of `recording`'s measures.
    pub fn of(recording: &Recording) -> Self {
        let known = kpa_per_unit(&recording.units).is_some();
        let written = recording
            .known_units()
            .map(|u| canonical_units(u).unwrap_or(u).to_string())
            .unwrap_or_else(|| "file units".to_string());
        let is_force = recording.force_factor().is_some();
        let force = match (is_force, recording.sensel_area()) {
            (true, _) => "N".to_string(),
            (false, Some(_)) => format!("{written}·mm²"),
            (false, None) => format!("{written}·sensel"),
        };
        Self {
            pressure: if known {
                "kPa".to_string()
            } else {
                written.clone()
            },
            force,
            time: if recording.dt_s.is_some() {
                "s"
            } else {
                "frame"
            }
            .to_string(),
            area: if recording.sensel_area().is_some() {
                "mm²"
            } else {
                "sensel"
            }
            .to_string(),
            is_force,
        }
    }
}

/// One value of [`Measures::quantities`]: its name, value and unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Quantity {
    /// `peak_pressure`, `pti_max`, `peak_force` (or `peak_load`), `fti` (or
    /// `load_time_integral`), `contact_time`, `max_contact_area`.
    pub name: &'static str,
    /// The value, finite.
    pub value: f64,
    /// Its unit (`"kPa"`, `"kPa·s"`, `"N"`, `"N·s"`, `"s"`, `"mm²"`, or those of
    /// [`MeasureUnits`] when the recording does not say).
    pub unit: String,
}

/// The values of [`Measures`], in the units of [`Measures::units`].
#[derive(Debug, Clone, PartialEq)]
pub struct MeasureValues {
    /// The largest value of the peak image.
    pub peak_pressure: f64,
    /// The largest value of the PTI image (pressure × time).
    pub pti_max: f64,
    /// The largest force (or load) of a frame.
    pub peak_force: f64,
    /// The force-time integral `Σ F·Δt`.
    pub fti: f64,
    /// `(last − first + 1) × Δt` of the frames above the contact force threshold.
    pub contact_time: f64,
    /// The first and last frame counted in the contact time.
    pub contact_frames: (usize, usize),
    /// The force threshold of the contact time (force unit).
    pub contact_force_threshold: f64,
    /// The largest contact area of a frame.
    pub max_contact_area: f64,
}

/// The measures of a recording's frames (see the [module](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct Measures {
    /// Rows of the images.
    pub rows: usize,
    /// Columns of the images.
    pub cols: usize,
    /// The frames measured, `start..end`.
    pub frames: Range<usize>,
    /// The contact threshold in the file's units: a sensel is loaded at or above it (and above 0).
    pub threshold: f64,
    /// Peak-pressure image, `rows × cols` row-major (NaN where there is no sensor).
    pub peak: Vec<f64>,
    /// Pressure-time-integral image (NaN where there is no sensor).
    pub pti: Vec<f64>,
    /// Mean-pressure image over each sensel's loaded frames (NaN where there is no sensor).
    pub mean: Vec<f64>,
    /// The values.
    pub values: MeasureValues,
    /// Their units.
    pub units: MeasureUnits,
    /// The stances among the frames, in frame order ([`crate::stances`]).
    pub stances: Vec<StanceMeasures>,
    /// The rule they were found by.
    pub stance_rule: StanceRule,
    /// For a recording of both feet apart ([`Recording::feet`]: pedar's two insoles), each
    /// foot's own measures, in the recording's order of the feet; a foot never loaded in the
    /// frames has none. Empty for a single sensor.
    pub feet: Vec<FootMeasures>,
}

/// The measures of one foot of a recording of both ([`Recording::feet`]): those of its sensels
/// alone, the images NaN outside them, its stances found from its own force.
#[derive(Debug, Clone, PartialEq)]
pub struct FootMeasures {
    /// Which foot.
    pub side: Side,
    /// The columns of its sensels in the recording's frames.
    pub columns: Range<usize>,
    /// Its measures (with no feet of their own).
    pub measures: Measures,
}

/// One stance of a recording: its frames, its values and its curves.
#[derive(Debug, Clone, PartialEq)]
pub struct StanceMeasures {
    /// Its frames.
    pub stance: Stance,
    /// Its values, in the units of [`Measures::units`].
    pub values: StanceValues,
    /// Its curves over 0–100 % of contact.
    pub curves: StanceCurves,
}

/// The values of one stance, over its frames `first..=last` (the definitions of
/// [`MeasureValues`] restricted to them), in the units of [`Measures::units`].
#[derive(Debug, Clone, PartialEq)]
pub struct StanceValues {
    /// Time of the first frame, `first × Δt`.
    pub start_time: f64,
    /// Time of the last frame, `last × Δt`.
    pub end_time: f64,
    /// `(last − first + 1) × Δt`.
    pub contact_time: f64,
    /// The largest force (or load) of its frames.
    pub peak_force: f64,
    /// `Σ F·Δt` over its frames.
    pub fti: f64,
    /// The largest value at a sensor in its frames.
    pub peak_pressure: f64,
    /// The largest contact area of its frames.
    pub max_contact_area: f64,
}

/// A stance's frame measures at [`CURVE_POINTS`](crate::stances::CURVE_POINTS) points of its
/// contact, 0, 1, …, 100 % ([`resample`]): those of the frames table (force, contact area, peak
/// pressure, centre of pressure), in the units of [`Measures::units`].
#[derive(Debug, Clone, PartialEq)]
pub struct StanceCurves {
    /// Force (or load).
    pub force: Vec<f64>,
    /// Contact area.
    pub area: Vec<f64>,
    /// Peak pressure of the frame.
    pub peak_pressure: Vec<f64>,
    /// Centre of pressure, x (column) in sensels; `None` only when no frame of the stance has
    /// load (frames without load are skipped, see [`resample`]).
    pub cop_x: Vec<Option<f64>>,
    /// Centre of pressure, y (row) in sensels.
    pub cop_y: Vec<Option<f64>>,
}

impl StanceMeasures {
    /// The values with their names and units, as [`Measures::quantities`] names them.
    pub fn quantities(&self, u: &MeasureUnits) -> Vec<Quantity> {
        let v = &self.values;
        let q = |name, value, unit: String| Quantity { name, value, unit };
        let [peak, fti] = u.load_quantities(v.peak_force, v.fti);
        vec![
            q("start_time", v.start_time, u.time.clone()),
            q("end_time", v.end_time, u.time.clone()),
            q("contact_time", v.contact_time, u.time.clone()),
            peak,
            fti,
            q("peak_pressure", v.peak_pressure, u.pressure.clone()),
            q("max_contact_area", v.max_contact_area, u.area.clone()),
        ]
    }
}

impl Measures {
    /// The measures of frames `frames` of `recording` (every frame of that range), counting a
    /// sensel as loaded above 0 and at or above `threshold` (file units).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `frames` is empty or reaches past the recording, or
    /// when no sensor is loaded in any of them ([`RecordingMeasures::finish`]).
    pub fn of_recording(
        recording: &Recording,
        threshold: f64,
        frames: Range<usize>,
    ) -> Result<Self> {
        if frames.start >= frames.end || frames.end > recording.n_frames() {
            return Err(IoError::invalid(format!(
                "frame range {}..{} is empty or beyond the {} of the recording",
                frames.start,
                frames.end,
                crate::counted(recording.n_frames(), "frame")
            )));
        }
        let mut m = RecordingMeasures::new(recording, threshold)?;
        for t in frames {
            let values = recording
                .frame_slice(t)
                .ok_or_else(|| IoError::invalid(format!("frame {t} is beyond the recording")))?;
            m.add_frame(t, &values)?;
        }
        m.finish()
    }

    /// The stances whose curves a recording's outputs show: each foot's own, the left's then
    /// the right's, for a recording of both feet apart ([`Measures::feet`]), else its stances.
    pub fn curve_stances(&self) -> Vec<&StanceMeasures> {
        if self.feet.is_empty() {
            self.stances.iter().collect()
        } else {
            (self.feet.iter())
                .flat_map(|f| &f.measures.stances)
                .collect()
        }
    }

    /// The values with their names and units, in the order the outputs list them.
    pub fn quantities(&self) -> Vec<Quantity> {
        let (u, v) = (&self.units, &self.values);
        let q = |name, value, unit: String| Quantity { name, value, unit };
        let [peak, fti] = u.load_quantities(v.peak_force, v.fti);
        vec![
            q("peak_pressure", v.peak_pressure, u.pressure.clone()),
            q("pti_max", v.pti_max, format!("{}·{}", u.pressure, u.time)),
            peak,
            fti,
            q("contact_time", v.contact_time, u.time.clone()),
            q("max_contact_area", v.max_contact_area, u.area.clone()),
        ]
    }
}

/// The measures of a recording taken frame by frame: [`add_frame`](Self::add_frame) each frame
/// in order, then [`finish`](Self::finish). Holds three images and one force per frame.
///
/// ```
/// use pedo_io::measures::RecordingMeasures;
/// use pedo_io::Recording;
/// // 3 frames of 1 × 2 sensels of 0.5 cm × 0.5 cm at 100 Hz, in kPa.
/// let data = vec![0.0, 100.0, 200.0, 100.0, 0.0, 0.0];
/// let rec = Recording::new(3, 1, 2, data, vec![true; 2])?
///     .with_pitch_mm([5.0, 5.0])?
///     .with_frame_rate(100.0)?
///     .with_units("kPa");
/// let mut m = RecordingMeasures::new(&rec, 0.0)?;
/// for t in 0..3 {
///     m.add_frame(t, &rec.frame_slice(t).unwrap())?;
/// }
/// let m = m.finish()?;
/// assert_eq!(m.peak, vec![200.0, 100.0]);
/// assert!((m.pti[1] - 2.0).abs() < 1e-12); // (100 + 100) kPa × 0.01 s
/// assert_eq!(m.mean, vec![200.0, 100.0]);
/// assert!((m.values.peak_force - 7.5).abs() < 1e-12); // 300 kPa × 25 mm²
/// assert!((m.values.fti - 0.1).abs() < 1e-12); // (2.5 + 7.5) N × 0.01 s
/// # Ok::<(), pedo_io::IoError>(())
/// ```
#[derive(Debug, Clone)]
pub struct RecordingMeasures {
    rows: usize,
    cols: usize,
    mask: Vec<bool>,
    threshold: f64,
    /// File units → reported pressure unit.
    pressure_factor: f64,
    /// Sum of loaded file values → force (or load).
    force_factor: f64,
    /// Area of one sensel in the area unit.
    area: f64,
    /// Time between frames in the time unit.
    dt: f64,
    units: MeasureUnits,
    peak: Vec<f64>,
    sum: Vec<f64>,
    loaded: Vec<u32>,
    forces: Vec<f64>,
    /// Per frame: loaded sensels, largest value (file units), centre of pressure (sensels).
    contacts: Vec<usize>,
    peaks: Vec<f64>,
    cops: Vec<Option<[f64; 2]>>,
    max_contact: usize,
    first: Option<usize>,
    next: usize,
    /// Each foot's measures, for a recording of both feet apart.
    feet: Vec<(FootColumns, RecordingMeasures)>,
}

impl RecordingMeasures {
    /// Starts the measures of frames of `recording` (its size, mask, pitch, rate and units; a
    /// header-only recording of a streamed run will do), counting a sensel as loaded above 0
    /// and at or above `threshold` (file units).
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `threshold` is not finite.
    pub fn new(recording: &Recording, threshold: f64) -> Result<Self> {
        let mut whole = Self::of_sensels(recording, threshold)?;
        for foot in &recording.feet {
            let mut m = Self::of_sensels(recording, threshold)?;
            // The foot's sensels alone: every other one is as a missing sensor.
            for (i, exists) in m.mask.iter_mut().enumerate() {
                *exists &= foot.columns.contains(&(i % m.cols));
            }
            whole.feet.push((foot.clone(), m));
        }
        Ok(whole)
    }

    /// [`new`](Self::new) without the feet.
    fn of_sensels(recording: &Recording, threshold: f64) -> Result<Self> {
        if !threshold.is_finite() {
            return Err(IoError::invalid(format!(
                "contact threshold {threshold} is not finite"
            )));
        }
        let per = recording.rows() * recording.cols();
        let area = recording.sensel_area();
        Ok(Self {
            rows: recording.rows(),
            cols: recording.cols(),
            mask: recording.sensor_mask().to_vec(),
            threshold,
            pressure_factor: kpa_per_unit(&recording.units).unwrap_or(1.0),
            force_factor: recording.force_factor().unwrap_or(area.unwrap_or(1.0)),
            area: area.unwrap_or(1.0),
            dt: recording.dt_s.unwrap_or(1.0),
            units: MeasureUnits::of(recording),
            peak: vec![0.0; per],
            sum: vec![0.0; per],
            loaded: vec![0; per],
            forces: Vec::new(),
            contacts: Vec::new(),
            peaks: Vec::new(),
            cops: Vec::new(),
            max_contact: 0,
            first: None,
            next: 0,
            feet: Vec::new(),
        })
    }

    /// Adds frame number `frame` (`rows × cols` values, row-major, in the file's units; values
    /// at missing sensors are ignored). Frames come in order, one after the other.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when `values` is not `rows × cols` long, when `frame` does not
    /// follow the frame added before, or when a value at an existing sensor is not finite.
    pub fn add_frame(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        if values.len() != self.mask.len() {
            return Err(IoError::invalid(format!(
                "a frame of {}x{} needs {} values, got {}",
                self.rows,
                self.cols,
                self.mask.len(),
                values.len()
            )));
        }
        self.check_order(frame)?;
        let bad = (values.iter().zip(&self.mask)).position(|(v, &m)| m && !v.is_finite());
        if let Some(i) = bad {
            return Err(IoError::invalid(format!(
                "frame {frame}, row {}, column {} is not finite",
                i / self.cols,
                i % self.cols
            )));
        }
        self.add_sensels(frame, values.iter().copied().enumerate());
        for (_, foot) in &mut self.feet {
            foot.add_frame(frame, values)?;
        }
        Ok(())
    }

    /// Adds frame number `frame` given by the values it holds ([`StoredValues`]: a frame held
    /// sparsely, or one of zeros), at the cost of those values rather than of the frame's size;
    /// the same as [`add_frame`](Self::add_frame) with the whole frame, bit for bit.
    ///
    /// # Errors
    ///
    /// As [`add_frame`](Self::add_frame).
    pub fn add_stored(&mut self, frame: usize, stored: StoredValues<'_>) -> Result<()> {
        if stored.frame_len() != self.mask.len() || !stored.all_positive() {
            return self.add_frame(frame, &stored.to_frame());
        }
        self.check_order(frame)?;
        // The zeros a stored frame leaves out add nothing: no peak, load or contact.
        self.add_sensels(frame, stored.iter());
        for (_, foot) in &mut self.feet {
            foot.add_stored(frame, stored)?;
        }
        Ok(())
    }

    /// Adds frame `frame`'s sensels `(position, value)`, in order of position.
    fn add_sensels(&mut self, frame: usize, sensels: impl Iterator<Item = (usize, f32)>) {
        let (mut load, mut contact, mut top) = (0.0f64, 0usize, 0.0f64);
        let mut moment = [0.0f64; 2];
        for (i, v) in sensels.filter(|&(i, _)| self.mask[i]) {
            let v = f64::from(v);
            if v > self.peak[i] {
                self.peak[i] = v;
            }
            top = top.max(v);
            if v > 0.0 && v >= self.threshold {
                self.sum[i] += v;
                self.loaded[i] += 1;
                load += v;
                contact += 1;
                // As the frames table's centre of pressure (`Recording::measures`).
                moment[0] += v * (i % self.cols) as f64;
                moment[1] += v * (i / self.cols) as f64;
            }
        }
        self.end_of_frame(frame, load, contact, top, moment);
    }

    fn check_order(&self, frame: usize) -> Result<()> {
        if self.first.is_some() && frame != self.next {
            return Err(IoError::invalid(format!(
                "frame {frame} measured after frame {}: frames are measured one after the other",
                self.next - 1
            )));
        }
        Ok(())
    }

    /// Records frame `frame`'s sums.
    fn end_of_frame(&mut self, frame: usize, load: f64, contact: usize, top: f64, m: [f64; 2]) {
        self.forces.push(load * self.force_factor);
        self.contacts.push(contact);
        self.peaks.push(top);
        self.cops
            .push((load > 0.0).then(|| [m[0] / load, m[1] / load]));
        self.max_contact = self.max_contact.max(contact);
        if self.first.is_none() {
            self.first = Some(frame);
        }
        self.next = frame + 1;
    }

    /// The measures of the frames added.
    ///
    /// # Errors
    ///
    /// [`IoError::InvalidInput`] when no frame was added, or when no sensor is loaded in any
    /// frame (a recording without contact has no peak, PTI or contact time).
    pub fn finish(self) -> Result<Measures> {
        let Some(first) = self.first else {
            return Err(IoError::invalid("no frame to measure"));
        };
        let frames = first..self.next;
        if self.max_contact == 0 {
            return Err(IoError::invalid(format!(
                "no sensor is loaded (above 0 and at or above {}) in frames {}..{}: \
                 the recording has no contact to measure",
                self.threshold, frames.start, frames.end
            )));
        }
        let (k, dt) = (self.pressure_factor, self.dt);
        let image = |f: &dyn Fn(usize) -> f64| -> Vec<f64> {
            (0..self.mask.len())
                .map(|i| if self.mask[i] { f(i) } else { f64::NAN })
                .collect()
        };
        let peak = image(&|i| self.peak[i] * k);
        let pti = image(&|i| self.sum[i] * k * dt);
        let mean = image(&|i| match self.loaded[i] {
            0 => 0.0,
            n => self.sum[i] * k / f64::from(n),
        });
        let finite_max = |v: &[f64]| {
            v.iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold(0.0, f64::max)
        };
        // Some frame has load, so the largest force exceeds the threshold.
        let ForceContact {
            peak: hi,
            threshold,
            first: a,
            last: b,
        } = ForceContact::of(&self.forces);
        let stance_rule = StanceRule::for_interval((self.units.time == "s").then_some(dt));
        let (_, found) = find_stances(&self.forces, first, &stance_rule)?;
        let stances = found.into_iter().map(|s| self.stance(s, first)).collect();
        let mut feet = Vec::new();
        for (foot, m) in self.feet {
            // A foot without contact in these frames has no measures; the other foot has.
            if m.max_contact > 0 {
                feet.push(FootMeasures {
                    side: foot.side,
                    columns: foot.columns,
                    measures: m.finish()?,
                });
            }
        }
        let values = MeasureValues {
            peak_pressure: finite_max(&peak),
            pti_max: finite_max(&pti),
            peak_force: hi,
            fti: self.forces.iter().sum::<f64>() * dt,
            contact_time: (b - a + 1) as f64 * dt,
            contact_frames: (first + a, first + b),
            contact_force_threshold: threshold,
            max_contact_area: self.max_contact as f64 * self.area,
        };
        Ok(Measures {
            rows: self.rows,
            cols: self.cols,
            frames,
            threshold: self.threshold,
            peak,
            pti,
            mean,
            values,
            units: self.units,
            stances,
            stance_rule,
            feet,
        })
    }

    /// The values and curves of stance `s` (frames numbered from `first`, the first added).
    fn stance(&self, s: Stance, first: usize) -> StanceMeasures {
        let frames = (s.first - first)..(s.last - first + 1);
        let (k, dt) = (self.pressure_factor, self.dt);
        let forces = &self.forces[frames.clone()];
        let max = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0f64, f64::max);
        let values = StanceValues {
            start_time: s.first as f64 * dt,
            end_time: s.last as f64 * dt,
            contact_time: s.frames() as f64 * dt,
            peak_force: max(&mut forces.iter().copied()),
            fti: forces.iter().sum::<f64>() * dt,
            peak_pressure: max(&mut self.peaks[frames.clone()].iter().map(|p| p * k)),
            max_contact_area: max(&mut self.contacts[frames.clone()]
                .iter()
                .map(|&c| c as f64 * self.area)),
        };
        let some = |v: &mut dyn Iterator<Item = f64>| {
            resample(&v.map(Some).collect::<Vec<_>>())
                .into_iter()
                .flatten()
                .collect::<Vec<f64>>()
        };
        let cops = &self.cops[frames.clone()];
        let curves = StanceCurves {
            force: some(&mut forces.iter().copied()),
            area: some(
                &mut self.contacts[frames.clone()]
                    .iter()
                    .map(|&c| c as f64 * self.area),
            ),
            peak_pressure: some(&mut self.peaks[frames].iter().map(|p| p * k)),
            cop_x: resample(&cops.iter().map(|c| c.map(|c| c[0])).collect::<Vec<_>>()),
            cop_y: resample(&cops.iter().map(|c| c.map(|c| c[1])).collect::<Vec<_>>()),
        };
        StanceMeasures {
            stance: s,
            values,
            curves,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 4 frames of 2 × 2, one sensor missing (row 1, column 1), 0.5 cm pitch, 50 Hz, N/cm².
    fn small() -> Recording {
        #[rustfmt::skip]
        let data = vec![
            0.0, 0.0, 0.0, 9.0,
            1.0, 2.0, 0.5, 9.0,
            3.0, 0.0, 1.0, 9.0,
            0.0, 0.0, 0.0, 9.0,
        ];
        let mask = vec![true, true, true, false];
        Recording::new(4, 2, 2, data, mask)
            .unwrap()
            .with_pitch_mm([5.0, 5.0])
            .unwrap()
            .with_frame_rate(50.0)
            .unwrap()
            .with_units("N/cm2")
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    proptest::proptest! {
        /// A frame added by the values it holds is measured as the whole frame is, bit for bit
        /// (values of every kind: loaded, below the threshold, negative, `-0.0`).
        #[test]
        fn frames_added_by_their_stored_values_measure_as_whole_frames(
            data in proptest::collection::vec(proptest::prop_oneof![
                6 => proptest::strategy::Just(0.0f32),
                3 => 0.01f32..50.0,
                1 => proptest::strategy::Just(-0.0f32),
                1 => -3.0f32..-0.01,
            ], 5 * 12),
            threshold in 0.0f64..20.0,
        ) {
            let mut mask = vec![true; 12];
            mask[5] = false;
            let rec = Recording::new(5, 3, 4, data, mask).unwrap().with_frame_rate(100.0).unwrap();
            let mut stored = RecordingMeasures::new(&rec, threshold).unwrap();
            let mut whole = RecordingMeasures::new(&rec, threshold).unwrap();
            for t in 0..5 {
                let frame = rec.frame_slice(t).unwrap();
                match rec.stored_values(t) {
                    Some(s) => stored.add_stored(t, s).unwrap(),
                    None => stored.add_frame(t, &frame).unwrap(),
                }
                whole.add_frame(t, &frame).unwrap();
            }
            proptest::prop_assert_eq!(
                format!("{:?}", stored.finish()),
                format!("{:?}", whole.finish())
            );
        }
    }

    #[test]
    fn hand_computed_measures_of_a_small_recording() {
        let rec = small();
        let m = Measures::of_recording(&rec, 0.0, 0..4).unwrap();
        // 1 N/cm² = 10 kPa; dt = 0.02 s; sensel 25 mm²: F = Σ N/cm² × 10 kPa × 25 mm² × 1e-3.
        assert_eq!(m.units.pressure, "kPa");
        assert_eq!(m.peak[..3], [30.0, 20.0, 10.0]);
        assert!(m.peak[3].is_nan() && m.pti[3].is_nan() && m.mean[3].is_nan());
        for (got, want) in m.pti[..3]
            .iter()
            .zip([(10.0 + 30.0) * 0.02, 0.4, (5.0 + 10.0) * 0.02])
        {
            assert!(close(*got, want), "{got} vs {want}");
        }
        assert_eq!(m.mean[..3], [20.0, 20.0, 7.5]);
        // Forces: frame 1: 3.5 N/cm² → 0.875 N; frame 2: 4 → 1.0 N; frames 0 and 3: 0.
        let v = &m.values;
        assert!(close(v.peak_force, 1.0));
        assert!(close(v.fti, (0.875 + 1.0) * 0.02));
        // Threshold 0 + 10 % of 1 N: frames 1 and 2, 2 × 0.02 s.
        assert!(close(v.contact_force_threshold, 0.1));
        assert_eq!(v.contact_frames, (1, 2));
        assert!(close(v.contact_time, 0.04));
        assert_eq!(v.max_contact_area, 75.0);
        assert_eq!(v.peak_pressure, 30.0);
        assert!(close(v.pti_max, 0.8));
        let names: Vec<_> = m
            .quantities()
            .iter()
            .map(|q| (q.name, q.unit.clone()))
            .collect();
        assert_eq!(
            names,
            [
                ("peak_pressure", "kPa".into()),
                ("pti_max", "kPa·s".into()),
                ("peak_force", "N".into()),
                ("fti", "N·s".into()),
                ("contact_time", "s".into()),
                ("max_contact_area", "mm²".into()),
            ]
        );
    }

    #[test]
    fn the_threshold_and_the_frame_range_bound_what_counts() {
        let rec = small();
        // At or above 1: the 0.5 leaves PTI, mean, force and area.
        let m = Measures::of_recording(&rec, 1.0, 1..3).unwrap();
        assert_eq!(m.frames, 1..3);
        assert_eq!(m.mean[2], 10.0);
        assert!(close(m.pti[2], 0.2));
        // The peak counts every value, as the frames table's peak pressure.
        assert_eq!(m.peak[2], 10.0);
        assert_eq!(m.values.max_contact_area, 50.0);
        assert!(close(m.values.peak_force, 1.0));
        // Forces 0.75 and 1.0: threshold 0.75 + 0.025; only frame 2 exceeds it.
        assert_eq!(m.values.contact_frames, (2, 2));
        assert!(close(m.values.contact_time, 0.02));
    }

    #[test]
    fn unknown_units_rate_and_pitch_name_the_values_by_what_they_are() {
        let mut rec = small();
        rec.units = String::new();
        rec.dt_s = None;
        rec.pitch_mm = None;
        let m = Measures::of_recording(&rec, 0.0, 0..4).unwrap();
        let q = m.quantities();
        let got: Vec<_> = q.iter().map(|q| (q.name, q.unit.as_str())).collect();
        assert_eq!(
            got,
            [
                ("peak_pressure", "file units"),
                ("pti_max", "file units·frame"),
                ("peak_load", "file units·sensel"),
                ("load_time_integral", "file units·sensel·frame"),
                ("contact_time", "frame"),
                ("max_contact_area", "sensel"),
            ]
        );
        assert_eq!(m.peak[0], 3.0);
        assert!(close(m.values.fti, 7.5));
        assert_eq!(m.values.contact_time, 2.0);
        // Stated but unknown units are named as written; the pitch gives a load in units·mm².
        rec.units = "raw".into();
        rec.pitch_mm = Some([5.0, 5.0]);
        let m = Measures::of_recording(&rec, 0.0, 0..4).unwrap();
        assert_eq!(m.quantities()[2].unit, "raw·mm²");
        assert!(close(m.values.peak_force, 100.0));
    }

    #[test]
    fn stances_have_their_own_values_and_curves_computed_by_hand() {
        // 1 × 2 sensels of 1 mm², 100 Hz (rule: gaps < 5 frames joined, stances >= 10 frames),
        // kPa; forces in N = Σ kPa × 1e-3. Frames 2..=13: one stance, the left sensel at
        // 1000 kPa, the right one rising 0, 100, …, 1100 kPa; frames 20..=31 another, the right
        // sensel alone at 2000 kPa.
        let n = 40;
        let mut data = vec![0.0f32; 2 * n];
        for t in 2..=13 {
            data[2 * t] = 1000.0;
            data[2 * t + 1] = 100.0 * (t - 2) as f32;
        }
        for t in 20..=31 {
            data[2 * t + 1] = 2000.0;
        }
        let rec = Recording::new(n, 1, 2, data, vec![true; 2])
            .unwrap()
            .with_pitch_mm([1.0, 1.0])
            .unwrap()
            .with_frame_rate(100.0)
            .unwrap()
            .with_units("kPa");
        let m = Measures::of_recording(&rec, 0.0, 0..n).unwrap();
        assert_eq!(m.stance_rule.min_gap, 5);
        let spans: Vec<_> = m.stances.iter().map(|s| s.stance).collect();
        assert_eq!(
            spans,
            [
                Stance {
                    first: 2,
                    last: 13,
                    complete: true
                },
                Stance {
                    first: 20,
                    last: 31,
                    complete: true
                }
            ]
        );
        let (a, b) = (&m.stances[0], &m.stances[1]);
        assert!(close(a.values.start_time, 0.02) && close(a.values.end_time, 0.13));
        assert!(close(a.values.contact_time, 0.12));
        assert!(close(a.values.peak_force, 2.1)); // (1000 + 1100) kPa × 1 mm²
                                                  // Σ (1 + 0.1 k) N over k = 0..11 = 12 + 6.6, × 0.01 s.
        assert!(close(a.values.fti, 0.186), "{}", a.values.fti);
        assert_eq!(a.values.peak_pressure, 1100.0);
        assert_eq!(a.values.max_contact_area, 2.0);
        assert_eq!(b.values.peak_pressure, 2000.0);
        assert_eq!(b.values.max_contact_area, 1.0);
        // Point p at frame 2 + 11 p / 100: the force 1 + 0.1 × 11 p / 100 N, linear.
        let c = &a.curves;
        for p in [0, 1, 37, 50, 99, 100] {
            let want = 1.0 + 0.1 * 11.0 * p as f64 / 100.0;
            assert!(close(c.force[p], want), "{p}: {} vs {want}", c.force[p]);
        }
        // Frame 2 (0 %) has the left sensel alone, frame 3 both: the area 1 → 2 mm² over the
        // first 1/11 of the stance.
        assert_eq!((c.area[0], c.area[100]), (1.0, 2.0));
        assert!(close(c.area[5], 1.0 + 5.0 * 11.0 / 100.0));
        // Centre of pressure x: frame 2 + j has weights 1000 (x = 0) and 100 j (x = 1).
        let cop = |j: f64| 100.0 * j / (1000.0 + 100.0 * j);
        assert_eq!(c.cop_x[0], Some(0.0));
        assert!(close(c.cop_x[100].unwrap(), cop(11.0)));
        // 50 % is frame 2 + 5.5: halfway between the centres of frames 7 and 8.
        assert!(close(c.cop_x[50].unwrap(), (cop(5.0) + cop(6.0)) / 2.0));
        assert_eq!(c.cop_y[50], Some(0.0));
        assert_eq!(b.curves.peak_pressure, vec![2000.0; 101]);
        assert_eq!(b.curves.cop_x, vec![Some(1.0); 101]);
        let names: Vec<_> = a.quantities(&m.units).iter().map(|q| q.name).collect();
        assert_eq!(
            names,
            [
                "start_time",
                "end_time",
                "contact_time",
                "peak_force",
                "fti",
                "peak_pressure",
                "max_contact_area"
            ]
        );
    }

    #[test]
    fn empty_recordings_and_bad_frames_are_clear_errors() {
        let rec = Recording::new(2, 1, 2, vec![0.0; 4], vec![true; 2]).unwrap();
        let e = Measures::of_recording(&rec, 0.0, 0..2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no sensor is loaded"), "{e}");
        let e = Measures::of_recording(&rec, 0.0, 1..1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("empty or beyond"), "{e}");
        let e = RecordingMeasures::new(&rec, 0.0)
            .unwrap()
            .finish()
            .unwrap_err();
        assert!(e.to_string().contains("no frame"), "{e}");
        let mut m = RecordingMeasures::new(&rec, 0.0).unwrap();
        assert!(m
            .add_frame(0, &[1.0])
            .unwrap_err()
            .to_string()
            .contains("needs 2 values"));
        m.add_frame(3, &[1.0, 0.0]).unwrap();
        let e = m.add_frame(5, &[1.0, 0.0]).unwrap_err().to_string();
        assert!(e.contains("after frame 3"), "{e}");
        let e = m.add_frame(4, &[f32::NAN, 0.0]).unwrap_err().to_string();
        assert!(e.contains("row 0, column 0 is not finite"), "{e}");
        assert!(RecordingMeasures::new(&rec, f64::NAN).is_err());
    }
}
