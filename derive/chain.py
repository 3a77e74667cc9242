"""An ordered chain of symbolic definitions: the derivation's intermediate quantities.

Every intermediate quantity of the derivation (a leg direction, a required moment, a reaction) is
given a name and a symbol of its own, defined once from earlier symbols. Expressions stay small,
shared quantities are computed once, and the same chain is translated three ways:

* to CasADi (``to_casadi``), which generates the C code;
* to NumPy (``evaluate``), the lambdified reference the compiled code is tested against;
* to LaTeX (``definitions``), to read in a notebook.

Every step is a definition ``symbol := expression``; the 6x6 system in the legs' axial forces is
solved by an orthogonal (Gram-Schmidt) factorisation written out as such steps (``factor``,
``solve``), so that a second right-hand side reuses the factor.
"""

from __future__ import annotations

import builtins
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import sympy as sp
from sympy.printing.numpy import NumPyPrinter


@dataclass
class Step:
    """One step of a chain: ``targets := exprs``."""

    name: str
    targets: list[sp.Symbol]
    exprs: list[sp.Expr] = field(default_factory=list)
    equation: str = ""


@dataclass
class Factor:
    """An orthogonal factor ``A = V U`` defined in a chain.

    ``v`` are orthogonal (not normalised) columns, ``U`` the strictly upper entries of a unit
    upper-triangular matrix, ``inv`` the reciprocals ``1 / (v_j . v_j)``.
    """

    name: str
    latex: str
    v: list[sp.Matrix]
    U: dict
    inv: list[sp.Symbol]


def inline(name: str, expr, latex: str | None = None):
    """The ``let`` that defines nothing: returns ``expr`` itself (for reading and testing).

    Parameters: ``name`` (str), ``expr`` (sympy.Expr or Matrix, any shape and unit), ``latex``
    (ignored). Returns ``expr``.

    Every derive/ function that names intermediate quantities takes a ``let`` argument with this
    signature; the model passes ``Chain.scope(...)`` so that each quantity becomes one chain step,
    computed once and shared by every later use.
    """
    return expr


class Scope:
    """A ``let`` bound to one chain, one equation group and (optionally) one leg.

    ``scope(name, expr, latex)`` defines ``name`` (suffixed ``_k`` for leg k) in the chain; its
    LaTeX gets the leg number as a last subscript (``D`` -> ``D_{3}``, ``a_{2}`` -> ``a_{2,3}``).
    """

    def __init__(self, chain: "Chain", equation: str, leg: int | None = None) -> None:
        self.chain, self.equation, self.leg = chain, equation, leg

    def __call__(self, name: str, expr, latex: str | None = None):
        base = latex or name
        if self.leg is not None:
            name = f"{name}_{self.leg}"
            if base.endswith("}") and "_{" in base:
                base = f"{base[:-1]},{self.leg}}}"
            else:
                base = f"{base}_{{{self.leg}}}"
        return self.chain.let(name, expr, base, self.equation)

    def group(self, equation: str) -> "Scope":
        """The same scope (chain, leg) for another equation group.

        Parameters
        ----------
        equation : str

        Returns
        -------
        Scope
        """
        return Scope(self.chain, equation, self.leg)


class Chain:
    """Ordered definitions in terms of named inputs.

    ``input`` declares an input block (a vector, or a matrix stored row-major);
    ``let`` defines a scalar, vector or matrix quantity; ``factor`` and ``solve`` define the
    solution of a linear system. Each returns SymPy symbols that later expressions use.
    """

    def __init__(self) -> None:
        self.inputs: dict[str, sp.Matrix] = {}
        self.steps: list[Step] = []
        self._names: set[str] = set()
        self._symbol_names: set[str] = set()
        self._numpy_body = None

    def _claim(self, name: str, base: str | None = None) -> None:
        """Reserve a quantity's name (it must be unique)."""
        if name in self._names:
            raise ValueError(f"chain: {name!r} is defined twice")
        self._names.add(name)

    def _symbol(self, name: str) -> sp.Symbol:
        """A new real symbol; two quantities never share a symbol name."""
        if name in self._symbol_names:
            raise ValueError(f"chain: symbol name {name!r} is already taken")
        self._symbol_names.add(name)
        return sp.Symbol(name, real=True)

    def input(self, name: str, rows: int, cols: int = 1, latex: str | None = None) -> sp.Matrix:
        """Declare an input block.

        Parameters
        ----------
        name : str
            Block name (unique in the chain); the generated functions take the blocks in
            declaration order.
        rows, cols : int
            Shape; a matrix block is stored row-major in the flat input.
        latex : str, optional
            LaTeX base of the entries' symbols.

        Returns
        -------
        sympy.Matrix, shape (rows, cols)
            Real symbols.
        """
        base = latex or name
        self._claim(name, base)
        syms = [
            [self._symbol(_entry_name(base, r, c, rows, cols)) for c in range(cols)]
            for r in range(rows)
        ]
        m = sp.Matrix(syms)
        self.inputs[name] = m
        return m

    def let(self, name: str, expr, latex: str | None = None, equation: str = ""):
        """Define ``name := expr``, one step of the chain.

        Parameters
        ----------
        name : str
            Unique name of the quantity.
        expr : sympy.Expr or sympy.Matrix
            Its definition in earlier symbols (any shape, any unit).
        latex : str, optional
            LaTeX base of its symbol(s) (default ``name``).
        equation : str
            The equation group it belongs to (``"8-10"``, ``"kinematics"``, ...).

        Returns
        -------
        sympy.Symbol or sympy.Matrix of the shape of expr
            The new symbol(s), to use in later expressions.
        """
        base = latex or name
        self._claim(name, base)
        if isinstance(expr, sp.MatrixBase):
            rows, cols = expr.shape
            targets = [
                self._symbol(_entry_name(base, r, c, rows, cols))
                for r in range(rows)
                for c in range(cols)
            ]
            self.steps.append(Step(name, targets, list(expr), equation=equation))
            return sp.Matrix(rows, cols, targets)
        target = self._symbol(base)
        self.steps.append(Step(name, [target], [sp.sympify(expr)], equation=equation))
        return target

    def scope(self, equation: str, leg: int | None = None) -> Scope:
        """A ``let`` for the quantities of one equation group (and one leg, numbered from 1).

        Parameters
        ----------
        equation : str
            Equation group of the quantities it defines.
        leg : int, optional
            Leg number 1..6, appended to names (``_k``) and LaTeX subscripts.

        Returns
        -------
        Scope
            Callable ``(name, expr, latex=None) -> symbol(s)``.
        """
        return Scope(self, equation, leg)

    def factor(self, name: str, A: sp.Matrix, latex: str | None = None,
               equation: str = "") -> "Factor":
        """Orthogonal factorisation ``A = V U`` of a square A by modified Gram-Schmidt, as steps.

        Each column ``a_j`` is reduced against the earlier columns ``v_i``
        (``U_ij = (v_i . v) / (v_i . v_i)``, ``v -= U_ij v_i``); the columns are not normalised
        (no square root) and the reciprocals ``1 / (v_j . v_j)`` are kept, so that solving with
        the factor needs no division.

        Parameters
        ----------
        name : str
            Prefix of the factor's steps.
        A : sympy.Matrix, shape (n, n)
            Nonsingular matrix in earlier symbols.
        latex : str, optional
        equation : str

        Returns
        -------
        Factor
        """
        base = latex or name
        n = A.shape[0]
        vs, U, inv = [], {}, []
        for j in range(n):
            v = A[:, j]
            for i in range(j):
                U[i, j] = self.let(f"{name}_U{i}{j}", (vs[i].T * v)[0, 0] * inv[i],
                                   f"{base}_{{U{i + 1}{j + 1}}}", equation)
                v = self.let(f"{name}_v{i}{j}", v - U[i, j] * vs[i],
                             f"{base}_{{v{i + 1}{j + 1}}}", equation)
            if j == 0:
                v = self.let(f"{name}_v0", v, f"{base}_{{v1}}", equation)
            vs.append(v)
            inv.append(self.let(f"{name}_inv{j}", 1 / (v.T * v)[0, 0],
                                f"{base}_{{n{j + 1}}}^{{-1}}", equation))
        return Factor(name, base, vs, U, inv)

    def solve(self, name: str, factor: "Factor", b: sp.Matrix, latex: str | None = None,
              equation: str = "") -> sp.Matrix:
        """Define ``name := A^-1 b`` with the factor of A: ``U x = diag(inv) V^T b``.

        Parameters
        ----------
        name : str
            Prefix of the solution's steps (``name0`` .. ``name{n-1}``).
        factor : Factor
            ``factor(...)`` of A.
        b : sympy.Matrix, shape (n, 1)
            Right-hand side.
        latex : str, optional
        equation : str

        Returns
        -------
        sympy.Matrix, shape (n, 1)
            Symbols of the solution.
        """
        base = latex or name
        n = len(factor.v)
        y = [(factor.v[j].T * b)[0, 0] * factor.inv[j] for j in range(n)]
        x = [None] * n
        for j in reversed(range(n)):
            rest = sum((factor.U[j, k] * x[k] for k in range(j + 1, n)), sp.S.Zero)
            x[j] = self.let(f"{name}{j}", y[j] - rest, f"{base}_{{{j + 1}}}", equation)
        return sp.Matrix(x)

    def definitions(self, equation: str | None = None):
        """The ``let`` steps (optionally of one equation group) as (name, LaTeX) pairs.

        Parameters
        ----------
        equation : str, optional
            Keep only the steps of this group.

        Returns
        -------
        list of (str, str)
            Step name and ``symbol = definition`` in LaTeX, in chain order.
        """
        out = []
        for step in self.steps:
            if equation is not None and step.equation != equation:
                continue
            lhs = sp.Matrix(step.targets) if len(step.targets) > 1 else step.targets[0]
            rhs = sp.Matrix(step.exprs) if len(step.exprs) > 1 else step.exprs[0]
            out.append((step.name, sp.latex(sp.Eq(lhs, rhs, evaluate=False))))
        return out

    def _print_numpy_body(self):
        """Python source lines computing every step, shared by all ``numpy_function`` calls."""
        names: dict[sp.Symbol, str] = {}

        class Printer(NumPyPrinter):
            def _print_Symbol(self, expr):
                return names[expr]

        printer = Printer({"fully_qualified_modules": False, "inline": True,
                           "allow_unknown_functions": False})
        lines = ["def chain(values):", "    n = 1",
                 "    for v in values.values():",
                 "        v = asarray(v)",
                 "        if v.ndim == 2:",
                 "            n = max(n, v.shape[0])"]
        for name, mat in self.inputs.items():
            var = f"in_{len(names)}"
            lines.append(f"    {var} = broadcast_to(asarray(values[{name!r}], dtype=float)"
                         f".reshape(-1, {len(mat)}), (n, {len(mat)}))")
            for k, sym in enumerate(mat):
                names[sym] = f"{var}[:, {k}]"

        def new(sym):
            names[sym] = f"s{len(names)}"
            return names[sym]

        for step in self.steps:
            for t, e in zip(step.targets, step.exprs):
                lines.append(f"    {new(t)} = {_full_length(printer, e)}")
        return names, lines, printer

    # ----------------------------------------------------------------- back ends
    def to_casadi(self, inputs: dict, outputs: dict[str, sp.Matrix]) -> dict:
        """Translate the chain into CasADi SX expressions.

        Parameters
        ----------
        inputs : dict
            input name -> casadi.SX column of the block's entries (row-major).
        outputs : dict
            output name -> Matrix of chain symbols.

        Returns
        -------
        dict of output name -> casadi.SX column (row-major entries of the Matrix).
        """
        env: dict[sp.Symbol, object] = {}
        for name, mat in self.inputs.items():
            col = inputs[name]
            for k, s in enumerate(mat):
                env[s] = col[k]
        conv = _CasadiConverter(env)
        for step in self.steps:
            for t, e in zip(step.targets, step.exprs):
                env[t] = conv(e)
        return {name: ca.vertcat(*[conv(v) for v in mat]) for name, mat in outputs.items()}

    def evaluate(self, values: dict, outputs: dict[str, sp.Matrix]) -> dict:
        """Evaluate the chain with NumPy (lambdified SymPy), vectorised over a leading axis.

        Parameters
        ----------
        values : dict
            input name -> array of shape (N, size) or (size,), entries row-major.
        outputs : dict
            output name -> Matrix of chain symbols (or expressions in them).

        Returns
        -------
        dict of output name -> ndarray of shape (N, size).
        """
        return self.numpy_function(outputs)(values)

    def numpy_function(self, outputs: dict[str, sp.Matrix]):
        """One Python function evaluating the whole chain with NumPy (printed by SymPy).

        Parameters
        ----------
        outputs : dict
            Output name -> Matrix of chain symbols (or expressions in them).

        Returns
        -------
        callable
            ``f(values) -> dict`` with ``values`` and the result as in ``evaluate``
            (arrays (N, size), entries row-major).
        """
        if self._numpy_body is None or self._numpy_body[0] != len(self.steps):
            self._numpy_body = (len(self.steps),) + self._print_numpy_body()
        _, names, lines, printer = self._numpy_body
        lines = list(lines)
        lines.append("    return {")
        for name, mat in outputs.items():
            entries = ", ".join(_full_length(printer, v) for v in mat)
            lines.append(f"        {name!r}: stack([{entries}], -1),")
        lines.append("    }")
        env = {k: getattr(np, k) for k in dir(np)
               if not k.startswith("_") and not hasattr(builtins, k)}
        env["reduce"] = __import__("functools").reduce
        exec(compile("\n".join(lines), "<chain>", "exec"), env)
        return env["chain"]


def _full_length(printer, expr) -> str:
    """NumPy source of ``expr`` broadcast to the chain's ``n`` steps (constants included)."""
    return f"broadcast_to(1.0 * ({printer.doprint(expr)}), (n,))"


def _entry_name(base: str, r: int, c: int, rows: int, cols: int) -> str:
    """LaTeX-friendly name of one entry: ``R_{E1}`` -> ``R_{E1,x}``; ``I`` -> ``I_{12}``."""
    if rows * cols == 1:
        return base
    if cols == 1:
        suffix = "xyz"[r] if rows == 3 else str(r + 1)
    else:
        suffix = f"{r + 1}{c + 1}"
    if base.endswith("}") and "_{" in base:
        return f"{base[:-1]},{suffix}}}"
    return f"{base}_{{{suffix}}}"


class _CasadiConverter:
    """SymPy expression -> CasADi SX, sharing the nodes of repeated subexpressions."""

    def __init__(self, env: dict) -> None:
        self.ca = ca
        self.env = env
        self.memo: dict = {}

    def __call__(self, expr):
        expr = sp.sympify(expr)
        hit = self.memo.get(expr)
        if hit is not None:
            return hit
        out = self._convert(expr)
        self.memo[expr] = out
        return out

    def _convert(self, e):
        ca = self.ca
        if e.is_Symbol:
            try:
                return self.env[e]
            except KeyError:
                raise KeyError(f"symbol {e} used before it is defined") from None
        if e.is_Number:
            return ca.SX(float(e))
        if e.is_Add:
            args = [self(a) for a in e.args]
            out = args[0]
            for a in args[1:]:
                out = out + a
            return out
        if e.is_Mul:
            args = [self(a) for a in e.args]
            out = args[0]
            for a in args[1:]:
                out = out * a
            return out
        if e.is_Pow:
            base, ex = e.args
            b = self(base)
            if ex == sp.Rational(1, 2):
                return ca.sqrt(b)
            if ex == -sp.Rational(1, 2):
                return 1 / ca.sqrt(b)
            if ex.is_Integer:
                k = int(ex)
                if k == -1:
                    return 1 / b
                if k == 2:
                    return b * b
                if k == -2:
                    return 1 / (b * b)
                return ca.constpow(b, k)
            return ca.power(b, self(ex))
        funcs = {sp.sin: ca.sin, sp.cos: ca.cos, sp.exp: ca.exp, sp.tanh: ca.tanh,
                 sp.Abs: ca.fabs, sp.sign: ca.sign, sp.atan2: ca.atan2}
        if e.func in funcs:
            return funcs[e.func](*[self(a) for a in e.args])
        if isinstance(e, (sp.Max, sp.Min)):
            op = ca.fmax if isinstance(e, sp.Max) else ca.fmin
            args = [self(a) for a in e.args]
            out = args[0]
            for a in args[1:]:
                out = op(out, a)
            return out
        if isinstance(e, sp.Piecewise):
            (val, cond), rest = e.args[0], e.args[1:]
            other = self(sp.Piecewise(*rest)) if rest and rest[0][1] is not sp.true else \
                self(rest[0][0])
            return ca.if_else(self._condition(cond), self(val), other)
        raise TypeError(f"no CasADi translation for {e.func.__name__}: {e}")

    def _condition(self, c):
        rel = {sp.StrictGreaterThan: lambda a, b: a > b, sp.GreaterThan: lambda a, b: a >= b,
               sp.StrictLessThan: lambda a, b: a < b, sp.LessThan: lambda a, b: a <= b}
        return rel[type(c)](self(c.lhs), self(c.rhs))
