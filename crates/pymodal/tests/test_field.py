"""pymodal.Field, the correspondence field of a matched pair, against scipy's thin-plate spline
(scipy.interpolate.RBFInterpolator, the same system: kernel r² log r plus an affine part,
``smoothing`` added to the kernel matrix's diagonal), and its errors, inverse and pickling."""

import pickle

import numpy as np
import pytest
from scipy.interpolate import RBFInterpolator

import pymodal


def foot(n=150, s=1.0):
    """A foot-like outline in mm (240 long), n nodes, scaled by s about its centre."""
    t = np.arange(n) / n * 2 * np.pi
    return np.c_[s * 120 * np.cos(t), s * 45 * np.sin(t) * (1 + 0.15 * np.cos(t))]


def bend(p, radius=300.0):
    """The sole wrapped onto a circle of ``radius`` mm, then moved by (5, -3)."""
    theta = p[:, 0] / radius
    return np.c_[(radius - p[:, 1]) * np.sin(theta) + 5, radius - (radius - p[:, 1]) * np.cos(theta) - 3]


INSIDE = np.vstack([foot(60, k / 10) for k in range(9)])
# Beyond the outline too: the two fields must agree where they extrapolate.
PROBE = np.vstack([INSIDE, foot(40, 1.5)])


def scipy_field(a, b, pairs, smoothing):
    return RBFInterpolator(a[pairs[:, 0]], b[pairs[:, 1]], kernel="thin_plate_spline", smoothing=smoothing)


@pytest.mark.parametrize("smoothing", [0.0, 0.5, 50.0, 5e3])
def test_same_field_as_scipy(smoothing):
    # Scrambled numbering and a subset of the nodes: the pairs say who goes with whom.
    rng = np.random.default_rng(7)
    a = foot(150)
    order = rng.permutation(150)
    b = bend(a)[order]
    pairs = np.c_[order.argsort(), np.arange(150)][rng.choice(150, 120, replace=False)]
    field = pymodal.Field(a, b, pairs, smoothing=smoothing)
    want = scipy_field(a, b, pairs, smoothing)(PROBE)
    got = field.apply(PROBE)
    assert got.shape == (len(PROBE), 2) and got.dtype == np.float64
    scale = np.abs(want).max()
    assert np.abs(got - want).max() <= 1e-8 * scale
    np.testing.assert_array_equal(field.pairs, pairs)
    assert field.smoothing == smoothing
    # The residuals are scipy's field's too.
    at_nodes = scipy_field(a, b, pairs, smoothing)(a[pairs[:, 0]])
    expected = np.linalg.norm(at_nodes - b[pairs[:, 1]], axis=1)
    np.testing.assert_allclose(field.residuals, expected, rtol=0, atol=1e-8 * scale)


def test_interpolates_without_smoothing_and_smooths_with():
    a = foot()
    exact = pymodal.Field(a, bend(a), np.c_[np.arange(150), np.arange(150)])
    assert exact.residuals.shape == (150,) and exact.residuals.max() < 1e-9
    smooth = pymodal.Field(a, bend(a), np.c_[np.arange(150), np.arange(150)], smoothing=1e4)
    assert smooth.residuals.max() > 1e-3


def test_affine_maps_are_reproduced_for_every_smoothing():
    a = foot()
    m, t = np.array([[1.1, 0.2], [-0.15, 0.9]]), np.array([12.0, -7.0])
    for smoothing in (0.0, 1.0, 1e6):
        field = pymodal.Field(a, a @ m.T + t, np.c_[np.arange(150), np.arange(150)], smoothing=smoothing)
        assert np.abs(field.apply(PROBE) - (PROBE @ m.T + t)).max() < 1e-9


def test_inverse_brings_points_back():
    a = foot()
    pairs = np.c_[np.arange(150), np.arange(150)]
    for radius, tol in ((3000.0, 0.01), (300.0, 0.8)):
        field = pymodal.Field(a, bend(a, radius), pairs)
        back = field.inverse()
        np.testing.assert_array_equal(back.pairs, pairs[:, ::-1])
        assert np.abs(back.apply(field.apply(INSIDE)) - INSIDE).max() < tol
        assert np.abs(back.apply(field.apply(a)) - a).max() < 1e-9
    # The inverse is scipy's field fitted the other way.
    b = bend(a)
    want = scipy_field(b, a, pairs, 0.0)(bend(PROBE))
    assert np.abs(pymodal.Field(a, b, pairs).inverse().apply(bend(PROBE)) - want).max() <= 1e-8 * np.abs(want).max()


def test_the_element_interpolation_would_leave_the_inside_behind():
    # Why a thin-plate spline (docs/method.md §11): the model's own interpolation
    # u(x) = g(x)ᵀ G⁻¹ u_nodes (Gaussians of width σ = 0.8 × node spacing, the contour
    # recipe's) of the outline nodes' displacements dies out a few σ inside the outline, so
    # the inside barely moves: its error is the whole displacement there.
    a = foot()
    b = bend(a)
    gaps = np.linalg.norm(a[:, None] - a[None], axis=2)
    sigma = 0.8 * np.sort(gaps, axis=1)[:, 1].mean()
    gauss = lambda p: np.exp(-np.linalg.norm(p[:, None] - a[None], axis=2) ** 2 / (2 * sigma**2))
    moved = INSIDE + gauss(INSIDE) @ np.linalg.solve(gauss(a), b - a)
    element = np.linalg.norm(moved - bend(INSIDE), axis=1)
    field = np.linalg.norm(pymodal.Field(a, b, np.c_[np.arange(150), np.arange(150)]).apply(INSIDE) - bend(INSIDE), axis=1)
    # Measured: element max 14.1 mm, median 5.8 mm (the displacement itself); field max 1.01 mm.
    assert element.max() > 13.0 and np.median(element) > 5.0
    assert field.max() < 1.1 and field.max() < element.max() / 10


def test_match_field_uses_the_one_to_one_pairs():
    a = foot(60)
    b = bend(foot(70))
    # The modal match (the bend leaves the outlines far enough apart for the default gate to
    # drift them, and a drifted match's field is fitted to its moved nodes: test_ordered.py).
    m = pymodal.match(a, b, refine="affine")
    assert not m.drifted and m.excess_count > 0
    field = m.field(a, b)
    one_to_one = m.pairs[~m.excess]
    np.testing.assert_array_equal(field.pairs, one_to_one)
    assert field.residuals.max() < 1e-9
    want = scipy_field(a, b, one_to_one, 2.0)(PROBE)
    got = m.field(a, b, smoothing=2.0).apply(PROBE)
    assert np.abs(got - want).max() <= 1e-8 * np.abs(want).max()
    # The same field as one built from those pairs by hand, bit for bit.
    assert field == pymodal.Field(a, b, one_to_one)


def test_degenerate_input_raises_clear_errors():
    a, b = foot(20), bend(foot(20))
    idx = np.c_[np.arange(20), np.arange(20)]
    with pytest.raises(pymodal.DegenerateShapeError, match="2 one-to-one matches; a correspondence field needs at least 3"):
        pymodal.Field(a, b, idx[:2])
    line = np.c_[np.arange(20.0), 2 * np.arange(20.0)]
    with pytest.raises(pymodal.DegenerateShapeError, match="object A: the matched nodes are collinear"):
        pymodal.Field(line, b, idx)
    twice = idx.copy()
    twice[5, 1] = 4
    with pytest.raises(pymodal.DegenerateShapeError, match="object B: node 4 is in two matches"):
        pymodal.Field(a, b, twice)
    nan = a.copy()
    nan[3, 1] = np.nan
    with pytest.raises(pymodal.DegenerateShapeError, match="object A: coordinate 1 of node 3 is not finite"):
        pymodal.Field(nan, b, idx)
    with pytest.raises(pymodal.InputError, match="match 6 names node 20 of object B, which has 20 nodes"):
        pymodal.Field(a, b, np.where(np.arange(40).reshape(20, 2) == 13, 20, idx))
    with pytest.raises(pymodal.InputError, match="maps the plane: got 3-D objects"):
        pymodal.Field(np.c_[a, np.zeros(20)], np.c_[b, np.zeros(20)], idx)
    with pytest.raises(pymodal.InputError, match="pairs must be a \\(k, 2\\) array"):
        pymodal.Field(a, b, np.arange(20))
    with pytest.raises(pymodal.InputError, match="negative index"):
        pymodal.Field(a, b, -idx)
    for bad in (-1.0, float("nan")):
        with pytest.raises(pymodal.OptionError, match="smoothing"):
            pymodal.Field(a, b, idx, smoothing=bad)
    field = pymodal.Field(a, b, idx)
    with pytest.raises(pymodal.InputError, match="points must be a \\(k, 2\\) array"):
        field.apply(np.zeros((4, 3)))
    # Every error is a ValueError too; a point that is not finite maps to NaN, no error.
    assert issubclass(pymodal.DegenerateShapeError, ValueError)
    out = field.apply([[np.nan, 0.0], [1.0, 2.0]])
    assert np.isnan(out[0]).all() and np.isfinite(out[1]).all()
    assert field.apply(np.zeros((0, 2))).shape == (0, 2)


def test_pickles_bit_for_bit_and_compares_by_value():
    a = foot()
    field = pymodal.Field(a, bend(a), np.c_[np.arange(150), np.arange(150)], smoothing=3.0)
    y = pickle.loads(pickle.dumps(field))
    assert y == field and hash(y) == hash(field) and y is not field
    np.testing.assert_array_equal(y.apply(PROBE), field.apply(PROBE))
    np.testing.assert_array_equal(y.residuals, field.residuals)
    assert repr(y) == repr(field)
    assert repr(field).startswith("Field(pairs=150, smoothing=3.0, max_residual=")
    assert field != field.inverse() and field != "field"
    assert not field.residuals.flags.writeable and field.apply(PROBE).flags.writeable
