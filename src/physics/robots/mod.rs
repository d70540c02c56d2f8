//! The robots: each kinematic model's rigid-body counterpart, built on the
//! engine ([`super::engine`]) from its URDF.

pub mod beam;
pub mod car;
pub mod declared;
pub mod diff_drive;
pub mod disk;
pub mod mobile_manipulator;
pub mod rover;
pub mod space_robot;
pub mod sphere;
pub mod wheeled;
