//! `pymodal.register`: footprints registered onto one template ([`pedo_register`]), the
//! folder of `pedomatch register` written when ``out`` is given.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pedo_io::ReadOptions;
use pedo_register::{FootImages, RegisterParams, StudyRegistration};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

use crate::arrays::checked_array;
use crate::errors::to_py;
use crate::options_py::table_rows;

/// The trials of `inputs`: a 3-D array (trials × rows × columns) or a sequence of 2-D arrays,
/// each a peak image; else paths or patterns, read as recordings.
fn trial_images(
    py: Python<'_>,
    inputs: &Bound<'_, PyAny>,
    read: &ReadOptions,
) -> PyResult<(Vec<FootImages>, Vec<String>, String)> {
    let expected = "paths or glob patterns, a 3-D array (trials, rows, columns) of peak images, or a sequence of 2-D arrays";
    let as_paths = || -> Option<Vec<String>> {
        if let Ok(p) = inputs.extract::<PathBuf>() {
            return Some(vec![p.to_string_lossy().into_owned()]);
        }
        let items: Vec<Bound<'_, PyAny>> = inputs.try_iter().ok()?.collect::<PyResult<_>>().ok()?;
        items
            .iter()
            .map(|v| {
                v.extract::<PathBuf>()
                    .ok()
                    .map(|p| p.to_string_lossy().into_owned())
            })
            .collect()
    };
    if let Some(strings) = as_paths() {
        let (trials, names, units) = crate::pool::detach(py, || {
            let paths = pedo_study::find_recordings(&strings)?;
            if paths.is_empty() {
                return Err(pedo_io::IoError::InvalidInput(format!(
                    "no recordings found in {}",
                    strings.join(" ")
                )));
            }
            use rayon::prelude::*;
            let recs: Vec<(FootImages, String)> = paths
                .par_iter()
                .map(|p| {
                    let rec = pedo_io::formats::read_recording_with(p, read)?;
                    let f = FootImages::of_recording(&rec)
                        .map_err(|e| e.of_input(&p.display().to_string()))?;
                    Ok((f, rec.units.clone()))
                })
                .collect::<pedo_io::Result<_>>()?;
            let units = recs.first().map(|r| r.1.clone()).unwrap_or_default();
            let names = paths.iter().map(|p| p.display().to_string()).collect();
            Ok((
                recs.into_iter().map(|r| r.0).collect::<Vec<_>>(),
                names,
                units,
            ))
        })
        .map_err(to_py)?;
        return Ok((trials, names, units));
    }
    let fits = |s: &[usize]| s.len() == 3 && s.iter().all(|&n| n > 0);
    let arr = checked_array(py, inputs, "inputs", expected, "float64", fits)?;
    let arr: PyReadonlyArray3<f64> = arr.extract()?;
    let shape = arr.shape().to_vec();
    let v = arr.as_slice().map_err(crate::errors::internal)?;
    let per = shape[1] * shape[2];
    let trials = (0..shape[0])
        .map(|i| FootImages::from_peak(shape[1], shape[2], v[i * per..(i + 1) * per].to_vec()))
        .collect::<pedo_io::Result<Vec<_>>>()
        .map_err(to_py)?;
    let names = (0..shape[0]).map(|i| format!("trial {i}")).collect();
    Ok((trials, names, String::new()))
}

fn stack<'py>(
    py: Python<'py>,
    reg: &StudyRegistration,
    get: impl Fn(&FootImages) -> Option<&Vec<f64>>,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let t = &reg.template.images;
    let mut v = Vec::with_capacity(reg.trials.len() * t.rows * t.cols);
    for r in &reg.trials {
        match get(&r.images) {
            Some(x) => v.extend_from_slice(x),
            None => return Ok(None),
        }
    }
    let a = PyArray1::from_vec(py, v).reshape([reg.trials.len(), t.rows, t.cols])?;
    Ok(Some(a.into_any()))
}

macro_rules! define_register {
    (
        match: [$($_m:ident),*], match_doc: $_md:literal,
        pair: [$($_p:ident),*], pair_doc: $_pd:literal,
        recording: [$($_r:ident),*], recording_doc: $_rd:literal,
        output: [$($_o:ident),*], output_doc: $_od:literal,
        units: [$($_u:ident),*], units_doc: $_ud:literal,
        read: [$($rd:ident),*], read_doc: $_rdd:literal,
        study: [$($_s:ident),*], study_doc: $_sd:literal,
        row: [$($_w:ident),*], row_doc: $_wd:literal,
        register: [$($g:ident),*], register_doc: $_gd:literal,
    ) => {
        /// Register footprints onto one template, for pixel-wise statistics (``pedomatch register``).
        ///
        /// ``inputs``: recordings (a path or glob pattern, or a sequence of them; each one
        /// footprint, its peak, PTI and mean images registered), or peak images (a 3-D array
        /// ``(trials, rows, columns)``). ``template``: ``"first"`` (the first trial), ``"study"``
        /// (a study template: registered, averaged and registered again ``template_rounds`` times),
        /// ``"mun104"`` / ``"mun104-left"`` (the bundled MUN104 peak image of Pataky et al. 2011)
        /// or a recording's path; ``template_image``: a 2-D peak image instead. Per trial the
        /// whole-foot outline (convex hull of the loaded sensels) is matched by modal matching with
        /// a prior against mirroring and turns beyond ``max_turn``, a thin-plate field carries the
        /// template's grid into the trial and its images are sampled there (bilinear).
        /// ``mirror_left``: mirror every trial left-right first. ``out``: also write
        /// ``registered.npz``, ``registration.csv``, ``registered.png`` and ``register.html`` there
        /// (whole or not at all).
        ///
        /// Returns a dict: ``peak`` (and ``pti``, ``mean`` for recordings), float arrays
        /// ``(trials, rows, columns)`` on the template's grid; ``mask`` (bool, same shape), each
        /// trial's footprint there; ``template_peak``, ``template_mask``; ``trials`` (names);
        /// ``table``, a list of dicts, one per trial, with the columns of ``registration.csv``
        /// (``trial``, ``fallback``, ``map`` (``warp``, ``rigid`` or ``identity``: the map kept),
        /// the map ``m11 m12 tx_sensels m21 m22 ty_sensels``,
        /// ``turn_deg``, ``scale``, ``residual_sensels``, ``mask_xor_pct``, ``correlation``).
        /// An empty footprint raises :class:`InputError` (or the no-object error) naming its trial.
        /// The GIL is released during the work.
        #[pyfunction]
        #[pyo3(name = "register", signature = (inputs, out=None, template_image=None, *, $($g = None,)* $($rd = None,)*))]
        #[allow(clippy::too_many_arguments)]
        fn register_footprints<'py>(
            py: Python<'py>,
            inputs: &Bound<'py, PyAny>,
            out: Option<PathBuf>,
            template_image: Option<&Bound<'py, PyAny>>,
            $($g: Option<&Bound<'py, PyAny>>,)*
            $($rd: Option<&Bound<'py, PyAny>>,)*
        ) -> PyResult<Bound<'py, PyDict>> {
            let given = [$((stringify!($g), $g),)* $((stringify!($rd), $rd),)*];
            let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
            let params: RegisterParams = crate::options_py::option_set(&get)?;
            params.validate().map_err(to_py)?;
            let read: ReadOptions = crate::options_py::option_set(&get)?;
            let template_image = match template_image.filter(|t| !t.is_none()) {
                Some(t) => {
                    let fits = |s: &[usize]| s.len() == 2 && s.iter().all(|&n| n > 0);
                    let arr = checked_array(py, t, "template_image", "a 2-D peak image", "float64", fits)?;
                    let arr: numpy::PyReadonlyArray2<f64> = arr.extract()?;
                    let shape = arr.shape().to_vec();
                    let v = arr.as_slice().map_err(crate::errors::internal)?.to_vec();
                    Some(FootImages::from_peak(shape[0], shape[1], v).map_err(to_py)?)
                }
                None => None,
            };
            let (trials, names, units) = trial_images(py, inputs, &read)?;
            let reg = crate::pool::detach(py, || {
                let source = match template_image {
                    Some(t) => pedo_register::TemplateSource::Images(t),
                    None => params.resolve_template(|p| {
                        let rec = pedo_io::formats::read_recording_with(p, &read)?;
                        FootImages::of_recording(&rec).map_err(|e| e.of_input(&p.display().to_string()))
                    })?,
                };
                let reg = pedo_register::register_trials(&trials, &source, &params)?;
                if let Some(out) = &out {
                    let mut axes = pedo_output::figure::FigureAxes::unscaled("sensels");
                    axes.pressure_units = units.clone();
                    pedo_output::register_folder::write_register_folder(out, &names, &reg, &axes)?;
                }
                Ok::<_, pedo_io::IoError>(reg)
            })
            .map_err(to_py)?;
            let d = PyDict::new(py);
            for (key, get) in [
                ("peak", (|f: &FootImages| Some(&f.peak)) as fn(&FootImages) -> Option<&Vec<f64>>),
                ("pti", |f: &FootImages| f.pti.as_ref()),
                ("mean", |f: &FootImages| f.mean.as_ref()),
            ] {
                if let Some(a) = stack(py, &reg, get)? {
                    d.set_item(key, a)?;
                }
            }
            let t = &reg.template.images;
            let masks: Vec<bool> = reg.trials.iter().flat_map(|r| r.mask.iter().copied()).collect();
            d.set_item(
                "mask",
                PyArray1::from_vec(py, masks).reshape([reg.trials.len(), t.rows, t.cols])?,
            )?;
            d.set_item(
                "template_peak",
                PyArray1::from_vec(py, t.peak.clone()).reshape([t.rows, t.cols])?,
            )?;
            d.set_item(
                "template_mask",
                PyArray1::from_vec(py, reg.template.mask.clone()).reshape([t.rows, t.cols])?,
            )?;
            d.set_item("trials", PyList::new(py, &names)?)?;
            let table = pedo_output::register_folder::registration_table(&names, &reg);
            d.set_item("table", table_rows(py, &table)?)?;
            Ok(d)
        }
    };
}

crate::keywords::with_option_keywords!(define_register);

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(register_footprints, m)?)?;
    Ok(())
}
