//! The deformable beam of seed 004 §II and §VI: material, cross-section and
//! a straight rest geometry, shared by the finite-element model (planner
//! side) and the physics beam.
//!
//! Seed 004 models the carried object with "two 3D rectangular beam finite
//! elements ... in which the nodal displacements correspond to three
//! infinitesimal translations and three infinitesimal rotations": three
//! nodes (0: grasp 1, 1: middle, 2: grasp 2), 18 nodal coordinates, the
//! floating frame of reference at grasp 1.
//!
//! Frames: the beam's rest axis is the x axis of its end-0 frame; at rest the
//! end-2 frame is the end-0 frame translated by `length` along x (same
//! orientation). Each end frame is fixed to a robot's grasp frame by a
//! constant offset (see the cooperative system).
//!
//! [`fe`] (finite elements, with exponential coordinates from [`se3`]) and
//! the physics beam build on these types.

pub mod physics;

pub mod fe;
#[cfg(test)]
mod fe_tests;
pub mod se3;
pub mod statics;

pub use fe::FeBeam;
pub use se3::{se3_exp, se3_log};
pub use statics::{GraspStatics, WristStiffness};

use serde::{Deserialize, Serialize};

/// An isotropic linear-elastic material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus E, Pa.
    pub youngs_modulus: f64,
    /// Shear modulus G, Pa.
    pub shear_modulus: f64,
    /// Density ρ, kg/m³.
    pub density: f64,
}

/// A solid circular or tubular cross-section.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Section {
    /// Outer diameter, m.
    pub outer_diameter: f64,
    /// Inner diameter, m (0: solid).
    #[serde(default)]
    pub inner_diameter: f64,
}

impl Section {
    /// Area A, m².
    pub fn area(&self) -> f64 {
        std::f64::consts::FRAC_PI_4 * (self.outer_diameter.powi(2) - self.inner_diameter.powi(2))
    }

    /// Second moment of area I (= I_y = I_z), m⁴.
    pub fn second_moment(&self) -> f64 {
        std::f64::consts::PI / 64.0 * (self.outer_diameter.powi(4) - self.inner_diameter.powi(4))
    }

    /// Polar moment J (torsion constant of a circular section), m⁴.
    pub fn polar_moment(&self) -> f64 {
        2.0 * self.second_moment()
    }
}

/// A straight beam at rest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Beam {
    /// Material.
    pub material: Material,
    /// Cross-section.
    pub section: Section,
    /// Rest length between the two grasp nodes, m.
    pub length: f64,
}

/// Why a beam (or its stiffness model) is unusable; messages name the field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BeamError {
    /// A modulus, density, diameter or the length is not finite and > 0.
    #[error("`{0}` must be > 0")]
    NotPositive(&'static str),
    /// The inner diameter is negative, not finite or not below the outer one.
    #[error("`section.inner_diameter` must be in [0, outer_diameter)")]
    InnerDiameter,
    /// The FE beam's middle-node stiffness block has no Cholesky factor.
    #[error("beam stiffness: middle-node block is not positive definite")]
    MiddleBlock,
    /// The carried chain's free stiffness block has no Cholesky factor.
    #[error("carried chain: the free block of the stiffness is not positive definite")]
    ChainBlock,
}

impl From<BeamError> for crate::error::SetupError {
    fn from(e: BeamError) -> Self {
        crate::error::SetupError::other(e.to_string())
    }
}

impl Beam {
    /// Why the beam is unusable, if it is (messages name the field).
    pub fn validate(&self) -> Result<(), BeamError> {
        let m = &self.material;
        let s = &self.section;
        let pos = |v: f64| v.is_finite() && v > 0.0;
        for (field, v) in [
            ("material.youngs_modulus", m.youngs_modulus),
            ("material.shear_modulus", m.shear_modulus),
            ("material.density", m.density),
            ("section.outer_diameter", s.outer_diameter),
        ] {
            if !pos(v) {
                return Err(BeamError::NotPositive(field));
            }
        }
        if !(s.inner_diameter.is_finite()
            && s.inner_diameter >= 0.0
            && s.inner_diameter < s.outer_diameter)
        {
            return Err(BeamError::InnerDiameter);
        }
        if !pos(self.length) {
            return Err(BeamError::NotPositive("length"));
        }
        Ok(())
    }

    /// Mass per unit length, kg/m.
    pub fn mass_per_length(&self) -> f64 {
        self.material.density * self.section.area()
    }

    /// Bending stiffness EI, N m².
    pub fn bending_stiffness(&self) -> f64 {
        self.material.youngs_modulus * self.section.second_moment()
    }

    /// Torsional stiffness GJ, N m².
    pub fn torsional_stiffness(&self) -> f64 {
        self.material.shear_modulus * self.section.polar_moment()
    }

    /// Axial stiffness EA, N.
    pub fn axial_stiffness(&self) -> f64 {
        self.material.youngs_modulus * self.section.area()
    }
}

/// Pultruded glass-fibre/epoxy (GFRP) solid rod, 10 mm: E = 40 GPa along the
/// fibres, G = 4 GPa, ρ = 2000 kg/m³ (typical manufacturer data for
/// pultruded E-glass rods). Chosen for seed 004's "deformable beam": at the
/// lengths of Table I (3–4.5 m) it bends visibly under its own weight and
/// under the grasps' motion while staying elastic (strain < 1 % for
/// curvatures below 2 m⁻¹), and at 0.16 kg/m a PUMA carries it easily.
pub const GFRP_ROD_10MM: (Material, Section) = (
    Material {
        youngs_modulus: 40e9,
        shear_modulus: 4e9,
        density: 2000.0,
    },
    Section {
        outer_diameter: 0.010,
        inner_diameter: 0.0,
    },
);
