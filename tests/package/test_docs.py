"""The API reference is generated from the docstrings and kept current."""

from __future__ import annotations

import importlib.util

import geomkit

from helpers.paths import ROOT


def test_api_reference_is_current():
    spec = importlib.util.spec_from_file_location("gen_api", ROOT / "docs" / "gen_api.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert text == mod.render(), "docs/api.md is stale: run python docs/gen_api.py"
    for name in geomkit.__all__:
        assert f"`geomkit.{name}" in text
    assert "## Other" not in text, "a new public name needs a group in docs/gen_api.py"
