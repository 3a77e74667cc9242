"""Entry point of the derivation: translate the model to CasADi and write generated/.

``python -m derive.build [--check]`` (or ``gsfric derive [--check]``) writes

* ``generated/gsfric_model.c`` and ``.h``: the C code of every function below;
* ``generated/gsfric_model.casadi``: the same functions serialized, for evaluation without a C
  compiler;
* ``generated/manifest.json``: hash of the derive/ sources, tool versions, each function's inputs
  and outputs with shapes and units, the effect catalog (both kinds of
  effect, ``derive/effects.py``).

Nothing written depends on the time or the machine, so regenerating is byte-identical.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import casadi as ca
import sympy

from . import coupled, envelope, simd
from . import effects as fx
from . import model as mdl
from .sources import source_hash

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
BASENAME = "gsfric_model"

# Parameters of P whose Jacobian the identification needs, followed by all of Q. The one list:
# written into the manifest (``jacobian_platform_parameters``), read by the runtime from there.
JACOBIAN_P = ("joint_viscous", "joint_coulomb", "prismatic_viscous", "prismatic_coulomb",
              "payload_mass", "platform_mass")

REACTION_OUTPUTS = ("F0", "R_E", "R_C", "M_C", "R_3", "M_3", "D", "D_dot", "u", "omega_leg",
                    "omega_rel", "s2")
FRICTION_OUTPUTS = ("MfrE", "MfrC", "Ffr", "MfrE_s", "MfrC_s", "Ffr_s")

# The combined map with the friction model fixed when deriving (``model.build``'s
# ``friction_model``), by name suffix: the runtime uses them for a platform of that model (the
# generic functions, the model read from P at every step, when P varies along a batch).
FIXED_MODELS = {"coupled": 1, "posthoc": 0}

# Functions that also get a SIMD-over-steps version (derive/simd.py): the batch hot paths (the
# generic actuator map runs only when the rows of a per-step P mix the two models).
SIMD_FUNCTIONS = ("eval", *(f"{f}_{suffix}" for suffix in FIXED_MODELS
                            for f in ("actuator", "eval", "envelope")))

# Functions whose SIMD-over-steps version is a file of its own, compiled with less
# optimisation (meson.build): the Jacobian (dF/dtheta of every parameter, the fits of discover
# and identify) is the longest body of the model, and a compiler's time on it grows much faster
# than its speed with the optimisation level.
SIMD_SEPARATE = ("jacobian",)


def _layout(specs) -> list[dict]:
    out, offset = [], 0
    for name, shape, unit, desc in specs:
        size = mdl._size(shape)
        out.append(dict(name=name, offset=offset, shape=list(shape), unit=unit,
                        description=desc))
        offset += size
    return out


def _split(sx, specs, env):
    """Map the chain's input blocks onto slices of the flat CasADi symbol ``sx``."""
    offset = 0
    for name, shape, *_ in specs:
        size = mdl._size(shape)
        env[name] = sx[offset:offset + size]
        offset += size


def _functions():
    """Every generated CasADi function, in file order, and their metadata (``_metadata``)."""
    nx = mdl.input_size(mdl.STATE)
    nP = mdl.input_size(mdl.PARAMETERS)
    q_names = fx.parameter_names()
    nQ = len(q_names)
    nK = mdl.input_size(mdl.PAPER_CONSTANTS)
    x = ca.SX.sym("x", nx)
    P = ca.SX.sym("P", nP)
    Q = ca.SX.sym("Q", nQ)
    K = ca.SX.sym("K", nK)
    specs = {"x": mdl.STATE, "P": mdl.PARAMETERS,
             "Q": tuple((n, (), "", "") for n in q_names), "K": mdl.PAPER_CONSTANTS}

    def translate(model):
        env = {}
        _split(x, mdl.STATE, env)
        _split(P, mdl.PARAMETERS, env)
        env["effects"] = Q
        if model.mode == "paper":
            _split(K, mdl.PAPER_CONSTANTS, env)
        return model.chain.to_casadi(env, model.outputs)

    out_names = [n for n, *_ in mdl.OUTPUTS]
    kin = translate(mdl.build("kinematic"))
    pap = translate(mdl.build("paper"))
    fric = mdl.build_friction()
    fric_in = {n: ca.SX.sym(n, mdl._size(s)) for n, s, *_ in mdl.FRICTION_INPUTS}
    env = dict(fric_in)
    _split(P, mdl.PARAMETERS, env)
    env["effects"] = Q
    fric_out = fric.chain.to_casadi(env, fric.outputs)

    offsets = {d["name"]: d["offset"] for d in _layout(mdl.PARAMETERS)}
    theta = ca.vertcat(*[P[offsets[n]] for n in JACOBIAN_P], Q)
    theta_names = list(JACOBIAN_P) + q_names

    funcs = [
        ca.Function(f"{BASENAME}_eval", [x, P, Q], [kin[n] for n in out_names],
                    ["x", "P", "Q"], out_names),
        ca.Function(f"{BASENAME}_eval_paper", [x, P, Q, K], [pap[n] for n in out_names],
                    ["x", "P", "Q", "K"], out_names),
        ca.Function(f"{BASENAME}_actuator", [x, P, Q], [kin["F"]], ["x", "P", "Q"], ["F"]),
        ca.Function(f"{BASENAME}_reactions", [x, P, Q], [kin[n] for n in REACTION_OUTPUTS],
                    ["x", "P", "Q"], list(REACTION_OUTPUTS)),
        ca.Function(f"{BASENAME}_friction", list(fric_in.values()) + [P, Q],
                    [fric_out[n] for n in FRICTION_OUTPUTS],
                    list(fric_in) + ["P", "Q"], list(FRICTION_OUTPUTS)),
        ca.Function(f"{BASENAME}_jacobian", [x, P, Q],
                    [kin["F"], ca.densify(ca.jacobian(kin["F"], theta))], ["x", "P", "Q"], ["F", "dF"]),
    ]
    for suffix, model in FIXED_MODELS.items():
        fixed = translate(mdl.build("kinematic", friction_model=model))
        funcs += [
            ca.Function(f"{BASENAME}_eval_{suffix}", [x, P, Q], [fixed[n] for n in out_names],
                        ["x", "P", "Q"], out_names),
            ca.Function(f"{BASENAME}_actuator_{suffix}", [x, P, Q], [fixed["F"]],
                        ["x", "P", "Q"], ["F"]),
            envelope.function(f"{BASENAME}_envelope_{suffix}", fixed, x, P, Q),
        ]
    return funcs, _metadata(specs, theta_names)


def _metadata(specs: dict, theta_names: list[str]) -> dict:
    """What the manifest records of the functions' inputs and outputs.

    Returns
    -------
    dict
        ``specs`` (input name -> its blocks), ``shapes``, ``units``, ``descriptions`` (output or
        friction input name -> shape list, unit, text), ``theta`` (the Jacobian's parameters)
        and ``rows`` (output name -> the names of its rows, where they have names).
    """
    shapes = {n: list(s) for n, s, *_ in mdl.OUTPUTS}
    units = {n: u for n, _, u, _ in mdl.OUTPUTS}
    descs = {n: d for n, _, _, d in mdl.OUTPUTS}
    for n, s, u, d in mdl.FRICTION_INPUTS:
        shapes.setdefault(n, list(s))
        units.setdefault(n, u)
        descs.setdefault(n, d)
    shapes.update(envelope.SHAPES)
    units.update(envelope.UNITS)
    descs.update(envelope.DESCRIPTIONS)
    shapes["dF"] = [6, len(theta_names)]
    units["dF"] = "N per unit of each parameter"
    descs["dF"] = "Jacobian of F with respect to theta (see jacobian_parameters)"
    return dict(specs=specs, shapes=shapes, units=units, descriptions=descs, theta=theta_names,
                rows=envelope.ROW_NAMES)


def generate(out_dir: Path = GENERATED) -> dict[str, bytes]:
    """Derive, translate and return the generated files (nothing written).

    Parameters
    ----------
    out_dir : Path
        Where a temporary directory for CasADi's code generator is made (and removed).

    Returns
    -------
    dict of str -> bytes
        File name in generated/ -> its content (C, header, serialized functions, batch C,
        manifest.json); identical on every run.
    """
    funcs, meta = _functions()
    files = _code_files(funcs, out_dir)
    files["manifest.json"] = (json.dumps(_manifest(funcs, meta, files), indent=2) + "\n").encode()
    return files


def _code_files(funcs: list, out_dir: Path) -> dict[str, bytes]:
    """The C source and header, the serialized functions and the batch C of ``funcs``.

    CasADi's code generator and serializer write into a temporary directory in ``out_dir``,
    removed afterwards.
    """
    tmp = out_dir / f".{BASENAME}.tmp"
    tmp.mkdir(parents=True, exist_ok=True)
    try:
        cg = ca.CodeGenerator(f"{BASENAME}.c", {"with_header": True, "casadi_int": "long long int",
                                                "with_mem": False})
        for f in funcs:
            cg.add(f)
        cg.generate(str(tmp) + "/")
        files = {f"{BASENAME}.c": (tmp / f"{BASENAME}.c").read_bytes(),
                 f"{BASENAME}.h": (tmp / f"{BASENAME}.h").read_bytes()}
        ser = ca.FileSerializer(str(tmp / f"{BASENAME}.casadi"))
        for f in funcs:
            ser.pack(f)
        del ser
        files[f"{BASENAME}.casadi"] = (tmp / f"{BASENAME}.casadi").read_bytes()
        files[f"{BASENAME}_batch.c"] = simd.batch_file(
            [f for f in funcs if f.name() in {f"{BASENAME}_{n}" for n in SIMD_FUNCTIONS}],
            on_request=mdl.ON_REQUEST).encode()
        for name in SIMD_SEPARATE:
            files[f"{BASENAME}_{name}_batch.c"] = simd.batch_file(
                [f for f in funcs if f.name() == f"{BASENAME}_{name}"], probes=False).encode()
    finally:
        for p in tmp.glob("*"):
            p.unlink()
        tmp.rmdir()
    return files


def _io(f, kind: str, meta: dict) -> list[dict]:
    """The manifest's entries for the inputs (``kind`` "in") or outputs ("out") of function f."""
    names = f.name_in() if kind == "in" else f.name_out()
    sizes = [f.numel_in(i) if kind == "in" else f.numel_out(i) for i in range(len(names))]
    items = []
    for name, size in zip(names, sizes):
        item = dict(name=name, size=size)
        if kind == "in" and name in meta["specs"]:
            item["layout"] = _layout(meta["specs"][name])
        else:
            item.update(shape=meta["shapes"].get(name, [size]),
                        unit=meta["units"].get(name, ""),
                        description=meta["descriptions"].get(name, ""))
            if name in meta["rows"]:
                item["rows"] = list(meta["rows"][name])
        items.append(item)
    return items


def _manifest(funcs: list, meta: dict, files: dict[str, bytes]) -> dict:
    """manifest.json's content: the derivation's source hash, the tools, the files' hashes, the
    functions' inputs and outputs (``_metadata``), the coupled solve's iteration count, the
    Jacobian's parameters and the effects."""
    return dict(
        generator="derive/build.py",
        source_hash=source_hash(),
        tools=dict(casadi=ca.__version__, sympy=sympy.__version__,
                   python=".".join(map(str, sys.version_info[:2]))),
        files={n: hashlib.sha256(b).hexdigest() for n, b in sorted(files.items())},
        functions=[dict(name=f.name(), inputs=_io(f, "in", meta), outputs=_io(f, "out", meta),
                        n_instructions=f.n_instructions(),
                        simd=f.name() in {f"{BASENAME}_{n}" for n in SIMD_FUNCTIONS})
                   for f in funcs],
        simd_lanes=simd.LANES,
        coupled_iterations=coupled.N_ITERATIONS,
        jacobian_parameters=meta["theta"],
        jacobian_platform_parameters=list(JACOBIAN_P),
        effects=[dict(name=e.name, description=e.description, term=e.term, kind=e.kind,
                      parameters=[dict(name=p.name, default=p.default, unit=p.unit,
                                       description=p.description) for p in e.parameters])
                 for e in fx.CATALOG],
    )


def write(files: dict[str, bytes], out_dir: Path = GENERATED) -> None:
    """Write ``generate()``'s files into ``out_dir``, each to a temporary name then renamed;
    a file whose bytes are already those is left alone (its time too: the build recompiles
    only the C that changed).

    Parameters
    ----------
    files : dict of str -> bytes
    out_dir : Path
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        target = out_dir / name
        if target.exists() and target.read_bytes() == data:
            continue
        tmp = out_dir / f".{name}.tmp"
        tmp.write_bytes(data)
        tmp.replace(target)


def is_stale(out_dir: Path = GENERATED) -> str | None:
    """A one-line reason why generated/ does not match derive/, or None when it matches.

    Parameters
    ----------
    out_dir : Path
        The generated/ directory.

    Returns
    -------
    str or None
    """
    path = out_dir / "manifest.json"
    if not path.exists():
        return f"{path} is missing"
    try:
        manifest = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        return f"{path} is not valid JSON ({exc})"
    if manifest.get("source_hash") != source_hash():
        return "derive/ changed since generated/ was written"
    for name, digest in manifest.get("files", {}).items():
        f = out_dir / name
        if not f.exists() or hashlib.sha256(f.read_bytes()).hexdigest() != digest:
            return f"generated/{name} does not match the manifest"
    return None


def main(argv=None) -> int:
    """``python -m derive.build [--check]``; returns the exit status (0, or 1 when stale)."""
    parser = argparse.ArgumentParser(prog="derive.build", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="exit 1 when generated/ is stale instead of regenerating")
    args = parser.parse_args(argv)
    if args.check:
        reason = is_stale()
        if reason:
            print(f"generated/ is stale: {reason}; run `gsfric derive`", file=sys.stderr)
            return 1
        print("generated/ is up to date")
        return 0
    write(generate())
    print(f"wrote {GENERATED}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
