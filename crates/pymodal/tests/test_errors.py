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
    # The message names the object, whichever side is degenerate.
    assert str(info.value).startswith("object A: ")
    with pytest.raises(pymodal.DegenerateShapeError, match=f"^object B: .*{text}"):
        pymodal.match(outline(), points)


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


# Argument errors: every argument of the wrong form is an InputError (still a ValueError, so
# `except ValueError` keeps working) whose message names the argument and what it takes.
SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 1.5]])


@pytest.mark.parametrize(
    "call, name, text",
    [
        (lambda: pymodal.match(np.zeros((5, 4)), SQUARE), "a", r"\(5, 4\)"),
        (lambda: pymodal.match(SQUARE, np.zeros(5)), "b", r"\(5,\)"),
        (lambda: pymodal.match(np.zeros((2, 3, 2)), SQUARE), "a", r"\(2, 3, 2\)"),
        (lambda: pymodal.match("abc", SQUARE), "a", "'abc'"),
        (lambda: pymodal.match(SQUARE, np.c_[SQUARE, np.ones(5)]), "a and b", "got 2 and 3"),
        (lambda: pymodal.match(SQUARE, SQUARE, triangles_a=[[0, 1]]), "triangles_a", r"\(1, 2\)"),
        (lambda: pymodal.run(np.zeros((3, 8, 8)), pitch_mm="abc"), "pitch_mm", "'abc'"),
        (lambda: pymodal.run(np.zeros((3, 8, 8)), pitch_mm=(1.0, 2.0, 3.0)), "pitch_mm", "pair"),
        # A decimal comma in a string is not read as two pitches: Python takes (x, y) numbers.
        (lambda: pymodal.read_recording(ASF, pitch_mm="5,08"), "pitch_mm", "'5,08'"),
        (lambda: pymodal.run(np.zeros((3, 8, 8)), frames=5), "frames", r"\(start, end\) pair.*got 5"),
        (lambda: pymodal.run(np.zeros((3, 8, 8)), frames=(1, "x")), "frames", "0-based"),
        (lambda: pymodal.run(np.zeros((3, 8, 8)), frames=(1.5, 2)), "frames", "got \\(1.5, 2\\)"),
        (lambda: pymodal.run(np.zeros((3, 8, 8)), frames=(True, 2)), "frames", "negative index"),
        (lambda: pymodal.run(np.zeros((2, 2, 2, 2))), "recording", r"\(2, 2, 2, 2\)"),
        (lambda: pymodal.run(object()), "recording", "a path, a Recording"),
        (lambda: pymodal.batch_row("x.asf", frames=5), "frames", r"\(start, end\) pair"),
        (lambda: pymodal.batch(42), "paths", "got 42"),
        (lambda: pymodal.find_recordings([1, 2]), "inputs", "a path or glob pattern"),
        (lambda: pymodal.contours(np.zeros(5)), "frame", r"\(5,\)"),
        (lambda: pymodal.contours([["a", "b"]]), "frame", "numbers|pressures"),
        (lambda: pymodal.Recording.from_array(np.zeros(5)), "frames", r"\(5,\)"),
        (lambda: pymodal.ModalModel(np.zeros((4, 5))), "points", r"\(4, 5\)"),
        (lambda: pymodal.ModalModel(SQUARE, edges=[[0, 1, 2]]), "edges", "2 columns"),
        (lambda: pymodal.eigh(np.eye(3), np.eye(2)), "k and m", r"\(3, 3\) and \(2, 2\)"),
        (lambda: pymodal.eigh(np.eye(2), [[np.nan, 0], [0, 1]]), "m", "NaN"),
        (lambda: pymodal.linear_sum_assignment(np.zeros(3)), "cost_matrix", "expected a matrix"),
        (lambda: pymodal.linear_sum_assignment(np.eye(2), solver="jv", method="jv"), "solver and method", "alias"),
        (lambda: pymodal.SyntheticWalk().true_positions(1, np.zeros((3, 3))), "points", r"\(3, 3\)"),
    ],
)
def test_argument_errors_are_input_errors_naming_the_argument(call, name, text):
    with pytest.raises(pymodal.InputError, match=text) as info:
        call()
    assert isinstance(info.value, ValueError)
    assert str(info.value).startswith(name), str(info.value)


# Integer keywords (counts, sizes, frame indices): a negative value is an OptionError naming the
# keyword and the value, not pyo3's unnamed OverflowError. The keywords come from the stubs (every
# parameter typed int or Optional[int], or a stride: an int or the word auto), so a keyword added
# later is covered too.
INT_ANNOTATIONS = ("int", "Optional[int]", "Optional[Union[int, Literal['auto']]]")
FRAMES = np.zeros((3, 8, 8))
INT_KEYWORD_CALLS = {
    "match": lambda **kw: pymodal.match(SQUARE, SQUARE, **kw),
    "run": lambda **kw: pymodal.run(FRAMES, **kw),
    "batch": lambda **kw: pymodal.batch([], **kw),
    "contours": lambda **kw: pymodal.contours(np.eye(5), **kw),
    "isocontours": lambda **kw: pymodal.isocontours(np.eye(5), [0.5], **kw),
    "surface": lambda **kw: pymodal.surface(np.eye(5), **kw),
    "eigh": lambda **kw: pymodal.eigh(np.eye(3), np.eye(3), **kw),
    "ModalModel": lambda **kw: pymodal.ModalModel(SQUARE, **kw),
    "SyntheticWalk": lambda **kw: pymodal.SyntheticWalk(**kw),
    "register": lambda **kw: pymodal.register(np.zeros((2, 8, 8)), **kw),
    "read_recording": lambda **kw: pymodal.read_recording(ASF, **kw),
    "batch_row": lambda **kw: pymodal.batch_row(ASF, **kw),
}


def int_keywords():
    import ast

    stub = ast.parse((pathlib.Path(pymodal.__file__).parent / "_pymodal.pyi").read_text())
    found = []
    for node in stub.body:
        fn = node
        if isinstance(node, ast.ClassDef):
            fn = next((f for f in node.body if isinstance(f, ast.FunctionDef) and f.name == "__init__"), None)
        if not isinstance(fn, ast.FunctionDef):
            continue
        for arg in fn.args.args + fn.args.kwonlyargs:
            if ast.unparse(arg.annotation or ast.Constant(None)) in INT_ANNOTATIONS:
                found.append((node.name, arg.arg))
    return found


@pytest.mark.parametrize("function, keyword", int_keywords())
def test_negative_integer_keywords_are_option_errors_naming_them(function, keyword):
    assert function in INT_KEYWORD_CALLS, f"add a call of {function} to INT_KEYWORD_CALLS"
    with pytest.raises(pymodal.OptionError) as info:
        INT_KEYWORD_CALLS[function](**{keyword: -1})
    assert str(info.value) == f"{keyword} must be a non-negative integer, got -1"


def test_every_integer_keyword_of_the_audit_is_covered():
    found = set(int_keywords())
    for keyword in ("refits", "band", "deform_modes", "center_stride"):
        assert ("match", keyword) in found and ("run", keyword) in found, keyword
    for keyword in ("iso_frame", "iso_levels", "surface_nodes", "drift_reference", "every"):
        assert ("run", keyword) in found, keyword


@pytest.mark.parametrize(
    "call, keyword",
    [
        (lambda: pymodal.batch_row("x.asf", refits=-2), "refits"),
        (lambda: pymodal.batch([], iso_frame=-2), "iso_frame"),
        (lambda: pymodal.SyntheticWalk().true_positions(-2, np.zeros((3, 2))), "t"),
        (lambda: pymodal.ModalModel(SQUARE).features(-2), "k"),
        (lambda: pymodal.run(FRAMES, band=np.int64(-2)), "band"),
    ],
)
def test_negative_integers_read_by_hand_are_option_errors_too(call, keyword):
    with pytest.raises(pymodal.OptionError, match=f"^{keyword} must be a non-negative integer, got -2$"):
        call()


def test_bad_material_values_are_option_errors_naming_material():
    for material in ({"young": "stiff"}, (1.0, 0.3), {1: 2.0}):
        with pytest.raises(pymodal.OptionError, match="material") as info:
            pymodal.match(outline(), outline(), material=material)
        assert isinstance(info.value, pymodal.InputError)


# Option keywords of the wrong type: a TypeError whose message itself names the keyword and the
# type it takes (pyo3's own names neither: "must be real number, not str", the keyword only in a
# note), one wording for every function that takes them, batch's **options included. The
# keywords and their types come from the stubs, so an option added later is covered too.
WRONG = {  # annotation -> (a value of another type, what the message says is expected)
    "Optional[float]": ("high", "a number"),
    "Optional[int]": (2.5, "an integer"),
    "Optional[bool]": ("yes", "True or False"),
    "Optional[str]": (3, "a string"),
    # A number or the word auto (every=): a float is neither.
    "Optional[Union[int, Literal['auto']]]": (2.5, "an integer"),
}
for _alias in ("Element", "Solver", "Search", "Prealign", "ThresholdMode",
               "Literal['contour', 'surface', 'isocontour']"):
    WRONG[f"Optional[{_alias}]"] = (3, "a string")
OPTION_CALLS = {
    "match": lambda **kw: pymodal.match(SQUARE, SQUARE, **kw),
    "run": lambda **kw: pymodal.run(FRAMES, **kw),
    "read_recording": lambda **kw: pymodal.read_recording(ASF, **kw),
    "Recording.from_array": lambda **kw: pymodal.Recording.from_array(FRAMES, **kw),
    "batch": lambda **kw: pymodal.batch([], **kw),
}


def option_keywords():
    import ast

    stub = ast.parse((pathlib.Path(pymodal.__file__).parent / "_pymodal.pyi").read_text())
    functions = {n.name: n for n in stub.body if isinstance(n, ast.FunctionDef)}
    recording = next(n for n in stub.body if isinstance(n, ast.ClassDef) and n.name == "Recording")
    functions["Recording.from_array"] = next(f for f in recording.body if getattr(f, "name", "") == "from_array")
    found = []
    for name in OPTION_CALLS:
        fn = functions[name]
        for arg in fn.args.args + fn.args.kwonlyargs:
            annotation = ast.unparse(arg.annotation or ast.Constant(None))
            if annotation.startswith("Optional[Literal["):
                # A word option (the generated stubs spell out its words).
                found.append((name, arg.arg, 3, "a string"))
            elif annotation in WRONG:
                found.append((name, arg.arg, *WRONG[annotation]))
    # batch and batch_row take run's keywords as **options.
    for _, keyword, value, expected in [f for f in found if f[0] == "run"]:
        found.append(("batch", keyword, value, expected))
        found.append(("batch_row", keyword, value, expected))
    return found


OPTION_CALLS["batch_row"] = lambda **kw: pymodal.batch_row("x.asf", **kw)


@pytest.mark.parametrize("function, keyword, value, expected", option_keywords())
def test_option_keywords_of_the_wrong_type_are_type_errors_naming_them(function, keyword, value, expected):
    with pytest.raises(TypeError) as info:
        OPTION_CALLS[function](**{keyword: value})
    assert str(info.value) == f"{keyword} must be {expected}, got {value!r}"
    assert not getattr(info.value, "__notes__", None), info.value.__notes__


def test_every_option_keyword_is_audited_for_its_type():
    audited = {(f, k) for f, k, _, _ in option_keywords()}
    specs = pymodal._options()
    for table, functions in [("match", ["match", "run", "batch_row"]), ("pair", ["match"]),
                             ("recording", ["run", "batch", "batch_row"]), ("units", ["read_recording"])]:
        for spec in specs[table]:
            if spec["name"] in ("material", "pitch_mm", "frames", "points", "regions"):
                continue  # not scalars: a wrong form is an InputError naming it
            for f in functions:
                assert (f, spec["name"]) in audited, (f, spec["name"])
    assert ("batch", "jobs") in audited and ("Recording.from_array", "frame_rate") in audited


def test_good_forms_of_frames_and_pitch_are_accepted():
    frames = np.zeros((4, 12, 10), np.float32)
    frames[:, 3:9, 3:7] = 100.0
    for kw in (dict(frames=[1, None]), dict(frames=(None, 3)), dict(pitch_mm=[5.0, 4.0]),
               dict(pitch_mm=np.array([5.0, 4.0])), dict(pitch_mm=np.float32(5.0))):
        res = pymodal.run(frames, **kw)
        assert res["summary"]["recording"]["frames"] == 4, kw


def test_docstrings_name_every_keyword_and_the_exceptions():
    doc = pymodal.match.__doc__
    assert "max_rotation" in doc and "degrees" in doc
    for name in ("InputError", "OptionError", "DegenerateShapeError"):
        assert name in doc, name
    assert "ValueError — arrays" not in doc
    run_doc = pymodal.run.__doc__
    assert "Raises" in run_doc and "max_rotation" in run_doc
    for name in ("InputError", "OptionError", "FormatError", "FileNotFoundError"):
        assert name in run_doc, name
    assert "sensels" in pymodal.contours.__doc__ and "pixel" not in pymodal.contours.__doc__


def test_reading_limits_are_keywords_and_a_refusal_says_how_to_raise_it():
    with pytest.raises(pymodal.FormatError, match=r"max_frames="):
        pymodal.read_recording(ASF, max_frames=100)
    assert pymodal.read_recording(ASF, max_frames=205).frames.shape[0] == 205


def test_an_object_beyond_the_node_limit_is_a_typed_error_at_once():
    # 20,000 points: a model of 1.6e9 values a matrix; refused before it is built.
    points = outline(20_000)
    with pytest.raises(pymodal.PedomatchError, match=r"max_nodes="):
        pymodal.match(points, points)
    small = outline(50)
    with pytest.raises(pymodal.PedomatchError, match=r"max_nodes="):
        pymodal.match(small, small, max_nodes=40)
    assert len(pymodal.match(small, small, max_nodes=60).pairs) > 0
