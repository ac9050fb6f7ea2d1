"""Feature models: signed orthogonal residuals, their Jacobians in local parameters
and the update rule, shared by the least-squares and the Chebyshev solvers.

Every model is immutable and lives in the coordinates of the centred points.  Its
Jacobian is taken at the local origin of a well-conditioned parametrisation (Forbes,
NPL report DITC 140/89): an axis is moved by two angles (alpha, beta) about its
current direction and two shifts (s, t) of its point normal to it; after each step
the axis point is moved back to the foot of the centroid (the origin).  ``ptype``
names each local parameter's unit ("L" length, "A" angle); ``size`` is the index of
the size parameter (radius, offset) or None.
"""

from __future__ import annotations

import numpy as np

from geomkit.fitting._geom import canonical, frame

_TINY = 1e-300


def _rotate(a, u, v, alpha, beta):
    w = a + alpha * u + beta * v
    return w / np.linalg.norm(w)


class Plane:
    """Plane ``{x : n.x = d}``; local (alpha, beta, d)."""

    ptype = ("A", "A", "L")
    size = 2

    def __init__(self, n, d):
        self.n, self.d = np.asarray(n, float), float(d)
        self.u, self.v = frame(self.n)

    def residuals(self, X):
        return X @ self.n - self.d

    def jacobian(self, X):
        return np.column_stack([X @ self.u, X @ self.v, -np.ones(X.shape[0])])

    def step(self, p):
        return Plane(_rotate(self.n, self.u, self.v, p[0], p[1]), self.d + p[2])

    def geometry(self, c0):
        n = canonical(self.n)
        d = self.d if n @ self.n > 0 else -self.d
        return {"point": c0 + d * n, "normal": n}, (1.0 if n @ self.n > 0 else -1.0)


class Ball:
    """Circle (d = 2) or sphere (d = 3): centre c, radius r; local (dc..., r)."""

    size = -1

    def __init__(self, c, r):
        self.c, self.r = np.asarray(c, float), float(r)
        self.ptype = ("L",) * (self.c.shape[0] + 1)
        self.size = self.c.shape[0]

    def radial(self, X):
        D = X - self.c
        return np.sqrt(np.einsum("ij,ij->i", D, D))

    def residuals(self, X):
        return self.radial(X) - self.r

    def jacobian(self, X):
        D = X - self.c
        rho = np.maximum(np.sqrt(np.einsum("ij,ij->i", D, D)), _TINY)
        return np.column_stack([-D / rho[:, None], -np.ones(X.shape[0])])

    def step(self, p):
        return Ball(self.c + p[:-1], self.r + p[-1])


class Cylinder:
    """Axis direction a, axis point x0 (x0.a = 0), radius r; local (s, t, alpha,
    beta, r)."""

    ptype = ("L", "L", "A", "A", "L")
    size = 4

    def __init__(self, a, x0, r):
        a = np.asarray(a, float)
        self.a = a / np.linalg.norm(a)
        x0 = np.asarray(x0, float)
        self.x0 = x0 - (x0 @ self.a) * self.a
        self.r = float(r)
        self.u, self.v = frame(self.a)

    def _local(self, X):
        Q = X - self.x0
        return Q @ self.u, Q @ self.v, Q @ self.a

    def radial(self, X):
        qu, qv, _ = self._local(X)
        return np.hypot(qu, qv)

    def residuals(self, X):
        return self.radial(X) - self.r

    def jacobian(self, X):
        qu, qv, qa = self._local(X)
        rho = np.maximum(np.hypot(qu, qv), _TINY)
        cu, cv = qu / rho, qv / rho
        return np.column_stack([-cu, -cv, -qa * cu, -qa * cv, -np.ones_like(qu)])

    def step(self, p):
        return Cylinder(_rotate(self.a, self.u, self.v, p[2], p[3]),
                        self.x0 + p[0] * self.u + p[1] * self.v, self.r + p[4])


class Cone:
    """Axis direction a, axis point x0 (x0.a = 0), radius r0 of the section through
    x0, half-angle phi (signed: the radius grows along +a when phi > 0); local (s, t,
    alpha, beta, r0, phi).  Residual (rho - r0 - h tan phi) cos phi, outward positive,
    exact for points whose foot is on the nappe."""

    ptype = ("L", "L", "A", "A", "L", "A")
    size = 4

    def __init__(self, a, x0, r0, phi):
        a = np.asarray(a, float)
        self.a = a / np.linalg.norm(a)
        x0 = np.asarray(x0, float)
        shift = -(x0 @ self.a)
        self.x0 = x0 + shift * self.a
        self.phi = float(phi)
        self.r0 = float(r0) + shift * np.tan(self.phi)
        self.u, self.v = frame(self.a)

    def _local(self, X):
        Q = X - self.x0
        return Q @ self.u, Q @ self.v, Q @ self.a

    def residuals(self, X):
        qu, qv, qa = self._local(X)
        cp, sp = np.cos(self.phi), np.sin(self.phi)
        return (np.hypot(qu, qv) - self.r0) * cp - qa * sp

    def jacobian(self, X):
        qu, qv, qa = self._local(X)
        rho = np.maximum(np.hypot(qu, qv), _TINY)
        cp, sp = np.cos(self.phi), np.sin(self.phi)
        cu, cv = qu / rho, qv / rho
        g = cp * qa + sp * rho
        return np.column_stack([-cp * cu, -cp * cv, -cu * g, -cv * g,
                                -cp * np.ones_like(qu), -(rho - self.r0) * sp - qa * cp])

    def step(self, p):
        return Cone(_rotate(self.a, self.u, self.v, p[2], p[3]),
                    self.x0 + p[0] * self.u + p[1] * self.v, self.r0 + p[4],
                    self.phi + p[5])

    def oriented(self):
        """The same cone with phi >= 0 (axis from the apex to the opening)."""
        if self.phi >= 0:
            return self
        return Cone(-self.a, self.x0, self.r0, -self.phi)

    def geometry(self, c0):
        m = self.oriented()
        apex = c0 + m.x0 - (m.r0 / np.tan(m.phi)) * m.a if m.phi > 0 else \
            np.full(3, np.nan)
        return {"apex": apex, "axis": m.a.copy(), "half_angle": m.phi}


def cylinder_geometry(m, c0):
    """Cylinder geometry dict: axis point nearest the centroid, canonical axis."""
    return {"point": c0 + m.x0, "axis": canonical(m.a), "radius": m.r}


def param_scale(model, L):
    """Scale of each local parameter: ``L`` for lengths, 1 for angles."""
    return np.array([L if t == "L" else 1.0 for t in model.ptype])
