"""Modal matching of deformable objects in dynamic pedobarography.

Python bindings of the pedomatch Rust workspace: numpy arrays in, numpy arrays out.
"""

import functools as _functools
import html as _html

from typing import Any as _Any

import numpy as _np

from ._pymodal import *  # noqa: F401,F403
from ._pymodal import __version__ as __version__
from ._pymodal import _options as _options  # type: ignore[attr-defined]
from ._pymodal import run as _run
# matplotlib loads lazily, at the first plot. "X as X": re-exported for type checkers (--strict).
from .plot import plot_frame as plot_frame, plot_match as plot_match, plot_tracks as plot_tracks


def _same(a: _Any, b: _Any) -> bool:
    """Whether two values of a result are equal: dicts by keys and values, lists and tuples
    element by element, numpy arrays by shape, dtype and values, floats and float arrays with NaN
    equal to NaN, anything else by ``==``."""
    if isinstance(a, _np.ndarray) or isinstance(b, _np.ndarray):
        return (isinstance(a, _np.ndarray) and isinstance(b, _np.ndarray)
                and a.shape == b.shape and a.dtype == b.dtype
                and bool(_np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")))
    if isinstance(a, dict) or isinstance(b, dict):
        return (isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys()
                and all(_same(a[k], b[k]) for k in a))
    for seq in (list, tuple):
        if isinstance(a, seq) or isinstance(b, seq):
            return (isinstance(a, seq) and isinstance(b, seq) and len(a) == len(b)
                    and all(_same(x, y) for x, y in zip(a, b)))
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True  # NaN: a result equals its copy
    return bool(a == b)


class RunResult(dict[str, _Any]):
    """What :func:`run` returns: a dict (``table``, ``matches``, ``reference_matches``,
    ``objects``, ``tracks``, ``track_steps``, ``track_round_trips``, ``points``, ``point_steps``, ``point_names``, ``point_round_trips``,
    ``region_series``, ``regions``, ``frames``, ``curves``, ``summary``, ``timings``) that Jupyter shows as a table of its
    summary. ``points`` are the material points of a contour run, followed by anchored
    registration (one array of rows ``frame, x, y`` per point; ``point_steps`` gives each step's
    object id and the node the point was seeded on, ``point_names`` the name of a point given
    with ``points=``, None for the outline's, ``point_round_trips`` each step's round trip in sensels,
    NaN on its seed frame); ``region_series`` the rows of ``region_series.csv`` for the
    regions given with ``regions=`` and, with ``region_rule=``, the anatomical regions fixed and
    carried through each stance; ``regions`` the rows of ``regions.csv`` (``kind`` fixed or moving).

    Compares by value with ``==``: the same keys, and values equal recursively (lists element by
    element, numpy arrays in shape, dtype and values), NaN equal to NaN, so that a result equals
    its pickled or deep copy. Unhashable, as a dict."""

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, dict):
            return NotImplemented
        return _same(dict(self), dict(other))

    def __ne__(self, other: object) -> bool:
        if not isinstance(other, dict):
            return NotImplemented
        return not _same(dict(self), dict(other))

    __hash__ = None

    def __repr__(self) -> str:
        """One line: the input, the counts and the mean optimisation percentage, and the keys
        (the dict itself holds every match and track: print ``dict(res)`` for all of it)."""
        s = self.get("summary", {})
        pct = s.get("mean_optimisation_percent")
        counts = ", ".join(f"{k}={s.get(k)}" for k in ("objects", "pairs", "tracks"))
        return (f"RunResult(input={s.get('input', {}).get('file')!r}, "
                f"frames={s.get('recording', {}).get('frames')}, {counts}, "
                f"mean_optimisation_percent={'None' if pct is None else format(pct, '.1f')}; "
                f"keys: {', '.join(self)})")

    def _repr_html_(self) -> str:
        """The run's summary as an HTML table: input, format, frames, pairs, mean match
        percentages and cost, what was skipped, and the time per stage."""
        s = self.get("summary", {})
        rec = s.get("recording", {})
        inp = s.get("input", {})
        skipped = s.get("skipped", {})
        timings = s.get("timings_s", {})

        def num(v: _Any, fmt: str) -> str:
            return "n/a" if v is None else format(v, fmt)

        rows = [
            ("input", inp.get("file")),
            ("format", inp.get("format") or "unknown"),
            ("frames", f"{rec.get('frames')} of {rec.get('rows')} × {rec.get('cols')} sensels"),
            ("pitch", "unknown" if rec.get("pitch_mm") is None
             else " × ".join(str(p) for p in rec["pitch_mm"]) + " mm"),
            ("frame rate", "unknown" if rec.get("frame_rate_hz") is None
             else f"{rec['frame_rate_hz']:g} Hz"),
            ("objects", s.get("objects")),
            ("pairs", s.get("pairs")),
            ("tracks", s.get("tracks")),
            ("mean local matches", num(s.get("mean_local_percent"), ".1f") + " %"),
            ("mean optimisation matches", num(s.get("mean_optimisation_percent"), ".1f") + " %"),
            ("mean trackable matches", num(s.get("mean_trackable_percent"), ".1f") + " %"),
            ("mean cost", num(s.get("mean_cost"), ".4f")),
            ("skipped", f"{len(skipped.get('frames', []))} frames, "
                        f"{len(skipped.get('pairs', []))} pairs"),
            ("timings", ", ".join(f"{k} {v:.3f} s" for k, v in timings.items())),
            ("version", f"pedomatch {s.get('pedomatch_version', __version__)}"),
        ]
        body = "".join(
            f"<tr><th style='text-align:left'>{_html.escape(str(k))}</th>"
            f"<td style='text-align:left'>{_html.escape(str(v))}</td></tr>"
            for k, v in rows
        )
        return f"<table class='pymodal-run'><caption>pymodal.run</caption>{body}</table>"


# The stub types the native run as returning RunResult, so that type checkers see this
# function's result with every keyword of the native signature.
@_functools.wraps(_run)  # type: ignore[no-redef]
def run(recording: _Any, **options: _Any) -> RunResult:
    return RunResult(_run(recording, **options))


run.__module__ = __name__
