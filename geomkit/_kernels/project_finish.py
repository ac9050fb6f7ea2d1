"""Foot points and unit normals of the projection's answers in one batch kernel."""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.borrow import borrow_all
from .numba_ext.policy import jit, prun
from .project import PROJECT_CHUNK, _surface
from .project_bilinear import derivs2
from .surface import (D2, POLE_RATIO, _binomial_table, derivs_scratch,
                      surface_normal)


@jit
def _frames_chunk(i0, i1, uv, surf, Pw_all, U_all, V_all, meta, dom, degen_rel, out_p,
                  out_n):
    pmax = np.int64(1)
    qmax = np.int64(1)
    for s in range(meta.shape[0]):
        pmax = max(pmax, meta[s, 3])
        qmax = max(qmax, meta[s, 4])
    _frames_range(i0, i1, uv, surf, Pw_all, U_all, V_all, meta, dom, degen_rel, out_p, out_n,
                  derivs_scratch(pmax, qmax, D2), _binomial_table(D2), np.empty((3, 3, 3)))


@jit
def _frames_range(i0, i1, uv, surf, Pw_all, U_all, V_all, meta, dom, degen_rel, out_p,
                  out_n, scr, bin_, SKL):
    """The loop of :func:`_frames_chunk` over borrowed arrays (:mod:`.numba_ext.borrow`)."""
    uv, surf, Pw_all, U_all, V_all, meta, dom, out_p, out_n, scr, bin_, SKL = borrow_all((
        uv, surf, Pw_all, U_all, V_all, meta, dom, out_p, out_n, scr, bin_, SKL))
    for i in range(i0, i1):
        s = surf[i]
        Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, s)
        u = uv[i, 0]
        v = uv[i, 1]
        derivs2(Pw, p, q, U, V, u, v, scr, SKL)
        for c in range(3):
            out_p[i, c] = SKL[0, 0, c]
        su0, su1, su2 = SKL[1, 0, 0], SKL[1, 0, 1], SKL[1, 0, 2]
        sv0, sv1, sv2 = SKL[0, 1, 0], SKL[0, 1, 1], SKL[0, 1, 2]
        n0 = su1 * sv2 - su2 * sv1
        n1 = su2 * sv0 - su0 * sv2
        n2 = su0 * sv1 - su1 * sv0
        lu = math.sqrt(su0 * su0 + su1 * su1 + su2 * su2)
        lv = math.sqrt(sv0 * sv0 + sv1 * sv1 + sv2 * sv2)
        ln = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        scale = max(lu, lv)
        if ln > degen_rel * scale * scale and ln > 0.0 and min(lu, lv) > POLE_RATIO * scale:
            out_n[i, 0] = n0 / ln
            out_n[i, 1] = n1 / ln
            out_n[i, 2] = n2 / ln
        else:  # at or next to a pole: the limit normal (surface_normal's rules)
            surface_normal(Pw, p, q, U, V, u, v, dom[s, 0], dom[s, 1], dom[s, 2], dom[s, 3],
                           degen_rel, bin_, scr, SKL, out_n[i])


def foot_frames(uv, surf, Pw_all, U_all, V_all, meta, dom, degen_rel, out_p, out_n):
    """Point ``out_p[i]`` and unit normal ``out_n[i]`` of packed surface ``surf[i]``
    (see :mod:`geomkit._kernels.project`) at ``uv[i]`` (inside its domain): one pass
    of the order-2 evaluation (:func:`~geomkit._kernels.surface.surface_derivs2`) per
    point; the normal is ``S_u x S_v / |S_u x S_v|``, or where that is degenerate (a
    pole) the limit normal of :func:`~geomkit._kernels.surface.surface_normal` — the
    same rules as :func:`geomkit.normals`.  Parallel over points."""
    prun(_frames_chunk, uv.shape[0], PROJECT_CHUNK, uv, surf, Pw_all, U_all, V_all, meta,
         dom, degen_rel, out_p, out_n)
