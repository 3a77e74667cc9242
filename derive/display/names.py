"""LaTeX names of the model's symbols, as in the paper where it has them.

A name is held in parts (``Name``: a kernel with sub- and superscripts) and written as the
quantity it names is: vectors bold (``\\mathbf{u}_{1}``), components with the axis last
(``u_{1,x}``), matrix entries with the body as superscript (``I^{L}_{11}``). ``legend(model)``
lists what the names of the model's inputs stand for.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..effects import generated
from ..model import (CONSTANT_LATEX, PAPER_CONSTANTS, PARAMETER_LATEX, PARAMETERS, STATE,
                     STATE_LATEX, Model)

AXES = "xyz"

RAW_NAMES = {
    "M_rot_alpha": r"\alpha^{b}",
    "M_rot_omega": r"\omega^{b}",
    "leg_body_alpha": r"\alpha^{b}_{L}",
    "leg_body_omega": r"\omega^{b}_{L}",
    "a2_u_dot": r"\dot{u}^{a}",
    "b_u_dot": r"\dot{u}^{b}",
}
"""LaTeX of the quantities whose name in the chain is no LaTeX name: the platform's and the
legs' rates in their own axes (superscript b, for body) and the components of u' along the
leg's axes a2 and b."""

EFFECT_NAMES = {
    "stribeck.static": "F_{S}",
    "stribeck.velocity": "v_{S}",
    "seal_friction.force": "F_{s}",
    "quadratic_drag.coefficient": "c_{d}",
    "stroke_friction.slope": "k_{D}",
    "stroke_friction.reference": "D_{0}",
    "payload_offset": r"\Delta c_{L}",
    "joint_friction_coupling.scale": "k_{jf}",
    "leg_weight.lower_mass": r"\Delta m_{4}",
    "leg_weight.upper_mass": r"\Delta m_{2}",
    "bushing_friction.coefficient": r"\mu_{b}",
    "bushing_friction.spacing": "b_{b}",
}
"""Names of the effect parameters (the input Q, derive/effects.py): the payload offset is a
vector, the sensor biases are ``b_{F,i}``; a parameter not listed is ``q_{\\text{name}}``."""

INPUT_LATEX = {**STATE_LATEX, **PARAMETER_LATEX, **CONSTANT_LATEX}
"""LaTeX of the model's inputs (state, platform parameters, paper constants) by name."""



def _script(text: str) -> tuple[str, str]:
    """Split ``"{ab}rest"`` into ``("ab", "rest")`` and ``"arest"`` into ``("a", "rest")``."""
    if not text.startswith("{"):
        return text[0], text[1:]
    depth = 0
    for i, ch in enumerate(text):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        if depth == 0:
            return text[1:i], text[i + 1:]
    raise ValueError(f"unbalanced braces in {text!r}")


_KERNEL = re.compile(r"(?:\\Delta\s*)?(?:\\[A-Za-z]+\{[^{}]*\}|\\[A-Za-z]+|[A-Za-z])")
_ITERATE = re.compile(r"^(.*[A-Za-z])_(\d+)$")
_ACCENT = re.compile(r"^\\(dot|ddot|hat|tilde|bar)\{(.+)\}$")


@dataclass(frozen=True)
class Name:
    """A symbol's LaTeX in parts, ``kernel_{sub}^{sup}`` with comma-joined scripts."""

    kernel: str
    sub: tuple[str, ...] = ()
    sup: tuple[str, ...] = ()

    @classmethod
    def parse(cls, latex: str) -> Name | None:
        """``latex`` in parts, or None when it is not a kernel with sub- and superscripts.

        An iterate's index written inside a subscript (``M_{frE_0}``) becomes a superscript
        (``M^{(0)}_{frE}``).
        """
        match = _KERNEL.match(latex)
        if match is None:
            return None
        rest, sub, sup = latex[match.end():], [], []
        while rest:
            if rest[0] not in "_^" or len(rest) < 2:
                return None
            script, tail = _script(rest[1:])
            (sub if rest[0] == "_" else sup).append(script)
            rest = tail
        for k, part in enumerate(sub):
            iterate = _ITERATE.match(part)
            if iterate and "\\" not in part:
                sub[k] = iterate.group(1)
                sup.append(f"({iterate.group(2)})")
        return cls(match.group(0), tuple(sub), tuple(sup))

    def with_sub(self, *extra: str) -> Name:
        return Name(self.kernel, self.sub + tuple(extra), self.sup)

    def _scripts(self, kernel: str, sub=None, sup=None) -> str:
        sub = self.sub if sub is None else sub
        sup = self.sup if sup is None else sup
        out = kernel
        if sub:
            out += "_{" + ",".join(sub) + "}"
        if sup:
            out += "^{" + ",".join(sup) + "}"
        return out

    @property
    def scalar(self) -> str:
        """The name of a scalar: ``D_{1}``."""
        return self._scripts(self.kernel)

    @property
    def vector(self) -> str:
        """The name of a vector, bold: ``\\mathbf{u}_{1}``, ``\\dot{\\mathbf{u}}_{1}``."""
        return self._scripts(_bold(self.kernel))

    def component(self, axis: str) -> str:
        """The name of one component: ``u_{1,x}``."""
        return self.with_sub(axis).scalar

    @property
    def matrix(self) -> str:
        """The name of a matrix: its labels as superscripts, ``I^{L}``."""
        return self._scripts(self.kernel, (), self.sub + self.sup)

    def entry(self, i: int, j: int) -> str:
        """The name of a matrix entry (from 0): ``I^{L}_{11}``."""
        return self._scripts(self.kernel, (f"{i + 1}{j + 1}",), self.sub + self.sup)


def _bold(kernel: str) -> str:
    if kernel.startswith(r"\Delta"):
        return r"\Delta" + _bold(kernel[len(r"\Delta"):].strip())
    accent = _ACCENT.match(kernel)
    if accent:
        return rf"\{accent.group(1)}{{{_bold(accent.group(2))}}}"
    if kernel.startswith("\\"):
        return rf"\boldsymbol{{{kernel}}}"
    return rf"\mathbf{{{kernel}}}"


def _name(latex: str) -> Name:
    """``Name.parse``, or the text itself as an upright name."""
    parsed = Name.parse(latex)
    if parsed is None:
        escaped = latex.replace("_", r"\_")
        return Name(rf"\mathrm{{{escaped}}}")
    return parsed


def _unsuffix(name: str, suffix: str) -> str | None:
    """Undo ``Scope`` and ``_entry_name`` (derive/chain.py): the base ``suffix`` was added to."""
    if name.endswith(f",{suffix}}}"):
        return name[:-len(f",{suffix}}}")] + "}"
    if name.endswith(f"_{{{suffix}}}"):
        return name[:-len(f"_{{{suffix}}}")]
    return None


def _effect_name(full: str) -> str:
    """LaTeX of the effect parameter ``full`` (``"effect.parameter"``), a scalar: the sensor
    biases ``b_{F,i}``, those of ``EFFECT_NAMES``, else ``q_{\\text{name}}``."""
    effect, _, parameter = full.partition(".")
    if effect == "sensor_bias":
        return f"b_{{F,{parameter[1:]}}}"
    return EFFECT_NAMES.get(full, rf"q_{{\text{{{full.replace('_', ' ')}}}}}")



def legend(model: Model) -> list[tuple[str, str, str, str]]:
    """What the symbols of the model's inputs stand for.

    Parameters
    ----------
    model : Model
        ``derive.model.build(mode)``.

    Returns
    -------
    list of (str, str, str, str)
        Input name, its LaTeX (``i`` for a leg's), unit and description: the state, the
        platform's parameters, in paper mode the constants, and the effect parameters.
    """
    specs = STATE + PARAMETERS + (PAPER_CONSTANTS if model.mode == "paper" else ())
    rows = []
    for name, shape, unit, description in specs:
        symbol = _name(INPUT_LATEX.get(name, name))
        if shape == (3, 3):
            tex = symbol.matrix
        elif shape == (3,):
            tex = symbol.vector
        elif shape == (6, 3):
            tex = symbol.with_sub("i").vector
        else:
            tex = symbol.scalar
        rows.append((name, tex, unit, description))
    for effect in generated():
        for parameter in effect.parameters:
            full = f"{effect.name}.{parameter.name}"
            if effect.name == "payload_offset":
                tex = _name(EFFECT_NAMES["payload_offset"]).component(parameter.name)
            else:
                tex = _effect_name(full)
            rows.append((full, tex, parameter.unit, parameter.description))
    return rows
