//! Physical units of a recording: the sensor pitch (mm) and the frame rate (Hz) a user may set
//! or override, and the conversions of pixel coordinates and frame numbers the outputs use.

use crate::error::IoError;
use crate::recording::Recording;
use modal_core::Choice;
use modal_core::{OptionError, OptionSpec};

modal_core::option_set! {
    /// Sensor pitch, frame rate and pressure units that replace a file's (`--pitch-mm X[xY]`,
    /// `--frame-rate HZ`, `--units U`; Python `pitch_mm=`, `frame_rate=`, `units=`). `None` keeps
    /// what the file says.
    UnitOverrides {
        let _d = ();
        /// Millimetres per sensel `[x, y]` = `[column spacing, row spacing]`.
        pitch_mm: Option<Pitch> = None;
            Value, "the file's, if it says",
            "Sensor pitch in mm per sensel: X (square sensels) or XxY (columns x rows, e.g. 7.62x5.08); overrides the file's. A comma is refused: 5,08 could be 5.08 or 5x8.";
        /// Frames per second.
        frame_rate: Option<f64> = None;
            Value, "the file's, if it says",
            "Frames per second; overrides the file's.";
        /// Pressure units of the values, one [`crate::recording::kpa_per_unit`] knows (so that
        /// the outputs can state forces in newtons): for formats that store none (`.npy`, `.npz`,
        /// CSV).
        units: Option<String> = None;
            Value, "the file's, if it says",
            "Pressure units of the values (kPa, Pa, MPa, N/cm², N/mm², psi, bar, mmHg), for formats that store none; overrides the file's.";
        /// Which axis of a 3-D array (`.npy`, `.npz`, an array handed to Python's
        /// `Recording.from_array`) is time. `None`: the first, and an array that looks stored
        /// time-last ([`crate::recording::TIME_LAST_RULE`]) is refused
        /// ([`IoError::TimeLast`]) naming both readings.
        time_axis: Option<TimeAxis> = None;
            Word(TimeAxis::NAMES), "first; an array that looks time-last is refused",
            "Which axis of a 3-D array (.npy, .npz, Recording.from_array) is time: first (frames, rows, columns) or last (rows, columns, frames; transposed when read). Unset, an array whose first two axes are at most 256 and whose last is at least 64 and 3 times as long as each is refused, naming both readings.";
        /// Set values below 0 to 0 before anything is measured or matched; by default they
        /// are kept (measures count only values above 0) and reported
        /// ([`Recording::negative_values`]).
        clip_negative: bool = false;
            Flag, false,
            "Set values below 0 (an offset or a subtracted baseline) to 0 before anything is read from the frames; by default they are kept, and counted with their minimum by inspect and summary.json (measures count only values above 0).";
    }
}

/// Which axis of a 3-D array is time ([`UnitOverrides::time_axis`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeAxis {
    /// `(frames, rows, columns)`, as NumPy files written by pedomatch and most Python code.
    First,
    /// `(rows, columns, frames)`, as MATLAB and many lab scripts store a recording.
    Last,
}

modal_core::choice!(TimeAxis, "time_axis", ["first" => TimeAxis::First, "last" => TimeAxis::Last]);

impl UnitOverrides {
    /// Checks that the pitch and the frame rate are positive and finite and that the units are
    /// known.
    pub fn validate(&self) -> Result<(), OptionError> {
        if let Some(p) = self.pitch_mm {
            p.validate()?;
        }
        if let Some(f) = self.frame_rate
            && !(f.is_finite() && f > 0.0)
        {
            return Err(OptionError::new("frame_rate", f, "frames per second, > 0"));
        }
        if let Some(u) = &self.units
            && crate::recording::kpa_per_unit(u).is_none()
        {
            return Err(OptionError::new("units", u.trim(), PRESSURE_UNITS));
        }
        Ok(())
    }

    /// Settles which axis of an array is time ([`time_axis`](Self::time_axis): a time-last
    /// array transposed, or refused when it looks time-last and no axis was given), sets
    /// values below 0 to 0 when asked ([`clip_negative`](Self::clip_negative)), then sets
    /// the recording's pitch (and the sensel area derived from it), frame interval and units.
    /// Applied again (a recording handed to a run), the time axis is not settled twice.
    ///
    /// # Errors
    ///
    /// [`IoError::Option`] for an invalid value; [`IoError::TimeLast`] for an array that looks
    /// stored time-last when no time axis was given (its `path` empty: see
    /// [`IoError::of_input`]); [`IoError::InvalidInput`] for `time_axis = last` on a recording
    /// that is no array, or whose time axis was already settled.
    pub fn apply(&self, recording: &mut Recording) -> crate::Result<()> {
        self.validate()?;
        self.settle_time_axis(recording)?;
        if self.clip_negative && !recording.negatives_clipped() {
            recording.clip_negatives();
        }
        if let Some(p) = self.pitch_mm {
            recording.set_pitch_mm(p.0);
        }
        if let Some(f) = self.frame_rate {
            recording.dt_s = Some(1.0 / f);
        }
        if let Some(u) = &self.units {
            // One spelling per unit, so that summaries and studies compare ("kpa" is "kPa").
            recording.units = crate::recording::canonical_units(u)
                .unwrap_or(u.trim())
                .to_string();
        }
        Ok(())
    }

    /// The time-axis step of [`apply`](Self::apply).
    fn settle_time_axis(&self, recording: &mut Recording) -> crate::Result<()> {
        let array = matches!(
            recording.format,
            None | Some(crate::Format::Npy) | Some(crate::Format::Npz)
        );
        match self.time_axis {
            Some(TimeAxis::Last) if !array => {
                return Err(IoError::invalid(format!(
                    "time_axis = last applies to arrays (.npy, .npz, Recording.from_array); a \
                     {} file says where its frames are",
                    recording.format.map_or("", |f| f.name())
                )));
            }
            Some(TimeAxis::Last) if recording.time_axis_settled() => {
                return Err(IoError::invalid(
                    "time_axis = last for a recording whose time axis was settled when it was \
                     read: give it where the array is read (read_recording, \
                     Recording.from_array), once",
                ));
            }
            Some(TimeAxis::Last) => *recording = recording.time_last_transposed()?,
            _ if recording.time_axis_settled() => {}
            None if recording.looks_time_last() => {
                return Err(IoError::TimeLast {
                    path: String::new(),
                    shape: [recording.n_frames(), recording.rows(), recording.cols()],
                });
            }
            Some(TimeAxis::First) | None => {}
        }
        recording.settle_time_axis();
        Ok(())
    }
}

/// A sensor pitch in mm per sensel, `[x, y]` = `[column spacing, row spacing]`: written `X`
/// (square sensels) or `XxY` (`7.62x5.08`; `×` too). A comma is refused rather than guessed:
/// `5,08` is 5.08 mm with a decimal comma and 5 × 8 mm as a list, and either misreading would
/// scale every millimetre, area and force of a run without a word; the message offers both.
///
/// ```
/// use pedo_io::units::Pitch;
/// assert_eq!("5.08".parse::<Pitch>().unwrap(), Pitch([5.08, 5.08]));
/// assert_eq!("7.62x5.08".parse::<Pitch>().unwrap(), Pitch([7.62, 5.08]));
/// let e = "5,08".parse::<Pitch>().unwrap_err().to_string();
/// assert!(e.contains("5.08") && e.contains("5x08"), "{e}");
/// assert!("-1".parse::<Pitch>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pitch(pub [f64; 2]);

/// What `--pitch-mm` takes, for its errors.
const PITCH_FORM: &str = "X or XxY: millimetres per sensel, > 0 (XxY: columns x rows)";

impl Pitch {
    /// Checks that both spacings are positive and finite.
    pub fn validate(&self) -> Result<(), OptionError> {
        if self.0.iter().all(|v| v.is_finite() && *v > 0.0) {
            Ok(())
        } else {
            Err(OptionError::new("pitch_mm", self, PITCH_FORM))
        }
    }
}

impl std::fmt::Display for Pitch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y] = self.0;
        if x == y {
            write!(f, "{x}")
        } else {
            write!(f, "{x}x{y}")
        }
    }
}

impl std::str::FromStr for Pitch {
    type Err = OptionError;

    fn from_str(s: &str) -> Result<Self, OptionError> {
        let s = s.trim();
        if let Some((a, b)) = s.split_once(',') {
            let (a, b) = (a.trim(), b.trim());
            let digits = |t: &str| !t.is_empty() && t.bytes().all(|c| c.is_ascii_digit());
            // Only digits either side: both readings are plausible, and the message names both.
            let readings = if digits(a) && digits(b) {
                format!("{a}.{b} for one pitch with a decimal point, or {a}x{b} for columns x rows")
            } else {
                PITCH_FORM.to_string()
            };
            return Err(OptionError::new(
                "pitch_mm",
                s,
                format!("no comma (a decimal comma or a list?): {readings}"),
            ));
        }
        let bad = || OptionError::new("pitch_mm", s, PITCH_FORM);
        let number = |x: &str| x.trim().parse::<f64>().map_err(|_| bad());
        let pitch = match s.split_once(['x', 'X', '×']) {
            Some((x, y)) => Pitch([number(x)?, number(y)?]),
            None => {
                let x = number(s)?;
                Pitch([x, x])
            }
        };
        pitch.validate().map_err(|_| bad())?;
        Ok(pitch)
    }
}

impl modal_core::options::OptionField for Pitch {
    fn python_type() -> String {
        "Pitch".into()
    }
    fn value_name() -> Option<&'static str> {
        Some("X[xY]")
    }
    fn read<I: modal_core::options::OptionInput + ?Sized>(
        input: &I,
        option: &'static str,
    ) -> Result<Self, I::Error> {
        match input.written() {
            Some(text) => Ok(text.parse()?),
            None => Ok(Pitch(input.one_or_two(
                option,
                "a number or an (x, y) pair of numbers (mm per sensel)",
            )?)),
        }
    }
    fn value(&self) -> modal_core::OptionValue {
        modal_core::OptionValue::Numbers(self.0.to_vec())
    }
}

/// The pressure units `--units` accepts (as `kpa_per_unit` reads them, case and spaces aside).
const PRESSURE_UNITS: &str = "a pressure unit: kPa, Pa, MPa, N/cm², N/mm², psi, bar or mmHg";

/// The unit options of `pedomatch run`/`demo`/`match`/`inspect`, `pymodal.run` and
/// `pymodal.read_recording`: their one declaration, [`UnitOverrides`].
pub fn unit_option_specs() -> Vec<OptionSpec> {
    UnitOverrides::specs()
}

impl Recording {
    /// Time of frame `t` in seconds (`t × dt`), when the frame interval is known.
    pub fn time_s(&self, t: usize) -> Option<f64> {
        self.dt_s.map(|dt| t as f64 * dt)
    }

    /// Pixel coordinates `(x, y)` (x = column, y = row) in millimetres, when the pitch is known.
    pub fn to_mm(&self, x: f64, y: f64) -> Option<[f64; 2]> {
        self.pitch_mm.map(|p| [x * p[0], y * p[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_pitch_area_and_time() {
        let mut rec = Recording::new(3, 2, 2, vec![1.0; 12], vec![true; 4]).unwrap();
        rec.sensel_area_mm2 = Some(99.0);
        assert_eq!(rec.time_s(2), None);
        assert_eq!(rec.force_factor(), None);
        let o = UnitOverrides {
            pitch_mm: Some("2x3".parse().unwrap()),
            frame_rate: Some(50.0),
            units: Some(" N/cm2 ".into()),
            ..Default::default()
        };
        o.apply(&mut rec).unwrap();
        assert_eq!(rec.units, "N/cm²");
        // N/cm² = 10 kPa; kPa × mm² × 1e-3 = N.
        assert_eq!(rec.force_factor(), Some(10.0 * 6.0 * 1e-3));
        let stone = UnitOverrides {
            units: Some("stone".into()),
            ..Default::default()
        };
        assert_eq!(stone.validate().unwrap_err().option, "units");
        assert_eq!(rec.sensel_area(), Some(6.0));
        assert_eq!(rec.time_s(2), Some(0.04));
        assert_eq!(rec.to_mm(1.0, 2.0), Some([2.0, 6.0]));
        let stopped = UnitOverrides {
            frame_rate: Some(0.0),
            ..Default::default()
        };
        assert_eq!(stopped.validate().unwrap_err().option, "frame_rate");
    }

    #[test]
    fn a_pitch_with_a_comma_is_refused_with_both_readings() {
        for (written, one, two) in [("5,08", "5.08", "5x08"), ("2,3", "2.3", "2x3")] {
            let e = written.parse::<Pitch>().unwrap_err();
            assert_eq!(e.option, "pitch_mm");
            let message = e.to_string();
            assert!(message.contains(one) && message.contains(two), "{message}");
        }
        // The two-value form with a comma, as it was once written: refused too, saying how.
        let e = "7.62,5.08".parse::<Pitch>().unwrap_err().to_string();
        assert!(e.contains("XxY"), "{e}");
        assert_eq!("5.08".parse::<Pitch>().unwrap(), Pitch([5.08, 5.08]));
        assert_eq!("7.62x5.08".parse::<Pitch>().unwrap(), Pitch([7.62, 5.08]));
        assert_eq!(" 2 × 3 ".parse::<Pitch>().unwrap(), Pitch([2.0, 3.0]));
        assert_eq!("2X3".parse::<Pitch>().unwrap(), Pitch([2.0, 3.0]));
        for bad in ["1x2x3", "x", "0", "-1", "2x-3", "inf", "five"] {
            assert_eq!(
                bad.parse::<Pitch>().unwrap_err().option,
                "pitch_mm",
                "{bad}"
            );
        }
        // Printed back in the form it is read.
        for p in [Pitch([5.08, 5.08]), Pitch([7.62, 5.08])] {
            assert_eq!(p.to_string().parse::<Pitch>().unwrap(), p);
        }
    }
}

#[cfg(test)]
mod input_tests {
    use super::*;
    use crate::formats::npy::{parse_npy, recording_to_npy};

    /// The value at `[i, j, k]` of the test arrays, different along each axis.
    fn v(i: usize, j: usize, k: usize) -> f32 {
        (1000 * i + 10 * j) as f32 + k as f32 * 0.5
    }

    /// A `.npy` read as stored from an array of `shape` (C order) holding `v`.
    fn read_as_stored([a, b, c]: [usize; 3]) -> Recording {
        let data: Vec<f32> = (0..a * b * c)
            .map(|n| v(n / (b * c), n / c % b, n % c))
            .collect();
        let rec = Recording::new(a, b, c, data, vec![true; b * c]).unwrap();
        parse_npy(&recording_to_npy(&rec), "speed.npy").unwrap()
    }

    #[test]
    fn a_time_last_array_is_refused_naming_both_shapes_unless_the_axis_is_given() {
        let mut rec = read_as_stored([63, 33, 500]);
        let e = UnitOverrides::default()
            .apply(&mut rec)
            .unwrap_err()
            .of_input("speed.npy");
        assert!(
            matches!(
                e,
                IoError::TimeLast {
                    shape: [63, 33, 500],
                    ..
                }
            ),
            "{e:?}"
        );
        let m = e.to_string();
        for says in [
            "speed.npy: ",
            "63 frames of 33 x 500",
            "500 frames of 63 x 33",
            "--time-axis last",
            "time_axis=\"last\"",
        ] {
            assert!(m.contains(says), "{says:?}: {m}");
        }
        // Refused whole: the recording is as it was.
        assert_eq!(rec.n_frames(), 63);
        let last = UnitOverrides {
            time_axis: Some(TimeAxis::Last),
            ..Default::default()
        };
        last.apply(&mut rec).unwrap();
        assert_eq!((rec.n_frames(), rec.rows(), rec.cols()), (500, 63, 33));
        for (k, i, j) in [(0, 0, 0), (499, 62, 32), (17, 40, 3), (250, 1, 30)] {
            assert_eq!(rec.frame(k).unwrap().get(i, j), f64::from(v(i, j, k)));
        }
        // Applied again (a recording handed to a run): not transposed twice, not refused.
        UnitOverrides::default().apply(&mut rec).unwrap();
        assert_eq!(rec.n_frames(), 500);
        assert!(last.apply(&mut rec).is_err());
        // Kept as stored when asked.
        let mut kept = read_as_stored([63, 33, 500]);
        let first = UnitOverrides {
            time_axis: Some(TimeAxis::First),
            ..Default::default()
        };
        first.apply(&mut kept).unwrap();
        assert_eq!((kept.n_frames(), kept.rows(), kept.cols()), (63, 33, 500));
    }

    #[test]
    fn the_time_last_rule_takes_recordings_stored_time_first() {
        // Time-first arrays as pedomatch and NumPy code write them, and sensors of vendor
        // sizes: none refused.
        for shape in [
            [500, 63, 33],
            [205, 60, 21],
            [40, 95, 64],
            [1, 33, 500],
            [63, 33, 100],
        ] {
            let mut rec = read_as_stored(shape);
            UnitOverrides::default().apply(&mut rec).unwrap();
            assert_eq!(rec.n_frames(), shape[0], "{shape:?}");
        }
        for shape in [[63, 33, 500], [60, 21, 205], [2, 2, 64], [256, 10, 1024]] {
            assert!(read_as_stored(shape).looks_time_last(), "{shape:?}");
        }
        // A vendor format states its frames: never asked, and `last` is refused for it.
        let mut lst = read_as_stored([63, 33, 500]);
        lst.format = Some(crate::Format::Lst);
        assert!(!lst.looks_time_last());
        let last = UnitOverrides {
            time_axis: Some(TimeAxis::Last),
            ..Default::default()
        };
        assert!(matches!(
            last.apply(&mut lst),
            Err(IoError::InvalidInput(_))
        ));
    }

    #[test]
    fn negative_values_are_counted_and_clipped_only_on_request() {
        let data = vec![
            -2.0, 5.0, 0.0, -0.5, // frame 0
            3.0, -7.25, 99.0, 0.0, // frame 1 (99 at a missing sensor)
        ];
        let mask = vec![true, true, true, false];
        let mut rec = Recording::new(2, 2, 2, data.clone(), mask.clone()).unwrap();
        let oracle = data
            .iter()
            .enumerate()
            .filter(|(n, x)| mask[n % 4] && **x < 0.0)
            .map(|(_, x)| f64::from(*x));
        let (count, min) = (oracle.clone().count(), oracle.fold(f64::INFINITY, f64::min));
        let n = rec.negative_values();
        assert_eq!((n.count, n.min), (2, Some(min)));
        assert_eq!(count, 2);
        let before = rec.measures(0.0);
        UnitOverrides::default().apply(&mut rec).unwrap();
        assert!(!rec.negatives_clipped());
        assert_eq!(rec.frame(1).unwrap().get(0, 1), -7.25);
        let clip = UnitOverrides {
            clip_negative: true,
            ..Default::default()
        };
        clip.apply(&mut rec).unwrap();
        assert!(rec.negatives_clipped());
        assert_eq!(rec.frame(1).unwrap().get(0, 1), 0.0);
        assert_eq!(rec.frame(0).unwrap().get(0, 0), 0.0);
        assert_eq!(rec.frame(0).unwrap().get(0, 1), 5.0);
        // Still the file's, reported.
        assert_eq!(rec.negative_values().count, 2);
        assert_eq!(rec.negative_values().min, Some(-7.25));
        // Measures count only values above 0: clipping changes none.
        assert_eq!(rec.measures(0.0), before);
    }
}
