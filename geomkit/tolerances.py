"""Named tolerances, documented in one place.

All tolerances are *relative* to a stated scale unless the name says otherwise; the
functions that use them convert them to absolute values once and pass scalars to the
kernels.  The kernels' own numerical constants (compiled into them: they cannot read
this module) are listed at the end under the names they have here.

NURBS model
-----------
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
DEGENERATE_NORMAL
    ``|Su x Sv| <= DEGENERATE_NORMAL * max(|Su|, |Sv|)**2`` marks a degenerate point
    (a pole), where the normal is the limit from inside the domain.

Meshes
------
WELD_REL
    Domain-boundary vertices closer than ``WELD_REL * surface.size`` in 3-D are merged.
AFFINE_REL
    A control net is affine when its residual from the best affine image of the
    Greville abscissae is at most ``AFFINE_REL * size`` (rounding of the stored
    coordinates).

Queries
-------
DEFAULT_MESH_TOL
    Default chord tolerance of the projector's candidate mesh, relative to the largest
    surface size.
NEWTON_STEP_TOL
    Point projection: Newton stops when the 3-D step is below this times the model size.
TIE_TOL
    Feet whose distances differ by less than this times max(model size, distance) are a
    tie (one point on an edge shared by two faces), resolved to the lowest surface index.
CERT_ROUNDING
    Absolute rounding allowance of the subdivided nets of the projection certificate,
    relative to their magnitude.
HULL_ROUNDING
    Surface distance: floating-point allowance (relative to the scene size) subtracted
    from the hull lower bound; de Casteljau subdivision and the slab projections are
    exact up to a few ulps of the coordinates.
EDGE_ROOT_TOL
    Plane sections: bracket width of a root on a mesh edge, in the edge parameter
    ``t`` in [0, 1] (absolute).

Collision and motion
--------------------
POSE_TOL
    Largest deviation of a pose's rotation from orthonormal (entries of R^T R - I),
    absolute.
SCREW_REL
    Clearance along a probe path: a segment whose motion has both a rotation and a
    translation along the rotation axis larger than this (relative to the pose scale)
    is a screw motion, refused.

Jobs
----
ALIGN_STEP_TOL
    Alignment stops when the largest point displacement of a step is below this times
    the model size.
ALIGN_RCOND
    Rigid motions whose least-squares sensitivity is below this fraction of the largest
    (rotation measured in model-size units) are left free: the surface does not fix them.
PERCENTILE_REL_ERROR
    Relative value error of the streamed deviation percentiles.

CAD import
----------
GAP_TOL
    Largest gap between the pieces of a trim loop that is bridged, relative to the
    parameter domain size.
TRIM_CLIP_TOL
    IGES: trim control points this close outside the domain (relative to its size) are
    moved onto it.
PCURVE_CLIP_TOL
    STEP: pcurve control points this close outside the face's domain (relative to its
    size) are moved onto it; the move counts as a bridged gap.
PCURVE_TOL
    UV error (relative to the domain size) allowed where a pcurve is re-fitted through a
    reparametrisation of its surface.
SAME_POINT_TOL
    Two UV points whose model points are this close (x the surface size) are one point:
    a gap between them (a pole) is bridged whatever its size in UV.
EDGE_TOL
    Default fit tolerance of an edge projected onto its surface (faces without
    pcurves), relative to the surface size.
ISO_TOL
    An edge whose local coordinate varies by at most this x the face size is an
    iso-line (files write transformation matrices and points to ~9 digits).
ON_CONIC_TOL
    Conic end points may lie this far (x the conic's size) off the conic (files write
    ~9 digits); they are moved onto it along the canonical parameter.
JOIN_TOL
    Neighbouring patches of a parametric spline surface (IGES 114) must meet within
    this x the surface size, or within the file's resolution when that is larger.
RULED_ARC_TOL
    A ruled surface of form 0 (rulings at equal relative arc length) is read as form 1
    (equal relative parameter) when neither curve's relative arc length strays from its
    relative parameter by more than this x the model size, or the file's resolution
    when that is larger.
OFFSET_TOL
    Default approximation error of an offset surface, relative to its base's size.

Kernel constants (compiled into the kernels; named here, defined there)
-----------------------------------------------------------------------
DEGENERATE_TRIANGLE
    Contact of a zero-area (collinear or coincident corners) triangle: its edges touch
    when their distance is at most this x the scale
    (:data:`geomkit._kernels.triangles.DEGENERATE_REL`).
DEGENERATE_TRIANGLE_SIN2
    Tessellation measure: a triangle with ``|ab x ac|^2 <= DEGENERATE_TRIANGLE_SIN2
    |ab|^2 |ac|^2`` (sine of its angle below 1e-12) is handled as its three edges
    (:data:`geomkit._kernels.triangles.DEGENERATE_REL2`).
BOX_INFLATE
    Relative growth of every fitted box / k-DOP, absorbing rounding of the fit
    (:data:`geomkit._kernels.bvh.BOX_INFLATE`).
SAT_EPS, PLANE_SLACK
    Slack of the separating-axis box tests and of the triangle plane bounds
    (:mod:`geomkit._kernels.bvh_query`).
CERT_MARGIN, LOSS_TOL
    Projection certificate: relative margin of its inequality, and how much nearer than
    the foot (x the Newton step tolerance) a settled candidate may hold a point
    (:mod:`geomkit._kernels.project_cert`).
"""

from geomkit._kernels.bvh import BOX_INFLATE
from geomkit._kernels.bvh_query import PLANE_SLACK, SAT_EPS
from geomkit._kernels.project_cert import CERT_MARGIN, LOSS_TOL
from geomkit._kernels.triangles import DEGENERATE_REL2 as DEGENERATE_TRIANGLE_SIN2
from geomkit._kernels.triangles import DEGENERATE_REL as DEGENERATE_TRIANGLE

# NURBS model
KNOT_TOL = 1e-12
DOMAIN_TOL = 1e-10
TRIM_TOL = 1e-9
CLOSURE_TOL = 1e-7
DEGENERATE_NORMAL = 1e-12

# meshes
WELD_REL = 1e-10
AFFINE_REL = 1e-14

# queries
DEFAULT_MESH_TOL = 2e-3
NEWTON_STEP_TOL = 1e-12
TIE_TOL = 1e-12
CERT_ROUNDING = 1e-13
HULL_ROUNDING = 1e-14
EDGE_ROOT_TOL = 1e-15

# collision and motion
POSE_TOL = 1e-9
SCREW_REL = 1e-9

# jobs
ALIGN_STEP_TOL = 1e-12
ALIGN_RCOND = 1e-8
PERCENTILE_REL_ERROR = 1e-4

# CAD import
GAP_TOL = 1e-2
TRIM_CLIP_TOL = 1e-7
PCURVE_CLIP_TOL = 1e-4
PCURVE_TOL = 1e-10
SAME_POINT_TOL = 1e-9
EDGE_TOL = 1e-6
ISO_TOL = 1e-7
ON_CONIC_TOL = 1e-6
JOIN_TOL = 1e-7
RULED_ARC_TOL = 1e-9
OFFSET_TOL = 1e-6

__all__ = [name for name in dir() if name.isupper()]
