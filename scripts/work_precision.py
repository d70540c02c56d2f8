#!/usr/bin/env python3
"""Work-precision diagrams: accuracy per CPU-second, the harness (Rapier) against MuJoCo.

For each system (rolling disk, space robot, rover, rolling sphere) one shipped
scenario runs at several physics steps dt, from the scenario's own dt to 8x it:

* the harness runs a copy of the scenario with `[sim] dt` changed
  (`anholonomy run`, logs to a temporary directory); its metrics come from
  summary.json and its CPU time from `wall_time_s.physics_cpu` (the CPU time
  of the replay's thread: building the world, stepping, read-back, channels);
* MuJoCo (its URDF importer, a floating base, a ground plane with the
  scenario's friction on every geom, `implicitfast`, the same dt) replays the
  same task: servo drives on the same joints track the joint angles of the
  harness's ideal run (the rover: the integral of its recorded commands),
  with the per-step mean rate as velocity target (the sphere: world-frame
  angular velocity servos, as in the harness); `mujoco.rollout` on one thread,
  CPU time of that call (`time.thread_time`).

Both runs are compared with the same ideal kinematic run (the harness's, at
that dt, from run.mcap) by the harness's own metric definitions (this script
recomputes them for MuJoCo and checks its recomputation against the harness's
summary on the harness's own trajectory). Reported per run: the goal errors
and the maximum tracking errors the shipped scenario gates on, each divided by
its gate (1 = at the gate), and the CPU time (median of --repeats).

Each engine is also compared with its own converged run (the same engine at
1/16 of the shipped dt, once): the end state's deviation from it, divided by
the goal gate, is the error that comes from the step size alone (the classic
work-precision measure), apart from what each engine's model of the contact
adds.

Writes one PNG per system (error against CPU-seconds, both engines) and a
JSON of every number per system to --out (default docs/src/images), and prints the
frontier: per engine, the least CPU time of a run that meets every gate of the
shipped scenario, and the least CPU time whose end state is within the goal
gates of the engine's own converged run.

Usage (from the repository root, after `cargo build --release`):

    python3 scripts/work_precision.py [--repeats 3] [--systems disk,space,rover,sphere]

Installs `mujoco`, `mcap`, `numpy` and `matplotlib` with pip (--user) when
they are missing. Not run by .ci/run.
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

# Installs mujoco, mcap and numpy when missing; the URDF-to-MJCF helpers.
import mujoco_compare as mc  # noqa: E402

mc.ensure([("matplotlib", "matplotlib")])

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mujoco import rollout  # noqa: E402

# key, title, scenario, URDF root link
SYSTEMS = [
    ("disk", "rolling disk", "disk_paper", "yoke"),
    ("space", "space robot", "space_robot_paper", "vehicle"),
    ("rover", "rover (open-loop replay)", "rover_open_loop", "chassis"),
    ("sphere", "rolling sphere", "sphere_triangle_paper", "ball"),
]
# dt as multiples of the shipped one, up to 8x.
# Below 1: where an engine misses a gate at the shipped step, how small a step it needs.
FACTORS = [0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8]
# The rover's MuJoCo run only approaches its own converged run below a quarter of the
# shipped dt: one step more.
FACTORS_OF = {"rover": [0.125] + FACTORS}
# The converged reference run of each engine: this multiple of the shipped dt.
REF_FACTOR = 1 / 16
# The rover's end state after 88 s of open-loop slip does not settle to a goal gate (0.1 m)
# as dt shrinks: the harness's own runs at 1/32 and 1/16 of its dt end 0.96 gates apart,
# those at 1/16 and 1/8 2.3 gates apart (not chaos: 1e-6 more friction moves the end by
# ~1 mm). The frontier table adds these looser accuracies.
LOOSER_OF = {"rover": (3, 10, 30)}
# Servo gains of the MuJoCo drives: damping (implicit in implicitfast) large
# against the links' inertia, stiffness so that an angle error halves per step
# (kp dt / kv = 0.5; the stiffness is explicit, the damping keeps it stable).
KV = 1.0e4
# The rover's servos are far softer: MuJoCo's contact solver sees the servo's force
# before its implicit damping, so a step in the commanded steering rate (the rover's
# telegraph commands) throws the rover off the ground. Measured at dt 0.5-16 ms:
# kv 1e4 and 1e3 diverge where the rate first drops to zero (t = 0.5 s), 100 and 30 lift the
# chassis by 0.1-0.8 m, 10 and 3 by 0.03-1.4 m at 8-16 ms; kv 1 keeps it within
# 7 mm of wheel height at every dt, its wheel angle within 0.04 rad of the target at 2 ms.
KV_OF = {"rover": 1.0}


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
    """Summary and MCAP path of the harness at dt, with the median physics CPU time."""
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
    return summary, statistics.median(cpu), os.path.join(logs, scenario, "run.mcap")


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


def mujoco_model(system, summary, root, dt):
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
    option.set("integrator", "implicitfast")
    # Contact settings for accuracy rather than speed: elliptic friction cones with a
    # high impedance ratio (less creep), and contacts as stiff as MuJoCo advises
    # (time constant 4 ms, at least twice the step); the defaults (pyramidal, 20 ms)
    # let the disk hop on its rim and slip by centimetres.
    option.set("cone", "elliptic")
    option.set("impratio", "10")
    world = mjcf.find("worldbody")
    body = world.find(f".//body[@name='{root}']")
    free = body.find("freejoint")
    if free is None:
        free = body.find("joint[@type='free']")
    free.set("name", "world_to_root")
    for j in mjcf.iter("joint"):
        j.attrib.pop("actuatorfrcrange", None)
    mu = repr(sim["friction"])
    # MuJoCo takes the larger friction of two geoms: every geom gets the scenario's.
    solref = f"{max(0.004, 2 * dt)!r} 1"
    for g in mjcf.iter("geom"):
        g.set("friction", f"{mu} 0.005 0.0001")
        g.set("solref", solref)
    actuators = ET.SubElement(mjcf, "actuator")
    kv = KV_OF.get(system, KV)
    kp = kv * 0.5 / dt

    # No force limits: MuJoCo integrates a force-limited actuator's damping explicitly,
    # which this stiff a servo does not survive.
    def servo(joint, gear="1"):
        # Velocity target first, then angle target (ctrl columns in this order).
        ET.SubElement(actuators, "velocity", joint=joint, kv=repr(kv), gear=gear)
        ET.SubElement(actuators, "position", joint=joint, kp=repr(kp), gear=gear)

    if system != "space":
        ET.SubElement(world, "geom", type="plane", size="0 0 1", friction=f"{mu} 0.005 0.0001",
                      solref=solref)
    model = summary["model"]
    if system == "disk":
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
            ET.SubElement(actuators, "velocity", site="centre", refsite="world_frame", kv=repr(KV),
                          gear=gear)
    return mujoco.MjModel.from_xml_string(ET.tostring(mjcf, encoding="unicode"))


def controls(system, summary, ideal, cmd, dt, steps):
    """Per-step ctrl rows for the drives of `mujoco_model`."""
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
    """MuJoCo states (one row per sample) as the harness's model coordinates."""
    d = mujoco.MjData(m)
    rows = []
    jq = lambda name: m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)]  # noqa: E731
    if system == "rover":
        # Straight from qpos (the state's columns after time), no kinematics: the rover's
        # reference run has 7e5 samples, too many for a Python loop.
        qpos = states[:, 1 : 1 + m.nq]
        f = jq("world_to_root")
        w, x, y, z = (qpos[:, f + 3 + i] for i in range(4))
        # Unwrapped continuously, as the harness's read-back does.
        yaw = np.unwrap(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
        return np.stack([qpos[:, f], qpos[:, f + 1], yaw, qpos[:, jq("steer_joint")]], axis=1)
    prev = None
    for s in states:
        mujoco.mj_setState(m, d, s, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_kinematics(m, d)
        if system == "disk":
            wid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "wheel")
            x, y = d.xpos[wid][:2]
            row = [x, y, start_state[2] + d.qpos[jq("wheel_joint")], math.pi / 2 - d.qpos[jq("yaw")]]
        elif system == "sphere":
            f = jq("world_to_root")
            qw = d.qpos[f + 3 : f + 7].copy()
            if prev is not None and np.dot(qw, prev[2:6]) < 0:
                qw = -qw
            row = [d.qpos[f], d.qpos[f + 1], *qw]
        else:
            f = jq("world_to_root")
            w, x, y, z = d.qpos[f + 3 : f + 7]
            yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
            if system == "space":
                row = [yaw, d.qpos[jq("joint1")], d.qpos[jq("joint2")]]
            else:
                row = [d.qpos[f], d.qpos[f + 1], yaw, d.qpos[jq("steer_joint")]]
        if prev is not None and system != "sphere":
            # Unwrap the angles continuously, as the harness's read-back does.
            for i in {"disk": [3], "space": [0], "rover": [2]}[system]:
                row[i] = prev[i] + wrap(row[i] - prev[i])
        rows.append(row)
        prev = row
    return np.array(rows)


def mujoco_runs(system, scenario, summary, root, ideal, cmd, dt, steps, repeats):
    m = mujoco_model(system, summary, root, dt)
    ctrl = controls(system, summary, ideal, cmd, dt, steps)
    d = mujoco.MjData(m)
    set_start(m, d, system, scenario, summary)
    mujoco.mj_forward(m, d)
    s0 = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, s0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    cpu = []
    for _ in range(repeats):
        c0 = time.thread_time()
        states, _ = rollout.rollout(m, d, s0, ctrl[None, :, :])
        cpu.append(time.thread_time() - c0)
    # MuJoCo resets a diverging run to its start (and rollout stops stepping it): the
    # state's time column then no longer counts steps.
    stable = bool(np.all(np.isfinite(states[0])) and np.allclose(states[0][:, 0], dt * np.arange(1, steps + 1)))
    states = np.concatenate([s0[None, :], states[0]], axis=0)
    return states, m, statistics.median(cpu), stable


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


def study(args, key, title, scenario, root, tmp):
    goal_gates, track_gates = gates_of(scenario)
    tracking_gated = bool(track_gates)
    if not track_gates:
        # A sanity gate only (the rover's open-loop replay): report the position tracking.
        track_gates = {"tracking_position_max": 1.0}
    with open(os.path.join(ROOT, "scenarios", f"{scenario}.toml"), "rb") as f:
        dt0 = tomllib.load(f)["sim"]["dt"]
    def run_at(dt, repeats):
        """Both engines at dt: the harness's summary and trajectories, MuJoCo's trajectory, CPU times."""
        summary, h_cpu, mcap_path = harness_runs(args.bin, scenario, dt, tmp, repeats)
        topics = read_topics(mcap_path, ["/ideal/state", "/sim/state", "/plan/command"])
        t_i, v_i = topics["/ideal/state"]
        state_names = list(v_i[0].keys())
        q_i = state_array(v_i, state_names)
        t_s, v_s = topics["/sim/state"]
        q_s = state_array(v_s, state_names)
        t_c, v_c = topics["/plan/command"]
        u = state_array(v_c, list(v_c[0].keys()))
        goal = q_i[-1].copy()
        goal_file = summary["goal"]
        # The goal in model coordinates (display units in summary.json: degrees).
        for i, n in enumerate(state_names):
            if f"{n}_deg" in goal_file:
                goal[i] = math.radians(goal_file[f"{n}_deg"])
            elif n in goal_file:
                goal[i] = goal_file[n]
        # Check the recomputation on the harness's own run.
        mine = metrics(key, state_names, goal, t_i, q_i, t_s, q_s, dt)
        for k, gate in {**goal_gates, **track_gates}.items():
            h = summary["metrics"][k]
            # abs_tol: an angle near 0 from arccos is good to ~1e-8 rad only.
            assert math.isclose(mine[k], h, rel_tol=1e-6, abs_tol=1e-4 * gate), f"{scenario} dt {dt}: {k} {mine[k]} vs {h}"
        steps = summary["sim_steps"]
        states, m, k_cpu, stable = mujoco_runs(key, scenario, summary, root, (t_i, q_i), (t_c, u), dt, steps,
                                               repeats)
        q_m = to_model_states(key, m, states, summary, q_i[0])
        t_m = np.arange(len(q_m)) * dt
        return {"names": state_names, "goal": goal, "ideal": (t_i, q_i), "summary": summary, "steps": steps,
                "harness": ((t_s, q_s), h_cpu), "mujoco": ((t_m, q_m), k_cpu), "mujoco_stable": stable}

    # The converged reference of each engine: its own run at REF_FACTOR x the shipped dt
    # (classic work-precision: the error that comes from the step alone), run once.
    ref = run_at(dt0 * REF_FACTOR, 1)
    rows = []
    for factor in FACTORS_OF.get(key, FACTORS):
        dt = dt0 * factor
        r = run_at(dt, args.repeats)
        t_i, q_i = r["ideal"]
        row = {"dt": dt, "steps": r["steps"]}
        for eng in ("harness", "mujoco"):
            (t_e, q_e), cpu = r[eng]
            vals = metrics(key, r["names"], r["goal"], t_i, q_i, t_e, q_e, dt)
            (t_r, q_r), _ = ref[eng]
            # Against the converged run: its trajectory as the ideal, its end as the goal.
            conv = metrics(key, r["names"], q_r[-1], t_r, q_r, t_e, q_e, dt)
            row[eng] = {
                "cpu_s": cpu,
                "goal": float(normalised(vals, goal_gates)),
                "tracking": float(normalised(vals, track_gates)),
                "converged_goal": float(normalised(conv, goal_gates)),
                "converged_tracking": float(normalised(conv, track_gates)),
                "metrics": {k: float(vals[k]) for k in list(goal_gates) + list(track_gates)},
            }
            if eng == "mujoco" and not (r["mujoco_stable"] and ref["mujoco_stable"]):
                # A diverged run (or reference) has no error to speak of: it meets no gate.
                row[eng]["unstable"] = not r["mujoco_stable"]
                for what in ("goal", "tracking") if not r["mujoco_stable"] else ():
                    row[eng][what] = math.inf
                for what in ("converged_goal", "converged_tracking"):
                    row[eng][what] = math.inf
            row[eng]["meets_gates"] = bool(row[eng]["goal"] <= 1) and bool(
                row[eng]["tracking"] <= 1 or "tracking_position_max" in track_gates and len(track_gates) == 1
            )
        rows.append(row)
        h, k = row["harness"], row["mujoco"]
        print(f"  {title:<26} dt {dt * 1e3:6.2f} ms | harness cpu {h['cpu_s'] * 1e3:8.2f} ms vs ideal: goal "
              f"{h['goal']:8.3g} track {h['tracking']:8.3g}, vs converged: goal {h['converged_goal']:8.3g}"
              f" | MuJoCo cpu {k['cpu_s'] * 1e3:8.2f} ms vs ideal: goal {k['goal']:8.3g} track "
              f"{k['tracking']:8.3g}, vs converged: goal {k['converged_goal']:8.3g}", flush=True)
    return {"system": title, "scenario": scenario, "goal_gates": goal_gates, "tracking_gates": track_gates,
            "tracking_gated": tracking_gated, "reference_dt": dt0 * REF_FACTOR, "rows": rows}


def plot(res, out_dir, key):
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2), constrained_layout=True)
    for ax, what, label in ((axes[0], "goal", "goal error vs ideal run / gate"),
                            (axes[1], "tracking", "max tracking error vs ideal run / gate"
                             if res.get("tracking_gated", True) else "max position tracking error vs ideal run, m"),
                            (axes[2], "converged_goal",
                             f"end-state deviation from own run at {res['reference_dt'] * 1e3:g} ms / goal gate")):
        for eng, color, name in (("harness", "tab:orange", "harness (Rapier)"), ("mujoco", "tab:blue", "MuJoCo")):
            # Diverged runs (MuJoCo's, error inf) are left out and named in the legend.
            rows = [r for r in res["rows"] if math.isfinite(r[eng][what])]
            lost = [f"{r['dt'] * 1e3:g}" for r in res["rows"] if r[eng].get("unstable")]
            x = [r[eng]["cpu_s"] for r in rows]
            y = [max(r[eng][what], 1e-6) for r in rows]
            ax.plot(x, y, "o-", color=color, label=name + (f" (diverged at {', '.join(lost)} ms)" if lost else ""))
            for r, xi, yi in zip(rows, x, y):
                ax.annotate(f"{r['dt'] * 1e3:g}", (xi, yi), textcoords="offset points", xytext=(4, 4),
                            fontsize=7, color=color)
        if what != "tracking" or res.get("tracking_gated", True):
            ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time of the physics run, s")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    fig.suptitle(f"{res['system']} ({res['scenario']}): points labelled with dt in ms; dashed: the shipped gate")
    path = os.path.join(out_dir, f"work_precision_{key}.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def frontier(res, converged=False):
    """Per engine: the cheapest run meeting every gate (CPU s, dt), or None.

    converged: the goal gates applied to the end state's deviation from the engine's own
    converged run (the step's share of the error) instead of the error against the ideal
    run. (Not the tracking gates: on driven joints both engines follow the commanded angle,
    and between two step sizes that differs by the commands' own sampling.)"""
    out = {}
    for eng in ("harness", "mujoco"):
        if converged:
            ok = [r for r in res["rows"] if r[eng]["converged_goal"] <= 1]
        else:
            ok = [r for r in res["rows"] if r[eng]["meets_gates"]]
        best = min(ok, key=lambda r: r[eng]["cpu_s"]) if ok else None
        out[eng] = (best[eng]["cpu_s"], best["dt"]) if best else None
    return out


def extrapolated(res, eng, what):
    """(CPU s, dt) where a power law through the two smallest-dt runs reaches the gate.

    For an engine that misses a gate at every measured dt: error ~ dt^p and CPU ~ 1/dt
    from the two smallest steps measured."""
    rows = sorted(res["rows"], key=lambda r: r["dt"])[:2]
    e = [max(r[eng][w] for w in what) for r in rows]
    if e[0] <= 1 or e[1] <= e[0]:
        return None
    p = math.log(e[1] / e[0]) / math.log(rows[1]["dt"] / rows[0]["dt"])
    dt = rows[0]["dt"] * e[0] ** (-1 / p)
    return rows[0][eng]["cpu_s"] * rows[0]["dt"] / dt, dt


def cpu_cell(cpu_s, dt, approx=""):
    """'35.4 ms (1.5 ms)', '6.7 s (0.25 ms)', '≈ 79 s (≈ 0.55 µs)'."""
    t = f"{cpu_s:.2g} s" if cpu_s >= 1 else f"{cpu_s * 1e3:.3g} ms"
    if approx:
        sig2 = lambda v: f"{float(f'{v:.2g}'):g}"  # noqa: E731
        t = f"{sig2(cpu_s)} s" if cpu_s >= 1 else f"{sig2(cpu_s * 1e3)} ms"
    d = f"{dt * 1e3:.2g} ms" if dt >= 1e-4 else f"{dt * 1e6:.2g} µs"
    return f"{approx}{t} ({approx}{d})"


def ratio_cell(cpu, approx):
    if not all(cpu):
        return "–"
    r = cpu[1] / cpu[0]
    text = f"{r:.2g}" if r < 100 else f"{float(f'{r:.2g}'):.0f}"
    return ("≈ " if approx else "") + text


def table(out_dir):
    """The frontier table (markdown) from the per-system JSONs in out_dir."""
    print("| system | gates against | harness CPU (dt) | MuJoCo CPU (dt) | MuJoCo / harness |")
    print("|---|---|---|---|---|")
    for key, *_ in SYSTEMS:
        path = os.path.join(out_dir, f"work_precision_{key}.json")
        if not os.path.exists(path):
            continue
        res = json.load(open(path))
        for which, against, what in (("frontier", "ideal run", ("goal", "tracking")),
                                     ("frontier_converged", "own converged run (goal gates)",
                                      ("converged_goal",))):
            if key == "rover" and which == "frontier":
                what = ("goal",)
            cells, cpu, approx = [], [], False
            for eng in ("harness", "mujoco"):
                f = res[which][eng]
                if f:
                    cells.append(cpu_cell(*f))
                    cpu.append(f[0])
                else:
                    # No power law for the rover: its converged run is itself unsettled by
                    # about a goal gate (LOOSER_OF), below which no trend can be read.
                    x = extrapolated(res, eng, what) if key not in LOOSER_OF else None
                    cells.append(cpu_cell(*x, approx="≈ ") + ", extrapolated" if x else "never")
                    cpu.append(x[0] if x else None)
                    approx = approx or bool(x)
            ratio = ratio_cell(cpu, approx)
            print(f"| {res['system']} | {against} | {cells[0]} | {cells[1]} | {ratio} |")
        for k in LOOSER_OF.get(key, ()):
            cells, cpu = [], []
            for eng in ("harness", "mujoco"):
                ok = [r for r in res["rows"] if r[eng]["converged_goal"] <= k]
                best = min(ok, key=lambda r: r[eng]["cpu_s"]) if ok else None
                cells.append(cpu_cell(best[eng]["cpu_s"], best["dt"]) if best else "never")
                cpu.append(best[eng]["cpu_s"] if best else None)
            ratio = ratio_cell(cpu, False)
            print(f"| {res['system']} | own converged run ({k:g} × goal gates) | {cells[0]} | {cells[1]} | {ratio} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "anholonomy"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--systems", default="disk,space,rover,sphere")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "src", "images"))
    ap.add_argument("--table", action="store_true",
                    help="only print the frontier table (markdown) from the JSONs in --out")
    args = ap.parse_args()
    if args.table:
        table(args.out)
        return
    if not os.path.exists(args.bin):
        sys.exit(f"{args.bin} not found: run `cargo build --release` first (or pass --bin)")
    os.makedirs(args.out, exist_ok=True)
    print(f"MuJoCo {mujoco.__version__}; CPU times are medians of {args.repeats}")
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    want = args.systems.split(",")
    results = {}
    for key, title, scenario, root in SYSTEMS:
        if key not in want:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            res = study(args, key, title, scenario, root, tmp)
        res["png"] = os.path.relpath(plot(res, args.out, key), ROOT)
        res["frontier"] = frontier(res)
        res["frontier_converged"] = frontier(res, converged=True)
        results[key] = res
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())
    for which, head in (("frontier", "every gate of the shipped scenario (against the ideal run)"),
                        ("frontier_converged", "the goal gates applied to the end state's deviation from "
                                               "the engine's own converged run")):
        print(f"\nFrontier: least CPU time of a run meeting {head}")
        print(f"{'system':<26} {'harness':>22} {'MuJoCo':>22} {'MuJoCo/harness':>15}")
        for key, res in results.items():
            cells = []
            for eng in ("harness", "mujoco"):
                f = res[which][eng]
                cells.append(f"{f[0] * 1e3:8.2f} ms at {f[1] * 1e3:g} ms" if f else "never")
            h, k = res[which]["harness"], res[which]["mujoco"]
            ratio = f"{k[0] / h[0]:.2f}" if h and k else "-"
            print(f"{res['system']:<26} {cells[0]:>22} {cells[1]:>22} {ratio:>15}")
    for key, res in results.items():
        with open(os.path.join(args.out, f"work_precision_{key}.json"), "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
