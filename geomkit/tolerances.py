"""Named tolerances, documented in one place.

All tolerances are *relative* to a stated scale unless the name says otherwise; the
functions that use them convert them to absolute values once and pass scalars to the
kernels.

KNOT_TOL
    Two knots closer than ``KNOT_TOL * (knot span of the whole vector)`` are treated as
    equal when counting multiplicities and when checking that a parameter lies in the
    domain.
DOMAIN_TOL
    A parameter value outside the domain by at most ``DOMAIN_TOL * domain width`` is
    clamped onto the domain; further out it is an error.
TRIM_TOL
    Width of the boundary band of a trim loop, relative to the larger side of the
    parameter domain.  A UV point whose distance to a trim curve is proven to be at
    most ``TRIM_TOL * domain size`` is classified ``ON_BOUNDARY``; every other point
    gets the exact inside/outside answer (winding number against the exact curves).
CLOSURE_TOL
    A trim loop is closed when its end point is within ``CLOSURE_TOL * domain size`` of
    its start point, and consecutive pieces of a loop join within the same distance.
"""

KNOT_TOL = 1e-12
DOMAIN_TOL = 1e-10
TRIM_TOL = 1e-9
CLOSURE_TOL = 1e-7
