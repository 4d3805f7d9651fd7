//! Bindings of pedo-io: `read_recording`, `contours`, `surface`, `isocontours`.

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

use pedo_io::contour::Saddle;
use pedo_io::isobar::{isocontours as iso_rs, IsoOptions};
use pedo_io::preprocess::{Interpolation, Preprocess};
use pedo_io::surface::{surface as surface_rs, Laplacian, SurfaceOptions, ZScale};
use pedo_io::{
    contours as contours_rs, ContourMethod, ContourOptions, Format, Grid, Recording, Resample,
};

use crate::arrays::{checked_array, read_only};
use crate::errors::{argument_error, input_error, internal, option_error, to_py};
use crate::options_py::{count, opt_count};
use crate::pickling::{Reader, Writer};

/// A plantar-pressure recording read by :func:`read_recording`.
///
/// Attributes: ``frames`` (T, H, W) float32 with NaN where there is no sensor, ``pitch_mm``
/// ``(dx, dy)`` = (column spacing, row spacing) or None, ``dt_s`` (seconds per frame or None),
/// ``units`` (e.g. "kPa", None if unknown), ``sensel_area_mm2``, ``noise_threshold``, ``format``,
/// ``sensor_mask`` (H, W) bool, and the per-frame measures ``contact_area`` (mm², or sensels when
/// the pitch is unknown), ``total_force`` (N when units and pitch are known), ``peak_pressure``,
/// ``cop`` (T, 2) centre of pressure (x = column, y = row; NaN without contact), and
/// ``peak_image`` (H, W). Measures count every sensor above 0; ``measures(threshold)`` recomputes
/// them at or above another threshold. The arrays are read-only copies made at each access: read
/// ``frames = rec.frames`` once, not ``rec.frames[i]`` in a loop.
#[pyclass(name = "Recording", module = "pymodal", frozen)]
pub struct PyRecording {
    inner: Recording,
}

fn measures_dict<'py>(
    py: Python<'py>,
    rec: &Recording,
    threshold: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let ms = rec.measures(threshold);
    let d = PyDict::new(py);
    d.set_item(
        "contact_area",
        PyArray1::from_vec(py, ms.iter().map(|m| m.contact_area).collect()),
    )?;
    d.set_item(
        "total_force",
        PyArray1::from_vec(py, ms.iter().map(|m| m.total_force).collect()),
    )?;
    d.set_item(
        "peak_pressure",
        PyArray1::from_vec(py, ms.iter().map(|m| m.peak_pressure).collect()),
    )?;
    d.set_item(
        "contact_sensors",
        PyArray1::from_vec(py, ms.iter().map(|m| m.contact_sensors as i64).collect()),
    )?;
    let cop: Vec<f64> = ms
        .iter()
        .flat_map(|m| m.cop.unwrap_or([f64::NAN, f64::NAN]))
        .collect();
    let cop = Array2::from_shape_vec((ms.len(), 2), cop).map_err(internal)?;
    d.set_item("cop", cop.into_pyarray(py))?;
    Ok(d)
}

impl PyRecording {
    /// The wrapped Rust recording (for other bindings that accept a `Recording`).
    pub fn recording(&self) -> &Recording {
        &self.inner
    }

    /// A Python `Recording` holding `inner` (for other bindings that make one).
    pub(crate) fn wrap(inner: Recording) -> Self {
        Self { inner }
    }

    /// Every field of the recording, for `__reduce__`.
    fn state(&self) -> Writer {
        let r = &self.inner;
        let mut w = Writer::new();
        w.usize(r.n_frames())
            .usize(r.rows())
            .usize(r.cols())
            .f32s(&r.data())
            .bools(r.sensor_mask())
            .bool(r.pitch_mm.is_some());
        let [dx, dy] = r.pitch_mm.unwrap_or([0.0; 2]);
        w.f64(dx)
            .f64(dy)
            .opt_f64(r.sensel_area_mm2)
            .opt_f64(r.dt_s)
            .str(&r.units)
            .opt_f64(r.noise_threshold)
            .str(&r.format.map(format_name).unwrap_or_default());
        // The values below 0 the file held, when they were clipped.
        let negatives = r.negative_values();
        w.bool(r.negatives_clipped())
            .usize(negatives.count)
            .opt_f64(negatives.min);
        // Where each foot is, for a recording of both feet apart (pedar).
        w.usize(r.feet.len());
        for foot in &r.feet {
            w.str(foot.side.name())
                .usize(foot.columns.start)
                .usize(foot.columns.end);
        }
        w
    }

    /// The inverse of [`Self::state`].
    pub(crate) fn restore(state: &[u8]) -> PyResult<Self> {
        let mut r = Reader::new("Recording", state)?;
        let (t, rows, cols) = (r.usize()?, r.usize()?, r.usize()?);
        let mut rec = Recording::new(t, rows, cols, r.f32s()?, r.bools()?).map_err(to_py)?;
        let has_pitch = r.bool()?;
        let pitch = [r.f64()?, r.f64()?];
        rec.pitch_mm = has_pitch.then_some(pitch);
        rec.sensel_area_mm2 = r.opt_f64()?;
        rec.dt_s = r.opt_f64()?;
        rec.units = r.string()?;
        rec.noise_threshold = r.opt_f64()?;
        let format = r.string()?;
        let clipped = r.bool()?;
        let negatives = pedo_io::recording::NegativeValues {
            count: r.usize()?,
            min: r.opt_f64()?,
        };
        for _ in 0..r.usize()? {
            let side = match r.string()?.as_str() {
                "left" => pedo_io::regions::Side::Left,
                "right" => pedo_io::regions::Side::Right,
                other => {
                    return Err(PyValueError::new_err(format!(
                        "cannot unpickle Recording: unknown foot {other:?}"
                    )))
                }
            };
            let columns = r.usize()?..r.usize()?;
            if columns.start > columns.end || columns.end > cols {
                return Err(PyValueError::new_err(
                    "cannot unpickle Recording: a foot's columns lie outside its frames",
                ));
            }
            rec.feet.push(pedo_io::FootColumns { side, columns });
        }
        r.finish()?;
        if clipped {
            rec.mark_negatives_clipped(negatives);
        }
        // Its time axis was settled when it was first read.
        rec.settle_time_axis();
        rec.format = match format.as_str() {
            "" => None,
            name => Some(format_of_name(name).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "cannot unpickle Recording: unknown format {name:?}"
                ))
            })?),
        };
        Ok(Self { inner: rec })
    }
}

/// The name of a format in Python (`"asf"`, `"npy"`, ...).
fn format_name(f: Format) -> String {
    f.name().to_string()
}

/// The inverse of [`format_name`].
fn format_of_name(name: &str) -> Option<Format> {
    Format::from_name(name)
}

#[pymethods]
impl PyRecording {
    /// A recording from any array: MATLAB (``scipy.io.loadmat``), HDF5 (``h5py``), NumPy, ...
    ///
    /// Parameters
    /// ----------
    /// frames : (T, H, W) or (H, W) array of pressures; NaN marks a sensel with no sensor
    ///     (unless ``mask`` is given).
    /// pitch_mm : float or (x, y), optional — sensor pitch in mm.
    /// frame_rate : float, optional — frames per second (Hz).
    /// units : str, optional — pressure units (``"kPa"``, ``"N/cm2"``, ``"psi"``, ...; the units
    ///     ``run(units=...)`` accepts); forces are in N when units and pitch are known.
    /// time_axis : ``"first"`` or ``"last"``, optional — which axis of a 3-D array is time:
    ///     ``"last"`` for (H, W, T) arrays (as MATLAB stores them), transposed here. Unset, an
    ///     array that looks time-last (first two axes at most 256, the last at least 64 and 3
    ///     times as long as each) is refused with a :class:`FormatError` naming both readings.
    /// clip_negative : bool, optional — set values below 0 to 0 (by default kept and counted:
    ///     :attr:`negative_values`).
    /// mask : (H, W) bool array, optional — True where a sensor exists.
    ///
    /// Raises :class:`InputError` (a ``ValueError``) for arrays of the wrong shape or infinite
    /// values, :class:`FormatError` for an array that looks time-last when ``time_axis`` is not
    /// given, :class:`OptionError` for a non-positive pitch or frame rate or unknown units.
    // The unit keywords are spelled here, not taken from `crate::keywords` as the free
    // functions' are: `#[pymethods]` sees no method a macro makes. The stub's keywords are
    // generated from the declaration and `test_stubs.py` checks this signature against them.
    #[staticmethod]
    #[pyo3(signature = (frames, *, pitch_mm=None, frame_rate=None, units=None, time_axis=None, clip_negative=None, mask=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_array(
        py: Python<'_>,
        frames: &Bound<'_, PyAny>,
        pitch_mm: Option<&Bound<'_, PyAny>>,
        frame_rate: Option<&Bound<'_, PyAny>>,
        units: Option<&Bound<'_, PyAny>>,
        time_axis: Option<&Bound<'_, PyAny>>,
        clip_negative: Option<&Bound<'_, PyAny>>,
        mask: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let (t, h, w, data) = frames_of(py, frames)?;
        let mask = match mask {
            None => None,
            Some(m) => {
                let np = py.import("numpy")?;
                let m = np
                    .call_method1("asarray", (m, np.getattr("bool_")?))
                    .map_err(|_| argument_error("mask", "an (H, W) array of bools", m))?;
                let shape: Vec<usize> = m.getattr("shape")?.extract()?;
                if shape != [h, w] {
                    return Err(input_error(format!(
                        "mask has shape {shape:?}, the frames are {h} x {w}"
                    )));
                }
                let flat: Vec<bool> = m.call_method0("ravel")?.call_method0("tolist")?.extract()?;
                Some(flat)
            }
        };
        // Checked like `run(units=...)`: a misspelt unit would silently turn forces in N into
        // the values' sum times mm².
        let given = [
            ("pitch_mm", pitch_mm),
            ("frame_rate", frame_rate),
            ("units", units),
            ("time_axis", time_axis),
            ("clip_negative", clip_negative),
        ];
        let overrides = crate::options_py::units(|name| {
            given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v)
        })?;
        let mut rec = Recording::from_array(t, h, w, data, mask).map_err(to_py)?;
        overrides.apply(&mut rec).map_err(to_py)?;
        Ok(Self { inner: rec })
    }

    /// (T, H, W) float32 pressure frames, NaN where there is no sensor.
    #[getter]
    fn frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let r = &self.inner;
        // A recording held sparsely may be far larger dense: an error, never an abort.
        let values = r.try_frames_with_nan().map_err(crate::errors::to_py)?;
        let a =
            Array3::from_shape_vec((r.n_frames(), r.rows(), r.cols()), values).map_err(internal)?;
        read_only(a.into_pyarray(py))
    }
    /// The values below 0 at existing sensors over every frame, as the file held them:
    /// ``{"count": int, "min": float or None, "clipped": bool}`` (``clipped``: set to 0 by
    /// ``clip_negative=True``). A pressure is not negative: these are an offset or a subtracted
    /// baseline. Measures count only values above 0.
    #[getter]
    fn negative_values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let n = self.inner.negative_values();
        let d = PyDict::new(py);
        d.set_item("count", n.count)?;
        d.set_item("min", n.min)?;
        d.set_item("clipped", self.inner.negatives_clipped())?;
        Ok(d)
    }

    /// The columns ``(start, end)`` of each foot's sensor when the frames hold both feet apart
    /// (pedar's two insoles side by side), by foot: ``{"left": (0, 12), "right": (14, 26)}``;
    /// empty for a single sensor (a plate), whose feet the file does not tell apart.
    #[getter]
    fn feet<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for f in &self.inner.feet {
            d.set_item(f.side.name(), (f.columns.start, f.columns.end))?;
        }
        Ok(d)
    }

    /// (H, W) bool, True where a sensor exists.
    #[getter]
    fn sensor_mask<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<bool>>> {
        let r = &self.inner;
        let a = Array2::from_shape_vec((r.rows(), r.cols()), r.sensor_mask().to_vec())
            .map_err(internal)?;
        read_only(a.into_pyarray(py))
    }
    /// ``(dx, dy)`` = (column spacing, row spacing) in mm, or None when the file does not say.
    #[getter]
    fn pitch_mm(&self) -> Option<(f64, f64)> {
        self.inner.pitch_mm.map(|p| (p[0], p[1]))
    }
    /// Seconds between frames, or None when unknown.
    #[getter]
    fn dt_s(&self) -> Option<f64> {
        self.inner.dt_s
    }
    /// Pressure units as the file states them (e.g. ``"kPa"``, ``"N/cm²"``), or None when it
    /// states none (as ``summary.json``'s ``pressure_units`` and the study table).
    #[getter]
    fn units(&self) -> Option<&str> {
        self.inner.known_units()
    }
    /// Area of one sensor in mm²: the stated area, else ``dx * dy``, else None.
    #[getter]
    fn sensel_area_mm2(&self) -> Option<f64> {
        self.inner.sensel_area()
    }
    /// The file's own noise threshold (Tekscan ``NOISE_THRESHOLD``) in its units, or None.
    #[getter]
    fn noise_threshold(&self) -> Option<f64> {
        self.inner.noise_threshold
    }
    /// The format read: ``"asf"``, ``"lst"``, ``"csv"``, ``"npy"``, ``"png"`` or ``"tiff"``; None
    /// when built in memory.
    #[getter]
    fn format(&self) -> Option<String> {
        self.inner.format.map(format_name)
    }
    /// Number of frames T.
    #[getter]
    fn n_frames(&self) -> usize {
        self.inner.n_frames()
    }
    /// ``(T, H, W)``.
    #[getter]
    fn shape(&self) -> (usize, usize, usize) {
        (self.inner.n_frames(), self.inner.rows(), self.inner.cols())
    }
    /// (H, W) float64: per sensor the maximum over all frames.
    #[getter]
    fn peak_image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = self.inner.peak_image();
        let a =
            Array2::from_shape_vec((g.rows(), g.cols()), g.data().to_vec()).map_err(internal)?;
        read_only(a.into_pyarray(py))
    }
    /// (T,) float64 contact area per frame: sensors above 0 times the sensor area in mm², in
    /// sensels when the area is unknown.
    #[getter]
    fn contact_area<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(
            measures_dict(py, &self.inner, 0.0)?
                .as_any()
                .get_item("contact_area")?,
        )
    }
    /// (T,) float64 total force per frame: in N when units and sensor area are known; else the
    /// values' sum times the sensel area in mm² (the file's units × mm²), or the plain sum when the
    /// pitch is unknown too (``run``'s frames table names these ``total_load_mm2`` and
    /// ``total_load_sensels``).
    #[getter]
    fn total_force<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(
            measures_dict(py, &self.inner, 0.0)?
                .as_any()
                .get_item("total_force")?,
        )
    }
    /// (T,) float64 highest pressure per frame, in the file's units (``units``; ``run``'s
    /// frames table converts it to kPa when they are known).
    #[getter]
    fn peak_pressure<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(
            measures_dict(py, &self.inner, 0.0)?
                .as_any()
                .get_item("peak_pressure")?,
        )
    }
    /// (T, 2) float64 centre of pressure ``(x, y)`` per frame in sensel units, NaN for empty
    /// frames.
    #[getter]
    fn cop<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(
            measures_dict(py, &self.inner, 0.0)?
                .as_any()
                .get_item("cop")?,
        )
    }
    /// Per-frame measures of the sensors in contact at ``threshold``: those with a value above 0
    /// and at or above ``threshold`` (as ``frames.csv`` counts them). A dict of arrays
    /// ``contact_sensors``, ``contact_area``, ``total_force`` and ``cop`` over those sensors, and
    /// ``peak_pressure`` (each frame's highest value, whatever the threshold).
    #[pyo3(signature = (threshold=0.0))]
    fn measures<'py>(&self, py: Python<'py>, threshold: f64) -> PyResult<Bound<'py, PyDict>> {
        measures_dict(py, &self.inner, threshold)
    }
    /// The measures gait researchers report of frames ``frames`` (``(start, end)``, every frame
    /// by default), a sensel loaded above 0 and at or above ``threshold`` (docs/measures.md):
    /// a dict of ``peak``, ``pti`` and ``mean`` (H, W) float64 images (NaN where there is no
    /// sensor; ``mean`` over the frames each sensel is loaded, 0 where it never is), ``values``
    /// (``peak_pressure``, ``pti_max``, ``peak_force`` or ``peak_load``, ``fti`` or
    /// ``load_time_integral``, ``contact_time``, ``max_contact_area``: floats), ``units`` (the
    /// unit of each value: kPa, kPa·s, N, N·s, s, mm² when the recording says so, else the
    /// file's units, frames or sensels), ``frames``, ``contact_frames`` (the first and last frame
    /// above the contact force threshold) and ``contact_force_threshold``; ``stances``, a list
    /// with a dict per stance (foot contact, docs/measures.md): ``frames`` (first and last,
    /// inclusive), ``complete`` (False when it touches the first or last frame measured),
    /// ``values`` (``start_time``, ``end_time``, ``contact_time``, ``peak_force`` or
    /// ``peak_load``, ``fti`` or ``load_time_integral``, ``peak_pressure``,
    /// ``max_contact_area``), ``units`` and ``curves``: float64 arrays of 101 points over 0–100 %
    /// of contact, ``percent``, ``contact_area``, ``total_force``, ``peak_pressure``, ``cop_x``
    /// and ``cop_y`` (sensels; NaN only when no frame of the stance has load); ``feet``, for a
    /// recording of both feet apart (pedar's two insoles; empty otherwise), ``"left"`` and
    /// ``"right"`` to each foot's own dict of the same keys (its images NaN outside its sensels,
    /// its stances found from its own force) and its ``columns`` ``(start, end)``; a foot never
    /// loaded in the frames is absent. The same as a run folder's ``peak.npy``, ``pti.npy``,
    /// ``mean.npy``, ``measures.json`` and ``curves.csv``.
    /// An ``InputError`` when no sensor is loaded in any frame.
    #[pyo3(signature = (threshold=0.0, frames=None))]
    fn gait_measures<'py>(
        &self,
        py: Python<'py>,
        threshold: f64,
        frames: Option<(usize, usize)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let range = frames.map_or(0..self.inner.n_frames(), |(a, b)| a..b);
        let rec = &self.inner;
        let m = crate::pool::detach(py, || {
            pedo_io::measures::Measures::of_recording(rec, threshold, range)
        })
        .map_err(to_py)?;
        let d = gait_dict(py, &m)?;
        let feet = PyDict::new(py);
        for foot in &m.feet {
            let f = gait_dict(py, &foot.measures)?;
            f.set_item("columns", (foot.columns.start, foot.columns.end))?;
            feet.set_item(foot.side.name(), f)?;
        }
        d.set_item("feet", feet)?;
        Ok(d)
    }
    /// The footprint's anatomical regions and each one's measures (docs/measures.md,
    /// Regions): ``rule`` ``"coarse"`` (hindfoot, midfoot, forefoot, toes) or ``"fine"``
    /// (heel_medial, heel_lateral, midfoot, mh1, mh2, mh3_5, hallux, lesser_toes), over
    /// ``frames=(start, end)`` (all by default), a sensel loaded above 0 and at or above
    /// ``threshold``. A dict: ``labels`` (int array rows × cols, 0 outside the footprint, ``k``
    /// for ``names[k - 1]``), ``names``, ``values`` (region → measure → value), ``units``
    /// (measure → unit), ``side`` (``"left"``/``"right"``), ``heel_toe_cue``, ``axis``
    /// (``heel_mm``, ``toe_mm``, ``direction``, ``medial``, ``length_mm``). The same as a run
    /// folder's ``regions.npy`` and ``regions.json``. With both feet apart (``Recording.feet``,
    /// pedar's insoles) each foot has its own regions: ``sides`` gives each name's foot,
    /// ``values`` is keyed ``"left/hindfoot"``, each foot's shares are of its own impulse, and
    /// there is no single ``side`` or ``axis``. An ``InputError`` when the footprint is too
    /// small to divide; ``NoObjectError`` when there is none.
    #[pyo3(signature = (rule="fine", threshold=0.0, frames=None))]
    fn regions<'py>(
        &self,
        py: Python<'py>,
        rule: &str,
        threshold: f64,
        frames: Option<(usize, usize)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        use pedo_io::regions::{recording_regions, RegionRule};
        let rule = match rule {
            "coarse" => RegionRule::Coarse,
            "fine" => RegionRule::Fine,
            other => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "rule must be \"coarse\" or \"fine\", got {other:?}"
                )))
            }
        };
        let range = frames.map_or(0..self.inner.n_frames(), |(a, b)| a..b);
        let rec = &self.inner;
        let (masks, values, m) = crate::pool::detach(py, || {
            let m = pedo_io::measures::Measures::of_recording(rec, threshold, range.clone())?;
            let (masks, values) = recording_regions(rec, threshold, range, rule)?;
            Ok::<_, pedo_io::IoError>((masks, values, m))
        })
        .map_err(to_py)?;
        let labels: Vec<i64> = masks.labels.iter().map(|&l| i64::from(l)).collect();
        let a = Array2::from_shape_vec((masks.rows, masks.cols), labels).map_err(internal)?;
        let d = PyDict::new(py);
        d.set_item("labels", read_only(a.into_pyarray(py).into_any())?)?;
        d.set_item("names", masks.names.clone())?;
        if !masks.sides.is_empty() {
            // Both feet apart: each region's foot; values are keyed "left/hindfoot".
            let sides: Vec<&str> = masks.sides.iter().map(|s| s.name()).collect();
            d.set_item("sides", sides)?;
        }
        let (per, units) = (PyDict::new(py), PyDict::new(py));
        for q in pedo_output::region_quantities(&m, &values) {
            let region = q.key();
            if per.get_item(&region)?.is_none() {
                per.set_item(&region, PyDict::new(py))?;
            }
            per.get_item(&region)?
                .ok_or_else(|| internal("region entry"))?
                .set_item(q.measure, q.value)?;
            units.set_item(q.measure, q.unit)?;
        }
        d.set_item("values", per)?;
        d.set_item("units", units)?;
        if let Some(axis) = &masks.axis {
            d.set_item("side", axis.side.name())?;
            d.set_item("heel_toe_cue", axis.heel_toe_cue.name())?;
            let ax = PyDict::new(py);
            ax.set_item("heel_mm", (axis.heel[0], axis.heel[1]))?;
            ax.set_item("toe_mm", (axis.toe[0], axis.toe[1]))?;
            ax.set_item("direction", (axis.direction[0], axis.direction[1]))?;
            ax.set_item("medial", (axis.medial[0], axis.medial[1]))?;
            ax.set_item("length_mm", axis.length)?;
            d.set_item("axis", ax)?;
        }
        Ok(d)
    }
    fn __len__(&self) -> usize {
        self.inner.n_frames()
    }
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        self.state().reduce(py, "Recording")
    }
    /// Equal when every value is the same, bit for bit (as after a pickle round trip).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        self.state()
            .same_as(other.cast::<Self>().ok().map(|o| o.get().state()))
    }
    fn __hash__(&self) -> u64 {
        self.state().digest()
    }
    /// ``Recording(frames=TxHxW, pitch_mm=(dx, dy) or None, dt_s=... or None, units='...' or None)``,
    /// the values as Python writes them.
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let r = &self.inner;
        let repr = |v: Bound<'_, PyAny>| -> PyResult<String> { Ok(v.repr()?.to_string()) };
        let pitch_mm = r.pitch_mm.map(|[x, y]| (x, y));
        Ok(format!(
            "Recording(frames={}x{}x{}, pitch_mm={}, dt_s={}, units={})",
            r.n_frames(),
            r.rows(),
            r.cols(),
            repr(pitch_mm.into_pyobject(py)?.into_any())?,
            repr(r.dt_s.into_pyobject(py)?.into_any())?,
            repr(r.known_units().into_pyobject(py)?.into_any())?,
        ))
    }
}

/// The measures `m` as [`PyRecording::gait_measures`] gives them, without the feet.
fn gait_dict<'py>(
    py: Python<'py>,
    m: &pedo_io::measures::Measures,
) -> PyResult<Bound<'py, PyDict>> {
    let image = |v: &[f64]| -> PyResult<Bound<'py, PyAny>> {
        let a = Array2::from_shape_vec((m.rows, m.cols), v.to_vec()).map_err(internal)?;
        read_only(a.into_pyarray(py).into_any())
    };
    let d = PyDict::new(py);
    d.set_item("peak", image(&m.peak)?)?;
    d.set_item("pti", image(&m.pti)?)?;
    d.set_item("mean", image(&m.mean)?)?;
    let (values, units) = (PyDict::new(py), PyDict::new(py));
    for q in m.quantities() {
        values.set_item(q.name, q.value)?;
        units.set_item(q.name, q.unit)?;
    }
    d.set_item("values", values)?;
    d.set_item("units", units)?;
    d.set_item("frames", (m.frames.start, m.frames.end))?;
    d.set_item("contact_frames", m.values.contact_frames)?;
    d.set_item("contact_force_threshold", m.values.contact_force_threshold)?;
    d.set_item("stances", stances_list(py, m)?)?;
    Ok(d)
}

/// The stances of `m` as [`PyRecording::gait_measures`] gives them.
fn stances_list<'py>(
    py: Python<'py>,
    m: &pedo_io::measures::Measures,
) -> PyResult<Bound<'py, pyo3::types::PyList>> {
    let list = pyo3::types::PyList::empty(py);
    let array = |v: Vec<f64>| read_only(PyArray1::from_vec(py, v).into_any());
    let opt = |v: &[Option<f64>]| v.iter().map(|x| x.unwrap_or(f64::NAN)).collect::<Vec<_>>();
    for s in &m.stances {
        let d = PyDict::new(py);
        d.set_item("frames", (s.stance.first, s.stance.last))?;
        d.set_item("complete", s.stance.complete)?;
        let (values, units) = (PyDict::new(py), PyDict::new(py));
        for q in s.quantities(&m.units) {
            values.set_item(q.name, q.value)?;
            units.set_item(q.name, q.unit)?;
        }
        d.set_item("values", values)?;
        d.set_item("units", units)?;
        let c = &s.curves;
        let curves = PyDict::new(py);
        let percent = (0..pedo_io::stances::CURVE_POINTS)
            .map(|p| p as f64)
            .collect();
        curves.set_item("percent", array(percent)?)?;
        curves.set_item("contact_area", array(c.area.clone())?)?;
        curves.set_item("total_force", array(c.force.clone())?)?;
        curves.set_item("peak_pressure", array(c.peak_pressure.clone())?)?;
        curves.set_item("cop_x", array(opt(&c.cop_x))?)?;
        curves.set_item("cop_y", array(opt(&c.cop_y))?)?;
        d.set_item("curves", curves)?;
        list.append(d)?;
    }
    Ok(list)
}

/// `read_recording`, its keywords from the one declaration of each option (`crate::keywords`):
/// the units and how the file is read.
macro_rules! define_read_recording {
    (
        match: [$($_m:ident),*], match_doc: $_md:literal,
        pair: [$($_p:ident),*], pair_doc: $_pd:literal,
        recording: [$($_r:ident),*], recording_doc: $_rd:literal,
        output: [$($_o:ident),*], output_doc: $_od:literal,
        units: [$($u:ident),*], units_doc: $_ud:literal,
        read: [$($rd:ident),*], read_doc: $_rdd:literal,
        $($rest:tt)*
    ) => {
        /// Read a pressure recording: Tekscan ``.asf``, novel emed ``.lst``, CSV grid, NumPy ``.npy``
        /// (2-D or 3-D), PNG/TIFF (8/16-bit grayscale), a folder of images, or a numbered sequence
        /// (``"walk_%03d.png"``). The format is detected from the content and the extension.
        ///
        /// ``pitch_mm`` (mm per sensel, a number or (x, y)) and ``frame_rate`` (Hz) set or override
        /// what the file says, as ``--pitch-mm`` and ``--frame-rate`` do on the command line, and
        /// ``units`` the pressure units (``--units``: kPa, Pa, MPa, N/cm², N/mm², psi, bar or mmHg)
        /// for formats that store none (``.npy``, ``.npz``, CSV), so that forces come out in newtons;
        /// ``layout`` is a pedar sensor-layout table (``--layout``; default: the bundled insole).
        ///
        /// Raises ``FileNotFoundError`` (an ``OSError``) if the file does not exist, other ``OSError``
        /// subclasses if it cannot be read, and :class:`FormatError` (a ``ValueError``) naming the file
        /// (and line, for text formats) if it is corrupt, truncated or of no known format.
        #[pyfunction]
        #[pyo3(signature = (path, *, $($u = None,)* $($rd = None),*))]
        #[allow(clippy::too_many_arguments)]
        fn read_recording(
            py: Python<'_>,
            path: PathBuf,
            $($u: Option<&Bound<'_, PyAny>>,)*
            $($rd: Option<&Bound<'_, PyAny>>,)*
        ) -> PyResult<PyRecording> {
            let given = [$((stringify!($u), $u),)* $((stringify!($rd), $rd),)*];
            let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
            let units = crate::options_py::units(get)?;
            let opts: pedo_io::formats::ReadOptions = crate::options_py::option_set(get)?;
            let mut rec = crate::pool::detach(py, || pedo_io::formats::read_recording_with(&path, &opts))
                .map_err(to_py)?;
            units
                .apply(&mut rec)
                .map_err(|e| to_py(e.of_input(&path.display().to_string())))?;
            Ok(PyRecording { inner: rec })
        }
    };
}

crate::keywords::with_option_keywords!(define_read_recording);

/// A (T, H, W) or (H, W) array-like as `(T, H, W, row-major f32 data)`.
fn frames_of(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
) -> PyResult<(usize, usize, usize, Vec<f32>)> {
    const EXPECTED: &str = "a (T, H, W) or (H, W) array of pressures";
    let fits = |s: &[usize]| matches!(s.len(), 2 | 3);
    let arr = checked_array(py, frames, "frames", EXPECTED, "float32", fits)?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    let (t, h, w) = match shape.as_slice() {
        [h, w] => (1, *h, *w),
        [t, h, w] => (*t, *h, *w),
        _ => return Err(internal("frames: a shape checked to be 2-D or 3-D")),
    };
    let flat = arr.call_method0("ravel")?;
    let flat: numpy::PyReadonlyArray1<'_, f32> = flat.extract()?;
    let data = flat.as_slice().map_err(internal)?.to_vec();
    // A finite value beyond float32's range became ±inf in the cast: say so, rather than
    // letting the recording call it "not finite".
    if let Some(k) = data.iter().position(|v| v.is_infinite()) {
        let np = py.import("numpy")?;
        let given: f64 = np
            .call_method1("asarray", (frames,))?
            .call_method0("ravel")?
            .get_item(k)?
            .extract()
            .unwrap_or(f64::INFINITY);
        if given.is_finite() {
            let (frame, row, col) = (k / (h * w), k / w % h, k % w);
            return Err(input_error(format!(
                "frames: {given:e} at frame {frame}, row {row}, column {col} is beyond the \
                 float32 range of a recording (±3.4e38)"
            )));
        }
    }
    Ok((t, h, w, data))
}

/// A 2-D array-like as a grid; NaN (no sensor) reads as 0, infinities are rejected.
fn grid_of(py: Python<'_>, frame: &Bound<'_, PyAny>) -> PyResult<Grid> {
    const EXPECTED: &str = "a 2-D (H, W) array of pressures";
    let arr = checked_array(py, frame, "frame", EXPECTED, "float64", |s| s.len() == 2)?;
    let arr: PyReadonlyArray2<'_, f64> = arr.extract()?;
    let (rows, cols) = (arr.shape()[0], arr.shape()[1]);
    let data: Vec<f64> = arr
        .as_slice()
        .map_err(internal)?
        .iter()
        .map(|&v| if v.is_nan() { 0.0 } else { v })
        .collect();
    Grid::new(rows, cols, data).map_err(to_py)
}

fn preprocess_of(
    threshold: Option<f64>,
    smooth: Option<f64>,
    upsample: Option<usize>,
    interpolation: &str,
) -> PyResult<Preprocess> {
    let interp = match interpolation {
        "bilinear" => Interpolation::Bilinear,
        "bicubic" => Interpolation::Bicubic,
        o => {
            return Err(option_error(format!(
                "interpolation must be \"bilinear\" or \"bicubic\", got {o:?}"
            )));
        }
    };
    Ok(Preprocess {
        threshold,
        sigma: smooth,
        upsample: upsample.map(|k| (k, interp)),
    })
}

fn resample_of(n_points: Option<usize>, spacing: Option<f64>) -> PyResult<Resample> {
    match (n_points, spacing) {
        (Some(_), Some(_)) => Err(input_error("give n_points or spacing, not both")),
        (Some(n), None) => Ok(Resample::Points(n)),
        (None, Some(s)) => Ok(Resample::Spacing(s)),
        (None, None) => Ok(Resample::None),
    }
}

fn saddle_of(s: &str) -> PyResult<Saddle> {
    match s {
        "low" => Ok(Saddle::LowConnected),
        "high" => Ok(Saddle::HighConnected),
        "average" => Ok(Saddle::Average),
        o => Err(option_error(format!(
            "fully_connected must be \"low\", \"high\" or \"average\", got {o:?}"
        ))),
    }
}

fn points_array<'py, const D: usize>(
    py: Python<'py>,
    pts: &[[f64; D]],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = pts.iter().flatten().copied().collect();
    Ok(Array2::from_shape_vec((pts.len(), D), flat)
        .map_err(internal)?
        .into_pyarray(py))
}

/// Closed contours of a pressure frame as a list of (k, 2) float64 arrays of ``(x, y)`` =
/// (column, row) in sensels, counter-clockwise in (x, y), the first point not repeated.
///
/// ``level``: contour level in the frame's units (default: half the smallest positive value,
/// the contact boundary). ``n_points`` / ``spacing``: resample uniformly in arc length, to
/// ``n_points`` nodes or one node every ``spacing`` sensels (default: no resampling, the
/// marching-squares vertices; ``pedomatch run``/``match`` and :func:`run` use ``spacing=1.0``,
/// so pass it to get their nodes). ``smooth``: Gaussian σ in sensels. ``threshold``: values
/// below it (frame's units) are set to 0 first. ``upsample``: integer factor (coordinates stay
/// in input sensels), ``interpolation`` "bilinear" or "bicubic". ``method``: "marching"
/// (sub-sensel marching squares) or "chain" (the paper's hysteresis + boundary tracking;
/// ``high`` is its upper threshold). ``fully_connected``: saddle rule as in
/// ``skimage.measure.find_contours``. ``include_holes``: keep contours around holes.
/// ``min_area``: drop smaller contours (sensels², i.e. in units of one sensel's area).
///
/// Raises :class:`InputError` naming ``frame`` if it is not a 2-D array of numbers, or if both
/// ``n_points`` and ``spacing`` are given; :class:`OptionError` for an unknown ``method``,
/// ``interpolation`` or ``fully_connected``.
/// NaN in the frame means no sensor (read as 0); the frame is surrounded by zeros so every
/// contour closes.
#[pyfunction]
#[pyo3(signature = (frame, *, level=None, n_points=None, spacing=None, smooth=None, threshold=None,
    upsample=None, interpolation="bilinear", method="marching", high=None, fully_connected="low",
    include_holes=true, min_area=0.0))]
#[allow(clippy::too_many_arguments)]
fn contours<'py>(
    py: Python<'py>,
    frame: &Bound<'py, PyAny>,
    level: Option<f64>,
    n_points: Option<i64>,
    spacing: Option<f64>,
    smooth: Option<f64>,
    threshold: Option<f64>,
    upsample: Option<i64>,
    interpolation: &str,
    method: &str,
    high: Option<f64>,
    fully_connected: &str,
    include_holes: bool,
    min_area: f64,
) -> PyResult<Vec<Bound<'py, PyArray2<f64>>>> {
    let grid = grid_of(py, frame)?;
    let method = match method {
        "marching" => ContourMethod::MarchingSquares {
            saddle: saddle_of(fully_connected)?,
        },
        "chain" => ContourMethod::Chain { high, refine: true },
        o => {
            return Err(option_error(format!(
                "method must be \"marching\" or \"chain\", got {o:?}"
            )));
        }
    };
    let opts = ContourOptions {
        level,
        preprocess: preprocess_of(
            threshold,
            smooth,
            opt_count("upsample", upsample)?,
            interpolation,
        )?,
        method,
        resample: resample_of(opt_count("n_points", n_points)?, spacing)?,
        min_area,
        include_holes,
        ..Default::default()
    };
    let cs = crate::pool::detach(py, || contours_rs(&grid, &opts)).map_err(to_py)?;
    cs.iter().map(|c| points_array(py, &c.points)).collect()
}

/// A brightness surface: ``points`` (n, 3) float64 and ``triangles`` (t, 3) int64 (indices into
/// ``points``, counter-clockwise in x-y).
#[pyclass(name = "Surface", module = "pymodal", frozen)]
pub struct PySurface {
    inner: pedo_io::surface::Surface,
}

impl PySurface {
    /// Points and triangles, for `__reduce__`.
    fn state(&self) -> Writer {
        let s = &self.inner;
        let mut w = Writer::new();
        w.f64s(&s.points.iter().flatten().copied().collect::<Vec<_>>())
            .usizes(
                s.triangles
                    .iter()
                    .flatten()
                    .copied()
                    .collect::<Vec<_>>()
                    .into_iter(),
            );
        w
    }

    /// The inverse of [`Self::state`].
    pub(crate) fn restore(state: &[u8]) -> PyResult<Self> {
        let mut r = Reader::new("Surface", state)?;
        let (points, triangles) = (r.f64s()?, r.usizes()?);
        r.finish()?;
        Ok(Self {
            inner: pedo_io::surface::Surface {
                points: points.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
                triangles: triangles
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
            },
        })
    }
}

#[pymethods]
impl PySurface {
    /// (n, 3) float64 nodes ``(x, y, z)``.
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        read_only(points_array(py, &self.inner.points)?)
    }
    /// (t, 3) int64 node indices, counter-clockwise in x-y.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let t = &self.inner.triangles;
        let flat: Vec<i64> = t.iter().flatten().map(|&i| i as i64).collect();
        read_only(
            Array2::from_shape_vec((t.len(), 3), flat)
                .map_err(internal)?
                .into_pyarray(py),
        )
    }
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        self.state().reduce(py, "Surface")
    }
    /// Equal when every value is the same, bit for bit (as after a pickle round trip).
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        self.state()
            .same_as(other.cast::<Self>().ok().map(|o| o.get().state()))
    }
    fn __hash__(&self) -> u64 {
        self.state().digest()
    }
    fn __repr__(&self) -> String {
        format!(
            "Surface(points={}, triangles={})",
            self.inner.points.len(),
            self.inner.triangles.len()
        )
    }
}

/// The paper's brightness surface of a frame (docs/method.md §8.3): values below ``threshold`` removed, Gaussian
/// smoothing ``smooth`` (σ px), samples above the threshold in the object's bounding rectangle
/// (every ``step`` px), Delaunay triangulation with pressure as z, decimation to ``max_nodes``
/// (hull corners kept unless ``keep_hull=False``), Laplacian smoothing (VTK semantics:
/// ``laplacian_iterations`` = 20, ``relaxation`` = 0.01; 0 iterations = none), and z rescaled to
/// the x-y range (``z_scale="xy"``, or "keep").
#[pyfunction]
#[pyo3(signature = (frame, *, threshold=None, max_nodes=None, smooth=None, step=1, keep_hull=true,
    laplacian_iterations=20, relaxation=0.01, z_scale="xy"))]
#[allow(clippy::too_many_arguments)]
fn surface(
    py: Python<'_>,
    frame: &Bound<'_, PyAny>,
    threshold: Option<f64>,
    max_nodes: Option<i64>,
    smooth: Option<f64>,
    step: i64,
    keep_hull: bool,
    laplacian_iterations: i64,
    relaxation: f64,
    z_scale: &str,
) -> PyResult<PySurface> {
    let grid = grid_of(py, frame)?;
    let (max_nodes, step) = (opt_count("max_nodes", max_nodes)?, count("step", step)?);
    let laplacian_iterations = count("laplacian_iterations", laplacian_iterations)?;
    let z_scale = match z_scale {
        "xy" => ZScale::MatchXY,
        "keep" => ZScale::Keep,
        o => {
            return Err(option_error(format!(
                "z_scale must be \"xy\" or \"keep\", got {o:?}"
            )));
        }
    };
    let opts = SurfaceOptions {
        preprocess: Preprocess {
            threshold,
            sigma: smooth,
            upsample: None,
        },
        sample_level: threshold.unwrap_or(0.0),
        step,
        max_nodes,
        keep_hull,
        laplacian: (laplacian_iterations > 0).then_some(Laplacian {
            iterations: laplacian_iterations,
            relaxation,
            ..Default::default()
        }),
        z_scale,
        ..Default::default()
    };
    let s = crate::pool::detach(py, || surface_rs(&grid, &opts)).map_err(to_py)?;
    Ok(PySurface { inner: s })
}

/// Isobaric contours: for each level, the closed level lines of the (thresholded, smoothed)
/// frame, as a list of ``(level, points)`` with points (k, 2) ``(x, y)`` or, with
/// ``three_d=True``, (k, 3) ``(x, y, level)``. Levels are visited in the order given.
#[pyfunction]
#[pyo3(signature = (frame, levels, *, smooth=None, threshold=None, three_d=false, n_points=None,
    spacing=None, include_holes=true, fully_connected="low"))]
#[allow(clippy::too_many_arguments)]
fn isocontours<'py>(
    py: Python<'py>,
    frame: &Bound<'py, PyAny>,
    levels: Vec<f64>,
    smooth: Option<f64>,
    threshold: Option<f64>,
    three_d: bool,
    n_points: Option<i64>,
    spacing: Option<f64>,
    include_holes: bool,
    fully_connected: &str,
) -> PyResult<Vec<(f64, Bound<'py, PyArray2<f64>>)>> {
    let grid = grid_of(py, frame)?;
    let opts = IsoOptions {
        preprocess: Preprocess {
            threshold,
            sigma: smooth,
            upsample: None,
        },
        saddle: saddle_of(fully_connected)?,
        resample: resample_of(opt_count("n_points", n_points)?, spacing)?,
        include_holes,
        ..Default::default()
    };
    let cs = crate::pool::detach(py, || iso_rs(&grid, &levels, &opts)).map_err(to_py)?;
    cs.iter()
        .map(|c| {
            let arr = if three_d {
                let p: Vec<[f64; 3]> = c.points.iter().map(|q| [q[0], q[1], c.level]).collect();
                points_array(py, &p)?
            } else {
                points_array(py, &c.points)?
            };
            Ok((c.level, arr))
        })
        .collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRecording>()?;
    m.add_class::<PySurface>()?;
    m.add_function(wrap_pyfunction!(read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(contours, m)?)?;
    m.add_function(wrap_pyfunction!(surface, m)?)?;
    m.add_function(wrap_pyfunction!(isocontours, m)?)?;
    Ok(())
}
