#!/usr/bin/env python3
"""Physics steps per second: the harness (Rapier) next to MuJoCo on the same URDFs.

For each system it runs one shipped scenario with the harness
(`anholonomy run`, logs to a temporary directory) and reads the harness's own
rate from summary.json (`sim_steps_per_second`: physics steps over the replay's
wall time, read-back and channels included). It then loads the same URDF into
MuJoCo with MuJoCo's own URDF importer, adds what the harness adds (a floating
base, a ground plane with the scenario's friction, velocity actuators on the
driven joints, the disk's roll/pitch lock, zero gravity and no contacts for the
space robot), and replays the commands the harness logged (`/plan/command` in
run.mcap, one per step, zero after they end) for the same number of steps at
the same dt with `mujoco.rollout` on one thread. Harness and MuJoCo runs
alternate, `--repeats` times each, and medians are printed.

The MuJoCo side only has to do the same work per step: it is not a fidelity
comparison (the sphere's drive acts about body axes in MuJoCo, world axes in
the harness).

The seed-004 pair (`dilf_pair_open`) is built from two imports of
`models/mobile_manipulator.urdf` (fixed joints kept as bodies, as the harness
keeps the casters and the gripper), each gripper on a compliant wrist (three
slide and three hinge joints with the scenario's stiffness, damping and
travel), and the 10 mm rod as the harness's chain: N + 1 capsules joined by
three hinges per joint point with the rod's torsion and bending springs
(GJ/l, EI/l, dampers 2 ms × k), its end bodies welded to the grippers at the
start. Robots and rod collide with the ground only; the casters are
frictionless. Velocity servos on the wheels ((v ∓ ω b)/r from the logged
(v, ω)) and the arm joints replay the harness's `/sim/command` (its feedback
law's commands, one per step).

Usage (from the repository root, after `cargo build --release`):

    python3 scripts/mujoco_compare.py [--repeats 5] [--bin target/release/anholonomy]

Installs `mujoco` and `mcap` with pip (--user outside a virtual environment)
when they are missing. Not run
by .ci/run.
"""

import argparse
import json
import os
import math
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def ensure(modules):
    missing = []
    for mod, pkg in modules:
        try:
            __import__(mod)
        except ImportError:
            missing.append(pkg)
    if missing:
        print(f"installing {' '.join(missing)} with pip ...", file=sys.stderr)
        # Inside a virtual environment pip refuses --user (and needs none).
        venv = sys.prefix != sys.base_prefix
        user = [] if venv else ["--user"]
        subprocess.check_call(
            [sys.executable, "-m", "pip", "install", "--quiet", *user, *missing]
        )
        if not venv:
            import site

            site.addsitedir(site.getusersitepackages())


ensure([("mujoco", "mujoco"), ("mcap", "mcap"), ("numpy", "numpy")])

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from mujoco import rollout  # noqa: E402

# system, scenario, URDF root link, actuated joints (with the command scale)
SYSTEMS = [
    ("rolling disk", "disk_paper", "yoke"),
    ("space robot", "space_robot_paper", "vehicle"),
    ("rover (5 wheel contacts)", "rover_open_loop", "chassis"),
    ("rolling sphere", "sphere_triangle_paper", "ball"),
    ("mobile manipulator pair", "dilf_pair_open", "base_link"),
]

# The mobile manipulator (src/model/mobile_manipulator.rs, the physics' wrist
# and rod defaults).
WHEEL_RADIUS, HALF_TRACK, GRASP_OFFSET = 0.1, 0.32, 0.16
ARM = [f"joint{i}" for i in range(1, 7)]


def harness_run(binary, scenario, logs):
    path = os.path.join(ROOT, "scenarios", f"{scenario}.toml")
    subprocess.run(
        [binary, "run", path, "--logs", logs, "--quiet"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    with open(os.path.join(logs, scenario, "summary.json")) as f:
        return json.load(f)


def logged_commands(mcap_path, topic="/plan/command"):
    rows = []
    with open(mcap_path, "rb") as f:
        for _schema, _channel, msg in make_reader(f).iter_messages(topics=[topic]):
            rows.append(list(json.loads(msg.data)["values"].values()))
    return np.array(rows, dtype=float)


def floating_urdf(urdf_path, root):
    """The URDF with a `world` link and a floating joint to the root (MuJoCo: free joint)."""
    tree = ET.parse(urdf_path)
    robot = tree.getroot()
    robot.insert(0, ET.Element("link", name="world"))
    joint = ET.SubElement(robot, "joint", name="world_to_root", type="floating")
    ET.SubElement(joint, "parent", link="world")
    ET.SubElement(joint, "child", link=root)
    return ET.tostring(robot, encoding="unicode")


def mujoco_model(system, summary, urdf_path, root):
    """MJCF built from MuJoCo's import of the URDF plus the harness's additions."""
    m = mujoco.MjModel.from_xml_string(floating_urdf(urdf_path, root))
    with tempfile.TemporaryDirectory() as tmp:
        xml_path = os.path.join(tmp, "model.xml")
        mujoco.mj_saveLastXML(xml_path, m)
        mjcf = ET.parse(xml_path).getroot()
    sim = summary["sim_settings"]
    option = ET.SubElement(mjcf, "option")
    option.set("timestep", repr(sim["dt"]))
    option.set("gravity", " ".join(repr(g) for g in sim["gravity"]))
    option.set("integrator", "implicitfast")
    world = mjcf.find("worldbody")
    body = world.find(f".//body[@name='{root}']")
    free = body.find("freejoint")
    if free is None:
        free = body.find("joint[@type='free']")
    free.set("name", "world_to_root")
    actuators = ET.SubElement(mjcf, "actuator")

    # Velocity servos without force limits (nor the joint limits MuJoCo imports
    # from the URDF's `effort`): a clamped actuator force is applied explicitly
    # and makes the light steering link unstable at this gain.
    for j in mjcf.iter("joint"):
        j.attrib.pop("actuatorfrcrange", None)

    def velocity(joint, gear="1"):
        ET.SubElement(actuators, "velocity", joint=joint, kv="1000", gear=gear)

    mu = repr(sim["friction"])
    if system != "space robot":
        ET.SubElement(world, "geom", type="plane", size="0 0 1", friction=f"{mu} 0.005 0.0001")
    model = summary["model"]
    if system == "rolling disk":
        # Balance controller: translation free, yaw driven, roll and pitch locked.
        body.remove(free)
        for i, axis in enumerate(["1 0 0", "0 1 0", "0 0 1"]):
            body.insert(i, ET.Element("joint", name=f"slide{i}", type="slide", axis=axis))
        body.insert(3, ET.Element("joint", name="yaw", type="hinge", axis="0 0 1"))
        body.set("pos", f"0 0 {model['radius']}")
        velocity("wheel_joint")
        velocity("yaw", gear="-1")
    elif system == "space robot":
        ET.SubElement(option, "flag", contact="disable")
        velocity("joint1")
        velocity("joint2")
    elif system.startswith("rover"):
        rho = model["geometry"]["wheel_radius"]
        body.set("pos", f"0 0 {rho}")
        velocity("front_wheel_joint", gear=repr(rho))  # ctrl u1 (m/s) → u1/ρ rad/s
        velocity("steer_joint")
    else:
        body.set("pos", f"0 0 {model['radius']}")
        # The free joint's rotational dofs (body axes; timing only).
        velocity("world_to_root", gear="0 0 0 1 0 0")
        velocity("world_to_root", gear="0 0 0 0 1 0")
    return mujoco.MjModel.from_xml_string(ET.tostring(mjcf, encoding="unicode"))


def prefixed(element, prefix):
    """A copy of an MJCF subtree with every name prefixed (robot 2)."""
    import copy

    out = copy.deepcopy(element)
    for e in out.iter():
        for key in ("name", "joint", "body1", "body2"):
            if key in e.attrib:
                e.set(key, prefix + e.get(key))
    return out


def pair_model(summary, urdf_path, scenario):
    """Two mobile manipulators holding the rod (see the module docs)."""
    with open(os.path.join(ROOT, "scenarios", f"{scenario}.toml"), "rb") as f:
        sc = tomllib.load(f)
    tree = ET.parse(urdf_path)
    robot = tree.getroot()
    mj = ET.SubElement(robot, "mujoco")
    ET.SubElement(mj, "compiler", fusestatic="false", discardvisual="true", balanceinertia="true")
    text = ET.tostring(robot, encoding="unicode")
    m = mujoco.MjModel.from_xml_string(floating_urdf_text(text, "base_link"))
    with tempfile.TemporaryDirectory() as tmp:
        xml_path = os.path.join(tmp, "model.xml")
        mujoco.mj_saveLastXML(xml_path, m)
        mjcf = ET.parse(xml_path).getroot()
    world = mjcf.find("worldbody")
    base = world.find("body[@name='base_link']")
    free = base.find("freejoint")
    if free is None:
        free = base.find("joint[@type='free']")
    free.set("name", "base_free")
    # Compliant wrist: three slides and three hinges about the grasp point.
    tool = base.find(".//body[@name='tool']")
    wrist = sc.get("model", {}).get("wrist", {})
    k = wrist.get("stiffness", [400.0, 400.0, 400.0, 50.0, 50.0, 50.0])
    c = wrist.get("damping", [25.0, 25.0, 25.0, 2.0, 2.0, 2.0])
    travel = wrist.get("travel", [0.2, 0.2, 0.2, 0.35, 0.35, 0.35])
    at = f"0 0 {GRASP_OFFSET}"
    for i, (kind, axis) in enumerate(
        [("slide", "1 0 0"), ("slide", "0 1 0"), ("slide", "0 0 1"),
         ("hinge", "1 0 0"), ("hinge", "0 1 0"), ("hinge", "0 0 1")]
    ):
        tool.insert(i, ET.Element(
            "joint", name=f"wrist{i}", type=kind, axis=axis, pos=at,
            stiffness=repr(k[i]), damping=repr(c[i]), limited="true",
            range=f"{-travel[i]} {travel[i]}",
        ))
    # Robots meet the ground only (the harness: never their own robot).
    for g in base.iter("geom"):
        g.set("contype", "2")
        g.set("conaffinity", "1")
    for name in ("caster_front", "caster_rear"):
        for g in base.find(f".//body[@name='{name}']").iter("geom"):
            # Frictionless: a contact takes the higher-priority geom's condim
            # (else the larger of the two, the ground's).
            g.set("condim", "1")
            g.set("priority", "1")
    world.append(prefixed(base, "r2_"))
    sim = summary["sim_settings"]
    option = ET.SubElement(mjcf, "option")
    option.set("timestep", repr(sim["dt"]))
    option.set("gravity", " ".join(repr(g) for g in sim["gravity"]))
    option.set("integrator", "implicitfast")
    mu = repr(sim["friction"])
    ET.SubElement(world, "geom", name="ground", type="plane", size="0 0 1",
                  friction=f"{mu} 0.005 0.0001", contype="1", conaffinity="7")
    actuators = ET.SubElement(mjcf, "actuator")
    for p in ("", "r2_"):
        for j in ["left_wheel_joint", "right_wheel_joint", *ARM]:
            ET.SubElement(actuators, "velocity", joint=p + j, kv="1000")
    # First pass: the robots at the start, for the grasp points.
    m0 = mujoco.MjModel.from_xml_string(ET.tostring(mjcf, encoding="unicode"))
    d0 = mujoco.MjData(m0)
    set_pair_start(m0, d0, sc["start"])
    mujoco.mj_forward(m0, d0)
    grasp, tools = [], []
    for p in ("", "r2_"):
        b = mujoco.mj_name2id(m0, mujoco.mjtObj.mjOBJ_BODY, p + "tool")
        rot = d0.xmat[b].reshape(3, 3)
        grasp.append(d0.xpos[b] + rot @ np.array([0.0, 0.0, GRASP_OFFSET]))
        tools.append((d0.xpos[b].copy(), rot.copy(), d0.xquat[b].copy()))
    # The rod: N joints at s = (k − ½) l, N + 1 bodies (as physics::beam).
    beam = sc["model"]["beam"]
    n = beam.get("physics_segments", 10)
    e, g_mod, rho = beam.get("youngs_modulus", 40e9), beam.get("shear_modulus", 4e9), beam.get("density", 2000.0)
    d = beam.get("diameter", 0.01)
    a, i_b = math.pi * d * d / 4, math.pi * d**4 / 64
    p0, p2 = grasp
    length = float(np.linalg.norm(p2 - p0))
    axis = (p2 - p0) / length
    l = length / n
    kb, kt = e * i_b / l, g_mod * 2 * i_b / l
    x = axis
    z = np.array([0.0, 0.0, 1.0]) - axis[2] * axis
    z /= np.linalg.norm(z)
    y = np.cross(z, x)
    rmat = np.column_stack([x, y, z])
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, rmat.flatten())
    qs = " ".join(repr(float(v)) for v in quat)
    parent = world
    for j in range(n + 1):
        s0 = 0.0 if j == 0 else (length if j == n else j * l)
        lo = 0.0 if j == 0 else (j - 0.5) * l
        hi = length if j == n else (j + 0.5) * l
        if j == 0:
            body = ET.SubElement(parent, "body", name="rod0",
                                 pos=" ".join(repr(float(v)) for v in p0), quat=qs)
            ET.SubElement(body, "freejoint", name="rod_free")
        else:
            body = ET.SubElement(parent, "body", name=f"rod{j}", pos=f"{float(s0 - prev)} 0 0")
            at = f"{(j - 0.5) * l - s0} 0 0"
            for axis_name, ax, kk in (("x", "1 0 0", kt), ("y", "0 1 0", kb), ("z", "0 0 1", kb)):
                ET.SubElement(body, "joint", name=f"rod{j}_{axis_name}", type="hinge", axis=ax,
                              pos=at, stiffness=repr(kk), damping=repr(2e-3 * kk))
        ET.SubElement(body, "geom", type="capsule", size=f"{d / 2}",
                      fromto=f"{lo - s0} 0 0 {hi - s0} 0 0",
                      mass=repr(rho * a * (hi - lo)), contype="4", conaffinity="1")
        parent, prev = body, s0
    # Each end welded to its gripper where it is at the start.
    eq = ET.SubElement(mjcf, "equality")
    for (xt, rt, qt), end, name in zip(tools, (p0, p2), ("tool", "r2_tool")):
        rel = rt.T @ (end - xt)
        qinv, qrel = np.empty(4), np.empty(4)
        mujoco.mju_negQuat(qinv, qt)
        mujoco.mju_mulQuat(qrel, qinv, quat)
        pose = " ".join(repr(float(v)) for v in [*rel, *qrel])
        ET.SubElement(eq, "weld", body1=name, body2="rod0" if name == "tool" else f"rod{n}",
                      relpose=pose)
    m = mujoco.MjModel.from_xml_string(ET.tostring(mjcf, encoding="unicode"))
    return m, lambda dd: set_pair_start(m, dd, sc["start"], keep_rod=True)


def floating_urdf_text(text, root):
    robot = ET.fromstring(text)
    robot.insert(0, ET.Element("link", name="world"))
    joint = ET.SubElement(robot, "joint", name="world_to_root", type="floating")
    ET.SubElement(joint, "parent", link="world")
    ET.SubElement(joint, "child", link=root)
    return ET.tostring(robot, encoding="unicode")


def set_pair_start(m, d, start, keep_rod=False):
    """Both robots at the scenario's start (file units: m and degrees); the
    rod, when there is one, where the model placed it."""
    def q(joint):
        return m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, joint)]

    for r, p in enumerate(("", "r2_")):
        x, y, th, *arm = start[9 * r: 9 * r + 9]
        f = q(p + "base_free")
        d.qpos[f: f + 3] = [x, y, 0.0]
        d.qpos[f + 3: f + 7] = quat_z(math.radians(th))
        for name, v in zip(ARM, arm):
            d.qpos[q(p + name)] = math.radians(v)
    if keep_rod:
        f = q("rod_free")
        d.qpos[f: f + 7] = m.qpos0[f: f + 7]


def pair_controls(commands, n_ctrl):
    """Wheel rates (v ∓ ω b)/r and joint rates per robot from the logged
    (v, ω, q̇1..q̇6) of both robots."""
    out = np.zeros((len(commands), n_ctrl))
    for r in range(2):
        u = commands[:, 8 * r: 8 * r + 8]
        v, w = u[:, 0], u[:, 1]
        out[:, 8 * r] = (v - w * HALF_TRACK) / WHEEL_RADIUS
        out[:, 8 * r + 1] = (v + w * HALF_TRACK) / WHEEL_RADIUS
        out[:, 8 * r + 2: 8 * r + 8] = u[:, 2:]
    return out


def quat_z(angle):
    return [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return [
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ]


def set_start(m, d, system, scenario, summary):
    """The scenario's start state (file units: m and degrees) in MuJoCo's coordinates."""
    with open(os.path.join(ROOT, "scenarios", f"{scenario}.toml"), "rb") as f:
        start = tomllib.load(f)["start"]

    def q(joint):
        return m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, joint)]

    rad = [math.radians(v) for v in start]
    model = summary["model"]
    if system == "rolling disk":
        d.qpos[q("slide0")], d.qpos[q("slide1")] = start[0], start[1]
        d.qpos[q("yaw")] = math.pi / 2 - rad[3]
        return
    free = q("world_to_root")
    if system == "space robot":
        d.qpos[free + 3 : free + 7] = quat_z(rad[0])
        d.qpos[q("joint1")], d.qpos[q("joint2")] = rad[1], rad[2]
    elif system.startswith("rover"):
        d.qpos[free : free + 3] = [start[0], start[1], model["geometry"]["wheel_radius"]]
        d.qpos[free + 3 : free + 7] = quat_z(rad[2])
        d.qpos[q("steer_joint")] = rad[3]
    else:
        # z-y-z Euler angles (α, θ, φ): R = Rz(α) Ry(θ) Rz(φ).
        ry = [math.cos(rad[3] / 2), 0.0, math.sin(rad[3] / 2), 0.0]
        d.qpos[free : free + 3] = [start[0], start[1], model["radius"]]
        d.qpos[free + 3 : free + 7] = quat_mul(quat_mul(quat_z(rad[2]), ry), quat_z(rad[4]))


def mujoco_rate(m, controls, steps, start):
    d = mujoco.MjData(m)
    start(d)
    mujoco.mj_forward(m, d)
    state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    ctrl = np.zeros((steps, m.nu))
    n = min(steps, len(controls))
    ctrl[:n, : controls.shape[1]] = controls[:n, : m.nu]
    t0 = time.perf_counter()
    rollout.rollout(m, d, state, ctrl[None, :, :])
    wall = time.perf_counter() - t0
    return steps / wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "anholonomy"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--only", help="run only the systems whose name contains this")
    args = ap.parse_args()
    if not os.path.exists(args.bin):
        sys.exit(f"{args.bin} not found: run `cargo build --release` first (or pass --bin)")
    print(f"MuJoCo {mujoco.__version__}, {args.repeats} alternating runs each, medians")
    # Both rates are wall-clock rates: on a shared machine they say little without the load.
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    header = f"{'system':<26} {'scenario':<22} {'steps':>7} {'harness/s':>10} {'MuJoCo/s':>10} {'ratio':>6}"
    print(header)
    for system, scenario, root in SYSTEMS:
        if args.only and args.only not in system:
            continue
        harness, muj = [], []
        with tempfile.TemporaryDirectory() as logs:
            for _ in range(args.repeats):
                summary = harness_run(args.bin, scenario, logs)
                harness.append(summary["wall_time_s"]["sim_steps_per_second"])
                if not muj:
                    urdf = os.path.join(ROOT, "scenarios", summary["model"]["urdf"])
                    mcap_path = os.path.join(logs, scenario, "run.mcap")
                    steps = summary["sim_steps"]
                    if system == "mobile manipulator pair":
                        m, start = pair_model(summary, os.path.normpath(urdf), scenario)
                        controls = pair_controls(logged_commands(mcap_path, "/sim/command"), m.nu)
                    else:
                        m = mujoco_model(system, summary, os.path.normpath(urdf), root)
                        controls = logged_commands(mcap_path)
                        start = lambda d: set_start(m, d, system, scenario, summary)  # noqa: E731
                muj.append(mujoco_rate(m, controls, steps, start))
        h, k = statistics.median(harness), statistics.median(muj)
        print(f"{system:<26} {scenario:<22} {steps:>7} {h:>10.0f} {k:>10.0f} {h / k:>6.2f}")
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
