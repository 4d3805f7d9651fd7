"""Figures of matches, frames and tracks with matplotlib (``pip install 'pedomatch[plot]'``).

matplotlib is imported only when a function is called; without it the call raises an
ImportError that says how to install it. Every function draws into ``ax`` (a new figure's axes
when ``None``) and returns the axes. A figure a function makes itself is sized to the aspect of
its data (a foot's outline gets a portrait figure, without bands of blank space beside the axes);
axes passed in, and their figure, are left as they are.

>>> import numpy as np, pymodal
>>> t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
>>> a = np.c_[np.cos(t), 0.6 * np.sin(t)]
>>> m = pymodal.match(a, a * 1.1)
>>> ax = pymodal.plot_match(m, a, a * 1.1)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

if TYPE_CHECKING:  # annotations only: matplotlib loads at the first call
    import numpy.typing as npt
    from matplotlib.axes import Axes

    from ._pymodal import Match, Recording

    Pitch = Union[float, Tuple[float, float], None]

__all__ = ["plot_match", "plot_frame", "plot_tracks"]

_MISSING = (
    "pymodal's plotting helpers need matplotlib, which is not installed: "
    "pip install 'pedomatch[plot]' (or pip install matplotlib)"
)


def _pyplot():
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - exercised by the no-matplotlib test
        raise ImportError(_MISSING) from e
    return plt


def _axes(ax, projection=None):
    if ax is not None:
        return ax
    # Constrained layout makes room for the colour bars, the legend and the title, so that
    # none of them runs into another (as in a figure of several panels made with it).
    fig = _pyplot().figure(layout="constrained")
    return fig.add_subplot(111, projection=projection)


# A figure a helper makes for itself is fitted to its data (_fit_figure): the axes may grow by
# this factor along the data's long side, and a colour bar stays at least this tall (inches).
_GROW = 1.3
_MIN_HEIGHT_IN = 2.5


def _layout(fig):
    """Run the layout engine and the axes' aspect, as a draw does, without rendering."""
    draw = getattr(fig, "draw_without_rendering", None)  # matplotlib >= 3.6
    (draw or fig.canvas.draw)()


def _fit_figure(ax, title, legend):
    """Size a figure made by :func:`_axes` to the aspect of its equal-aspect data: a tall object
    (a foot's outline) in the default landscape figure left bands of blank space beside the
    axes, a wide one above and below.

    The axes keep the data's aspect by their limits (``adjustable="datalim"``), not by shrinking
    inside the room the layout gave them, so the colour bars, labels, title and legend sit
    against the axes. The axes grow (by at most ``_GROW``) along the data's long side and shrink
    along the other to the data's aspect, never narrower than the title and the legend above
    them (the legend in one column when two are wider than the data) nor lower than
    ``_MIN_HEIGHT_IN`` (a shorter colour bar is unreadable); what the data cannot fill is a
    margin of the limits. Axes the caller made are never touched."""
    if getattr(ax, "name", "") == "3d":
        return
    fig = ax.figure
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    if x1 == x0 or y1 == y0:
        return
    aspect = abs(x1 - x0) / abs(y1 - y0)  # equal aspect: the data's width over its height
    ax.set_adjustable("datalim")

    def box():
        """The axes' size in inches and the room around them, after a layout."""
        _layout(fig)
        # The layout widened one range to the box's aspect: back to the data's.
        ax.autoscale_view()
        w, h = fig.get_size_inches()
        pos = ax.get_position()
        return pos.width * w, pos.height * h, w - pos.width * w, h - pos.height * h

    def text_width():
        return max((t.get_window_extent().width / fig.dpi
                    for t in (ax.title, ax.get_legend()) if t is not None and t.get_visible()),
                   default=0.0)

    box_w, box_h, room_w, room_h = box()
    if box_w <= 0 or box_h <= 0:
        return
    if aspect < box_w / box_h:  # tall: blank beside the data
        leg = ax.get_legend()
        if legend and leg is not None and leg.get_window_extent().width / fig.dpi > aspect * box_h:
            _title_and_legend(ax, title, legend, ncol=1)
            box_w, box_h, room_w, room_h = box()
        text = text_width()
        new_h = min(max(box_h, text / aspect), _GROW * box_h)
        new_w = max(aspect * new_h, text)
    else:  # wide: blank above and below
        new_w = min(max(box_w, _MIN_HEIGHT_IN * aspect), _GROW * box_w)
        new_h = max(new_w / aspect, min(_MIN_HEIGHT_IN, box_h))
    # The room around the axes (colour bars) changes a little with their size: a second pass.
    for _ in range(2):
        fig.set_size_inches(new_w + room_w, new_h + room_h)
        box_w, box_h, room_w, room_h = box()


def _title_and_legend(ax, title, legend=True, ncol=2):
    """The title, and the legend in rows between it and the axes: never over the data (a
    legend inside the axes hides part of an outline). The title is lifted by the legend's
    height, which is fixed in points whatever the figure's layout does later."""
    pad = 6.0
    if legend:
        handles, _ = ax.get_legend_handles_labels()
        leg = ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=min(ncol, len(handles)) or 1,
                        fontsize="small", frameon=False, borderaxespad=0.2, handlelength=1.6,
                        columnspacing=1.0)
        pad += leg.get_window_extent().height * 72.0 / ax.figure.dpi
    ax.set_title(title, pad=pad)


def _input_error(message):
    """pymodal's InputError (a ValueError), as the compiled functions raise it."""
    from . import _pymodal

    return _pymodal.InputError(message)


def _scale(pitch_mm):
    """(sx, sy, unit): coordinates in sensels times (sx, sy) are in `unit` (mm when the pitch is
    known, else sensels)."""
    if pitch_mm is None:
        return 1.0, 1.0, "sensels"
    try:
        p = np.broadcast_to(np.asarray(pitch_mm, dtype=float), (2,))
    except (TypeError, ValueError):
        p = np.array([np.nan])
    if p.shape != (2,) or not np.all(np.isfinite(p)) or np.any(p <= 0):
        raise _input_error(
            f"pitch_mm must be a positive number or an (x, y) pair of them (mm per sensel), "
            f"got {pitch_mm!r}")
    return float(p[0]), float(p[1]), "mm"


def plot_match(m: Match, a: npt.ArrayLike, b: npt.ArrayLike, ax: Optional[Axes] = None, *,
               pitch_mm: Pitch = None, show_excess: bool = True, closed: Optional[bool] = None,
               invert_y: bool = True, cmap: Any = "RdYlGn_r",
               labels: Tuple[str, str] = ("A", "B"), title: Optional[str] = None,
               legend: bool = True, zlabel: str = "z") -> Axes:
    """Draw objects ``a`` (blue) and ``b`` (black) and the matches ``m`` between them.

    ``m`` is a :class:`pymodal.Match` of ``a`` onto ``b`` (``(n, 2)`` or ``(n, 3)`` arrays of
    coordinates in sensels; 3-D objects are drawn in a 3-D axes). One-to-one matches are
    segments coloured by their cost (``cmap``, with a "match cost" colour bar), excess matches
    dashed orange, nodes left unmatched ringed. ``pitch_mm`` (a number or (x, y), mm per sensel)
    scales x and y to millimetres and the axes are labelled "x (mm)", "y (mm)"; without it they
    are in sensels and labelled so. ``labels`` names the two objects in the legend (e.g.
    ``("frame 40", "frame 41")``), which lies above the axes, off the data; ``legend=False``
    leaves it out. ``title`` replaces the
    default title: the two labels, then the counts of one-to-one and excess matches and of
    unmatched nodes. ``closed`` draws the outlines as closed polygons (default: for 2-D
    objects); ``invert_y`` puts row 0 at the top, as in the pressure image. ``zlabel`` labels the
    z axis of 3-D objects; z is not scaled by ``pitch_mm`` (for the points of
    :func:`pymodal.surface`, z is the pressure rescaled to the x-y extent in sensels, e.g.
    ``zlabel="pressure (scaled)"``). Returns the axes.

    Raises :class:`pymodal.InputError` (a ``ValueError``) if ``a`` or ``b`` is not an (n, 2) or
    (n, 3) array, if they differ in dimension, if ``m`` names nodes beyond them, or for a bad
    ``pitch_mm``.
    """
    try:
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
    except (TypeError, ValueError):
        raise _input_error("a and b must be (n, 2) or (n, 3) arrays of coordinates") from None
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != b.shape[1] or a.shape[1] not in (2, 3):
        raise _input_error(
            f"a and b must be (n, 2) or (n, 3) arrays of the same dimension, got shapes "
            f"{a.shape} and {b.shape}")
    pairs = np.asarray(m.pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) and (pairs[:, 0].max() >= len(a) or pairs[:, 1].max() >= len(b)):
        raise _input_error("the match m names nodes beyond a or b: is it the match of a onto b?")
    excess = np.asarray(getattr(m, "excess", np.zeros(len(pairs), bool)), dtype=bool)
    costs = np.asarray(getattr(m, "costs", np.zeros(len(pairs))), dtype=float)
    name_a, name_b = labels
    sx, sy, unit = _scale(pitch_mm)
    s = np.array([sx, sy, 1.0][: a.shape[1]])
    a, b = a * s, b * s
    three_d = a.shape[1] == 3
    own = ax is None
    ax = _axes(ax, "3d" if three_d else None)
    if closed is None:
        closed = not three_d
    from matplotlib import cm, colors

    if three_d:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection as Segments
    else:
        from matplotlib.collections import LineCollection as Segments
    for pts, colour, name in ((a, "tab:blue", name_a), (b, "0.15", name_b)):
        if closed and not three_d:
            loop = np.vstack([pts, pts[:1]])
            ax.plot(loop[:, 0], loop[:, 1], "-", color=colour, lw=1.2, marker=".", ms=4,
                    label=name)
        else:
            ax.scatter(*pts.T, s=8, color=colour, label=name)
    one = ~excess
    segments = np.stack([a[pairs[:, 0]], b[pairs[:, 1]]], axis=1) if len(pairs) else np.zeros((0, 2, a.shape[1]))
    finite = costs[one][np.isfinite(costs[one])]
    norm = colors.Normalize(*(finite.min(), finite.max()) if len(finite) else (0.0, 1.0))
    matched = Segments(segments[one], cmap=cmap, norm=norm, lw=1.0,
                       label="one-to-one match (colour: cost)")
    matched.set_array(costs[one])
    (ax.add_collection3d if three_d else ax.add_collection)(matched)
    n_excess = int(excess.sum())
    if show_excess and n_excess:
        dashed = Segments(segments[excess], colors="tab:orange", linestyles="--", lw=1.0,
                          label="excess match")
        (ax.add_collection3d if three_d else ax.add_collection)(dashed)
    n_unmatched = 0
    for pts, idx, colour in ((a, getattr(m, "unmatched_a", []), "tab:blue"),
                             (b, getattr(m, "unmatched_b", []), "0.15")):
        idx = np.asarray(idx, dtype=np.int64)
        if len(idx):
            ax.scatter(*pts[idx].T, s=60, facecolors="none", edgecolors=colour, linewidths=1.2,
                       label="unmatched" if n_unmatched == 0 else "_unmatched")
            n_unmatched += len(idx)
    ax.figure.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="match cost")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    if title is None:
        title = (f"{name_a} \u2192 {name_b}\n{int(one.sum())} one-to-one, {n_excess} excess, "
                 f"{n_unmatched} unmatched")
    if three_d:
        ax.set_zlabel(zlabel)
    else:
        ax.set_aspect("equal")
        ax.autoscale_view()
        if invert_y and not ax.yaxis_inverted():
            ax.invert_yaxis()
    _title_and_legend(ax, title, legend)
    if own:
        _fit_figure(ax, title, legend)
    return ax


def plot_frame(recording: Recording, i: int, ax: Optional[Axes] = None, *,
               contours: bool = True, cmap: Any = "viridis", **contour_options: Any) -> Axes:
    """Draw frame ``i`` (0-based) of a :class:`pymodal.Recording`: the pressure image with a
    colour bar in the recording's units, and the frame's contours (:func:`pymodal.contours`,
    with ``contour_options``; the recording's noise threshold unless one is given) in white.

    Axes are in mm when the recording knows its pitch, else in sensels; row 0 is at the top.
    Sensors the plate lacks are left blank. Returns the axes.
    """
    import pymodal

    n = recording.n_frames
    if not 0 <= i < n:
        raise IndexError(f"frame {i} out of range: the recording has frames 0..{n - 1}")
    frame = np.asarray(recording.frames[i], dtype=float)
    sx, sy, unit = _scale(recording.pitch_mm)
    rows, cols = frame.shape
    own = ax is None
    ax = _axes(ax)
    image = ax.imshow(np.ma.masked_invalid(frame), cmap=cmap, origin="upper",
                      extent=(-0.5 * sx, (cols - 0.5) * sx, (rows - 0.5) * sy, -0.5 * sy),
                      interpolation="nearest")
    units = recording.units or "units unknown"
    ax.figure.colorbar(image, ax=ax, label=f"pressure ({units})")
    if contours:
        options = dict(contour_options)
        if "threshold" not in options and recording.noise_threshold is not None:
            options["threshold"] = recording.noise_threshold
        for c in pymodal.contours(np.nan_to_num(frame), **options):
            loop = np.vstack([c, c[:1]])
            ax.plot(loop[:, 0] * sx, loop[:, 1] * sy, "-", color="white", lw=1.2)
    time = f", {i * recording.dt_s:.3f} s" if recording.dt_s else ""
    ax.set_title(f"frame {i}{time}")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_aspect("equal")
    if own:
        _fit_figure(ax, ax.get_title(), legend=False)
    return ax


def plot_tracks(tracks: Union[Mapping[str, Any], Sequence[npt.ArrayLike]], ax: Optional[Axes] = None, *,
                background: Union[Recording, npt.ArrayLike, None] = None,
                pitch_mm: Pitch = None, units: Optional[str] = None,
                dt_s: Optional[float] = None, longest: Optional[int] = 40, min_length: int = 3,
                invert_y: bool = True, cmap: Any = "plasma") -> Axes:
    """Draw node tracks in the x-y plane: the result of :func:`pymodal.run`, or its
    ``["tracks"]``, each a ``(k, 3 or 4)`` array of ``(frame, x, y[, z])`` rows in sensels.

    Like the ``tracks.png`` of ``pedomatch run``, only the ``longest`` tracks (default 40, by
    number of steps; ``None`` for all) among those spanning at least ``min_length`` steps are
    drawn: thousands of overlapping tracks hide each other. The title says how many are shown
    of how many. Each track is a line coloured by frame (``cmap``, with a colour bar in frames,
    or in seconds when ``dt_s`` is known) with a dot where it starts; the legend is above the
    axes, off the data.

    Given the result of an isocontour run (``model="isocontour"``: every object an isobaric
    level of one frame), the tracks are coloured by level instead (each step's level is that of
    its object, from the result's ``track_steps``), with a colour bar in the pressure units, the
    title names the frame and the levels, and a recording as ``background`` is drawn as that
    frame's pressure image.

    Given the result of :func:`pymodal.run`, its recording's pitch, frame rate and units (from
    its ``summary``) are used unless given, so the axes are in mm and the colours in seconds
    when the run knew them.

    ``background`` is an optional image under the tracks: a :class:`pymodal.Recording` (its
    peak-pressure image; its pitch, units and frame interval are used unless given) or an
    (H, W) array (NaN drawn transparent), with a colour bar labelled in ``units``. ``pitch_mm``
    (a number or (x, y), mm per sensel) draws in mm, else in sensels; the axes are labelled
    with the unit. ``invert_y`` puts row 0 at the top, as in the pressure image. Returns the
    axes.

    Raises :class:`pymodal.InputError` (a ``ValueError``) for a track that is not a
    ``(k, 3 or 4)`` array, a background that is not 2-D, or a bad ``pitch_mm``.
    """
    import pymodal

    objects = steps = None
    if isinstance(tracks, dict):
        objects = tracks.get("objects")
        steps = tracks.get("track_steps")
        # A run's result knows its recording's pitch, frame rate and units (its summary).
        known = (tracks.get("summary") or {}).get("recording") or {}
        pitch_mm = known.get("pitch_mm") if pitch_mm is None else pitch_mm
        units = known.get("pressure_units") if units is None else units
        rate = known.get("frame_rate_hz")
        dt_s = (1.0 / rate if rate else None) if dt_s is None else dt_s
        tracks = tracks.get("tracks", [])
    iso = _iso_levels(objects, steps)
    background_what = "peak pressure"
    if isinstance(background, pymodal.Recording):
        rec = background
        if iso is None:
            background = rec.peak_image
        else:
            background = np.asarray(rec.frames[iso["frame"]], dtype=float)
            background_what = f"pressure, frame {iso['frame']}"
        pitch_mm = rec.pitch_mm if pitch_mm is None else pitch_mm
        units = rec.units if units is None else units
        dt_s = rec.dt_s if dt_s is None else dt_s
    sx, sy, unit = _scale(pitch_mm)
    eligible, which = _eligible_tracks(tracks, min_length)
    # Longest first; ties by first frame, so the choice is deterministic (as the CLI's).
    order = sorted(range(len(eligible)), key=lambda k: (-len(eligible[k]), eligible[k][0, 0]))
    order = order[: None if longest is None else max(int(longest), 0)]
    shown = [eligible[k] for k in order]

    own = ax is None
    ax = _axes(ax)
    from matplotlib import cm, colors
    from matplotlib.collections import LineCollection

    if background is not None:
        _draw_background(ax, background, sx, sy, f"{background_what} ({units or 'units unknown'})")
    if iso is None:
        scale = 1.0 if dt_s is None else float(dt_s)
        values = [t[:, 0] * scale for t in shown]
        what, bar_label = "time", ("frame" if dt_s is None else "time (s)")
    else:
        # Each step's object (track_steps: object id, node) gives its level.
        values = [iso["levels"][np.asarray(steps[which[k]], dtype=np.int64)[:, 0]] for k in order]
        what, bar_label = "level", f"isobaric level ({units or 'units unknown'})"
    finite = np.concatenate(values + [np.zeros(0)])
    finite = finite[np.isfinite(finite)]
    norm = colors.Normalize(*(finite.min(), finite.max()) if len(finite) else (0.0, 1.0))
    for k, (t, v) in enumerate(zip(shown, values)):
        xy = t[:, 1:3] * [sx, sy]
        lines = LineCollection(np.stack([xy[:-1], xy[1:]], axis=1), cmap=cmap, norm=norm, lw=1.2,
                               label=f"node track (colour: {what})" if k == 0 else "_track")
        lines.set_array(v[:-1])
        ax.add_collection(lines)
    if shown:
        starts = np.array([t[0, 1:3] * [sx, sy] for t in shown])
        ax.scatter(starts[:, 0], starts[:, 1], s=10, c=[v[0] for v in values], cmap=cmap,
                   norm=norm, edgecolors="k", linewidths=0.4, label="track start", zorder=3)
    # Without a layout engine a second bar on the right would sit between the axes and the
    # first one, its tick labels on the first's: it goes below the axes instead.
    below = background is not None and ax.figure.get_layout_engine() is None
    ax.figure.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label=bar_label,
                       location="bottom" if below else "right")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_aspect("equal")
    ax.autoscale_view()
    if background is None and invert_y and not ax.yaxis_inverted():
        ax.invert_yaxis()
    title = _tracks_title(shown, eligible, min_length, iso, dt_s, units)
    _title_and_legend(ax, title, legend=bool(shown))
    if own:
        _fit_figure(ax, title, legend=bool(shown))
    return ax


def _iso_levels(objects, steps):
    """For an isocontour run (its objects each with a level, all of one frame; ``steps`` the
    object id and node of each track step): the frame, every object's level by id, the range
    and count of the levels; else None."""
    if steps is None or not objects or any(o.get("level") is None for o in objects):
        return None
    frames = {o["frame"] for o in objects}
    if len(frames) != 1:
        return None
    levels = np.array([o["level"] for o in objects], dtype=float)
    return {"frame": frames.pop(), "levels": levels, "range": (levels.min(), levels.max()),
            "count": len(levels)}


def _eligible_tracks(tracks, min_length):
    """The tracks as float arrays, those of at least ``min_length`` (and 2) steps, and the
    index of each in ``tracks``."""
    eligible, which = [], []
    for i, t in enumerate(tracks):
        try:
            t = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            t = np.zeros((0,))
        if t.ndim != 2 or t.shape[1] not in (3, 4):
            raise _input_error(
                f"tracks[{i}] must be a (k, 3 or 4) array of (frame, x, y[, z]) rows, got "
                f"shape {t.shape}")
        if len(t) >= max(min_length, 2):
            eligible.append(t)
            which.append(i)
    return eligible, which


def _draw_background(ax, background, sx, sy, label):
    bg = np.asarray(background, dtype=float)
    if bg.ndim != 2:
        raise _input_error(
            f"background must be a Recording or an (H, W) image, got shape {bg.shape}")
    image = ax.imshow(np.ma.masked_invalid(bg), cmap="Greys", origin="upper",
                      interpolation="nearest",
                      extent=(-0.5 * sx, (bg.shape[1] - 0.5) * sx,
                              (bg.shape[0] - 0.5) * sy, -0.5 * sy))
    ax.figure.colorbar(image, ax=ax, label=label)


def _tracks_title(shown, eligible, min_length, iso, dt_s, units):
    """Two or three short lines (a long one runs into the next panel): what, when, how many."""
    which = "all" if len(shown) == len(eligible) else f"{len(shown)} longest of"
    if iso is not None:
        lo, hi = iso["range"]
        time = f", {iso['frame'] * dt_s:.3f} s" if dt_s else ""
        return (f"node tracks, frame {iso['frame']}{time}\n{iso['count']} isobaric levels, "
                f"{lo:.0f}\u2013{hi:.0f} {units or ''}".rstrip()
                + f"\n{which} {len(eligible)} (\u2265 {max(min_length, 2)} levels)")
    frames = [t[:, 0] for t in eligible]
    span = ""
    if frames:
        f0, f1 = int(min(f.min() for f in frames)), int(max(f.max() for f in frames))
        span = f", frames {f0}\u2013{f1}"
    return f"node tracks{span}\n{which} {len(eligible)} (\u2265 {max(min_length, 2)} frames)"
