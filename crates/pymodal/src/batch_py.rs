//! `pymodal.batch`, `pymodal.batch_row` and `pymodal.find_recordings`: a whole study, with the
//! library's study code ([`pedo_study`]) that `pedomatch batch` runs.

use pedo_io::cancel::Cancel;
use pedo_io::ReadOptions;
use pedo_output::RunOutputs;
use pedo_study::{StudyOptions, StudyParams, StudyRow};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
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

/// What a run's folder holds, from the output keywords among those `get` gives (each None at
/// its default): the output options of ``pedomatch run`` and ``batch``, declared once in
/// `pedo_output::OutputOptions`.
pub(crate) fn run_outputs<'a, 'py: 'a>(
    get: impl Fn(&str) -> Option<&'a Bound<'py, PyAny>>,
) -> PyResult<RunOutputs> {
    let options: pedo_output::OutputOptions = crate::options_py::option_set(get)?;
    Ok(RunOutputs::of(&options))
}

/// The study options of the keywords `get` gives (the study's, the outputs', the reading's)
/// and of the run's `options`.
fn study_options<'a, 'py: 'a>(
    py: Python<'py>,
    inputs: Vec<String>,
    out: Option<PathBuf>,
    get: impl Fn(&str) -> Option<&'a Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<StudyOptions> {
    let params = crate::run_py::run_params(py, options)?;
    params.validate().map_err(to_py)?;
    let study: StudyParams = crate::options_py::option_set(&get)?;
    let read: ReadOptions = crate::options_py::option_set(&get)?;
    let mut opts = StudyOptions {
        inputs,
        params,
        read,
        out,
        cancel: None,
        outputs: run_outputs(&get)?,
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

/// `batch` and `batch_row`, their keywords from the one declaration of each option
/// (`crate::keywords`): the study's (`batch` alone runs several at once), the outputs' and
/// the reading's.
macro_rules! define_batch {
    (
        match: [$($_m:ident),*], match_doc: $_md:literal,
        pair: [$($_p:ident),*], pair_doc: $_pd:literal,
        recording: [$($_r:ident),*], recording_doc: $_rd:literal,
        output: [$($o:ident),*], output_doc: $_od:literal,
        units: [$($_u:ident),*], units_doc: $_ud:literal,
        read: [$($rd:ident),*], read_doc: $_rdd:literal,
        study: [$($s:ident),*], study_doc: $_sd:literal,
        row: [$($w:ident),*], row_doc: $_wd:literal,
        $($rest:tt)*
    ) => {
        /// Run every recording of ``paths`` like :func:`run` and return the study table: a list of dicts,
        /// one per recording in order, with the columns of ``study.csv``: ``path``, ``output`` (its
        /// folder under ``out``, or None), ``format``, ``frames``, ``frame_rate_hz``, ``pitch_x_mm``,
        /// ``pitch_y_mm``, ``pressure_units`` (None when unknown), ``pairs``, ``mean_local_percent``,
        /// ``mean_optimisation_percent``, ``mean_trackable_percent``, ``mean_round_trip_sensels``, ``tracks``,
        /// ``track_round_trip_median_sensels``, ``track_round_trip_p95_sensels``,
        /// ``point_round_trip_median_sensels``, ``point_round_trip_p95_sensels`` (None where the run
        /// has none: see ``summary.json``'s ``track_round_trip_sensels`` and
        /// ``point_round_trip_sensels``), the measures
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
        /// ``"none"``. ``region_rule``: ``"coarse"`` or ``"fine"`` writes each recording's anatomical
        /// regions (``regions.*``) and ``study_regions.csv``; ``"none"`` (the default) none. ``tables``:
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
        #[pyo3(signature = (paths, out=None, $($s = None,)* *, $($o = None,)* $($rd = None,)* **options))]
        #[allow(clippy::too_many_arguments)]
        fn batch<'py>(
            py: Python<'py>,
            paths: &Bound<'py, PyAny>,
            out: Option<PathBuf>,
            $($s: Option<&Bound<'py, PyAny>>,)*
            $($o: Option<&Bound<'py, PyAny>>,)*
            $($rd: Option<&Bound<'py, PyAny>>,)*
            options: Option<&Bound<'py, PyDict>>,
        ) -> PyResult<Bound<'py, PyList>> {
            let inputs = input_strings(paths, "paths")?;
            let given = [$((stringify!($s), $s),)* $((stringify!($o), $o),)* $((stringify!($rd), $rd),)*];
            let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
            let mut opts = study_options(py, inputs, out, get, options)?;
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
        /// what went wrong); bad options raise. Calls at once into one ``out`` (many processes)
        /// give each recording its own folder, and a :func:`batch` into ``out`` is refused while
        /// any runs (and this, while a batch runs). ``figures``, ``figure_format``, ``tables``, ``report``,
        /// ``animation`` and ``layout`` as for :func:`batch`.
        #[pyfunction]
        #[pyo3(signature = (path, out=None, *, $($w = None,)* $($o = None,)* $($rd = None,)* **options))]
        #[allow(clippy::too_many_arguments)]
        fn batch_row<'py>(
            py: Python<'py>,
            path: PathBuf,
            out: Option<PathBuf>,
            $($w: Option<&Bound<'py, PyAny>>,)*
            $($o: Option<&Bound<'py, PyAny>>,)*
            $($rd: Option<&Bound<'py, PyAny>>,)*
            options: Option<&Bound<'py, PyDict>>,
        ) -> PyResult<Bound<'py, PyAny>> {
            let inputs = vec![path.display().to_string()];
            let given = [$((stringify!($w), $w),)* $((stringify!($o), $o),)* $((stringify!($rd), $rd),)*];
            let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
            let mut opts = study_options(py, inputs, out, get, options)?;
            // One recording, on one thread.
            opts.jobs = 1;
            let cancel = Cancel::new();
            opts.cancel = Some(cancel.clone());
            let row = crate::pool::detach_cancellable(py, &cancel, || {
                // Held through the run: a `batch` into the folder is refused while rows run.
                let (_shared, previous) = match &opts.out {
                    Some(out) => {
                        let (lock, rows) = pedo_study::share_study_folder(out)?;
                        (Some(lock), rows)
                    }
                    None => (None, Vec::new()),
                };
                let before = pedo_study::previous_row(&previous, &path);
                let row =
                    pedo_study::on_one_thread(|| pedo_study::run_recording(&path, &opts, before, &|_| {}));
                Ok::<_, pedo_io::IoError>(row)
            })?
            .map_err(to_py)?;
            row_dict(py, &row)
        }
    };
}

crate::keywords::with_option_keywords!(define_batch);

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(find_recordings, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    m.add_function(wrap_pyfunction!(batch_row, m)?)?;
    Ok(())
}
