#!/usr/bin/env python3
"""Record the shipped differential drive (models/diff_drive.urdf) in MuJoCo
and write the run as a ROS 2 bag: /cmd_vel (geometry_msgs/msg/Twist, 20 Hz)
and /odom (nav_msgs/msg/Odometry, 20 Hz, the base's pose as MuJoCo has it).

MuJoCo stands in for the real robot: another engine, with its own contact
model, and a robot that differs from its URDF the way real ones do. Its
wheels are 4 % larger than the URDF says (tyres of 52 mm, not 50 mm)
and the floor grips with friction 0.6 where the scenario assumes 0.8. The commands drive it hard on purpose (speed steps of 0.6 m/s, held
by a zero-order hold), so that the wheels slip while they accelerate and
friction shows in the path. The controller turns each Twist into wheel
rates with the URDF's numbers (radius 0.05 m, track 0.26 m), as a robot's
base controller would.

    pip install mujoco rosbags numpy
    python3 examples/fit_mujoco/make_recording.py      # writes mujoco_lap/

The bag is written by rosbags (rosbag2, MCAP storage), like
examples/ros_bags/make_bags.py's; nothing writes CDR or MCAP bytes by hand.
"""

import math
import shutil
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

HERE = Path(__file__).resolve().parent
URDF = HERE.parent.parent / "models" / "diff_drive.urdf"
OUT = HERE / "mujoco_lap"

# The real robot: what its URDF does not say.
WHEEL_RADIUS = 0.052  # m (URDF: 0.05)
FRICTION = 0.6  # floor (scenario: 0.8)
# What its base controller assumes (the URDF's numbers).
NOMINAL_RADIUS = 0.05
HALF_TRACK = 0.13
DT = 0.001  # s, MuJoCo's step
CMD_RATE = 20  # Hz
ODOM_RATE = 20  # Hz
T0 = 1_700_000_000 * 10**9  # recording start, ns since the epoch

STORE = get_typestore(Stores.ROS2_JAZZY)
T = STORE.types


def commands():
    """(t, v, omega) at 20 Hz: hard starts and stops, two bends, 13 s."""
    out = []
    for k in range(13 * CMD_RATE):
        t = k / CMD_RATE
        if t < 0.5:
            v, w = 0.0, 0.0
        elif t < 3.0:
            v, w = 0.6, 0.0
        elif t < 5.5:
            v, w = 0.4, 0.8
        elif t < 6.5:
            v, w = 0.6, 0.0
        elif t < 9.0:
            v, w = 0.4, -0.9
        elif t < 11.0:
            v, w = 0.6, 0.0
        else:
            v, w = 0.0, 0.0
        out.append((t, v, w))
    return out


def model():
    """MuJoCo's import of the URDF, on a floating base, on a floor."""
    tree = ET.parse(URDF)
    robot = tree.getroot()
    robot.insert(0, ET.Element("link", name="world"))
    j = ET.SubElement(robot, "joint", name="float", type="floating")
    ET.SubElement(j, "parent", link="world")
    ET.SubElement(j, "child", link="base_link")
    # The real tyres.
    for link in robot.iter("link"):
        if link.get("name") in ("left_wheel", "right_wheel"):
            for s in link.iter("sphere"):
                s.set("radius", repr(WHEEL_RADIUS))
    m = mujoco.MjModel.from_xml_string(ET.tostring(robot, encoding="unicode"))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "m.xml"
        mujoco.mj_saveLastXML(str(path), m)
        mjcf = ET.parse(path).getroot()
    # Elliptic friction cones: MuJoCo's choice for rolling contacts.
    opt = ET.SubElement(
        mjcf, "option", timestep=repr(DT), integrator="implicitfast", cone="elliptic"
    )
    opt.set("gravity", "0 0 -9.81")
    world = mjcf.find("worldbody")
    ET.SubElement(
        world, "geom", type="plane", size="0 0 1", friction=f"{FRICTION} 0.005 0.0001"
    )
    base = world.find(".//body[@name='base_link']")
    base.set("pos", f"0 0 {WHEEL_RADIUS}")
    for g in mjcf.iter("geom"):
        g.set("friction", f"{FRICTION} 0.005 0.0001")
        if g.get("type", "sphere") == "sphere" and abs(float(g.get("size", "0").split()[0]) - 0.025) < 1e-9:
            # The ball caster: frictionless, as the harness makes it.
            g.set("condim", "1")
            g.set("priority", "1")
    act = ET.SubElement(mjcf, "actuator")
    for joint in ("left_wheel_joint", "right_wheel_joint"):
        # A velocity servo within the URDF's 1 N m effort.
        ET.SubElement(
            act, "velocity", joint=joint, kv="20", forcelimited="true", forcerange="-1 1"
        )
    return mujoco.MjModel.from_xml_string(ET.tostring(mjcf, encoding="unicode"))


def run():
    m = model()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    cmds = commands()
    end = cmds[-1][0] + 1.0 / CMD_RATE + 1.0  # a second to stop
    steps = int(round(end / DT))
    odom = []
    per_odom = int(round(1.0 / (ODOM_RATE * DT)))
    base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "base_link")
    for k in range(steps + 1):
        t = k * DT
        i = min(int(t * CMD_RATE + 1e-9), len(cmds) - 1)
        _, v, w = cmds[i] if t < len(cmds) / CMD_RATE else (0.0, 0.0, 0.0)
        d.ctrl[0] = (v - w * HALF_TRACK) / NOMINAL_RADIUS
        d.ctrl[1] = (v + w * HALF_TRACK) / NOMINAL_RADIUS
        if k % per_odom == 0:
            p = d.xpos[base].copy()
            q = d.xquat[base].copy()  # w x y z
            odom.append((t, p, q))
        mujoco.mj_step(m, d)
    return cmds, odom


def vec3(x=0.0, y=0.0, z=0.0):
    return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def write(cmds, odom):
    if OUT.exists():
        shutil.rmtree(OUT)
    twist_t = "geometry_msgs/msg/Twist"
    odom_t = "nav_msgs/msg/Odometry"
    # The recorder starts a little before the first command.
    lead = 200_000_000
    with Writer(OUT, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        c_cmd = w.add_connection("/cmd_vel", twist_t, typestore=STORE)
        c_odom = w.add_connection("/odom", odom_t, typestore=STORE)
        msgs = []
        for t, v, om in cmds:
            msg = T[twist_t](linear=vec3(x=v), angular=vec3(z=om))
            msgs.append((T0 + lead + int(round(t * 1e9)), c_cmd, STORE.serialize_cdr(msg, twist_t)))
        for t, p, q in odom:
            ns = T0 + lead + int(round(t * 1e9))
            stamp = T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            pose = T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
                orientation=T["geometry_msgs/msg/Quaternion"](x=q[1], y=q[2], z=q[3], w=q[0]),
            )
            zero = np.zeros(36, dtype=np.float64)
            msg = T[odom_t](
                header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="odom"),
                child_frame_id="base_link",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=zero),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](
                    twist=T["geometry_msgs/msg/Twist"](linear=vec3(), angular=vec3()),
                    covariance=zero,
                ),
            )
            msgs.append((ns, c_odom, STORE.serialize_cdr(msg, odom_t)))
        for ns, conn, data in sorted(msgs, key=lambda x: x[0]):
            w.write(conn, ns, bytes(data))


def main():
    cmds, odom = run()
    write(cmds, odom)
    t, p, q = odom[-1]
    yaw = math.atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2))
    size = sum(f.stat().st_size for f in OUT.iterdir())
    print(f"wrote {OUT} ({size} bytes): end x {p[0]:.4f} y {p[1]:.4f} yaw {math.degrees(yaw):.2f} deg")


if __name__ == "__main__":
    main()
