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
//! Every round is charged to it, one level at least, so a round that finds
//! nothing new to probe still spends budget.
//!
//! **Termination** whatever the resolution: the bisection also stops when
//! the bracket is within [`float_floor`] of its upper end (a few float
//! spacings per level of a round: below that the levels of a round could
//! not be told apart), and when a round finds no level it has not probed.
//! A resolution of 1e-300 therefore ends at the float spacing, after at
//! most about 40 rounds of 2.

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
    /// A `[margins]` gate in `run`/`check`: the one level at the gate passed,
    /// so the margin is at least the gate (not searched further).
    Holds,
    /// A `[margins]` gate in `run`/`check`: the level at the gate failed, so
    /// the margin is below the gate (not searched further).
    Breaks,
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
        match st.run(levels, eval) {
            Round::Ran => {}
            Round::Budget => return st.finish(Status::Budget),
            // Up the ladder every level is new: this cannot happen, and
            // must not loop if it did.
            Round::NothingNew => return st.finish(Status::Budget),
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
        match st.run(levels, eval) {
            Round::Ran => {}
            Round::Budget | Round::NothingNew => return st.finish(Status::Budget),
        }
    }
    // 3. Bisect, checking once above the bracket.
    let mut checked_above = false;
    loop {
        let (lo, hi) = st.bracket();
        if hi <= lo * (1.0 + spec.resolution) || hi - lo <= float_floor(hi, b) {
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
        match st.run(levels, eval) {
            Round::Ran => {}
            Round::Budget => return st.finish(Status::Budget),
            // The bracket is as fine as the floats allow.
            Round::NothingNew => break,
        }
    }
    st.finish(Status::Found)
}

/// The narrowest bracket worth bisecting at upper end `hi` with `batch`
/// levels per round: 4 float spacings per level (so every level of a round
/// is a float of its own between the ends), whatever the resolution asked.
pub fn float_floor(hi: f64, batch: usize) -> f64 {
    4.0 * (batch + 1) as f64 * f64::EPSILON * hi.abs().max(f64::MIN_POSITIVE)
}

/// What a round did.
enum Round {
    /// Levels were evaluated.
    Ran,
    /// Nothing was left to probe (the round was charged to the budget all the same).
    NothingNew,
    /// The budget is spent: nothing was run.
    Budget,
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
    /// budget leaves (in order: the search's first choices first). Every
    /// round costs the budget one level at least, so a search that keeps
    /// finding nothing new still ends.
    fn run(&mut self, levels: Vec<f64>, eval: &mut Eval<'_, T>) -> Round {
        let mut levels: Vec<f64> = levels
            .into_iter()
            .filter(|l| !self.probes.iter().any(|p| p.level == *l))
            .collect();
        levels.dedup();
        if let Some(left) = &mut self.budget {
            if *left == 0 {
                return Round::Budget;
            }
            levels.truncate(*left);
            *left -= levels.len().max(1);
        }
        if levels.is_empty() {
            return Round::NothingNew;
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
        Round::Ran
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
            Status::BelowFloor | Status::NominalFails | Status::Breaks => 0.0,
            Status::Found | Status::Ceiling | Status::Budget | Status::Holds => lo,
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

    /// A resolution far below the float spacing (1e-300) ends, with and
    /// without a budget: at a bracket a few float spacings wide that holds
    /// the edge, within about 40 rounds (it looped for ever when the
    /// bracket reached adjacent floats and no new level was offered).
    #[test]
    fn a_resolution_below_the_float_spacing_ends() {
        for batch in [1, 2, 5] {
            for max_levels in [None, Some(1000), Some(30)] {
                let s = Spec {
                    resolution: 1e-300,
                    batch,
                    max_levels,
                    ..spec()
                };
                let edge = 0.0123456789;
                let mut rounds = 0;
                let o = search(&s, &mut |levels: &[f64]| {
                    rounds += 1;
                    assert!(rounds < 500, "the search does not end");
                    levels.iter().map(|l| (*l <= edge, ())).collect()
                });
                assert!(o.margin <= edge && edge < o.hi, "{} {}", o.margin, o.hi);
                match max_levels {
                    Some(30) => assert_eq!(o.status, Status::Budget),
                    _ => {
                        assert_eq!(o.status, Status::Found);
                        assert!(o.hi - o.margin <= float_floor(o.hi, batch), "{o:?}");
                        assert!(o.rounds < 200, "{} rounds", o.rounds);
                    }
                }
            }
        }
    }

    /// A round that finds nothing new to probe is charged to the budget:
    /// an evaluation that always offers the same level ends.
    #[test]
    fn rounds_with_nothing_new_still_spend_the_budget() {
        let mut st = State::<()> {
            probes: Vec::new(),
            rounds: 0,
            budget: Some(3),
        };
        let mut eval = |l: &[f64]| l.iter().map(|_| (true, ())).collect::<Vec<_>>();
        assert!(matches!(st.run(vec![0.5], &mut eval), Round::Ran));
        assert!(matches!(st.run(vec![0.5], &mut eval), Round::NothingNew));
        assert!(matches!(st.run(vec![0.5], &mut eval), Round::NothingNew));
        assert!(matches!(st.run(vec![0.5], &mut eval), Round::Budget));
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
