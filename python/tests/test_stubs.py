"""The type stubs describe the compiled module as it is: every name and
method the stub declares exists, and every public one the module has is
declared; every public function and class of the package has a docstring."""

import ast
import inspect
import pathlib

import slipfront
from slipfront import _core

STUB = pathlib.Path(slipfront.__file__).with_name("_core.pyi")


def declared():
    tree = ast.parse(STUB.read_text())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {n.name for n in node.body
                                if isinstance(n, ast.FunctionDef)} | {
                n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.AnnAssign):
            names[node.target.id] = None
    return names


def test_the_stub_matches_the_compiled_module():
    names = declared()
    public = {n for n in dir(_core) if not n.startswith("_")} | {"__version__"}
    assert set(names) == public, (set(names) ^ public)
    for cls, members in names.items():
        if members is None:
            continue
        kind = getattr(_core, cls)
        inherited = set(dir(kind.__mro__[1])) if len(kind.__mro__) > 1 else set()
        real = {m for m in dir(kind) if not m.startswith("_") and m not in inherited}
        real |= {"__init__"}
        declared_public = {m for m in members if not m.startswith("_")}
        assert declared_public <= real, (cls, declared_public - real)
        assert {m for m in real if m != "__init__"} <= members, (cls, real - members)


def test_the_package_is_documented():
    assert slipfront.__doc__
    for name in slipfront.__all__ + ["open"]:
        obj = getattr(slipfront, name)
        if inspect.isclass(obj) or inspect.isfunction(obj) or inspect.isbuiltin(obj):
            assert obj.__doc__, name
