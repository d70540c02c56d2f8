//! The edge search of one dimension, independent of what a level is: a
//! level passes or fails (`eval` runs a batch of levels, in parallel if it
//! likes), level 0 (nominal) passes.
//!
//! 1. **Bracket up** along the ladder start, 2·start, 4·start, … (capped at
//!    the ceiling), `batch` levels per round, until a level fails; when the
//!    ceiling passes, the margin is the ceiling ("at least").
//! 2. When the first ladder level already fails, **bracket down** (start/2,
//!    start/4, …) until one passes; below the floor the margin is 0
//!    ("less than the floor").
//! 3. **Bisect** the bracket [lo, hi] (lo the largest passing level below
//!    the smallest failing one, hi that failing level) with `batch` equally
//!    spaced levels per round until hi ≤ lo·(1 + resolution). The margin is
//!    lo: every gate holds there, and the edge lies in [lo, hi).
//!
//! **Monotonicity** is checked on the way: the first round of bisection also
//! probes above hi (2·hi, capped at the ceiling) unless a probe above hi
//! exists already, and every pass found above a failure is reported as an
//! inversion. The margin stays conservative: the largest pass below the
//! smallest failure. Results depend on `batch` (which levels are probed),
//! never on how many threads evaluate them.
//!
//! A **run budget** (`max_levels`) ends the search before the next round
//! that would exceed it: the bracket reached so far is the result
//! ([`Status::Budget`]), coarser than the resolution and stated as such.

use serde::Serialize;

/// Where and how finely to search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spec {
    /// First level of the ladder.
    pub start: f64,
    /// Smallest level worth telling apart from 0.
    pub floor: f64,
    /// Largest level searched.
    pub ceiling: f64,
    /// Relative resolution: stop when hi ≤ lo·(1 + resolution).
    pub resolution: f64,
    /// Levels per round.
    pub batch: usize,
    /// At most this many levels in all (None: until the resolution).
    pub max_levels: Option<usize>,
}

/// How a search ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// An edge in [lo, hi).
    Found,
    /// Every level up to the ceiling passed: the margin is at least the ceiling.
    Ceiling,
    /// Every level down to the floor failed: the margin is below the floor.
    BelowFloor,
    /// The nominal run already breaks a gate: no margin.
    NominalFails,
    /// The run budget ended the search: the edge lies in [margin, hi) (hi
    /// ∞: not bracketed yet; margin 0: no level passed yet).
    Budget,
}

/// One evaluated level.
#[derive(Debug, Clone)]
pub struct Probe<T> {
    /// The level (perturbation magnitude).
    pub level: f64,
    /// Every gate held.
    pub pass: bool,
    /// The round it was evaluated in (1, 2, …).
    pub round: usize,
    /// What the evaluation returned.
    pub data: T,
}

/// The result of a search.
#[derive(Debug, Clone)]
pub struct Outcome<T> {
    /// How it ended.
    pub status: Status,
    /// The margin: the largest passing level below the smallest failing one.
    pub margin: f64,
    /// The smallest failing level (∞ when none failed).
    pub hi: f64,
    /// Every probe, by level.
    pub probes: Vec<Probe<T>>,
    /// Non-monotone pattern: (failing level, passing level above it).
    pub inversions: Vec<(f64, f64)>,
    /// Rounds of `eval`.
    pub rounds: usize,
}

/// Runs a batch of levels: one (pass, data) per level, in order.
pub type Eval<'a, T> = dyn FnMut(&[f64]) -> Vec<(bool, T)> + 'a;

/// Search the edge (module docs). `eval` gets a batch of levels and returns
/// one (pass, data) per level, in order.
pub fn search<T>(spec: &Spec, eval: &mut Eval<'_, T>) -> Outcome<T> {
    let b = spec.batch.max(1);
    let mut st = State {
        probes: Vec::new(),
        rounds: 0,
        budget: spec.max_levels,
    };
    // 1. Up the ladder.
    let mut x = spec.start.min(spec.ceiling);
    loop {
        let mut levels = Vec::new();
        while levels.len() < b {
            levels.push(x);
            if x >= spec.ceiling {
                break;
            }
            x = (2.0 * x).min(spec.ceiling);
        }
        if !st.run(levels, eval) {
            return st.finish(Status::Budget);
        }
        if st.probes.iter().any(|p| !p.pass) {
            break;
        }
        if st.probes.iter().any(|p| p.level >= spec.ceiling) {
            return st.finish(Status::Ceiling);
        }
    }
    // 2. Down the ladder while nothing passes below the first failure.
    loop {
        let (lo, hi) = st.bracket();
        if lo > 0.0 {
            break;
        }
        let mut levels = Vec::new();
        let mut y = hi / 2.0;
        while levels.len() < b && y >= spec.floor {
            levels.push(y);
            y /= 2.0;
        }
        if levels.is_empty() {
            return st.finish(Status::BelowFloor);
        }
        if !st.run(levels, eval) {
            return st.finish(Status::Budget);
        }
    }
    // 3. Bisect, checking once above the bracket.
    let mut checked_above = false;
    loop {
        let (lo, hi) = st.bracket();
        if hi <= lo * (1.0 + spec.resolution) {
            break;
        }
        let mut levels: Vec<f64> = (1..=b)
            .map(|i| lo + (hi - lo) * i as f64 / (b + 1) as f64)
            .collect();
        if !checked_above {
            checked_above = true;
            if !st.probes.iter().any(|p| p.level > hi) && hi < spec.ceiling {
                levels.push((2.0 * hi).min(spec.ceiling));
            }
        }
        if !st.run(levels, eval) {
            return st.finish(Status::Budget);
        }
    }
    st.finish(Status::Found)
}

/// The probes so far.
struct State<T> {
    probes: Vec<Probe<T>>,
    rounds: usize,
    /// Levels that may still be run (None: no limit).
    budget: Option<usize>,
}

impl<T> State<T> {
    /// Evaluate the levels not probed yet, as one round, as many as the
    /// budget leaves (in order: the search's first choices first). False
    /// when the budget is spent and nothing was run.
    fn run(&mut self, levels: Vec<f64>, eval: &mut Eval<'_, T>) -> bool {
        let mut levels: Vec<f64> = levels
            .into_iter()
            .filter(|l| !self.probes.iter().any(|p| p.level == *l))
            .collect();
        if let Some(left) = &mut self.budget {
            if *left == 0 {
                return false;
            }
            levels.truncate(*left);
            *left -= levels.len();
        }
        if levels.is_empty() {
            return true;
        }
        self.rounds += 1;
        for (level, (pass, data)) in levels.iter().zip(eval(&levels)) {
            self.probes.push(Probe {
                level: *level,
                pass,
                round: self.rounds,
                data,
            });
        }
        true
    }

    /// The smallest failure (∞ without one) and the largest pass below it (0 without one).
    fn bracket(&self) -> (f64, f64) {
        let hi = self
            .probes
            .iter()
            .filter(|p| !p.pass)
            .map(|p| p.level)
            .fold(f64::INFINITY, f64::min);
        let lo = self
            .probes
            .iter()
            .filter(|p| p.pass && p.level < hi)
            .map(|p| p.level)
            .fold(0.0, f64::max);
        (lo, hi)
    }

    fn finish(mut self, status: Status) -> Outcome<T> {
        let (lo, hi) = self.bracket();
        self.probes.sort_by(|a, c| a.level.total_cmp(&c.level));
        let mut inversions = Vec::new();
        for p in self.probes.iter().filter(|p| p.pass) {
            if let Some(f) = self.probes.iter().find(|f| !f.pass && f.level < p.level) {
                inversions.push((f.level, p.level));
            }
        }
        let margin = match status {
            Status::BelowFloor | Status::NominalFails => 0.0,
            Status::Found | Status::Ceiling | Status::Budget => lo,
        };
        Outcome {
            status,
            margin,
            hi,
            probes: self.probes,
            inversions,
            rounds: self.rounds,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn spec() -> Spec {
        Spec {
            start: 0.01,
            floor: 1e-6,
            ceiling: 5.0,
            resolution: 0.05,
            batch: 2,
            max_levels: None,
        }
    }

    /// Evaluates `pass` on every level and counts the levels.
    fn run(spec: &Spec, pass: impl Fn(f64) -> bool) -> (Outcome<()>, usize) {
        let mut n = 0;
        let o = search(spec, &mut |levels: &[f64]| {
            n += levels.len();
            assert!(levels.len() <= spec.batch + 1);
            levels.iter().map(|l| (pass(*l), ())).collect()
        });
        (o, n)
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(256))]
        /// A monotone case with a known edge: found to the stated resolution,
        /// from above and below the ladder's start, with any batch size.
        #[test]
        fn finds_a_known_edge_to_the_resolution(
            log_edge in -5.5f64..0.6, batch in 1usize..5, res in 0.01f64..0.3,
        ) {
            let edge = 10f64.powf(log_edge);
            let s = Spec { batch, resolution: res, ..spec() };
            let (o, n) = run(&s, |l| l <= edge);
            prop_assert_eq!(o.status, Status::Found);
            prop_assert!(o.margin <= edge && edge < o.hi, "{} {} {}", o.margin, edge, o.hi);
            prop_assert!(o.hi <= o.margin * (1.0 + res) * (1.0 + 1e-12));
            prop_assert!(o.inversions.is_empty());
            prop_assert_eq!(n, o.probes.len());
            // Every passing probe is at or below the edge, every failure above it.
            for p in &o.probes {
                prop_assert_eq!(p.pass, p.level <= edge);
            }
        }
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(128))]
        /// A run budget ends the search within it, with a bracket that holds
        /// the edge; a budget the search does not need changes nothing.
        #[test]
        fn a_budget_ends_the_search_with_a_true_bracket(
            log_edge in -5.5f64..0.6, batch in 1usize..5, max in 1usize..12,
        ) {
            let edge = 10f64.powf(log_edge);
            let s = Spec { batch, max_levels: Some(max), ..spec() };
            let (o, n) = run(&s, |l| l <= edge);
            prop_assert!(n <= max);
            prop_assert!(o.margin <= edge && edge < o.hi);
            let (full, m) = run(&spec_b(batch), |l| l <= edge);
            if m <= max {
                prop_assert_eq!(o.status, full.status);
                prop_assert_eq!((o.margin, o.hi), (full.margin, full.hi));
            } else if o.status == Status::Found {
                // A truncated round (the check above the bracket dropped)
                // can still reach the resolution.
                prop_assert!(o.hi <= o.margin * 1.05 * (1.0 + 1e-12));
            } else {
                prop_assert_eq!(o.status, Status::Budget);
            }
        }
    }

    fn spec_b(batch: usize) -> Spec {
        Spec { batch, ..spec() }
    }

    #[test]
    fn ceiling_and_floor() {
        let (o, _) = run(&spec(), |_| true);
        assert_eq!((o.status, o.margin), (Status::Ceiling, 5.0));
        assert!(o.hi.is_infinite());
        let (o, _) = run(&spec(), |l| l < 1e-7);
        assert_eq!((o.status, o.margin), (Status::BelowFloor, 0.0));
        assert!(o.probes.iter().all(|p| p.level >= 1e-6));
    }

    /// Pass up to 0.05, fail in (0.05, 0.1), pass again in [0.1, 0.3]: the
    /// check above the bracket finds the second pass; the margin stays below
    /// the first failure.
    #[test]
    fn a_non_monotone_case_is_reported() {
        let pass = |l: f64| l <= 0.05 || (0.1..=0.3).contains(&l);
        let (o, _) = run(&spec(), pass);
        assert_eq!(o.status, Status::Found);
        assert!(!o.inversions.is_empty(), "{:?}", o.inversions);
        let (f, p) = o.inversions[0];
        assert!(f > 0.05 && f < 0.1 && (0.1..=0.3).contains(&p), "{f} {p}");
        assert!(o.margin <= 0.05 && 0.05 < o.hi && o.hi <= o.margin * 1.05);
        // The same with a monotone pass: no inversion (the check can fail).
        let (o, _) = run(&spec(), |l| l <= 0.05);
        assert!(o.inversions.is_empty());
    }
}
