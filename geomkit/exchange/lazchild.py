"""LAZ decompression in a child process (``python -m geomkit.exchange.lazchild FILE
CHUNK``).

The LAZ decompressors (lazrs, in Rust; LASzip) abort the process on some damaged files
(a Rust panic is a SIGABRT, found by the reader fuzz), which no ``except`` can catch.
:func:`geomkit.exchange.scanlib.iter_las` therefore reads compressed files through this
child: it writes a JSON header line (point count, the record's fields and types) and
then, per chunk, the count as 8 bytes and the records, on its stdout; the parent
streams them (memory bounded by the chunk) and turns an early end into a
:class:`~geomkit.FileFormatError`.
"""

from __future__ import annotations

import json
import sys

import numpy as np

ATTRS = ("intensity", "red", "green", "blue")


def main(argv=None) -> int:
    path, chunk = (argv or sys.argv[1:])[:2]
    import laspy

    out = sys.stdout.buffer
    try:
        fh = laspy.open(path)
    except Exception as exc:  # noqa: BLE001 - reported to the parent
        out.write((json.dumps({"error": " ".join(str(exc).split())}) + "\n").encode())
        return 0
    with fh:
        dims = set(fh.header.point_format.dimension_names)
        names = [d for d in ATTRS if d in dims]
        fields = [("x", "<f8"), ("y", "<f8"), ("z", "<f8")] + [
            (d, np.dtype(fh.header.point_format.dimension_by_name(d).dtype).newbyteorder("<")
             .str) for d in names]
        out.write((json.dumps({"n": int(fh.header.point_count), "fields": fields}) + "\n")
                  .encode())
        out.flush()
        dt = np.dtype([tuple(f) for f in fields])
        try:
            for pts in fh.chunk_iterator(int(chunk)):
                m = len(pts)
                rec = np.empty(m, dt)
                rec["x"], rec["y"], rec["z"] = pts.x, pts.y, pts.z
                for d in names:
                    rec[d] = pts[d]
                out.write(int(m).to_bytes(8, "little"))
                out.write(rec.tobytes())
                out.flush()
        except Exception as exc:  # noqa: BLE001 - the parent sees the early end
            sys.stderr.write(" ".join(str(exc).split())[:300])
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
