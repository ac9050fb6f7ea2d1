"""Module paths of earlier releases still work, with a DeprecationWarning naming the
new one; the public API imports from ``geomkit`` unchanged."""

from __future__ import annotations

import importlib
import io
import pickle

import numpy as np
import pytest

import geomkit
from geomkit._moved import MOVED


def test_every_public_name_imports_from_geomkit():
    for name in geomkit.__all__:
        assert getattr(geomkit, name) is not None, name
    assert callable(geomkit.tessellate) and callable(geomkit.deviation)


@pytest.mark.parametrize("old, name", [
    ("geomkit.deviation", "deviation"), ("geomkit.scene", "Scene"),
    ("geomkit.motion", "first_contact"), ("geomkit.iges", "read_iges"),
    ("geomkit.demo", "run_demo"), ("geomkit.types", "Mesh"), ("geomkit.types", "Surface"),
    ("geomkit.tessellate", "tessellate"), ("geomkit.oracles.occ", "evaluate"),
])
def test_old_paths_warn_and_forward(old, name):
    if old.startswith("geomkit.oracles"):
        pytest.importorskip("OCP")
    mod = importlib.import_module(old)
    mod.__dict__["_warned"] = False
    with pytest.warns(DeprecationWarning, match="moved to geomkit\\."):
        obj = getattr(mod, name)
    new = importlib.import_module(MOVED[old][0])
    assert obj is getattr(new, name, obj)
    # the package's own names are not clobbered by importing the old path
    assert callable(geomkit.tessellate) and callable(geomkit.deviation)


def test_pickles_naming_old_paths_load():
    """pickle finds a class by importing its module and reading the name: an old
    path (a Body pickled by an earlier release) resolves to the class of today."""
    mod = importlib.import_module("geomkit._collision_types")
    mod.__dict__["_warned"] = False
    with pytest.warns(DeprecationWarning):
        cls = pickle.Unpickler.find_class(pickle.Unpickler(io.BytesIO(b"")),
                                          "geomkit._collision_types", "Body")
    assert cls is geomkit.Body
    body = geomkit.Body((np.eye(3), np.array([[0, 1, 2]])))
    assert type(pickle.loads(pickle.dumps(body))) is geomkit.Body
