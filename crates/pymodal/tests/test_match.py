"""pymodal.match: ground truth on a warped real outline, result layout, options and errors."""
from pathlib import Path

import numpy as np
import pytest

import pymodal

DATA = Path(__file__).resolve().parents[2] / "modal-core" / "tests" / "data"


def outline(name="MUN104L-level15"):
    pts, started = [], False
    for line in (DATA / "contours.txt").read_text().splitlines():
        if line.startswith("# " + name):
            started = True
        elif line.startswith("#") and started:
            break
        elif started and line.strip():
            pts.append([float(v) for v in line.split()])
    return np.array(pts)


def resample(c, n, start):
    seg = np.linalg.norm(np.roll(c, -1, 0) - c, axis=1)
    cum = np.concatenate([[0], np.cumsum(seg)])
    s = ((start + np.arange(n) / n) % 1.0) * cum[-1]
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(c) - 1)
    f = (s - cum[i]) / seg[i]
    return c[i] + f[:, None] * (np.roll(c, -1, 0)[i] - c[i])


def warp(p, deg=12.0):
    c = np.array([12.0, 30.0])
    t = np.deg2rad(deg)
    r = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    q = (p - c) @ np.diag([1.08, 0.93]) @ r.T
    q[:, 0] += 0.004 * q[:, 1] ** 2  # bending
    return q + c + [5.0, -3.0]


@pytest.fixture(scope="module")
def case():
    o = outline()
    a = resample(o, 60, 0.13)
    wo = warp(o)
    b = resample(wo, 65, 0.71)
    spacing = np.linalg.norm(np.roll(wo, -1, 0) - wo, axis=1).sum() / len(b)
    return a, b, warp(a), spacing


def test_ground_truth_and_layout(case):
    a, b, truth, spacing = case
    m = pymodal.match(a, b)
    assert m.pairs.shape == (65, 2) and m.pairs.dtype == np.int64
    assert m.costs.shape == (65,) and m.excess.dtype == np.bool_
    assert m.affinity.shape == (60, 65)
    assert np.isclose(m.affinity.max(), 1.0) and m.affinity.min() >= 0
    assert np.allclose(m.costs, m.affinity[m.pairs[:, 0], m.pairs[:, 1]])
    assert m.optimisation_count == 60 and m.excess_count == 5 and m.excess.sum() == 5
    assert len(m.unmatched_a) == 0 and len(m.unmatched_b) == 0
    one = m.pairs[~m.excess]
    err = np.linalg.norm(b[one[:, 1]] - truth[one[:, 0]], axis=1)
    assert (err <= spacing).mean() >= 0.97
    # Local matches: mutual best on the returned affinity.
    z = m.affinity
    for i, j in m.local_pairs:
        assert z[i].argmin() == j and z[:, j].argmin() == i
    assert m.local_count == len(m.local_pairs) > 30


def test_swapping_objects_and_searches(case):
    a, b, truth, spacing = case
    m = pymodal.match(b, a)
    assert m.affinity.shape == (65, 60) and len(m.pairs) == 65
    loc = pymodal.match(a, b, search="local")
    assert not loc.excess.any() and len(loc.pairs) == loc.local_count
    for solver in ("hungarian", "simplex"):
        s = pymodal.match(a, b, solver=solver)
        assert np.isclose(s.costs[~s.excess].sum(), pymodal.match(a, b).costs[~pymodal.match(a, b).excess].sum())
    t = pymodal.match(a, b, threshold=0.05, excess=False)
    assert (t.costs <= 0.05).all() and len(t.unmatched_a) > 0


def test_ordered_contours_are_detected_from_the_point_order(case):
    # Left to itself (ordered=None), match treats points that trace an outline in their order as
    # a contour and anything else as a point set; the two recipes differ (excess step, orientation).
    a, b, truth, spacing = case
    as_contour = pymodal.match(a, b, ordered=True)
    as_points = pymodal.match(a, b, ordered=False)
    assert not np.array_equal(as_contour.pairs, as_points.pairs)
    assert np.array_equal(pymodal.match(a, b).pairs, as_contour.pairs)
    perm = np.random.default_rng(0).permutation(len(a))
    scrambled = pymodal.match(a[perm], b)
    assert np.array_equal(scrambled.pairs, pymodal.match(a[perm], b, ordered=False).pairs)
    # The point-set recipe does not depend on the order: mapped back, the same pairs.
    back = np.column_stack([perm[scrambled.pairs[:, 0]], scrambled.pairs[:, 1]])
    for excess in (False, True):
        assert set(map(tuple, back[scrambled.excess == excess])) == set(
            map(tuple, as_points.pairs[as_points.excess == excess])
        )


def test_refine_modal_warps_a_and_keeps_the_affine_part(case):
    a, b, truth, spacing = case
    plain = pymodal.match(a, b)
    # The warp's settings leave the default (affine) path as it was.
    same = pymodal.match(a, b, refine="affine", deform_modes=40, deform_stiffness=0.5)
    assert np.array_equal(plain.pairs, same.pairs) and np.array_equal(plain.aligned_a, same.aligned_a)
    warped = pymodal.match(a, b, refine="modal")
    assert np.all(np.isfinite(warped.aligned_a))
    assert not np.allclose(warped.aligned_a, plain.aligned_a)
    assert np.allclose(warped.transform, plain.transform)
    # The warp moves A towards the truth (this pair is bent, so the affine map leaves a residual).
    err = lambda x: np.sqrt(((x - truth) ** 2).sum(1).mean())
    assert err(warped.aligned_a) < err(plain.aligned_a), (err(warped.aligned_a), err(plain.aligned_a))
    # Only the rigid modes: nothing to warp with, the affine result.
    rigid = pymodal.match(a, b, refine="modal", deform_modes=3)
    assert np.array_equal(rigid.pairs, plain.pairs) and np.array_equal(rigid.aligned_a, plain.aligned_a)


def test_refit_tolerance(case):
    a, b, truth, spacing = case
    every = pymodal.match(a, b, refit_tolerance=0.0, refits=3)
    assert every.refits >= 1  # this pair's first pass is not one affine map's worth of pairs
    # A tolerance no residual reaches stops before the first re-fit: the refits=0 result.
    never = pymodal.match(a, b, refit_tolerance=1e9)
    plain = pymodal.match(a, b, refits=0)
    assert never.refits == 0
    assert np.array_equal(never.pairs, plain.pairs) and np.array_equal(never.affinity, plain.affinity)
    assert pymodal.match(a, b).refits <= every.refits


def test_reduced_gaussian_basis(case):
    a, b, truth, spacing = case
    m = pymodal.match(a, b, center_stride=2)
    assert m.n_modes == 30 and m.pairs.shape == (65, 2)
    one = m.pairs[~m.excess]
    err = np.linalg.norm(b[one[:, 1]] - truth[one[:, 0]], axis=1)
    assert (err <= spacing).mean() >= 0.95
    # Same σ: Gaussians on every second node span a subspace of the full element's fields, so
    # every eigenvalue of the reduced model bounds the full one from above (min-max principle).
    full = pymodal.ModalModel(a, kappa=1.6)
    reduced = pymodal.ModalModel(a, sigma=full.sigma, center_stride=2)
    assert reduced.modes.shape == (120, 60) and full.modes.shape == (120, 120)
    assert np.all(reduced.eigenvalues >= full.eigenvalues[:60] * (1 - 1e-9))
    assert np.allclose(reduced.eigenvalues[:4], full.eigenvalues[:4], rtol=0.1)  # smooth modes agree
    with pytest.raises(ValueError, match="reduced"):
        reduced.stiffness()  # no nodal K, M for a reduced basis


def test_rotation_search_on_a_rounded_heel():
    # The nearly round heel blob of a late F-Scan frame, turned 15-35 degrees and stretched:
    # affine ICP from the five principal-axes starts stops in a wrong minimum, the dense search does not.
    o = outline("FrasP01L-frame67-late")
    c = o.mean(0)

    def turn(p, deg, sx, sy):
        t = np.deg2rad(deg)
        r = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        return ((p - c) @ np.diag([sx, sy])) @ r.T + c + [2.0, -1.0]

    acc = {"robust": []}
    for deg in (-35, -25, -15, 15, 25, 35):
        for sx, sy in ((1.2, 0.85), (0.85, 1.15)):
            a = resample(o, 50, 0.3)
            wo = turn(o, deg, sx, sy)
            b = resample(wo, 54, 0.8)
            truth = turn(a, deg, sx, sy)
            spacing = np.linalg.norm(np.roll(wo, -1, 0) - wo, axis=1).sum() / len(b)
            for k in acc:
                m = pymodal.match(a, b, prealign=k)
                one = m.pairs[~m.excess]
                err = np.linalg.norm(b[one[:, 1]] - truth[one[:, 0]], axis=1)
                acc[k].append((err <= spacing).mean())
    # Measured 1.00 in all 12 cases with the default (0.08 on average with the five starts of a
    # plain identity / principal-axes search).
    assert min(acc["robust"]) >= 0.95


def test_material_invariance(case):
    a, b, _, _ = case
    m1 = pymodal.match(a, b, material=(1.0, 0.49, 1.0))
    m2 = pymodal.match(a, b, material={"young": 7e6, "poisson": 0.49, "density": 1100.0})
    np.testing.assert_array_equal(m1.pairs, m2.pairs)
    m3 = pymodal.match(a, b, material="rubber")
    assert len(m3.pairs) == 65


def test_surfaces_3d():
    rng = np.random.default_rng(0)
    a = rng.uniform(-1, 1, (80, 3)) * [3.0, 6.0, 1.0]
    a[:, 2] = np.exp(-(a[:, 0] ** 2 + (a[:, 1] / 2) ** 2) / 4)
    perm = rng.permutation(80)
    t = np.deg2rad(20)
    r = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    b = (a @ r.T)[perm] * 1.1 + 2.0
    m = pymodal.match(a, b)
    assert (perm[m.pairs[:, 1]] == m.pairs[:, 0]).mean() >= 0.95


def _pressure(g, p):
    x = np.clip(p[:, 0], 0, g.shape[1] - 1.001)
    y = np.clip(p[:, 1], 0, g.shape[0] - 1.001)
    i, j = y.astype(int), x.astype(int)
    fy, fx = y - i, x - j
    return (g[i, j] * (1 - fx) * (1 - fy) + g[i, j + 1] * fx * (1 - fy)
            + g[i + 1, j] * (1 - fx) * fy + g[i + 1, j + 1] * fx * fy)


def _surface_cases():
    """Two independent samplings of a real pressure image (x, y, pressure), b warped: no point
    of b sits where a point of a lands. Yields a, b, the true positions of a's points in b's
    frame, and b's mean nearest-neighbour distance (the tolerance)."""
    from scipy.spatial import cKDTree

    g = np.loadtxt(DATA / "mun104l.txt")
    zs = 20.0 / 350.0
    for seed in range(6):
        rng = np.random.default_rng(seed)

        def sample(n):
            out = np.empty((0, 2))
            while len(out) < n:
                p = rng.uniform([0, 0], [g.shape[1] - 1, g.shape[0] - 1], (4 * n, 2))
                out = np.vstack([out, p[_pressure(g, p) > 30.0]])
            return out[:n]

        pa, pb = sample(110), sample(118)
        t = np.deg2rad(12)
        r = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        c = pa.mean(0)

        def w(p):
            return ((p - c) @ np.diag([1.1, 0.92])) @ r.T + c + [2.0, -1.0]

        a = np.column_stack([pa, zs * _pressure(g, pa)])
        b = np.column_stack([w(pb), 1.05 * zs * _pressure(g, pb)])
        truth = np.column_stack([w(pa), 1.05 * zs * _pressure(g, pa)])
        yield a, b, truth, cKDTree(b).query(b, 2)[0][:, 1].mean()


def _hits(m, b, truth, tol):
    """Share of a's points whose (one-to-one, non-excess) partner is within tol of the truth."""
    one = ~m.excess  # a has fewer points: every one of them is in a non-excess pair
    i, j = m.pairs[one, 0], m.pairs[one, 1]
    return (np.linalg.norm(b[j] - truth[i], axis=1) <= tol).sum() / len(truth)


def test_independent_surface_samplings_against_the_squared_cost_oracle():
    # An assignment of squared distances, even on the TRUE positions (scipy), puts only about a
    # quarter of a's points within one spacing; the surface defaults (powered costs) must do
    # clearly better from the data alone.
    from scipy.optimize import linear_sum_assignment

    got, squared, oracle = [], [], []
    for a, b, truth, tol in _surface_cases():
        got.append(_hits(pymodal.match(a, b), b, truth, tol))
        squared.append(_hits(pymodal.match(a, b, cost_power=1.0), b, truth, tol))
        ri, ci = linear_sum_assignment(((truth[:, None] - b[None]) ** 2).sum(2))
        oracle.append((np.linalg.norm(b[ci] - truth[ri], axis=1) <= tol).mean())
    got, squared, oracle = np.mean(got), np.mean(squared), np.mean(oracle)
    assert got > oracle + 0.05, (got, oracle)
    assert got > squared + 0.05, (got, squared)


def test_best_search_is_the_row_minimum_many_to_one():
    best, one_to_one = [], []
    for a, b, truth, tol in _surface_cases():
        m = pymodal.match(a, b, search="best")
        assert m.pairs.shape == (len(a), 2) and not m.excess.any()
        np.testing.assert_array_equal(m.pairs[:, 0], np.arange(len(a)))
        np.testing.assert_array_equal(m.pairs[:, 1], m.affinity.argmin(1))
        best.append(_hits(m, b, truth, tol))
        one_to_one.append(_hits(pymodal.match(a, b), b, truth, tol))
    assert np.mean(best) > np.mean(one_to_one) + 0.05, (np.mean(best), np.mean(one_to_one))


@pytest.mark.parametrize(
    "kwargs, text",
    [
        (dict(search="nearest"), "search = nearest: expected one of global, local, best"),
        (dict(solver="lapjv"), "solver = lapjv: expected one of jv, hungarian, simplex"),
        (dict(element="spline"), "element = spline"),
        (dict(modes=0.0), "modes = 0"),
        (dict(threshold=-1.0), "threshold = -1"),
        (dict(threshold_mode="before"), "threshold_mode = before"),
        (dict(material="jelly"), "material = jelly"),
        (dict(prealign="pca"), "prealign = pca"),
        (dict(prealign="spec"), "prealign = spec"),
        (dict(refit_tolerance=-0.5), "refit_tolerance"),
        (dict(center_stride=0), "center_stride"),
        (dict(refit_tolerance=float("nan")), "refit_tolerance"),
        (dict(kappa=0.0), "kappa"),
        (dict(position_weight=1.5), "position_weight"),
        (dict(cost_power=0.0), "cost_power"),
        (dict(cost_power=float("inf")), "cost_power"),
        (dict(refine="tps"), "refine = tps: expected one of affine, modal"),
        (dict(refine="modal", deform_stiffness=0.0), "deform_stiffness"),
    ],
)
def test_bad_options(case, kwargs, text):
    a, b, _, _ = case
    with pytest.raises(ValueError, match=text):
        pymodal.match(a, b, **kwargs)


def test_bad_inputs(case):
    a, b, _, _ = case
    with pytest.raises(ValueError, match="columns"):
        pymodal.match(a[:, :1], b)
    with pytest.raises(ValueError):
        pymodal.match(a, np.column_stack([b, b[:, :1]]))
    bad = a.copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        pymodal.match(bad, b)
    with pytest.raises(ValueError, match="at least 3"):
        pymodal.match(a[:2], b)
    dup = a.copy()
    dup[4] = dup[5]
    with pytest.raises(ValueError, match="coincide"):
        pymodal.match(dup, b)
    with pytest.raises(ValueError, match="collinear"):
        pymodal.match(np.column_stack([np.arange(10.0), 2 * np.arange(10.0)]), b)
    with pytest.raises(ValueError):
        pymodal.match("abc", b)


def apply(transform, pts):
    d = pts.shape[1]
    return pts @ transform[:d, :d].T + transform[:d, d]


@pytest.mark.parametrize("kwargs", [dict(), dict(prealign="normalize"), dict(refits=0), dict(search="best")])
def test_transform_maps_a_onto_aligned_a(case, kwargs):
    a, b, _, spacing = case
    m = pymodal.match(a, b, **kwargs)
    assert m.transform.shape == (3, 3) and m.aligned_a.shape == a.shape
    np.testing.assert_array_equal(m.transform[2], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(apply(m.transform, a), m.aligned_a, rtol=0, atol=1e-9 * np.abs(b).max())
    if kwargs.get("prealign") != "normalize":
        # Aligned into b's frame: the one-to-one pairs lie within a few node spacings.
        one = m.pairs[~m.excess]
        gap = np.linalg.norm(m.aligned_a[one[:, 0]] - b[one[:, 1]], axis=1)
        assert np.median(gap) < 2 * spacing


@pytest.mark.parametrize("dim", [2, 3])
def test_transform_recovers_a_rigid_motion(case, dim):
    a = case[0]
    if dim == 3:
        a = np.random.default_rng(7).normal(size=(60, 3)) * [3.0, 2.0, 1.0]
    t = np.deg2rad(35.0)
    rot = np.eye(dim)
    rot[:2, :2] = [[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]
    shift = np.array([4.0, -7.0, 2.5][:dim])
    perm = np.roll(np.arange(len(a)), 11)
    b = (a @ rot.T + shift)[perm]
    m = pymodal.match(a, b)
    truth = np.eye(dim + 1)
    truth[:dim, :dim], truth[:dim, dim] = rot, shift
    np.testing.assert_allclose(m.transform, truth, atol=1e-6)
    np.testing.assert_allclose(m.aligned_a, a @ rot.T + shift, atol=1e-6)
    # Every node found its own image.
    one = m.pairs[~m.excess]
    np.testing.assert_array_equal(perm[one[:, 1]], one[:, 0])
