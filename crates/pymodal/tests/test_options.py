"""One vocabulary: the keywords of pymodal.match and pymodal.run are the library's option tables
(pymodal._options(), the tables the pedomatch CLI reads too: a Rust test checks its flags), and
the word options accept exactly the listed values."""
import inspect

import numpy as np
import pytest

import pymodal

OPTIONS = pymodal._options()


def names(*groups):
    return [o["name"] for g in groups for o in OPTIONS[g]]


def keywords(fn):
    return [p.name for p in inspect.signature(fn).parameters.values() if p.kind == p.KEYWORD_ONLY]


def test_match_keywords_are_the_match_and_pair_options():
    extra = ["triangles_a", "triangles_b"]  # meshes given as arrays: Python only
    assert keywords(pymodal.match) == names("match", "pair") + extra


def test_run_keywords_are_the_match_recording_output_and_read_options():
    # `out` is the folder written (pedomatch run --out), the output options what it holds; the
    # reading options (limits, layout) as read_recording takes them.
    assert keywords(pymodal.run) == names("match", "recording") + ["out"] + names("output", "read")


def test_batch_keywords_are_the_output_options():
    for fn in (pymodal.batch, pymodal.batch_row):
        assert [k for k in keywords(fn) if k in names("output")] == names("output"), fn.__name__


def test_batch_takes_the_study_options():
    # `jobs` (positional too, as before) and `force` are `pedomatch batch`'s --jobs and --force.
    params = inspect.signature(pymodal.batch).parameters
    assert [p for p in params if p in names("study")] == names("study") == ["jobs", "force"]
    assert "force" in inspect.signature(pymodal.batch_row).parameters
    study = {o["name"]: o for o in OPTIONS["study"]}
    assert study["jobs"]["cli_flags"] == ["--jobs"] and study["force"]["cli_flags"] == ["--force"]


def test_from_array_keywords_are_the_unit_options():
    assert keywords(pymodal.Recording.from_array) == names("units") + ["mask"]


def test_read_recording_keywords_are_the_unit_options():
    # Plus the reading options (the pedar layout table, the limits), as on the CLI.
    assert names("read")[0] == "layout" and "max_frames" in names("read")
    assert keywords(pymodal.read_recording) == names("units") + names("read")
    assert set(names("units")) <= set(names("recording"))


def test_every_keyword_defaults_to_none():
    for fn in (pymodal.match, pymodal.run, pymodal.read_recording):
        for p in inspect.signature(fn).parameters.values():
            if p.kind == p.KEYWORD_ONLY:
                assert p.default is None, (fn.__name__, p.name)


def test_cli_flags_follow_the_python_names():
    for group in OPTIONS.values():
        for o in group:
            flag = "--" + o["name"].replace("_", "-")
            assert flag in o["cli_flags"] or "--no-" + flag[2:] in o["cli_flags"], o


@pytest.mark.parametrize("option", [o for o in OPTIONS["match"] if o["kind"] == "word"], ids=lambda o: o["name"])
def test_every_listed_word_is_accepted_by_match(option):
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    a = np.c_[3 * np.cos(t), 2 * np.sin(t)]
    for value in option["values"]:
        pymodal.match(a, a * 1.1, **{option["name"]: value})
    with pytest.raises(ValueError, match=option["name"]):
        pymodal.match(a, a, **{option["name"]: "no-such-value"})
