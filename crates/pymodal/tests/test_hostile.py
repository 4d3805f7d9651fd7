"""Hostile inputs through Python: each small file, however much it claims, is a typed
PedomatchError (or a correct result) within 512 MB of memory and 20 s of CPU, measured on a child
interpreter bounded by an address-space limit, so that an abort (a failed allocation ends the
process), a panic (PanicException is a BaseException) or a hang shows as what it is.

Each path through the bindings (reading, a run, a batch, a match) meets a hostile file of each
kind of claim (frames, sensors, an image's size, a bad line, a line or a file of gigabytes); every
reader's own bounds (nesting, decompression, dense frames, each vendor's claims) are tested
in Rust, in crates/pedo-io/tests/hostile.rs, where they cost a fraction of the time.
The files are made at test time; none is committed."""

import os
import pathlib
import resource
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest

import pymodal

DATA = pathlib.Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data"

# The corpus is made once per process (a few MB of gzip and two sparse gigabytes): with
# pytest-xdist, this module's tests stay on one worker (`--dist loadgroup`) instead of every
# worker making its own.
pytestmark = pytest.mark.xdist_group("hostile")

# A child may map this much: far more than the 512 MB it may use, far less than what the
# files claim (262 GB, 30 GB, 4.3 GB), so an allocation sized by a claim fails in it.
ADDRESS_SPACE = 4 << 30
PEAK_RSS_KB = 512 << 10
# A guard against a hang or quadratic work, not a speed target: reading the sparse gigabyte
# takes seconds of CPU, more on a machine whose two cores are both busy.
CPU_S = 20.0

CHILD = r"""
import sys, pymodal
call, path = sys.argv[1], sys.argv[2]
try:
    if call == "read_recording":
        rec = pymodal.read_recording(path)
        print("result", rec.n_frames, rec.shape)
    elif call == "run":
        result = pymodal.run(path, out=sys.argv[3] if len(sys.argv) > 3 else None)
        print("result", len(result["table"]))
    elif call == "batch":
        rows = pymodal.batch([path], sys.argv[3], figures="none", report="none")
        print("result", [(r["path"].rsplit("/", 1)[-1], r["status"], r["message"]) for r in rows])
    elif call == "match":
        import numpy as np
        t = np.linspace(0, 2 * np.pi, int(path), endpoint=False)
        pymodal.match(np.c_[np.cos(t), np.sin(t)], np.c_[np.cos(t), np.sin(t)])
        print("result matched")
except pymodal.PedomatchError as e:
    print("error", type(e).__name__, str(e).replace("\n", " "))
"""


def bounded(*args):
    """Runs CHILD with `args` under the address-space limit; its exit code, output and usage."""

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
        # A hang ends as SIGXCPU rather than stalling the suite.
        resource.setrlimit(resource.RLIMIT_CPU, (60, 60))

    env = dict(os.environ, RAYON_NUM_THREADS="2")
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=limit,
        env=env,
    )
    out, err = child.stdout.read().decode(), child.stderr.read().decode()
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    return child.returncode, out.strip(), err, usage


def check(*args, expect, says):
    """`args` ends in `expect` ("result" or an exception class name) saying `says`, bounded."""
    code, out, err, usage = bounded(*args)
    cpu = usage.ru_utime + usage.ru_stime
    print(f"{args[0]} {pathlib.Path(str(args[1])).name}: exit {code}, peak {usage.ru_maxrss // 1024} MB, "
          f"cpu {cpu:.2f} s: {out}")
    assert code == 0, f"exit {code} (134: abort; -24: out of CPU): {err[-2000:]}"
    assert "PanicException" not in err, err
    assert out.startswith(expect if expect == "result" else f"error {expect} "), out + err
    assert says in out, out
    assert usage.ru_maxrss <= PEAK_RSS_KB, f"peak {usage.ru_maxrss} kB"
    assert cpu <= CPU_S, f"{cpu:.1f} s of CPU"
    return out


def gzip_of(*parts):
    z = zlib.compressobj(6, zlib.DEFLATED, 31)
    chunks = [z.compress(part * times) for part, times in parts]
    return b"".join(chunks) + z.flush()


ZEBRIS_HEAD = (b"<measurement><cell_count><x>256</x><y>256</y></cell_count><movements><movement>"
               b"<clips><clip><cell_size><x>8.467</x><y>8.467</y></cell_size><frequency>100</frequency>"
               b"<data>")
ZEBRIS_TAIL = b"</data></clip></clips></movement></movements></measurement>"


def png_of_zeros(side):
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    z = zlib.compressobj(9)
    row = bytes(side + 1)
    idat = b"".join(z.compress(row) for _ in range(side)) + z.flush()
    header = struct.pack(">IIBBBBB", side, side, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def sparse(path, head, size):
    with open(path, "wb") as f:
        f.write(head)
        f.truncate(size)
    return path


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    """The hostile files, each under 2 MB on disk, with what reading one must say."""
    d = tmp_path_factory.mktemp("hostile")
    says = "values a recording may hold"
    files = {
        # 10⁶ empty frames on a 256 × 256 plate: 262 GB as dense frames.
        "million.xml.gz": (gzip_of((ZEBRIS_HEAD, 1), (b"<quant/>", 1_000_000), (ZEBRIS_TAIL, 1)), says),
        # An emed page claiming a 10000 × 10000 matrix: 30 GB.
        "walk.lst.gz": (gzip_of((b"Page 1\nMatrix: 10000x10000\n\t1\tForce\n1\t0\t0\nForce\t0\n\x0c", 75),
                                (b"\n", 60_000_000)), "sensors a frame may have"),
        # 16384² zeros in 261 KB: 4.3 GB in marching squares before.
        "zeros.png": (png_of_zeros(16384), "an image of 16384 x 16384"),
        # A grid whose line 46 is bad, then 100 MB more: the error at once.
        "grid.csv.gz": (gzip_of((b"0,0,0,0,0\n", 45), (b"0,0,x,0,0\n", 1), (b"0,0,0,0,0\n", 10_000_000)),
                        "grid.csv.gz:46"),
    }
    cases = {}
    for name, (data, message) in files.items():
        assert len(data) < 2 << 20, (name, len(data))
        path = d / name
        path.write_bytes(data)
        cases[name] = (path, "FormatError", message)
    # 1 GiB on disk but a sparse hole (a few KB used): one line of values, then NULs.
    cases["line.csv"] = (sparse(d / "line.csv", b"0," * 8192, 1 << 30), "FormatError", "a line longer than")
    # A gigabyte of NULs: no text at all.
    cases["nul.csv"] = (sparse(d / "nul.csv", b"", 1 << 30), "FormatError", "not a supported pressure recording")
    return cases


CASES = ["million.xml.gz", "walk.lst.gz", "zeros.png", "grid.csv.gz", "line.csv", "nul.csv"]


@pytest.mark.parametrize("name", CASES)
def test_a_hostile_file_read_is_a_format_error_within_memory_and_time(corpus, name):
    path, expect, says = corpus[name]
    check("read_recording", path, expect=expect, says=says)


@pytest.mark.parametrize("name", ["million.xml.gz", "walk.lst.gz", "zeros.png", "line.csv"])
def test_a_hostile_file_run_is_a_format_error_and_writes_nothing(corpus, name, tmp_path):
    path, expect, says = corpus[name]
    out = tmp_path / "run"
    check("run", path, out, expect=expect, says=says)
    assert not out.exists()


DOT = (b"<quant><cell_begin><x>5</x><y>7</y></cell_begin><cell_count><x>1</x><y>1</y></cell_count>"
       b"<cells>100</cells></quant>")


@pytest.mark.parametrize("frame", [b"<quant/>", DOT], ids=["empty", "one-sensel"])
def test_a_run_of_many_frames_holding_little_costs_what_they_hold(frame, tmp_path):
    # 32,768 frames of 256 x 256 (every value a recording may hold) in under 13 KB, each empty
    # or loading one sensel: 13.5 s and 20 s of CPU, frame by frame, before.
    path = tmp_path / "wait.xml.gz"
    path.write_bytes(gzip_of((ZEBRIS_HEAD, 1), (frame, 32_768), (ZEBRIS_TAIL, 1)))
    check("run", path, tmp_path / "run", expect="DegenerateShapeError", says="no object to match")
    assert not (tmp_path / "run").exists()


def test_an_honest_npz_of_zeros_reads_within_memory(tmp_path):
    # 100 MB of frames stored in about 100 KB (deflated): read, held sparsely.
    path = tmp_path / "zeros.npz"
    np.savez_compressed(path, frames=np.zeros((100, 1000, 1000), np.uint8))
    assert path.stat().st_size < 2 << 20
    check("read_recording", path, expect="result", says="result 100 (100, 1000, 1000)")


def test_a_deflated_npz_of_dense_frames_is_held_to_its_size(tmp_path):
    # 100 MB of ones in about 100 KB: 600 MB held as frames before.
    path = tmp_path / "ones.npz"
    np.savez_compressed(path, frames=np.ones((100, 1000, 1000), np.uint8))
    assert path.stat().st_size < 2 << 20
    check("read_recording", path, expect="FormatError", says="max_memory_mb")


def test_too_many_nodes_is_an_error_not_an_abort():
    # 20,000 points raised a PanicException and aborted the interpreter.
    check("match", 20_000, expect="DegenerateShapeError", says="max_nodes")


def test_a_batch_beside_a_hostile_file_gives_one_error_row_within_memory(corpus, tmp_path):
    inputs = tmp_path / "inputs"
    inputs.mkdir()
    lst = (DATA / "emed-test-1-10.lst").read_bytes()
    (inputs / "a.lst").write_bytes(lst)
    (inputs / "b.xml.gz").write_bytes(corpus["million.xml.gz"][0].read_bytes())
    (inputs / "c.lst").write_bytes(lst)
    out = check("batch", inputs, tmp_path / "study", expect="result", says="b.xml.gz")
    assert "('a.lst', 'ok'" in out and "('c.lst', 'ok'" in out, out
    assert "('b.xml.gz', 'error', " in out and "values a recording may hold" in out, out
    table = (tmp_path / "study" / "study.csv").read_text().splitlines()
    assert len(table) == 4, table


def test_reading_limits_reach_run():
    # The limits are run's keywords too, and a run refused by one names it.
    with pytest.raises(pymodal.FormatError, match="max_frames"):
        pymodal.run(DATA / "emed-test-1-10.lst", max_frames=3)
    assert pymodal.run(DATA / "emed-test-1-10.lst", max_frames=10)["table"]
