"""Small vector helpers on 3x1 SymPy matrices."""

import sympy as sp


def dot(a: sp.Matrix, b: sp.Matrix):
    """Scalar product of two (3, 1) matrices (units multiply)."""
    return (a.T * b)[0, 0]


def cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    """Vector product ``a x b`` of two (3, 1) matrices in the same frame; shape (3, 1)."""
    return a.cross(b)


def norm(a: sp.Matrix):
    """Euclidean length ``sqrt(a . a)`` of a (3, 1) matrix (the unit of a)."""
    return sp.sqrt(dot(a, a))
