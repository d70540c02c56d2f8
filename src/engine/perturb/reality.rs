//! The command and observation perturbations of one replay (latency, lag,
//! state latency, noise), applied inside the replay loop; exact definitions
//! in [`super`]'s docs.

use super::Perturbation;
use crate::model::{Input, State};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A standard normal deviate (Box–Muller, one of the pair). Not `rand_distr`:
/// it turns on num-traits' `libm` feature, which rebuilds nalgebra, Rapier
/// and the Rerun SDK.
pub(crate) fn standard_normal(r: &mut ChaCha8Rng) -> f64 {
    // u1 in (0, 1], so the logarithm is finite.
    let u1 = 1.0 - r.random::<f64>();
    let u2 = r.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A duration as whole steps plus a fraction of a step: (n, f), 0 ≤ f < 1
/// (f snapped to 0 within round-off of the grid).
fn steps_and_fraction(duration: f64, dt: f64) -> (usize, f64) {
    if duration <= 0.0 {
        return (0, 0.0);
    }
    let x = duration / dt;
    let n = (x + 1e-9).floor();
    let f = x - n;
    (n as usize, if f < 1e-9 { 0.0 } else { f })
}

/// Steps a replay under `p` is extended by, so every delayed command arrives.
pub(crate) fn extra_steps(p: &Perturbation, dt: f64) -> usize {
    let (n, f) = steps_and_fraction(p.command_latency, dt);
    n.saturating_add(usize::from(f > 0.0))
}

/// The command and observation perturbations of one replay (module docs).
pub struct Reality {
    /// Latency: whole steps and the fraction of a step.
    lat: (usize, f64),
    /// The last `lat.0 + 2` commands, newest last.
    issued: std::collections::VecDeque<Input>,
    /// Lag: actuator state, e^(−dt/τ), and the mean of the step response
    /// over one step, (τ/dt)(1 − e^(−dt/τ)).
    lag: Option<(Input, f64, f64)>,
    /// State latency: whole steps and fraction.
    obs: (usize, f64),
    noise: f64,
    rng: ChaCha8Rng,
}

impl Reality {
    /// The perturbations of `p` for a replay with step `dt` and `inputs` inputs.
    pub fn new(p: &Perturbation, dt: f64, inputs: usize) -> Reality {
        let lag = (p.actuator_tau > 0.0).then(|| {
            let x = dt / p.actuator_tau;
            let decay = (-x).exp();
            // −expm1(−x)/x keeps full precision for τ ≫ dt.
            (Input::zeros(inputs), decay, -(-x).exp_m1() / x)
        });
        Reality {
            lat: steps_and_fraction(p.command_latency, dt),
            issued: std::collections::VecDeque::new(),
            lag,
            obs: steps_and_fraction(p.state_latency, dt),
            noise: p.state_noise,
            rng: ChaCha8Rng::seed_from_u64(p.seed),
        }
    }

    /// Whether the drives receive something other than what was issued.
    pub fn acts(&self) -> bool {
        self.lat != (0, 0.0) || self.lag.is_some()
    }

    /// Whether a feedback law sees something other than the current state.
    pub fn observes(&self) -> bool {
        self.obs != (0, 0.0) || self.noise > 0.0
    }

    /// What the drives receive over the next step, given the command issued for it.
    pub fn actuate(&mut self, issued: &Input) -> Input {
        let (n, f) = self.lat;
        let delayed = if (n, f) == (0, 0.0) {
            issued.clone()
        } else {
            self.issued.push_back(issued.clone());
            while self.issued.len() > n + 2 {
                self.issued.pop_front();
            }
            // c_{k−j} is at index len − 1 − j (zero before the first command).
            let len = self.issued.len();
            let at = |j: usize| {
                len.checked_sub(1 + j)
                    .map(|i| self.issued[i].clone())
                    .unwrap_or_else(|| Input::zeros(issued.len()))
            };
            if f == 0.0 {
                at(n)
            } else {
                at(n) * (1.0 - f) + at(n + 1) * f
            }
        };
        match &mut self.lag {
            None => delayed,
            Some((a, decay, mean)) => {
                // Mean over the step of c + (a0 − c) e^(−s/τ), then the state at its end.
                let out = &delayed + (&*a - &delayed) * *mean;
                *a = &delayed + (&*a - &delayed) * *decay;
                out
            }
        }
    }

    /// What a feedback law sees at sample `k` of the recorded states `q`
    /// (`q[k]` is the current one).
    pub fn observe(&mut self, q: &[State], k: usize) -> State {
        let (m, g) = self.obs;
        let at = |j: usize| &q[k.saturating_sub(j).min(q.len() - 1)];
        let mut seen = if g == 0.0 || k < m + 1 {
            at(m).clone()
        } else {
            at(m) * (1.0 - g) + at(m + 1) * g
        };
        if self.noise > 0.0 {
            for v in seen.iter_mut() {
                *v += self.noise * standard_normal(&mut self.rng);
            }
        }
        seen
    }
}

/// Channels `drive_issued_<input>` and `drive_received_<input>` (what the
/// controller sent, what the drives got, from each sample on) added to `sim`
/// when the commands were delayed or lagged (`sim.received` not empty), so
/// the logs show both: MCAP `/sim/channels`, Rerun `sim/drive_*`.
pub(crate) fn add_drive_channels(sim: &mut crate::record::SimTrajectory, input_names: &[&str]) {
    if sim.received.len() != sim.traj.u.len() {
        return;
    }
    for (j, name) in input_names.iter().enumerate() {
        let issued = sim.traj.u.iter().map(|u| u[j]).collect();
        sim.channels.push((format!("drive_issued_{name}"), issued));
    }
    for (j, name) in input_names.iter().enumerate() {
        let got = sim.received.iter().map(|u| u[j]).collect();
        sim.channels.push((format!("drive_received_{name}"), got));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(v: f64) -> Input {
        Input::from_vec(vec![v, -2.0 * v])
    }

    #[test]
    fn latency_on_the_grid_is_an_exact_shift() {
        let dt = 0.002;
        let p = Perturbation {
            command_latency: 7.0 * dt,
            ..Default::default()
        };
        let mut r = Reality::new(&p, dt, 2);
        assert!(r.acts() && !r.observes());
        assert_eq!(extra_steps(&p, dt), 7);
        let c: Vec<f64> = (0..40).map(|k| (k as f64 * 0.37).sin() + 0.1).collect();
        for (k, ck) in c.iter().enumerate() {
            let got = r.actuate(&input(*ck));
            let want = if k >= 7 { input(c[k - 7]) } else { input(0.0) };
            assert_eq!(got, want, "step {k}");
        }
    }

    #[test]
    fn latency_between_steps_blends_the_two_commands_it_straddles() {
        let dt = 0.01;
        let p = Perturbation {
            command_latency: 2.25 * dt,
            ..Default::default()
        };
        let mut r = Reality::new(&p, dt, 2);
        assert_eq!(extra_steps(&p, dt), 3);
        let c: Vec<f64> = (0..20).map(|k| k as f64 * k as f64).collect();
        for (k, _) in c.iter().enumerate() {
            let got = r.actuate(&input(c[k]))[0];
            let at = |j: isize| if j >= 0 { c[j as usize] } else { 0.0 };
            let want = 0.75 * at(k as isize - 2) + 0.25 * at(k as isize - 3);
            assert!((got - want).abs() < 1e-12, "step {k}: {got} vs {want}");
        }
    }

    /// The step response of the lag against its closed form: the mean over
    /// each step of 1 − e^(−t/τ), and the integral t − τ(1 − e^(−t/τ)).
    #[test]
    fn lag_matches_the_closed_form_step_response() {
        for (tau, dt) in [(0.05, 0.002), (0.003, 0.002), (2.0, 0.001)] {
            let p = Perturbation {
                actuator_tau: tau,
                ..Default::default()
            };
            let mut r = Reality::new(&p, dt, 2);
            let mut integral = 0.0;
            for k in 0..500 {
                let got = r.actuate(&input(1.0));
                let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
                let mean = 1.0 - tau * ((-t0 / tau).exp() - (-t1 / tau).exp()) / dt;
                assert!((got[0] - mean).abs() < 1e-12, "τ {tau} step {k}");
                assert!((got[1] + 2.0 * mean).abs() < 1e-12);
                integral += got[0] * dt;
                let exact = t1 - tau * (1.0 - (-t1 / tau).exp());
                assert!(
                    (integral - exact).abs() < 1e-12 * (1.0 + t1),
                    "τ {tau} t {t1}"
                );
            }
        }
    }

    #[test]
    fn state_latency_interpolates_and_noise_follows_the_seed() {
        let dt = 0.01;
        let q: Vec<State> = (0..10)
            .map(|k| State::from_vec(vec![k as f64, 10.0 * k as f64]))
            .collect();
        let p = Perturbation {
            state_latency: 2.5 * dt,
            ..Default::default()
        };
        let mut r = Reality::new(&p, dt, 2);
        assert!(r.observes() && !r.acts());
        assert_eq!(r.observe(&q, 9).as_slice(), &[6.5, 65.0]);
        assert_eq!(
            r.observe(&q, 1).as_slice(),
            &[0.0, 0.0],
            "start state before t = Ls"
        );
        let noisy = |seed| {
            let p = Perturbation {
                state_noise: 0.1,
                seed,
                ..Default::default()
            };
            let mut r = Reality::new(&p, dt, 2);
            (0..200)
                .flat_map(|k| r.observe(&q, k % 10).as_slice().to_vec())
                .collect::<Vec<f64>>()
        };
        let (a, b, c) = (noisy(3), noisy(3), noisy(4));
        assert_eq!(a, b);
        assert_ne!(a, c);
        // The deviates: mean ~0, σ ~0.1.
        let dev: Vec<f64> = (0..400).map(|i| a[i] - q[(i / 2) % 10][i % 2]).collect();
        let mean = dev.iter().sum::<f64>() / 400.0;
        let sd = (dev.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / 399.0).sqrt();
        assert!(mean.abs() < 0.02 && (sd - 0.1).abs() < 0.015, "{mean} {sd}");
    }
}
