"""`make wheel-check`: the installed wheel on its own (no Rust, no source tree) is the
distribution `pedomatch` (the public index's `pymodal` is an unrelated project), imported as
`pymodal`, and matches a rotated, shifted, re-indexed outline exactly and pickles its result."""
import importlib.metadata
import pickle
import sys

import numpy as np

import pymodal

assert "site-packages" in pymodal.__file__, pymodal.__file__
# The wheel's metadata names our distribution, and it is what provides the import `pymodal`.
dist = importlib.metadata.distribution("pedomatch")
assert dist.metadata["Name"] == "pedomatch", dist.metadata["Name"]
assert dist.version == pymodal.__version__, (dist.version, pymodal.__version__)
assert any(str(f) == "pymodal/__init__.py" for f in dist.files or []), dist.files
assert importlib.metadata.packages_distributions()["pymodal"] == ["pedomatch"]
t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
a = np.c_[3 * np.cos(t) + 0.5 * np.cos(2 * t), 2 * np.sin(t)]
rot = np.array([[np.cos(0.6), -np.sin(0.6)], [np.sin(0.6), np.cos(0.6)]])
perm = np.roll(np.arange(40), 7)
b = (a @ rot.T + [5.0, -2.0])[perm]
m = pickle.loads(pickle.dumps(pymodal.match(a, b)))
assert len(m.pairs) == 40 and (perm[m.pairs[:, 1]] == m.pairs[:, 0]).all(), m.pairs
print(f"pymodal {pymodal.__version__} wheel OK on Python {sys.version.split()[0]}: {m!r}")
