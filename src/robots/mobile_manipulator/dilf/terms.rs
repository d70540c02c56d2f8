//! ln V split into its factors, with each factor's gradient: what drives
//! or holds a platform, for diagnostics (`examples/dilf_trace.rs`, the
//! seed-004 note's stall figures). The split itself is computed by
//! [`crate::robots::mobile_manipulator::dilf::potential::Scene::evaluate_terms`], beside V.

use crate::model::spatial::{k, Scalar};

/// ln V split into its factors: ln V = dipole − d + obstacles + robots +
/// beam_parts + beam_obstacles + singular + admissible, the numerator's
/// factors already divided by k_v (for diagnostics: which factor's gradient
/// drives or holds a robot).
#[derive(Debug, Clone)]
pub struct Terms<T> {
    /// ln of the dipole factor (Π γ_r, or its geometric mean).
    pub dipole: T,
    /// ln Σ_p ‖h2^p‖² (enters ln V with a minus sign).
    pub d: T,
    /// Robot parts against the static obstacles, / k_v.
    pub obstacles: T,
    /// Robot parts against the other robot's parts, / k_v.
    pub robots: T,
    /// Robot parts against the beam's segments, / k_v.
    pub beam_parts: T,
    /// The beam's segments against the static obstacles, / k_v.
    pub beam_obstacles: T,
    /// The singularity enclosures, / k_v.
    pub singular: T,
    /// ln b_f, the beam's admissible set, / k_v.
    pub admissible: T,
    /// Each robot's dipole γ_r.
    pub gammas: Vec<T>,
}

impl<T: Scalar> Default for Terms<T> {
    fn default() -> Self {
        Terms {
            dipole: k(0.0),
            d: k(0.0),
            obstacles: k(0.0),
            robots: k(0.0),
            beam_parts: k(0.0),
            beam_obstacles: k(0.0),
            singular: k(0.0),
            admissible: k(0.0),
            gammas: Vec::new(),
        }
    }
}

impl<T: Scalar> Terms<T> {
    /// (name, contribution to ln V): they sum to ln V.
    pub fn named(&self) -> Vec<(&'static str, T)> {
        vec![
            ("dipole", self.dipole),
            ("goal", -self.d),
            ("obstacles", self.obstacles),
            ("robots", self.robots),
            ("beam_parts", self.beam_parts),
            ("beam_obstacles", self.beam_obstacles),
            ("singular", self.singular),
            ("admissible", self.admissible),
        ]
    }
}

/// ln V's factors at one configuration with their gradients
/// ([`crate::robots::mobile_manipulator::dilf::potential::Scene::term_gradients`]).
#[derive(Debug, Clone)]
pub struct TermGradients {
    /// (name, value, ∂/∂q) of each contribution to ln V ([`Terms::named`]).
    pub terms: Vec<(&'static str, f64, Vec<f64>)>,
    /// Each robot's dipole γ_r.
    pub gammas: Vec<f64>,
}
