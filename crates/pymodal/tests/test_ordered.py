"""solver="ordered": the order-preserving assignment of closed contours, Match.crossings, the run
table's crossings column, and the errors elsewhere."""
import pickle
from pathlib import Path

import numpy as np
import pytest

import pymodal
from test_match import outline, resample, warp

BUNDLED = Path(__file__).resolve().parents[3] / "examples" / "data" / "FrasP01L.asf"


def cyclic_order_kept(pairs):
    """At most one cyclic descent of the partners read in row order (the definition)."""
    p = pairs[np.argsort(pairs[:, 0])]
    return int((np.roll(p[:, 1], -1) < p[:, 1]).sum()) <= 1


@pytest.fixture(scope="module")
def contours():
    o = outline()
    return resample(o, 60, 0.13), resample(warp(o), 65, 0.71)


def test_ordered_matches_keep_the_cyclic_order(contours):
    a, b = contours
    m = pymodal.match(a, b, solver="ordered")
    one = m.pairs[~m.excess]
    assert len(one) == 60 and m.crossings == 0
    assert cyclic_order_kept(one)
    # Also for a clockwise numbering of b: the matches, not the numbering, keep the order.
    rev = pymodal.match(a, b[::-1].copy(), solver="ordered")
    assert rev.crossings == 0
    assert sorted(map(tuple, rev.pairs[~rev.excess])) == sorted((i, 64 - j) for i, j in one)
    jv = pymodal.match(a, b)
    assert isinstance(jv.crossings, int) and jv.crossings >= 0
    # The ordered optimum is never cheaper than the unconstrained one.
    assert m.costs[~m.excess].sum() >= jv.costs[~jv.excess].sum() - 1e-9
    assert pickle.loads(pickle.dumps(m)).crossings == 0
    # With the threshold inside the optimiser: the cyclic alignment with gaps, still in order.
    gaps = pymodal.match(a, b, solver="ordered", threshold=0.05, threshold_mode="during")
    assert gaps.crossings == 0 and gaps.optimisation_count < 60
    assert (gaps.costs[~gaps.excess] <= 0.05).all()


def test_crossings_counted_where_the_free_assignment_crosses():
    # The paper's setting (no rotation search) on a 40° rotation crosses many matches (260
    # measured); the ordered solver in the same setting never does.
    o = outline()
    a, b = resample(o, 56, 0.3), resample(warp(o, deg=40.0), 61, 0.9)
    free = pymodal.match(a, b, paper=True)
    ordered = pymodal.match(a, b, paper=True, solver="ordered")
    assert free.crossings > 100
    assert ordered.crossings == 0 and cyclic_order_kept(ordered.pairs[~ordered.excess])


def test_ordered_needs_closed_contours(contours):
    a, b = contours
    assert pymodal.match(a, b, ordered=False).crossings is None
    with pytest.raises(ValueError, match="closed contours"):
        pymodal.match(a, b, ordered=False, solver="ordered")
    rng = np.random.default_rng(1)
    cloud = rng.normal(size=(40, 3))
    with pytest.raises(ValueError, match="closed contours"):
        pymodal.match(cloud, cloud + 0.01, solver="ordered")


def test_linear_sum_assignment_ordered():
    cost = np.array([[9.0, 9.0, 0.0, 9.0], [9.0, 9.0, 9.0, 0.0], [0.0, 9.0, 9.0, 9.0]])
    r, c = pymodal.linear_sum_assignment(cost, solver="ordered")
    assert r.tolist() == [0, 1, 2] and c.tolist() == [2, 3, 0]  # wraps past the last column


def test_run_table_has_crossings():
    res = pymodal.run(str(BUNDLED), frames=(40, 46), solver="ordered")
    matched = [row for row in res["table"] if row["status"] == "ok"]
    assert len(matched) >= 5 and len(res["matches"]) == len(matched)
    assert all(row["crossings"] == 0 for row in matched)
    assert all(m.crossings == 0 for m in res["matches"])
    with pytest.raises(ValueError, match="closed contours"):
        pymodal.run(str(BUNDLED), frames=(40, 42), model="surface", solver="ordered")


def test_outline_images_on_b_after_the_drift_and_the_partners_otherwise(contours):
    a, b = contours
    m = len(b)

    def on_b(s):
        j = np.floor(s).astype(int) % m
        t = (s - np.floor(s))[:, None]
        return b[j] + t * (b[(j + 1) % m] - b[j])

    drifted = pymodal.match(a, b, refine="coherent")
    img = drifted.outline_images
    assert img.shape == (len(a),) and ((img >= 0) & (img < m)).all()
    # Each image is the point of b's outline nearest the node's moved position (brute force).
    dense = on_b(np.arange(m * 50) / 50.0)
    nearest = np.sqrt(((drifted.aligned_a[:, None] - dense[None]) ** 2).sum(2)).min(1)
    gap = np.linalg.norm(on_b(img) - drifted.aligned_a, axis=1)
    assert (gap <= nearest + 1e-9).all()
    assert np.array_equal(pickle.loads(pickle.dumps(drifted)).outline_images, img)
    # Without the drift: the node of each one's first pair.
    plain = pymodal.match(a, b, refine="affine")
    first = {}
    for i, j in plain.pairs[::-1]:
        first[i] = j
    assert all(plain.outline_images[i] == j for i, j in first.items())
    # Only for two closed contours.
    assert drifted.drifted and not plain.drifted
    assert pickle.loads(pickle.dumps(drifted)).drifted
    assert pymodal.match(a, b, ordered=False).outline_images is None


def test_the_field_of_a_drifted_match_carries_a_to_its_outline_images(contours):
    a, b = contours
    m = len(b)

    def on_b(s):
        j = np.floor(s).astype(int) % m
        t = (s - np.floor(s))[:, None]
        return b[j] + t * (b[(j + 1) % m] - b[j])

    for drifted in (pymodal.match(a, b, refine="coherent"),
                    pymodal.match(a, b, prealign="normalize", position_weight=1.0, refine="coherent")):
        field = drifted.field(a, b)
        np.testing.assert_allclose(field.apply(a), on_b(drifted.outline_images), atol=1e-9 * np.abs(b).max())
        assert np.array_equal(field.pairs, np.column_stack([np.arange(len(a))] * 2))
    # A b that is not the match's (fewer nodes than the images name) is refused.
    with pytest.raises(pymodal.InputError, match="fewer nodes"):
        drifted.field(a, b[: int(np.floor(drifted.outline_images.max()))])
    # Unordered point sets have no outline images: the field carries a to the moved nodes.
    points = pymodal.match(a, b, ordered=False, refine="coherent")
    assert points.drifted and points.outline_images is None
    np.testing.assert_allclose(points.field(a, b).apply(a), points.aligned_a, atol=1e-9 * np.abs(b).max())
    # Without the drift: the pairs' field, as before.
    plain = pymodal.match(a, b, refine="affine")
    one = plain.pairs[~plain.excess]
    np.testing.assert_allclose(plain.field(a, b).apply(a[one[:, 0]]), b[one[:, 1]], atol=1e-9 * np.abs(b).max())
