"""Plane sections of surfaces: exact points, tracing, export."""

from .plane import *  # noqa: F401,F403
from .plane import __all__  # noqa: F401
