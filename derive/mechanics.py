"""Small value types of rigid-body mechanics: a wrench, an inertia, a body's motion.

They carry what the equations would otherwise carry by hand: the point a moment is taken about,
the frame an inertia is written in, and the sign of a reaction (``Wrench.reaction``: the force
and moment a body puts back on the one acting on it, at the same point, as in
``sympy.physics.mechanics``' ``apply_force(force, point, reaction_point)``).

All vectors are SymPy 3x1 matrices in the base frame (SI units) unless said otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .chain import inline
from .vectors import cross


@dataclass(frozen=True)
class Wrench:
    """A force and a moment about a point.

    Attributes
    ----------
    force : sympy.Matrix, shape (3, 1)
        Resultant force, base frame, N.
    moment : sympy.Matrix, shape (3, 1)
        Resultant moment about ``point``, base frame, N m.
    point : sympy.Matrix, shape (3, 1)
        The point the moment is taken about, base frame, m.
    """

    force: sp.Matrix
    moment: sp.Matrix
    point: sp.Matrix

    def about(self, point) -> "Wrench":
        """The same wrench with its moment about ``point``: ``M_q = M + (point_self - q) x F``.

        Parameters
        ----------
        point : sympy.Matrix, shape (3, 1)
            New reference point, base frame, m.

        Returns
        -------
        Wrench
        """
        return Wrench(self.force, self.moment + cross(self.point - point, self.force), point)

    def reaction(self) -> "Wrench":
        """Newton's third law: what the acted-on body puts back, ``(-F, -M)`` at the same point."""
        return Wrench(-self.force, -self.moment, self.point)

    def __add__(self, other: "Wrench") -> "Wrench":
        """Sum of two wrenches, the moment about this wrench's point."""
        other = other if other.point == self.point else other.about(self.point)
        return Wrench(self.force + other.force, self.moment + other.moment, self.point)

    def __sub__(self, other: "Wrench") -> "Wrench":
        return self + other.reaction()


@dataclass(frozen=True)
class Inertia:
    """A rotational inertia: its matrix, the frame it is written in and the point it is about.

    Attributes
    ----------
    matrix : sympy.Matrix, shape (3, 3)
        Inertia about ``point`` in the body's axes, kg m^2.
    frame : sympy.Matrix, shape (3, 3)
        Rotation body axes -> base axes (its columns are the body axes in the base frame), 1.
    point : sympy.Matrix, shape (3, 1)
        The point it is about (the centre of mass), base frame, m.
    """

    matrix: sp.Matrix
    frame: sp.Matrix
    point: sp.Matrix

    def in_base(self) -> sp.Matrix:
        """``J = R I R^T``: the same inertia in base axes, shape (3, 3), kg m^2."""
        return self.frame * self.matrix * self.frame.T

    def body_rates(self, alpha, omega, let=inline, name="rates"):
        """``a_b = R^T alpha`` and ``w_b = R^T omega``: the body's rates in its own axes.

        Parameters
        ----------
        alpha, omega : sympy.Matrix, shape (3, 1)
            Angular acceleration (rad/s^2) and velocity (rad/s), base frame.
        let : callable
            The chain's ``let``; defines ``<name>_alpha`` and ``<name>_omega``.

        Returns
        -------
        tuple of sympy.Matrix, shape (3, 1)
            rad/s^2 and rad/s, body axes (``omega`` stays the zero vector when it is one).
        """
        R = self.frame
        a_b = let(f"{name}_alpha", R.T * alpha)
        w_b = omega if omega.is_zero_matrix else let(f"{name}_omega", R.T * omega)
        return a_b, w_b

    def rotation_moment_in_body(self, a_b, w_b) -> sp.Matrix:
        """``I a_b + w_b x I w_b``: the rotation moment in body axes.

        Parameters
        ----------
        a_b, w_b : sympy.Matrix, shape (3, 1)
            Angular acceleration (rad/s^2) and velocity (rad/s), body axes (``body_rates``).

        Returns
        -------
        sympy.Matrix, shape (3, 1)
            Moment about ``point``, body axes, N m.
        """
        body = self.matrix * a_b
        if not w_b.is_zero_matrix:
            body = body + cross(w_b, self.matrix * w_b)
        return body

    def rotation_moment(self, alpha, omega, let=inline, name="M_rot", latex=None, rates=None):
        """``J alpha + omega x J omega`` about ``point``, computed in body axes (J never formed).

        With ``a_b = R^T alpha`` and ``w_b = R^T omega`` (body axes), the moment is
        ``R (I a_b + w_b x I w_b)``.

        Parameters
        ----------
        alpha, omega : sympy.Matrix, shape (3, 1)
            Angular acceleration (rad/s^2) and velocity (rad/s) of the body, base frame.
        let : callable
            The chain's ``let`` (``inline`` keeps the expression).
        name, latex : str
            Name of the moment in the chain.
        rates : tuple, optional
            ``body_rates(alpha, omega)`` when already known (bodies sharing one frame).

        Returns
        -------
        sympy.Matrix, shape (3, 1)
            Moment about ``point``, base frame, N m.
        """
        a_b, w_b = rates if rates is not None else self.body_rates(alpha, omega, let, name)
        return let(name, self.frame * self.rotation_moment_in_body(a_b, w_b), latex)


@dataclass(frozen=True)
class Body:
    """A rigid body in motion: what Newton-Euler needs to give its required wrench.

    Attributes
    ----------
    mass : sympy.Expr
        Inertial mass, kg.
    weight_mass : sympy.Expr
        Mass on which gravity acts (equal to ``mass`` for a real body; the catalog's effects and
        the ``leg_weight`` switch make them differ), kg.
    inertia : Inertia
        Rotational inertia about the centre of mass (``inertia.point``).
    acceleration : sympy.Matrix, shape (3, 1)
        Acceleration of the centre of mass, base frame, m/s^2.
    alpha, omega : sympy.Matrix, shape (3, 1)
        Angular acceleration (rad/s^2) and velocity (rad/s), base frame, as they enter the
        rotation moment (zero omega: no gyroscopic term, as the paper writes).
    """

    mass: sp.Expr
    weight_mass: sp.Expr
    inertia: Inertia
    acceleration: sp.Matrix
    alpha: sp.Matrix
    omega: sp.Matrix

    @property
    def centre(self) -> sp.Matrix:
        """Centre of mass, base frame, m."""
        return self.inertia.point

    def required_force(self, g_vec) -> sp.Matrix:
        """``m a - m_w g``: the resultant external force the body needs, base frame, N.

        Parameters
        ----------
        g_vec : sympy.Matrix, shape (3, 1)
            Gravitational acceleration, base frame, m/s^2.
        """
        return self.mass * self.acceleration - self.weight_mass * g_vec

    def required_wrench(self, g_vec, rotation_moment) -> Wrench:
        """Resultant external wrench the body needs, about its centre of mass.

        ``F = m a - m_w g`` and ``M = J alpha + omega x J omega`` (given as ``rotation_moment``,
        from ``Inertia.rotation_moment``, so that the chain shares it).

        Parameters
        ----------
        g_vec : sympy.Matrix, shape (3, 1)
            Gravitational acceleration, base frame, m/s^2.
        rotation_moment : sympy.Matrix, shape (3, 1)
            ``J alpha + omega x J omega`` about the centre, N m.

        Returns
        -------
        Wrench
            About ``centre``.
        """
        return Wrench(self.required_force(g_vec), rotation_moment, self.centre)
