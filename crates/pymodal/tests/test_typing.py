"""The package as a type checker sees it: a user's script, written from the README, passes
`mypy --strict` against the installed pymodal (its stubs, py.typed and annotations). A stub that
types `run` as a plain dict, or a helper that is imported but not re-exported, fails here."""
import importlib.util
import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent(
    """
    from typing import Any
    import numpy as np
    import pymodal

    rec = pymodal.read_recording("walk.asf", pitch_mm=5.08)
    a = max(pymodal.contours(rec.frames[40], spacing=1.0), key=len)
    b = max(pymodal.contours(rec.frames[41], spacing=1.0), key=len)
    m = pymodal.match(a, b, max_rotation=30.0)
    pairs: np.ndarray[Any, Any] = m.pairs
    field = m.field(a, b, smoothing=0.0)
    moved: np.ndarray[Any, Any] = field.inverse().apply(field.apply(a))
    same: bool = field == pymodal.Field(a, b, field.pairs, smoothing=field.smoothing)
    res = pymodal.run("walk.asf", frames=(40, 80), pitch_mm=5.08, drift_reference=0)
    page: str = res._repr_html_()
    first: dict[str, Any] = res["table"][0]
    keeps_the_class: bool = isinstance(res, pymodal.RunResult)
    rows = pymodal.batch("data/", out="study/", jobs=2, spacing=1.5)
    row = pymodal.batch_row("data/walk.asf", out="study/")
    found = pymodal.find_recordings(["data/", "extra/*.lst"])
    r, c = pymodal.linear_sum_assignment(np.eye(3), maximize=False, solver="jv")
    w, v = pymodal.eigh(np.eye(3), np.eye(3), n_modes=None)
    model = pymodal.ModalModel(a)
    ax = pymodal.plot_tracks(res, background=rec)
    ax = pymodal.plot_match(m, a, b, pitch_mm=rec.pitch_mm, labels=("frame 40", "frame 41"))
    ax = pymodal.plot_frame(rec, 40)
    ax.set_title("frame 40")
    options: Any = pymodal._options()
    version: str = pymodal.__version__
    try:
        pymodal.run("walk.asf", spacing=1.0)
    except pymodal.FormatError as e:
        print(e)
    """
)


@pytest.mark.skipif(importlib.util.find_spec("mypy") is None, reason="mypy is not installed")
def test_a_users_script_passes_mypy_strict(tmp_path):
    script = tmp_path / "analysis.py"
    script.write_text(SCRIPT)
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", "--cache-dir",
         str(tmp_path / "cache"), str(script)],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout + done.stderr
