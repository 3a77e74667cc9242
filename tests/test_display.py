"""The equations notebook's LaTeX (derive/display/): every quantity of every equation group
has a proper LaTeX name, and every vector definition is one equation between vectors."""

from __future__ import annotations

import re

import pytest

sp = pytest.importorskip("sympy")

from derive import display  # noqa: E402
from derive.model import build  # noqa: E402

pytestmark = pytest.mark.integration  # end to end: `make check` leaves it out

GARBAGE = [
    (re.compile(r"[A-Za-z]+_[A-Za-z]+_[A-Za-z]"), "a Python name (M_rot_alpha)"),
    (re.compile(r"_rot_"), "a Python name"),
    (re.compile(r"I_\{[A-Z0-9]+,\d\d"), "a matrix entry with its body as subscript (I_{L,11})"),
    (re.compile(r"\\left\(I_"), "a sum of matrix entries where a matrix belongs"),
    (re.compile(r"\\(?:dot|ddot)\{[^{}]*,"), "a leg number inside an accent"),
    (re.compile(r"\^\{[^{}]*\}\^"), "a double superscript"),
    (re.compile(r"_\{[^{}]*\}_"), "a double subscript"),
]


@pytest.fixture(scope="module", params=["kinematic", "paper"])
def model(request):
    return build(request.param)


def _balanced(tex: str) -> bool:
    depth = 0
    for ch in tex.replace(r"\{", "").replace(r"\}", ""):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        if depth < 0:
            return False
    return depth == 0 and tex.count(r"\left") == tex.count(r"\right")


def _check(tex: str, where: str) -> None:
    assert _balanced(tex), f"{where}: unbalanced: {tex[:200]}"
    for pattern, what in GARBAGE:
        found = pattern.search(tex)
        assert not found, f"{where}: {what}: ...{tex[max(0, found.start() - 40):found.end() + 40]}"


@pytest.mark.parametrize("group", display.GROUPS)
def test_every_group_is_written_with_proper_names(model, group):
    lines = display.equations(model, group)
    assert lines, group
    for line in lines:
        _check(line, f"{model.mode} {group}")
        lhs = line.split(" = ")[0]
        assert not lhs.startswith(r"\begin{pmatrix}"), f"{group}: by components: {line[:120]}"


def test_every_symbol_has_a_name(model):
    names = display.symbol_names(model)
    chain = model.chain
    symbols = [s for block in chain.inputs.values() for s in block]
    symbols += [t for step in chain.steps for t in step.targets]
    assert not [s for s in symbols if s not in names]
    for symbol, tex in names.items():
        _check(tex, str(symbol))


def test_vectors_are_written_as_derive_builds_them():
    model = build("kinematic")
    assert display.equations(model, "1")[0] == r"\mathbf{r}_{M} = T \mathbf{c}_{M}"
    assert display.equations(model, "8-10") == [
        r"D_{1} = \left|\mathbf{E}_{1} - \mathbf{C}_{1}\right|",
        r"\mathbf{u}_{1} = \frac{\mathbf{E}_{1} - \mathbf{C}_{1}}{D_{1}}"]
    lines = display.equations(model, "2-7")
    assert r"\boldsymbol{\alpha}^{b} = T^{T} \boldsymbol{\alpha}" in lines
    assert any(line.startswith(r"\mathbf{M}_{rot} = T \left(\left(I^{L} + I^{M}\right)")
               for line in lines)
    assert (r"\mathbf{M}_{rot2,1} = \left[\mathbf{a}_{2,1}\;\mathbf{b}_{1}\;\mathbf{u}_{1}\right]"
            r" \mathbf{M}_{rot2,1}^{leg}") in display.equations(model, "17")
    assert display.equations(model, "8-10", leg=3)[0] == \
        r"D_{3} = \left|\mathbf{E}_{3} - \mathbf{C}_{3}\right|"


def test_components_only_on_request():
    model = build("kinematic")
    short = display.equations(model, "8-10")
    full = display.equations(model, "8-10", expand=True)
    assert len(full) == len(short) + 1
    assert full[-1].startswith(r"\begin{pmatrix} u_{1,x} \\ u_{1,y} \\ u_{1,z} \end{pmatrix} = ")
    assert len(display.equations(model, "coupled", iterates=True)) > \
        len(display.equations(model, "coupled"))


@pytest.mark.parametrize("group", sorted(display.GROUP_RANGES))
def test_the_papers_printed_forms_and_errata(group):
    forms = display.printed(group)
    listed = display.errata(group)
    assert bool(forms) == bool(listed) or group == "1", group
    for label, tex in forms:
        assert re.fullmatch(r"\(\d+(?:-\d+)?\)(?:-\(\d+\))?", label), label
        assert _balanced(tex), (group, label)
    assert all(e.id.startswith("E") for e in listed)


def test_the_legend_names_every_input():
    rows = display.legend(build("paper"))
    names = {row[0] for row in rows}
    assert {"position", "payload_inertia", "joint_speed", "payload_offset.x"} <= names
    for _, tex, _, _ in rows:
        _check(tex, "legend")
