"""Ctrl-C (SIGINT) during pymodal.run and pymodal.batch: a KeyboardInterrupt that ``except
KeyboardInterrupt`` catches (never a PanicException), raised promptly, with the study folder left
as the command line leaves it, and a process that runs pymodal normally afterwards. Each case runs
in a subprocess that is sent SIGINT."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")

DATA = Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data"
LONG = DATA / "FrasP01L.asf"  # 205 frames: a second or more, with a finer spacing longer
SHORT = DATA / "footscan-FrasP01L-11-20.txt"

# Each child restores Python's own SIGINT handler: a process started in the background by a
# non-interactive shell inherits SIGINT ignored, and Python then leaves it ignored.
RUN = r"""
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
path, short = sys.argv[1], sys.argv[2]
import pymodal
print("ready", flush=True)
try:
    pymodal.run(path, spacing=0.5)
    print("finished", flush=True)
except BaseException as e:  # PanicException derives from BaseException
    print(type(e).__name__, time.monotonic(), flush=True)
# The process goes on: pymodal works as before.
print("again", pymodal.run(short)["summary"]["pairs"] > 0, flush=True)
"""

BATCH = r"""
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
inputs, out, short, out2 = sys.argv[1].split(","), sys.argv[2], sys.argv[3], sys.argv[4]
import pymodal
print("ready", flush=True)
try:
    pymodal.batch(inputs, out, jobs=1, force=True, figures="pairs", spacing=0.5)
    print("finished", flush=True)
except BaseException as e:
    print(type(e).__name__, time.monotonic(), flush=True)
rows = pymodal.batch([short], out2, figures="none")
print("again", [r["status"] for r in rows], flush=True)
"""


def start(tmp_path, script, *args):
    path = tmp_path / "child.py"
    path.write_text(script)
    p = subprocess.Popen(
        [sys.executable, str(path), *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert p.stdout.readline().strip() == "ready"
    return p


def finish(p, timeout=600):
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        pytest.fail("the child did not end")
    assert "PanicException" not in out + err, err
    assert p.returncode == 0, err
    return out.split("\n")


def test_ctrl_c_during_the_first_run_raises_keyboard_interrupt(tmp_path):
    # The first run of a process: rust-numpy used to load numpy's C API lazily after the work,
    # and the pending KeyboardInterrupt made that fail with a PanicException.
    p = start(tmp_path, RUN, LONG, SHORT)
    time.sleep(0.5)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    lines = finish(p)
    assert lines[0].split()[0] == "KeyboardInterrupt", lines
    stopped = float(lines[0].split()[1]) - sent  # CLOCK_MONOTONIC: one clock for every process
    assert "again True" in lines
    # Cancelled at the run's next progress step, not after the whole recording (several
    # seconds at this spacing): from the signal to the child's `except`, not counting the run
    # that follows it. Generous for a loaded machine.
    assert stopped < 3.0, stopped


def test_ctrl_c_during_batch_keeps_finished_folders_and_the_study_table(tmp_path):
    # a is short (10 frames: it finishes at once, with its figures), b and c long.
    inputs = []
    for name, source in (("a.txt", SHORT), ("b.asf", LONG), ("c.asf", LONG)):
        shutil.copy(source, tmp_path / name)
        inputs.append(tmp_path / name)
    out = tmp_path / "study"
    import pymodal

    # A study holding a's folder and table; then a, b and c run again (force): a finishes, b is
    # interrupted, c never starts.
    pymodal.batch([inputs[0]], out, figures="none")
    table = (out / "study.csv").read_bytes()
    table_json = (out / "study.json").read_bytes()
    (a_folder,) = [d for d in out.iterdir() if d.name.startswith("a.txt")]
    a_summary = a_folder / "summary.json"
    before = a_summary.stat().st_mtime_ns

    p = start(tmp_path, BATCH, ",".join(map(str, inputs)), out, SHORT, tmp_path / "study2")
    deadline = time.monotonic() + 600  # a hang guard: a finishes in a second on a quiet machine
    while not (a_summary.exists() and a_summary.stat().st_mtime_ns != before):
        assert p.poll() is None and time.monotonic() < deadline, "a was not run again"
        time.sleep(0.02)
    time.sleep(0.3)  # b under way
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    lines = finish(p)
    assert lines[0].split()[0] == "KeyboardInterrupt", lines
    stopped = float(lines[0].split()[1]) - sent
    assert "again ['ok']" in lines
    # a, finished, keeps its new folder; b (in progress) and c (not started) have none, nor any
    # staging folder; the study table is as it was.
    names = sorted(d.name for d in out.iterdir())
    assert [n for n in names if n.startswith(("b.asf", "c.asf"))] == [], names
    assert [n for n in names if "pedomatch-tmp" in n] == [], names
    assert a_folder.is_dir() and (a_folder / "figures").is_dir()
    assert (out / "study.csv").read_bytes() == table
    assert (out / "study.json").read_bytes() == table_json
    assert stopped < 3.0, stopped
