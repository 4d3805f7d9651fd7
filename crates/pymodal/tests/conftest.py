"""What several test modules share: runs that cost seconds, made once per test process."""

from pathlib import Path

import pytest

import pymodal

ROOT = Path(__file__).resolve().parents[3]
STEP = ROOT / "benches" / "data" / "emed-pressuRe-step.lst"


@pytest.fixture(scope="session")
def fine_run_of_the_step(tmp_path_factory):
    """benches/data/emed-pressuRe-step.lst and the folder of its run with the fine regions
    (`report="none", figures="none", region_rule="fine"`), which the tests only read. The tests
    that use it share an xdist group ("fine-step"), so that one worker makes the run."""
    rec = pymodal.read_recording(str(STEP))
    out = tmp_path_factory.mktemp("fine-step") / "run"
    pymodal.run(rec, out=str(out), report="none", figures="none", region_rule="fine")
    return rec, out
