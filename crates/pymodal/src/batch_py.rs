//! `pymodal.batch`, `pymodal.batch_row` and `pymodal.find_recordings`: a whole study, with the
//! library's study code ([`pedo_study`]) that `pedomatch batch` runs.

use pedo_io::cancel::Cancel;
use pedo_io::ReadOptions;
use pedo_output::RunOutputs;
use pedo_study::{StudyOptions, StudyParams, StudyRow};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList};
use std::path::PathBuf;

use crate::errors::{argument_error, to_py};
use crate::options_py::table_rows;

/// Inputs as strings: one path or pattern, or a sequence of them (str or os.PathLike); anything
/// else is an `InputError` naming the argument `name`.
fn input_strings(inputs: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<String>> {
    let one = |v: &Bound<'_, PyAny>| -> Option<String> {
        Some(v.extract::<PathBuf>().ok()?.to_string_lossy().into_owned())
    };
    if let Some(s) = one(inputs) {
        return Ok(vec![s]);
    }
    let bad = || {
        argument_error(
            name,
            "a path or glob pattern (str or os.PathLike), or a sequence of them",
            inputs,
        )
    };
    let items = inputs.try_iter().map_err(|_| bad())?;
    items.map(|v| one(&v?).ok_or_else(bad)).collect()
}

/// What a run's folder holds, from the keywords ``figures``, ``figure_format``, ``tables``,
/// ``report``, ``animation`` and ``region_rule`` (each None at its default): the output options of
/// ``pedomatch run`` and ``batch``, declared once in `pedo_output::OutputOptions`.
pub(crate) fn run_outputs(
    figures: Option<&Bound<'_, PyAny>>,
    figure_format: Option<&Bound<'_, PyAny>>,
    tables: Option<&Bound<'_, PyAny>>,
    report: Option<&Bound<'_, PyAny>>,
    animation: Option<&Bound<'_, PyAny>>,
    region_rule: Option<&Bound<'_, PyAny>>,
) -> PyResult<RunOutputs> {
    let given = [
        ("figures", figures),
        ("figure_format", figure_format),
        ("tables", tables),
        ("report", report),
        ("animation", animation),
        ("region_rule", region_rule),
    ];
    let options: pedo_output::OutputOptions = crate::options_py::option_set(|name| {
        given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v)
    })?;
    Ok(RunOutputs::of(&options))
}

/// How a study runs, from the keywords ``jobs`` (None: one per core) and ``force``: the options
/// of ``pedomatch batch``, declared once in `pedo_study::StudyParams`.
fn study_params(
    py: Python<'_>,
    jobs: Option<&Bound<'_, PyAny>>,
    force: bool,
) -> PyResult<StudyParams> {
    let force = PyBool::new(py, force).to_owned().into_any();
    let given = [("jobs", jobs), ("force", Some(&force))];
    crate::options_py::option_set(|name| {
        given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v)
    })
}

/// The study options of the keywords.
fn study_options(
    py: Python<'_>,
    inputs: Vec<String>,
    out: Option<PathBuf>,
    study: StudyParams,
    outputs: RunOutputs,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<StudyOptions> {
    let params = crate::run_py::run_params(py, options)?;
    params.validate().map_err(to_py)?;
    let mut opts = StudyOptions {
        inputs,
        params,
        read: ReadOptions::default(),
        out,
        cancel: None,
        outputs,
        ..StudyOptions::default()
    };
    study.apply(&mut opts).map_err(to_py)?;
    Ok(opts)
}

fn row_dict<'py>(py: Python<'py>, row: &StudyRow) -> PyResult<Bound<'py, PyAny>> {
    let rows = table_rows(py, &pedo_study::study_table(std::slice::from_ref(row)))?;
    rows.get_item(0)
}

/// The recordings named by ``inputs`` (a path or pattern, or a sequence of them), in order,
/// each once, as :func:`batch` finds them: a file as it is; a folder searched recursively for
/// files whose content is a recording (a folder of PNG/TIFF images is one image-sequence
/// recording; hidden folders and pedomatch output folders are not searched); anything else a
/// glob pattern (``"data/**/*.asf"``). A path that neither exists nor matches is kept (its row
/// reports it missing). Returns a list of str.
#[pyfunction]
fn find_recordings(py: Python<'_>, inputs: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    let inputs = input_strings(inputs, "inputs")?;
    let found = crate::pool::detach(py, || pedo_study::find_recordings(&inputs)).map_err(to_py)?;
    Ok(found.iter().map(|p| p.display().to_string()).collect())
}

/// Run every recording of ``paths`` like :func:`run` and return the study table: a list of dicts,
/// one per recording in order, with the columns of ``study.csv``: ``path``, ``output`` (its
/// folder under ``out``, or None), ``format``, ``frames``, ``frame_rate_hz``, ``pitch_x_mm``,
/// ``pitch_y_mm``, ``pressure_units`` (None when unknown), ``pairs``, ``mean_local_percent``,
/// ``mean_optimisation_percent``, ``mean_trackable_percent``, ``tracks``, the measures
/// ``peak_pressure_kpa``, ``pti_max_kpa_s``, ``peak_force_n``, ``fti_n_s``, ``contact_time_s``,
/// ``max_contact_area_mm2`` (None when the recording cannot give the unit), ``wall_time_s``,
/// ``status`` (``"ok"``, ``"skipped"`` or ``"error"``) and ``message`` (one line: why it failed or
/// was skipped).
/// ``pandas.DataFrame(rows)`` makes it a data frame.
///
/// ``paths``: files, folders or glob patterns (see :func:`find_recordings`). ``out``: the study
/// folder; each recording's folder (the tables, figures, ``summary.json`` and ``report.html`` of
/// ``pedomatch run``) is written there atomically, with
/// ``study.csv`` and ``study.json`` (which also keep the rows of earlier runs' recordings that are
/// not among ``paths``; the list returned is this run's rows only); a recording whose folder is
/// complete (same input SHA-256 and options) is skipped unless ``force``. ``jobs``: recordings run at once, each on one
/// thread (None: every core). ``figures``: ``"summary"`` (the tracks, curves and peak-pressure
/// figures), ``"pairs"`` (those and a match figure per pair) or ``"none"``; ``figure_format``:
/// ``"png"`` or ``"svg"``. ``report``: ``"html"`` (the
/// self-contained ``report.html``) or ``"none"``. ``animation``: ``"gif"`` (``animation.gif``) or
/// ``"none"``. ``tables``:
/// ``"csv"``, or ``"parquet"`` (typed, compressed columns with the CSV's names and values;
/// ``pandas.read_parquet`` reads them; the study table is then ``study.parquet``). ``layout``: a
/// pedar sensor-layout table for the pedar recordings (``--layout``; default: the bundled
/// insole), recorded in their ``summary.json``. ``options``: the keywords of :func:`run`. A recording that fails is an ``"error"`` row; the others go on. Bad
/// options or an ``out`` folder holding other files raise; ``paths`` naming no recording at all
/// raise :class:`InputError` (``no recordings found in ...``, as ``pedomatch batch`` exits 1) and
/// nothing is written. The GIL is released throughout.
/// Ctrl-C raises ``KeyboardInterrupt`` at the running recordings' next progress step (a frame,
/// a pair or a figure), as ``pedomatch batch`` stops: the recordings finished keep their
/// folders, those running or not started leave none (a folder of an earlier run stays as it
/// was), and the study table is not written.
#[pyfunction]
#[pyo3(signature = (paths, out=None, jobs=None, *, force=false, figures=None, figure_format=None, tables=None, report=None, animation=None, region_rule=None, layout=None, **options))]
#[allow(clippy::too_many_arguments)]
fn batch<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    jobs: Option<&Bound<'py, PyAny>>,
    force: bool,
    figures: Option<&Bound<'py, PyAny>>,
    figure_format: Option<&Bound<'py, PyAny>>,
    tables: Option<&Bound<'py, PyAny>>,
    report: Option<&Bound<'py, PyAny>>,
    animation: Option<&Bound<'py, PyAny>>,
    region_rule: Option<&Bound<'py, PyAny>>,
    layout: Option<PathBuf>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let inputs = input_strings(paths, "paths")?;
    let study = study_params(py, jobs, force)?;
    let outputs = run_outputs(
        figures,
        figure_format,
        tables,
        report,
        animation,
        region_rule,
    )?;
    let mut opts = study_options(py, inputs, out, study, outputs, options)?;
    opts.read.layout = layout;
    // Ctrl-C stops the study as the command line's does (the recordings finished keep their
    // folders, no study table is written) and raises KeyboardInterrupt.
    let cancel = Cancel::new();
    opts.cancel = Some(cancel.clone());
    let run = crate::pool::detach_cancellable(py, &cancel, || {
        let found = pedo_study::find_recordings(&opts.inputs)?;
        // As `pedomatch batch`: nothing to run is an error, and nothing is written.
        if found.is_empty() {
            return Err(pedo_io::IoError::InvalidInput(format!(
                "no recordings found in {}",
                opts.inputs.join(" ")
            )));
        }
        pedo_study::run_study(&found, &opts, &|_| {})
    })?
    .map_err(to_py)?;
    // This run's rows only (the shape it always had); study.json also holds the kept ones.
    table_rows(py, &pedo_study::study_table(&run.rows))
}

/// One row of :func:`batch`'s table: runs the recording at ``path`` (on one thread, the GIL
/// released), writing its folder under ``out`` when given (skipped when complete unless
/// ``force``), but no study table. For distributing a study yourself (a Dask cluster, a job
/// queue): ``[batch_row(p, out) for p in find_recordings(inputs)]`` equals
/// ``batch(inputs, out)`` but for ``wall_time_s``. Never raises for a bad recording (its row says
/// what went wrong); bad options raise. ``figures``, ``figure_format``, ``tables``, ``report``,
/// ``animation`` and ``layout`` as for :func:`batch`.
#[pyfunction]
#[pyo3(signature = (path, out=None, *, force=false, figures=None, figure_format=None, tables=None, report=None, animation=None, region_rule=None, layout=None, **options))]
#[allow(clippy::too_many_arguments)]
fn batch_row<'py>(
    py: Python<'py>,
    path: PathBuf,
    out: Option<PathBuf>,
    force: bool,
    figures: Option<&Bound<'py, PyAny>>,
    figure_format: Option<&Bound<'py, PyAny>>,
    tables: Option<&Bound<'py, PyAny>>,
    report: Option<&Bound<'py, PyAny>>,
    animation: Option<&Bound<'py, PyAny>>,
    region_rule: Option<&Bound<'py, PyAny>>,
    layout: Option<PathBuf>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let inputs = vec![path.display().to_string()];
    let outputs = run_outputs(
        figures,
        figure_format,
        tables,
        report,
        animation,
        region_rule,
    )?;
    // One recording, on one thread.
    let study = StudyParams {
        jobs: Some(1),
        ..study_params(py, None, force)?
    };
    let mut opts = study_options(py, inputs, out, study, outputs, options)?;
    opts.read.layout = layout;
    let cancel = Cancel::new();
    opts.cancel = Some(cancel.clone());
    let row = crate::pool::detach_cancellable(py, &cancel, || {
        let previous = match &opts.out {
            Some(out) => pedo_study::open_study_folder(out)?,
            None => Vec::new(),
        };
        let before = pedo_study::previous_row(&previous, &path);
        let row =
            pedo_study::on_one_thread(|| pedo_study::run_recording(&path, &opts, before, &|_| {}));
        Ok::<_, pedo_io::IoError>(row)
    })?
    .map_err(to_py)?;
    row_dict(py, &row)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(find_recordings, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch_row, m)?)?;
    Ok(())
}
