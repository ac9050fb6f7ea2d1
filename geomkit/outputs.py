"""Writing output files safely: every writer in geomkit goes through here.

* :func:`check_target` refuses to replace an existing file unless asked to;
* :func:`atomic_write` writes a temporary file beside the target and renames it into
  place, so a crash or a full disk never leaves a half-written file where a good one was;
* :func:`json_safe` turns NaN / inf into ``null`` and numpy scalars into Python ones.
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["atomic_write", "check_target", "json_safe"]


def check_target(path, overwrite: bool) -> Path:
    """``path`` as a :class:`~pathlib.Path`; :class:`FileExistsError` if it exists and
    ``overwrite`` is false."""
    p = Path(path)
    if p.exists() and not overwrite:
        raise FileExistsError(f"{p}: exists; pass overwrite=True to replace it")
    return p


def _umask() -> int:
    """The process umask, read without changing it where the system allows
    (``/proc/self/status`` on Linux), else by setting and restoring it."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(p: Path, write) -> Path:
    """Call ``write(fh)`` on a temporary file in the target folder, then rename it to
    ``p``; on any error the temporary file is removed and ``p`` is untouched.

    The file gets the mode a plain ``open(p, "w")`` would give (``0o666`` less the
    umask: 0644 under the usual 022), not the 0600 of the temporary file."""
    p = Path(p)
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            os.fchmod(fh.fileno(), 0o666 & ~_umask())
            write(fh)
        os.replace(tmp, p)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return p


def json_safe(obj):
    """JSON-safe copy: NaN / inf -> None, arrays -> lists, numpy scalars -> Python."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj
