#!/usr/bin/env python3
"""Write the ROS 2 bags of examples/ros_bags/ and tests/data/ros_bags/.

Every bag is written by rosbags (pip install rosbags), a standard rosbag2
library, in rosbag2's MCAP storage: a directory holding metadata.yaml and
one .mcap file, as `ros2 bag record` leaves it. Messages are serialized by
rosbags from their definitions (ackermann_msgs and the test's own types are
registered from their .msg text); nothing here writes CDR or MCAP bytes by
hand. The bad bags of tests/data/ros_bags/ are valid bags whose contents
are wrong in one way each (a message cut short after serialization, a
topic recorded without its definition, time going backwards, a topic with
no message); tests/data/ros_bags/sqlite3 holds twist_steps' commands in
sqlite3 storage.

    python3 examples/ros_bags/make_bags.py          # rewrite them all
    python3 examples/ros_bags/make_bags.py --goals  # print the examples' goals

The examples' goals (where the ideal model ends under the held commands)
are printed with --goals; the scenarios carry them.
"""

import math
import shutil
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
TESTS = ROOT / "tests" / "data" / "ros_bags"

ACKERMANN_DRIVE = """\
float32 steering_angle
float32 steering_angle_velocity
float32 speed
float32 acceleration
float32 jerk
"""
ACKERMANN_DRIVE_STAMPED = """\
std_msgs/Header header
AckermannDrive  drive
"""
# A made-up command type: a header, a nested message of this package (a
# relative type name), a fixed array, a string and a sequence.
MOTION = """\
float64 forward
float32 turn
"""
BASE_COMMAND = """\
std_msgs/Header header
string mode
float64[3] gains
Motion motion
int32[] flags
"""

STORE = get_typestore(Stores.ROS2_JAZZY)
STORE.register(get_types_from_msg(ACKERMANN_DRIVE, "ackermann_msgs/msg/AckermannDrive"))
STORE.register(
    get_types_from_msg(ACKERMANN_DRIVE_STAMPED, "ackermann_msgs/msg/AckermannDriveStamped")
)
STORE.register(get_types_from_msg(MOTION, "anholonomy_test_msgs/msg/Motion"))
STORE.register(get_types_from_msg(BASE_COMMAND, "anholonomy_test_msgs/msg/BaseCommand"))
T = STORE.types

TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
ACKERMANN = "ackermann_msgs/msg/AckermannDriveStamped"
CUSTOM = "anholonomy_test_msgs/msg/BaseCommand"

# Recording start, ns since the epoch (any instant: t starts at the first message).
T0 = 1_700_000_000 * 10**9


def stamp(ns):
    return T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)


def header(ns):
    return T["std_msgs/msg/Header"](stamp=stamp(ns), frame_id="base_link")


def vec3(x=0.0, y=0.0, z=0.0):
    return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def twist(v, w):
    return T[TWIST](linear=vec3(x=v), angular=vec3(z=w))


def twist_stamped(ns, v, w):
    return T[TWIST_STAMPED](header=header(ns), twist=twist(v, w))


def ackermann(ns, v, steer):
    drive = T["ackermann_msgs/msg/AckermannDrive"](
        steering_angle=steer, steering_angle_velocity=0.0, speed=v, acceleration=0.0, jerk=0.0
    )
    return T[ACKERMANN](header=header(ns), drive=drive)


def custom(ns, v, w):
    return T[CUSTOM](
        header=header(ns),
        mode="auto",
        gains=np.array([1.0, 0.5, 0.25], dtype=np.float64),
        motion=T["anholonomy_test_msgs/msg/Motion"](forward=v, turn=w),
        flags=np.array([1, 2], dtype=np.int32),
    )


def cdr(msg, msgtype):
    return bytes(STORE.serialize_cdr(msg, msgtype))


def write(path, topics, sqlite=False):
    """Write bag `path`: topics = [(topic, msgtype, [(log_ns, bytes), ...], msgdef or None)]."""
    if path.exists():
        shutil.rmtree(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    plugin = StoragePlugin.SQLITE3 if sqlite else StoragePlugin.MCAP
    with Writer(path, version=9, storage_plugin=plugin) as w:
        for topic, msgtype, messages, msgdef in topics:
            if msgdef is None:
                conn = w.add_connection(topic, msgtype, typestore=STORE)
            else:
                # A definition of our own choosing (the empty one of a
                # recorder that lacked the package).
                conn = w.add_connection(
                    topic, msgtype, msgdef=msgdef, rihs01="RIHS01_" + "0" * 64
                )
            for ns, data in messages:
                w.write(conn, ns, data)


# ---- the examples -------------------------------------------------------

RATE = 20  # Hz, a typical cmd_vel rate
PERIOD = 10**9 // RATE


def jitter(k):
    """A recorder's receive-time jitter, ns (deterministic, within +-3 ms)."""
    return int(3e6 * math.sin(12.9898 * k + 78.233 * math.sin(k)))


def smooth(t, t0, t1):
    """0 before t0, 1 after t1, a smooth step between."""
    if t <= t0:
        return 0.0
    if t >= t1:
        return 1.0
    s = (t - t0) / (t1 - t0)
    return s * s * (3 - 2 * s)


def diff_drive_commands():
    """A lap a teleoperator or a navigation stack might drive: speed up,
    a left bend, straight, a right bend, slow down; 20 Hz for 14 s."""
    out = []
    for k in range(14 * RATE):
        t = k / RATE
        v = 0.3 * smooth(t, 0.0, 1.5) * (1.0 - smooth(t, 12.0, 13.5))
        w = 0.5 * (smooth(t, 2.5, 3.5) - smooth(t, 5.5, 6.5)) - 0.4 * (
            smooth(t, 8.0, 9.0) - smooth(t, 10.5, 11.5)
        )
        out.append((k, round(v, 6), round(w, 6)))
    return out


def car_commands():
    """A lane change and back at up to 0.5 m/s: the steering angle a
    pure-pursuit controller might send, 20 Hz for 12 s."""
    out = []
    for k in range(12 * RATE):
        t = k / RATE
        v = 0.5 * smooth(t, 0.0, 2.0) * (1.0 - smooth(t, 10.0, 11.8))
        steer = 0.25 * math.sin(2 * math.pi * (t - 2.5) / 3.0) if 2.5 <= t < 8.5 else 0.0
        out.append((k, round(v, 4), round(steer, 4)))
    return out


def unicycle_end(samples, q=(0.0, 0.0, 0.0)):
    """Closed-form end pose under zero-order hold: samples [(t, v, w)], the
    last one's t the end."""
    x, y, th = q
    for (t, v, w), (t1, _, _) in zip(samples, samples[1:]):
        tau = t1 - t
        if abs(w) > 1e-12:
            x += v / w * (math.sin(th + w * tau) - math.sin(th))
            y -= v / w * (math.cos(th + w * tau) - math.cos(th))
        else:
            x += v * tau * math.cos(th)
            y += v * tau * math.sin(th)
        th += w * tau
    return x, y, th


def f32(x):
    import struct

    return struct.unpack("<f", struct.pack("<f", x))[0]


def median_end(times):
    gaps = sorted(b - a for a, b in zip(times, times[1:]))
    n = len(gaps)
    med = gaps[n // 2] if n % 2 else gaps[n // 2 - 1] + (gaps[n // 2] - gaps[n // 2 - 1]) // 2
    return times[-1] + med


def examples(goals=False):
    dd = diff_drive_commands()
    log = [T0 + k * PERIOD + jitter(k) for k, _, _ in dd]
    write(
        HERE / "cmd_vel_lap",
        [("/cmd_vel", TWIST, [(ns, cdr(twist(v, w), TWIST)) for ns, (_, v, w) in zip(log, dd)], None)],
    )
    car = car_commands()
    stamps = [T0 + k * PERIOD for k, _, _ in car]
    # Received 2 to 8 ms after the stamp.
    logs = [ns + 5_000_000 + jitter(k) for ns, (k, _, _) in zip(stamps, car)]
    write(
        HERE / "ackermann_lane_change",
        [
            (
                "/ackermann_cmd",
                ACKERMANN,
                [
                    (lg, cdr(ackermann(st, v, s), ACKERMANN))
                    for lg, st, (_, v, s) in zip(logs, stamps, car)
                ],
                None,
            )
        ],
    )
    if goals:
        ts = [(ns - log[0]) / 1e9 for ns in log] + [(median_end(log) - log[0]) / 1e9]
        end = unicycle_end([(t, v, w) for t, (_, v, w) in zip(ts, dd)] + [(ts[-1], 0, 0)])
        print("cmd_vel_lap goal: [%r, %r, %r]" % (end[0], end[1], math.degrees(end[2])))
        ts = [(ns - stamps[0]) / 1e9 for ns in stamps] + [(median_end(stamps) - stamps[0]) / 1e9]
        L = 0.32
        samples = [(t, f32(v), f32(v) * math.tan(f32(s)) / L) for t, (_, v, s) in zip(ts, car)]
        end = unicycle_end(samples + [(ts[-1], 0, 0)])
        print(
            "ackermann_lane_change goal (header time): [%r, %r, %r]"
            % (end[0], end[1], math.degrees(end[2]))
        )


# ---- the test bags ------------------------------------------------------

# Piecewise-constant commands (v m/s, omega rad/s), each held 0.25 s; the
# speeds and rates are exact in float32 too (the Ackermann fields are).
STEPS = [(0.5, 0.0), (0.5, 1.0), (0.25, -0.5), (0.0, 0.75), (-0.375, 0.0), (0.5, -1.25)]
STEERS = [(0.5, 0.0), (0.5, 0.25), (0.25, -0.375), (0.0, 0.125), (-0.375, 0.3125), (0.5, 0.0)]
HOLD = 250_000_000  # ns


def test_bags():
    # A Twist bag: log times on a 0.25 s grid.
    write(
        TESTS / "twist_steps",
        [
            (
                "/cmd_vel",
                TWIST,
                [(T0 + k * HOLD, cdr(twist(v, w), TWIST)) for k, (v, w) in enumerate(STEPS)],
                None,
            ),
            # Another topic, of another type, that is not the commands.
            (
                "/battery_voltage",
                "std_msgs/msg/Float64",
                [(T0 + k * 10**9, cdr(T["std_msgs/msg/Float64"](data=12.0), "std_msgs/msg/Float64")) for k in range(2)],
                None,
            ),
        ],
    )
    # TwistStamped: header stamps on the grid, log times late by 1 to 7 ms.
    write(
        TESTS / "twist_stamped_steps",
        [
            (
                "/cmd_vel",
                TWIST_STAMPED,
                [
                    (T0 + k * HOLD + 4_000_000 + jitter(k), cdr(twist_stamped(T0 + k * HOLD, v, w), TWIST_STAMPED))
                    for k, (v, w) in enumerate(STEPS)
                ],
                None,
            )
        ],
    )
    # AckermannDriveStamped: speed and steering angle held 0.25 s each.
    write(
        TESTS / "ackermann_steps",
        [
            (
                "/ackermann_cmd",
                ACKERMANN,
                [(T0 + k * HOLD, cdr(ackermann(T0 + k * HOLD, v, s), ACKERMANN)) for k, (v, s) in enumerate(STEERS)],
                None,
            )
        ],
    )
    # The made-up type, its speed and turn rate in a nested message.
    write(
        TESTS / "custom_steps",
        [
            (
                "/base/command",
                CUSTOM,
                [(T0 + k * HOLD, cdr(custom(T0 + k * HOLD, v, w), CUSTOM)) for k, (v, w) in enumerate(STEPS)],
                None,
            )
        ],
    )
    # Bad bags.
    good = [cdr(twist(v, w), TWIST) for v, w in STEPS]
    cut = list(good)
    cut[3] = cut[3][:-13]
    write(TESTS / "truncated", [("/cmd_vel", TWIST, [(T0 + k * HOLD, d) for k, d in enumerate(cut)], None)])
    write(
        TESTS / "no_definition",
        [("/cmd_vel", TWIST, [(T0 + k * HOLD, d) for k, d in enumerate(good)], "")],
    )
    back = [T0 + k * HOLD for k in range(len(STEPS))]
    back[4] = back[2] + 1000
    write(
        TESTS / "header_backwards",
        [
            (
                "/cmd_vel",
                TWIST_STAMPED,
                [(T0 + k * HOLD, cdr(twist_stamped(ns, v, w), TWIST_STAMPED)) for k, (ns, (v, w)) in enumerate(zip(back, STEPS))],
                None,
            )
        ],
    )
    write(
        TESTS / "log_backwards",
        [("/cmd_vel", TWIST, [(ns, d) for ns, d in zip(back, good)], None)],
    )
    write(
        TESTS / "empty_topic",
        [
            ("/cmd_vel", TWIST, [], None),
            ("/odom_speed", "std_msgs/msg/Float64", [(T0, cdr(T["std_msgs/msg/Float64"](data=0.0), "std_msgs/msg/Float64"))], None),
        ],
    )
    write(
        TESTS / "sqlite3",
        [("/cmd_vel", TWIST, [(T0 + k * HOLD, d) for k, d in enumerate(good)], None)],
        sqlite=True,
    )


if __name__ == "__main__":
    if "--goals" in sys.argv:
        examples(goals=True)
    else:
        examples()
        test_bags()
