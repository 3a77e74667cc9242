"""The hexapod's description (geometry, inertia, legs, friction, optional effects, limits) and
the catalog of optional effects."""

from gsfric.platform.description import Body, Friction, Geometry, Legs, Platform

__all__ = ["Body", "Friction", "Geometry", "Legs", "Platform"]
