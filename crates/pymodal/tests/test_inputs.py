"""Inputs that cannot mislead: arrays stored time-last, pedomatch's own tables, negative values."""

import pathlib

import numpy as np
import pytest

import pymodal

DATA = pathlib.Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data"
ASF = DATA / "FrasP01L.asf"


def time_last_array():
    """(rows, cols, frames) = (63, 33, 500), as the SpeedPP2DS files store a recording."""
    i, j, k = np.meshgrid(np.arange(63), np.arange(33), np.arange(500), indexing="ij")
    centre = 20 + 10 * np.sin(k / 50.0)
    return (200 * np.exp(-((i - centre) ** 2 + (j - 15) ** 2) / 40.0)).astype(np.float32)


def test_inputs_a_time_last_array_is_refused_naming_both_shapes(tmp_path):
    a = time_last_array()
    with pytest.raises(pymodal.FormatError) as e:
        pymodal.Recording.from_array(a)
    message = str(e.value)
    for says in ["(63, 33, 500)", "63 frames of 33 x 500", "500 frames of 63 x 33", 'time_axis="last"']:
        assert says in message, message
    # The same array in a .npy file, with the file named.
    path = tmp_path / "speed.npy"
    np.save(path, a)
    with pytest.raises(pymodal.FormatError, match="speed.npy"):
        pymodal.read_recording(str(path))
    # Transposed on request, as NumPy transposes it.
    for rec in [
        pymodal.Recording.from_array(a, time_axis="last"),
        pymodal.read_recording(str(path), time_axis="last"),
    ]:
        assert rec.shape == (500, 63, 33)
        np.testing.assert_array_equal(rec.frames, np.transpose(a, (2, 0, 1)))
        # Handed to a run, not transposed again (and not refused).
        assert rec.shape == pymodal.Recording.from_array(rec.frames).shape
    kept = pymodal.Recording.from_array(a, time_axis="first")
    assert kept.shape == (63, 33, 500)
    with pytest.raises(pymodal.OptionError):
        pymodal.Recording.from_array(a, time_axis="middle")


def test_inputs_pedomatchs_own_table_is_refused_naming_it(tmp_path):
    out = tmp_path / "run"
    pymodal.run(str(ASF), frames=(30, 45), out=str(out), figures="none", report="none")
    for name in ["frames.csv", "objects.csv", "pairs.csv", "matches.csv", "tracks.csv"]:
        with pytest.raises(pymodal.FormatError, match=f"pedomatch's own {name}"):
            pymodal.read_recording(str(out / name))


def test_inputs_negative_values_are_counted_and_clipped_on_request():
    frames = np.zeros((4, 14, 12), np.float32)
    frames[:, 3:11, 2:9] = 30.0
    frames[0, 0, 0] = -2.5
    frames[2, 13, 11] = -0.25
    frames[3, 0, 11] = -9.0
    rec = pymodal.Recording.from_array(frames)
    expected = {"count": int((frames < 0).sum()), "min": float(frames.min()), "clipped": False}
    assert rec.negative_values == expected
    np.testing.assert_array_equal(rec.frames, frames)
    clipped = pymodal.Recording.from_array(frames, clip_negative=True)
    assert clipped.negative_values == {**expected, "clipped": True}
    np.testing.assert_array_equal(clipped.frames, np.maximum(frames, 0))
    # Measures count only values above 0: clipping changes none.
    np.testing.assert_array_equal(clipped.total_force, rec.total_force)
    # summary.json's record, from a run.
    summary = pymodal.run(rec)["summary"]
    assert summary["recording"]["negative_values"] == expected
    none = pymodal.Recording.from_array(np.maximum(frames, 0))
    assert none.negative_values == {"count": 0, "min": None, "clipped": False}
