"""The chord refinement kernel gives the points of the rounds of array operations.

:func:`geomkit._kernels.section_refine.refine_chains` replaced a loop that halved all
segments above the tolerance in rounds, one numpy operation per step (kept below as the
oracle, as plane_section ran it).  Every call the section makes is checked against
it: the same number of points on every chain, the same points up to the rounding of
fused multiply-adds (the kernel's ``contract`` flag: a few ulps of the parameters),
the same measured chord deviation up to that rounding."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.sections import mid_plane_sections

import geomkit
from geomkit import samples
from geomkit._kernels import section as K
from geomkit.cad.occ import HAVE_OCP
from geomkit.section import trace
from geomkit.section.trace import _Eval


# ------------------------------------------------------------- oracle: the numpy rounds
class _ArgsEval(_Eval):
    """:class:`_Eval` from the kernel arguments (no surface needed)."""

    def __init__(self, args, box):
        self.args, self.box, self.plane = args, box, args[5]


def _midpoints(ev, leaves, a, b, leaf, zsnap):
    m = 0.5 * (a + b)
    out = m.copy()
    state = leaves[leaf, 4]
    done = np.zeros(len(m), bool)
    sel = np.nonzero((state == K.MONO_U) | (state == K.MONO_V))[0]
    if len(sel):
        c = (state[sel] == K.MONO_V).astype(np.intp)   # MONO_U: along u; MONO_V: v
        rows = np.arange(len(sel))
        lo = m[sel]
        hi = lo.copy()
        lo[rows, c] = leaves[leaf[sel], 2 * c]
        hi[rows, c] = leaves[leaf[sel], 2 * c + 1]
        fl = ev.f(np.concatenate([lo, hi]))
        fl[np.abs(fl) <= zsnap] = 0.0
        flo, fhi = fl[:len(sel)], fl[len(sel):]
        br = flo * fhi < 0
        if np.any(br):
            i = sel[br]
            out[i] = ev.roots(lo[br], hi[br], flo[br], fhi[br])
            done[i] = True
    rest = np.nonzero(~done)[0]
    if len(rest):
        step = np.linalg.norm(b[rest] - a[rest], axis=1)
        out[rest], _ = ev.project(m[rest], step, 0.25 * zsnap)
    return out


def _refine_rounds(ev, leaves, uv, segleaf, tol, zsnap, max_rounds):
    X = ev.points(uv)
    active = np.ones(len(uv) - 1, bool)
    chord = 0.0
    for _ in range(max_rounds):
        idx = np.nonzero(active)[0]
        if not len(idx):
            break
        a, b = uv[idx], uv[idx + 1]
        mid = _midpoints(ev, leaves, a, b, segleaf[idx], zsnap)
        M = ev.points(mid)
        A, B = X[idx], X[idx + 1]
        d = B - A
        ll = np.einsum("ij,ij->i", d, d)
        t = np.clip(np.einsum("ij,ij->i", M - A, d) / np.where(ll > 0, ll, 1.0), 0, 1)
        err = np.linalg.norm(A + t[:, None] * d - M, axis=1)
        tiny = np.linalg.norm(b - a, axis=1) <= 1e-13
        split = (err > 0.5 * tol) & ~tiny
        ok = np.nonzero(~split & ~tiny)[0]
        if len(ok):
            lq = np.tile(segleaf[idx[ok]], 2)
            Q = ev.points(_midpoints(ev, leaves, np.concatenate([a[ok], mid[ok]]),
                                     np.concatenate([mid[ok], b[ok]]), lq, zsnap))
            Ak, dk = np.tile(A[ok], (2, 1)), np.tile(d[ok], (2, 1))
            llk = np.tile(ll[ok], 2)
            tq = np.clip(np.einsum("ij,ij->i", Q - Ak, dk) / np.where(llk > 0, llk, 1.0), 0, 1)
            eq = np.linalg.norm(Ak + tq[:, None] * dk - Q, axis=1)
            err[ok] = np.maximum(err[ok], np.maximum(eq[:len(ok)], eq[len(ok):]))
            split = (err > 0.5 * tol) & ~tiny
        if np.any(~split):
            chord = max(chord, float(err[~split].max()))
        if not np.any(split):
            break
        s_idx = idx[split]
        n = len(uv)
        new_uv = np.insert(uv, s_idx + 1, mid[split], axis=0)
        new_X = np.insert(X, s_idx + 1, M[split], axis=0)
        new_leaf = np.insert(segleaf, s_idx + 1, segleaf[s_idx])
        new_active = np.zeros(n - 1 + len(s_idx), bool)
        pos = s_idx + np.arange(len(s_idx))
        new_active[pos] = True
        new_active[pos + 1] = True
        uv, X, segleaf, active = new_uv, new_X, new_leaf, new_active
    else:
        if np.any(active):
            chord = np.inf
    return uv, chord


# ------------------------------------------------------------- every call checked
def _checked(monkeypatch, calls):
    """Wrap ``trace.refine_chains``: each call compared with the rounds, chain by chain."""
    kernel = trace.refine_chains

    def both(Pw, p, q, U, V, plane, leaves, uv, segleaf, starts, tol, zsnap, ttol, box,
             max_rounds):
        out, ostarts, chord = kernel(Pw, p, q, U, V, plane, leaves, uv, segleaf, starts, tol,
                                     zsnap, ttol, box, max_rounds)
        ev = _ArgsEval((Pw, p, q, U, V, plane), box)
        dom = max(box[1] - box[0], box[3] - box[2])
        for c in range(len(starts) - 1):
            s0, s1 = starts[c], starts[c + 1]
            ref, rchord = _refine_rounds(ev, leaves, uv[s0:s1], segleaf[s0:s1], tol, zsnap,
                                         max_rounds)
            got = out[ostarts[c]:ostarts[c + 1]]
            assert got.shape == ref.shape
            assert np.abs(got - ref).max() <= 1e-12 * dom
            if np.isinf(rchord):
                assert np.isinf(chord[c])
            else:
                assert abs(chord[c] - rchord) <= 1e-9 * tol + 1e-12 * np.abs(plane[3])
            calls.append(len(got))
        return out, ostarts, chord

    monkeypatch.setattr(trace, "refine_chains", both)


CASES = [("sphere", [0.3, -0.5, 0.8, -2.0], 1e-5), ("torus", [1, 0, 0, 0], 1e-6),
         ("torus", [0, 0, 1, -0.25], 1e-7), ("torus", [0, 0, 1, 5], 1e-6),
         ("sphere", [0, 0, 1, -10], 1e-6), ("saddle", [0, 0, 1, 0], 1e-6),
         ("wave_seed003", None, 1e-7), ("crease", [1, 0, 0, -0.5], 1e-6),
         ("plate_with_hole", [1, 0.3, 0, -60], 1e-6), ("sphere_pair", [0, 1, 0, 0], 1e-5),
         ("freeform_1", [0.2, 1, 0.1, -0.5], 1e-6)]


@pytest.mark.parametrize("name, plane, tol", CASES)
def test_refine_kernel_gives_the_rounds_points(monkeypatch, name, plane, tol):
    case = samples.load_case(name)
    surfaces = case.surfaces
    plane = plane if plane is not None else case.truth["section_plane"]
    calls = []
    _checked(monkeypatch, calls)
    sec = geomkit.plane_section(surfaces, plane, tol)
    assert calls and len(sec.curves) + len(sec.points) > 0


def test_refine_kernel_out_of_rounds_reports_inf(monkeypatch):
    """With 3 rounds the sphere's chains are not refined to 1e-9: the points reached
    are kept and the chord deviation is reported as inf, as by the rounds."""
    calls = []
    _checked(monkeypatch, calls)
    monkeypatch.setattr(trace, "MAX_ROUNDS", 3)
    sec = geomkit.plane_section(samples.load("sphere"), [0.3, -0.5, 0.8, -2.0], 1e-9)
    assert calls and sec.max_chord_error == np.inf


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
@pytest.mark.parametrize("part", ["nist_ctc_01_ap242.stp", "nist_ftc_06_ap242.stp",
                                  "sw2018_base_interface_ap203.step"])
def test_refine_kernel_on_real_parts(monkeypatch, part):
    """Mid-planes of real parts (cylinders, cones, B-spline fillets, planes)."""
    calls = []
    _checked(monkeypatch, calls)
    mid_plane_sections(part)
    assert len(calls) > 20
