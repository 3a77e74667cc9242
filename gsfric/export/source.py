"""The C text an export copies: generated functions made static, helpers, the step flags.

Every piece is cut from the committed sources by a deterministic text transformation:

* a generated function ``gsfric_model_<name>`` of generated/gsfric_model.c: CasADi's body
  (``casadi_fN``) under the name ``<prefix>_<name>``, ``static``, with the signature
  ``(const casadi_real** arg, casadi_real** res)`` (the functions an export carries need no
  work arrays and no memory: that is checked, see ``generated_function``);
* the CasADi helpers the body calls (``casadi_sq``, ``casadi_fmax``, ...), made ``static``;
* the step flags of gsfric/compiled/batch.c (the block between its ``step flags: begin`` and
  ``step flags: end`` lines), so that the library flags a step as ``gsfric simulate`` does.
"""

from __future__ import annotations

import functools
import importlib.resources
import re
from dataclasses import dataclass

from gsfric.compiled.manifest import BASENAME, function, generated_dir
from gsfric.errors import GsfricError
from gsfric.evaluation import flags

_FLAG_BEGIN = "/* step flags: begin"
_FLAG_END = "/* step flags: end */"



@dataclass(frozen=True)
class GeneratedFunction:
    """One generated function as the export carries it.

    Attributes
    ----------
    name : str
        The C name in the export (``<prefix>_<name>``).
    text : str
        Its definition: a ``static int`` function of ``(arg, res)``.
    helpers : tuple of str
        The CasADi helpers it calls (``casadi_sq``, ...), in the order of the generated file.
    """

    name: str
    text: str
    helpers: tuple[str, ...]


@functools.lru_cache(maxsize=None)
def _model_source() -> str:
    path = generated_dir() / f"{BASENAME}.c"
    try:
        return path.read_text()
    except FileNotFoundError:
        raise GsfricError(f"{path} is missing: run `gsfric derive`") from None


def _helper_definitions(source: str) -> dict[str, str]:
    """CasADi's helper functions of the generated file: name -> definition (not static)."""
    found = {}
    pattern = re.compile(r"^casadi_real (casadi_\w+)\((?:[^\n]*\}$|.*?^\})", re.M | re.S)
    for match in pattern.finditer(source):
        found[match.group(1)] = match.group(0)
    return found


def _body(source: str, full_name: str) -> tuple[str, str]:
    """(CasADi's internal name, its definition) of generated function ``full_name``."""
    wrapper = re.search(rf"^CASADI_SYMBOL_EXPORT int {full_name}\(.*?\{{\n\s*return "
                        r"(casadi_f\d+)\(arg, res, iw, w, mem\);", source, re.M)
    if wrapper is None:
        raise GsfricError(f"generated/{BASENAME}.c has no function {full_name}; "
                          "run `gsfric derive`")
    internal = wrapper.group(1)
    body = re.search(rf"^static int {internal}\(const casadi_real\*\* arg, casadi_real\*\* res, "
                     r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n.*?^\}\n", source,
                     re.M | re.S)
    if body is None:
        raise GsfricError(f"generated/{BASENAME}.c: the body of {full_name} ({internal}) "
                          "was not found")
    return internal, body.group(0)


def generated_function(name: str, prefix: str) -> GeneratedFunction:
    """Generated function ``gsfric_model_<name>`` as ``static int <prefix>_<name>(arg, res)``.

    Raises ``GsfricError`` when the function is missing or needs work arrays or memory
    (the export calls it without them) or calls another generated function.
    """
    entry = function(name)
    source = _model_source()
    internal, text = _body(source, entry["name"])
    head, rest = text.split("\n", 1)
    if re.search(r"\b(iw|w|mem|casadi_f\d+)\b", rest):
        raise GsfricError(f"{entry['name']} uses work arrays, memory or other functions: "
                          "the export cannot carry it")
    exported = f"{prefix}_{name}"
    head = f"static int {exported}(const casadi_real** arg, casadi_real** res) {{"
    helpers = helpers_called(rest)
    comment = f"/* {exported}: {entry['name']} of generated/{BASENAME}.c */\n"
    return GeneratedFunction(exported, comment + head + "\n" + rest, helpers)


def helpers_called(c_text: str) -> tuple[str, ...]:
    """The CasADi helpers of the generated file that ``c_text`` calls, in the file's order."""
    return tuple(h for h in _helper_definitions(_model_source())
                 if re.search(rf"\b{h}\(", c_text))


def helper_text(names) -> str:
    """The definitions of the CasADi helpers ``names``, each made ``static``."""
    found = _helper_definitions(_model_source())
    return "\n\n".join("static " + found[name] for name in names)


@functools.lru_cache(maxsize=None)
def flag_block() -> str:
    """The step-flag block of gsfric/compiled/batch.c (bits, ``gsfric_flags``, ``step_flags``),
    verbatim; ``GsfricError`` if its bits differ from ``gsfric.evaluation.flags``."""
    text = importlib.resources.files("gsfric.compiled").joinpath("batch.c").read_text()
    try:
        start = text.index(_FLAG_BEGIN)
        stop = text.index(_FLAG_END) + len(_FLAG_END)
    except ValueError:
        raise GsfricError("gsfric/compiled/batch.c has no step-flag block") from None
    block = text[start:stop]
    for name, bit in flags.FLAG_BITS.items():
        if not re.search(rf"^#define FLAG_{name} {bit}$", block, re.M):
            raise GsfricError(f"gsfric/compiled/batch.c: FLAG_{name} is not {bit} as in "
                              "gsfric.evaluation.flags")
    return block
