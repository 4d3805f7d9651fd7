"""pymodal in processes forked after the parent used it (multiprocessing's default start method
on Linux): every entry point works in the child. The parent's rayon pools are inherited without
their threads; before the fix the child's first parallel call waited forever, so each case runs
in a subprocess with a timeout (a hang fails the test, it does not hang the suite)."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data"
RECORDING = DATA / "footscan-FrasP01L-11-20.txt"
TIMEOUT_S = 60

SCRIPT = r"""
import concurrent.futures, json, multiprocessing, sys
import pymodal

path = sys.argv[1]

def contour(frame):
    rec = pymodal.read_recording(path)
    return max(pymodal.contours(rec.frames[frame], spacing=1.0), key=len)

def job(kind):
    if kind == "run":
        return pymodal.run(path)["summary"]["pairs"]
    if kind == "match":
        return len(pymodal.match(contour(3), contour(4)))
    if kind == "batch":
        return [r["pairs"] for r in pymodal.batch([path], None, jobs=1, figures="none")]
    if kind == "batch_row":
        return pymodal.batch_row(path, None, figures="none")["pairs"]
    raise ValueError(kind)

if __name__ == "__main__":
    # The parent uses every entry point (starting rayon's pools), then forks.
    parent = {k: job(k) for k in ("run", "match", "batch", "batch_row")}
    kind = sys.argv[2]
    fork = multiprocessing.get_context("fork")
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=fork) as pool:
        children = list(pool.map(job, [kind, kind]))
    print(json.dumps({"parent": parent[kind], "children": children}))
"""


def run_with_timeout(args, timeout):
    """`args` in a new session, killed as a whole (forked workers included) after `timeout`."""
    p = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        pytest.fail(f"{args[-1]} in a forked child did not return within {timeout} s (hung)")
    assert p.returncode == 0, err
    return out


@pytest.mark.skipif(sys.platform == "win32", reason="no fork on Windows")
@pytest.mark.parametrize("kind", ["run", "match", "batch", "batch_row"])
def test_entry_point_works_in_a_forked_child(tmp_path, kind):
    script = tmp_path / "fork_after_use.py"
    script.write_text(SCRIPT)
    out = run_with_timeout([sys.executable, str(script), str(RECORDING), kind], TIMEOUT_S)
    result = json.loads(out.strip().splitlines()[-1])
    assert result["children"] == [result["parent"]] * 2
