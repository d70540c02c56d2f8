"""The work-precision study's yardstick and report: targets, frontier, tables, figures.

What `scripts/work_precision.py` measures is judged here: the physical targets
(TARGETS), the frontier (the least CPU time of a measured run meeting a
target, else a marked extrapolation), every markdown table and the figures.
It needs only matplotlib (no engine), so that the docs' tables can
be regenerated and checked from the committed JSONs anywhere:

    python3 scripts/work_precision.py --table   # the tables page, figures redrawn

and `scripts/test_work_precision.py` checks the docs against it.
"""

import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# key, title, scenario, URDF root link
SYSTEMS = [
    ("disk", "rolling disk", "disk_paper", "yoke"),
    ("space", "space robot", "space_robot_paper", "vehicle"),
    ("rover", "rover (open-loop replay)", "rover_open_loop", "chassis"),
    ("sphere", "rolling sphere", "sphere_triangle_paper", "ball"),
]
ENGINES = ("harness", "mujoco", "drake")
ENGINE_NAMES = {"harness": "harness (Rapier)", "mujoco": "MuJoCo (best settings per dt)",
                "drake": "Drake (point contact, SAP)", "drake_hydro": "Drake (hydroelastic, SAP)"}
COLORS = {"harness": "tab:orange", "mujoco": "tab:blue", "drake": "tab:green", "drake_hydro": "tab:olive"}


# Physical targets: what a user of each system would ask for, in its own units; none is
# derived from any engine's results. Against the ideal run each quantity is the largest
# deviation along the run (the end state included; `tracking_*_max`); against the engine's
# own converged run it is the end state's deviation (`sim_goal_*`): along the run, runs at
# two step sizes differ by when the plan's rate changes fall on the step grid (up to a step
# of time: ~1 deg of the disk's heading at 8 ms), which says nothing of accuracy. A target
# level is met when every quantity of the system is within it.
#   key: [(quantity, metric, unit)], [(level name, {quantity: bound})]
TARGETS = {
    # A 0.25 m disk: 1 cm is the tolerance of docking or of a marker on the floor, 1 mm that
    # of a motion-capture system; a heading error of 1 deg (0.1 deg) moves the contact point
    # 1.7 cm (1.7 mm) sideways per metre rolled, the same order as the position targets.
    "disk": ([("position", "tracking_position_max", "m"), ("heading", "tracking_alpha_deg_max", "deg")],
             [("1 cm, 1°", {"position": 0.01, "heading": 1.0}),
              ("1 mm, 0.1°", {"position": 0.001, "heading": 0.1})]),
    # The reorientation is the space robot's whole task: 0.1 deg is the pointing of a body-fixed
    # antenna or a coarse sensor, 0.01 deg (36 arcsec) that of a star tracker's field
    # alignment. The arm's joints are driven and followed by every engine's servo.
    "space": ([("base attitude", "tracking_theta0_deg_max", "deg")],
              [("0.1°", {"base attitude": 0.1}), ("0.01°", {"base attitude": 0.01})]),
    # 88.7 s of open-loop driving over ~20 m: 1 m (5 % of the path) and 10 deg is what dead
    # reckoning over such a drive is asked for, 10 cm and 5 deg the task's own tolerance (the
    # planner's epsilon = 0.1 m and 0.1 rad), 1 cm and 1 deg the general targets.
    "rover": ([("position", "tracking_position_max", "m"), ("heading", "tracking_theta_deg_max", "deg")],
              [("1 m, 10°", {"position": 1.0, "heading": 10.0}),
               ("10 cm, 5°", {"position": 0.1, "heading": 5.0}),
               ("1 cm, 1°", {"position": 0.01, "heading": 1.0})]),
    # A 1 m ball: its task is a reorientation; 1 deg of orientation is 1.7 cm of surface arc,
    # 0.1 deg 1.7 mm, matched with the position targets.
    "sphere": ([("position", "tracking_position_max", "m"), ("orientation", "tracking_orientation_deg_max", "deg")],
               [("1 cm, 1°", {"position": 0.01, "orientation": 1.0}),
                ("1 mm, 0.1°", {"position": 0.001, "orientation": 0.1})]),
}


# No extrapolation for the rover: against the ideal run its error is the wheels' slip (17 m on
# every engine at every dt), and its converged runs are themselves unsettled at the targets
# (the harness's run at 0.5 ms ends 0.24 m from its run at 0.125 ms); no power law holds there.
NO_TREND = {"rover"}


def goal_metric(metric):
    """The end-state metric of a tracking metric: tracking_alpha_deg_max -> sim_goal_alpha_deg."""
    return "sim_goal_" + metric[len("tracking_") : -len("_max")]


def target_error(key, vals, level, end=False):
    """Largest quantity / bound of the level (1 = at the target); end: the end-state metrics."""
    quantities, _levels = TARGETS[key]
    return max(vals[goal_metric(metric) if end else metric] / level[q] for q, metric, _u in quantities)


# Settings without effect on a system: the space robot has no contact, the sphere no
# position servo.
MJ_SKIP = {"space": {"cone", "condim", "impratio", "noslip_iterations", "solref_tc"}, "sphere": {"kp_ratio"}}


def mj_label(cfg, key=None):
    """'implicitfast, elliptic, condim 3, impratio 10, noslip 0, tc max(4ms,2dt), kv 1e+04, kp·dt/kv 0.5'
    (without the settings that have no effect on `key`)."""
    parts = {"integrator": cfg["integrator"], "cone": cfg["cone"], "condim": f"condim {cfg['condim']}",
             "impratio": f"impratio {cfg['impratio']:g}", "noslip_iterations": f"noslip {cfg['noslip_iterations']}",
             "solref_tc": f"tc {cfg['solref_tc']}", "kv": f"kv {cfg['kv']:g}", "kp_ratio": f"kp·dt/kv {cfg['kp_ratio']:g}"}
    return ", ".join(v for k, v in parts.items() if k not in MJ_SKIP.get(key, ()))


def tight(key):
    return TARGETS[key][1][-1][1]


def error_of(key, cell, ref, level):
    """Target error (1 = at the target) of one run against `ref` ('ideal' or 'converged')."""
    if ref not in cell:
        return math.inf
    return target_error(key, cell[ref], level, end=ref == "converged")


def frontier_cell(key, res, eng, ref, level):
    """The cheapest measured run meeting `level` against `ref`: (cpu, dt, cpu_all, measured);
    else a power law through the two smallest steps (error ~ dt^p, CPU ~ 1/dt); else None."""
    ok = [r for r in res["rows"] if error_of(key, r[eng], ref, level) <= 1]
    if ok:
        best = min(ok, key=lambda r: r[eng]["cpu_s"])
        return {"cpu_s": best[eng]["cpu_s"], "dt": best["dt"], "cpu_all": best[eng]["cpu_all"], "measured": True}
    if key in NO_TREND:
        return None
    rows = sorted(res["rows"], key=lambda r: r["dt"])[:2]
    e = [error_of(key, r[eng], ref, level) for r in rows]
    if not all(math.isfinite(v) and v > 0 for v in e) or e[1] <= e[0]:
        return None
    p = math.log(e[1] / e[0]) / math.log(rows[1]["dt"] / rows[0]["dt"])
    # An error that falls slower than sqrt(dt), or a step 100 times below the smallest
    # measured: no trend to extrapolate through.
    if p < 0.5 or math.log(e[0]) / p > math.log(100):
        return None
    dt = rows[0]["dt"] * e[0] ** (-1 / p)
    scale = rows[0]["dt"] / dt
    return {"cpu_s": rows[0][eng]["cpu_s"] * scale, "dt": dt,
            "cpu_all": [c * scale for c in rows[0][eng]["cpu_all"]], "measured": False, "p": p}


def fmt_cpu(cpu_s, dt, approx=False):
    """'35.4 ms (1.5 ms)', '≈ 79 s (≈ 0.55 µs)'."""
    sig = (lambda v: f"{float(f'{v:.2g}'):g}") if approx else (lambda v: f"{v:.3g}")
    t = f"{sig(cpu_s)} s" if cpu_s >= 1 else f"{sig(cpu_s * 1e3)} ms"
    d = f"{dt * 1e3:.2g} ms" if dt >= 1e-4 else f"{dt * 1e6:.2g} µs"
    a = "≈ " if approx else ""
    return f"{a}{t} ({a}{d})"


def ratio_text(a, b):
    """Ratio a / b of two frontier cells, with its range over the repeats (min/max, max/min)."""
    if not a or not b:
        return "–"
    r = a["cpu_s"] / b["cpu_s"]
    lo, hi = min(a["cpu_all"]) / max(b["cpu_all"]), max(a["cpu_all"]) / min(b["cpu_all"])
    f = lambda v: f"{v:.2g}" if v < 100 else f"{float(f'{v:.2g}'):.0f}"  # noqa: E731
    if not (a["measured"] and b["measured"]):
        return f"≈ {f(r)}"
    return f"{f(r)} ({f(lo)}–{f(hi)})"


def frontier_table(results):
    """Markdown: per system, reference and target, each engine's least CPU and the ratios."""
    lines = ["| system | against | target | harness CPU (dt) | MuJoCo CPU (dt) | Drake CPU (dt) "
             "| MuJoCo / harness | Drake / harness |", "|---|---|---|---|---|---|---|---|"]
    for key, res in results.items():
        for ref, against in (("ideal", "ideal run"), ("converged", "own converged run")):
            for name, level in TARGETS[key][1]:
                cells = {eng: frontier_cell(key, res, eng, ref, level) for eng in ENGINES}
                text = []
                for eng in ENGINES:
                    c = cells[eng]
                    text.append("never" if c is None else fmt_cpu(c["cpu_s"], c["dt"], not c["measured"])
                                + ("" if c["measured"] else ", extrapolated"))
                lines.append(f"| {res['system']} | {against} | {name} | " + " | ".join(text) + " | "
                             + ratio_text(cells["mujoco"], cells["harness"]) + " | "
                             + ratio_text(cells["drake"], cells["harness"]) + " |")
    return "\n".join(lines)


def gate_table(results):
    """Markdown, secondary: the shipped scenario's gates (set from the harness's own errors)."""
    lines = ["| system | against | harness CPU (dt) | MuJoCo CPU (dt) | Drake CPU (dt) |", "|---|---|---|---|---|"]
    for key, res in results.items():
        for what, against in ((("goal", "tracking"), "ideal run, every gate"), (("converged_goal",), "own converged run, goal gates")):
            cells = []
            for eng in ENGINES:
                ok = [r for r in res["rows"] if all(r[eng].get(w, math.inf) <= 1 for w in what)]
                if key == "rover" and what[0] == "goal":
                    ok = [r for r in res["rows"] if r[eng].get("goal", math.inf) <= 1]
                b = min(ok, key=lambda r: r[eng]["cpu_s"]) if ok else None
                cells.append(fmt_cpu(b[eng]["cpu_s"], b["dt"]) if b else "never")
            lines.append(f"| {res['system']} | {against} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def best_table(results):
    """Markdown: MuJoCo's best configuration per system and dt (the frontier uses it)."""
    lines = ["| system | dt | best configuration | error / tightest target | CPU |", "|---|---|---|---|---|"]
    for key, res in results.items():
        for e in res["mujoco_sweep"]:
            if e.get("best"):
                lines.append(f"| {res['system']} | {e['dt'] * 1e3:g} ms | {mj_label(e['config'], key)} | "
                             f"{objective_of(key, e):.3g} | {e['cpu_s'] * 1e3:.3g} ms |")
    return "\n".join(lines)


def objective_of(key, e):
    """A search row's error / the system's tightest target, from its stored errors."""
    if any(v is None for v in e["errors"].values()):
        return math.inf
    return max(e["errors"][q] / b for q, b in tight(key).items())


def fmt_err(v, unit):
    if v is None:
        return "diverged"
    if unit == "m":
        return f"{v * 1e3:.3g} mm"
    return f"{v:.3g}°"


def sweep_table(results):
    """Markdown, per system: every MuJoCo configuration the search ran (setting, dt, error, CPU)."""
    out = []
    for key, res in results.items():
        q = TARGETS[key][0]
        against = "MuJoCo's own converged run (start configuration)" if key == "rover" else "the ideal run"
        out.append(f"\n### {res['system']}\n\nErrors against {against}; each row changes one setting of the "
                   "best configuration so far (the first row per dt is the start configuration); **bold**: the "
                   "best at that dt.\n")
        out.append("| dt | setting | " + " | ".join(f"{n} error" for n, _m, _u in q) + " | error / tightest target | CPU |")
        out.append("|---|---|" + "---|" * len(q) + "---|---|")
        for e in res["mujoco_sweep"]:
            what = "start: " + mj_label(e["config"], key) if e["setting"] == "start" else f"{e['setting']} = {e['value']}"
            b = "**" if e.get("best") else ""
            out.append(f"| {e['dt'] * 1e3:g} ms | {b}{what}{b} | "
                       + " | ".join(fmt_err(e["errors"][n], u) for n, _m, u in q)
                       + f" | {objective_of(key, e):.3g} | {e['cpu_s'] * 1e3:.3g} ms |")
    return "\n".join(out)


def plot(key, res, out_dir):
    quantities, levels = TARGETS[key]
    fig, axes = plt.subplots(2, len(quantities), figsize=(max(6.2 * len(quantities), 8.5), 8.2),
                             constrained_layout=True, squeeze=False)
    for row_i, (ref, rname) in enumerate((("ideal", "ideal run"),
                                          ("converged", f"own run at {res['reference_dt'] * 1e3:g} ms"))):
        for col, (qn, metric, unit) in enumerate(quantities):
            ax = axes[row_i][col]
            scale = 1e3 if unit == "m" else 1.0
            for eng in res["engines"]:
                rows = [r for r in res["rows"] if ref in r[eng]]
                lost = [f"{r['dt'] * 1e3:g}" for r in res["rows"] if ref not in r[eng]]
                x = [r[eng]["cpu_s"] for r in rows]
                m = goal_metric(metric) if ref == "converged" else metric
                y = [max(r[eng][ref][m] * scale, 1e-9) for r in rows]
                ls = "--" if eng == "drake_hydro" else "-"
                ax.plot(x, y, "o" + ls, color=COLORS[eng], ms=4,
                        label=ENGINE_NAMES[eng] + (f" (diverged at {', '.join(lost)} ms)" if lost else ""))
                for r, xi, yi in zip(rows, x, y):
                    ax.annotate(f"{r['dt'] * 1e3:g}", (xi, yi), textcoords="offset points", xytext=(3, 3),
                                fontsize=6, color=COLORS[eng])
            for name, level in levels:
                ax.axhline(level[qn] * scale, color="k", lw=0.8, ls=":")
                ax.annotate(name, (1.0, level[qn] * scale), xycoords=("axes fraction", "data"), fontsize=7,
                            ha="right", va="bottom")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("CPU time of the physics run, s")
            what = "end-state" if ref == "converged" else "max"
            ax.set_ylabel(f"{what} {qn} error vs {rname}, {'mm' if unit == 'm' else 'deg'}")
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"{res['system']} ({res['scenario']}): points labelled with dt in ms; dotted: the targets",
                 fontsize=10)
    path = os.path.join(out_dir, f"work_precision_{key}.png")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def load_results(out_dir, keys=None):
    results = {}
    for key, *_ in SYSTEMS:
        path = os.path.join(out_dir, f"work_precision_{key}.json")
        if os.path.exists(path) and (keys is None or key in keys):
            res = json.load(open(path))
            if "engines" in res:  # not a JSON of the two-engine study before this one
                results[key] = res
    return results


def readme_cell(a, b):
    """README form of `ratio_text` (a: the engine, b: the harness): who misses the target."""
    if a and b:
        return ratio_text(a, b)
    return "never" if b else "harness never" if a else "neither"


def readme_table(results):
    """Markdown, the README's summary: each engine's CPU over the harness's at each target."""
    lines = ["| system | target | against | MuJoCo / harness | Drake / harness |", "|---|---|---|---|---|"]
    for key, res in results.items():
        for name, level in TARGETS[key][1]:
            for ref, against in (("ideal", "ideal run"), ("converged", "own converged run")):
                cells = {eng: frontier_cell(key, res, eng, ref, level) for eng in ENGINES}
                lines.append(f"| {res['system']} | {name} | {against} | "
                             + readme_cell(cells["mujoco"], cells["harness"]) + " | "
                             + readme_cell(cells["drake"], cells["harness"]) + " |")
    return "\n".join(lines)


def tables_page(results):
    """docs/src/work_precision_tables.md: every table, from the study's JSONs."""
    out = ["# Work-precision tables\n\nWritten by `scripts/work_precision.py --table` from "
           "`docs/src/images/work_precision_*.json` (the method: [Performance](performance.md)). "
           "Cells marked ≈ are extrapolated (a power law through the two smallest steps), the others "
           "measured; ratios give the range over the repeats (least over most CPU time, most over least)."]
    for head, text in (("Frontier (physical targets)", frontier_table(results)),
                       ("Ratios at the targets (the README's table)", readme_table(results)),
                       ("Gate-normalised (secondary)", gate_table(results)),
                       ("MuJoCo's best configuration per dt", best_table(results)),
                       ("MuJoCo's settings sweep", sweep_table(results))):
        out.append(f"\n## {head}\n\n{text}")
    return "\n".join(out) + "\n"
