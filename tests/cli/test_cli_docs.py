"""docs/cli.md and README.md stay true to the code: every command and option of the
parser is documented, every module and folder of the package is in the README's
layout, and every command is in its command-line section."""

from __future__ import annotations

import argparse

from geomkit.cli import build_parser

from helpers.paths import ROOT


def _commands():
    sub = next(a for a in build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    return sub.choices


def test_cli_doc_lists_every_command_and_option():
    doc = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    missing = []
    for name, p in _commands().items():
        if f"`{name}" not in doc:
            missing.append(name)
        for a in p._actions:
            for opt in a.option_strings:
                if opt not in ("-h", "--help") and f"`{opt}" not in doc \
                        and f", {opt}" not in doc:
                    missing.append(f"{name} {opt}")
    assert not missing, f"not in docs/cli.md: {missing}"


def test_readme_layout_and_command_line_are_complete():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    layout = text[text.index("## Layout"):]
    cmdline = text[text.index("## Command line"):text.index("## Layout")]
    pkg = ROOT / "geomkit"
    names = [p.name for p in pkg.iterdir()
             if (p.suffix == ".py" or (p.is_dir() and (p / "__init__.py").exists()))]
    missing = [n for n in names if n.removesuffix(".py") not in layout]
    assert not missing, f"not in README's layout: {missing}"
    assert "examples/" in layout and "cli/" in layout and "cli.py" not in layout
    assert [c for c in _commands() if f"geomkit {c}" not in cmdline] == []
