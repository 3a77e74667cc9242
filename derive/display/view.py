"""The chain's definitions written back as equations between vectors (``equations``).

``_View`` names every component of the chain (names.py) and knows which components make up
which vector or matrix (a ``_Family``: an input block or a step of several entries); its vector
and scalar forms recognise, in the component expressions, the operations the derivation is
made of.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp

from ..effects import parameter_names
from ..model import Model
from .names import (AXES, EFFECT_NAMES, INPUT_LATEX, RAW_NAMES, Name, _effect_name, _name,
                    _unsuffix)
from .printer import _Printer, _Scalar, _Vector

GROUPS = ("1", "kinematics", "2-7", "8-10", "11-17", "17", "28-32", "33-35", "coupled",
          "conditioning")
"""The chain's equation groups (``Step.equation``), in the order of the paper."""


@dataclass
class _Family:
    """The components of one vector, 6-column or matrix: ``symbols`` in order (row-major)."""

    kind: str                      # "vector" (3 or 6 entries) or "matrix" (3x3)
    symbols: tuple[sp.Symbol, ...]
    placeholder: sp.Symbol


class _View:
    """A model's chain with names for every symbol and its definitions in vector form."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.names: dict[sp.Symbol, str] = {}
        self.families: list[_Family] = []
        self.of_component: dict[sp.Symbol, tuple[_Family, object]] = {}
        self.by_components: dict[tuple, _Family] = {}
        self.step_family: dict[int, _Family] = {}
        self.step_leg: dict[int, int | None] = {}
        self.step_name: dict[int, Name] = {}
        self.spin_substitution: dict[sp.Symbol, sp.Expr] = {}
        self.extra_lines: dict[int, str] = {}
        self._placeholders: dict[tuple[type, str], sp.Symbol] = {}
        self._memo: dict = {}
        self._name_inputs()
        self._name_steps()
        self.components = frozenset(self.of_component)

    # ---------------------------------------------------------------- naming
    def _placeholder(self, cls, latex: str, **assumptions) -> sp.Symbol:
        """The symbol that stands for ``latex`` (named after it, so that sums print in the
        order of their names)."""
        key = (cls, latex)
        if key not in self._placeholders:
            symbol = cls(f"{latex} #{len(self._placeholders)}", **assumptions)
            self._placeholders[key] = symbol
            self.names[symbol] = latex
        return self._placeholders[key]

    def _vector_family(self, name: Name, symbols) -> _Family:
        symbols = tuple(symbols)
        if len(symbols) == 3:
            labels = AXES
        else:
            labels = [str(k + 1) for k in range(len(symbols))]
        family = _Family("vector", symbols, self._placeholder(_Vector, name.vector))
        for k, (s, label) in enumerate(zip(symbols, labels)):
            self.names[s] = name.component(label)
            self.of_component[s] = (family, k)
        self.families.append(family)
        self.by_components[symbols] = family
        return family

    def _matrix_family(self, name: Name, matrix: sp.Matrix) -> _Family:
        symbols = tuple(matrix)
        family = _Family("matrix", symbols, self._placeholder(_Vector, name.matrix))
        for k, s in enumerate(symbols):
            self.names[s] = name.entry(*divmod(k, 3))
            self.of_component[s] = (family, divmod(k, 3))
        self.families.append(family)
        return family

    def _name_inputs(self) -> None:
        for block, matrix in self.model.chain.inputs.items():
            if block == "effects":
                self._name_effects(matrix)
                continue
            name = _name(INPUT_LATEX.get(block, block))
            rows, cols = matrix.shape
            if rows * cols == 1:
                self.names[matrix[0, 0]] = name.scalar
            elif cols == 1 and rows == 3:
                self._vector_family(name, matrix)
            elif (rows, cols) == (3, 3):
                self._matrix_family(name, matrix)
            elif cols == 3:
                for i in range(rows):
                    self._vector_family(name.with_sub(str(i + 1)), matrix[i, :])
            else:
                for k, s in enumerate(matrix):
                    self.names[s] = name.with_sub(str(k + 1)).scalar

    def _name_effects(self, matrix: sp.Matrix) -> None:
        entries = dict(zip(parameter_names(), matrix))
        offset = [entries.pop(f"payload_offset.{a}") for a in AXES]
        self._vector_family(_name(EFFECT_NAMES["payload_offset"]), offset)
        for full, s in entries.items():
            self.names[s] = _effect_name(full)

    def _name_steps(self) -> None:
        steps = self.model.chain.steps
        names = {step.name for step in steps}
        by_name = {}
        for index, step in enumerate(steps):
            by_name[step.name] = index
            first = step.targets[0].name
            if len(step.targets) > 1:
                first = _unsuffix(first, "x" if len(step.targets) == 3 else "1") or first
            base, leg, python = first, None, step.name
            match = re.match(r"^(.*)_([1-6])$", step.name)
            if match and all(f"{match.group(1)}_{k}" in names for k in range(1, 7)):
                unsuffixed = _unsuffix(first, match.group(2))
                if unsuffixed is not None:
                    base, leg, python = unsuffixed, int(match.group(2)), match.group(1)
            name = _name(RAW_NAMES.get(python, base))
            if leg is not None:
                name = name.with_sub(str(leg))
            self.step_leg[index] = leg
            self.step_name[index] = name
            if len(step.targets) == 1:
                self.names[step.targets[0]] = name.scalar
            elif len(step.targets) == 9:
                self.step_family[index] = self._matrix_family(
                    name, sp.Matrix(3, 3, step.targets))
            else:
                self.step_family[index] = self._vector_family(name, step.targets)
        self._name_spins(by_name)

    def _name_spins(self, by_name: dict[str, int]) -> None:
        """The legs' angular velocity in their own axes, ``(-b . u', a2 . u', lam)``
        (kinematics.leg_angular_velocity): no step of the chain, but the vector that the legs'
        rotation moments (17) are written in."""
        steps = self.model.chain.steps
        for leg in range(1, 7):
            parts = [by_name.get(f"{n}_{leg}")
                     for n in ("b_u_dot", "a2_u_dot", "lam", "omega_leg")]
            if None in parts:
                continue
            b, a, lam = (steps[k].targets[0] for k in parts[:3])
            spin = sp.symbols(f"omega_b_leg_{leg}_x:z", real=True)
            name = Name(r"\omega", ("L", str(leg)), ("b",))
            family = self._vector_family(name, spin)
            self.spin_substitution.update({b: -spin[0], a: spin[1], lam: spin[2]})
            column = self._column([-b, a, lam])
            self.extra_lines[parts[3]] = f"{self.tex(family.placeholder)} = {column}"

    # ---------------------------------------------------------------- printing
    def tex(self, expr) -> str:
        return _Printer({"symbol_names": self.names}).doprint(expr)

    def _operand(self, expr) -> str:
        """LaTeX of an operand of a product: parenthesised unless it is one symbol."""
        text = self.tex(expr)
        return text if isinstance(expr, sp.Symbol) else rf"\left({text}\right)"

    def _cross(self, a, b) -> sp.Symbol:
        return self._placeholder(
            _Vector, rf"\left({self._operand(a)} \times {self._operand(b)}\right)")

    def _matvec(self, matrix, v) -> sp.Symbol:
        return self._placeholder(_Vector, f"{self._operand(matrix)} {self._operand(v)}")

    def _dot(self, a, b):
        if a == b:
            return self._norm(a) ** 2
        if a.could_extract_minus_sign():
            return -self._dot(-a, b)
        return self._placeholder(
            _Scalar, rf"\left({self._operand(a)} \cdot {self._operand(b)}\right)", real=True)

    def _norm(self, a) -> sp.Symbol:
        return self._placeholder(_Scalar, rf"\left|{self.tex(a)}\right|", positive=True)

    def _unit(self, axis: int) -> sp.Symbol:
        return self._placeholder(_Vector, rf"\mathbf{{e}}_{{{AXES[axis]}}}")

    def _stack(self, top, bottom) -> sp.Symbol:
        """The 6-column ``(top; bottom)`` of two 3-vectors."""
        return self._placeholder(
            _Vector, rf"\begin{{pmatrix}} {self.tex(top)} \\ {self.tex(bottom)} \end{{pmatrix}}")

    # ---------------------------------------------------------------- vector forms
    def _pivots(self, exprs, size: int) -> list[_Family]:
        """Families of ``size`` entries whose components are factors of the top-level terms,
        the most frequent first."""
        counts: dict[int, int] = {}
        order: dict[int, _Family] = {}
        for expr in exprs:
            for term in sp.Add.make_args(expr):
                for factor in sp.Mul.make_args(term):
                    hit = self.of_component.get(factor)
                    if hit and hit[0].kind == "vector" and len(hit[0].symbols) == size:
                        counts[id(hit[0])] = counts.get(id(hit[0]), 0) + 1
                        order[id(hit[0])] = hit[0]
        return [order[k] for k in sorted(counts, key=lambda k: -counts[k])]

    @staticmethod
    def _extract(exprs, symbols):
        """``exprs = J symbols + rest`` over the top-level terms linear in one of ``symbols``."""
        index = {s: j for j, s in enumerate(symbols)}
        J = sp.zeros(len(exprs), len(symbols))
        rest = []
        for i, expr in enumerate(exprs):
            left = []
            for term in sp.Add.make_args(expr):
                hits = [f for f in sp.Mul.make_args(term) if f in index]
                if len(hits) == 1:
                    J[i, index[hits[0]]] += term / hits[0]
                else:
                    left.append(term)
            rest.append(sp.Add(*left))
        return J, rest

    def vector(self, exprs):
        """The vector form of a column of component expressions (3 or 6 entries)."""
        key = tuple(sp.sympify(e) for e in exprs)
        if key not in self._memo:
            self._memo[key] = self._vector(list(key))
        return self._memo[key]

    def _vector(self, e):
        size = len(e)
        if all(x == 0 for x in e):
            return self._placeholder(_Vector, r"\mathbf{0}")
        family = self.by_components.get(tuple(e))
        if family is not None:
            return family.placeholder
        factor, rest = _common_factor(e)
        if factor != 1:
            inner = self.vector(rest)
            if inner is not None:
                return self.scalar(factor) * inner
        for family in self._pivots(e, size):
            J, rest = self._extract(e, family.symbols)
            part = self._linear(J, family)
            if part is not None:
                return part + self._rest(rest)
        if size == 3:
            for family in self._matrix_pivots(e):
                part, rest = self._matrix_product(e, family)
                if part is not None:
                    return part + self._rest(rest)
        if all(isinstance(x, sp.Piecewise) for x in e):
            piecewise = self._piecewise(e)
            if piecewise is not None:
                return piecewise
        if size == 6:
            return self._stack(self.vector(e[:3]), self.vector(e[3:]))
        nonzero = [k for k, x in enumerate(e) if x != 0]
        if len(nonzero) == 1:
            return self.scalar(e[nonzero[0]]) * self._unit(nonzero[0])
        rows = r" \\ ".join(self.tex(self.scalar(x)) for x in e)
        return self._placeholder(_Vector, rf"\begin{{pmatrix}} {rows} \end{{pmatrix}}")

    def _rest(self, rest):
        return 0 if all(r == 0 for r in rest) else self.vector(rest)

    def _matrix_pivots(self, exprs) -> list[_Family]:
        """Matrix families with entries among the factors of the top-level terms."""
        found = []
        for expr in exprs:
            for term in sp.Add.make_args(expr):
                for factor in sp.Mul.make_args(term):
                    hit = self.of_component.get(factor)
                    if hit and hit[0].kind == "matrix" and hit[0] not in found:
                        found.append(hit[0])
        return found

    def _matrix_product(self, e, family: _Family):
        """``(M x, rest)`` or ``(M^T x, rest)`` with ``e = M x + rest`` (M the family), or
        ``(None, e)``: the terms with an entry of M as a factor must be ``M_ij x_j``."""
        K, rest = self._extract(e, family.symbols)
        name = self.names[family.placeholder]
        for transposed in (False, True):
            x = []
            for i in range(3):
                row = [K[i, 3 * (j if transposed else i) + (i if transposed else j)]
                       for j in range(3)]
                x.append(row)
            others = [K[i, k] for i in range(3) for k in range(9)
                      if k not in {3 * (j if transposed else i) + (i if transposed else j)
                                   for j in range(3)}]
            if any(o != 0 for o in others):
                continue
            if not all(_same(x[i][j], x[0][j]) for i in range(3) for j in range(3)):
                continue
            vector = self.vector(x[0])
            if transposed:
                name = rf"\left({name}\right)^{{T}}" if "^" in name else f"{name}^{{T}}"
            return self._matvec(self._placeholder(_Vector, name), vector), rest
        return None, e

    def _piecewise(self, e):
        branches = [x.args for x in e]
        if len({len(b) for b in branches}) != 1:
            return None
        out = []
        for k in range(len(branches[0])):
            conditions = {b[k][1] for b in branches}
            if len(conditions) != 1:
                return None
            value = self.vector([b[k][0] for b in branches])
            if value is None:
                return None
            out.append((value, self._condition(conditions.pop())))
        return sp.Piecewise(*out, evaluate=False)

    def _condition(self, condition):
        if isinstance(condition, sp.core.relational.Relational):
            return condition.func(self.scalar(condition.lhs), self.scalar(condition.rhs))
        return condition

    def _linear(self, J: sp.Matrix, family: _Family):
        """The vector form of ``J v`` (v the family), or None."""
        v = family.placeholder
        n = J.shape[0]
        diagonal = [J[k, k] for k in range(n)]
        off = [(i, j) for i in range(n) for j in range(n) if i != j]
        same_diagonal = all(_same(d, diagonal[0]) for d in diagonal)
        if same_diagonal and all(J[i, j] == 0 for i, j in off):
            return self.scalar(diagonal[0]) * v
        if n != 3:
            return None
        if same_diagonal and all(_same(J[i, j], -J[j, i]) for i, j in off):
            # J v = B x v: written so when B is a named vector, else as v x (-B)
            B = [J[2, 1], J[0, 2], J[1, 0]]
            if tuple(B) in self.by_components:
                cross = self._cross(self.vector(B), v)
            else:
                cross = self._cross(v, self.vector([-b for b in B]))
            return self.scalar(diagonal[0]) * v + cross
        matrix = self.matrix(J)
        if matrix is not None:
            return self._matvec(matrix, v)
        return None

    def matrix(self, J: sp.Matrix):
        """The form of a 3x3 matrix of expressions: a sum of input matrices (or their
        transposes) times scalars, or a matrix of three vector columns; None otherwise."""
        columns = [self.by_components.get(tuple(J[:, j])) for j in range(3)]
        if all(columns):
            cols = r"\;".join(self.tex(c.placeholder) for c in columns)
            return self._placeholder(_Vector, rf"\left[{cols}\right]")
        rows = [self.by_components.get(tuple(J[i, :])) for i in range(3)]
        if all(rows):
            cols = r"\;".join(self.tex(c.placeholder) for c in rows)
            return self._placeholder(_Vector, rf"\left[{cols}\right]^{{T}}")
        total, rest = sp.S.Zero, J
        for family in self.families:
            if family.kind != "matrix":
                continue
            for transposed in (False, True):
                M = sp.Matrix(3, 3, family.symbols)
                M = M.T if transposed else M
                K, left = self._extract(list(rest), list(M))
                coefficients = [K[k, k] for k in range(9)]
                if (coefficients[0] == 0 or any(K[a, b] != 0 for a in range(9) for b in range(9)
                                                if a != b)
                        or not all(_same(c, coefficients[0]) for c in coefficients)):
                    continue
                name = self.names[family.placeholder]
                if transposed:
                    name = rf"\left({name}\right)^{{T}}" if "^" in name else f"{name}^{{T}}"
                total += self.scalar(coefficients[0]) * self._placeholder(_Vector, name)
                rest = sp.Matrix(3, 3, left)
        if total != 0 and all(r == 0 for r in rest):
            return total
        return None

    # ---------------------------------------------------------------- scalar forms
    def scalar(self, expr):
        """The form of a scalar expression with its dot products and lengths recognised."""
        expr = sp.sympify(expr)
        if not expr.free_symbols & self.components or expr in self.components:
            return expr
        key = ("scalar", expr)
        if key not in self._memo:
            self._memo[key] = self._scalar(expr)
        return self._memo[key]

    def _scalar(self, s):
        if s.is_Add:
            for size in (3, 6):
                for family in self._pivots([s], size):
                    G, rest = self._extract([s], family.symbols)
                    if sum(1 for g in G if g != 0) < 2:
                        continue
                    g = self.vector(list(G))
                    if g is not None:
                        return self._dot(g, family.placeholder) + self.scalar(rest[0])
            squares = self._squares(s)
            if squares is not None:
                return squares
            return sp.Add(*[self.scalar(t) for t in s.args])
        if s.is_Mul:
            return sp.Mul(*[self.scalar(a) for a in s.args])
        if s.is_Pow:
            return self.scalar(s.base) ** s.exp
        if isinstance(s, sp.Piecewise):
            return sp.Piecewise(*[(self.scalar(v), self._condition(c)) for v, c in s.args],
                                evaluate=False)
        if s.args:
            return s.func(*[self.scalar(a) for a in s.args])
        return s

    def _squares(self, s):
        """``|g|^2 + rest`` when the squares among the terms of ``s`` are a vector's."""
        squares, rest = {}, []
        for term in s.args:
            axis = self._axis(term.base) if term.is_Pow and term.exp == 2 else None
            if axis is not None and axis not in squares:
                squares[axis] = term.base
            else:
                rest.append(term)
        for size in (3, 6):
            if sorted(k for n, k in squares if n == size) == list(range(size)):
                g = self.vector([squares[size, k] for k in range(size)])
                if g is not None:
                    left = rest + [b ** 2 for (n, _), b in squares.items() if n != size]
                    return self._norm(g) ** 2 + self.scalar(sp.Add(*left))
        return None

    def _axis(self, expr):
        """``(size, entry)``: the entry of a vector of that size that ``expr`` is read as, or
        None. Every vector component in ``expr`` is of that entry, or, for a cross product's
        component, of the two other axes. (A sum of squares is a length whatever the order of
        its entries: the order only makes the vector read well.)"""
        axes = set()
        for s in expr.free_symbols & self.components:
            family, index = self.of_component[s]
            if family.kind != "vector":
                return None
            axes.add((len(family.symbols), index))
        if len(axes) == 1:
            return axes.pop()
        if len(axes) == 2 and {n for n, _ in axes} == {3}:
            return 3, ({0, 1, 2} - {k for _, k in axes}).pop()
        return None

    # ---------------------------------------------------------------- equations
    def equations(self, group: str, leg: int = 1, expand: bool = False,
                  iterates: bool = False) -> list[str]:
        chosen = [index for index, step in enumerate(self.model.chain.steps)
                  if step.equation == group and self.step_leg[index] in (None, leg)]
        numbers = {index: self._iterate(index) for index in chosen}
        last = max((n for n in numbers.values() if n is not None), default=None)
        lines = []
        for index in chosen:
            n = numbers[index]
            if not iterates and n is not None and 2 < n < last:
                if lines[-1] != r"\vdots":
                    lines.append(r"\vdots")
                continue
            lines += self._definition(index, group, expand)
            if index in self.extra_lines:
                lines.append(self.extra_lines[index])
        return lines

    def _iterate(self, index: int) -> int | None:
        """The iterate a quantity belongs to (its superscript ``(k)``), or None."""
        for script in self.step_name[index].sup:
            match = re.fullmatch(r"\((\d+)\)", script)
            if match:
                return int(match.group(1))
        return None

    def _definition(self, index: int, group: str, expand: bool) -> list[str]:
        step = self.model.chain.steps[index]
        exprs = step.exprs
        if group == "17":
            exprs = [e.xreplace(self.spin_substitution) for e in exprs]
        family = self.step_family.get(index)
        if family is None:
            return [f"{self.tex(step.targets[0])} = {self.tex(self.scalar(exprs[0]))}"]
        components = f"{self._column(step.targets)} = {self._column(step.exprs)}"
        if family.kind != "vector":
            return [components]
        line = f"{self.tex(family.placeholder)} = {self.tex(self.vector(exprs))}"
        return [line, components] if expand else [line]

    def _column(self, exprs) -> str:
        rows = r" \\ ".join(self.tex(e) for e in exprs)
        return rf"\begin{{pmatrix}} {rows} \end{{pmatrix}}"


def _same(a, b) -> bool:
    """``a == b`` for expressions, structurally or after expanding their difference."""
    return a == b or sp.expand(a - b) == 0


def _common_factor(exprs):
    """The factor common to every non-zero expression (a number or a product), and the rest."""
    nonzero = [e for e in exprs if e != 0]
    if not nonzero:
        return sp.S.One, list(exprs)
    coefficients = [e.as_coeff_Mul()[0] for e in nonzero]
    factors = [set(sp.Mul.make_args(e.as_coeff_Mul()[1])) for e in nonzero]
    shared = set.intersection(*factors)
    number = coefficients[0] if all(c == coefficients[0] for c in coefficients) else sp.S.One
    common = number * sp.Mul(*shared)
    if common == 1:
        return sp.S.One, list(exprs)
    return common, [e / common for e in exprs]


_VIEWS: dict[int, tuple[Model, _View]] = {}


def _view(model: Model) -> _View:
    """The view of a model, made once (the model is kept, so that its id stays its own)."""
    if id(model) not in _VIEWS:
        if len(_VIEWS) >= 4:
            _VIEWS.pop(next(iter(_VIEWS)))
        _VIEWS[id(model)] = (model, _View(model))
    return _VIEWS[id(model)][1]


def symbol_names(model: Model) -> dict[sp.Symbol, str]:
    """LaTeX of every symbol of the model's chain (inputs and named quantities).

    Parameters
    ----------
    model : Model
        ``derive.model.build(...)``.

    Returns
    -------
    dict
        Symbol -> LaTeX, for ``sympy.latex(expr, symbol_names=...)``.
    """
    view = _view(model)
    return {s: t for s, t in view.names.items() if not isinstance(s, (_Vector, _Scalar))}


def equations(model: Model, group: str, leg: int = 1, expand: bool = False,
              iterates: bool = False) -> list[str]:
    """The definitions of one equation group as LaTeX, one line per quantity.

    Parameters
    ----------
    model : Model
        ``derive.model.build(mode)``.
    group : str
        One of ``GROUPS`` (``Step.equation``).
    leg : int
        The leg (1-6) whose quantities are shown; quantities of the platform are always shown.
    expand : bool
        Follow every vector definition by its components, as the generated code computes them.
    iterates : bool
        Show every iterate of the coupled model's fixed point; by default the first three and
        the last, the others elided (``\\vdots``): each repeats the one before.

    Returns
    -------
    list of str
        ``name = definition`` in LaTeX, in the chain's order.
    """
    return _view(model).equations(group, leg, expand, iterates)
