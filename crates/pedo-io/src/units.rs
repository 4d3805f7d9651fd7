//! Physical units of a recording: the sensor pitch (mm) and the frame rate (Hz) a user may set
//! or override, and the conversions of pixel coordinates and frame numbers the outputs use.

use crate::recording::Recording;
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
    }
}

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

    /// Sets the recording's pitch (and the sensel area derived from it) and frame interval.
    pub fn apply(&self, recording: &mut Recording) -> Result<(), OptionError> {
        self.validate()?;
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
