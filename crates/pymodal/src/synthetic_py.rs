//! `pymodal.SyntheticWalk`: a synthetic recording with a known motion, and its ground truth.

use numpy::{PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pedo_io::synthetic::SyntheticWalk;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::errors::to_py;
use crate::io_py::PyRecording;
use crate::options_py::{count, opt_count};
use crate::pickling::{Reader, Writer};

/// A foot-like pressure field warped smoothly in time (translation towards the toes, rotation,
/// widening of the forefoot) with the true map from frame-0 coordinates to frame ``t`` known.
///
/// Keywords (all optional; lengths in sensels, angles in degrees): ``frames`` (120), ``rows``
/// (84), ``cols`` (40), ``translation`` ((dx, dy) reached at the last frame; (0, -10)),
/// ``rotation`` (12), ``spread`` (relative forefoot widening at the last frame; 0.15),
/// ``noise`` (threshold in kPa; 10), ``pitch_mm`` (5), ``frame_rate`` (Hz; 100).
///
/// ``recording()`` is the :class:`Recording`; ``true_positions(t, points)`` maps an (n, 2) array
/// of frame-0 (x, y) points to frame ``t``; ``reference_positions(t, points)`` is its inverse.
#[pyclass(name = "SyntheticWalk", module = "pymodal", frozen)]
pub struct PySyntheticWalk {
    inner: SyntheticWalk,
}

fn map_points<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    f: impl Fn([f64; 2]) -> [f64; 2],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    if points.shape()[1] != 2 {
        return Err(crate::errors::input_error(format!(
            "points must be an (n, 2) array of (x, y) coordinates, got {}",
            crate::arrays::array_text(points.shape())
        )));
    }
    let a = points.as_array();
    let out: Vec<Vec<f64>> = a
        .rows()
        .into_iter()
        .map(|r| f([r[0], r[1]]).to_vec())
        .collect();
    if out.is_empty() {
        return Ok(PyArray2::zeros(py, [0, 2], false));
    }
    Ok(PyArray2::from_vec2(py, &out)?)
}

impl PySyntheticWalk {
    /// Every parameter of the walk, for `__reduce__`.
    fn state(&self) -> Writer {
        let w = &self.inner;
        let mut out = Writer::new();
        out.usize(w.frames).usize(w.rows).usize(w.cols);
        for v in [
            w.translation[0],
            w.translation[1],
            w.rotation_deg,
            w.spread,
            w.noise_kpa,
            w.pitch_mm,
            w.frame_rate_hz,
        ] {
            out.f64(v);
        }
        out
    }

    /// The inverse of [`Self::state`].
    pub(crate) fn restore(state: &[u8]) -> PyResult<Self> {
        let mut r = Reader::new("SyntheticWalk", state)?;
        let inner = SyntheticWalk {
            frames: r.usize()?,
            rows: r.usize()?,
            cols: r.usize()?,
            translation: [r.f64()?, r.f64()?],
            rotation_deg: r.f64()?,
            spread: r.f64()?,
            noise_kpa: r.f64()?,
            pitch_mm: r.f64()?,
            frame_rate_hz: r.f64()?,
        };
        r.finish()?;
        inner.validate().map_err(to_py)?;
        Ok(Self { inner })
    }
}

#[pymethods]
impl PySyntheticWalk {
    #[new]
    #[pyo3(signature = (*, frames=None, rows=None, cols=None, translation=None, rotation=None,
        spread=None, noise=None, pitch_mm=None, frame_rate=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        frames: Option<i64>,
        rows: Option<i64>,
        cols: Option<i64>,
        translation: Option<(f64, f64)>,
        rotation: Option<f64>,
        spread: Option<f64>,
        noise: Option<f64>,
        pitch_mm: Option<f64>,
        frame_rate: Option<f64>,
    ) -> PyResult<Self> {
        let d = SyntheticWalk::default();
        let inner = SyntheticWalk {
            frames: opt_count("frames", frames)?.unwrap_or(d.frames),
            rows: opt_count("rows", rows)?.unwrap_or(d.rows),
            cols: opt_count("cols", cols)?.unwrap_or(d.cols),
            translation: translation.map_or(d.translation, |(x, y)| [x, y]),
            rotation_deg: rotation.unwrap_or(d.rotation_deg),
            spread: spread.unwrap_or(d.spread),
            noise_kpa: noise.unwrap_or(d.noise_kpa),
            pitch_mm: pitch_mm.unwrap_or(d.pitch_mm),
            frame_rate_hz: frame_rate.unwrap_or(d.frame_rate_hz),
        };
        inner.validate().map_err(to_py)?;
        Ok(Self { inner })
    }

    /// The synthetic recording (kPa, with pitch, frame rate and noise threshold).
    fn recording(&self, py: Python<'_>) -> PyResult<PyRecording> {
        let w = self.inner.clone();
        let rec = crate::pool::detach(py, move || w.recording()).map_err(to_py)?;
        Ok(PyRecording::wrap(rec))
    }

    /// Where the frame-0 points (n, 2; x = column, y = row) lie in frame ``t``.
    fn true_positions<'py>(
        &self,
        py: Python<'py>,
        t: i64,
        points: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = count("t", t)?;
        map_points(py, points, |p| self.inner.true_position(t, p))
    }

    /// Where the frame-``t`` points (n, 2) lay in frame 0.
    fn reference_positions<'py>(
        &self,
        py: Python<'py>,
        t: i64,
        points: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = count("t", t)?;
        map_points(py, points, |p| self.inner.reference_position(t, p))
    }

    /// Number of frames of the recording.
    #[getter]
    fn frames(&self) -> usize {
        self.inner.frames
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        self.state().reduce(py, "SyntheticWalk")
    }
    /// Equal when every parameter is the same.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        self.state()
            .same_as(other.cast::<Self>().ok().map(|o| o.get().state()))
    }
    fn __hash__(&self) -> u64 {
        self.state().digest()
    }

    /// The constructor call that makes this walk, with the keywords' names.
    fn __repr__(&self) -> String {
        let w = &self.inner;
        format!(
            "SyntheticWalk(frames={}, rows={}, cols={}, translation=({:?}, {:?}), rotation={:?}, \
             spread={:?}, noise={:?}, pitch_mm={:?}, frame_rate={:?})",
            w.frames,
            w.rows,
            w.cols,
            w.translation[0],
            w.translation[1],
            w.rotation_deg,
            w.spread,
            w.noise_kpa,
            w.pitch_mm,
            w.frame_rate_hz
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySyntheticWalk>()?;
    Ok(())
}
