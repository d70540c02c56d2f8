//! Plain physics settings, owned by the physics layer (the scenario's `[sim]`
//! table converts into them; nothing here knows about scenario files).

/// Settings of one simulated world and its actuators.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicsSettings {
    /// Physics step, s.
    pub dt: f64,
    /// Rapier solver iterations per step: substeps, each rebuilding the
    /// constraints from the current poses and integrating positions.
    pub solver_iterations: usize,
    /// Projected Gauss–Seidel sweeps per substep (cheaper than substeps:
    /// the constraints are not rebuilt).
    pub pgs_iterations: usize,
    /// Re-solve velocities without position correction after each substep
    /// (Rapier's stabilization pass); `None`: only in worlds with a ground.
    pub relax_pass: Option<bool>,
    /// Coulomb friction coefficient between robot and ground (both sides set to it).
    pub friction: f64,
    /// Gravity, m/s².
    pub gravity: [f64; 3],
    /// Maximum torque of each joint drive (motor) whose URDF joint gives no
    /// `<limit effort>`, N·m.
    pub motor_max_torque: f64,
    /// Factor on every drive's effective torque limit, whatever its source
    /// (URDF effort, model key or `motor_max_torque`): `[sim.perturb] torque_scale`.
    pub torque_scale: f64,
    /// Velocity motor gain (Rapier's motor damping factor); higher tracks tighter.
    pub motor_gain: f64,
    /// Rate (1/s) at which a joint drive removes the error between the joint
    /// angle and the commanded angle ∫u dt (the integral action of a velocity
    /// servo); 0 gives a pure velocity motor.
    pub motor_angle_gain: f64,
    /// Factor on every URDF link's mass and inertia (`[sim.perturb] mass_scale`;
    /// the model keeps the nominal ones).
    pub mass_scale: f64,
    /// Factor on the simulated wheels' radius (`[sim.perturb] wheel_radius_scale`;
    /// the model and the controller keep the nominal one). Wheeled systems only.
    pub wheel_radius_scale: f64,
}

impl Default for PhysicsSettings {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            solver_iterations: 1,
            pgs_iterations: 4,
            relax_pass: None,
            friction: 1.0,
            gravity: [0.0, 0.0, -9.81],
            motor_max_torque: 50.0,
            torque_scale: 1.0,
            motor_gain: 1.0e6,
            motor_angle_gain: 1000.0,
            mass_scale: 1.0,
            wheel_radius_scale: 1.0,
        }
    }
}
