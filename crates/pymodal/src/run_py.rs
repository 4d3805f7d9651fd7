//! `pymodal.run`: a whole recording in; the per-pair table, the matches and the node tracks out.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pedo_io::cancel::Cancel;
use pedo_io::recording::kpa_per_unit;
use pedo_io::Recording;
use pedo_output::{run_into_folder, InputInfo, RunPlan};
use pedo_track::require_objects;
use pedo_track::{run_sequence, Collect, SequenceResult};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

use crate::arrays::checked_array;
use crate::errors::{internal, to_py};
use crate::match_py::PyMatch;
use crate::options_py::{cell_to_py, json_to_py, table_rows};

/// A recording from a path, a (T, H, W) or (H, W) array (NaN = no sensor), or a `Recording`,
/// and where it came from (a file's name and SHA-256).
fn recording_from(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    read: &pedo_io::ReadOptions,
) -> PyResult<(Recording, InputInfo)> {
    let unnamed = |name: &str| InputInfo {
        name: name.to_string(),
        ..InputInfo::default()
    };
    if let Ok(rec) = obj.cast::<crate::io_py::PyRecording>() {
        return Ok((rec.get().recording().clone(), unnamed("Recording")));
    }
    if let Ok(path) = obj.extract::<std::path::PathBuf>() {
        return crate::pool::detach(py, || {
            // The SHA-256 recorded must be of the bytes parsed: the file must not change from
            // before the read to after the hash.
            let stamp = pedo_io::formats::stamp::FileStamp::of(&path);
            let (rec, sha256) = pedo_io::formats::read_hashed(&path, read)?;
            let input = InputInfo::of_read(&path, sha256)?.with_layout(read, rec.format)?;
            stamp.check(&path)?;
            Ok::<_, pedo_io::IoError>((rec, input))
        })
        .map_err(to_py);
    }
    const EXPECTED: &str = "a path, a Recording or a (T, H, W) or (H, W) array of pressures";
    let fits = |s: &[usize]| matches!(s.len(), 2 | 3);
    let arr: PyReadonlyArrayDyn<'_, f32> =
        checked_array(py, obj, "recording", EXPECTED, "float32", fits)?.extract()?;
    let (t, h, w) = match *arr.shape() {
        [h, w] => (1, h, w),
        [t, h, w] => (t, h, w),
        _ => return Err(internal("recording: a shape checked to be 2-D or 3-D")),
    };
    let data = arr.as_array().iter().copied().collect();
    let rec = Recording::from_nan_frames(t, h, w, data).map_err(to_py)?;
    Ok((rec, unnamed("array")))
}

macro_rules! define_run {
    (
        match: [$($m:ident),*], match_doc: $match_doc:literal,
        pair: [$($p:ident),*], pair_doc: $pair_doc:literal,
        recording: [$($r:ident),*], recording_doc: $recording_doc:literal,
        output: [$($o:ident),*], output_doc: $output_doc:literal,
        units: [$($_u:ident),*], units_doc: $_ud:literal,
        read: [$($rd:ident),*], read_doc: $read_doc:literal,
        $($rest:tt)*
    ) => {
        /// Match the objects of a whole recording, frame after frame (or level after level).
        ///
        /// The options are those of ``pedomatch run`` (keyword ``x_y`` is the flag ``--x-y``;
        /// ``pymodal._options()`` lists them) and default to ``None``, meaning the documented default.
        /// ``out``: a folder to write the run into, exactly as ``pedomatch run --out`` writes it (the
        /// tables, ``pairs.json``, ``summary.json``, the figures and ``report.html``), whole or not at
        /// all; None (the default) writes nothing; the output options say what it holds.
        ///
        /// Parameters
        /// ----------
        /// recording : Recording, path or array_like — a :class:`Recording`, a file or folder to read,
        ///     or a (frames, rows, cols) or (rows, cols) array of pressures.
        #[doc = $match_doc]
        #[doc = $recording_doc]
        /// out : path or None — the folder to write (see above).
        #[doc = $output_doc]
        #[doc = $read_doc]
        ///
        /// Returns a dict with
        ///
        /// - ``table``: list of dicts, one per matched pair (ids, 0-based frames, their times
        ///   ``time_a_s``/``time_b_s`` when the frame rate is known, node counts, local matches and %,
        ///   optimisation matches and %, matches after the excess step, mean cost, trackable matches
        ///   and %, as ``pairs.csv``);
        /// - ``matches``: list of :class:`Match`, aligned with ``table``;
        /// - ``reference_matches``: with drift correction (``drift_reference`` >= 2, not for the
        ///   isocontour model), one dict per reference pair, each object matched against its ancestor
        ///   on the last reference frame: ``id_a`` (the ancestor), ``id_b``, ``frame_a``, ``frame_b``
        ///   (0-based), ``match`` (a :class:`Match`) and ``tracked``, a (k,) bool array aligned with
        ///   ``match.pairs``: True when a track took that match (its two nodes are on the same track:
        ///   a step of ``track_steps`` onto node ``b`` that is no match of ``matches``), as
        ///   ``reference_matches.csv``'s ``tracked``; an empty list without drift correction;
        /// - ``objects``: list of dicts ``{id, frame, time_s, index, level, level_kpa, points,
        ///   points_mm}`` (``id`` is the index in this list; ``level`` the isobaric level of an
        ///   isocontour run in the recording's units and ``level_kpa`` in kPa when those units are
        ///   known, both None otherwise; ``points`` (n, d) array in sensels, ``points_mm`` its x, y in
        ///   mm or None when the pitch is unknown) and the other columns of ``objects.csv``: the
        ///   centroid and the measures of the sensors inside the outline (``contact_sensors``,
        ///   ``contact_area_mm2``, ``total_force_n``, ``peak_pressure_kpa``, ``cop_x_mm``, ... as the
        ///   units allow, like ``frames``; None for surfaces);
        /// - ``tracks``: list of (k, 1 + d) float arrays of ``(frame, x, y[, z])`` rows, one per track;
        /// - ``track_steps``: list of (k, 2) int arrays of ``(object_id, node)`` rows, aligned with
        ///   ``tracks`` (row for row): the object each step is on (an index into ``objects``, which
        ///   gives its frame and, for an isocontour run, its level) and the node within it, as
        ///   ``tracks.csv``'s ``object_id`` and ``node``;
        /// - ``track_round_trips``: (number of tracks,) float array, aligned with ``tracks``: each
        ///   track's round trip in sensels, the largest over its steps of how far the backward field
        ///   of the pair it steps through carries its node from where it came (``tracks.csv``'s
        ///   ``round_trip_sensels``); NaN for a track of one step, for surfaces and with drift
        ///   correction;
        /// - ``points``: the material points of a contour run (``points.csv``): per point a
        ///   (k, 3) float array of ``(frame, x, y)`` rows (sensels); ``point_steps`` per point a
        ///   (k, 2) int array of ``(object_id, seed_node)`` rows (node -1 for a point given by
        ///   position); ``point_names`` per point the name of a point given with ``points``
        ///   (None for the outline's default points); ``point_round_trips`` per point a (k,)
        ///   float array of its round trip on each step in sensels (``points.csv``'s
        ///   ``round_trip_sensels``: how far the backward field of the pair it stepped through
        ///   carries it from where it was on the frame it came from; NaN on its seed frame);
        ///   empty lists for the other models;
        /// - ``region_series``: with ``regions``, ``region_rule`` or ``masks``, the rows of ``region_series.csv``
        ///   as dicts (``region``, ``kind`` "moving" or "fixed", ``frame``, ``time_s``, ``sensels``,
        ///   ``area_mm2``, ``total_force_n``, ``peak_pressure_kpa``, ``cop_x``, ``cop_y``, ...,
        ///   ``mean_pressure_kpa``, named by the units known; ``name`` and ``stance`` of an
        ///   anatomical region, None for the user's); an empty list without;
        /// - ``regions``: with ``region_rule`` or ``masks``, the rows of ``regions.csv`` as dicts (``region``,
        ///   ``measure``, ``value``, ``unit``, ``kind`` "fixed" or "moving": carried through the stances, by the contour field for a
        ///   surface or isocontour run); an
        ///   empty list without, or when the footprint cannot be divided;
        /// - ``frames``: list of dicts of per-frame measures (``frame``, ``time_s``,
        ///   ``contact_area_mm2``, ``total_force_n``, ``peak_pressure_kpa``, ``cop_x_mm``, ... as the
        ///   units allow, like ``frames.csv``);
        /// - ``summary``: the provenance and outcome of the run, as ``summary.json``;
        /// - ``timings``: seconds per stage.
        ///
        /// Raises
        /// ------
        /// FileNotFoundError, OSError — ``recording`` is a path that does not exist or cannot be read;
        /// FormatError — the file is corrupt, truncated or of no known format;
        /// InputError — an argument of the wrong form, named in the message: ``recording`` not a path,
        ///     a Recording or a 2-D/3-D array; ``frames`` not a ``(start, end)`` pair; ``pitch_mm``
        ///     not a number or an (x, y) pair;
        /// OptionError — an unknown or out-of-range option value (e.g. ``model="mesh"``, a negative
        ///     ``pitch_mm``, ``frames`` empty or beyond the recording once negative indices are
        ///     counted from its end; the message names the range and the frame count); an
        ///     ``InputError``;
        /// DegenerateShapeError — no frame of ``frames`` holds an object (everything below ``noise``,
        ///     or outlines too small to model), as ``pedomatch run`` fails on such a recording.
        /// All but the ``OSError`` are :class:`PedomatchError` and ``ValueError`` subclasses. Ctrl-C
        /// raises ``KeyboardInterrupt`` at the run's next frame or pair. An option
        /// of the wrong type raises ``TypeError`` naming it and the type it takes
        /// (``spacing="wide"``: "spacing must be a number, got 'wide'"). A pair or frame that
        /// cannot be processed does not raise: it is skipped, with its reason in ``summary``
        /// (``summary["skipped"]``).
        #[pyfunction]
        #[pyo3(signature = (recording, *, $($m = None,)* $($r = None,)* out = None, $($o = None,)* $($rd = None),*))]
        #[allow(clippy::too_many_arguments)]
        fn run<'py>(
            py: Python<'py>,
            recording: &Bound<'py, PyAny>,
            $($m: Option<&Bound<'py, PyAny>>,)*
            $($r: Option<&Bound<'py, PyAny>>,)*
            out: Option<PathBuf>,
            $($o: Option<&Bound<'py, PyAny>>,)*
            $($rd: Option<&Bound<'py, PyAny>>,)*
        ) -> PyResult<Bound<'py, PyDict>> {
            let given = [$((stringify!($m), $m),)* $((stringify!($r), $r),)* $((stringify!($o), $o),)* $((stringify!($rd), $rd),)*];
            let get = |name: &str| given.iter().find(|(n, _)| *n == name).and_then(|(_, v)| *v);
            let outputs = crate::batch_py::run_outputs(get)?;
            let params = crate::options_py::option_set(get)?;
            let read: pedo_io::formats::ReadOptions = crate::options_py::option_set(get)?;
            run_recording(py, recording, params, &read, out, outputs)
        }
    };
}

crate::keywords::with_option_keywords!(define_run);

/// [`run`] with its options read.
fn run_recording<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    params: pedo_track::RunParams,
    read: &pedo_io::ReadOptions,
    out: Option<PathBuf>,
    outputs: pedo_output::RunOutputs,
) -> PyResult<Bound<'py, PyDict>> {
    params.validate().map_err(to_py)?;
    let started = std::time::Instant::now();
    let (mut rec, input) = recording_from(py, recording, read)?;
    params.units.apply(&mut rec).map_err(to_py)?;
    let read_time = started.elapsed().as_secs_f64();
    let mut options = params.to_options(&rec).map_err(to_py)?;
    // Ctrl-C stops the run at its next frame or pair and raises KeyboardInterrupt.
    let cancel = Cancel::new();
    options.cancel = Some(cancel.clone());
    // With a folder, one run feeds the folder's writer (the one of `pedomatch run`, so the
    // folder is the command line's) and the gathering of the result returned here; without,
    // the run is only gathered.
    let (result, summary) = crate::pool::detach_cancellable(py, &cancel, || {
        let Some(folder) = &out else {
            let result = run_sequence(&rec, &options, &|_, _, _| {})?;
            require_objects(result.objects.len(), &rec, &options)?;
            return Ok((result, None));
        };
        let mut whole = Collect::new(options.keep_match_details);
        let plan = RunPlan {
            input: &input,
            params: &params,
            frames: None,
            folder: Some(folder),
            outputs: &outputs,
            timings: &[("read", read_time)],
            also: Some(&mut whole),
        };
        let (summary, counts) = run_into_folder(&rec, &options, plan, &|_, _, _| {})?;
        Ok::<_, pedo_io::IoError>((whole.into_result(counts), Some(summary)))
    })?
    .map_err(|e| to_py(e.of_input(&input.name)))?;
    let points = crate::pool::detach_cancellable(py, &cancel, || {
        pedo_track::follow::run_points(&result, &options)
    })?
    .map_err(to_py)?;

    let dict = PyDict::new(py);
    dict.set_item(
        "table",
        table_rows(py, &pedo_output::pairs_table(&rec, &result))?,
    )?;
    let matches = PyList::empty(py);
    for p in &result.pairs {
        matches.append(Py::new(py, PyMatch::from_result(p.result.clone()))?)?;
    }
    dict.set_item("matches", matches)?;
    dict.set_item("reference_matches", reference_matches(py, &result)?)?;
    dict.set_item("objects", objects(py, &rec, &result)?)?;
    set_tracks(py, &dict, &result)?;
    set_points(py, &dict, &result, points.as_ref(), &options.inputs)?;
    let (start, end) = options.frames.unwrap_or((0, rec.n_frames()));
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let measures = pedo_output::frames_table(&rec, threshold, start, end);
    dict.set_item("frames", table_rows(py, &measures)?)?;
    let m = crate::pool::detach(py, || {
        pedo_io::measures::Measures::of_recording(&rec, threshold, start..end)
    })
    .map_err(to_py)?;
    let (regions, values, fixed_values) = region_tables(
        py,
        &cancel,
        RunHeld {
            rec: &rec,
            params: &params,
            options: &options,
            result: &result,
        },
        (&m, threshold),
        points.as_ref(),
        &outputs,
    )?;
    // The stance-normalised curves, with each fixed region's as curves.csv has them.
    let curves = pedo_output::curves_table(&rec, &m, fixed_values.as_deref());
    dict.set_item("curves", table_rows(py, &curves)?)?;
    dict.set_item("region_series", table_rows(py, &regions)?)?;
    dict.set_item("regions", table_rows(py, &values)?)?;
    let summary = match summary {
        Some(summary) => summary,
        None => {
            let mut summary = pedo_output::run_summary(
                &input,
                &rec,
                &params,
                &options,
                &result,
                &[("read", read_time)],
            );
            if let Some(p) = &points {
                pedo_output::set_point_round_trips(&mut summary, pedo_output::point_round_trips(p));
            }
            // The measures a folder's summary.json holds (a folder computes them as it runs).
            summary["measures"] = pedo_output::measure_values_json(&m);
            summary
        }
    };
    dict.set_item("summary", json_to_py(py, &summary)?)?;
    let timings = PyDict::new(py);
    timings.set_item("read", read_time)?;
    timings.set_item("objects", result.timings.objects.as_secs_f64())?;
    timings.set_item("matching", result.timings.matching.as_secs_f64())?;
    timings.set_item("tracks", result.timings.tracks.as_secs_f64())?;
    dict.set_item("timings", timings)?;
    Ok(dict)
}

/// `tracks` (per track, its rows `frame, x, y[, z]`), `track_steps` (per track, its steps as
/// rows `object id, node`: the object, an index into `objects`, says which frame, object and
/// isobaric level a step is on, as tracks.csv's `object_id` and `node`) and `track_round_trips`.
fn set_tracks(
    py: Python<'_>,
    dict: &Bound<'_, PyDict>,
    result: &pedo_track::SequenceResult,
) -> PyResult<()> {
    let tracks = PyList::empty(py);
    let track_steps = PyList::empty(py);
    for t in &result.tracks {
        let ids: Vec<i64> = t
            .steps
            .iter()
            .flat_map(|&(o, n)| [o as i64, n as i64])
            .collect();
        track_steps.append(PyArray1::from_vec(py, ids).reshape([t.steps.len(), 2])?)?;
        let pts = result.track_points(t);
        let width = 1 + pts.first().map_or(2, |(_, p)| p.len());
        let flat: Vec<f64> = pts
            .iter()
            .flat_map(|(f, p)| std::iter::once(*f as f64).chain(p.iter().copied()))
            .collect();
        tracks.append(PyArray1::from_vec(py, flat).reshape([pts.len(), width])?)?;
    }
    dict.set_item("tracks", tracks)?;
    dict.set_item("track_steps", track_steps)?;
    let trips: Vec<f64> = (0..result.tracks.len())
        .map(|k| result.track_round_trip(k).unwrap_or(f64::NAN))
        .collect();
    dict.set_item("track_round_trips", PyArray1::from_vec(py, trips))?;
    Ok(())
}

/// A run held whole: its recording, its parameters and options, and its result.
struct RunHeld<'a> {
    rec: &'a pedo_io::Recording,
    params: &'a pedo_track::RunParams,
    options: &'a pedo_track::SequenceOptions,
    result: &'a pedo_track::SequenceResult,
}

/// `region_series` (the user's regions followed, then the anatomical regions carried through
/// the stances), `regions` (regions.csv's rows: fixed, then moving) and the fixed regions'
/// values (for `curves`), as a run's folder has them. The anatomical regions are those of
/// `region_rule` or `masks`, carried by the contour field (each foot's through its own): this
/// run's, or for a surface or isocontour run the contour run of its frames. A footprint that
/// cannot be divided has no regions (a folder's regions.json says why).
#[allow(clippy::type_complexity)]
fn region_tables(
    py: Python<'_>,
    cancel: &Cancel,
    run: RunHeld<'_>,
    (m, threshold): (&pedo_io::measures::Measures, f64),
    points: Option<&pedo_track::follow::FollowedPoints>,
    outputs: &pedo_output::RunOutputs,
) -> PyResult<(
    pedo_output::Table,
    pedo_output::Table,
    Option<Vec<pedo_io::regions::RegionValues>>,
)> {
    let RunHeld {
        rec,
        params,
        options,
        result,
    } = run;
    let mut series = match points {
        Some(p) if !options.inputs.regions.is_empty() => pedo_output::regions_table(
            rec,
            &|o| result.objects[o].frame,
            p,
            &options.inputs,
            threshold,
        )
        .map_err(to_py)?,
        _ => pedo_output::Table::default(),
    };
    let feet = !rec.feet.is_empty();
    let Some(asked) = pedo_output::regions_asked(outputs, rec).map_err(to_py)? else {
        return Ok((
            series,
            pedo_output::region_values_table(m, &[], None, feet),
            None,
        ));
    };
    let anatomy = crate::pool::detach_cancellable(py, cancel, || {
        let Ok((masks, fixed)) = pedo_output::recording_regions(rec, m, threshold, asked) else {
            return Ok(None);
        };
        let field = pedo_output::moving_regions::carrying_options(params, rec, options)?;
        let run = (options.model == pedo_track::ObjectModel::Contour).then_some(result);
        let moving =
            pedo_output::moving_regions::follow_anatomy(rec, run, &field, m, &masks, &fixed)?;
        Ok::<_, pedo_io::IoError>(Some((masks, fixed, moving)))
    })?
    .map_err(to_py)?;
    let Some((masks, fixed, moving)) = anatomy else {
        return Ok((
            series,
            pedo_output::region_values_table(m, &[], None, feet),
            None,
        ));
    };
    if series.header.is_empty() {
        series = pedo_output::region_series_header(rec);
    }
    pedo_output::moving_regions::anatomy_rows(&mut series, rec, &masks, &moving, threshold)
        .map_err(to_py)?;
    let values = pedo_output::region_values_table(m, &fixed, Some(&moving.values), feet);
    Ok((series, values, Some(fixed)))
}

/// The material points of a contour run ([`pedo_track::follow`]) as `points` (per point, its
/// steps as rows `frame, x, y` in pixels), `point_steps` (per point, its steps as rows
/// `object id, seed node`, the node −1 for a point not seeded on a node) and `point_names` (per
/// point, the user's name of a point given with `points=`, None for the outline's), as the
/// points of `points.csv` (not the regions' outlines); all empty lists for the other models.
fn set_points<'py>(
    py: Python<'py>,
    out: &Bound<'py, PyDict>,
    result: &SequenceResult,
    points: Option<&pedo_track::follow::FollowedPoints>,
    inputs: &pedo_track::UserInputs,
) -> PyResult<()> {
    use pedo_track::follow::Seeded;
    let (xy, steps, names) = (PyList::empty(py), PyList::empty(py), PyList::empty(py));
    let trips = PyList::empty(py);
    let all = points.map_or(&[][..], |p| p.points.as_slice());
    for p in all.iter().filter(|p| !matches!(p.kind, Seeded::Region(_))) {
        let name = match p.kind {
            Seeded::Point(i) => inputs.points.get(i).map(|u| u.name.clone()),
            _ => None,
        };
        names.append(name)?;
        let n = p.steps.len();
        let flat: Vec<f64> = p
            .steps
            .iter()
            .flat_map(|&(o, q)| [result.objects[o].frame as f64, q[0], q[1]])
            .collect();
        xy.append(PyArray1::from_vec(py, flat).reshape([n, 3])?)?;
        let node = p.seed.1.map_or(-1, |v| v as i64);
        let ids: Vec<i64> = p
            .steps
            .iter()
            .flat_map(|&(o, _)| [o as i64, node])
            .collect();
        steps.append(PyArray1::from_vec(py, ids).reshape([n, 2])?)?;
        let d: Vec<f64> = (p.round_trips.iter())
            .map(|d| d.map_or(f64::NAN, f64::from))
            .collect();
        trips.append(PyArray1::from_vec(py, d))?;
    }
    out.set_item("points", xy)?;
    out.set_item("point_names", names)?;
    out.set_item("point_round_trips", trips)?;
    out.set_item("point_steps", steps)
}

/// The reference pairs of drift correction as dicts: the two objects, their frames, the
/// :class:`Match` and which of its matches a track took.
fn reference_matches<'py>(
    py: Python<'py>,
    result: &SequenceResult,
) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for (p, tracked) in result
        .reference_pairs
        .iter()
        .zip(result.reference_tracked())
    {
        let (oa, ob) = (&result.objects[p.a], &result.objects[p.b]);
        let d = PyDict::new(py);
        d.set_item("id_a", oa.id)?;
        d.set_item("id_b", ob.id)?;
        d.set_item("frame_a", oa.frame)?;
        d.set_item("frame_b", ob.frame)?;
        d.set_item(
            "match",
            Py::new(py, PyMatch::from_result(p.result.clone()))?,
        )?;
        d.set_item("tracked", PyArray1::from_vec(py, tracked))?;
        out.append(d)?;
    }
    Ok(out)
}

/// The objects as dicts, with their frame times and their points in mm where known.
fn objects<'py>(
    py: Python<'py>,
    rec: &Recording,
    result: &SequenceResult,
) -> PyResult<Bound<'py, PyList>> {
    let objects = PyList::empty(py);
    // The columns of objects.csv besides those set below (centroids, the measures inside each
    // outline), written as that table writes them.
    let table = pedo_output::objects_table(rec, result);
    for (o, row) in result.objects.iter().zip(&table.rows) {
        let d = PyDict::new(py);
        d.set_item("id", o.id)?;
        d.set_item("frame", o.frame)?;
        d.set_item("time_s", rec.time_s(o.frame))?;
        d.set_item("index", o.index)?;
        d.set_item("level", o.level)?;
        // kPa beside the file's units, as objects.csv states it, so levels of mixed sensors compare.
        let kpa = kpa_per_unit(&rec.units);
        d.set_item("level_kpa", o.level.zip(kpa).map(|(l, k)| l * k))?;
        let (n, dim) = (o.shape.len(), o.shape.dim());
        let pts = PyArray1::from_slice(py, o.shape.coords()).reshape([n, dim])?;
        d.set_item("points", pts)?;
        match rec.pitch_mm {
            Some(p) => {
                let mm: Vec<f64> = (0..n)
                    .flat_map(|i| {
                        let q = o.shape.point(i);
                        [q[0] * p[0], q[1] * p[1]]
                    })
                    .collect();
                d.set_item("points_mm", PyArray1::from_vec(py, mm).reshape([n, 2])?)?;
            }
            None => d.set_item("points_mm", py.None())?,
        }
        for (k, c) in table.header.iter().zip(row) {
            if !d.contains(k)? {
                d.set_item(k, cell_to_py(py, c)?)?;
            }
        }
        objects.append(d)?;
    }
    Ok(objects)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    Ok(())
}

/// The run parameters of `**options` holding [`run`]'s keywords (read exactly as `run` reads
/// them: the options of [`pedo_track::RunParams`], matching and units included); an unknown
/// keyword is an `OptionError`.
pub fn run_params<'py>(
    py: Python<'py>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<pedo_track::RunParams> {
    let d = options.cloned().unwrap_or_else(|| PyDict::new(py));
    // Listed as `run`'s signature lists them: the matching options, then the recording ones.
    let matching = modal_core::options::match_option_specs();
    let keywords: Vec<&str> = (matching.iter().map(|s| s.name))
        .chain(pedo_track::recording_option_specs().iter().map(|s| s.name))
        .collect();
    for key in d.keys() {
        let key: String = key.extract()?;
        if !keywords.contains(&key.as_str()) {
            return Err(crate::errors::option_error(format!(
                "unknown option {key:?}; the options are the keywords of pymodal.run: {}",
                keywords.join(", ")
            )));
        }
    }
    // Read exactly as `run` reads its keywords: a value of the wrong type is the same
    // `TypeError` naming it.
    let mut given = std::collections::HashMap::new();
    for (key, value) in d.iter() {
        given.insert(key.extract::<String>()?, value);
    }
    crate::options_py::option_set(|k: &str| given.get(k))
}
