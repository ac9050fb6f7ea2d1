"""The result type of :func:`geomkit.fitting.fit`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

_GEOMETRY = {
    "plane": ("point", "normal"),
    "line": ("point", "direction"),
    "circle": ("center", "normal", "radius"),
    "sphere": ("center", "radius"),
    "cylinder": ("point", "axis", "radius"),
    "cone": ("apex", "axis", "half_angle"),
}


@dataclass(frozen=True)
class FitResult:
    """A fitted feature.

    Attributes
    ----------
    kind, method : str
        As requested.
    form_error : float
        Width of the zone holding every point, normal to the feature: max - min
        residual (lsq, mincircumscribed, maxinscribed), the optimal zone width
        (minzone); for a line the diameter of the cylinder about the fitted line
        holding every point.
    residuals : (n,) float
        Signed orthogonal distance of each point (outward positive for circle,
        sphere, cylinder, cone; along ``normal`` for a plane; unsigned for a line).
    contacts : (k,) int
        Points that decide the solution (minzone / mincircumscribed /
        maxinscribed), or the points of largest and smallest residual (lsq).
    optimality : dict
        How well the optimality conditions hold (see the guide).
    point, normal, direction, center, axis, apex : (3,) float or None
        Geometry of the kind (directions unit length, see the guide for signs).
    radius, half_angle : float or None
        Radius (length) or cone half-angle (radians).
    """

    kind: str
    method: str
    form_error: float
    residuals: np.ndarray = field(repr=False)
    contacts: np.ndarray
    optimality: dict
    point: np.ndarray | None = None
    normal: np.ndarray | None = None
    direction: np.ndarray | None = None
    center: np.ndarray | None = None
    axis: np.ndarray | None = None
    radius: float | None = None
    apex: np.ndarray | None = None
    half_angle: float | None = None

    @property
    def geometry(self) -> dict:
        """The geometry fields of this kind, by name."""
        return {k: getattr(self, k) for k in _GEOMETRY[self.kind]}

    def to_dict(self, residuals: bool = True) -> dict:
        """JSON-safe dict (lists and floats); ``residuals=False`` leaves them out."""
        def conv(x):
            if isinstance(x, np.ndarray):
                return x.tolist()
            if isinstance(x, (np.floating, np.integer, np.bool_)):
                return x.item()
            if isinstance(x, dict):
                return {k: conv(v) for k, v in x.items()}
            if isinstance(x, (list, tuple)):
                return [conv(v) for v in x]
            return x

        out = {"kind": self.kind, "method": self.method,
               "form_error": float(self.form_error),
               "contacts": conv(self.contacts), "optimality": conv(self.optimality)}
        out.update({k: conv(v) for k, v in self.geometry.items()})
        if residuals:
            out["residuals"] = conv(self.residuals)
        return out
