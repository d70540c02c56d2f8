//! Plans: what a planner hands to the harness.
//!
//! A [`Plan`] is either an open-loop command u(t) or a feedback policy
//! u = k(t, q). Both are consumed through [`Plan::controller`], so the ideal
//! run and the physics replay treat them the same way; a feedback policy is
//! simply evaluated on whichever state (ideal or simulated) it is given.

use crate::model::{Input, State};
use serde::Serialize;
use std::sync::Arc;

/// The longest plan (or feedback horizon) a scenario may have, s: far
/// beyond any run the step budget allows, short of durations whose steps
/// cannot be counted.
pub const MAX_DURATION: f64 = 1e6;

/// A named time interval of an open-loop plan, e.g. "OZ" or "loop x: PQ".
#[derive(Debug, Clone, Serialize)]
pub struct Segment {
    /// Index into [`Plan::labels`].
    pub label: usize,
    /// Start time, s.
    pub start: f64,
    /// End time, s.
    pub end: f64,
}

/// What a controller outputs at one instant.
#[derive(Debug, Clone)]
pub struct Command {
    /// The input vector.
    pub u: Input,
    /// Index into [`Plan::labels`] of the segment or primitive in force.
    pub label: usize,
    /// The controller considers the task complete (feedback policies only).
    pub done: bool,
}

/// A controller instance: produces u from (t, q). Open-loop plans ignore q.
pub trait Controller: Send {
    /// The command at time `t` with measured state `q`.
    fn command(&mut self, t: f64, q: &State) -> Command;
    /// Why the controller stopped working, once it has (an external law's
    /// process died, answered garbage or too late; a caller's law raised).
    /// The runs ask after every command and end with a runtime failure
    /// (exit 3) carrying this message; the command that came with the fault
    /// is never applied. Built-in controllers never fail: `None`.
    fn fault(&self) -> Option<String> {
        None
    }

    /// The command when the replay also measures what the model
    /// coordinates leave out (a physics system's `measurement`, e.g. the
    /// 3D poses of the mobile manipulators' flanges). Default: ignore it.
    fn command_measured(&mut self, t: f64, q: &State, _measured: &[f64]) -> Command {
        self.command(t, q)
    }
}

/// A controller asked at most once per sample: a call with the same `t`
/// and state (bit for bit) as the one before gets the same command again
/// without asking the inner controller. The runs ask a feedback law twice
/// at t = 0 (to start, then as the first sample); a law outside the harness
/// (an external process, a Python callable) sees each sample once.
pub struct OncePerSample<C> {
    inner: C,
    last: Option<(u64, Vec<u64>, Command)>,
}

impl<C: Controller> OncePerSample<C> {
    /// Wrap `inner`.
    pub fn new(inner: C) -> Self {
        OncePerSample { inner, last: None }
    }

    /// The wrapped controller.
    pub fn inner(&self) -> &C {
        &self.inner
    }
}

impl<C: Controller> Controller for OncePerSample<C> {
    fn command(&mut self, t: f64, q: &State) -> Command {
        let same = |(tb, qb, _): &(u64, Vec<u64>, Command)| {
            *tb == t.to_bits()
                && qb.len() == q.len()
                && qb.iter().zip(q.iter()).all(|(a, b)| *a == b.to_bits())
        };
        if let Some(last) = self.last.as_ref().filter(|l| same(l)) {
            return last.2.clone();
        }
        let c = self.inner.command(t, q);
        self.last = Some((
            t.to_bits(),
            q.iter().map(|v| v.to_bits()).collect(),
            c.clone(),
        ));
        c
    }

    fn fault(&self) -> Option<String> {
        self.inner.fault()
    }
}

/// Builds fresh controller instances (a feedback policy may keep internal
/// state, so the ideal run and the physics run each get their own).
pub trait PolicyFactory: Send + Sync {
    /// A new controller, in its initial state.
    fn start(&self) -> Box<dyn Controller>;
    /// Label names for policies that name their labels while running (an
    /// external law sends strings): index i names label i of the commands
    /// issued so far, by every controller of this factory. `None`: the plan's
    /// own [`Plan::labels`] are complete (every built-in policy).
    fn labels(&self) -> Option<Vec<String>> {
        None
    }
    /// Whether two controllers of this factory may run at the same time
    /// (the ideal run beside the physics replay). `false` for laws outside
    /// the harness, which may share state between their controllers and
    /// name labels in the order they meet them.
    fn concurrent(&self) -> bool {
        true
    }
}

/// Label names interned while running, shared by the controllers of one
/// factory (see [`PolicyFactory::labels`]). Indices never change once given,
/// so a label index in a trajectory stays valid; the ideal run interns
/// before the physics run, so the table is the same on every run.
#[derive(Debug, Default)]
pub struct LabelTable(std::sync::Mutex<Vec<String>>);

impl LabelTable {
    /// A table holding `names` (indices 0..).
    pub fn new(names: Vec<String>) -> LabelTable {
        LabelTable(std::sync::Mutex::new(names))
    }

    /// The index of `name`, added when new; `None` when the table already
    /// holds `max` names and `name` is not one of them.
    pub fn intern(&self, name: &str, max: usize) -> Option<usize> {
        let mut names = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = names.iter().position(|n| n == name) {
            return Some(i);
        }
        if names.len() >= max {
            return None;
        }
        names.push(name.to_string());
        Some(names.len() - 1)
    }

    /// The names so far.
    pub fn names(&self) -> Vec<String> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Open-loop command u(t) plus the label in force at t.
pub type OpenLoopFn = dyn Fn(f64) -> (Input, usize) + Send + Sync;

/// How the plan produces commands.
#[derive(Clone)]
pub enum ControlLaw {
    /// A fixed u(t), evaluated continuously (at every integrator stage).
    OpenLoop(Arc<OpenLoopFn>),
    /// A fixed u(t) that jumps at known times, e.g. a zero-order hold of
    /// samples (plan files): evaluated like [`ControlLaw::OpenLoop`], with the
    /// jumps declared instead of found at segment joins.
    Piecewise {
        /// u(t) and the label in force (right-continuous at the jumps).
        u: Arc<OpenLoopFn>,
        /// Jump times in (0, duration], increasing.
        jumps: Arc<[f64]>,
    },
    /// A feedback law u = k(t, q), sampled every `period` seconds and held.
    Feedback {
        /// Creates controller instances.
        factory: Arc<dyn PolicyFactory>,
        /// Sample period, s.
        period: f64,
    },
}

/// The output of a planner.
#[derive(Clone)]
pub struct Plan {
    /// Names of segments (open loop) or primitives (feedback).
    pub labels: Vec<String>,
    /// Timed segments of an open-loop plan; empty for feedback policies.
    pub segments: Vec<Segment>,
    /// Open loop: exact duration. Feedback: time horizon (the run stops earlier when `done`).
    pub duration: f64,
    /// The command source.
    pub law: ControlLaw,
    /// Planner-derived numbers (loop sizes, chosen parameters...) for reports.
    pub details: serde_json::Value,
}

struct OpenLoopController(Arc<OpenLoopFn>);

impl Controller for OpenLoopController {
    fn command(&mut self, t: f64, _q: &State) -> Command {
        let (u, label) = (self.0)(t);
        Command {
            u,
            label,
            done: false,
        }
    }
}

impl Plan {
    /// A feedback plan: `factory`'s controllers sampled every `period` s and
    /// held, for at most `horizon` s (less when a controller reports `done`).
    /// `labels` may be empty when the factory names its labels while running
    /// ([`PolicyFactory::labels`]).
    pub fn feedback(
        labels: Vec<String>,
        factory: Arc<dyn PolicyFactory>,
        period: f64,
        horizon: f64,
        details: serde_json::Value,
    ) -> Plan {
        Plan {
            labels,
            segments: Vec::new(),
            duration: horizon,
            law: ControlLaw::Feedback { factory, period },
            details,
        }
    }

    /// A fresh controller for one run.
    pub fn controller(&self) -> Box<dyn Controller> {
        match &self.law {
            ControlLaw::OpenLoop(f) | ControlLaw::Piecewise { u: f, .. } => {
                Box::new(OpenLoopController(f.clone()))
            }
            ControlLaw::Feedback { factory, .. } => factory.start(),
        }
    }

    /// The plan with the label names its policy has used so far (see
    /// [`PolicyFactory::labels`]): for the logs, after the runs. Borrowed
    /// when the plan's own labels are complete.
    pub fn with_run_labels(&self) -> std::borrow::Cow<'_, Plan> {
        let ControlLaw::Feedback { factory, .. } = &self.law else {
            return std::borrow::Cow::Borrowed(self);
        };
        match factory.labels() {
            Some(labels) => std::borrow::Cow::Owned(Plan {
                labels,
                ..self.clone()
            }),
            None => std::borrow::Cow::Borrowed(self),
        }
    }

    /// Sample-and-hold period for feedback laws; `None` for continuous open-loop commands.
    pub fn hold_period(&self) -> Option<f64> {
        match &self.law {
            ControlLaw::OpenLoop(_) | ControlLaw::Piecewise { .. } => None,
            ControlLaw::Feedback { period, .. } => Some(*period),
        }
    }

    /// Times in (0, duration) where an open-loop u(t) jumps, increasing:
    /// segment joins whose one-sided limits differ (relative 1e-9), or the
    /// declared jumps of a [`ControlLaw::Piecewise`] law (in (0, duration]:
    /// a held plan may jump at its end, where the last step must still read
    /// the value before). Empty for feedback laws (their holds are the
    /// sample grid itself).
    pub fn jumps(&self) -> Vec<f64> {
        let f = match &self.law {
            ControlLaw::OpenLoop(f) => f,
            // A held plan's last sample can be a jump: the run ends there.
            ControlLaw::Piecewise { jumps, .. } => {
                let inside = |j: &&f64| **j > 0.0 && **j <= self.duration;
                return jumps.iter().filter(inside).copied().collect();
            }
            ControlLaw::Feedback { .. } => return Vec::new(),
        };
        let mut out: Vec<f64> = Vec::new();
        for s in &self.segments {
            let b = s.start;
            if b <= 0.0 || b >= self.duration || out.iter().any(|j| (j - b).abs() < 1e-12) {
                continue;
            }
            let (l, r) = (f(b - jump_offset(b)).0, f(b + jump_offset(b)).0);
            let scale = l.iter().chain(r.iter()).fold(1.0f64, |m, x| m.max(x.abs()));
            if l.iter()
                .zip(r.iter())
                .any(|(a, c)| (a - c).abs() > 1e-9 * scale)
            {
                out.push(b);
            }
        }
        out.sort_by(f64::total_cmp);
        out
    }

    /// How `/plan/command` relates to the plan (for logs): continuous u(t)
    /// sampled at the ideal grid (right limits at jumps) or a feedback
    /// command held for `hold_period_s`, the jump times, and the planner's
    /// details (e.g. the endogenous segments' Legendre coefficients).
    pub fn command_info(&self) -> serde_json::Value {
        match self.hold_period() {
            Some(p) => serde_json::json!({
                "kind": "held", "hold_period_s": p, "details": self.details,
            }),
            // A held file plan jumps at (nearly) every sample: the count, not
            // the list (the samples are `/plan/command` itself).
            None if matches!(self.law, ControlLaw::Piecewise { .. }) => serde_json::json!({
                "kind": "continuous", "jump_count": self.jumps().len(), "details": self.details,
            }),
            None => serde_json::json!({
                "kind": "continuous", "jumps_s": self.jumps(), "details": self.details,
            }),
        }
    }

    /// Name of a label index ("?" when out of range).
    pub fn label_name(&self, label: usize) -> &str {
        self.labels.get(label).map(String::as_str).unwrap_or("?")
    }
}

/// How far from a jump its one-sided limits are read, s: far below any
/// step, far above round-off of t.
pub(crate) fn jump_offset(t: f64) -> f64 {
    1e-11 * t.abs().max(1.0)
}

/// Velocity profile along one straight segment: smoothstep ramps of length
/// `ramp` at both ends around a cruise phase. Acceleration and jerk are zero
/// at the ends, so segments chain smoothly and RK4 keeps its order.
#[derive(Debug, Clone, Copy)]
pub struct RampProfile {
    /// Total duration, s.
    pub duration: f64,
    /// Ramp duration at each end, s (≤ duration / 2).
    pub ramp: f64,
}

impl RampProfile {
    /// ds/dt at local time τ ∈ [0, duration], normalised so that ∫ ds = 1.
    pub fn rate(&self, tau: f64) -> f64 {
        let (d, r) = (self.duration, self.ramp);
        if !(0.0..=d).contains(&tau) || d <= 0.0 {
            return 0.0;
        }
        let v = 1.0 / (d - r);
        // Quintic smoothstep: u, u' and u'' are continuous at the leg ends, so
        // RK4 keeps its fourth order across legs.
        let edge = |s: f64| {
            let x = s / r;
            v * x * x * x * (10.0 + x * (-15.0 + 6.0 * x))
        };
        if tau < r {
            edge(tau)
        } else if tau > d - r {
            edge(d - tau)
        } else {
            v
        }
    }
}

impl RampProfile {
    /// Fraction of the leg covered at local time τ (the integral of [`RampProfile::rate`]).
    pub fn progress(&self, tau: f64) -> f64 {
        let (d, r) = (self.duration, self.ramp);
        if d <= 0.0 || tau >= d {
            return 1.0;
        }
        if tau <= 0.0 {
            return 0.0;
        }
        let v = 1.0 / (d - r);
        let edge = |s: f64| {
            if r > 0.0 {
                let x = s / r;
                v * r * x.powi(4) * (2.5 + x * (-3.0 + x))
            } else {
                0.0
            }
        };
        if tau < r {
            edge(tau)
        } else if tau > d - r {
            1.0 - edge(d - tau)
        } else {
            0.5 * v * r + v * (tau - r)
        }
    }
}

/// One straight segment in the space of integrated inputs (∫u dt).
#[derive(Debug, Clone)]
pub struct Leg {
    /// Index into the plan's labels.
    pub label: usize,
    /// Total change of ∫u dt over the leg.
    pub delta: Input,
    /// Velocity profile.
    pub profile: RampProfile,
}

/// Rate limits for building legs.
#[derive(Debug, Clone)]
pub struct Limits {
    /// Per-input magnitude limit of u.
    pub max_rate: Vec<f64>,
    /// Ramp time at each end of a leg, s.
    pub ramp: f64,
    /// Durations are rounded up to a multiple of this step (the sim dt), s.
    pub step: f64,
}

impl Limits {
    /// The fastest ramped profile moving by `delta` within the rate limits.
    pub fn profile(&self, delta: &Input) -> RampProfile {
        let cruise = delta
            .iter()
            .zip(&self.max_rate)
            .map(|(d, m)| d.abs() / m)
            .fold(0.0, f64::max);
        // Legs shorter than a ramp are slowed to last two ramps: ramps of a few
        // steps would cost RK4 its order (and the physics its smoothness).
        let ramp = if cruise > 0.0 { self.ramp } else { 0.0 };
        let raw = cruise.max(ramp) + ramp;
        let duration = (raw / self.step - 1e-9).ceil().max(0.0) * self.step;
        // Stretch the ramp with the duration so the peak rate stays within limits.
        RampProfile {
            duration,
            ramp: ramp * duration / raw.max(f64::MIN_POSITIVE),
        }
    }
}

/// Chains legs into an open-loop plan. Legs with zero motion are skipped.
pub fn plan_from_legs(
    labels: Vec<String>,
    legs: Vec<(usize, Input)>,
    limits: &Limits,
    details: serde_json::Value,
) -> Plan {
    let m = limits.max_rate.len();
    let mut timed: Vec<(f64, Leg)> = Vec::new();
    let mut segments = Vec::new();
    let mut t = 0.0;
    for (label, delta) in legs {
        if delta.amax() == 0.0 {
            continue;
        }
        let profile = limits.profile(&delta);
        segments.push(Segment {
            label,
            start: t,
            end: t + profile.duration,
        });
        timed.push((
            t,
            Leg {
                label,
                delta,
                profile,
            },
        ));
        t += profile.duration;
    }
    let duration = t;
    let last_label = timed.last().map(|(_, l)| l.label).unwrap_or(0);
    let law = ControlLaw::OpenLoop(Arc::new(move |time: f64| {
        // Binary search for the leg containing `time`.
        let idx = timed
            .partition_point(|(t0, _)| *t0 <= time)
            .saturating_sub(1);
        match timed.get(idx) {
            Some((t0, leg)) if time <= t0 + leg.profile.duration => {
                (&leg.delta * leg.profile.rate(time - t0), leg.label)
            }
            _ => (Input::zeros(m), last_label),
        }
    }));
    Plan {
        labels,
        segments,
        duration,
        law,
        details,
    }
}
