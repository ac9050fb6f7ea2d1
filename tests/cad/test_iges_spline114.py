"""IGES 114 (parametric spline surface, bicubic polynomial patches) as an exact
bicubic B-spline.

The file is written here from a global bicubic polynomial ``F(u, v)`` (each patch's
coefficients are its Taylor expansion at the patch corner, so a wrong coefficient
order or shift shows): the surface equals ``F`` at random ``(u, v)`` to rounding, and
equals Open CASCADE's reading of the same file at the same ``(u, v)``.  A 114 under a
144 is trimmed by parameter-space curves in its own ``(u, v)``.  Malformed records raise
a FileFormatError naming the entity and its DE number.
"""

from __future__ import annotations

from math import comb

import numpy as np
import pytest

from geomkit.errors import FileFormatError
from geomkit.nurbs.evaluation import evaluate
from geomkit.cad.iges.reader import read_iges

from helpers.igeswrite import de, write_iges

TU, TV = [0.0, 0.7, 1.5], [-1.0, 0.0, 0.4, 1.2]


def _poly():
    rng = np.random.default_rng(2)
    sc = np.array([1, 0.5, 0.2, 0.1])
    G = rng.normal(size=(3, 4, 4)) * sc[None, :, None] * sc[None, None, :]  # [xyz, a, b]
    G[0, 1, 0] += 3
    G[1, 0, 1] += 3

    def F(u, v):
        return np.stack([sum(G[k, a, b] * u ** a * v ** b for a in range(4)
                             for b in range(4)) for k in range(3)], -1)

    def taylor(u0, v0):  # coefficients of F(u0 + s, v0 + t) in s^a t^b
        C = np.zeros((3, 4, 4))
        for a in range(4):
            for b in range(4):
                for i in range(a, 4):
                    for j in range(b, 4):
                        C[:, a, b] += (G[:, i, j] * comb(i, a) * comb(j, b)
                                       * u0 ** (i - a) * v0 ** (j - b))
        return C

    return F, taylor


def _params(taylor, tu=TU, tv=TV):
    out = [3, 1, len(tu) - 1, len(tv) - 1, *tu, *tv]
    for i in range(len(tu) - 1):
        for j in range(len(tv) - 1):
            C = taylor(tu[i], tv[j])
            for k in range(3):  # AX..SX: coefficient of s^a t^b at a + 4 b
                out += list(C[k].T.reshape(-1))
        out += [0.0] * 48  # the arbitrary values the format carries
    return out + [0.0] * 48 * len(tv)


def test_114_is_the_files_polynomial(tmp_path):
    F, taylor = _poly()
    path = tmp_path / "s114.igs"
    write_iges(path, [(114, _params(taylor))])
    res = read_iges(path)
    (s,) = res.surfaces
    assert s.name == "114@1" and s.domain == ((0.0, 1.5), (-1.0, 1.2))
    assert s.degree_u == s.degree_v == 3 and s.approx_error == 0
    uv = np.random.default_rng(3).random((200, 2)) * [1.5, 2.2] + [0, -1]
    X = evaluate(s, uv)
    assert np.abs(X - F(uv[:, 0], uv[:, 1])).max() <= 1e-13 * np.abs(X).max()


def test_114_equals_open_cascade(tmp_path):
    pytest.importorskip("OCP", reason="Open CASCADE (OCP) is the oracle")
    from OCP.BRep import BRep_Tool
    from OCP.IGESControl import IGESControl_Reader
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    _, taylor = _poly()
    path = tmp_path / "s114.igs"
    write_iges(path, [(114, _params(taylor))])
    (s,) = read_iges(path).surfaces
    r = IGESControl_Reader()
    assert r.ReadFile(str(path)) == 1
    r.TransferRoots()
    face = TopoDS.Face(TopExp_Explorer(r.OneShape(), TopAbs_FACE).Current())
    srf = BRep_Tool.Surface_s(face)
    assert srf.Bounds() == pytest.approx((0.0, 1.5, -1.0, 1.2), abs=1e-15)
    uv = np.random.default_rng(4).random((100, 2)) * [1.5, 2.2] + [0, -1]
    Y = np.array([[q.X(), q.Y(), q.Z()] for q in (srf.Value(*map(float, p)) for p in uv)])
    assert np.abs(evaluate(s, uv) - Y).max() <= 1e-13 * np.abs(Y).max()


def test_114_trimmed_by_144(tmp_path):
    """A 144 over a 114 (with a 124 transform) with a 110-line triangle as its outer
    boundary in the 114's own (u, v): the trim is where the pcurves say."""
    import geomkit

    F, taylor = _poly()
    path = tmp_path / "t114.igs"
    M = [0, -1, 0, 5.0, 1, 0, 0, -2.0, 0, 0, 1, 0.5]  # rotate 90 deg about z, move
    write_iges(path, [
        (114, _params(taylor), 0, de(1), "00010000"),
        (124, M),
        (110, [0.1, -0.9, 0, 1.4, -0.9, 0]), (110, [1.4, -0.9, 0, 0.1, 1.1, 0]),
        (110, [0.1, 1.1, 0, 0.1, -0.9, 0]),
        (102, [3, de(2), de(3), de(4)]),
        (142, [1, de(0), de(5), 0, 1]),
        (144, [de(0), 1, 0, de(6)]),
    ])
    (s,) = read_iges(path).surfaces
    assert s.name == "144@15" and len(s.trim) == 1
    uv = np.random.default_rng(6).random((400, 2)) * [1.5, 2.2] + [0, -1]
    u, v = uv[:, 0], uv[:, 1]
    # inside the triangle (0.1, -0.9), (1.4, -0.9), (0.1, 1.1), away from its edges
    e = np.stack([v + 0.9, u - 0.1, 1.3 * 2.0 - (2.0 * (u - 0.1) + 1.3 * (v + 0.9))], 1)
    e /= [1, 1, np.hypot(2.0, 1.3)]
    clear = np.abs(e).min(axis=1) > 1e-3
    inside = (e > 0).all(axis=1)
    got = geomkit.classify_uv(s, uv[clear])
    assert np.array_equal(got == geomkit.INSIDE, inside[clear])
    R = np.array(M).reshape(3, 4)
    X = evaluate(s, uv[:5])
    assert np.abs(X - (F(u[:5], v[:5]) @ R[:, :3].T + R[:, 3])).max() <= 1e-12


BAD = {
    "truncated": ([3, 1, 1, 1, 0.0, 1.0, 0.0, 1.0] + [0.0] * 20, "patches need 52"),
    "no segments": ([3, 1, 0, 1, 0.0, 0.0, 1.0], "0 x 1 segments"),
    "breakpoints": ([3, 1, 1, 1, 1.0, 0.0, 0.0, 1.0] + [0.0] * 96, "not increasing"),
    "non-numeric": ([3, 1, 1, 1, 0.0, 1.0, 0.0, 1.0, "abc"] + [0.0] * 95, "non-numeric"),
    "patches apart": (None, "does not meet"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_malformed_114_names_entity_and_de(tmp_path, case):
    params, msg = BAD[case]
    if params is None:  # two patches whose shared edge differs
        _, taylor = _poly()
        params = _params(taylor, [0.0, 0.5, 1.0], [0.0, 1.0])
        params[4 + 3 + 2 + 48 + 48] += 0.1  # AX of patch (1, 0)
    path = tmp_path / "bad.igs"
    write_iges(path, [(110, [0, 0, 0, 1, 0, 0]), (114, params)])
    with pytest.raises(FileFormatError, match=msg) as ei:
        read_iges(path)
    assert "entity 114 at DE 3" in str(ei.value)


def test_114_patches_meeting_within_the_resolution(tmp_path):
    """Real files round the coefficients, so neighbouring patches meet only within the
    file's resolution (pythonocc-demos' surf114.igs: 7.9e-7 at resolution 1e-4): read,
    the first patch's boundary kept and the gap stated as the face's approx_error;
    beyond the resolution it stays an error."""
    F, taylor = _poly()
    params = _params(taylor, [0.0, 0.5, 1.0], [0.0, 1.0])
    params[4 + 3 + 2 + 48 + 48] += 3e-6  # AX of patch (1, 0): its corners move 3e-6 in x
    path = tmp_path / "near.igs"
    write_iges(path, [(114, params)], resolution=1e-5)
    (s,) = read_iges(path).surfaces
    assert s.approx_error == pytest.approx(3e-6, rel=1e-6)
    uv = np.random.default_rng(4).random((100, 2)) * [1.0, 1.0]
    assert np.abs(evaluate(s, uv) - F(uv[:, 0], uv[:, 1])).max() <= 3e-6 * (1 + 1e-9)
    write_iges(path, [(114, params)], resolution=1e-6)
    with pytest.raises(FileFormatError, match="does not meet"):
        read_iges(path)
