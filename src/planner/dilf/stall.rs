//! Progress of the feedback law (ours): the stall stop and the hand-over to
//! the final alignment.
//!
//! Eq. 18 keeps V̇ ≥ 0, and Proposition 2 concludes convergence from it
//! only where V has no critical point but the goal ("v_r vanishes only at
//! the origin", Appendix G). A V with a spurious local maximum (a wall
//! across the dipole's field line: `docs/src/research/seed-004-stall.md`),
//! or a sliding motion on the switching surface of Eq. 18a where V̇ = 0 with
//! v ≠ 0 on either side, leaves the law moving without raising V until the
//! horizon. [`Progress`] watches for that:
//!
//! * **progress** is V rising by the factor `1 + gain` above the best value
//!   seen so far, or, while a platform turns in place to its goal heading,
//!   the largest heading error of the aligning platforms shrinking by the
//!   same factor (that turn converges by itself, V need not rise);
//! * **stall**: no progress for `time` seconds ends the run (label
//!   `stalled`);
//! * **hand-over**: a platform within the position tolerance whose law has
//!   made no progress for `handover_time` seconds starts the final
//!   alignment even if it is not within half the tolerance (where the
//!   alignment normally starts), and a platform that has started aligning
//!   keeps aligning while it stays within the tolerance (in physics its
//!   axle drifts by millimetres while it turns).

use serde::{Deserialize, Serialize};

/// `[planner.stall]`: when the law counts as stalled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StallParams {
    /// No progress for this long ends the run with the label `stalled`, s;
    /// 0 disables the stop (the run goes on to the horizon).
    pub time: f64,
    /// Relative rise of V (and relative fall of the aligning platforms'
    /// heading error) that counts as progress.
    pub gain: f64,
    /// No progress for this long hands a platform within the position
    /// tolerance over to the final alignment, s.
    pub handover_time: f64,
}

impl Default for StallParams {
    /// 10 s: 2.5 times the longest in-place turn the limits allow (π at
    /// 0.8 rad/s), and twice the longest stretch without 1 % of progress in
    /// the shipped runs that reach their goal or stop for another reason
    /// (4.7 s, `dilf_paper`'s physics replay). 3 s for the hand-over: near
    /// its goal Eq. 18 may turn a platform for a second or two with V
    /// nearly flat before it closes in, and handing over then only makes
    /// the alignment start farther out.
    fn default() -> Self {
        StallParams {
            time: 10.0,
            gain: 0.01,
            handover_time: 3.0,
        }
    }
}

impl StallParams {
    /// Range checks: (parameter, reason) of the first bad one.
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        if !(self.time.is_finite() && self.time >= 0.0) {
            return Err(("stall.time", "must be ≥ 0 s (0 disables the stall stop)"));
        }
        if !(self.gain.is_finite() && self.gain > 0.0) {
            return Err(("stall.gain", "must be > 0 (a relative rise of V)"));
        }
        if !(self.handover_time.is_finite() && self.handover_time >= 0.0) {
            return Err(("stall.handover_time", "must be ≥ 0 s"));
        }
        Ok(())
    }
}

/// What the law's progress says at one policy sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Progress within the last `handover_time` seconds.
    Moving,
    /// No progress for `handover_time` seconds: platforms within the
    /// position tolerance start aligning.
    HandOver,
    /// No progress for `time` seconds: the run ends.
    Stalled,
}

/// The progress tracker of one run (one per controller instance).
#[derive(Debug, Clone)]
pub struct Progress {
    params: StallParams,
    ln_factor: f64,
    /// ln V at the last progress.
    best_ln_v: f64,
    /// Largest heading error of the aligning platforms at the last progress
    /// (∞ while none aligns).
    best_heading: f64,
    /// Time of the last progress, s.
    since: f64,
}

impl Progress {
    /// A tracker for a run starting at t = 0.
    pub fn new(params: StallParams) -> Progress {
        Progress {
            params,
            ln_factor: params.gain.ln_1p(),
            best_ln_v: f64::NEG_INFINITY,
            best_heading: f64::INFINITY,
            since: 0.0,
        }
    }

    /// Record the sample at time `t` with potential `v` (> 0) and the largest
    /// heading error of the platforms turning in place (`None` when none
    /// does), and say what it means.
    pub fn observe(&mut self, t: f64, v: f64, aligning_heading: Option<f64>) -> Verdict {
        let ln_v = v.ln();
        let mut progress = false;
        if ln_v >= self.best_ln_v + self.ln_factor {
            self.best_ln_v = ln_v;
            progress = true;
        }
        match aligning_heading {
            Some(h) if h * (1.0 + self.params.gain) <= self.best_heading => {
                self.best_heading = h;
                progress = true;
            }
            Some(_) => {}
            // Nobody turns in place: a later alignment starts afresh.
            None => self.best_heading = f64::INFINITY,
        }
        if progress {
            self.since = t;
        }
        let idle = t - self.since;
        if self.params.time > 0.0 && idle > self.params.time {
            Verdict::Stalled
        } else if idle > self.params.handover_time {
            Verdict::HandOver
        } else {
            Verdict::Moving
        }
    }

    /// Time of the last progress, s.
    pub fn since(&self) -> f64 {
        self.since
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// V rising by less than the gain is no progress; by more, it is. The
    /// stop comes `time` after the last progress, the hand-over after
    /// `handover_time`, both strictly after.
    #[test]
    fn stalls_after_the_stated_time_without_progress() {
        let p = StallParams {
            time: 3.0,
            gain: 0.01,
            handover_time: 0.5,
        };
        let mut g = Progress::new(p);
        let dt = 0.02;
        let mut v = 1.0;
        let mut t = 0.0;
        // 2 s of a 2 %/s rise: progress every ~0.5 s.
        while t < 2.0 {
            assert_ne!(g.observe(t, v, None), Verdict::Stalled);
            v *= 1.0 + 0.02 * dt;
            t += dt;
        }
        let last = g.since();
        assert!(last > 1.4, "{last}");
        // Then a creep of 0.3 % in total: never progress again.
        let mut verdicts = Vec::new();
        for k in 0..400 {
            let t = 2.0 + k as f64 * dt;
            verdicts.push((t, g.observe(t, v * (1.0 + 0.003 * k as f64 / 400.0), None)));
        }
        let first = |want| verdicts.iter().find(|(_, x)| *x == want).unwrap().0;
        assert!((first(Verdict::HandOver) - (last + 0.5)).abs() <= dt + 1e-9);
        assert!((first(Verdict::Stalled) - (last + 3.0)).abs() <= dt + 1e-9);
        assert_eq!(g.since(), last);
    }

    /// A platform turning in place counts as progress while its heading
    /// error shrinks, even with V constant; time 0 disables the stop.
    #[test]
    fn turning_in_place_is_progress_and_time_zero_never_stalls() {
        let mut g = Progress::new(StallParams {
            time: 1.0,
            gain: 0.01,
            handover_time: 0.2,
        });
        let mut h = 3.0f64;
        for k in 0..200 {
            let t = k as f64 * 0.02;
            assert_eq!(g.observe(t, 2.0, Some(h)), Verdict::Moving, "t = {t}");
            h *= 0.98;
        }
        let mut off = Progress::new(StallParams {
            time: 0.0,
            ..StallParams::default()
        });
        for k in 0..5000 {
            assert_ne!(off.observe(k as f64 * 0.02, 1.0, None), Verdict::Stalled);
        }
    }
}
