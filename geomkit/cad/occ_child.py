"""Open CASCADE's STEP read in a child process (``python -m geomkit.cad.occ_child``).

:func:`geomkit.cad.step.read_step` hands a file to Open CASCADE only when geomkit's own
reader could not finish it, and such files are often broken: OCC can crash on them
(a segmentation fault in ``TransferRoots``).  The child reads the file with
:func:`geomkit.cad.step.read_step_occ` and pickles the result (or the error) to the file
named on its command line, with the warnings raised while reading; a crash ends only
the child.  Its stdout (OCC's messages) is captured by the parent, never printed there.
"""

from __future__ import annotations

import pickle
import sys
import warnings


def main(argv=None) -> int:
    path, skip_invalid, skip_unsupported, out = (argv or sys.argv[1:])[:4]
    from geomkit.cad.step import read_step_occ

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            res = ("ok", read_step_occ(path, skip_invalid == "1", skip_unsupported == "1"))
        except Exception as exc:  # noqa: BLE001 - sent to the parent, which raises it
            res = ("error", exc)
    sys.stdout.flush()
    found = [(w.category, str(w.message)) for w in caught]
    with open(out, "wb") as fh:
        pickle.dump((*res, found), fh)
    return 0


if __name__ == "__main__":
    sys.exit(main())
