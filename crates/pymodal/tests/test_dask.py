"""The Dask recipe of docs/batch.md (examples/batch_dask.py) on a LocalCluster of 2 worker processes:
the gathered table equals pymodal.batch's serial one (but for the wall times)."""

import importlib.util
import shutil
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")
pd = pytest.importorskip("pandas")

import pymodal  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "crates" / "pedo-io" / "tests" / "data"


def load_example():
    spec = importlib.util.spec_from_file_location("batch_dask", ROOT / "examples" / "batch_dask.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_dask_table_equals_the_serial_batch(tmp_path):
    inputs = tmp_path / "in"
    (inputs / "a").mkdir(parents=True)
    shutil.copy(DATA / "emed-test-1-10.lst", inputs / "a" / "trial.lst")
    shutil.copy(DATA / "synthetic-walk.lst", inputs / "trial.lst")
    shutil.copy(DATA / "tekscan-FrasP01L-11-20.csv", inputs / "tekscan.csv")
    asf = (DATA / "FrasP01L.asf").read_bytes()
    (inputs / "corrupt.asf").write_bytes(asf[: len(asf) // 50])

    serial = pd.DataFrame(pymodal.batch(inputs, tmp_path / "serial", jobs=1, figures="none", spacing=1.5))
    example = load_example()
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with cluster, distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        table = example.dask_study(client, str(inputs), out=str(tmp_path / "dask"), spacing=1.5)

    assert list(table["status"]) == ["ok", "error", "ok", "ok"]
    assert (tmp_path / "dask" / table["output"][0] / "pairs.csv").is_file()
    pd.testing.assert_frame_equal(
        table.drop(columns="wall_time_s"), serial.drop(columns="wall_time_s"), check_exact=True
    )
