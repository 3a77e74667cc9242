"""The LaTeX printer of the display: SymPy's, with vectors written as one symbol each."""

from __future__ import annotations

import sympy as sp
from sympy.printing.latex import LatexPrinter


class _Vector(sp.Symbol):
    """A vector (or matrix) expression written as one symbol; its LaTeX is in ``_View.names``."""


class _Scalar(sp.Symbol):
    """A scalar made of vectors (a dot product, a length), written as one symbol."""


class _Printer(LatexPrinter):
    """SymPy's LaTeX printer with the vectors of a product written last (``c_{s} \\omega``)
    and the terms of a sum that carry no minus sign first (``E - C``)."""

    def _as_ordered_terms(self, expr, order=None):
        terms = super()._as_ordered_terms(expr, order=order)
        return ([t for t in terms if not t.could_extract_minus_sign()]
                + [t for t in terms if t.could_extract_minus_sign()])

    def _print_Mul(self, expr):
        vectors = [a for a in expr.args if isinstance(a, _Vector)]
        if not vectors:
            return super()._print_Mul(expr)
        scalar = sp.Mul(*[a for a in expr.args if not isinstance(a, _Vector)])
        text = " ".join(self._print(v) for v in vectors)
        if scalar == 1:
            return text
        if scalar == -1:
            return f"- {text}"
        coefficient = self._print(scalar)
        if scalar.is_Add:
            coefficient = rf"\left({coefficient}\right)"
        return f"{coefficient} {text}"
