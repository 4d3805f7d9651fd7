"""Figures of matches and tracks with matplotlib (imported lazily, only when a function is called).

>>> import numpy as np, pymodal
>>> from pymodal.plot import plot_match
>>> t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
>>> a = np.c_[np.cos(t), 0.6 * np.sin(t)]
>>> m = pymodal.match(a, a * 1.1)
>>> ax = plot_match(a, a * 1.1, m)  # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_match", "plot_tracks"]


def _axes(ax, projection=None):
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    fig = plt.figure()
    return fig.add_subplot(111, projection=projection)


def plot_match(a, b, match, ax=None, *, show_excess=True, closed=None, invert_y=True):
    """Draw objects ``a`` (blue) and ``b`` (red) and a line per matched pair.

    ``match`` is a :class:`pymodal.Match` (or anything with ``pairs`` and ``excess``). One-to-one
    matches are grey lines, excess matches dashed orange. 3-D objects (``(n, 3)`` arrays) are drawn
    in a 3-D axes. ``closed`` draws the outlines as closed polygons (default: for 2-D objects).
    ``invert_y`` puts row 0 at the top, as in the pressure image. Returns the axes.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != b.shape[1] or a.shape[1] not in (2, 3):
        raise ValueError("a and b must be (n, 2) or (n, 3) arrays of the same dimension")
    pairs = np.asarray(match.pairs, dtype=np.int64).reshape(-1, 2)
    excess = np.asarray(getattr(match, "excess", np.zeros(len(pairs), bool)), dtype=bool)
    three_d = a.shape[1] == 3
    ax = _axes(ax, "3d" if three_d else None)
    if closed is None:
        closed = not three_d
    for pts, colour in ((a, "tab:blue"), (b, "tab:red")):
        if closed and not three_d:
            loop = np.vstack([pts, pts[:1]])
            ax.plot(loop[:, 0], loop[:, 1], "-", color=colour, lw=1)
        ax.scatter(*pts.T, s=8, color=colour)
    for (i, j), ex in zip(pairs, excess):
        if ex and not show_excess:
            continue
        seg = np.vstack([a[i], b[j]])
        style = dict(color="tab:orange", ls="--") if ex else dict(color="0.5", ls="-")
        ax.plot(*seg.T, lw=0.8, **style)
    if not three_d:
        ax.set_aspect("equal")
        if invert_y and not ax.yaxis_inverted():
            ax.invert_yaxis()
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
