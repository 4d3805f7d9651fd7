//! `pymodal.run`: a whole recording in; the per-pair table, the matches and the node tracks out.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pedo_io::sequence::{run_sequence, ObjectModel, RunParams, SearchMode, SequenceResult};
use pedo_io::Recording;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::to_py;
use crate::match_py::PyMatch;

/// A recording from a path, a (T, H, W) or (H, W) array (NaN = no sensor), or a `Recording`.
fn recording_from(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Recording> {
    if let Ok(rec) = obj.cast::<crate::io_py::PyRecording>() {
        return Ok(rec.get().recording().clone());
    }
    if let Ok(path) = obj.extract::<std::path::PathBuf>() {
        return py.detach(|| pedo_io::read_recording(&path)).map_err(to_py);
    }
    let arr: PyReadonlyArrayDyn<'_, f32> = obj
        .call_method1("astype", ("float32",))
        .and_then(|a| a.extract())
        .map_err(|_| {
            PyValueError::new_err(
                "recording must be a path, a Recording or a (T, H, W) / (H, W) array",
            )
        })?;
    let shape = arr.shape().to_vec();
    let (t, h, w) = match shape.as_slice() {
        [h, w] => (1, *h, *w),
        [t, h, w] => (*t, *h, *w),
        _ => {
            return Err(PyValueError::new_err(format!(
                "recording array must be 2-D or 3-D, got shape {shape:?}"
            )))
        }
    };
    let data = arr.as_array().iter().copied().collect();
    Recording::from_nan_frames(t, h, w, data).map_err(to_py)
}

fn parse<T: Copy>(what: &str, value: &str, options: &[(&str, T)]) -> PyResult<T> {
    options
        .iter()
        .find(|(k, _)| *k == value)
        .map(|&(_, v)| v)
        .ok_or_else(|| {
            let names: Vec<String> = options.iter().map(|(k, _)| format!("{k:?}")).collect();
            PyValueError::new_err(format!(
                "unknown {what} {value:?}; expected one of {}",
                names.join(", ")
            ))
        })
}

fn table<'py>(py: Python<'py>, r: &SequenceResult) -> PyResult<Bound<'py, PyList>> {
    let rows = PyList::empty(py);
    for p in &r.pairs {
        let row = &p.row;
        let d = PyDict::new(py);
        d.set_item("id_a", row.id_a)?;
        d.set_item("id_b", row.id_b)?;
        d.set_item("frame_a", row.frame_a + 1)?;
        d.set_item("frame_b", row.frame_b + 1)?;
        d.set_item("nodes_a", row.nodes_a)?;
        d.set_item("nodes_b", row.nodes_b)?;
        d.set_item("local_matches", row.local_matches)?;
        d.set_item("local_percent", row.local_percent)?;
        d.set_item("optimisation_matches", row.optimisation_matches)?;
        d.set_item("optimisation_percent", row.optimisation_percent)?;
        d.set_item("excess_matches", row.excess_matches)?;
        d.set_item("mean_cost", row.mean_cost)?;
        rows.append(d)?;
    }
    Ok(rows)
}

/// Match the objects of a whole recording, frame after frame (or level after level).
///
/// Parameters are those of ``pedomatch run``: ``model`` ("contour", "surface", "isocontour"),
/// ``element`` ("gaussian", "axial"), ``modes``, ``search`` ("global", "local", "both"), ``solver``
/// ("jv", "hungarian", "simplex"), ``threshold``, ``excess``, ``paper`` (the paper's literal
/// setting), ``center_stride`` (Gaussians on every n-th node only: faster), ``frames`` ((first, last), 1-based inclusive), ``noise``, ``smooth``, ``spacing``,
/// ``surface_nodes``, ``iso_frame`` (1-based), ``iso_levels``.
///
/// Returns a dict with
///
/// - ``table``: list of dicts, one per matched pair, with the paper's columns (ids, frames, node
///   counts, local matches and %, optimisation matches and %, matches after the excess step);
/// - ``matches``: list of :class:`Match`, aligned with ``table``;
/// - ``objects``: list of dicts ``{id, frame, index, level, points}`` (``points`` (n, d) array);
/// - ``tracks``: list of (k, 1 + d) float arrays of ``(frame, x, y[, z])`` rows, one per node track;
/// - ``timings``: seconds per stage.
#[pyfunction]
#[pyo3(signature = (recording, *, model="contour", element="gaussian", modes=0.25, search="both", solver="jv",
    threshold=None, excess=true, paper=false, center_stride=1, frames=None, noise=None, smooth=0.0, spacing=1.0,
    surface_nodes=120, iso_frame=None, iso_levels=10))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    model: &str,
    element: &str,
    modes: f64,
    search: &str,
    solver: &str,
    threshold: Option<f64>,
    excess: bool,
    paper: bool,
    center_stride: usize,
    frames: Option<(usize, usize)>,
    noise: Option<f64>,
    smooth: f64,
    spacing: f64,
    surface_nodes: usize,
    iso_frame: Option<usize>,
    iso_levels: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let rec = recording_from(py, recording)?;
    let params = RunParams {
        model: parse(
            "model",
            model,
            &[
                ("contour", ObjectModel::Contour),
                ("surface", ObjectModel::Surface),
                ("isocontour", ObjectModel::Isocontour),
            ],
        )?,
        element: parse(
            "element",
            element,
            &[
                ("gaussian", modal_core::ElementKind::Gaussian),
                ("axial", modal_core::ElementKind::Axial),
            ],
        )?,
        modes,
        search: parse(
            "search",
            search,
            &[
                ("global", SearchMode::Global),
                ("local", SearchMode::Local),
                ("both", SearchMode::Both),
            ],
        )?,
        method: crate::assign_py::parse_method("solver", solver)?,
        threshold,
        excess,
        paper,
        center_stride,
        frames,
        noise,
        smooth,
        spacing,
        surface_nodes,
        iso_frame,
        iso_levels,
    };
    let options = params.to_options(&rec).map_err(to_py)?;
    let result = py
        .detach(|| run_sequence(&rec, &options, &|_, _, _| {}))
        .map_err(to_py)?;

    let out = PyDict::new(py);
    out.set_item("table", table(py, &result)?)?;
    let matches = PyList::empty(py);
    for p in &result.pairs {
        matches.append(Py::new(py, PyMatch::from_result(p.result.clone()))?)?;
    }
    out.set_item("matches", matches)?;
    let objects = PyList::empty(py);
    for o in &result.objects {
        let d = PyDict::new(py);
        d.set_item("id", o.id)?;
        d.set_item("frame", o.frame + 1)?;
        d.set_item("index", o.index)?;
        d.set_item("level", o.level)?;
        let pts =
            PyArray1::from_slice(py, o.shape.coords()).reshape([o.shape.len(), o.shape.dim()])?;
        d.set_item("points", pts)?;
        objects.append(d)?;
    }
    out.set_item("objects", objects)?;
    let tracks = PyList::empty(py);
    for t in &result.tracks {
        let pts = result.track_points(t);
        let width = 1 + pts.first().map_or(2, |(_, p)| p.len());
        let flat: Vec<f64> = pts
            .iter()
            .flat_map(|(f, p)| std::iter::once((*f + 1) as f64).chain(p.iter().copied()))
            .collect();
        tracks.append(PyArray1::from_vec(py, flat).reshape([pts.len(), width])?)?;
    }
    out.set_item("tracks", tracks)?;
    let timings = PyDict::new(py);
    timings.set_item("objects", result.timings.objects.as_secs_f64())?;
    timings.set_item("matching", result.timings.matching.as_secs_f64())?;
    timings.set_item("tracks", result.timings.tracks.as_secs_f64())?;
    out.set_item("timings", timings)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    Ok(())
}
