"""Folders the tests read: the repository root (``docs/``, ``examples/``,
``README.md``, ``pyproject.toml``), ``tests/`` and its ``data/``."""

from __future__ import annotations

from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
ROOT = TESTS.parent
DATA = TESTS / "data"
