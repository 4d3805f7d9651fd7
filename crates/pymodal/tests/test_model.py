"""pymodal.ModalModel and pymodal.eigh, with scipy.linalg.eigh as the oracle."""

import numpy as np
import pytest
import scipy.linalg

import pymodal


def contour(n, phase=0.3):
    t = 2 * np.pi * (np.arange(n) + phase) / n
    r = 1.0 + 0.25 * np.cos(2 * t) + 0.1 * np.sin(3 * t)
    return np.column_stack([1.3 * r * np.cos(t), 0.8 * r * np.sin(t)])


def surface(nx=6, ny=7):
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    x = x + 0.1 * np.sin(3 * y)
    z = 1.2 * np.sin(0.5 * x) * np.cos(0.4 * y)
    pts = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    tris = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            v = j * nx + i
            tris += [[v, v + 1, v + nx + 1], [v, v + nx + 1, v + nx]]
    return pts, np.array(tris)


def same_up_to_sign(a, b, tol):
    return min(np.abs(a - b).max(), np.abs(a + b).max()) <= tol * np.abs(b).max()


@pytest.mark.parametrize(
    "points, kwargs",
    [
        (contour(40), {}),
        (contour(30), {"material": "unit", "kappa": 1.5}),
        (np.random.default_rng(3).normal(size=(25, 3)), {"material": {"young": 2.0, "poisson": 0.3, "density": 5.0}}),
        (contour(36), {"element": "axial", "material": "steel"}),
        (surface()[0], {"triangles": surface()[1]}),
    ],
)
def test_scipy_oracle_on_exposed_matrices(points, kwargs):
    model = pymodal.ModalModel(points, **kwargs)
    K, M = model.stiffness(), model.mass()
    d, n = points.shape[1], points.shape[0]
    assert K.shape == M.shape == (d * n, d * n)
    np.testing.assert_allclose(K, K.T, atol=1e-12 * np.abs(K).max())
    np.testing.assert_allclose(M, M.T, atol=1e-12 * np.abs(M).max())
    assert np.linalg.eigvalsh(M).min() > 0
    w, v = scipy.linalg.eigh(K, M)
    lam = model.eigenvalues
    top = w.max()
    np.testing.assert_allclose(lam, w, rtol=1e-7, atol=1e-9 * top)
    np.testing.assert_allclose(model.frequencies, np.sqrt(np.maximum(lam, 0)))
    phi = model.modes
    assert phi.shape == (d * n, d * n)
    np.testing.assert_allclose(phi.T @ M @ phi, np.eye(d * n), atol=1e-7)
    np.testing.assert_allclose(phi.T @ K @ phi, np.diag(lam), atol=1e-7 * top)
    # Simple modes agree with scipy's up to sign.
    for j in range(d * n):
        gaps = np.abs(np.delete(w, j) - w[j])
        if gaps.min() > 1e-5 * max(abs(w[j]), 1e-12 * top) and w[j] > 1e-8 * top:
            assert same_up_to_sign(phi[:, j], v[:, j], 1e-5), j


def test_deterministic_sign_and_partial_modes():
    pts = contour(60)
    full = pymodal.ModalModel(pts)
    part = pymodal.ModalModel(pts, n_modes=30)
    assert part.modes.shape == (120, 30)
    np.testing.assert_allclose(part.eigenvalues, full.eigenvalues[:30], rtol=1e-10)
    np.testing.assert_allclose(part.modes, full.modes[:, :30], atol=1e-7)
    m = full.modes
    idx = np.abs(m).argmax(axis=0)
    assert np.all(m[idx, np.arange(m.shape[1])] > 0)


def test_features_layout():
    pts = np.random.default_rng(1).normal(size=(12, 3))
    model = pymodal.ModalModel(pts)
    f = model.features(5)
    assert f.shape == (12, 15)
    phi = model.modes
    np.testing.assert_array_equal(f[:, :5], phi[:12, :5])
    np.testing.assert_array_equal(f[:, 5:10], phi[12:24, :5])
    np.testing.assert_array_equal(f[:, 10:], phi[24:, :5])
    with pytest.raises(ValueError):
        model.features(37)


def test_sigma_rule_and_explicit_sigma():
    pts = contour(40)
    nn = np.sort(np.linalg.norm(pts[:, None] - pts[None], axis=2), axis=1)[:, 1].mean()
    assert pymodal.ModalModel(pts).sigma == pytest.approx(nn, rel=1e-12)
    assert pymodal.ModalModel(pts, kappa=0.8).sigma == pytest.approx(0.8 * nn, rel=1e-12)
    assert pymodal.ModalModel(pts, sigma=0.05).sigma == 0.05
    assert pymodal.ModalModel(pts, element="axial").sigma is None


def test_material_scaling():
    pts = contour(30)
    base = pymodal.ModalModel(pts, material="unit")
    stiff = pymodal.ModalModel(pts, material=(7e6, 0.3, 1.0))
    heavy = pymodal.ModalModel(pts, material={"young": 1.0, "poisson": 0.3, "density": 1100.0})
    np.testing.assert_allclose(stiff.eigenvalues, 7e6 * base.eigenvalues, rtol=1e-9)
    np.testing.assert_allclose(heavy.eigenvalues, base.eigenvalues / 1100.0, rtol=1e-9)
    np.testing.assert_allclose(stiff.modes, base.modes, atol=1e-8)
    np.testing.assert_allclose(heavy.modes * np.sqrt(1100.0), base.modes, atol=1e-8)


def test_exact_rigid_and_bar_zero_modes():
    pts = contour(40)
    rigid = pymodal.ModalModel(pts, exact_rigid=True)
    assert np.all(rigid.eigenvalues[:3] == 0) and rigid.eigenvalues[3] > 0
    bars = pymodal.ModalModel(pts, element="axial", material="unit")
    lam = bars.eigenvalues
    assert np.sum(lam < 1e-9 * lam.max()) == 3
    pts3, tris = surface()
    mesh = pymodal.ModalModel(pts3, triangles=tris, material="unit")
    lam = mesh.eigenvalues
    assert np.sum(lam < 1e-9 * lam.max()) == 6
    # A plain ring of bars given as edges is a mechanism: rejected with the reason.
    ring = np.column_stack([np.arange(40), (np.arange(40) + 1) % 40])
    with pytest.raises(ValueError, match="zero-energy"):
        pymodal.ModalModel(pts, edges=ring)
    braced = np.vstack([ring, np.column_stack([np.arange(40), (np.arange(40) + 2) % 40])])
    lam = pymodal.ModalModel(pts, edges=braced, material="unit").eigenvalues
    assert np.sum(lam < 1e-9 * lam.max()) == 3


@pytest.mark.parametrize(
    "points, kwargs, message",
    [
        ([[0, 0], [1, 0]], {}, "at least 3"),
        ([[0, 0], [1, 0], [0, 1], [1, 0]], {}, "coincide"),
        ([[0, 0], [1, np.nan], [0, 1]], {}, "not finite"),
        ([[0, 0, 0, 0]] * 5, {}, "2 or 3 columns"),
        ([0, 1, 2], {}, "points must be an .n, 2. or .n, 3. array.*got a 1-D array"),
        (contour(10), {"material": "jelly"}, "material = jelly"),
        (contour(10), {"material": {"young": 1, "poisson": 0.5}}, "Poisson"),
        (contour(10), {"material": {"yung": 1}}, "unknown material key"),
        (contour(10), {"sigma": -1.0}, "sigma"),
        (contour(10), {"element": "shell"}, "unknown element"),
        (contour(10), {"edges": [[0, 1], [1, 99]]}, "invalid edge"),
        (contour(10), {"edges": [[0, 1, 2]]}, "2 columns"),
        (contour(10), {"triangles": [[0, 1, -2]]}, "negative"),
        (np.random.default_rng(0).normal(size=(6, 3)), {"element": "axial"}, "3-D closed contour"),
        ([[0, 0], [1, 0], [2, 0], [3, 0]], {"element": "axial"}, "zero-energy"),
        (contour(10), {"n_modes": 21}, "n_modes"),
    ],
)
def test_bad_input_raises_value_error(points, kwargs, message):
    with pytest.raises(ValueError, match=message):
        pymodal.ModalModel(np.asarray(points, dtype=float), **kwargs)


def test_eigh_matches_scipy():
    rng = np.random.default_rng(5)
    a = rng.normal(size=(50, 50))
    K = a @ a.T
    b = rng.normal(size=(50, 50))
    M = b @ b.T + 50 * np.eye(50)
    w, v = pymodal.eigh(K, M)
    ws, vs = scipy.linalg.eigh(K, M)
    np.testing.assert_allclose(w, ws, rtol=1e-9, atol=1e-12 * ws.max())
    np.testing.assert_allclose(v.T @ M @ v, np.eye(50), atol=1e-9)
    w10, v10 = pymodal.eigh(K, M, n_modes=10)
    np.testing.assert_allclose(w10, ws[:10], rtol=1e-9, atol=1e-12 * ws.max())
    for j in range(10):
        assert same_up_to_sign(v10[:, j], vs[:, j], 1e-7)
    with pytest.raises(ValueError):
        pymodal.eigh(K, -M)
    with pytest.raises(ValueError):
        pymodal.eigh(K, M[:10, :10])


def test_eigh_reads_the_lower_triangle_like_scipy():
    rng = np.random.default_rng(11)
    a = rng.normal(size=(30, 30))
    K = a @ a.T
    b = rng.normal(size=(30, 30))
    M = b @ b.T + 30 * np.eye(30)
    upper = np.triu_indices(30, 1)
    k_lower, m_lower = K.copy(), M.copy()
    # Garbage above the diagonal: neither symmetric nor definite, finite.
    k_lower[upper] = rng.normal(scale=1e3, size=len(upper[0]))
    m_lower[upper] = -rng.uniform(1e2, 1e3, size=len(upper[0]))
    ws, vs = scipy.linalg.eigh(k_lower, m_lower)  # lower=True is scipy's default
    w, v = pymodal.eigh(k_lower, m_lower)
    np.testing.assert_allclose(w, ws, rtol=1e-9, atol=1e-12 * ws.max())
    np.testing.assert_allclose(w, scipy.linalg.eigh(K, M, eigvals_only=True), rtol=1e-9, atol=1e-12 * ws.max())
    np.testing.assert_allclose(v.T @ M @ v, np.eye(30), atol=1e-9)
    for j in range(30):
        assert same_up_to_sign(v[:, j], vs[:, j], 1e-6)
    # Fortran-ordered input reads the same lower triangle.
    w_f, _ = pymodal.eigh(np.asfortranarray(k_lower), np.asfortranarray(m_lower))
    np.testing.assert_allclose(w_f, ws, rtol=1e-9, atol=1e-12 * ws.max())
