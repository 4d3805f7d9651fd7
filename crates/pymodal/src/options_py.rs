//! The keyword options of `pymodal.match` and `pymodal.run`, read into the library's option
//! types: every keyword defaults to `None`, meaning the documented default, which the library
//! fills in ([`MatchParams::default`], [`RunParams::default`]); words are parsed by the Rust
//! types' `FromStr`, so Python and the CLI accept the same values.

use modal_core::options::MatchOverrides;
use modal_core::{Choice, MatchParams, OptionKind, OptionSpec};
use pedo_io::report::{Cell, Table};
use pedo_io::sequence::{FrameRange, RunParams};
use pedo_io::units::UnitOverrides;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString};

use crate::errors::{argument_error, option_error, to_py};

/// A word option: `None` keeps `default`, a string is parsed by `T`'s `FromStr`.
pub fn word<T: Choice>(value: Option<&str>, default: T) -> PyResult<T> {
    value.map_or(Ok(default), |s| T::parse_word(s).map_err(to_py))
}

/// An integer keyword (a count, a size, a frame index) as the library's `usize`.
///
/// Such keywords are taken from Python as `i64`, not `usize`: pyo3 refuses a negative int for a
/// `usize` with an `OverflowError` that names neither the keyword nor the value, outside the
/// exception hierarchy; here it is an `OptionError` (a `ValueError`) like every other
/// out-of-range option.
pub fn count(name: &str, value: i64) -> PyResult<usize> {
    usize::try_from(value).map_err(|_| {
        option_error(format!(
            "{name} must be a non-negative integer, got {value}"
        ))
    })
}

/// [`count`] of a keyword that may be absent.
pub fn opt_count(name: &str, value: Option<i64>) -> PyResult<Option<usize>> {
    value.map(|v| count(name, v)).transpose()
}

/// The matching keywords, in the order of [`modal_core::options::match_option_specs`].
pub struct MatchKw<'a, 'py> {
    pub element: Option<&'a str>,
    pub modes: Option<f64>,
    pub search: Option<&'a str>,
    pub solver: Option<&'a str>,
    pub threshold: Option<f64>,
    pub threshold_mode: Option<&'a str>,
    pub excess: Option<bool>,
    pub paper: Option<bool>,
    pub prealign: Option<&'a str>,
    pub max_rotation: Option<f64>,
    pub refits: Option<i64>,
    pub refit_tolerance: Option<f64>,
    pub refine: Option<&'a str>,
    pub deform_modes: Option<i64>,
    pub deform_stiffness: Option<f64>,
    pub kappa: Option<f64>,
    pub center_stride: Option<i64>,
    pub position_weight: Option<f64>,
    pub cost_power: Option<f64>,
    pub common_sigma: Option<bool>,
    pub skip_rigid: Option<bool>,
    pub band: Option<i64>,
    pub material: Option<&'a Bound<'py, PyAny>>,
}

impl<'a, 'py> MatchKw<'a, 'py> {
    /// The keywords in the order of the `match` and `run` signatures, so both read them with one
    /// call.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        element: Option<&'a str>,
        modes: Option<f64>,
        search: Option<&'a str>,
        solver: Option<&'a str>,
        threshold: Option<f64>,
        threshold_mode: Option<&'a str>,
        excess: Option<bool>,
        paper: Option<bool>,
        prealign: Option<&'a str>,
        max_rotation: Option<f64>,
        refits: Option<i64>,
        refit_tolerance: Option<f64>,
        refine: Option<&'a str>,
        deform_modes: Option<i64>,
        deform_stiffness: Option<f64>,
        kappa: Option<f64>,
        center_stride: Option<i64>,
        position_weight: Option<f64>,
        cost_power: Option<f64>,
        common_sigma: Option<bool>,
        skip_rigid: Option<bool>,
        band: Option<i64>,
        material: Option<&'a Bound<'py, PyAny>>,
    ) -> Self {
        Self {
            element,
            modes,
            search,
            solver,
            threshold,
            threshold_mode,
            excess,
            paper,
            prealign,
            max_rotation,
            refits,
            refit_tolerance,
            refine,
            deform_modes,
            deform_stiffness,
            kappa,
            center_stride,
            position_weight,
            cost_power,
            common_sigma,
            skip_rigid,
            band,
            material,
        }
    }

    /// The library's parameters; `None` keywords at their defaults. Not yet validated.
    pub fn params(&self) -> PyResult<MatchParams> {
        let material = match self.material.filter(|m| !m.is_none()) {
            None => None,
            Some(m) => Some(match m.extract::<String>() {
                Ok(s) => s.parse().map_err(to_py)?,
                Err(_) => crate::model_py::parse_material(Some(m))?,
            }),
        };
        Ok(MatchOverrides {
            element: parsed(self.element)?,
            modes: self.modes,
            search: parsed(self.search)?,
            solver: parsed(self.solver)?,
            threshold: self.threshold,
            threshold_mode: parsed(self.threshold_mode)?,
            excess: self.excess,
            paper: self.paper,
            prealign: parsed(self.prealign)?,
            max_rotation: self.max_rotation,
            refits: opt_count("refits", self.refits)?,
            refit_tolerance: self.refit_tolerance,
            refine: parsed(self.refine)?,
            deform_modes: opt_count("deform_modes", self.deform_modes)?,
            deform_stiffness: self.deform_stiffness,
            kappa: self.kappa,
            center_stride: opt_count("center_stride", self.center_stride)?,
            position_weight: self.position_weight,
            cost_power: self.cost_power,
            common_sigma: self.common_sigma,
            skip_rigid: self.skip_rigid,
            band: opt_count("band", self.band)?,
            material,
        }
        .params())
    }
}

/// A word option as given: `None` when absent, else parsed by `T`'s `FromStr`.
fn parsed<T: Choice>(value: Option<&str>) -> PyResult<Option<T>> {
    value.map(|s| T::parse_word(s).map_err(to_py)).transpose()
}

/// `pitch_mm=`: a number (square sensels) or an `(x, y)` pair.
pub fn pitch(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<[f64; 2]>> {
    let Some(v) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    // A string would read as a sequence of characters.
    if !v.is_instance_of::<PyString>() {
        if let Ok(x) = v.extract::<f64>() {
            return Ok(Some([x, x]));
        }
        if let Ok([x, y]) = v.extract::<Vec<f64>>().as_deref() {
            return Ok(Some([*x, *y]));
        }
    }
    Err(argument_error(
        "pitch_mm",
        "a number or an (x, y) pair of numbers (mm per sensel)",
        v,
    ))
}

/// `frames=`: a `(start, end)` pair of 0-based frame indices, end excluded, either `None`; a
/// negative index counts back from the end of the recording, as in a Python slice (resolved
/// with the frame count by [`FrameRange::resolve`], as the CLI's `--frames`).
pub fn frame_range(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<FrameRange>> {
    let Some(v) = value.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    let bound = |b: Bound<'_, PyAny>| -> Option<Option<isize>> {
        if b.is_none() {
            Some(None)
        } else if b.is_instance_of::<PyBool>() {
            None
        } else {
            b.extract::<isize>().ok().map(Some)
        }
    };
    let pair = match v.extract::<Vec<Bound<'_, PyAny>>>() {
        Ok(items) if !v.is_instance_of::<PyString>() => match <[_; 2]>::try_from(items) {
            Ok([start, end]) => bound(start).zip(bound(end)),
            Err(_) => None,
        },
        _ => None,
    };
    let (start, end) = pair.ok_or_else(|| {
        argument_error(
            "frames",
            "a (start, end) pair of 0-based frame indices, end excluded (either may be None; a \
             negative index counts back from the end, as in a slice)",
            v,
        )
    })?;
    Ok(Some(FrameRange {
        start: start.unwrap_or(0),
        end,
    }))
}

/// The unit keywords, checked.
pub fn units(
    pitch_mm: Option<&Bound<'_, PyAny>>,
    frame_rate: Option<f64>,
    units: Option<String>,
) -> PyResult<UnitOverrides> {
    let u = UnitOverrides {
        pitch_mm: pitch(pitch_mm)?,
        frame_rate,
        units,
    };
    u.validate().map_err(to_py)?;
    Ok(u)
}

/// The recording keywords of `pymodal.run`.
pub struct RecordingKw<'a, 'py> {
    pub model: Option<&'a str>,
    pub frames: Option<FrameRange>,
    pub noise: Option<f64>,
    pub smooth: Option<f64>,
    pub spacing: Option<f64>,
    pub surface_nodes: Option<i64>,
    pub iso_frame: Option<i64>,
    pub iso_levels: Option<i64>,
    pub pitch_mm: Option<&'a Bound<'py, PyAny>>,
    pub frame_rate: Option<f64>,
    pub units: Option<String>,
    pub drift_reference: Option<i64>,
}

impl RecordingKw<'_, '_> {
    /// The library's run parameters with `matching`; `None` keywords at their defaults.
    pub fn params(&self, matching: MatchParams) -> PyResult<RunParams> {
        let d = RunParams::default();
        Ok(RunParams {
            matching,
            model: word(self.model, d.model)?,
            frames: self.frames,
            noise: self.noise.or(d.noise),
            smooth: self.smooth.unwrap_or(d.smooth),
            spacing: self.spacing.unwrap_or(d.spacing),
            surface_nodes: opt_count("surface_nodes", self.surface_nodes)?
                .unwrap_or(d.surface_nodes),
            iso_frame: opt_count("iso_frame", self.iso_frame)?.or(d.iso_frame),
            iso_levels: opt_count("iso_levels", self.iso_levels)?.unwrap_or(d.iso_levels),
            units: units(self.pitch_mm, self.frame_rate, self.units.clone())?,
            drift_reference: opt_count("drift_reference", self.drift_reference)?
                .unwrap_or(d.drift_reference),
        })
    }
}

/// A table as a list of dicts keyed by column name.
pub fn table_rows<'py>(py: Python<'py>, t: &Table) -> PyResult<Bound<'py, PyList>> {
    let rows = PyList::empty(py);
    for r in &t.rows {
        let d = PyDict::new(py);
        for (k, c) in t.header.iter().zip(r) {
            d.set_item(k, cell_to_py(py, c)?)?;
        }
        rows.append(d)?;
    }
    Ok(rows)
}

/// A table cell as a Python int, float, str or None.
pub fn cell_to_py<'py>(py: Python<'py>, c: &Cell) -> PyResult<Bound<'py, PyAny>> {
    Ok(match c {
        Cell::Int(v) => v.into_pyobject(py)?.into_any(),
        Cell::Float(v, _) => v.into_pyobject(py)?.into_any(),
        Cell::Text(s) => s.into_pyobject(py)?.into_any(),
        Cell::Empty => py.None().into_bound(py),
    })
}

/// A JSON value as the equivalent Python object (dicts, lists, numbers, strings, None).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

fn spec_dicts<'py>(py: Python<'py>, specs: &[OptionSpec]) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for s in specs {
        let d = PyDict::new(py);
        d.set_item("name", s.name)?;
        let (kind, values): (&str, Vec<&str>) = match s.kind {
            OptionKind::Flag | OptionKind::NegatedFlag | OptionKind::TriState => ("bool", vec![]),
            OptionKind::Word(w) => ("word", w.to_vec()),
            OptionKind::Value => ("value", vec![]),
        };
        d.set_item("kind", kind)?;
        d.set_item("values", values)?;
        d.set_item("default", &s.default)?;
        d.set_item("help", s.help)?;
        d.set_item("cli_flags", s.cli_flags())?;
        out.append(d)?;
    }
    Ok(out)
}

/// The library's option tables: ``{"match": [...], "pair": [...], "recording": [...],
/// "units": [...], "output": [...]}``, each option a dict ``{name, kind, values, default, help,
/// cli_flags}``. ``match`` takes the "match" and "pair" options, ``run`` the "match" and
/// "recording" ones (which include "units"), ``read_recording`` the "units" ones, ``batch`` the
/// "output" ones besides those of ``run``.
#[pyfunction]
fn _options<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "match",
        spec_dicts(py, &modal_core::options::match_option_specs())?,
    )?;
    d.set_item(
        "pair",
        spec_dicts(py, &modal_core::options::pair_option_specs())?,
    )?;
    d.set_item(
        "recording",
        spec_dicts(py, &pedo_io::sequence::recording_option_specs())?,
    )?;
    d.set_item(
        "units",
        spec_dicts(py, &pedo_io::units::unit_option_specs())?,
    )?;
    d.set_item(
        "output",
        spec_dicts(py, &pedo_io::tables::output_option_specs())?,
    )?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_options, m)?)?;
    Ok(())
}
