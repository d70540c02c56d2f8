//! Sampled-data safety of Eq. 18 (ours): the hold guard.
//!
//! V̇ ≥ 0 (Appendix G) is a continuous-time statement. The harness samples
//! the law every `period` and holds the input, and V's barriers are thin:
//! with box-like obstacles (n = 4) β grows like (distance)^{2n} away from
//! the surface and V like β^{1/(2k_v)}, so V is steep only millimetres from
//! a wall, and a 20 ms hold at 0.5 m/s (1 cm) can step over it: the field
//! at the sample points past a door's edge, the platform drives into it
//! before the next sample (seen on the pair's door tasks).
//!
//! The guard predicts the end of the hold exactly (the unicycle's arc, the
//! joints' ramps) and halves the whole input until, at the predicted state,
//! every barrier keeps at least half its present value: the least obstacle
//! function β (robot parts, the other robot, the beam), the least
//! singularity function, and the least admissible-ball margin
//! 1 − ‖q_fi‖²/q_F² of the beam's nodes. Far from every barrier the check
//! passes at once and the law is Eq. 18 unchanged. Scaling all inputs by the
//! same positive factor is a state-dependent k_v, k_o, K_a, so V̇ ≥ 0 still
//! holds at the sample (the same argument as the speed limits in
//! [`crate::robots::mobile_manipulator::dilf::control`]). A barrier can lose at most half its value per hold,
//! so it stays positive at every sample; to first order in the step the
//! check passes for a small enough scale whenever the barrier is positive,
//! so the halving ends.

use crate::robots::mobile_manipulator::dilf::contact::ContactError;
use crate::robots::mobile_manipulator::dilf::potential::{
    Evaluation, GraspCorrection, Scene, Warm,
};
use crate::robots::mobile_manipulator::kinematics::{DOF, INPUTS};

/// Each barrier may lose at most this fraction of its value over one hold.
pub const KEEP: f64 = 0.5;
/// Halvings tried before the input is zeroed for the hold.
pub const MAX_HALVINGS: u32 = 12;

/// The barrier values the guard keeps positive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Barriers {
    /// Least obstacle function β over every pair (∞ without pairs).
    pub beta: f64,
    /// Least singularity function over arms and factors (∞ without enclosures).
    pub singular: f64,
    /// Least 1 − ‖q_fi‖²/q_F² over the beam's nodes (∞ without a beam).
    pub admissible: f64,
}

impl Barriers {
    /// The barriers of an evaluation of V.
    pub fn of(e: &Evaluation<f64>) -> Barriers {
        Barriers {
            beta: e.min_beta,
            singular: e.min_singular,
            admissible: e.admissible,
        }
    }

    /// The barriers at `q` (f64 evaluation of V's terms; the beam at the
    /// measured flanges when given).
    pub fn at(
        scene: &Scene,
        q: &[f64],
        measured: Option<&GraspCorrection>,
        warm: &mut Warm,
    ) -> Result<Barriers, ContactError> {
        Ok(Barriers::of(
            &scene.evaluate_with::<f64>(q, measured, warm)?,
        ))
    }

    /// Whether `next` keeps every barrier of `self` at least at [`KEEP`] of its value.
    pub fn kept_by(&self, next: &Barriers) -> bool {
        let keeps = |now: f64, then: f64| then > 0.0 && then >= KEEP * now;
        keeps(self.beta, next.beta)
            && keeps(self.singular, next.singular)
            && keeps(self.admissible, next.admissible)
    }
}

/// The state after holding input `u` for `t` seconds from `q` (Eq. 1,
/// exactly: each platform on its arc, each joint on its ramp).
pub(crate) fn predict(q: &[f64], u: &[f64], t: f64) -> Vec<f64> {
    let mut out = q.to_vec();
    for (r, qr) in out.chunks_mut(DOF).enumerate() {
        let ur = &u[INPUTS * r..INPUTS * (r + 1)];
        let (v, w, th) = (ur[0], ur[1], qr[2]);
        let turn = w * t;
        // sin(θ + ωt) − sin θ over ω, continued to v t cos θ as ω → 0.
        let (dx, dy) = if turn.abs() < 1e-9 {
            (v * t * th.cos(), v * t * th.sin())
        } else {
            (
                v / w * ((th + turn).sin() - th.sin()),
                -v / w * ((th + turn).cos() - th.cos()),
            )
        };
        qr[0] += dx;
        qr[1] += dy;
        qr[2] += turn;
        for a in 0..6 {
            qr[3 + a] += ur[2 + a] * t;
        }
    }
    out
}

/// Scale `u` by 2^-k, k = 0, 1, …, until the predicted end of the hold
/// keeps `now`'s barriers ([`Barriers::kept_by`]); returns k, with `u`
/// zeroed when [`MAX_HALVINGS`] do not suffice. A failed evaluation at the
/// predicted state counts as not kept.
pub fn guard(
    scene: &Scene,
    q: &[f64],
    measured: Option<&GraspCorrection>,
    now: &Barriers,
    u: &mut [f64],
    period: f64,
    warm: &mut Warm,
) -> u32 {
    for k in 0..=MAX_HALVINGS {
        let next = Barriers::at(scene, &predict(q, u, period), measured, warm);
        if next.is_ok_and(|b| now.kept_by(&b)) {
            return k;
        }
        u.iter_mut().for_each(|x| *x *= 0.5);
    }
    u.iter_mut().for_each(|x| *x = 0.0);
    MAX_HALVINGS + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::simulate;
    use crate::model::State;
    use crate::plan::{Command, ControlLaw, Controller, Plan, PolicyFactory};
    use crate::robots::mobile_manipulator::kinematics::MobileManipulator;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::sync::Arc;

    /// A held input, for integrating the prediction independently.
    struct Hold(Vec<f64>);
    impl Controller for Hold {
        fn command(&mut self, _t: f64, _q: &State) -> Command {
            Command {
                u: crate::model::Input::from_vec(self.0.clone()),
                label: 0,
                done: false,
            }
        }
    }
    impl PolicyFactory for Hold {
        fn start(&self) -> Box<dyn Controller> {
            Box::new(Hold(self.0.clone()))
        }
    }

    /// The exact hold matches the harness's RK4 of Eq. 1 (random states and
    /// inputs, one and two robots, straight and turning).
    #[test]
    fn prediction_matches_the_integrated_model() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for robots in [1, 2] {
            for case in 0..40 {
                let q: Vec<f64> = (0..DOF * robots)
                    .map(|_| rng.random_range(-3.0..3.0))
                    .collect();
                let mut u: Vec<f64> = (0..INPUTS * robots)
                    .map(|_| rng.random_range(-1.0..1.0))
                    .collect();
                if case % 4 == 0 {
                    u[1] = 0.0;
                }
                let t = 0.3;
                let plan = Plan {
                    labels: vec!["hold".into()],
                    segments: Vec::new(),
                    duration: t,
                    law: ControlLaw::Feedback {
                        factory: Arc::new(Hold(u.clone())),
                        period: t,
                    },
                    details: serde_json::Value::Null,
                };
                let model = MobileManipulator { robots };
                let tr = simulate(&model, &plan, &State::from_vec(q.clone()), 1e-3);
                let end = tr.q.last().unwrap();
                let exact = predict(&q, &u, t);
                for (a, b) in exact.iter().zip(end.iter()) {
                    assert!((a - b).abs() < 1e-9, "{exact:?} vs {end:?}");
                }
            }
        }
    }

    /// Every barrier must keep half its value, and a barrier at 0 or below
    /// is never kept.
    #[test]
    fn barriers_are_kept_only_above_half() {
        let now = Barriers {
            beta: 0.4,
            singular: f64::INFINITY,
            admissible: 0.9,
        };
        let ok = Barriers {
            beta: 0.2,
            singular: f64::INFINITY,
            admissible: 0.5,
        };
        assert!(now.kept_by(&ok));
        assert!(!now.kept_by(&Barriers { beta: 0.19, ..ok }));
        assert!(!now.kept_by(&Barriers {
            admissible: 0.44,
            ..ok
        }));
        let grazing = Barriers { beta: 1e-12, ..now };
        assert!(!grazing.kept_by(&Barriers { beta: 0.0, ..ok }));
    }
}
