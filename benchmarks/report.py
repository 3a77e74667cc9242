"""The report of ``gsfric bench``: what one run measured, the targets, and its plain-text table."""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmarks.cases import Case, ratio
from benchmarks.simulate import SIMULATE_STEPS

TARGETS = {
    "compiled_1e5_steps_per_s": ("compiled map, one core, N = 1e5", ">=", 1e6, "steps/s"),
    "speedup_vs_numpy": ("compiled (one core) / vectorised NumPy, N = 1e5", ">=", 10.0, "x"),
    "speedup_vs_loop": ("compiled (one core) / per-step loop, N = 1e5", ">=", 500.0, "x"),
    "latency_40_us": ("one call of 40 steps (median)", "<=", 50.0, "us"),
    "two_core_speedup_1e6": ("two cores / one core, N = 1e6", ">=", 1.7, "x"),
    "import_s": ("import gsfric, fresh interpreter (median)", "<=", 0.3, "s"),
    "evaluate_1e5_steps_per_s": ("gsfric.evaluate (kept outputs + flags), one core, N = 1e5",
                                 ">=", 2e6, "steps/s"),
    "evaluate_vs_numpy": ("gsfric.evaluate / vectorised NumPy actuator map, N = 1e5", ">=",
                          6.0, "x"),
    "control_loop_40_us": ("README control loop: new Evaluator + forces(), 40 steps (median)",
                           "<=", 20.0, "us"),
    "busy_two_vs_one": ("two threads / one thread with the other core busy, N = 1e3 and 1e5 "
                        "(worst)", ">=", 1.0, "x"),
    "evaluate_memory_1e6_gib": ("gsfric.evaluate at N = 1e6, peak memory added", "<=", 2.3,
                                "GiB"),
    "simulate_steps_per_s": (f"gsfric simulate to Parquet, default columns, N = "
                             f"{SIMULATE_STEPS:.0e} (wall clock, end to end)", ">=", 5e5,
                             "steps/s"),
    "simulate_peak_gb": (f"gsfric simulate, N = {SIMULATE_STEPS:.0e}, peak RSS", "<=", 1.0,
                         "GB"),
}


@dataclass
class Report:
    """Everything one run measured, with the machine and the command."""

    command: str
    machine: dict
    cases: list[Case] = field(default_factory=list)
    import_time: dict = field(default_factory=dict)
    paths: dict = field(default_factory=dict)
    ratios: dict = field(default_factory=dict)
    targets: dict = field(default_factory=dict)

    def case(self, implementation: str, threads: int, steps: int) -> Case | None:
        for c in self.cases:
            if (c.implementation, c.threads, c.steps) == (implementation, threads, steps):
                return c
        return None

    def as_dict(self) -> dict:
        return dict(command=self.command, machine=self.machine,
                    cases=[c.as_dict() for c in self.cases], import_time=self.import_time,
                    paths=self.paths,
                    ratios=self.ratios, targets=self.targets)


def ratios(report: Report, sizes) -> dict:
    out = {}
    for n in sizes:
        c1 = report.case("compiled", 1, n)
        c2 = report.case("compiled", 2, n)
        npy = report.case("numpy", 1, n)
        loop = report.case("loop", 1, n)
        out[str(n)] = {
            "compiled_vs_numpy": ratio(npy.best, c1.best),
            "compiled_vs_loop": ratio(loop.best, c1.best),
            "two_vs_one_core": ratio(c1.best, c2.best),
            "compiled_vs_numpy_cpu": ratio(npy.cpu_best, c1.cpu_best),
        }
    return out


def targets(report: Report) -> dict:
    values = {}
    big = report.case("compiled", 1, 100_000)
    notes = {}
    if big is not None:
        values["compiled_1e5_steps_per_s"] = big.steps_per_second
        notes["compiled_1e5_steps_per_s"] = (f"{big.steps_per_cpu_second:.3g} per CPU "
                                             "second")
        notes["speedup_vs_numpy"] = (f"{report.ratios['100000']['compiled_vs_numpy_cpu']:.3g}"
                                     " in CPU time")
        values["speedup_vs_numpy"] = report.ratios["100000"]["compiled_vs_numpy"]
        values["speedup_vs_loop"] = report.ratios["100000"]["compiled_vs_loop"]
    small = report.case("compiled", 1, 40)
    if small is not None:
        values["latency_40_us"] = small.median * 1e6
    if "1000000" in report.ratios:
        values["two_core_speedup_1e6"] = report.ratios["1000000"]["two_vs_one_core"]
        free = min(report.machine.get("parallel_capacity_start", float("nan")),
                   report.machine.get("parallel_capacity_end", float("nan")))
        notes["two_core_speedup_1e6"] = f"cores free for the run: {free:.2f} of 2"
    values["import_s"] = report.import_time["median_s"]
    paths = report.paths
    if "evaluate_1e5" in paths:
        e = paths["evaluate_1e5"]
        values["evaluate_1e5_steps_per_s"] = e["steps_per_s"]
        notes["evaluate_1e5_steps_per_s"] = f"{e['steps_per_cpu_s']:.3g} per CPU second"
        values["evaluate_vs_numpy"] = e["vs_numpy"]
        notes["evaluate_vs_numpy"] = f"{e['vs_numpy_cpu']:.3g} in CPU time"
    if "control_loop_40" in paths:
        values["control_loop_40_us"] = paths["control_loop_40"]["median_us"]
        notes["control_loop_40_us"] = (f"best {paths['control_loop_40']['best_us']:.3g} us, "
                                       f"CPU {paths['control_loop_40']['cpu_us']:.3g} us")
    if paths.get("busy_core"):
        values["busy_two_vs_one"] = min(r["two_vs_one"] for r in paths["busy_core"].values())
    if "evaluate_memory_1e6" in paths:
        mem = paths["evaluate_memory_1e6"]
        values["evaluate_memory_1e6_gib"] = mem["peak_gib"]
        notes["evaluate_memory_1e6_gib"] = f"results {mem['results_gib']:.3g} GiB"
    if "simulate" in paths:
        sim = paths["simulate"]
        values["simulate_steps_per_s"] = sim["steps_per_s"]
        notes["simulate_steps_per_s"] = f"{sim['steps_per_cpu_s']:.3g} per CPU second"
        values["simulate_peak_gb"] = sim["peak_rss_gb"]
    out = {}
    for key, value in values.items():
        label, op, target, unit = TARGETS[key]
        met = value >= target if op == ">=" else value <= target
        out[key] = {"label": label, "value": value, "target": f"{op} {target:g} {unit}",
                    "met": bool(met), "note": notes.get(key, "")}
    return out


def _seconds(t: float) -> str:
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if t >= scale:
            return f"{t / scale:.3g} {unit}"
    return f"{t * 1e9:.3g} ns"


def _mib(value: float | None) -> str:
    return "-" if value is None else f"{max(value, 0.0):.1f}"


def format_report(report: Report) -> str:
    """The report as a plain-text table, ratios and targets."""
    lines = _header_lines(report.machine) + _case_lines(report) + _ratio_lines(report)
    p = report.paths
    if p:
        lines += ["", f"SIMD lanes: {p.get('lanes')}"]
        if "evaluate_1e5" in p:
            lines += _evaluate_lines(p)
        lines += _path_lines(p)
    return "\n".join(lines + _import_and_target_lines(report))


def _header_lines(m: dict) -> list[str]:
    """The machine, compiler, source and load."""
    return ["gsfric bench: actuator forces with friction, reference platform "
            "(NumPy in, NumPy out)",
            f"machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, "
            f"NumPy {m['numpy']}; build: {m['build']}; actuator map: "
            f"{m['actuator_entry']}",
            "CasADi instructions per step (generated/manifest.json): " + ", ".join(
                f"{name} {n}" for name, n in m.get("instructions", {}).items()),
            f"source: {m.get('source')}; load average (1, 5, 15 min): start "
            f"{m['load_average_start']}, end {m.get('load_average_end')}",
            f"cores free for this run (two CPU-bound processes together, 2.0 = two idle "
            f"cores): start {m.get('parallel_capacity_start', float('nan')):.2f}, end "
            f"{m.get('parallel_capacity_end', float('nan')):.2f}", ""]


def _case_lines(report: Report) -> list[str]:
    """The table of the cases, by size, implementation and threads."""
    head = (f"{'implementation':<14} {'threads':>7} {'N':>9} {'steps/s':>10} "
            f"{'(CPU time)':>10} {'latency best':>13} {'median':>10} {'calls':>6} "
            f"{'mem RSS MiB':>12} {'tracemalloc':>12}")
    lines = [head, "-" * len(head)]
    order = {"compiled": 0, "compiled_paper": 1, "numpy": 2, "loop": 3}
    for c in sorted(report.cases, key=lambda c: (c.steps, order[c.implementation],
                                                  c.threads)):
        mark = " (extrapolated)" if c.extrapolated else ""
        cpu = "-" if c.steps_per_cpu_second is None else f"{c.steps_per_cpu_second:.3g}"
        lines.append(f"{c.implementation:<14} {c.threads:>7} {c.steps:>9,} "
                     f"{c.steps_per_second:>10.3g} {cpu:>10} {_seconds(c.best):>13} "
                     f"{_seconds(c.median):>10} {c.calls:>6} {_mib(c.memory_rss_mib):>12} "
                     f"{_mib(c.memory_tracemalloc_mib):>12}{mark}")
    return lines


def _ratio_lines(report: Report) -> list[str]:
    """The ratios of the fastest calls per size."""
    lines = ["", "ratios of the fastest calls: compiled on one core vs vectorised NumPy (wall "
             "clock; CPU time), vs the per-step loop; compiled on two cores vs one"]
    for n, r in report.ratios.items():
        lines.append(f"  N = {int(n):>9,}: {r['compiled_vs_numpy']:6.1f}x "
                     f"({r['compiled_vs_numpy_cpu']:5.1f}x) NumPy  "
                     f"{r['compiled_vs_loop']:8.0f}x loop  {r['two_vs_one_core']:5.2f}x on two "
                     "cores")
    return lines


def _evaluate_lines(p: dict) -> list[str]:
    """``gsfric.evaluate``'s figures at N = 1e5."""
    lines = []
    e = p["evaluate_1e5"]
    lines.append("gsfric.evaluate (the kept outputs + flags; the detail outputs, "
                 "evaluation.DETAILS, are computed on first read), "
                 f"{p.get('friction_model')} friction model, N = 100,000: "
                 f"{e['steps_per_s']:.3g} steps/s ({e['steps_per_cpu_s']:.3g} per CPU "
                 f"second), {e['vs_numpy']:.1f}x the vectorised NumPy actuator map "
                 f"({e['vs_numpy_cpu']:.1f}x in CPU time); into reused arrays "
                 f"(evaluate_quiet(buffers=...)): {e['reused_steps_per_s']:.3g} steps/s "
                 f"({e['reused_steps_per_cpu_s']:.3g} per CPU second)")
    if "new_memory_steps_per_s" in e:
        lines.append("gsfric.evaluate into memory mapped anew (no dropped result's "
                     "memory to reuse, evaluation.release_memory() before each call): "
                     f"{e['new_memory_steps_per_s']:.3g} steps/s "
                     f"({e['new_memory_steps_per_cpu_s']:.3g} per CPU second)")
    if "paper_steps_per_s" in e:
        lines.append(f"gsfric.evaluate, paper friction model (no fixed-point "
                     f"iterations), N = 100,000: {e['paper_steps_per_s']:.3g} steps/s "
                     f"({e['paper_steps_per_cpu_s']:.3g} per CPU second)")
    return lines


def _path_lines(p: dict) -> list[str]:
    """The control loop, the busy core, evaluate's memory and ``gsfric simulate``."""
    lines = []
    if "control_loop_40" in p:
        c, k = p["control_loop_40"], p["evaluator_construct"]
        lines.append(f"README control loop (new Evaluator + forces, 40 steps): median "
                     f"{c['median_us']:.3g} us, best {c['best_us']:.3g} us; Evaluator() "
                     f"alone: median {k['median_us']:.3g} us")
    for n, r in p.get("busy_core", {}).items():
        lines.append(f"other core busy, N = {int(n):,}: one thread {r['one_thread_ms']:.3g} "
                     f"ms, two threads {r['two_threads_ms']:.3g} ms (median): "
                     f"{r['two_vs_one']:.2f}x")
    if "evaluate_memory_1e6" in p:
        mem = p["evaluate_memory_1e6"]
        lines.append(f"gsfric.evaluate at N = 1e6: peak memory added {mem['peak_gib']:.3g} "
                     f"GiB (results {mem['results_gib']:.3g} GiB: "
                     f"{mem.get('values_per_step', '?')} values per step in "
                     f"{mem.get('arrays', '?')} arrays, the detail outputs not read)")
    if "simulate" in p:
        sim = p["simulate"]
        lines.append(f"gsfric simulate, {sim['steps']:,} steps Parquet to Parquet (default "
                     f"columns): {sim['wall_s']:.3g} s wall, {sim['cpu_s']:.3g} s CPU "
                     f"({sim.get('user_s', float('nan')):.3g} user, "
                     f"{sim.get('system_s', float('nan')):.3g} system), "
                     f"{sim['steps_per_s']:.3g} steps/s ({sim['steps_per_cpu_s']:.3g} per "
                     f"CPU second), peak RSS {sim['peak_rss_gb']:.3g} GB, output "
                     f"{sim['output_gb']:.3g} GB")
    return lines


def _import_and_target_lines(report: Report) -> list[str]:
    """Import time and the targets, met or missed."""
    it = report.import_time
    lines = ["", f"import gsfric: median {it['median_s'] * 1e3:.0f} ms, best "
             f"{it['best_s'] * 1e3:.0f} ms over {it['runs']} fresh interpreters "
             f"(-X importtime: {it['importtime_cumulative_s'] * 1e3:.0f} ms); import + "
             f"Evaluator + first 40-step call: {it['first_call_s'] * 1e3:.0f} ms", "",
             "targets:"]
    for t in report.targets.values():
        value = t["value"]
        shown = f"{value:.3g}"
        note = f"; {t['note']}" if t.get("note") else ""
        lines.append(f"  [{'met' if t['met'] else 'MISSED':>6}] {t['label']}: {shown} "
                     f"(target {t['target']}{note})")
    return lines
