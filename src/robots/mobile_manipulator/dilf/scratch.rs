//! Buffers of the adjoint pass ([`crate::robots::mobile_manipulator::dilf::adjoint`]), kept in
//! [`crate::robots::mobile_manipulator::dilf::potential::Warm`]: their own module so that `potential` (which
//! owns `Warm`) does not import `adjoint` (which reads `potential`'s scene).

use crate::model::spatial::{M3, V3};
use crate::robots::mobile_manipulator::dilf::contact::Contact;
use crate::robots::mobile_manipulator::ellipsoid::PlacedEllipsoid;
use crate::robots::mobile_manipulator::kinematics::RobotFrames;

/// One shape of a contact pair.
#[derive(Debug, Clone, Copy)]
pub(super) enum Side {
    /// A static obstacle (constant).
    Static,
    /// Robot part `r * parts + i`.
    Part(usize),
    /// Beam segment.
    Segment(usize),
}

/// One (part, obstacle) pair of one part's stage.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pair {
    pub(super) beta: f64,
    /// ln b̃ = ln(β/(β+1)).
    pub(super) lb: f64,
    /// Minimiser x* and the multiplier of the minimised shape's surface.
    pub(super) x: V3<f64>,
    pub(super) mu: f64,
    /// The shape minimised over (weight μ in β) and the other (weight 1).
    pub(super) minimised: Side,
    pub(super) other: Side,
    /// The obstacle (the shape that is not the part) and h_p − h_O.
    pub(super) obstacle: Side,
    pub(super) delta: V3<f64>,
    pub(super) sigma: f64,
    pub(super) sqrt_b: f64,
    pub(super) moved: V3<f64>,
}

impl Pair {
    pub(super) fn new(beta: f64, sol: &Contact, sides: [Side; 3], delta: V3<f64>) -> Pair {
        Pair {
            beta,
            lb: (beta / (beta + 1.0)).ln(),
            x: sol.x,
            mu: sol.mu,
            minimised: sides[0],
            other: sides[1],
            obstacle: sides[2],
            delta,
            sigma: 0.0,
            sqrt_b: 0.0,
            moved: [0.0; 3],
        }
    }
}

/// What the reverse pass needs of one part's stage.
#[derive(Debug, Clone, Copy)]
pub(super) struct PartStage {
    pub(super) pairs: (usize, usize),
    pub(super) c: V3<f64>,
    pub(super) h: V3<f64>,
    pub(super) hh: f64,
    /// Whether the switches act (‖h‖ > 1e-12 and some obstacle), with their
    /// ln‖h‖ and Σ ln b̃.
    pub(super) switched: bool,
    pub(super) ln_h: f64,
    pub(super) total: f64,
    pub(super) shift: V3<f64>,
    pub(super) h2: V3<f64>,
    /// World → goal coordinates (h = rotᵀ(…)); `platform`: rot = Rz(θ_r).
    pub(super) rot: M3<f64>,
    pub(super) platform: bool,
}

/// Buffers of [`Scene::field`], kept in [`Warm`] so a call does not allocate.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    pub(super) frames: Vec<RobotFrames<f64>>,
    pub(super) placed: Vec<PlacedEllipsoid<f64>>,
    pub(super) segs: Vec<PlacedEllipsoid<f64>>,
    pub(super) pairs: Vec<Pair>,
    pub(super) ln_b: Vec<f64>,
    pub(super) parts: Vec<PartStage>,
    pub(super) gammas: Vec<f64>,
    pub(super) singular: Vec<[f64; 6]>,
    /// Per pair of the current part: adjoints of h_p − h_O and of ln b̃.
    pub(super) bar: Vec<(V3<f64>, f64)>,
    /// Per robot and joint depth (0 platform … 6 tool): force, moment about the origin.
    pub(super) wrench: Vec<[(V3<f64>, V3<f64>); 7]>,
    /// Beam segment against a static obstacle: (segment, β, x*, μ).
    pub(super) seg_static: Vec<(usize, f64, V3<f64>, f64)>,
    /// Per beam segment: adjoints of its centre and rotation.
    pub(super) seg_bar: Vec<(V3<f64>, M3<f64>)>,
}
