//! Physical units of a recording: the sensor pitch (mm) and the frame rate (Hz) a user may set
//! or override, and the conversions of pixel coordinates and frame numbers the outputs use.

use crate::recording::Recording;
use modal_core::{OptionError, OptionKind, OptionSpec};

/// Sensor pitch, frame rate and pressure units that replace a file's (`--pitch-mm X[,Y]`,
/// `--frame-rate HZ`, `--units U`; Python `pitch_mm=`, `frame_rate=`, `units=`). `None` keeps
/// what the file says.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UnitOverrides {
    /// Millimetres per sensel `[x, y]` = `[column spacing, row spacing]`.
    pub pitch_mm: Option<[f64; 2]>,
    /// Frames per second.
    pub frame_rate: Option<f64>,
    /// Pressure units of the values, one [`crate::recording::kpa_per_unit`] knows (so that the
    /// outputs can state forces in newtons): for formats that store none (`.npy`, `.npz`, CSV).
    pub units: Option<String>,
}

impl UnitOverrides {
    /// Checks that the pitch and the frame rate are positive and finite.
    pub fn validate(&self) -> Result<(), OptionError> {
        if let Some(p) = self.pitch_mm
            && !p.iter().all(|v| v.is_finite() && *v > 0.0)
        {
            return Err(OptionError::new(
                "pitch_mm",
                format!("{},{}", p[0], p[1]),
                "X[,Y]: millimetres per sensel, > 0",
            ));
        }
        if let Some(f) = self.frame_rate
            && !(f.is_finite() && f > 0.0)
        {
            return Err(OptionError::new("frame_rate", f, "frames per second, > 0"));
        }
        if let Some(u) = &self.units
            && crate::recording::kpa_per_unit(u).is_none()
        {
            return Err(OptionError::new("units", u, PRESSURE_UNITS));
        }
        Ok(())
    }

    /// Sets the recording's pitch (and the sensel area derived from it) and frame interval.
    pub fn apply(&self, recording: &mut Recording) -> Result<(), OptionError> {
        self.validate()?;
        if let Some(p) = self.pitch_mm {
            recording.set_pitch_mm(p);
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

/// Parses a pitch `X` or `X,Y` in mm per sensel (`X` alone for square sensels).
///
/// ```
/// assert_eq!(pedo_io::units::parse_pitch("5.08").unwrap(), [5.08, 5.08]);
/// assert_eq!(pedo_io::units::parse_pitch("5,7.5").unwrap(), [5.0, 7.5]);
/// assert!(pedo_io::units::parse_pitch("-1").is_err());
/// ```
pub fn parse_pitch(s: &str) -> Result<[f64; 2], OptionError> {
    let bad = || OptionError::new("pitch_mm", s, "X[,Y]: millimetres per sensel, > 0");
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    let pitch = match v.as_slice() {
        [x] => [*x, *x],
        [x, y] => [*x, *y],
        _ => return Err(bad()),
    };
    UnitOverrides {
        pitch_mm: Some(pitch),
        ..UnitOverrides::default()
    }
    .validate()
    .map_err(|_| bad())?;
    Ok(pitch)
}

/// The pressure units `--units` accepts (as `kpa_per_unit` reads them, case and spaces aside).
const PRESSURE_UNITS: &str = "a pressure unit: kPa, Pa, MPa, N/cm², N/mm², psi, bar or mmHg";

/// Parses pressure units (one of [`crate::recording::kpa_per_unit`]'s).
///
/// ```
/// assert_eq!(pedo_io::units::parse_units("N/cm2").unwrap(), "N/cm²");
/// assert_eq!(pedo_io::units::parse_units("kpa").unwrap(), "kPa");
/// assert!(pedo_io::units::parse_units("furlongs").is_err());
/// ```
pub fn parse_units(s: &str) -> Result<String, OptionError> {
    crate::recording::canonical_units(s)
        .map(str::to_string)
        .ok_or_else(|| OptionError::new("units", s.trim(), PRESSURE_UNITS))
}

/// Parses a frame rate in Hz.
pub fn parse_frame_rate(s: &str) -> Result<f64, OptionError> {
    let f: f64 = s
        .trim()
        .parse()
        .map_err(|_| OptionError::new("frame_rate", s, "frames per second, > 0"))?;
    UnitOverrides {
        frame_rate: Some(f),
        ..UnitOverrides::default()
    }
    .validate()?;
    Ok(f)
}

/// The unit options of `pedomatch run`/`demo`/`match`/`inspect`, `pymodal.run` and
/// `pymodal.read_recording`.
pub fn unit_option_specs() -> Vec<OptionSpec> {
    vec![
        OptionSpec::new(
            "pitch_mm",
            OptionKind::Value,
            "the file's, if it says",
            "Sensor pitch X[,Y] in mm per sensel (X alone: square sensels); overrides the file's.",
        )
        .with_python_type("Pitch"),
        OptionSpec::new(
            "frame_rate",
            OptionKind::Value,
            "the file's, if it says",
            "Frames per second; overrides the file's.",
        ),
        OptionSpec::new(
            "units",
            OptionKind::Value,
            "the file's, if it says",
            "Pressure units of the values (kPa, Pa, MPa, N/cm², N/mm², psi, bar, mmHg), for formats that store none; overrides the file's.",
        )
        .with_python_type("str"),
    ]
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
            pitch_mm: Some(parse_pitch("2,3").unwrap()),
            frame_rate: Some(parse_frame_rate("50").unwrap()),
            units: Some(parse_units(" N/cm2 ").unwrap()),
        };
        o.apply(&mut rec).unwrap();
        assert_eq!(rec.units, "N/cm²");
        // N/cm² = 10 kPa; kPa × mm² × 1e-3 = N.
        assert_eq!(rec.force_factor(), Some(10.0 * 6.0 * 1e-3));
        assert_eq!(parse_units("stone").unwrap_err().option, "units");
        assert_eq!(rec.sensel_area(), Some(6.0));
        assert_eq!(rec.time_s(2), Some(0.04));
        assert_eq!(rec.to_mm(1.0, 2.0), Some([2.0, 6.0]));
        assert_eq!(parse_frame_rate("0").unwrap_err().option, "frame_rate");
        assert_eq!(parse_pitch("1,2,3").unwrap_err().option, "pitch_mm");
    }
}
