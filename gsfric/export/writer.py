"""Writing an export: the folder of a self-contained C library for one platform.

``export_library`` checks what the platform asks of the library, fills the templates of this
package (``templates/*.in``: ``@name@`` placeholders) and writes the folder atomically
(``gsfric.io.files.output_folder``). The model's C comes from ``templates/model_<code>.c.in``
filled with the build ``code`` (``CODES``). The folder is a function of the platform, the
model, the prefix, the build and the committed generated code only: no timestamps, so an
export is reproducible.
"""

from __future__ import annotations

import importlib.resources
import json
import re
import textwrap
from dataclasses import dataclass
from pathlib import Path

from gsfric.compiled.manifest import layout, manifest
from gsfric.compiled.state import state_layout
from gsfric.errors import GsfricError, InputError
from gsfric.evaluation import flags
from gsfric.evaluation.flags import flag_spec
from gsfric.evaluation.parameters import effect_vector, model_function, parameter_vector
from gsfric.export import folded, source, text
from gsfric.io.files import output_folder
from gsfric.platform.catalog import GENERATED_EFFECTS, SENSOR_EFFECTS, sensor_parameters
from gsfric.platform.description import Platform

MODELS = ("coupled", "paper")
CODES = ("specialised", "generic")
"""The builds of the model: the platform folded into the code (``gsfric.export.folded``), or
CasADi's generated function of every platform with the parameters as data."""
STEP_OUTPUTS = ("F", "F0", "D", "s2", "h", "coupling_change")
"""The outputs ``<prefix>_actuator_forces`` computes: F and what the step flags read."""
_CODE_TEXT = {
    "specialised": "has them folded into its code (every value that depends on the platform "
                   "alone computed when exported)",
    "generic": "reads them from there at every call",
}
_PARAMETERS_NOTE = {
    "specialised": "The specialised build has P and Q folded\n * into its code: they are "
                   "here for the record (changing them changes nothing; export again).",
    "generic": "The generic build reads P and Q from these values.",
}
CFLAGS = ("-O2", "-std=c99", "-Wall", "-Wextra", "-pedantic")
"""The Makefile's default flags (``--verify`` builds with them too)."""
PLATFORM_FILE = "platform.toml"
"""The platform as exported (its friction model set), for ``--verify`` and for the record."""
MANIFEST_FILE = "manifest.json"
"""What the folder holds (``Export.manifest``): the library ``--verify`` checks."""
FILES = {"library.h.in": "{prefix}.h", "library.c.in": "{prefix}.c",
         "example.c.in": "example.c", "Makefile.in": "Makefile",
         "CMakeLists.txt.in": "CMakeLists.txt", "README.md.in": "README.md"}
"""Template -> file name in the export."""

_C_RESERVED = {"auto", "break", "case", "char", "const", "continue", "default", "do", "double",
               "else", "enum", "extern", "float", "for", "goto", "if", "inline", "int", "long",
               "register", "restrict", "return", "short", "signed", "sizeof", "static",
               "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while",
               "_Bool", "_Complex", "_Imaginary", "_Alignas", "_Alignof",
               "_Atomic", "_Generic", "_Noreturn", "_Static_assert", "_Thread_local", "bool",
               "true", "false", "alignas", "alignof", "constexpr", "nullptr", "static_assert",
               "thread_local", "typeof", "typeof_unqual"}
"""C keywords (C99 to C23)."""

_OWN_NAMES = {"example", "main"}
"""The export's own names: its example program (example.c) and the program's entry point."""

_C_HEADERS = {"assert", "complex", "ctype", "errno", "fenv", "float", "inttypes", "iso646",
              "limits", "locale", "math", "setjmp", "signal", "stdalign", "stdarg",
              "stdatomic", "stdbit", "stdbool", "stdckdint", "stddef", "stdint", "stdio",
              "stdlib", "stdnoreturn", "string", "tgmath", "threads", "time", "uchar", "wchar",
              "wctype"}
"""The C standard's headers (C99 to C23): ``<prefix>.h`` of one of these names, beside the
code, would be included instead of the system's (``#include <math.h>`` searches the
including file's folder first with many compilers' -I.)."""

_BUILD_NAMES = {"all", "clean", "help", "install", "test", "package", "package_source",
                "depend", "edit_cache", "rebuild_cache", "list_install_components",
                "install_strip", "install_local", "preinstall", "all_build", "zero_check",
                "run_tests", "m", "c"}
"""Names the build files cannot give the library: make's and CMake's reserved targets
(compared case-insensitively: ALL_BUILD, ZERO_CHECK on Visual Studio) and the C and maths
libraries that ``lib<prefix>.a`` would shadow (libc, libm)."""


@dataclass(frozen=True)
class Export:
    """What ``export_library`` wrote.

    Attributes
    ----------
    folder : Path
        The export's folder.
    prefix : str
        The C prefix of every public name (``<prefix>_evaluate``, ``<prefix>.h``).
    model : str
        The friction model, "coupled" or "paper".
    code : str
        The build of the model, "specialised" or "generic" (``CODES``).
    function : str
        The generated function the library carries (e.g. ``eval_coupled``).
    iterations : int
        The coupled model's fixed-point iterations (0: the paper's model, none).
    """

    folder: Path
    prefix: str
    model: str
    code: str
    function: str
    iterations: int

    def manifest(self) -> dict:
        """The folder's ``manifest.json``: the library's prefix, model, build, generated
        function, fixed-point iterations, and the files written."""
        files = sorted([*(t.format(prefix=self.prefix) for t in FILES.values()), PLATFORM_FILE,
                        MANIFEST_FILE])
        return {"generator": "gsfric export", "prefix": self.prefix, "model": self.model,
                "code": self.code, "function": self.function,
                "coupled_iterations": self.iterations, "files": files}


def check_prefix(prefix: str) -> str:
    """``prefix`` when it is a C identifier usable as the library's prefix, else ``InputError``."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", prefix or "") or prefix in _C_RESERVED:
        raise InputError(f"--prefix: {prefix!r} is not a C identifier (letters, digits and _, "
                         "not starting with a digit, not a C keyword)")
    why = ("the C standard header <{0}.h>, which {0}.h would hide" if prefix.lower() in
           _C_HEADERS else "a make or CMake target or system library name" if prefix.lower()
           in _BUILD_NAMES else "reserved in C: names at file scope that start with _"
           if prefix.startswith("_") else "the example program's (example.c, main)"
           if prefix in _OWN_NAMES else
           "gsfric's own" if prefix.lower() == "gsfric_model" else "")
    if why:
        raise InputError(f"--prefix: {prefix!r} is reserved ({why.format(prefix.lower())}); "
                         "choose another C identifier")
    return prefix


def check_effects(platform: Platform) -> None:
    """``InputError`` (one line, naming it) for an effect the exported step cannot apply.

    Every generated effect is an input of the generated code and ``force_scale`` is a gain on
    F; ``time_offset`` delays F along a time series, which one step does not have.
    """
    carried = set(GENERATED_EFFECTS) | {"force_scale"}
    for name, params in platform.effects.items():
        if name == "time_offset":
            if any(v != SENSOR_EFFECTS[name][p] for p, v in params.items()):
                raise InputError("effects.time_offset: a delay of the force readings acts on a "
                                 "time series, not on one step; the export cannot carry it "
                                 "(remove it from the platform file, or delay F in the "
                                 "controller)")
        elif name not in carried:
            kind = "sensor " if name in SENSOR_EFFECTS else ""
            raise InputError(f"effects.{name}: the export does not support this {kind}effect")


def coupled_iterations(model: str) -> int:
    """The coupled model's fixed-point iterations unrolled in the generated code, as the
    manifest records them (0 for the paper's model)."""
    if model != "coupled":
        return 0
    found = manifest().get("coupled_iterations")
    if found is None:
        raise GsfricError("generated/manifest.json does not record the coupled solve's "
                          "iterations; run `gsfric derive`")
    return int(found)


def _iterations_text(model: str, iterations: int) -> str:
    if model != "coupled":
        return "The paper's friction model: no fixed-point iterations."
    return (f"The coupled friction model's fixed point is solved by {iterations} iterations, "
            "unrolled in the generated code.")


def _platform_file_text(platform: Platform, platform_file: Path | None) -> tuple[str, str]:
    """(name, text) of the platform file for the header's comment (the reference platform's
    TOML when there is no file)."""
    if platform_file is None:
        return "the reference platform", "(gsfric.reference_platform(): no platform file)"
    return f"the platform file {Path(platform_file).name}", Path(platform_file).read_text()


def _model_code(platform: Platform, name: str, prefix: str, code: str) -> str:
    """The C of the model (``run`` and ``run_step``) in build ``code``, from its template."""
    outs = [o.name for o in text.outputs(name)]
    if code == "generic":
        generated = source.generated_function(name, prefix)
        values = {"function": generated.name, "generated": generated.text,
                  "helpers": source.helper_text(generated.helpers)}
    else:
        body = folded.statements(folded.folded_function(name, platform, outs),
                                 [f"OUT_{o}" for o in outs])
        run = folded.function_text(body, "run")
        step = folded.function_text(body, "run_step", {outs.index(o) for o in STEP_OUTPUTS})
        helpers = source.helpers_called(run)
        missing = sorted(set(re.findall(r"\b(casadi_\w+)\(", run)) - set(helpers))
        if missing:
            raise GsfricError(f"the specialised build calls {missing[0]}, which generated/ "
                              "does not define; export with --code generic")
        values = {"function": name, "run": run, "run_step": step,
                  "helpers": source.helper_text(helpers)}
    values["PREFIX"] = prefix.upper()
    template = importlib.resources.files("gsfric.export").joinpath("templates",
                                                                    f"model_{code}.c.in")
    return _fill(template.read_text(), values)


def _values(platform: Platform, platform_file, model: str, prefix: str,
            code: str) -> dict[str, str]:
    """Every placeholder of the templates."""
    name = model_function("eval", model)
    outs = text.outputs(name)
    gains, _ = sensor_parameters(platform.effects)
    iterations = coupled_iterations(model)
    platform_name, platform_text = _platform_file_text(platform, platform_file)
    state = [(b["offset"], b["shape"], b.get("unit") or "1", b["name"], b["description"])
             for b in layout("eval", "x")]
    return {
        "prefix": prefix, "PREFIX": prefix.upper(), "cflags": " ".join(CFLAGS), "model": model,
        "function": name, "code": code, "parameters_note": _PARAMETERS_NOTE[code],
        "code_text": _CODE_TEXT[code],
        "model_code": _model_code(platform, name, prefix, code),
        "platform_name": platform_name, "platform_comment": text.comment(platform_text),
        "iterations": str(iterations),
        "iterations_text": _iterations_text(model, iterations),
        "iterations_comment": text.comment(textwrap.fill(_iterations_text(model, iterations),
                                                         92)),
        "state_size": str(state_layout().size), "state_macros": text.state_macros(prefix),
        "legs": str(next(o.size for o in outs if o.name == "F")),
        "flag_macros": text.flag_macros(prefix),
        "n_parameters": str(parameter_vector(platform).size),
        "parameters": text.initializer("eval", "P", parameter_vector(platform)),
        "n_effects": str(effect_vector(platform).size),
        "effects": text.initializer("eval", "Q", effect_vector(platform)),
        "gains": "{" + ", ".join(text.number(1.0 + g, "force_scale") for g in gains) + "}",
        "output_fields": "\n".join(o.declaration() for o in outs),
        "output_indices": "\n".join([f"#define N_OUT {len(outs)}"] +
                                    [f"#define OUT_{o.name} {o.index}" for o in outs]),
        "output_sizes": "{" + ", ".join(str(o.size) for o in outs) + "}",
        "output_pointers": "\n".join(f"    res[OUT_{o.name}] = {o.pointer('out')};"
                                     for o in outs),
        "flag_block": source.flag_block(),
        "flag_settings": text.flag_settings(flag_spec([(o.name, o.size, o.shape) for o in outs],
                                                      platform.geometry.stroke)),
        "state_table": "\n".join(f"| {o} | {'x'.join(map(str, s))} | {u} | {n}: {d} |"
                                 for o, s, u, n, d in state),
        "flag_table": "\n".join(f"| {bit} `{prefix.upper()}_FLAG_{key}` | "
                                f"{flags.FLAG_NAMES[bit]} |"
                                for key, bit in flags.FLAG_BITS.items()),
    }


def _fill(template: str, values: dict[str, str]) -> str:
    return re.sub(r"@(\w+)@", lambda m: values[m.group(1)] if m.group(1) in values
                  else m.group(0), template)


def libraries(folder: Path) -> list[str]:
    """The prefixes of the libraries written by ``gsfric export`` in ``folder`` (a header
    ``<prefix>.h`` defining ``<PREFIX>_MODEL`` beside its ``<prefix>.c``)."""
    found = []
    for header in sorted(folder.glob("*.h")):
        model = re.search(r'^#define (\w+)_MODEL "(\w+)"$', header.read_text(errors="replace"),
                          re.M)
        if model and model.group(1) == header.stem.upper() and \
                (folder / f"{header.stem}.c").is_file():
            found.append(header.stem)
    return found


def export_library(platform: Platform, out, model: str | None = None, prefix: str = "gsfric",
                   platform_file=None, code: str = "specialised") -> Export:
    """Write the C library of ``platform`` into the folder ``out`` (atomically).

    Parameters
    ----------
    platform : Platform
    out : path-like
        The folder (created; files of the same names in an existing folder are replaced;
        a folder holding another prefix's library is refused).
    model : {"coupled", "paper"} or None
        The friction model (None: the platform's own, ``friction.model``).
    prefix : str
        A C identifier: the library's header ``<prefix>.h`` and the prefix of its names.
    platform_file : path-like, optional
        The platform's file, copied into the header's first comment.
    code : {"specialised", "generic"}
        The build of the model: the platform folded into straight-line code (fast; needs
        casadi when exporting), or CasADi's generated function reading the parameters.
    """
    check_prefix(prefix)
    others = [p for p in libraries(Path(out)) if p != prefix] if Path(out).is_dir() else []
    if others:
        raise InputError(f"--out: {out} holds the library {others[0]!r} ({others[0]}.h); "
                         f"export {prefix!r} into a folder of its own (--verify checks one "
                         "library a folder)")
    model = platform.friction.model if model is None else model
    if model not in MODELS:
        raise InputError(f"--model: {model!r} is not one of {', '.join(MODELS)}")
    if code not in CODES:
        raise InputError(f"--code: {code!r} is not one of {', '.join(CODES)}")
    if model != platform.friction.model:
        platform = platform.with_friction(model=model)
    check_effects(platform)
    values = _values(platform, platform_file, model, prefix, code)
    written = Export(Path(out), prefix, model, code, model_function("eval", model),
                     coupled_iterations(model))
    templates = importlib.resources.files("gsfric.export").joinpath("templates")
    with output_folder(out, inputs={"platform": platform_file}) as tmp:
        for template, target in FILES.items():
            content = _fill(templates.joinpath(template).read_text(), values)
            (tmp / target.format(prefix=prefix)).write_text(content)
        platform.to_toml(tmp / PLATFORM_FILE)
        (tmp / MANIFEST_FILE).write_text(json.dumps(written.manifest(), indent=2) + "\n")
    return written
