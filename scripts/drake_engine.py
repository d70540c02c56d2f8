"""Drake (MultibodyPlant, discrete) as a third engine for scripts/work_precision.py.

The same URDFs as the harness and MuJoCo, parsed by Drake's own URDF parser, with
what the harness adds around them:

* disk: three prismatic joints (x, y, z) and a yaw joint between the world and the
  yoke (roll and pitch locked: the harness's balance controller), PD-driven yaw and
  wheel joints, the wheel's cylinder on a ground half-space;
* space robot: a floating vehicle, no gravity, no contact (every pair filtered, as
  the harness disables the robot's self-contacts), PD-driven joint1 and joint2;
* rover: a floating chassis, PD-driven steering and front wheel joints (the steering
  joint's URDF limits), passive rear wheels, five sphere wheels on a ground half-space;
* sphere: a floating ball on a ground half-space, driven by a world-frame torque
  servo on its angular velocity (the harness's drive acts about world axes).

The joint drives are Drake's implicit PD controllers on joint actuators
(`JointActuator.set_controller_gains`, solved inside the SAP contact problem, with
the actuator's effort limit): the harness's servo drive (Rapier motor with a target
velocity and a target angle, damping 1e6, stiffness 1e9, torque limit 50 N m unless
the URDF says otherwise) as Drake models one (damping 1e4, stiffness 1e6: SAP does
not converge at the harness's 1e6 and 1e9). Desired angle: the commanded angle at
the end of the step (Drake's PD acts on the next step's angle); desired rate: the
step's mean rate.

Drake has no world-frame angular-velocity actuator (actuators act on one-dof joints),
so the sphere's servo is explicit: tau = K (w_d - w), saturated at the scenario's
motor_max_torque, built from Drake's own systems (MatrixGain, Adder, Saturation on
the plant's applied generalized force input: a quaternion floating joint's first
three generalized velocities are the world-frame angular velocity). K = c I_eff / dt
(I_eff: the rolling ball's inertia about the contact point, the spin axis' own);
`sphere_gain` is c.

Everything is a C++ system (trajectory sources for the commands, a vector log sink
for the states), so `Simulator.AdvanceTo` runs without Python callbacks; its CPU time
is the calling thread's (`time.thread_time`), as for MuJoCo's rollout.
"""

import math
import time
import xml.etree.ElementTree as ET

import numpy as np

from pydrake.all import (
    AddMultibodyPlant,
    Adder,
    CollisionFilterDeclaration,
    CoulombFriction,
    DiagramBuilder,
    GeometrySet,
    HalfSpace,
    LogVectorOutput,
    MatrixGain,
    MultibodyPlantConfig,
    Parser,
    PdControllerGains,
    PiecewisePolynomial,
    PrismaticJoint,
    ProximityProperties,
    RevoluteJoint,
    RigidTransform,
    RotationMatrix,
    Role,
    RoleAssign,
    Saturation,
    Simulator,
    SpatialInertia,
    TrajectorySource,
    AddContactMaterial,
    AddCompliantHydroelasticProperties,
    AddRigidHydroelasticProperties,
)

try:
    from importlib.metadata import version as _version

    VERSION = _version("drake")
except Exception:  # noqa: BLE001 (a source build has no distribution metadata)
    VERSION = "?"

# The harness's drive (src/physics/settings.rs): Rapier motor damping 1e6, stiffness
# motor_angle_gain (1000 /s) times it.
DEFAULT = {
    "contact": "point",  # or "hydroelastic"
    "approximation": "sap",  # discrete_contact_approximation
    # Damping 1e4 (N m s/rad): SAP fails to converge on the space robot at 1e5 and 1e6; the
    # angle errors of the disk and the space robot are the same at 1e3 and 1e4.
    "kd": 1.0e4,
    # Stiffness 100 x the damping: at 1000 x (the harness's motor_angle_gain) SAP does not
    # converge on the space robot at 62.5 us; at 1 ms both give the same errors.
    "kp_per_kd": 100.0,
    "sphere_gain": 1.0,
    "target": "end",  # desired angle at the step's end ("start": at its start)
    # Point contact: Drake's default stiffness comes from the penetration allowance
    # (1 mm); None keeps it. Hydroelastic modulus, Pa, of the compliant geometry (1 GPa, a
    # hard plastic: at 0.1 GPa the ball rolling at 0.5 rad/s misses r w by 1.1e-3).
    "point_stiffness": None,
    "hydro_modulus": 1.0e9,
    # Mesh resolution hint of compliant geometry, a fraction of its radius.
    "hydro_resolution": 0.1,
    "hunt_crossley": 0.0,
}


def _quat_z(a):
    return RotationMatrix.MakeZRotation(a)


def _zyz(alpha, theta, phi):
    return RotationMatrix.MakeZRotation(alpha) @ RotationMatrix.MakeYRotation(theta) @ RotationMatrix.MakeZRotation(phi)


class DrakeRun:
    """One system's diagram at one dt; `run(ctrl)` simulates and returns model states."""

    def __init__(self, system, urdf, summary, start, dt, steps, settings=None):
        self.system, self.dt, self.steps = system, dt, steps
        s = dict(DEFAULT)
        s.update(settings or {})
        self.s = s
        sim = summary["sim_settings"]
        self.mu = sim["friction"]
        model = summary["model"]
        cfg = MultibodyPlantConfig(
            time_step=dt,
            contact_model="hydroelastic_with_fallback" if s["contact"] == "hydroelastic" else "point",
            discrete_contact_approximation=s["approximation"],
        )
        builder = DiagramBuilder()
        plant, sg = AddMultibodyPlant(cfg, builder)
        self.plant = plant
        text = open(urdf).read()
        (mi,) = Parser(plant).AddModelsFromString(text, "urdf")
        self.mi = mi
        plant.mutable_gravity_field().set_gravity_vector(np.array(sim["gravity"], dtype=float))
        if system != "space":
            props = ProximityProperties()
            AddContactMaterial(dissipation=s["hunt_crossley"], point_stiffness=s["point_stiffness"],
                               friction=CoulombFriction(self.mu, self.mu), properties=props)
            if s["contact"] == "hydroelastic":
                AddRigidHydroelasticProperties(0.1, props)
            plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(), HalfSpace(), "ground", props)
        self.effort = sim.get("motor_max_torque", 50.0)
        if system == "disk":
            # world -> x -> y -> z -> yaw -> yoke (massless intermediate frames).
            yoke = plant.GetBodyByName("yoke", mi)
            parent = plant.world_body()
            self.slides = []
            for i, axis in enumerate(np.eye(3)):
                b = plant.AddRigidBody(f"slide_body{i}", mi, SpatialInertia.Zero())
                j = plant.AddJoint(PrismaticJoint(f"slide{i}", parent.body_frame(), b.body_frame(), axis))
                self.slides.append(j)
                parent = b
            self.yaw = plant.AddJoint(RevoluteJoint("yaw", parent.body_frame(), yoke.body_frame(), [0, 0, 1]))
            self.driven = [plant.GetJointByName("wheel_joint", mi), self.yaw]
        elif system == "space":
            self.driven = [plant.GetJointByName("joint1", mi), plant.GetJointByName("joint2", mi)]
        elif system == "rover":
            self.driven = [plant.GetJointByName("front_wheel_joint", mi), plant.GetJointByName("steer_joint", mi)]
        else:
            self.driven = []
        self.root = plant.GetBodyByName({"disk": "yoke", "space": "vehicle", "rover": "chassis",
                                         "sphere": "ball"}[system], mi)
        for j in self.driven:
            lim = self._effort_of(urdf, j.name()) or self.effort
            a = plant.AddJointActuator(f"{j.name()}_drive", j, lim)
            a.set_controller_gains(PdControllerGains(p=s["kd"] * s["kp_per_kd"], d=s["kd"]))
        # Friction on the robot's collision geometry (the URDF has none).
        inspector = sg.model_inspector()
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            if inspector.GetFrameId(gid) == inspector.world_frame_id():
                continue
            props = ProximityProperties(inspector.GetProximityProperties(gid))
            if props.HasProperty("material", "coulomb_friction"):
                props.UpdateProperty("material", "coulomb_friction", CoulombFriction(self.mu, self.mu))
            else:
                AddContactMaterial(dissipation=s["hunt_crossley"], point_stiffness=s["point_stiffness"],
                                   friction=CoulombFriction(self.mu, self.mu), properties=props)
            if s["contact"] == "hydroelastic":
                size = (model.get("radius") or model.get("geometry", {}).get("wheel_radius", 0.1))
                AddCompliantHydroelasticProperties(size * s["hydro_resolution"], s["hydro_modulus"], props)
            sg.AssignRole(plant.get_source_id(), gid, props, RoleAssign.kReplace)
        plant.Finalize()
        if system == "space":
            ids = GeometrySet(list(inspector.GetAllGeometryIds(Role.kProximity)))
            sg.collision_filter_manager().Apply(CollisionFilterDeclaration().ExcludeWithin(ids))
        self.nq, self.nv = plant.num_positions(), plant.num_velocities()
        self.builder, self.sg = builder, sg
        self.start = start
        self.model = model
        self.summary = summary
        self.logger = LogVectorOutput(plant.get_state_output_port(), builder)
        self._built = False

    @staticmethod
    def _effort_of(urdf, name):
        for j in ET.parse(urdf).getroot().iter("joint"):
            if j.get("name") == name:
                lim = j.find("limit")
                if lim is not None and lim.get("effort") is not None:
                    return float(lim.get("effort"))
        return None

    def _connect(self, desired):
        """Command sources: `desired` rows per step (PD: [q_d..., v_d...]; sphere: K w_d)."""
        b, plant, dt = self.builder, self.plant, self.dt
        n = desired.shape[0]
        # Zero-order hold whose breaks sit half a step before each step's time, so that
        # the value at t = k dt is row k whatever the round-off of the simulator's time.
        times = (np.arange(n + 1) - 0.5) * dt
        vals = np.concatenate([desired, desired[-1:]], axis=0).T
        traj = PiecewisePolynomial.ZeroOrderHold(times, vals)
        src = b.AddSystem(TrajectorySource(traj))
        if self.system == "sphere":
            # tau = K w_d - K w, saturated; the floating joint's v = [w_WB (world), v_WB].
            K = self._sphere_K()
            sel = np.zeros((3, self.nq + self.nv))
            w0 = self.nq + self.root.floating_velocities_start_in_v()
            sel[:, w0 : w0 + 3] = -K
            fb = b.AddSystem(MatrixGain(sel))
            add = b.AddSystem(Adder(2, 3))
            lim = self.summary["sim_settings"].get("motor_max_torque", 50.0)
            sat = b.AddSystem(Saturation(-lim * np.ones(3), lim * np.ones(3)))
            b.Connect(plant.get_state_output_port(), fb.get_input_port())
            b.Connect(fb.get_output_port(), add.get_input_port(0))
            b.Connect(src.get_output_port(), add.get_input_port(1))
            b.Connect(add.get_output_port(), sat.get_input_port())
            # Generalized force on the ball: the floating joint's 6 velocities.
            expand = np.zeros((self.nv, 3))
            expand[self.root.floating_velocities_start_in_v() : self.root.floating_velocities_start_in_v() + 3] = np.eye(3)
            ex = b.AddSystem(MatrixGain(expand))
            b.Connect(sat.get_output_port(), ex.get_input_port())
            b.Connect(ex.get_output_port(), plant.get_applied_generalized_force_input_port())
        else:
            b.Connect(src.get_output_port(), plant.get_desired_state_input_port(self.mi))
            zero = b.AddSystem(TrajectorySource(PiecewisePolynomial(np.zeros((len(self.driven), 1)))))
            b.Connect(zero.get_output_port(), plant.get_actuation_input_port(self.mi))

    def _sphere_K(self):
        """Gains c I_eff / dt: about the horizontal axes the inertia of rolling without slip
        (I + m a^2, about the contact point), about the vertical one the ball's own; c = 1 is a
        deadbeat servo of the rolling ball."""
        inertia = self.root.default_rotational_inertia().get_moments()
        m, a = self.root.default_mass(), self.model["radius"]
        eff = np.array([inertia[0] + m * a * a, inertia[1] + m * a * a, inertia[2]])
        return self.s["sphere_gain"] * np.diag(eff) / self.dt

    def _set_start(self, context):
        plant, st, model = self.plant, self.start, self.model
        pc = plant.GetMyMutableContextFromRoot(context)
        rad = [math.radians(v) for v in st]
        if self.system == "disk":
            for j, v in zip(self.slides, [st[0], st[1], model["radius"]]):
                j.set_translation(pc, v)
            self.yaw.set_angle(pc, math.pi / 2 - rad[3])
        elif self.system == "space":
            plant.SetFreeBodyPose(pc, self.root, RigidTransform(_quat_z(rad[0]), [0, 0, 0]))
            self.driven[0].set_angle(pc, rad[1])
            self.driven[1].set_angle(pc, rad[2])
        elif self.system == "rover":
            rho = model["geometry"]["wheel_radius"]
            plant.SetFreeBodyPose(pc, self.root, RigidTransform(_quat_z(rad[2]), [st[0], st[1], rho]))
            self.driven[1].set_angle(pc, rad[3])
        else:
            plant.SetFreeBodyPose(pc, self.root, RigidTransform(_zyz(rad[2], rad[3], rad[4]),
                                                                [st[0], st[1], model["radius"]]))

    def build(self, desired):
        self._connect(desired)
        self.diagram = self.builder.Build()
        self._built = True

    def run(self, repeats=1):
        """Simulate `steps` steps `repeats` times: (states [steps + 1, nq + nv], CPU s of each, finite)."""
        cpu = []
        for _ in range(repeats):
            sim = Simulator(self.diagram)
            ctx = sim.get_mutable_context()
            self._set_start(ctx)
            sim.Initialize()
            c0 = time.thread_time()
            try:
                sim.AdvanceTo(self.steps * self.dt)
            except RuntimeError as e:
                # SAP reports a solve that does not converge: a diverged run.
                self.error = str(e).splitlines()[0]
                return None, [time.thread_time() - c0], False
            cpu.append(time.thread_time() - c0)
            log = self.logger.FindLog(ctx)
            data = log.data().T.copy()
            t = log.sample_times().copy()
        # The sink logs at initialisation and after every step (sampled ports): keep one
        # row per step time, the last written.
        keep = np.concatenate([t[1:] > t[:-1] + 0.5 * self.dt, [True]])
        data, t = data[keep], t[keep]
        ok = bool(np.all(np.isfinite(data)) and len(t) == self.steps + 1)
        return data, cpu, ok

    def model_states(self, x, start_state):
        """Drake states (one row per sample) as the harness's model coordinates."""
        def qi(joint):
            return joint.position_start()

        if self.system == "disk":
            return np.stack([x[:, qi(self.slides[0])], x[:, qi(self.slides[1])],
                             start_state[2] + x[:, qi(self.driven[0])],
                             math.pi / 2 - np.unwrap(x[:, qi(self.yaw)])], axis=1)
        f = self.root.floating_positions_start()
        w, qx, qy, qz = (x[:, f + i] for i in range(4))
        if self.system == "sphere":
            q = np.stack([w, qx, qy, qz], axis=1)
            # Continuous sign, as the harness's read-back.
            flips = np.concatenate([[1.0], np.sign(np.sum(q[1:] * q[:-1], axis=1))])
            q = q * np.cumprod(np.where(flips == 0, 1.0, flips))[:, None]
            q = q / np.linalg.norm(q, axis=1, keepdims=True)
            return np.stack([x[:, f + 4], x[:, f + 5], *q.T], axis=1)
        yaw = np.unwrap(np.arctan2(2 * (w * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)))
        if self.system == "space":
            return np.stack([yaw, x[:, qi(self.driven[0])], x[:, qi(self.driven[1])]], axis=1)
        return np.stack([x[:, f + 4], x[:, f + 5], yaw, x[:, qi(self.driven[1])]], axis=1)

