#!/usr/bin/env python3
"""Work-precision in physical units: the harness (Rapier), MuJoCo and Drake on the same tasks.

For each system (rolling disk, space robot, rover, rolling sphere) one shipped
scenario runs at several physics steps dt, from a quarter of the scenario's own
dt to 8x it, on three engines:

* the harness runs a copy of the scenario with `[sim] dt` changed
  (`anholonomy run`, logs to a temporary directory); its CPU time is
  `wall_time_s.physics_cpu` of summary.json (the CPU time of the replay's
  thread: building the world, stepping, read-back);
* MuJoCo (its URDF importer, a floating base, a ground plane with the
  scenario's friction, the same dt) replays the same task: servo drives on
  the same joints track the joint angles of the harness's ideal run (the
  rover: the integral of its recorded commands), with the per-step mean rate
  as velocity target (the sphere: world-frame angular velocity servos, as in
  the harness); `mujoco.rollout` on one thread, CPU time of that call
  (`time.thread_time`). At every dt a coordinate-wise search over the
  settings MuJoCo documents for contact and servo accuracy (MJ_SWEEP:
  integrator, friction cone, condim, impratio, noslip_iterations, the contact
  time constant, servo gains) picks the configuration with the least error;
  the frontier uses it;
* Drake (scripts/drake_engine.py: MultibodyPlant from the same URDFs, a
  discrete plant at the same dt, SAP, point contact, and hydroelastic contact
  where there is a ground) with the same commands through implicit joint PD
  controllers; CPU time of `Simulator.AdvanceTo` (`time.thread_time`).

Every run is compared with the harness's ideal kinematic run at that dt (from
run.mcap) by the harness's own metric definitions (recomputed here and checked
against summary.json on the harness's own runs), and with the same engine's
own converged run (its run at 1/16 of the shipped dt). Errors are in the
systems' units (m, degrees) and set against physical targets (TARGETS),
chosen for each system's use, not from any engine's results. The frontier is
the least CPU time of a measured run that meets a target; where no measured
run does, a power law through the two smallest steps, marked as extrapolated.

Writes per system a PNG (error against CPU-seconds, three engines, targets as
lines) and a JSON of every number to --out (default docs/src/images);
`--table` prints the tables page from them (the frontier, the README's ratio
table, the gate-normalised table (secondary), MuJoCo's best configuration per
dt and its whole settings sweep) and redraws the figures. The targets, the
frontier, the tables and the figures are scripts/work_precision_report.py
(matplotlib only); scripts/test_work_precision.py checks the docs
against the JSONs, and a short rerun against the committed errors.

Usage (from the repository root, after `cargo build --release`):

    scripts/work_precision_env.sh            # fresh venv, pinned packages, the whole study
    python3 scripts/work_precision.py [--repeats 3] [--systems disk,space,rover,sphere]

Not run by .ci/run.
"""

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))

# The yardstick, the tables and the figures (matplotlib only).
from work_precision_report import (  # noqa: E402
    ENGINES, MJ_SKIP, SYSTEMS, TARGETS, frontier_table, goal_metric, load_results, mj_label, plot,
    tables_page, target_error, tight)

try:
    # The URDF-to-MJCF helpers (installs mujoco, mcap and numpy with pip --user when missing).
    import mujoco_compare as mc  # noqa: E402
    import drake_engine as de  # noqa: E402
except ImportError as e:
    sys.exit(f"{e}: run scripts/work_precision_env.sh (a venv with the pinned packages)")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mujoco import rollout  # noqa: E402

# dt as multiples of the shipped one, up to 8x.
# Below 1: where an engine misses a target at the shipped step, how small a step it needs.
FACTORS = [0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8]
# The converged reference run of each engine: this multiple of the shipped dt.
REF_FACTOR = 1 / 16


# MuJoCo's settings: the configuration the earlier study used (the start of the search) and
# the values the coordinate-wise search tries. Velocity servos (kv) with a position term
# kp = ratio * kv / dt on the driven joints (the sphere: world-frame angular velocity
# servos, kv only).
MJ_BASE = {"integrator": "implicitfast", "cone": "elliptic", "condim": 3, "impratio": 10,
           "noslip_iterations": 0, "solref_tc": "max(4ms,2dt)", "kv": 1.0e4, "kp_ratio": 0.5}
# The rover's servos start far softer (earlier study: at kv 1e4 and 1e3 a step in the
# commanded steering rate throws the rover off the ground).
MJ_BASE_OF = {"rover": {"kv": 1.0}}
MJ_SWEEP = [
    ("integrator", ["implicitfast", "Euler", "RK4"]),
    ("cone", ["elliptic", "pyramidal"]),
    ("condim", [3, 4, 6]),
    ("impratio", [1, 10, 100]),
    ("noslip_iterations", [0, 10, 100]),
    ("solref_tc", ["2dt", "max(4ms,2dt)", "20ms"]),
    ("kv", ["/1000", "/100", "/10", "x1", "x10", "x100"]),
    ("kp_ratio", [0, 0.25, 0.5, 1.0]),
    # The integrator once more, with the servo gains found: RK4 and Euler integrate a
    # velocity servo's damping explicitly, so with the start's stiff servos they diverge
    # (a separate check found RK4 with kv 10 best on the disk at 0.25 ms).
    ("integrator", ["implicitfast", "Euler", "RK4"]),
]


# ---------------------------------------------------------------- harness


def scenario_copy(scenario, dt, tmp):
    """The scenario with `[sim] dt` = dt and absolute model paths, in tmp."""
    path = os.path.join(ROOT, "scenarios", f"{scenario}.toml")
    text = open(path).read()
    text, n = re.subn(r"(?m)^dt = [0-9.eE+-]+", f"dt = {dt!r}", text)
    assert n == 1, f"{scenario}: expected one `dt =` line"
    text = text.replace('"../models/', f'"{ROOT}/models/')
    out = os.path.join(tmp, f"{scenario}.toml")
    with open(out, "w") as f:
        f.write(text)
    return out


def harness_runs(binary, scenario, dt, tmp, repeats):
    """Summary, the physics CPU time of each repeat and the MCAP path of the harness at dt."""
    path = scenario_copy(scenario, dt, tmp)
    logs = os.path.join(tmp, "logs")
    cpu = []
    for i in range(repeats):
        # Only the last run's logs are read: the others keep summary.json alone (the replay
        # thread's CPU time does not include writing logs).
        keep = "all" if i == repeats - 1 else "summary"
        subprocess.run(
            # --max-steps: the rover's planner records its 300 s closed-loop run at sim.dt,
            # 2.4e6 steps at its reference dt (the default budget is 2e6).
            [binary, "run", path, "--logs", logs, "--quiet", "--pose-rate", "1", "--max-steps", "4000000",
             "--keep", keep],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        with open(os.path.join(logs, scenario, "summary.json")) as f:
            summary = json.load(f)
        wt = summary["wall_time_s"]
        cpu.append(wt.get("physics_cpu", wt["physics"]))
    return summary, cpu, os.path.join(logs, scenario, "run.mcap")


def read_topics(mcap_path, topics):
    """{topic: (t array, [values dicts])} of JSON topics, in the order they were written.

    Scans the MCAP's chunks directly (zstd, lz4 or none) and decodes each topic's JSON
    payloads in one `json.loads` call: the `mcap` package's pure-Python record reader
    took ~90 % of a rover study's time (a run at the shipped dt logs 265 k messages)."""
    import struct

    with open(mcap_path, "rb") as f:
        summary = make_reader(f).get_summary()
        if summary is None or not summary.chunk_indexes:
            return _read_topics_slow(mcap_path, topics)
        wanted = {cid: c.topic for cid, c in summary.channels.items() if c.topic in topics}
        parts = {t: [] for t in topics}
        for ci in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
            f.seek(ci.chunk_start_offset)
            raw = f.read(ci.chunk_length)
            # Chunk record: opcode u8, length u64, start/end time u64 x2, uncompressed size u64,
            # crc u32, compression (u32 length + text), records (u64 length + bytes).
            pos = 1 + 8 + 8 + 8
            size = struct.unpack_from("<Q", raw, pos)[0]
            pos += 8 + 4
            n = struct.unpack_from("<I", raw, pos)[0]
            comp = raw[pos + 4 : pos + 4 + n].decode()
            pos += 4 + n
            m = struct.unpack_from("<Q", raw, pos)[0]
            data = raw[pos + 8 : pos + 8 + m]
            if comp == "zstd":
                import zstandard

                data = zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
            elif comp == "lz4":
                import lz4.frame

                data = lz4.frame.decompress(data)
            elif comp:
                return _read_topics_slow(mcap_path, topics)
            pos, end = 0, len(data)
            unpack = struct.unpack_from
            while pos < end:
                op, length = unpack("<BQ", data, pos)
                pos += 9
                if op == 0x05:  # Message: channel u16, sequence u32, log/publish time u64 x2, data
                    topic = wanted.get(unpack("<H", data, pos)[0])
                    if topic is not None:
                        parts[topic].append(data[pos + 22 : pos + length])
                pos += length
    out = {}
    for t, msgs in parts.items():
        decoded = json.loads(b"[" + b",".join(msgs) + b"]") if msgs else []
        out[t] = (np.array([d["t"] for d in decoded]), [d["values"] for d in decoded])
    return out


def _read_topics_slow(mcap_path, topics):
    """read_topics through the `mcap` package's reader (unchunked or unusual files)."""
    out = {t: ([], []) for t in topics}
    with open(mcap_path, "rb") as f:
        for _s, channel, msg in make_reader(f).iter_messages(topics=topics, log_time_order=False):
            d = json.loads(msg.data)
            out[channel.topic][0].append(d["t"])
            out[channel.topic][1].append(d["values"])
    return {k: (np.array(t), v) for k, (t, v) in out.items()}


def state_array(values, names):
    return np.array([[v[n] if v[n] is not None else np.nan for n in names] for v in values])


# ---------------------------------------------------------------- metrics


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def sample(t, q, at):
    """Linear interpolation per column, held at the ends (the harness's `compare::sample`)."""
    return np.stack([np.interp(at, t, q[:, i]) for i in range(q.shape[1])], axis=1)


def geodesic(qa, qb):
    """Angle between unit quaternions (w, x, y, z) row by row, rad."""
    qa = qa / np.linalg.norm(qa, axis=1, keepdims=True)
    qb = qb / np.linalg.norm(qb, axis=1, keepdims=True)
    # conj(qa) * qb; atan2 of its vector part keeps small angles exact (arccos does not).
    w = np.sum(qa * qb, axis=1)
    v = (qa[:, :1] * qb[:, 1:] - qb[:, :1] * qa[:, 1:]) - np.cross(qa[:, 1:], qb[:, 1:])
    return 2 * np.arctan2(np.linalg.norm(v, axis=1), np.abs(w))


def metrics(system, names, goal, t_i, q_i, t_s, q_s, dt):
    """The harness's goal and tracking metrics of a simulated run against the ideal one."""
    end = max(t_i[-1], t_s[-1])
    n = int(round(end / dt)) if abs(end / dt - round(end / dt)) < 1e-6 else math.ceil(end / dt)
    grid = np.minimum(np.arange(n + 1) * dt, end)
    a, b = sample(t_i, q_i, grid), sample(t_s, q_s, grid)
    out = {}
    if system == "sphere":
        out["sim_goal_position"] = math.hypot(q_s[-1, 0] - goal[0], q_s[-1, 1] - goal[1])
        out["tracking_position_max"] = float(np.max(np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])))
        out["sim_goal_orientation_deg"] = math.degrees(geodesic(goal[None, 2:6], q_s[-1:, 2:6])[0])
        out["tracking_orientation_deg_max"] = math.degrees(float(np.max(geodesic(a[:, 2:6], b[:, 2:6]))))
        return out
    angular = {"disk": [2, 3], "space": [0, 1, 2], "rover": [2, 3]}[system]
    e = b - a
    for i in angular:
        e[:, i] = wrap(e[:, i])
    ge = q_s[-1] - goal
    for i in angular:
        ge[i] = wrap(ge[i])
    if system in ("disk", "rover"):
        out["sim_goal_position"] = math.hypot(ge[0], ge[1])
        out["tracking_position_max"] = float(np.max(np.hypot(e[:, 0], e[:, 1])))
    for i, nm in enumerate(names):
        scale = 180 / math.pi if i in angular else 1.0
        suffix = "_deg" if i in angular else ""
        out[f"sim_goal_{nm}{suffix}"] = abs(ge[i]) * scale
        out[f"tracking_{nm}{suffix}_max"] = float(np.max(np.abs(e[:, i]))) * scale
    if system == "rover":
        out["sim_goal_se2"] = math.sqrt(ge[0] ** 2 + ge[1] ** 2 + ge[2] ** 2)
    return out


# ---------------------------------------------------------------- MuJoCo


def mj_config(key, dt, **over):
    """The MuJoCo configuration of `key` at dt: MJ_BASE, the system's changes, `over`."""
    cfg = {**MJ_BASE, **MJ_BASE_OF.get(key, {})}
    cfg.update(over)
    return cfg


def solref_tc(spec, dt):
    return {"2dt": 2 * dt, "max(4ms,2dt)": max(0.004, 2 * dt), "20ms": 0.02}[spec]


def mujoco_model(system, summary, root, dt, cfg):
    """MJCF from MuJoCo's URDF import plus the harness's additions and servo drives."""
    urdf = os.path.normpath(os.path.join(ROOT, "scenarios", summary["model"]["urdf"]))
    m = mujoco.MjModel.from_xml_string(mc.floating_urdf(urdf, root))
    with tempfile.TemporaryDirectory() as tmp:
        xml_path = os.path.join(tmp, "model.xml")
        mujoco.mj_saveLastXML(xml_path, m)
        mjcf = ET.parse(xml_path).getroot()
    sim = summary["sim_settings"]
    option = ET.SubElement(mjcf, "option")
    option.set("timestep", repr(dt))
    option.set("gravity", " ".join(repr(g) for g in sim["gravity"]))
    option.set("integrator", cfg["integrator"])
    option.set("cone", cfg["cone"])
    option.set("impratio", repr(float(cfg["impratio"])))
    option.set("noslip_iterations", str(int(cfg["noslip_iterations"])))
    world = mjcf.find("worldbody")
    body = world.find(f".//body[@name='{root}']")
    free = body.find("freejoint")
    if free is None:
        free = body.find("joint[@type='free']")
    free.set("name", "world_to_root")
    for j in mjcf.iter("joint"):
        j.attrib.pop("actuatorfrcrange", None)
    mu = repr(sim["friction"])
    # MuJoCo takes the larger friction of two geoms: every geom gets the scenario's
    # (torsional and rolling friction as MuJoCo's defaults; they act with condim 4 and 6).
    solref = f"{solref_tc(cfg['solref_tc'], dt)!r} 1"
    for g in mjcf.iter("geom"):
        g.set("friction", f"{mu} 0.005 0.0001")
        g.set("solref", solref)
        g.set("condim", str(cfg["condim"]))
    actuators = ET.SubElement(mjcf, "actuator")
    kv = cfg["kv"]
    kp = kv * cfg["kp_ratio"] / dt

    # No force limits: MuJoCo integrates a force-limited actuator's damping explicitly,
    # which this stiff a servo does not survive.
    def servo(joint, gear="1"):
        # Velocity target first, then angle target (ctrl columns in this order).
        ET.SubElement(actuators, "velocity", joint=joint, kv=repr(kv), gear=gear)
        if kp > 0:
            ET.SubElement(actuators, "position", joint=joint, kp=repr(kp), gear=gear)
        else:
            # kp 0: a zero-gain placeholder keeps the ctrl columns.
            ET.SubElement(actuators, "general", joint=joint, gear=gear, gainprm="0", biasprm="0 0 0")

    if system != "space":
        ET.SubElement(world, "geom", type="plane", size="0 0 1", friction=f"{mu} 0.005 0.0001",
                      solref=solref, condim=str(cfg["condim"]))
    model = summary["model"]
    if system == "disk":
        # Balance controller: translation free, yaw driven, roll and pitch locked.
        body.remove(free)
        for i, axis in enumerate(["1 0 0", "0 1 0", "0 0 1"]):
            body.insert(i, ET.Element("joint", name=f"slide{i}", type="slide", axis=axis))
        body.insert(3, ET.Element("joint", name="yaw", type="hinge", axis="0 0 1"))
        body.set("pos", f"0 0 {model['radius']}")
        servo("wheel_joint")
        servo("yaw")
    elif system == "space":
        ET.SubElement(option, "flag", contact="disable")
        servo("joint1")
        servo("joint2")
    elif system == "rover":
        body.set("pos", f"0 0 {model['geometry']['wheel_radius']}")
        servo("front_wheel_joint")
        servo("steer_joint")
    else:
        body.set("pos", f"0 0 {model['radius']}")
        ET.SubElement(body, "site", name="centre")
        ET.SubElement(world, "site", name="world_frame")
        # World-frame angular velocity servos, as the harness's.
        for gear in ["0 0 0 1 0 0", "0 0 0 0 1 0", "0 0 0 0 0 1"]:
            ET.SubElement(actuators, "velocity", site="centre", refsite="world_frame", kv=repr(kv),
                          gear=gear)
    return mujoco.MjModel.from_xml_string(ET.tostring(mjcf, encoding="unicode"))


def controls(system, summary, ideal, cmd, dt, steps):
    """Per-step command rows: per driven joint (rate, angle at the step's start); the sphere:
    world-frame angular velocity (x, y, z)."""
    t_i, q_i = ideal
    grid = np.arange(steps + 1) * dt
    q = sample(t_i, q_i, grid)
    if system == "sphere":
        # Rolling without slip: x' = a w_y, y' = -a w_x (mean rates over each step).
        a = summary["model"]["radius"]
        dx, dy = np.diff(q[:, 0]) / dt, np.diff(q[:, 1]) / dt
        return np.stack([-dy / a, dx / a, np.zeros(steps)], axis=1)
    if system == "rover":
        # Open-loop replay: the recorded commands, held per step; angles are their integrals
        # (the steering angle clamped to the joint limits, as the harness's drive does).
        t_c, u = cmd
        k = np.minimum(np.searchsorted(t_c, grid[:-1] + 1e-9, side="right") - 1, len(u) - 1)
        u = u[np.maximum(k, 0)]
        rho = summary["model"]["geometry"]["wheel_radius"]
        w = u[:, 0] / rho
        # The angle targets are the angles at each step's start (as for the other systems).
        wheel = (np.cumsum(w) - w) * dt
        lo, hi = steer_limits(summary)
        steer = np.clip((np.cumsum(u[:, 1]) - u[:, 1]) * dt + q_i[0, 3], lo, hi)
        return np.stack([w, wheel, u[:, 1], steer], axis=1)
    cols = {"disk": [(2, 1.0), (3, -1.0)], "space": [(1, 1.0), (2, 1.0)]}[system]
    out = []
    for i, sign in cols:
        ang = sign * q[:, i]
        if system == "disk" and i == 3:
            ang = math.pi / 2 + ang  # yaw = pi/2 - alpha
        if system == "disk" and i == 2:
            ang = ang - q[0, 2]  # the wheel joint starts at 0
        # The angle term acts on the state at the step's start, so its target is the angle
        # there (as the harness's drive does); the velocity term carries the step's mean rate.
        out.append(np.diff(ang) / dt)
        out.append(ang[:-1])
    return np.stack(out, axis=1)


def steer_limits(summary):
    """The rover's steering joint limits from its URDF, rad."""
    urdf = os.path.normpath(os.path.join(ROOT, "scenarios", summary["model"]["urdf"]))
    for j in ET.parse(urdf).getroot().iter("joint"):
        if j.get("name") == "steer_joint":
            lim = j.find("limit")
            return float(lim.get("lower")), float(lim.get("upper"))
    return -math.inf, math.inf


def set_start(m, d, system, scenario, summary):
    mc.set_start(m, d, {"disk": "rolling disk", "space": "space robot", "rover": "rover",
                        "sphere": "rolling sphere"}[system], scenario, summary)


def to_model_states(system, m, states, summary, start_state):
    """MuJoCo states (one row per sample) as the harness's model coordinates (vectorised)."""
    qpos = states[:, 1 : 1 + m.nq]
    jq = lambda name: m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)]  # noqa: E731
    if system == "disk":
        # The wheel's centre is the yoke's origin: (slide0, slide1) from the body's start (0, 0).
        return np.stack([qpos[:, jq("slide0")], qpos[:, jq("slide1")], start_state[2] + qpos[:, jq("wheel_joint")],
                         math.pi / 2 - np.unwrap(qpos[:, jq("yaw")])], axis=1)
    f = jq("world_to_root")
    w, x, y, z = (qpos[:, f + 3 + i] for i in range(4))
    if system == "sphere":
        q = np.stack([w, x, y, z], axis=1)
        flips = np.sign(np.sum(q[1:] * q[:-1], axis=1))
        q[1:] *= np.cumprod(np.where(flips == 0, 1.0, flips))[:, None]
        return np.stack([qpos[:, f], qpos[:, f + 1], *q.T], axis=1)
    # Unwrapped continuously, as the harness's read-back does.
    yaw = np.unwrap(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    if system == "space":
        return np.stack([yaw, qpos[:, jq("joint1")], qpos[:, jq("joint2")]], axis=1)
    return np.stack([qpos[:, f], qpos[:, f + 1], yaw, qpos[:, jq("steer_joint")]], axis=1)


def mujoco_runs(system, scenario, summary, root, ctrl, dt, steps, repeats, cfg, start_state):
    """MuJoCo at dt with `cfg`: (model states, CPU time of each repeat, stable)."""
    kv = cfg["kv"]
    m = mujoco_model(system, summary, root, dt, cfg)
    d = mujoco.MjData(m)
    set_start(m, d, system, scenario, summary)
    mujoco.mj_forward(m, d)
    s0 = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, s0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    del kv
    cpu = []
    for _ in range(repeats):
        c0 = time.thread_time()
        states, _ = rollout.rollout(m, d, s0, ctrl[None, :, :])
        cpu.append(time.thread_time() - c0)
    # MuJoCo resets a diverging run to its start (and rollout stops stepping it): the
    # state's time column then no longer counts steps.
    stable = bool(np.all(np.isfinite(states[0])) and np.allclose(states[0][:, 0], dt * np.arange(1, steps + 1)))
    states = np.concatenate([s0[None, :], states[0]], axis=0)
    return to_model_states(system, m, states, summary, start_state), cpu, stable


def resolve_kv(key, cfg):
    """The sweep's relative kv values ('/10', 'x1', 'x10') against the system's base kv."""
    v = cfg["kv"]
    if isinstance(v, str):
        base = mj_config(key, 0)["kv"]
        cfg = {**cfg, "kv": base * {"/1000": 1e-3, "/100": 0.01, "/10": 0.1, "x1": 1.0, "x10": 10.0,
                                    "x100": 100.0}[v]}
    return cfg


# ---------------------------------------------------------------- Drake


def drake_runs(key, urdf, summary, start, ctrl, dt, steps, repeats, start_state, settings=None):
    """Drake at dt: (model states, CPU time of each repeat, finite)."""
    run = de.DrakeRun(key, urdf, summary, start, dt, steps, settings)
    run.build(drake_desired(key, run, ctrl, dt))
    x, cpu, ok = run.run(repeats)
    if x is None:
        return np.full((steps + 1, 6), np.nan), cpu, False
    return run.model_states(x, start_state), cpu, ok


def drake_desired(key, run, ctrl, dt):
    """Per-step rows for Drake's command port from `controls`' rows."""
    if key == "sphere":
        return ctrl @ run._sphere_K().T
    rates, start = ctrl[:, 0::2], ctrl[:, 1::2]
    if run.s["target"] == "end":
        # Drake's PD acts on the next step's angle: the commanded angle at the step's end.
        ang = np.concatenate([start[1:], start[-1:] + rates[-1:] * dt], axis=0)
        if key == "rover":
            lo, hi = steer_limits(run.summary)
            ang[:, 1] = np.clip(ang[:, 1], lo, hi)
    else:
        ang = start
    return np.concatenate([ang, rates], axis=1)


# ---------------------------------------------------------------- study


def gates_of(scenario):
    with open(os.path.join(ROOT, "scenarios", f"{scenario}.toml"), "rb") as f:
        th = tomllib.load(f)["thresholds"]
    goal = {k: v for k, v in th.items() if k.startswith("sim_goal_")}
    track = {k: v for k, v in th.items() if k.startswith("tracking_") and k.endswith("_max")}
    return goal, track


def normalised(metric_values, gates):
    """Largest metric / gate over `gates` (1 = at the gate)."""
    return max(metric_values[k] / g for k, g in gates.items())


def start_of(scenario):
    with open(os.path.join(ROOT, "scenarios", f"{scenario}.toml"), "rb") as f:
        return tomllib.load(f)["start"]


def harness_at(args, key, scenario, dt, tmp, repeats, gates):
    """The harness at dt: its run, the ideal run, the commands, the CPU times."""
    summary, h_cpu, mcap_path = harness_runs(args.bin, scenario, dt, tmp, repeats)
    topics = read_topics(mcap_path, ["/ideal/state", "/sim/state", "/plan/command"])
    t_i, v_i = topics["/ideal/state"]
    names = list(v_i[0].keys())
    q_i = state_array(v_i, names)
    t_s, v_s = topics["/sim/state"]
    q_s = state_array(v_s, names)
    t_c, v_c = topics["/plan/command"]
    u = state_array(v_c, list(v_c[0].keys()))
    goal = q_i[-1].copy()
    goal_file = summary["goal"]
    # The goal in model coordinates (display units in summary.json: degrees).
    for i, n in enumerate(names):
        if f"{n}_deg" in goal_file:
            goal[i] = math.radians(goal_file[f"{n}_deg"])
        elif n in goal_file:
            goal[i] = goal_file[n]
    # Check the recomputation on the harness's own run.
    mine = metrics(key, names, goal, t_i, q_i, t_s, q_s, dt)
    for k, gate in gates.items():
        h = summary["metrics"][k]
        # abs_tol: an angle near 0 from arccos is good to ~1e-8 rad only.
        assert math.isclose(mine[k], h, rel_tol=1e-6, abs_tol=1e-4 * gate), f"{scenario} dt {dt}: {k} {mine[k]} vs {h}"
    steps = summary["sim_steps"]
    ctrl = controls(key, summary, (t_i, q_i), (t_c, u), dt, steps)
    return {"dt": dt, "names": names, "goal": goal, "ideal": (t_i, q_i), "summary": summary, "steps": steps,
            "ctrl": ctrl, "harness": ((t_s, q_s), h_cpu, True)}


def mujoco_search(key, scenario, root, r, start, against, log):
    """Coordinate-wise search over MJ_SWEEP at r's dt: every run's row, the best configuration.

    One run per configuration (one CPU time); the objective is the error against `against`
    ((t, q), goal) in units of the system's tightest target."""
    dt = r["dt"]
    (t_a, q_a), goal_a = against
    entries, seen = [], {}

    def evaluate(cfg, setting, value):
        k = tuple(sorted(cfg.items()))
        if k in seen:
            return seen[k]
        (q, cpu, ok) = mujoco_runs(key, scenario, r["summary"], root, r["ctrl"], dt, r["steps"], 1,
                                   resolve_kv(key, cfg), r["ideal"][1][0])
        t = np.arange(len(q)) * dt
        if ok and np.all(np.isfinite(q)):
            vals = metrics(key, r["names"], goal_a, t_a, q_a, t, q, dt)
            obj = target_error(key, vals, tight(key), end=key == "rover")
        else:
            vals, obj = None, math.inf
        e = {"dt": dt, "setting": setting, "value": value, "config": dict(resolve_kv(key, cfg)),
             "cpu_s": cpu[0], "stable": ok, "objective": obj,
             "errors": {qn: (vals[goal_metric(m) if key == "rover" else m] if vals else None)
                        for qn, m, _u in TARGETS[key][0]}}
        entries.append(e)
        seen[k] = e
        return e

    best = mj_config(key, dt)
    best_e = evaluate(best, "start", "")
    for setting, values in MJ_SWEEP:
        if setting in MJ_SKIP.get(key, ()):
            continue
        cur = best[setting]
        for v in values:
            if v == cur or (setting == "kv" and v == "x1"):
                continue
            cand = {**best, setting: v}
            e = evaluate(cand, setting, v)
            if e["objective"] < best_e["objective"]:
                best, best_e = cand, e
        if setting == "kv" and isinstance(best["kv"], str):
            best = resolve_kv(key, best)
    best = resolve_kv(key, best)
    best_e["best"] = True
    log(f"    MuJoCo dt {dt * 1e3:g} ms: {len(entries)} configurations; best {mj_label(best, key)}: "
        f"{best_e['objective']:.3g} × the tightest target")
    return entries, best


def study(args, key, title, scenario, root, tmp, log=print):
    goal_gates, track_gates = gates_of(scenario)
    tracking_gated = bool(track_gates)
    if not track_gates:
        # A sanity gate only (the rover's open-loop replay): report the position tracking.
        track_gates = {"tracking_position_max": 1.0}
    all_gates = {**goal_gates, **track_gates}
    with open(os.path.join(ROOT, "scenarios", f"{scenario}.toml"), "rb") as f:
        dt0 = tomllib.load(f)["sim"]["dt"]
    start = start_of(scenario)
    urdf = None
    # Hydroelastic contact: the disk and the sphere (one run per dt: a secondary line). The
    # rover's 88 s runs are left to point contact, for the study's time.
    hydro = key in ("disk", "sphere") and not args.no_hydro

    def drake(r, repeats, settings=None):
        nonlocal urdf
        urdf = os.path.normpath(os.path.join(ROOT, "scenarios", r["summary"]["model"]["urdf"]))
        q, cpu, ok = drake_runs(key, urdf, r["summary"], start, r["ctrl"], r["dt"], r["steps"], repeats,
                                r["ideal"][1][0], settings)
        return (np.arange(len(q)) * r["dt"], q), cpu, ok

    def mj(r, repeats, cfg):
        q, cpu, ok = mujoco_runs(key, scenario, r["summary"], root, r["ctrl"], r["dt"], r["steps"], repeats, cfg,
                                 r["ideal"][1][0])
        return (np.arange(len(q)) * r["dt"], q), cpu, ok

    # The converged reference of each engine: its own run at REF_FACTOR x the shipped dt.
    ref = harness_at(args, key, scenario, dt0 * REF_FACTOR, tmp, 1, all_gates)
    log(f"  {title}: harness reference at {dt0 * REF_FACTOR * 1e3:g} ms done", flush=True)
    refs = {"harness": ref["harness"]}
    ref_cfg = {}
    if key == "rover":
        # The rover's ideal run is no yardstick for its physics (17 m of slip on every engine):
        # its MuJoCo configurations are ranked against MuJoCo's own converged run at the start
        # configuration.
        base_ref = mj(ref, 1, resolve_kv(key, mj_config(key, ref["dt"])))
    rows, sweep, best_of = [], [], {}
    engines = list(ENGINES) + (["drake_hydro"] if hydro else [])
    for factor in FACTORS:
        dt = dt0 * factor
        r = harness_at(args, key, scenario, dt, tmp, args.repeats, all_gates)
        against = ((base_ref[0], base_ref[0][1][-1]) if key == "rover" else (r["ideal"], r["goal"]))
        entries, best = mujoco_search(key, scenario, root, r, start, against, log)
        sweep += entries
        best_of[dt] = best
        runs = {"harness": r["harness"], "mujoco": mj(r, args.repeats, best), "drake": drake(r, args.repeats)}
        if hydro:
            runs["drake_hydro"] = drake(r, 1, {"contact": "hydroelastic"})
        row = {"dt": dt, "steps": r["steps"], "mujoco_config": best, "_runs": runs, "_r": r}
        rows.append(row)
        cells = []
        for eng in engines:
            (t_e, q_e), cpu, ok = runs[eng]
            vals = metrics(key, r["names"], r["goal"], *r["ideal"], t_e, q_e, dt) if ok else None
            cells.append(f"{eng} {statistics.median(cpu) * 1e3:.1f} ms "
                         + (f"{target_error(key, vals, tight(key)):.3g}" if vals else "diverged"))
        log(f"  {title:<26} dt {dt * 1e3:6.3f} ms | " + " | ".join(cells) + "  (CPU, error / tightest target)",
            flush=True)
    # References of MuJoCo (the best configuration at the shipped dt) and Drake.
    ref_cfg = best_of[dt0]
    refs["mujoco"] = mj(ref, 1, ref_cfg)
    refs["drake"] = drake(ref, 1)
    if hydro:
        refs["drake_hydro"] = drake(ref, 1, {"contact": "hydroelastic"})
    for eng in engines:
        if not refs[eng][2]:
            log(f"  {title}: the {eng} reference diverged")
    out_rows = []
    for row in rows:
        r, runs, dt = row.pop("_r"), row.pop("_runs"), row["dt"]
        for eng in engines:
            (t_e, q_e), cpu, ok = runs[eng]
            (t_r, q_r), _c, ref_ok = refs[eng]
            cell = {"cpu_s": statistics.median(cpu), "cpu_all": cpu, "stable": ok}
            if ok:
                vals = metrics(key, r["names"], r["goal"], *r["ideal"], t_e, q_e, dt)
                cell["ideal"] = {k: float(v) for k, v in vals.items()}
                cell["goal"] = float(normalised(vals, goal_gates))
                cell["tracking"] = float(normalised(vals, track_gates))
            if ok and ref_ok:
                conv = metrics(key, r["names"], q_r[-1], t_r, q_r, t_e, q_e, dt)
                cell["converged"] = {k: float(v) for k, v in conv.items()}
                cell["converged_goal"] = float(normalised(conv, goal_gates))
            row[eng] = cell
        out_rows.append(row)
    return {"system": title, "scenario": scenario, "goal_gates": goal_gates, "tracking_gates": track_gates,
            "tracking_gated": tracking_gated, "reference_dt": dt0 * REF_FACTOR, "shipped_dt": dt0,
            "engines": engines, "rows": out_rows, "mujoco_sweep": sweep, "mujoco_reference_config": ref_cfg,
            "drake_settings": de.DEFAULT, "repeats": args.repeats}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "anholonomy"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--systems", default="disk,space,rover,sphere")
    ap.add_argument("--factors", default=None, help="dt factors (comma-separated), default " + ",".join(map(str, FACTORS)))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "src", "images"))
    ap.add_argument("--no-hydro", action="store_true", help="skip Drake's hydroelastic runs")
    ap.add_argument("--table", action="store_true",
                    help="only print the tables (markdown) from the JSONs in --out")
    args = ap.parse_args()
    if args.factors:
        FACTORS[:] = [float(f) for f in args.factors.split(",")]
    if args.table:
        results = load_results(args.out)
        for key, res in results.items():
            plot(key, res, args.out)
        sys.stdout.write(tables_page(results))
        return
    if not os.path.exists(args.bin):
        sys.exit(f"{args.bin} not found: run `cargo build --release` first (or pass --bin)")
    os.makedirs(args.out, exist_ok=True)
    print(f"MuJoCo {mujoco.__version__}, Drake {de.VERSION}; CPU times are medians of {args.repeats}")
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    want = args.systems.split(",")
    results = {}
    for key, title, scenario, root in SYSTEMS:
        if key not in want:
            continue
        t0 = time.time()
        with tempfile.TemporaryDirectory() as tmp:
            res = study(args, key, title, scenario, root, tmp)
        res["png"] = os.path.relpath(plot(key, res, args.out), ROOT)
        res["wall_s"] = time.time() - t0
        res["load_average_end"] = os.getloadavg()
        results[key] = res
        with open(os.path.join(args.out, f"work_precision_{key}.json"), "w") as f:
            json.dump(res, f, indent=1, default=float)
        print(f"  {title}: {res['wall_s']:.0f} s wall", flush=True)
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())
    print("\n" + frontier_table(results))


if __name__ == "__main__":
    main()
