//! The engine side of the physics: Rapier worlds built from URDFs (frames
//! lumped, meshes loaded), batched worlds, settings and perturbations, and
//! the replay loop. Nothing here knows a particular robot.

pub mod angles;
pub mod batch;
pub mod lump;
pub mod mesh;
pub mod mesh_limits;
pub mod obstacles;
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
