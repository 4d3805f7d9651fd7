"""Figures of matches, frames and tracks with matplotlib (``pip install 'pymodal[plot]'``).

matplotlib is imported only when a function is called; without it the call raises an
ImportError that says how to install it. Every function draws into ``ax`` (a new figure's axes
when ``None``) and returns the axes.

>>> import numpy as np, pymodal
>>> t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
>>> a = np.c_[np.cos(t), 0.6 * np.sin(t)]
>>> m = pymodal.match(a, a * 1.1)
>>> ax = pymodal.plot_match(m, a, a * 1.1)  # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_match", "plot_frame", "plot_tracks"]

_MISSING = (
    "pymodal's plotting helpers need matplotlib, which is not installed: "
    "pip install 'pymodal[plot]' (or pip install matplotlib)"
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
    fig = _pyplot().figure()
    return fig.add_subplot(111, projection=projection)


def _scale(pitch_mm):
    """(sx, sy, unit): coordinates times (sx, sy) are in `unit`."""
    if pitch_mm is None:
        return 1.0, 1.0, "sensels"
    p = np.broadcast_to(np.asarray(pitch_mm, dtype=float), (2,))
    if not np.all(np.isfinite(p)) or np.any(p <= 0):
        raise ValueError(f"pitch_mm must be positive, got {pitch_mm!r}")
    return float(p[0]), float(p[1]), "mm"


def plot_match(m, a, b, ax=None, *, pitch_mm=None, show_excess=True, closed=None,
               invert_y=True, cmap="RdYlGn_r"):
    """Draw objects ``a`` (blue) and ``b`` (black) and the matches ``m`` between them.

    ``m`` is a :class:`pymodal.Match` of ``a`` onto ``b`` (``(n, 2)`` or ``(n, 3)`` arrays; 3-D
    objects are drawn in a 3-D axes). One-to-one matches are segments coloured by their cost
    (``cmap``, with a colour bar), excess matches dashed orange, nodes left unmatched ringed.
    ``pitch_mm`` (a number or (x, y)) scales x and y to millimetres; the axes are labelled in
    mm, else in sensels. ``closed`` draws the outlines as closed polygons (default: for 2-D
    objects); ``invert_y`` puts row 0 at the top, as in the pressure image. Returns the axes.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != b.shape[1] or a.shape[1] not in (2, 3):
        raise ValueError("a and b must be (n, 2) or (n, 3) arrays of the same dimension")
    pairs = np.asarray(m.pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) and (pairs[:, 0].max() >= len(a) or pairs[:, 1].max() >= len(b)):
        raise ValueError("the match names nodes beyond a or b: is it the match of a onto b?")
    excess = np.asarray(getattr(m, "excess", np.zeros(len(pairs), bool)), dtype=bool)
    costs = np.asarray(getattr(m, "costs", np.zeros(len(pairs))), dtype=float)
    sx, sy, unit = _scale(pitch_mm)
    s = np.array([sx, sy, 1.0][: a.shape[1]])
    a, b = a * s, b * s
    three_d = a.shape[1] == 3
    ax = _axes(ax, "3d" if three_d else None)
    if closed is None:
        closed = not three_d
    from matplotlib import cm, colors

    if three_d:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection as Segments
    else:
        from matplotlib.collections import LineCollection as Segments
    for pts, colour, name in ((a, "tab:blue", "A"), (b, "0.15", "B")):
        if closed and not three_d:
            loop = np.vstack([pts, pts[:1]])
            ax.plot(loop[:, 0], loop[:, 1], "-", color=colour, lw=1.2, label=name)
        ax.scatter(*pts.T, s=8, color=colour, label=None if closed and not three_d else name)
    one = ~excess
    segments = np.stack([a[pairs[:, 0]], b[pairs[:, 1]]], axis=1) if len(pairs) else np.zeros((0, 2, a.shape[1]))
    finite = costs[one][np.isfinite(costs[one])]
    norm = colors.Normalize(*(finite.min(), finite.max()) if len(finite) else (0.0, 1.0))
    matched = Segments(segments[one], cmap=cmap, norm=norm, lw=1.0, label="match")
    matched.set_array(costs[one])
    (ax.add_collection3d if three_d else ax.add_collection)(matched)
    if show_excess and excess.any():
        dashed = Segments(segments[excess], colors="tab:orange", linestyles="--", lw=1.0,
                          label="excess match")
        (ax.add_collection3d if three_d else ax.add_collection)(dashed)
    for pts, idx, colour in ((a, getattr(m, "unmatched_a", []), "tab:blue"),
                             (b, getattr(m, "unmatched_b", []), "0.15")):
        idx = np.asarray(idx, dtype=np.int64)
        if len(idx):
            ax.scatter(*pts[idx].T, s=60, facecolors="none", edgecolors=colour, linewidths=1.2,
                       label="unmatched")
    ax.figure.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="match cost")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    if three_d:
        ax.set_zlabel("z")
    else:
        ax.set_aspect("equal")
        ax.autoscale_view()
        if invert_y and not ax.yaxis_inverted():
            ax.invert_yaxis()
    return ax


def plot_frame(recording, i, ax=None, *, contours=True, cmap="viridis", **contour_options):
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
    return ax


def plot_tracks(tracks, ax=None, *, background=None, min_length=3, invert_y=True):
    """Draw node tracks, each a ``(k, 3 or 4)`` array of ``(frame, x, y[, z])`` rows as returned
    by :func:`pymodal.run`, as coloured polylines in the x-y plane, optionally over a background
    image (e.g. the recording's peak-pressure image, NaN drawn transparent). Tracks shorter than
    ``min_length`` steps are skipped. Returns the axes.
    """
    ax = _axes(ax)
    if background is not None:
        bg = np.asarray(background, dtype=float)
        ax.imshow(np.ma.masked_invalid(bg), cmap="Greys", origin="upper",
                  extent=(-0.5, bg.shape[1] - 0.5, bg.shape[0] - 0.5, -0.5))
    drawn = 0
    for t in tracks:
        t = np.asarray(t, dtype=float)
        if t.ndim != 2 or t.shape[1] < 3:
            raise ValueError("each track must be a (k, 3 or 4) array of (frame, x, y[, z]) rows")
        if len(t) < min_length:
            continue
        line, = ax.plot(t[:, 1], t[:, 2], "-", lw=1)
        ax.plot(t[0, 1], t[0, 2], "o", ms=2, color=line.get_color())
        drawn += 1
    ax.set_aspect("equal")
    if background is None and invert_y and not ax.yaxis_inverted():
        ax.invert_yaxis()
    return ax
