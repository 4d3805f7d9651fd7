"""Generalized eigensolve K φ = ω² M φ: scipy.linalg.eigh vs pymodal, single-threaded.

The matrices are the explicit K and M of the Gaussian-element model of a foot-like contour with
150 and 450 nodes (300 and 900 dof), exposed by ``pymodal.ModalModel.stiffness()/.mass()``.
Rows:
  scipy eigh(K, M)                    LAPACK (driver gvd), all pairs
  scipy eigh(K, M, subset_by_index)   LAPACK (driver gvx), lowest 25 %
  pymodal.eigh(K, M)                  blocked Cholesky reduction + tridiagonal QL / inverse iteration, all pairs
  pymodal.eigh(K, M, n_modes)         same reduction, lowest 25 % by tridiagonal inverse iteration
  pymodal.ModalModel(points)          whole model build + ψ-form solve (block-diagonal Γ̃), all
  pymodal.ModalModel(points, n_modes) the same, lowest 25 %
and the 60-node contour (120 dof) solve that the matching recipe repeats per pair. scipy's
drivers are named explicitly: `gvd` is LAPACK's dsygvd, `gvx` its dsygvx.

Run:  python benches/python/bench_eigen.py [--nodes 60,150,450]   (pymodal built --release)
      --nodes: the contours' node counts (2 dof a node), e.g. 64,100,185 for the sizes of the
      synthetic contour pair and of the landmark benchmark's outlines.
"""

import argparse
import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS"):
    os.environ[var] = "1"

import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.linalg  # noqa: E402

import pymodal  # noqa: E402


def contour(n, phase=0.3):
    t = 2 * np.pi * (np.arange(n) + phase) / n
    r = 1.0 + 0.25 * np.cos(2 * t) + 0.1 * np.sin(3 * t)
    return np.column_stack([1.3 * r * np.cos(t), 0.8 * r * np.sin(t)])


def best_time(fn, repeats):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), float(np.min(times))


def repeats_for(nodes):
    """Repeats falling with the cube of the size (200, 32 and 7 at 60, 150 and 450 nodes)."""
    return max(7, min(200, int(500 * (60 / nodes) ** 3)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", default="60,150,450", help="comma-separated node counts")
    args = parser.parse_args()
    print(f"numpy {np.__version__}, scipy {scipy.__version__}, single-threaded")
    rows = []
    for nodes in (int(n) for n in args.nodes.split(",")):
        repeats = repeats_for(nodes)
        pts = contour(nodes)
        model = pymodal.ModalModel(pts)
        K, M = model.stiffness(), model.mass()
        dof = K.shape[0]
        k = dof // 4
        cases = [
            ("scipy eigh(K, M) (dsygvd)", lambda: scipy.linalg.eigh(K, M, driver="gvd")),
            (
                f"scipy eigh(K, M, subset 0..{k}) (dsygvx)",
                lambda: scipy.linalg.eigh(K, M, subset_by_index=[0, k - 1], driver="gvx"),
            ),
            ("pymodal.eigh(K, M)", lambda: pymodal.eigh(K, M)),
            (f"pymodal.eigh(K, M, n_modes={k})", lambda: pymodal.eigh(K, M, n_modes=k)),
            ("pymodal.ModalModel(points)", lambda: pymodal.ModalModel(pts)),
            (f"pymodal.ModalModel(points, n_modes={k})", lambda: pymodal.ModalModel(pts, n_modes=k)),
        ]
        for name, fn in cases:
            med, mn = best_time(fn, repeats)
            rows.append((dof, name, med, mn))
            print(f"{dof:5d} dof  {name:42s} median {med * 1e3:9.3f} ms   min {mn * 1e3:9.3f} ms", flush=True)
        # Accuracy cross-check on the same matrices.
        w, _ = scipy.linalg.eigh(K, M)
        wp, _ = pymodal.eigh(K, M)
        print(f"{dof:5d} dof  max |ω² − ω²_scipy| / max ω² = {np.abs(w - wp).max() / w.max():.1e}")
    print()
    print("| dof | solver | median (ms) | min (ms) |")
    print("|---:|---|---:|---:|")
    for dof, name, med, mn in rows:
        print(f"| {dof} | `{name}` | {med * 1e3:.3f} | {mn * 1e3:.3f} |")


if __name__ == "__main__":
    main()
