"""Candidates of a trimmed face settled by a foot OUTSIDE the face (no Newton run).

Let x be the point, f(u, v) = |S(u, v) - x|^2 / 2 on surface S over its domain box
D, F the trimmed face (a subset of D) and z a point of the (u, v) plane — in practice
a Newton foot of x on S that was classified OUTSIDE F, or its image one period away
on a surface closed in that direction.  For a candidate triangle whose piece of F
lies in the parameter box B (``tbox``: the parameter triangle grown by its trim
sliver, :func:`geomkit.projection_trim.cert_boxes`), suppose

    grad f(y) . (y - z) > 0        for every y in B.                       (*)

Then no point y of the piece that is not on a trim curve of F is a local minimum of
the distance over F: the direction from y towards z stays in D for a short way (D is
a box and z lies in it; an image z outside D in u is only used for boxes strictly
inside D in u, and so for v) and in F (y is not on a trim curve), and f decreases
along it.  The nearest
point of the piece is therefore on a trim curve of F, which the trim stage searches
for this point anyway (it runs for every surface with an OUTSIDE foot: z).  That is
the same hand-over as when the candidate's own Newton run ends OUTSIDE, so the run is
not needed: the candidate is *settled*.

The same conclusion without a centre (**): when f is strictly monotone in u over B
(say increasing), every y of B with u > umin descends towards smaller u; the points
of B on the edge u = umin (if B reaches it) need a descent direction along the edge:
f monotone in v there (away from the corner it descends to), or the 1-D (*) about an
OUTSIDE foot on that edge.  Likewise in v.  This settles the pieces near an OUTSIDE
foot stopped on a domain edge (its face's unconstrained minimum beyond the edge),
where (*) about the foot fails.

(*) and (**) are proven, not sampled: with c the box centre, (hu, hv) its half widths,
r = S(c) - x and g = grad f(c) = (r.S_u, r.S_v) at c, and true bounds over B
(sub-span bounds of :mod:`geomkit.projection_cert`) ``|S_u| <= Mu``, ``|S_v| <= Mv``,
``|S_uu| <= Muu``, ``|S_uv| <= Muv``, ``|S_vv| <= Mvv``:

* ``|S(y) - x| <= R = |r| + Mu hu + Mv hv`` over B;
* the Hessian of f, ``S_u.S_u + (S - x).S_uu`` etc., is bounded entrywise by
  ``Huu = Mu^2 + R Muu``, ``Huv = Mu Mv + R Muv``, ``Hvv = Mv^2 + R Mvv``, so by the
  mean value theorem (B lies in one C0 piece: no crease in the closed box)
  ``grad f(y)`` lies in the interval box ``g +- (Huu hu + Huv hv, Huv hu + Hvv hv)``;
* ``y - z`` lies in ``[ua - zu, ub - zu] x [va - zv, vb - zv]``;

and the interval product of the two, summed over u and v, must exceed a relative
margin of :data:`MARGIN` of its magnitude (the evaluation's rounding).  A box that
holds z never passes.  Geometrically: the box is small against its distance from z
(in the metric of f's Hessian), as for the triangles along a trim curve when the
face's unconstrained minimum lies well beyond it (pyiges' impeller, box points).
"""

from __future__ import annotations

import math

from .numba_ext.policy import jit, jit_inline
from .project_cert import box_bounds
from .project_bilinear import derivs2
from .trim import OUTSIDE

FOOT_OK = 0
"""Newton status of a converged foot (:data:`geomkit._kernels.project.FOOT_OK`)."""

MARGIN = 1e-9
"""Relative margin of the inequality (*) (rounding of the centre's evaluation)."""


@jit
def _iv_mul_lo(a0, a1, b0, b1):
    """Lower end of the product of the intervals [a0, a1] and [b0, b1]."""
    return min(min(a0 * b0, a0 * b1), min(a1 * b0, a1 * b1))


@jit_inline
def _box_gradient(Pw, p, q, U, V, cbrk, bnd, bo, brk_u, brk_v, x, ua, ub, va, vb, scr,
                  SKL):
    """``(ok, gu, gv, eu, ev)``: over the box [ua, ub] x [va, vb], grad f lies in
    ``(gu +- eu, gv +- ev)`` (module docstring); ok is False for a NaN box or a box
    meeting a crease.  ``bo`` is the surface's row of ``bnd_off``, ``brk_u`` /
    ``brk_v`` its C0 piece borders (domain ends included); ``SKL`` is overwritten
    (the derivatives at the box centre)."""
    if not (ua <= ub and va <= vb):  # NaN box: the piece is not bounded by it
        return False, 0.0, 0.0, 0.0, 0.0
    ok, Mu, Mv, Muu, Muv, Mvv = box_bounds(cbrk, bnd, bo, brk_u, brk_v, ua, ub, va, vb)
    if not ok:  # a crease in the box
        return False, 0.0, 0.0, 0.0, 0.0
    cu = 0.5 * (ua + ub)
    cv = 0.5 * (va + vb)
    hu = max(ub - cu, cu - ua)
    hv = max(vb - cv, cv - va)
    derivs2(Pw, p, q, U, V, cu, cv, scr, SKL)
    r0 = SKL[0, 0, 0] - x[0]
    r1 = SKL[0, 0, 1] - x[1]
    r2 = SKL[0, 0, 2] - x[2]
    gu = r0 * SKL[1, 0, 0] + r1 * SKL[1, 0, 1] + r2 * SKL[1, 0, 2]
    gv = r0 * SKL[0, 1, 0] + r1 * SKL[0, 1, 1] + r2 * SKL[0, 1, 2]
    R = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2) + Mu * hu + Mv * hv
    Huu = Mu * Mu + R * Muu
    Huv = Mu * Mv + R * Muv
    Hvv = Mv * Mv + R * Mvv
    # + the rounding of g at the centre (S, x and the derivatives to ~1e-15 of their
    # magnitudes), generously
    sc = R + abs(SKL[0, 0, 0]) + abs(SKL[0, 0, 1]) + abs(SKL[0, 0, 2]) + abs(x[0]) \
        + abs(x[1]) + abs(x[2])
    eu = Huu * hu + Huv * hv + 1e-12 * sc * Mu
    ev = Huv * hu + Hvv * hv + 1e-12 * sc * Mv
    ok = math.isfinite(gu) and math.isfinite(gv) and math.isfinite(eu) \
        and math.isfinite(ev)
    return ok, gu, gv, eu, ev


@jit
def _radial(gu, gv, eu, ev, ua, ub, va, vb, zu, zv):
    """(*) on the box for the centre (zu, zv), grad f in (gu +- eu, gv +- ev)."""
    if ua <= zu <= ub and va <= zv <= vb:
        return False  # (*) fails at y = z
    wu0 = ua - zu
    wu1 = ub - zu
    wv0 = va - zv
    wv1 = vb - zv
    lo = _iv_mul_lo(gu - eu, gu + eu, wu0, wu1) + _iv_mul_lo(gv - ev, gv + ev, wv0, wv1)
    mag = (abs(gu) + eu) * max(abs(wu0), abs(wu1)) + (abs(gv) + ev) * max(abs(wv0),
                                                                           abs(wv1))
    return lo > MARGIN * mag


@jit
def outside_settles(Pw, p, q, U, V, cbrk, bnd, bo, brk_u, brk_v, x, zu, zv, ua, ub, va,
                    vb, scr, SKL):
    """True when (*) of the module docstring holds on the box [ua, ub] x [va, vb] for
    the centre (zu, zv) (arguments as :func:`_box_gradient`)."""
    ok, gu, gv, eu, ev = _box_gradient(Pw, p, q, U, V, cbrk, bnd, bo, brk_u, brk_v, x,
                                       ua, ub, va, vb, scr, SKL)
    return ok and _radial(gu, gv, eu, ev, ua, ub, va, vb, zu, zv)


@jit_inline
def settled_outside(i, nf, s, out_s, out_uv, out_st, out_cls, Pw_all, U_all, V_all,
                    meta, dom, closed, brk_all, brk_off, cbrk, bnd, bnd_off, tb, x, scr,
                    SKL):
    """A candidate of trimmed surface ``s`` with piece box ``tb`` is settled by a
    converged foot of the point on ``s`` classified OUTSIDE its face, or by its image
    one period away on a closed surface (for a box strictly inside the domain in that
    direction): (*) of the module docstring, one evaluation at the box centre."""
    ua = tb[0]
    ub = tb[1]
    va = tb[2]
    vb = tb[3]
    have = False
    gu = gv = eu = ev = 0.0
    pu = dom[s, 1] - dom[s, 0]
    pv = dom[s, 3] - dom[s, 2]
    wrap_u = closed[s, 0] != 0 and ua > dom[s, 0] and ub < dom[s, 1]
    wrap_v = closed[s, 1] != 0 and va > dom[s, 2] and vb < dom[s, 3]
    for j in range(nf):
        if out_s[i, j] != s or out_cls[i, j] != OUTSIDE or out_st[i, j] != FOOT_OK:
            continue
        if not have:
            o, nu, nv, p, q, uo, vo = (meta[s, 0], meta[s, 1], meta[s, 2], meta[s, 3],
                                       meta[s, 4], meta[s, 5], meta[s, 6])
            Pw = Pw_all[o:o + nu * nv].reshape((nu, nv, 4))
            U = U_all[uo:uo + nu + p + 1]
            Vk = V_all[vo:vo + nv + q + 1]
            bu = brk_all[brk_off[s, 0]:brk_off[s, 0] + brk_off[s, 1]]
            bv = brk_all[brk_off[s, 2]:brk_off[s, 2] + brk_off[s, 3]]
            ok, gu, gv, eu, ev = _box_gradient(Pw, p, q, U, Vk, cbrk, bnd, bnd_off[s], bu,
                                               bv, x, ua, ub, va, vb, scr, SKL)
            if not ok:
                return False
            have = True
        zu = out_uv[i, j, 0]
        zv = out_uv[i, j, 1]
        if _radial(gu, gv, eu, ev, ua, ub, va, vb, zu, zv):
            return True
        if wrap_u and (_radial(gu, gv, eu, ev, ua, ub, va, vb, zu + pu, zv)
                       or _radial(gu, gv, eu, ev, ua, ub, va, vb, zu - pu, zv)):
            return True
        if wrap_v and (_radial(gu, gv, eu, ev, ua, ub, va, vb, zu, zv + pv)
                       or _radial(gu, gv, eu, ev, ua, ub, va, vb, zu, zv - pv)):
            return True
    if not have:
        return False
    # (**): f monotone in u over the box (or in v)
    return _monotone(gu, gv, eu, ev, ua, ub, va, vb, dom[s, 0], dom[s, 1], dom[s, 2],
                     dom[s, 3], i, nf, s, out_s, out_uv, out_st, out_cls, 0) \
        or _monotone(gv, gu, ev, eu, va, vb, ua, ub, dom[s, 2], dom[s, 3], dom[s, 0],
                     dom[s, 1], i, nf, s, out_s, out_uv, out_st, out_cls, 1)


@jit
def _edge_ok(ga, ea, la, lb, lo, hi, i, nf, s, out_s, out_uv, out_st, out_cls, k, e):
    """Every point of the box's part on the domain edge (parameter ``1 - k`` at ``e``)
    has a descent direction along the edge: f's slope along it (``ga +- ea``) keeps
    one sign away from the domain corner it points to ([la, lb] the box's range
    along the edge, [lo, hi] the domain's), or points away from an OUTSIDE foot on
    that edge (1-D (*))."""
    if ga - ea > 0.0 and la > lo:
        return True
    if ga + ea < 0.0 and lb < hi:
        return True
    for j in range(nf):
        if out_s[i, j] != s or out_cls[i, j] != OUTSIDE or out_st[i, j] != FOOT_OK:
            continue
        if out_uv[i, j, 1 - k] != e:
            continue
        z = out_uv[i, j, k]
        if la <= z <= lb:
            continue
        w0 = la - z
        w1 = lb - z
        lo_ = _iv_mul_lo(ga - ea, ga + ea, w0, w1)
        if lo_ > MARGIN * (abs(ga) + ea) * max(abs(w0), abs(w1)):
            return True
    return False


@jit
def _monotone(ga, gb, ea, eb, a0, a1, b0, b1, lo, hi, blo, bhi, i, nf, s, out_s, out_uv,
              out_st, out_cls, k):
    """(**) of the module docstring along parameter ``k`` (0: u, 1: v; ``ga +- ea``
    its slope over the box [a0, a1] x [b0, b1], the domain [lo, hi] x [blo, bhi] in
    the same order)."""
    if ga - ea > 0.0:  # descent towards lo
        if a0 > lo:
            return True
        return _edge_ok(gb, eb, b0, b1, blo, bhi, i, nf, s, out_s, out_uv, out_st,
                        out_cls, 1 - k, lo)
    if ga + ea < 0.0:  # descent towards hi
        if a1 < hi:
            return True
        return _edge_ok(gb, eb, b0, b1, blo, bhi, i, nf, s, out_s, out_uv, out_st,
                        out_cls, 1 - k, hi)
    return False
