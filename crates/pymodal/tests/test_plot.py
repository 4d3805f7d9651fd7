"""The matplotlib helpers (pymodal.plot_match, pymodal.plot_frame) and the HTML summaries Jupyter
shows for pymodal.run and a Match: what is drawn and what is said, checked on the artists."""

import pickle
import subprocess
import sys

import numpy as np
import pytest

import pymodal

mpl = pytest.importorskip("matplotlib")
mpl.use("Agg")
from matplotlib.collections import LineCollection  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def ellipse(n, scale=1.0, shift=0.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[3 * np.cos(t), 2 * np.sin(t)] * scale + shift


def blob_recording(frames=3, pitch_mm=(5.0, 4.0)):
    r, c = np.mgrid[0:30, 0:20]
    out = np.zeros((frames, 30, 20), np.float32)
    for t in range(frames):
        q = ((c - 9 - t) / 5.0) ** 2 + ((r - 14) / 9.0) ** 2
        out[t] = np.maximum(0.0, 300.0 * (1.0 - q))
    return pymodal.Recording.from_array(out, pitch_mm=pitch_mm, frame_rate=50.0, units="kPa")


def segments(ax):
    """(one-to-one segments, excess segments) as drawn: LineCollections by line style."""
    cols = [c for c in ax.collections if isinstance(c, LineCollection)]
    dashed = [c for c in cols if c.get_linestyle()[0][1] is not None]
    solid = [c for c in cols if c.get_linestyle()[0][1] is None]
    count = lambda cs: sum(len(c.get_segments()) for c in cs)  # noqa: E731
    return solid, count(solid), count(dashed)


def test_plot_match_draws_every_match_coloured_by_cost_in_mm():
    a, b = ellipse(40), ellipse(30, 1.1, 0.3)
    m = pymodal.match(a, b)
    assert m.excess_count > 0 and len(m.unmatched_a) + len(m.unmatched_b) == 0
    ax = pymodal.plot_match(m, a, b, pitch_mm=5.0)
    solid, n_one, n_excess = segments(ax)
    assert n_one == m.optimisation_count
    assert n_excess == m.excess_count
    # The segments join a's node to b's, in mm; their colours follow the costs.
    one = m.pairs[~m.excess]
    drawn = np.asarray(solid[0].get_segments())
    np.testing.assert_allclose(drawn[:, 0], a[one[:, 0]] * 5.0)
    np.testing.assert_allclose(drawn[:, 1], b[one[:, 1]] * 5.0)
    np.testing.assert_allclose(solid[0].get_array(), m.costs[~m.excess])
    assert len(ax.lines) == 2, "the two closed outlines"
    assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "y (mm)"
    bars = [a_ for a_ in ax.figure.axes if a_ is not ax]
    assert len(bars) == 1 and bars[0].get_ylabel() == "match cost"
    assert ax.yaxis_inverted()


def test_plot_match_rings_unmatched_nodes_and_draws_3d():
    a, b = ellipse(40), ellipse(30, 1.1, 0.3)
    m = pymodal.match(a, b, excess=False)
    ax = pymodal.plot_match(m, a, b)
    assert ax.get_xlabel() == "x (sensels)"
    _, n_one, n_excess = segments(ax)
    assert (n_one, n_excess) == (30, 0)
    rings = [c for c in ax.collections if c.get_label() == "unmatched"]
    assert sum(len(c.get_offsets()) for c in rings) == len(m.unmatched_a) == 10
    # 3-D points: a 3-D axes with a z label.
    rng = np.random.default_rng(0)
    p = np.c_[rng.normal(size=(25, 2)) * 3, rng.random(25)]
    m3 = pymodal.match(p, p + [0.1, 0.0, 0.0])
    ax3 = pymodal.plot_match(m3, p, p + [0.1, 0.0, 0.0])
    assert ax3.name == "3d" and ax3.get_zlabel() == "z"
    ax3 = pymodal.plot_match(m3, p, p + [0.1, 0.0, 0.0], pitch_mm=5.08, zlabel="pressure (scaled)")
    assert ax3.get_zlabel() == "pressure (scaled)" and ax3.get_xlabel() == "x (mm)"
    with pytest.raises(ValueError, match="beyond"):
        pymodal.plot_match(m, a[:5], b)


def test_plot_frame_shows_pressure_in_mm_with_colour_bar_and_contours():
    rec = blob_recording()
    ax = pymodal.plot_frame(rec, 1)
    image = ax.images[0]
    frame = rec.frames[1]
    np.testing.assert_allclose(np.ma.filled(image.get_array(), np.nan), frame)
    # The image covers the grid in mm: 20 columns of 5 mm, 30 rows of 4 mm, row 0 at the top.
    assert image.get_extent() == pytest.approx((-2.5, 97.5, 118.0, -2.0))
    assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "y (mm)"
    assert ax.get_title() == "frame 1, 0.020 s"
    bar = [a for a in ax.figure.axes if a is not ax]
    assert len(bar) == 1 and bar[0].get_ylabel() == "pressure (kPa)"
    # One closed outline: the blob's contour, in mm, around its centre (column 10, row 14).
    contours = pymodal.contours(frame)
    assert len(ax.lines) == len(contours) == 1
    x, y = ax.lines[0].get_data()
    assert x[0] == x[-1] and y[0] == y[-1]
    assert np.mean(x) == pytest.approx(10 * 5.0, abs=2.5)
    assert np.mean(y) == pytest.approx(14 * 4.0, abs=2.0)
    # Without a pitch: sensels.
    ax = pymodal.plot_frame(blob_recording(pitch_mm=None), 0, contours=False)
    assert ax.get_xlabel() == "x (sensels)" and len(ax.lines) == 0
    with pytest.raises(IndexError):
        pymodal.plot_frame(rec, 3)


def test_run_result_shows_its_summary_as_html():
    rec = blob_recording(frames=4)
    res = pymodal.run(rec)
    assert isinstance(res, dict) and isinstance(res, pymodal.RunResult)
    s = res["summary"]
    # The plain repr is one line of counts, not every match and track.
    text = repr(res)
    assert "\n" not in text and len(text) < 400, text
    assert text.startswith("RunResult(input=") and f"pairs={s['pairs']}" in text
    assert "keys: table, matches, reference_matches, objects, tracks" in text
    html = res._repr_html_()
    assert html.startswith("<table") and html.endswith("</table>")
    for text in (
        "Recording",
        "4 of 30 × 20 sensels",
        "5.0 × 4.0 mm",
        "50 Hz",
        f"<td style='text-align:left'>{s['pairs']}</td>",
        f"{s['mean_local_percent']:.1f} %",
        f"{s['mean_optimisation_percent']:.1f} %",
        f"{s['mean_cost']:.4f}",
        "0 frames, 0 pairs",
        f"matching {s['timings_s']['matching']:.3f} s",
    ):
        assert text in html, text
    # Still a plain dict to pickle, and the wrapper keeps run's signature and help.
    assert pickle.loads(pickle.dumps(res))["summary"] == s
    import inspect

    assert "iso_levels" in inspect.signature(pymodal.run).parameters
    assert "Match the objects of a whole recording" in pymodal.run.__doc__


def test_match_shows_its_counts_as_html():
    a, b = ellipse(40), ellipse(30, 1.1, 0.3)
    m = pymodal.match(a, b)
    html = m._repr_html_()
    mean = np.mean(m.costs[~m.excess])
    for k, v in (("matches", len(m.pairs)), ("one-to-one", m.optimisation_count),
                 ("excess", m.excess_count), ("local (mutual best)", m.local_count),
                 ("mean one-to-one cost", f"{mean:.4f}")):
        assert f"<th style='text-align:left'>{k}</th><td>{v}</td>" in html, k


def test_without_matplotlib_the_helpers_say_how_to_install_it():
    code = (
        "import sys; sys.modules['matplotlib'] = None; sys.modules['matplotlib.pyplot'] = None\n"
        "import numpy as np, pymodal\n"
        "a = np.c_[np.cos(np.arange(12)), np.sin(np.arange(12))]\n"
        "m = pymodal.match(a, a)\n"
        "try:\n"
        "    pymodal.plot_match(m, a, a)\n"
        "except ImportError as e:\n"
        "    print(e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pip install 'pedomatch[plot]'" in out.stdout, out.stdout + out.stderr


def legend_texts(ax):
    legend = ax.get_legend()
    assert legend is not None, "no legend"
    return [t.get_text() for t in legend.get_texts()]


def colour_bar_labels(ax):
    return sorted(a.get_ylabel() or a.get_xlabel() for a in ax.figure.axes if a is not ax)


def extent(artist):
    return artist.get_window_extent(artist.figure.canvas.get_renderer())


def assert_legend_off_the_data_and_under_the_title(ax):
    """The legend lies above the axes (never over the data), the title above the legend."""
    ax.figure.canvas.draw()
    legend, box = extent(ax.get_legend()), ax.get_window_extent()
    assert legend.y0 >= box.y1 - 1, (legend, box)
    assert extent(ax.title).y0 >= legend.y1 - 1, (extent(ax.title), legend)


def test_plot_match_explains_its_marks_with_a_legend_and_a_title():
    a, b = ellipse(40), ellipse(30, 1.1, 0.3)
    m = pymodal.match(a, b, excess=True)
    ax = pymodal.plot_match(m, a, b, labels=("frame 40", "frame 41"))
    texts = legend_texts(ax)
    assert texts[:2] == ["frame 40", "frame 41"]
    assert "one-to-one match (colour: cost)" in texts and "excess match" in texts
    assert ax.get_title() == (f"frame 40 → frame 41\n{m.optimisation_count} one-to-one, "
                              f"{m.excess_count} excess, 0 unmatched")
    assert ax.get_xlabel() == "x (sensels)" and ax.get_ylabel() == "y (sensels)"
    # Without excess matches, the rings of unmatched nodes are explained instead.
    m = pymodal.match(a, b, excess=False)
    ax = pymodal.plot_match(m, a, b, pitch_mm=(5.0, 4.0), title="mine")
    texts = legend_texts(ax)
    assert texts[:2] == ["A", "B"] and "unmatched" in texts and "excess match" not in texts
    assert ax.get_title() == "mine" and ax.get_xlabel() == "x (mm)"
    assert pymodal.plot_match(m, a, b, legend=False).get_legend() is None
    assert_legend_off_the_data_and_under_the_title(pymodal.plot_match(m, a, b))
    with pytest.raises(pymodal.InputError, match="a and b must be"):
        pymodal.plot_match(m, a, np.zeros((5, 3)))
    with pytest.raises(pymodal.InputError, match="pitch_mm"):
        pymodal.plot_match(m, a, b, pitch_mm=-1.0)


def fake_tracks(n=60):
    """n tracks of lengths 3..n+2 frames: track k starts at frame k % 5 and moves right."""
    out = []
    for k in range(n):
        length = 3 + k
        f = np.arange(length) + k % 5
        out.append(np.c_[f, 2.0 + 0.1 * np.arange(length), 1.0 + 0.2 * k * np.ones(length)])
    return out


def track_collections(ax):
    return [c for c in ax.collections if isinstance(c, LineCollection)]


def test_plot_tracks_draws_the_longest_tracks_in_mm_with_labels_legend_and_colour_bars():
    tracks = fake_tracks(60)
    rec = blob_recording(frames=3, pitch_mm=(5.0, 4.0))
    ax = pymodal.plot_tracks(tracks, background=rec)
    lines = track_collections(ax)
    assert len(lines) == 40, "the 40 longest by default, like the CLI's tracks.png"
    # The longest 40 are tracks 20..59; drawn in mm (x times 5, y times 4).
    drawn = sorted(len(c.get_segments()) + 1 for c in lines)
    assert drawn == [len(t) for t in tracks[20:]]
    first = max(lines, key=lambda c: len(c.get_segments())).get_segments()[0]
    np.testing.assert_allclose(first[0], tracks[59][0, 1:3] * [5.0, 4.0])
    assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "y (mm)"
    assert ax.get_title() == "node tracks, frames 0–65\n40 longest of 60 (≥ 3 frames)"
    assert colour_bar_labels(ax) == ["peak pressure (kPa)", "time (s)"]
    assert legend_texts(ax) == ["node track (colour: time)", "track start"]
    # Colours follow time: the recording's frame interval (50 Hz) times the frame.
    longest = max(lines, key=lambda c: len(c.get_segments()))
    np.testing.assert_allclose(longest.get_array(), tracks[59][:-1, 0] * 0.02)
    image = ax.images[0]
    assert image.get_extent() == pytest.approx((-2.5, 97.5, 118.0, -2.0))
    assert_legend_off_the_data_and_under_the_title(ax)


def test_plot_tracks_without_pitch_is_in_sensels_and_longest_none_draws_all():
    tracks = fake_tracks(12)
    ax = pymodal.plot_tracks(tracks, longest=None, min_length=5)
    assert len(track_collections(ax)) == 10
    assert ax.get_xlabel() == "x (sensels)" and ax.get_ylabel() == "y (sensels)"
    assert ax.get_title() == "node tracks, frames 0–15\nall 10 (≥ 5 frames)"
    assert colour_bar_labels(ax) == ["frame"]
    assert "node track (colour: time)" in legend_texts(ax)
    assert ax.yaxis_inverted()
    ax = pymodal.plot_tracks(tracks, longest=3, pitch_mm=2.0)
    assert len(track_collections(ax)) == 3 and ax.get_xlabel() == "x (mm)"
    with pytest.raises(pymodal.InputError, match=r"tracks\[1\]"):
        pymodal.plot_tracks([tracks[0], np.zeros((4, 2))])



def test_plot_tracks_of_a_run_uses_its_pitch_and_frame_rate_unless_given():
    rec = blob_recording(frames=4, pitch_mm=(5.0, 4.0))
    res = pymodal.run(rec)
    ax = pymodal.plot_tracks(res, min_length=2)
    assert ax.get_xlabel() == "x (mm)" and colour_bar_labels(ax) == ["time (s)"]
    longest = max(track_collections(ax), key=lambda c: len(c.get_segments()))
    track = max(res["tracks"], key=len)
    np.testing.assert_allclose(longest.get_segments()[0][0], track[0, 1:3] * [5.0, 4.0])
    np.testing.assert_allclose(longest.get_array(), track[:-1, 0] * 0.02)
    ax = pymodal.plot_tracks(res, min_length=2, pitch_mm=1.0, dt_s=1.0)
    assert colour_bar_labels(ax) == ["time (s)"]
    np.testing.assert_allclose(max(track_collections(ax), key=lambda c: len(c.get_segments()))
                               .get_segments()[0][0], track[0, 1:3])


def test_plot_tracks_of_an_isocontour_run_are_coloured_by_level_over_its_frame():
    rec = blob_recording(frames=3)
    res = pymodal.run(rec, model="isocontour", iso_levels=6, spacing=1.0)
    objects = res["objects"]
    frame = objects[0]["frame"]
    levels = sorted(o["level"] for o in objects)
    ax = pymodal.plot_tracks(res, background=rec, min_length=2)
    # The levels order the steps: the colour bar is in the pressure units, not in time.
    assert colour_bar_labels(ax) == ["isobaric level (kPa)", f"pressure, frame {frame} (kPa)"]
    title = ax.get_title()
    assert f"frame {frame}" in title and f"{len(objects)} isobaric levels" in title
    assert f"{levels[0]:.0f}–{levels[-1]:.0f} kPa" in title and "frames" not in title
    np.testing.assert_allclose(np.ma.filled(ax.images[0].get_array(), np.nan), rec.frames[frame])
    assert "node track (colour: level)" in legend_texts(ax)
    lines = track_collections(ax)
    assert lines
    for c in lines:
        assert set(np.round(c.get_array(), 9)) <= set(np.round(levels, 9))
    assert_legend_off_the_data_and_under_the_title(ax)


def test_plot_tracks_takes_each_steps_level_from_its_object_not_its_position():
    rec = blob_recording(frames=3)
    res = pymodal.run(rec, model="isocontour", iso_levels=6, spacing=1.0)
    level = {o["id"]: o["level"] for o in res["objects"]}
    expected = {}
    for t, s in zip(res["tracks"], res["track_steps"]):
        if len(t) >= 2:
            expected[tuple(map(tuple, t[:, 1:3]))] = [level[o] for o in s[:-1, 0]]
    # Points moved off the tracks' positions (e.g. re-sampled for a figure) change nothing:
    # the levels come from the steps' objects.
    moved = pymodal.RunResult(res)
    moved["objects"] = [dict(o, points=o["points"] + 0.25) for o in res["objects"]]
    ax = pymodal.plot_tracks(moved, min_length=2, longest=None, pitch_mm=1.0)
    lines = track_collections(ax)
    assert len(lines) == len(expected)
    for c in lines:
        xy = np.concatenate([c.get_segments()[0][:1], np.asarray(c.get_segments())[:, 1]])
        np.testing.assert_allclose(c.get_array(), expected[tuple(map(tuple, xy))])
    # Without its track_steps (tracks alone), a result's tracks are coloured by time.
    ax = pymodal.plot_tracks(res["tracks"], min_length=2)
    assert colour_bar_labels(ax) == ["frame"]


def test_readme_three_panels_do_not_overlap():
    # The example of docs/python.md: no two texts of different panels or colour bars overlap (titles,
    # axis labels, tick labels, colour bar labels, legends).
    rec = blob_recording(frames=6)
    a = max(pymodal.contours(rec.frames[2], spacing=1.0), key=len)
    b = max(pymodal.contours(rec.frames[3], spacing=1.0), key=len)
    m = pymodal.match(a, b)
    res = pymodal.run(rec)
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(14, 8), layout="constrained")
    pymodal.plot_frame(rec, 2, ax=left)
    pymodal.plot_match(m, a, b, ax=middle, pitch_mm=rec.pitch_mm, labels=("frame 2", "frame 3"))
    pymodal.plot_tracks(res, ax=right, background=rec, min_length=2)
    fig.canvas.draw()
    boxes = []
    for k, ax in enumerate(fig.axes):
        texts = [ax.title, ax.xaxis.label, ax.yaxis.label]
        texts += [t for t in ax.get_xticklabels() + ax.get_yticklabels() if t.get_text()]
        if ax.get_legend() is not None:
            texts.append(ax.get_legend())
        boxes += [(k, extent(t)) for t in texts if t.get_visible() and (
            not hasattr(t, "get_text") or t.get_text())]
    for i, (ka, ba) in enumerate(boxes):
        for kb, bb in boxes[i + 1:]:
            if ka != kb:
                assert not ba.overlaps(bb), (fig.axes[ka], fig.axes[kb], ba, bb)


def tall_and_wide_plots(shape):
    """Each helper on its own figure, for an object 4 times taller than wide (a foot's outline)
    or 4 times wider than tall; with the data's extent in mm, (width, height)."""
    t = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    long, short = 40.0 + 12.0 * np.sin(t), 15.0 + 3.0 * np.cos(t)
    a = np.c_[short, long] if shape == "tall" else np.c_[long, short]
    b = a + 0.6 * np.c_[np.sin(3 * t), np.cos(5 * t)]
    rows, cols = (60, 30) if shape == "tall" else (30, 60)
    frames = np.zeros((2, rows, cols), np.float32)
    r, c = np.mgrid[0:rows, 0:cols]
    q = ((c - cols / 2) / (0.1 * cols if shape == "tall" else 0.4 * cols)) ** 2 + (
        (r - rows / 2) / (0.4 * rows if shape == "tall" else 0.1 * rows)) ** 2
    frames[:] = np.maximum(0.0, 100.0 * (1.0 - q))
    rec = pymodal.Recording.from_array(frames, pitch_mm=5.0, units="kPa")
    tracks = [np.c_[np.arange(3), a[k] + [[0, 0], [0.2, 0.1], [0.4, 0.2]]] for k in range(0, 48, 4)]
    m = pymodal.match(a, b)
    span = lambda p: np.ptp(p, axis=0) * 5.0  # noqa: E731
    return [
        (pymodal.plot_match(m, a, b, pitch_mm=5.0), span(np.r_[a, b])),
        (pymodal.plot_tracks(tracks, pitch_mm=5.0), span(np.concatenate([t[:, 1:] for t in tracks]))),
        (pymodal.plot_frame(rec, 0, contours=False), np.array([cols, rows]) * 5.0),
    ]


@pytest.mark.parametrize("shape", ["tall", "wide"])
def test_a_figure_the_helpers_make_is_sized_to_the_data(shape):
    for ax, (data_w, data_h) in tall_and_wide_plots(shape):
        fig = ax.figure
        fig.canvas.draw()
        w, h = fig.get_size_inches()
        assert (h > w) if shape == "tall" else (w > h), (ax.get_title(), w, h)
        # No band of blank space beside the axes: they fill the room the layout gives them (the
        # limits keep the aspect), and the colour bars stand against them.
        box, drawn = ax.get_position(original=True), ax.get_position()
        assert drawn.bounds == pytest.approx(box.bounds), ax.get_title()
        bars = [b for b in fig.axes if b is not ax]
        gap = (min(b.get_position().x0 for b in bars) - drawn.x1) * w
        assert 0 < gap < 0.5, (ax.get_title(), gap)
        # Along its long side the data span the axes (autoscale's margins); across, the axes are
        # no wider than the data or than the title and legend above them need, and a wide
        # object's axes stay tall enough for a readable colour bar.
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        mm_per_inch = abs(y1 - y0) / (drawn.height * h)
        assert abs(x1 - x0) / (drawn.width * w) == pytest.approx(mm_per_inch, rel=1e-3), "equal aspect"
        above = max(extent(t).width / fig.dpi for t in (ax.title, ax.get_legend()) if t is not None)
        if shape == "tall":
            assert abs(y1 - y0) <= 1.15 * data_h, ax.get_title()
            assert drawn.width * w <= max(1.15 * data_w / mm_per_inch, above) + 0.1, ax.get_title()
        else:
            assert abs(x1 - x0) <= 1.15 * data_w, ax.get_title()
            assert drawn.height * h <= max(1.15 * data_h / mm_per_inch, 2.5) + 0.1, ax.get_title()
            assert drawn.height * h >= 2.5 - 0.1, ax.get_title()
        plt.close(fig)


def test_the_callers_axes_and_figure_are_left_as_they_are():
    a = ellipse(40) * [1, 4]
    m = pymodal.match(a, a + 0.2)
    fig, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    assert pymodal.plot_match(m, a, a + 0.2, ax=ax) is ax
    fig.canvas.draw()
    assert tuple(fig.get_size_inches()) == (6.4, 4.8)
    assert ax.get_adjustable() == "box" and ax.get_legend()._ncols == 2
    fig, ax = plt.subplots()
    pymodal.plot_tracks(fake_tracks(5), ax=ax)
    assert tuple(fig.get_size_inches()) == (6.4, 4.8) and ax.get_adjustable() == "box"
