"""Array attributes of results are read-only: they are copies of what the object holds, so a
write would silently change nothing. numpy must refuse it instead; methods return arrays the
caller owns."""

import pathlib

import numpy as np
import pytest

import pymodal

ASF = pathlib.Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data" / "FrasP01L.asf"


def outline(n=40, phase=0.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False) + phase
    return np.c_[3 * np.cos(t) + 0.5 * np.cos(2 * t), 2 * np.sin(t)]


def results():
    rec = pymodal.read_recording(str(ASF))
    frame = rec.frames[int(np.argmax(rec.peak_pressure))]
    return {
        "Match": pymodal.match(outline(30), outline(32, 0.1)),
        "Field": pymodal.match(outline(30), outline(32, 0.1)).field(outline(30), outline(32, 0.1)),
        "Recording": rec,
        "Surface": pymodal.surface(frame, threshold=1.0, max_nodes=60),
        "ModalModel": pymodal.ModalModel(outline(12)),
    }


def array_attributes(obj):
    """Every public property of the object's class whose value is an array (so a property
    added later is covered too)."""
    cls = type(obj)
    names = [k for k, v in vars(cls).items() if not k.startswith("_") and not callable(v)]
    return {k: getattr(obj, k) for k in names if isinstance(getattr(obj, k), np.ndarray)}


@pytest.mark.parametrize("kind", ["Match", "Field", "Recording", "Surface", "ModalModel"])
def test_array_attributes_refuse_writes(kind):
    obj = results()[kind]
    arrays = array_attributes(obj)
    assert arrays, kind
    for name, arr in arrays.items():
        assert not arr.flags.writeable, f"{kind}.{name}"
        if arr.size == 0:
            continue
        before = getattr(obj, name).copy()
        with pytest.raises(ValueError, match="read-only"):
            arr[(0,) * arr.ndim] = arr[(0,) * arr.ndim]
        np.testing.assert_array_equal(getattr(obj, name), before)
        mine = arr.copy()
        mine[(0,) * arr.ndim] = mine[(0,) * arr.ndim]  # a copy is the caller's to change


def test_match_attributes_named():
    arrays = array_attributes(results()["Match"])
    expected = {"pairs", "costs", "excess", "affinity", "unmatched_a", "unmatched_b", "local_pairs", "transform", "aligned_a"}
    assert expected <= set(arrays)


def test_methods_return_arrays_the_caller_owns():
    model = pymodal.ModalModel(outline(12))
    for arr in (model.features(3), model.mass(), model.stiffness()):
        assert arr.flags.writeable
    assert results()["Field"].apply(outline(5)).flags.writeable
    rec = results()["Recording"]
    assert all(v.flags.writeable for v in rec.measures().values())
