"""The identification's budget: ``excite`` for 60 s at 500 Hz, then ``identify`` on the 30,000
samples of a record made along it with the reference platform as the truth, force noise 0.5 %
of the static load, started from a wrong prior (platform 12 kg instead of 10, upper leg part
0.9 kg instead of 0.7, prismatic mu 0.05 instead of 0.1, seal 1 N instead of 2).

Prints the CPU and wall seconds of each (CPU of this process: what other load on the machine
disturbs least; run it on one core with ``taskset -c 0``), and each parameter's estimate, its
relative standard deviation and its error in standard deviations::

    taskset -c 0 python benchmarks/identify_budget.py
"""

from __future__ import annotations

import time

import gsfric
from gsfric.identification import excite
from gsfric.identification.parameters import parameter_set
from gsfric.models import reference_platform
from gsfric.synth import synthesize

SAMPLES = 30_000


def _timed(call):
    c0, t0 = time.process_time(), time.perf_counter()
    out = call()
    return out, time.process_time() - c0, time.perf_counter() - t0


def main() -> None:
    true = reference_platform()
    prior = true.with_body(mass=12.0).with_legs(upper_mass=0.9).with_friction(
        prismatic_coulomb=0.05, prismatic_seal=1.0)
    design, cpu, wall = _timed(lambda: excite(true, duration=60.0, rate=500.0))
    print(f"excite 60 s at 500 Hz: {cpu:.1f} s CPU, {wall:.1f} s wall; condition number "
          f"{design.condition:.4g} (plain sinusoid {design.sinusoid_condition:.4g}); force "
          f"noise {design.force_noise:.4g} N")
    data = synthesize(true, motion=design.motion.slice(0, SAMPLES), noise=design.force_noise,
                      seed=7)
    forces = data.frame.filter(regex="^F").to_numpy()
    result, cpu, wall = _timed(lambda: gsfric.identify(data.motion, forces, prior))
    print(f"identify {len(forces)} samples: {cpu:.1f} s CPU, {wall:.1f} s wall, "
          f"{result.evaluations} residual evaluations")
    print(result.statement())
    truth = parameter_set(true)
    for name, value in zip(truth.names, truth.prior):
        e = result.parameters[name]
        rel = "" if e.rel_std is None or value == 0 else f"{100 * e.std / abs(value):7.3g} %"
        z = "" if e.std is None else f"{(e.value - value) / e.std:+.2f}"
        print(f"  {name:30s} true {value:9.4g}  estimate {e.value:10.5g}  rel std {rel:>9s}  "
              f"error/std {z}")


if __name__ == "__main__":
    main()
