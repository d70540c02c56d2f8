"""Write the example robot's meshes (STL, metres) with trimesh.

Run from anywhere: `python3 examples/ros_robot/make_meshes.py` (needs
`pip install trimesh numpy`). The files are committed; this script is how
they were made, so they can be made again or changed.
"""

from pathlib import Path

import numpy as np
import trimesh

OUT = Path(__file__).resolve().parent / "pocket_bot_description" / "meshes"


def base():
    # A rounded-looking body: a box with a chamfered top plate.
    body = trimesh.creation.box(extents=(0.24, 0.18, 0.07))
    body.apply_translation((0.0, 0.0, 0.035))
    plate = trimesh.creation.cylinder(radius=0.09, height=0.01, sections=48)
    plate.apply_translation((0.02, 0.0, 0.075))
    return trimesh.util.concatenate([body, plate])


def wheel():
    # Tyre along its axis z (the URDF turns the wheel frame), with a hub.
    tyre = trimesh.creation.cylinder(radius=0.04, height=0.02, sections=48)
    hub = trimesh.creation.cylinder(radius=0.015, height=0.026, sections=24)
    return trimesh.util.concatenate([tyre, hub])


def lidar():
    housing = trimesh.creation.cylinder(radius=0.035, height=0.03, sections=40)
    head = trimesh.creation.cylinder(radius=0.025, height=0.015, sections=40)
    head.apply_translation((0.0, 0.0, 0.022))
    return trimesh.util.concatenate([housing, head])


def camera():
    return trimesh.creation.box(extents=(0.02, 0.07, 0.025))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    for name, mesh in [("base", base()), ("wheel", wheel()), ("lidar", lidar()), ("camera", camera())]:
        mesh.vertices = np.round(mesh.vertices, 6)
        mesh.export(OUT / f"{name}.stl")
        print(f"{OUT / (name + '.stl')}: {len(mesh.faces)} triangles")


if __name__ == "__main__":
    main()
