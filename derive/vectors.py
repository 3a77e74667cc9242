"""Small vector helpers on 3x1 SymPy matrices."""

import sympy as sp


def dot(a: sp.Matrix, b: sp.Matrix):
    return (a.T * b)[0, 0]


def cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return a.cross(b)


def norm(a: sp.Matrix):
    return sp.sqrt(dot(a, a))


def columns(*cols: sp.Matrix) -> sp.Matrix:
    return sp.Matrix.hstack(*cols)
