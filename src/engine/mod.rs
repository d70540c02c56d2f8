//! The physics engine: Rapier worlds (double precision: `rapier3d-f64`)
//! built from URDFs (frames lumped, meshes loaded), batched worlds,
//! settings and perturbations, and the one replay loop. Nothing here knows
//! a particular robot: each robot's counterpart is `robots::<kind>::physics`.
//!
//! A [`PhysicsSystem`] maps model inputs to joint motors and reads the model
//! coordinates back from the simulated bodies. [`replay()`] drives it with
//! the same controller the ideal run used, evaluated on the simulated state.
//! Settings come in as plain [`PhysicsSettings`]; URDF robots are loaded by
//! [`world`].

pub mod angles;
pub mod batch;
pub mod lump;
pub mod mesh;
pub mod mesh_limits;
pub mod packages;
pub mod perturb;
pub mod reading;
pub mod real;
pub mod replay;
pub mod required;
pub mod settings;
pub mod shared_world;
pub mod urdf;
pub mod urdf_text;
pub mod world;

/// The engine. Physics code names its types through this alias and the
/// `Real`/`Vector`/`Rotation` aliases, so switching this line (and the
/// dependency) to `rapier3d` builds the f32 engine for comparison.
pub use rapier3d_f64 as rapier;
pub use settings::PhysicsSettings;

use crate::model::{Input, State};
use crate::record::Pose;

pub use replay::{replay, Replay, ReplayError, ReplayObserver, ReplayOptions};

/// A command a [`PhysicsSystem`] could not carry out.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    /// What failed, naming the scenario key (`key `model.drive.j` (`v / r`)
    /// gives inf`).
    pub what: String,
    /// The state and input it failed at, as the scenario writes them.
    pub from: String,
}

/// A simulated robot that accepts model inputs and reports model coordinates.
pub trait PhysicsSystem {
    /// Current model coordinates (angles unwrapped continuously).
    fn state(&self) -> State;
    /// Set the actuators for the next step.
    fn apply(&mut self, u: &Input);
    /// A command this system could not carry out (a declared drive
    /// expression that is NaN or infinite), from the last [`apply`] on:
    /// the replay stops there. `None` (the default): every command is
    /// carried out.
    ///
    /// [`apply`]: PhysicsSystem::apply
    fn fault(&self) -> Option<Fault> {
        None
    }
    /// Advance one physics step and update the read-back.
    fn step(&mut self);
    /// World pose of each URDF link, in URDF order.
    fn link_poses(&self) -> Vec<Pose>;
    /// Names of the extra channels ([`PhysicsSystem::channels`]).
    fn channel_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Extra per-step measurements (slip, momentum, ...).
    fn channels(&self) -> Vec<f64> {
        Vec::new()
    }
    /// What a feedback law may measure besides the model coordinates
    /// (handed to [`crate::plan::Controller::command_measured`] at every
    /// policy sample), or `None`.
    fn measurement(&self) -> Option<Vec<f64>> {
        None
    }
    /// The engine world of a system that can share one with other systems
    /// (batched sweeps, [`batch`]): its engine state is one URDF robot in
    /// this [`world::SimWorld`], it steps it with [`world::SimWorld::step`]
    /// and reads only its own bodies. `None` (the default): always stepped
    /// alone.
    fn sim_world(&mut self) -> Option<&mut world::SimWorld> {
        None
    }
    /// What this counterpart read from its URDF beyond the bodies (wheels,
    /// drives, derived geometry, defaults it filled in): shown to the user.
    fn reading(&self) -> reading::UrdfReading {
        reading::UrdfReading::default()
    }
}
