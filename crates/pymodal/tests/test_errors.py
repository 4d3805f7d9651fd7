"""The exception hierarchy: every library error is a pymodal.PedomatchError of the class its kind
says, the ValueError subclasses stay ValueErrors, and OS errors are the builtin OSError classes."""

import errno
import pathlib
import pickle

import numpy as np
import pytest

import pymodal

DATA = pathlib.Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data"
ASF = DATA / "FrasP01L.asf"
VALUE_ERRORS = ["FormatError", "DegenerateShapeError", "InputError", "OptionError", "InfeasibleError", "NumericalError"]


def outline(n=30):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[3 * np.cos(t) + 0.5 * np.cos(2 * t), 2 * np.sin(t)]


def test_hierarchy():
    assert issubclass(pymodal.PedomatchError, Exception)
    assert not issubclass(pymodal.PedomatchError, ValueError)
    for name in VALUE_ERRORS:
        cls = getattr(pymodal, name)
        assert issubclass(cls, pymodal.PedomatchError) and issubclass(cls, ValueError), name
        assert cls.__module__ == "pymodal" and cls.__doc__.strip()
    assert issubclass(pymodal.OptionError, pymodal.InputError)


def test_exceptions_pickle_for_multiprocessing():
    e = pickle.loads(pickle.dumps(pymodal.FormatError("broken.asf: truncated")))
    assert type(e) is pymodal.FormatError and str(e) == "broken.asf: truncated"
    e = pickle.loads(pickle.dumps(pymodal.PedomatchError("x")))
    assert type(e) is pymodal.PedomatchError


def test_missing_file_is_file_not_found(tmp_path):
    path = tmp_path / "missing.asf"
    with pytest.raises(FileNotFoundError) as info:
        pymodal.read_recording(str(path))
    assert info.value.errno == errno.ENOENT
    assert info.value.filename == str(path)
    assert "missing.asf" in str(info.value)
    with pytest.raises(FileNotFoundError):
        pymodal.run(str(path))


def test_unreadable_path_is_os_error(tmp_path):
    # A path through a file: the OS's own error (ENOTDIR), not a format error.
    (tmp_path / "plain").write_text("x")
    with pytest.raises(NotADirectoryError) as info:
        pymodal.read_recording(str(tmp_path / "plain" / "r.npy"))
    assert info.value.errno == errno.ENOTDIR and info.value.filename.endswith("r.npy")
    assert not isinstance(info.value, pymodal.PedomatchError)


@pytest.mark.parametrize(
    "name, content",
    [
        ("garbage.dat", bytes(range(256)) * 8),
        ("garbage.npy", b"\x93NUMPY\x01\x00garbage"),
        ("truncated.asf", ASF.read_bytes()[:100000]),
    ],
)
def test_corrupt_file_is_format_error(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(pymodal.FormatError, match=name) as info:
        pymodal.read_recording(str(path))
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize(
    "points, text",
    [
        (outline()[:2], "at least 3"),
        (np.c_[np.arange(10.0), 2 * np.arange(10.0)], "collinear"),
        (np.where(np.arange(60).reshape(30, 2) == 7, np.nan, outline()), "not finite"),
        (np.ones((10, 2)), "coincide"),
    ],
)
def test_degenerate_shape(points, text):
    with pytest.raises(pymodal.DegenerateShapeError, match=text) as info:
        pymodal.match(points, outline())
    assert isinstance(info.value, ValueError)


def test_degenerate_model():
    with pytest.raises(pymodal.DegenerateShapeError):
        pymodal.ModalModel([[0.0, 0.0], [1.0, 0.0]])


@pytest.mark.parametrize(
    "call",
    [
        lambda: pymodal.match(outline(), outline(), solver="fast"),
        lambda: pymodal.match(outline(), outline(), modes=2.0),
        lambda: pymodal.match(outline(), outline(), threshold=-1.0),
        lambda: pymodal.ModalModel(outline(), plane="shell"),
        lambda: pymodal.ModalModel(outline(), material="jelly"),
        lambda: pymodal.linear_sum_assignment(np.eye(3), method="auction"),
        lambda: pymodal.contours(np.eye(5), method="snake"),
    ],
)
def test_bad_option_value(call):
    with pytest.raises(pymodal.OptionError) as info:
        call()
    assert isinstance(info.value, ValueError) and isinstance(info.value, pymodal.InputError)


def test_invalid_entries_and_infeasible_assignments():
    with pytest.raises(pymodal.InputError, match="invalid numeric entries"):
        pymodal.linear_sum_assignment([[np.nan, 1.0], [1.0, 2.0]])
    with pytest.raises(pymodal.InfeasibleError, match="cost matrix is infeasible") as info:
        pymodal.linear_sum_assignment([[np.inf, np.inf], [1.0, 2.0]])
    assert isinstance(info.value, ValueError)


def test_numerical_failure():
    k = np.eye(4)
    with pytest.raises(pymodal.NumericalError, match="positive definite") as info:
        pymodal.eigh(k, -k)
    assert isinstance(info.value, ValueError)
