"""The docstrings' examples run (from the repository's root, where their paths point), and
every public name is documented and in the type stubs' reach."""

from __future__ import annotations

import doctest
import importlib
import inspect
import os
from pathlib import Path

import pytest

import sticky_lips

REPO = Path(__file__).resolve().parents[2]
MODULES = ["sticky_lips", "sticky_lips._scenario", "sticky_lips._run", "sticky_lips._face", "sticky_lips.errors"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name, monkeypatch):
    monkeypatch.chdir(REPO)
    module = importlib.import_module(name)
    result = doctest.testmod(
        module, extraglobs={"sticky_lips": sticky_lips}, optionflags=doctest.ELLIPSIS, verbose=False
    )
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"


def test_every_public_name_is_documented():
    for name in sticky_lips.__all__:
        obj = getattr(sticky_lips, name)
        if name == "__version__":
            assert isinstance(obj, str)
            continue
        assert inspect.getdoc(obj), name


def test_the_package_is_typed():
    root = Path(sticky_lips.__file__).parent
    assert (root / "py.typed").is_file()
    assert (root / "_native.pyi").is_file()
    # the stubs name every function the native module has
    stub = (root / "_native.pyi").read_text()
    native = importlib.import_module("sticky_lips._native")
    for name in dir(native):
        if not name.startswith("_"):
            assert f"def {name}(" in stub or f"class {name}" in stub or f"{name}:" in stub, name
    assert os.path.basename(native.__file__).startswith("_native")
