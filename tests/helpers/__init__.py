"""Helpers shared by the tests of every folder (``tests/`` is put on ``sys.path`` by
``tests/conftest.py``; import them as ``from helpers import naive``,
``from helpers.tesshelp import REL``, ...).

* :mod:`helpers.paths` — the repository, ``tests/`` and ``tests/data/`` folders.
* :mod:`helpers.surfaces` — sample surfaces, parameter sets, geomdl as reference
  evaluator, hypothesis strategies of random surfaces.
* :mod:`helpers.naive` — the brute-force oracles (Cox–de Boor, dense sampling, ...).
* :mod:`helpers.trims` — UV trim loops in closed form (exact circles, the unit plate).
* :mod:`helpers.poses` — 4x4 rigid poses.
* :mod:`helpers.tesshelp` — the tessellation tests' cases and mesh checks.
* :mod:`helpers.igeswrite` — a minimal IGES writer and reader of entity types.
* :mod:`helpers.occ_oracle` — Open CASCADE oracles of the CAD tests.
* :mod:`helpers.clihelp` — running the command line in or out of process.
* :mod:`helpers.browser` — opening HTML reports in headless Chromium.
"""
