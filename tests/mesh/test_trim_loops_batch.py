"""The closed trim loops of many faces in one call
(:func:`geomkit.mesh.trim_polylines.loop_polylines`, kernel
``geomkit._kernels.tess_loops.face_loops``) against the route before it: per face, the
pieces' polylines from ``trim_polylines`` joined in numpy (each piece after a loop's
first drops its first row, the last row set to the first) and each loop's
``loop_rectangle_gap``.  Bit for bit, one face at a time and all faces of a part in one
call, on the trimmed faces of four real parts (planes with arcs, cylinders, cones,
quintic pcurves of many spans, several loops a face), with and without the UV-chord
test; the loops come back read only."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit._kernels.tess_trim import loop_rectangle_gap, trim_polylines
from geomkit.mesh.trim_polylines import SEED_SPANS, loop_polylines, packed_trims

from helpers.parts import part_surfaces

PARTS = ["proe_as1_ap203.stp", "nist_ctc_01_ap242.stp", "euclid_screw_ap214.step",
         "inventor2015_cylinder_block_face6.stp"]


def _numpy_route(s, chord_tol, affine):
    """The loops as the face-by-face route made them."""
    (u0, u1), (v0, v1) = s.domain
    CP, W, K, deg, cp_off, k_off, loop_first = packed_trims(s)
    m = len(deg)
    counts = np.empty(m, dtype=np.int64)
    buf = np.empty((8 * len(K) + 64, 3))
    while True:
        n = trim_polylines(CP, W, K, deg, cp_off, k_off, SEED_SPANS, u0, v0, u1, v1,
                           s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                           chord_tol, chord_tol, 2 * chord_tol, not affine, True, buf,
                           counts, True)
        if n >= 0:
            break
        buf = np.empty((4 * len(buf), 3))
    uv = buf[:n, 1:]
    first = np.concatenate([[0], np.cumsum(counts)])
    loops = []
    for a, b in zip(loop_first[:-1], loop_first[1:]):
        rows = [uv[first[a]:first[a + 1]]] + [uv[first[c] + 1:first[c + 1]]
                                              for c in range(a + 1, b)]
        pts = np.concatenate(rows)
        pts[-1] = pts[0]
        loops.append(pts)
    gaps = [list(loop_rectangle_gap(p, u0, u1, v0, v1)) for p in loops]
    return loops, gaps


@pytest.fixture(scope="module", params=PARTS)
def part(request):
    S, size = part_surfaces(request.param)
    return request.param, [s for s in S if s.trim], size


@pytest.mark.parametrize("affine", [False, True])
def test_loops_match_the_face_by_face_route(part, affine):
    name, S, size = part
    chord_tol = 5e-4 * size
    batch = loop_polylines(S, chord_tol, affine, True)
    assert len(batch) == len(S)
    several = 0
    for s, got in zip(S, batch):
        want = _numpy_route(s, chord_tol, affine)
        alone = loop_polylines([s], chord_tol, affine, True)[0]
        for g in (got, alone):
            assert len(g[0]) == len(want[0]) == len(s.trim)
            for a, b in zip(g[0], want[0]):
                assert a.shape == b.shape and np.array_equal(a, b)
                assert not a.flags.writeable
            assert g[1] == want[1]
        several += len(s.trim) > 1
    if name in ("proe_as1_ap203.stp", "nist_ctc_01_ap242.stp"):
        assert several  # faces with holes: several loops a face


def test_a_small_buffer_grows():
    """Many-span pieces (Inventor's quintic of ~100 spans) need more rows than the
    first guess of 8 per knot: the kernel grows its buffers itself."""
    s = part_surfaces(PARTS[3])[0][0]
    loops, _ = loop_polylines([s], 1e-7 * s.size, False, True)[0]
    want, _ = _numpy_route(s, 1e-7 * s.size, False)
    assert len(loops[0]) > 8 * sum(len(c.knots) for c in s.trim[0].pieces) + 64
    assert all(np.array_equal(a, b) for a, b in zip(loops, want))
