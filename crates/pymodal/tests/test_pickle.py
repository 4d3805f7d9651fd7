"""Every result type pickles and round-trips exactly (every public attribute equal, arrays bit for
bit), also across processes."""

import concurrent.futures
import multiprocessing
import pathlib
import pickle

import numpy as np
import pytest

import pymodal

ASF = pathlib.Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data" / "FrasP01L.asf"


def outline(n=40, phase=0.0):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False) + phase
    return np.c_[3 * np.cos(t) + 0.5 * np.cos(2 * t), 2 * np.sin(t)]


def assert_same(x, y, where="value"):
    """Equal in type and value; arrays in dtype, shape and every bit (NaN where NaN)."""
    assert type(x) is type(y), where
    if isinstance(x, np.ndarray):
        assert x.dtype == y.dtype and x.shape == y.shape, where
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), where
    elif isinstance(x, dict):
        assert sorted(x) == sorted(y), where
        for k in x:
            assert_same(x[k], y[k], f"{where}[{k!r}]")
    elif isinstance(x, (list, tuple)):
        assert len(x) == len(y), where
        for i, (a, b) in enumerate(zip(x, y)):
            assert_same(a, b, f"{where}[{i}]")
    elif isinstance(x, (pymodal.Match, pymodal.Field, pymodal.Recording, pymodal.Surface, pymodal.ModalModel)):
        assert_same_object(x, y)
    else:
        assert x == y or (x != x and y != y), where


def assert_same_object(x, y):
    """Every public property of the class (so a property added later is covered too)."""
    cls = type(x)
    props = [k for k, v in vars(cls).items() if not k.startswith("_") and not callable(v)]
    assert props, cls
    for k in props:
        assert_same(getattr(x, k), getattr(y, k), f"{cls.__name__}.{k}")
    assert repr(x) == repr(y)


RESULT_CLASSES = (pymodal.Match, pymodal.Field, pymodal.Recording, pymodal.Surface, pymodal.ModalModel)


def round_trip(x):
    y = pickle.loads(pickle.dumps(x, protocol=pickle.HIGHEST_PROTOCOL))
    assert y is not x
    assert_same(x, y)
    if isinstance(x, RESULT_CLASSES):
        # Value equality: what a round trip keeps, checkable with == (and hashable alike).
        assert y == x and not (y != x) and hash(y) == hash(x)
    # Protocol 2 (the oldest Dask may use) too.
    assert_same(x, pickle.loads(pickle.dumps(x, protocol=2)))
    return y


@pytest.mark.parametrize(
    "kwargs", [dict(), dict(search="best"), dict(threshold=0.2, excess=False), dict(prealign="normalize")]
)
def test_match_round_trip(kwargs):
    m = pymodal.match(outline(40), outline(44, 0.3) * 1.1 + 2.0, **kwargs)
    y = round_trip(m)
    assert len(y) == len(m)


def test_match_3d_round_trip():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(40, 3))
    y = round_trip(pymodal.match(a, a[::-1] * 1.2))
    assert y.transform.shape == (4, 4) and y.aligned_a.shape == (40, 3)


@pytest.mark.parametrize("smoothing", [0.0, 2.5])
def test_field_round_trip(smoothing):
    a, b = outline(40), outline(44, 0.3) * 1.1 + 2.0
    field = pymodal.match(a, b).field(a, b, smoothing=smoothing)
    y = round_trip(field)
    probe = outline(30) * 0.5
    assert_same(field.apply(probe), y.apply(probe))
    assert_same(field.inverse(), y.inverse())


def test_recording_round_trip(tmp_path):
    rec = pymodal.read_recording(str(ASF))
    y = round_trip(rec)
    assert_same(rec.measures(30.0), y.measures(30.0))
    # No pitch, no frame time, no units; NaN where there is no sensor.
    frames = np.arange(24.0).reshape(2, 3, 4)
    frames[:, 1, 2] = np.nan
    np.save(tmp_path / "r.npy", frames)
    y = round_trip(pymodal.read_recording(str(tmp_path / "r.npy")))
    assert y.format == "npy" and y.pitch_mm is None and np.isnan(y.frames[:, 1, 2]).all()


def test_surface_round_trip():
    rec = pymodal.read_recording(str(ASF))
    s = pymodal.surface(rec.frames[int(np.argmax(rec.peak_pressure))], threshold=1.0, max_nodes=80)
    round_trip(s)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(),
        dict(n_modes=8, material="steel", center_stride=2),
        dict(element="axial"),
        dict(edges=[[0, 1], [1, 2], [2, 0], [2, 3], [3, 0]]),
    ],
)
def test_modal_model_round_trip(kwargs):
    pts = outline(12) if "edges" not in kwargs else outline(4)
    model = pymodal.ModalModel(pts, **kwargs)
    y = round_trip(model)
    assert_same(model.features(3), y.features(3))
    if kwargs.get("center_stride", 1) == 1:
        assert_same(model.mass(), y.mass())
        assert_same(model.stiffness(), y.stiffness())


def test_mesh_model_round_trip():
    rng = np.random.default_rng(1)
    pts = np.c_[rng.uniform(size=(8, 2)), rng.uniform(size=8)]
    tris = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5], [0, 5, 6], [0, 6, 7]]
    y = round_trip(pymodal.ModalModel(pts, triangles=tris))
    assert y.element == "axial"


def test_run_result_round_trip():
    t = np.arange(6)[:, None, None]
    r, c = np.mgrid[0:30, 0:20]
    frames = np.maximum(0.0, 100.0 * (1 - ((c - 8 - 0.5 * t) / 5.0) ** 2 - ((r - 12 - t) / 8.0) ** 2))
    res = pymodal.run(frames.astype(np.float32))
    y = round_trip(res)
    assert y["table"] == res["table"]


def test_corrupt_state_raises():
    m = pymodal.match(outline(20), outline(20, 0.1))
    restore, (name, state) = m.__reduce__()
    with pytest.raises(ValueError, match="truncated or corrupt"):
        restore(name, state[:-3])
    with pytest.raises(ValueError, match="version"):
        restore(name, b"\x07" + state[1:])
    with pytest.raises(ValueError, match="unknown pymodal class"):
        restore("Nothing", state)


def test_match_in_worker_processes():
    a, b = outline(40), outline(44, 0.3) * 1.1 + 2.0
    here = pymodal.match(a, b)
    # spawn: a forked child would inherit the parent's thread pool without its threads.
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
        futures = [pool.submit(pymodal.match, a, b), pool.submit(pymodal.match, b, a)]
        there, swapped = [f.result(timeout=300) for f in futures]
    assert_same(here.pairs, there.pairs)
    assert_same(here.affinity, there.affinity)
    assert_same(here.transform, there.transform)
    assert swapped.affinity.shape == (44, 40)
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
        # A Match goes to a worker and comes back.
        back = pool.submit(pickle.loads, pickle.dumps(here)).result(timeout=300)
    assert_same(here, back)


def test_recording_repr_is_python_syntax():
    rec = pymodal.Recording.from_array(np.zeros((3, 30, 20), np.float32), pitch_mm=5.08,
                                       frame_rate=50.0, units="kPa")
    assert repr(rec) == "Recording(frames=3x30x20, pitch_mm=(5.08, 5.08), dt_s=0.02, units='kPa')"
    bare = pymodal.Recording.from_array(np.zeros((2, 4, 3)))
    assert repr(bare) == "Recording(frames=2x4x3, pitch_mm=None, dt_s=None, units=None)"
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    model = pymodal.ModalModel(np.c_[3 * np.cos(t), 2 * np.sin(t)])
    assert repr(model).startswith("ModalModel(dim=2, n_nodes=12, element='gaussian', modes=24, sigma=")
    assert "Some(" not in repr(model)


def test_synthetic_walk_repr_is_the_call_that_makes_it():
    walk = pymodal.SyntheticWalk(frames=30, rotation=5.0, translation=(1.0, -2.5))
    text = repr(walk)
    assert text.startswith("SyntheticWalk(frames=30, ") and "rotation=5.0" in text
    again = eval(text, {"SyntheticWalk": pymodal.SyntheticWalk})
    assert repr(again) == text
    assert np.array_equal(again.true_positions(7, np.array([[3.0, 4.0]])),
                          walk.true_positions(7, np.array([[3.0, 4.0]])))


def test_results_compare_by_value():
    a, b = outline(30), outline(32, 0.2)
    m = pymodal.match(a, b)
    assert m == pymodal.match(a, b) and m != pymodal.match(b, a)
    assert m != m.pairs and m != None  # noqa: E711  (another type is never equal)
    assert len({m, pymodal.match(a, b), pymodal.match(b, a)}) == 2
    assert pymodal.ModalModel(a) == pymodal.ModalModel(a) != pymodal.ModalModel(b)
    rec = pymodal.Recording.from_array(np.ones((2, 4, 3)), pitch_mm=5.0)
    assert rec == pymodal.Recording.from_array(np.ones((2, 4, 3)), pitch_mm=5.0)
    assert rec != pymodal.Recording.from_array(np.ones((2, 4, 3)), pitch_mm=5.08)


def test_synthetic_walk_round_trip():
    walk = pymodal.SyntheticWalk(frames=30, rotation=5.0, translation=(1.0, -2.5))
    back = pickle.loads(pickle.dumps(walk))
    assert back == walk and hash(back) == hash(walk) and repr(back) == repr(walk)
    assert back != pymodal.SyntheticWalk(frames=31)
    pts = np.array([[10.0, 20.0], [15.0, 40.0]])
    assert_same(walk.true_positions(12, pts), back.true_positions(12, pts))


def test_run_result_compares_by_value():
    # A RunResult holds numpy arrays: == compared them as dict values and raised ("The truth
    # value of an array ... is ambiguous").
    import copy

    t = np.arange(6)[:, None, None]
    r, c = np.mgrid[0:30, 0:20]
    frames = np.maximum(0.0, 100.0 * (1 - ((c - 8 - 0.5 * t) / 5.0) ** 2 - ((r - 12 - t) / 8.0) ** 2))
    res = pymodal.run(frames.astype(np.float32))
    assert res["tracks"] and res["objects"]
    for same in (pickle.loads(pickle.dumps(res)), copy.deepcopy(res)):
        assert type(same) is type(res)
        assert same == res and res == same and not (same != res)
    assert res == dict(res)  # a dict with the same content is equal, as for any dict
    with pytest.raises(TypeError, match="unhashable"):
        hash(res)

    one_element = copy.deepcopy(res)
    one_element["tracks"][0][0, 1] += 1.0
    one_key = copy.deepcopy(res)
    one_key["extra"] = one_key.pop("timings")
    nested = copy.deepcopy(res)
    nested["summary"]["recording"]["frames"] += 1
    dtype = copy.deepcopy(res)
    dtype["track_steps"][0] = dtype["track_steps"][0].astype(np.int32)
    for other in (one_element, one_key, nested, dtype):
        assert other != res and res != other and not (other == res)
    assert res != [res] and res != None  # noqa: E711
