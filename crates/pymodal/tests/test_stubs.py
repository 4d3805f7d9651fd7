"""The type stubs (pymodal/_pymodal.pyi) against the compiled module: every public name,
parameter, keyword-only marker and default must agree, properties must be properties, and every
public function, class and attribute must carry a docstring (help() and IDEs show them)."""
import ast
import inspect
from pathlib import Path

import pytest

import pymodal
from pymodal import _pymodal

PKG = Path(pymodal.__file__).resolve().parent
STUB = ast.parse((PKG / "_pymodal.pyi").read_text())
TOP = {n.name: n for n in STUB.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
PUBLIC = sorted(n for n in dir(_pymodal) if not n.startswith("_"))


def stub_params(fn, skip_self=False):
    """(name, kind, default) of a stub function, in order."""
    a = fn.args
    pos = a.posonlyargs + a.args
    if skip_self:
        pos = pos[1:]
    defaults = [inspect.Parameter.empty] * (len(pos) - len(a.defaults)) + [
        ast.literal_eval(d) for d in a.defaults
    ]
    out = [(p.arg, inspect.Parameter.POSITIONAL_OR_KEYWORD, d) for p, d in zip(pos, defaults)]
    if a.vararg:
        out.append((a.vararg.arg, inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.empty))
    for p, d in zip(a.kwonlyargs, a.kw_defaults):
        out.append(
            (p.arg, inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.empty if d is None else ast.literal_eval(d))
        )
    if a.kwarg:
        out.append((a.kwarg.arg, inspect.Parameter.VAR_KEYWORD, inspect.Parameter.empty))
    return out


def runtime_params(obj):
    sig = inspect.signature(obj)
    out = []
    for p in sig.parameters.values():
        kind = p.kind
        if kind == inspect.Parameter.POSITIONAL_ONLY:
            kind = inspect.Parameter.POSITIONAL_OR_KEYWORD
        out.append((p.name, kind, p.default))
    return out


def test_stub_and_marker_ship_with_the_package():
    assert (PKG / "_pymodal.pyi").is_file()
    assert (PKG / "py.typed").is_file()


def test_every_public_name_has_a_stub_and_no_stub_is_stale():
    assert sorted(TOP) == PUBLIC


@pytest.mark.parametrize("name", [n for n in PUBLIC if inspect.isbuiltin(getattr(_pymodal, n))])
def test_function_signatures_agree(name):
    fn = getattr(_pymodal, name)
    assert isinstance(TOP[name], ast.FunctionDef)
    assert stub_params(TOP[name]) == runtime_params(fn)
    assert (fn.__doc__ or "").strip(), f"{name} has no docstring"


@pytest.mark.parametrize("name", [n for n in PUBLIC if inspect.isclass(getattr(_pymodal, n))])
def test_classes_agree(name):
    cls = getattr(_pymodal, name)
    node = TOP[name]
    assert isinstance(node, ast.ClassDef)
    assert (cls.__doc__ or "").strip(), f"{name} has no docstring"
    defs = {f.name: f for f in node.body if isinstance(f, ast.FunctionDef)}
    init = defs.pop("__init__", None)
    if cls.__text_signature__ is None:
        assert init is None, f"{name} cannot be constructed from Python"
    else:
        assert init is not None
        assert stub_params(init, skip_self=True) == runtime_params(cls)
    runtime = {k: v for k, v in vars(cls).items() if not k.startswith("_")}
    stubbed = {k: f for k, f in defs.items() if not k.startswith("_")}
    assert sorted(stubbed) == sorted(runtime)
    for k, v in runtime.items():
        is_prop = any(isinstance(d, ast.Name) and d.id == "property" for d in stubbed[k].decorator_list)
        assert is_prop == inspect.isgetsetdescriptor(v), f"{name}.{k}: property in one, not the other"
        assert (v.__doc__ or "").strip(), f"{name}.{k} has no docstring"
        if not is_prop:
            assert stub_params(stubbed[k], skip_self=True) == runtime_params(getattr(cls, k))[1:]
    assert ("__len__" in defs) == ("__len__" in vars(cls))
