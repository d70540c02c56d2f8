//! Metrics, declared once: each [`Metric`] row gives a name (or a pattern of
//! names), its unit, which way it gets worse and how it evolves along a run.
//! The baseline comparison, the margin search's early stop and the report
//! read the row; nothing is guessed from a name's tokens. The harness's own
//! rows are [`HARNESS`]; each robot declares its own in its room, and
//! `crate::robots::metric` finds the row of any name.
//!
//! A pattern's placeholders: `{run}` is `ideal` or `sim`; `{coord}` a state
//! coordinate (with `_deg` when it is an angle, reported in degrees); `{n}`
//! a robot's number; `{dim}` a `[sim.perturb]` key.

use serde::{Deserialize, Serialize};

/// Which way a metric gets worse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Errors, maxima, times, counts: a rise is a regression.
    LowerIsBetter,
    /// Success rates, fractions inside an envelope, minimum clearances: a fall is a regression.
    HigherIsBetter,
    /// Reported when it changes, never a regression.
    Informational,
}

impl Direction {
    pub(crate) fn symbol(self) -> &'static str {
        match self {
            Direction::LowerIsBetter => "lower",
            Direction::HigherIsBetter => "higher",
            Direction::Informational => "info",
        }
    }
}

/// How a metric evolves along a run (what the margin search's early stop
/// may conclude from a prefix of the run).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// A running maximum (or a count): can only grow.
    RunningMax,
    /// A running minimum: can only fall.
    RunningMin,
    /// The first time something happens (NaN: not yet).
    FirstPassage,
    /// Known only at the end.
    EndOnly,
}

/// A metric's unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Metres.
    Meter,
    /// Degrees.
    Degree,
    /// Seconds.
    Second,
    /// Metres per second.
    MeterPerSecond,
    /// The unit of the state coordinate `{coord}`: degrees for an angle
    /// (`_deg`), its SI unit otherwise (metres for a position).
    Coordinate,
    /// A fraction of samples or variants, 0 to 1.
    Fraction,
    /// A count.
    Count,
    /// A dimensionless ratio or function value.
    Ratio,
    /// Radians per second.
    RadianPerSecond,
    /// Newtons.
    Newton,
    /// Newton metres.
    NewtonMeter,
    /// Linear momentum, kg·m/s.
    LinearMomentum,
    /// Angular momentum, kg·m²/s.
    AngularMomentum,
    /// The unit of the perturbation `{dim}` (seconds, or a factor's distance from 1).
    Perturbation,
}

impl Unit {
    /// The unit as written after a value (`m`, `°`, `s`; empty for a ratio),
    /// for a metric named `name` (a coordinate's unit depends on it).
    pub fn symbol(self, name: &str) -> &'static str {
        match self {
            Unit::Meter => "m",
            Unit::Degree => "°",
            Unit::Second => "s",
            Unit::MeterPerSecond => "m/s",
            Unit::RadianPerSecond => "rad/s",
            // The coordinate's own unit needs the model: `crate::compare::MetricSpec`.
            Unit::Coordinate if name.ends_with("_deg") => "°",
            Unit::Coordinate => "",
            Unit::Fraction | Unit::Count | Unit::Ratio => "",
            Unit::Newton => "N",
            Unit::NewtonMeter => "N·m",
            Unit::LinearMomentum => "kg·m/s",
            Unit::AngularMomentum => "kg·m²/s",
            Unit::Perturbation => "",
        }
    }
}

/// One metric's row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metric {
    /// The name, or a pattern of names (module docs).
    pub name: &'static str,
    /// Its unit.
    pub unit: Unit,
    /// Which way it gets worse.
    pub direction: Direction,
    /// How it evolves along a run.
    pub family: Family,
    /// What it measures, for the reference.
    pub doc: &'static str,
    /// Whether it compares the ideal and the physics run sample by sample
    /// (a tracking error): meaningless when each run closes its own loop.
    pub compares_runs: bool,
}

/// A row, briefly: `m(name, unit, direction, family, doc)`.
pub const fn m(
    name: &'static str,
    unit: Unit,
    direction: Direction,
    family: Family,
    doc: &'static str,
) -> Metric {
    Metric {
        name,
        unit,
        direction,
        family,
        doc,
        compares_runs: false,
    }
}

/// A tracking row: a difference between the two runs, lower is better,
/// `tracking(name, unit, family, doc)`.
pub const fn tracking(name: &'static str, unit: Unit, family: Family, doc: &'static str) -> Metric {
    Metric {
        name,
        unit,
        direction: Direction::LowerIsBetter,
        family,
        doc,
        compares_runs: true,
    }
}

use Direction::{HigherIsBetter as Higher, Informational as Info, LowerIsBetter as Lower};
use Family::{EndOnly, FirstPassage, RunningMax, RunningMin};

/// The harness's own metrics: every model's goal and tracking errors,
/// margins, sweeps, and what the wheeled robots share.
pub const HARNESS: &[Metric] = &[
    m(
        "{run}_goal_position",
        Unit::Meter,
        Lower,
        EndOnly,
        "Planar distance of the run's end from the goal (the worst robot's).",
    ),
    m(
        "{run}_goal_position_{n}",
        Unit::Meter,
        Lower,
        EndOnly,
        "Planar distance of robot n's end from its goal.",
    ),
    m(
        "{run}_goal_{coord}",
        Unit::Coordinate,
        Lower,
        EndOnly,
        "Error of one coordinate at the run's end (angles wrapped, in degrees).",
    ),
    tracking(
        "tracking_position_max",
        Unit::Meter,
        RunningMax,
        "Largest planar distance between the two runs at one time (open-loop plans).",
    ),
    tracking(
        "tracking_position_rms",
        Unit::Meter,
        EndOnly,
        "RMS planar distance between the two runs over time.",
    ),
    tracking(
        "tracking_position_final",
        Unit::Meter,
        EndOnly,
        "Planar distance between the two runs' ends.",
    ),
    tracking(
        "tracking_position_{n}_max",
        Unit::Meter,
        RunningMax,
        "Largest planar distance between the runs of robot n.",
    ),
    tracking(
        "tracking_position_{n}_rms",
        Unit::Meter,
        EndOnly,
        "RMS planar distance between the runs of robot n.",
    ),
    tracking(
        "tracking_position_{n}_final",
        Unit::Meter,
        EndOnly,
        "Planar distance between the runs' ends, robot n.",
    ),
    tracking(
        "tracking_{coord}_max",
        Unit::Coordinate,
        RunningMax,
        "Largest difference of one coordinate between the two runs.",
    ),
    tracking(
        "tracking_{coord}_rms",
        Unit::Coordinate,
        EndOnly,
        "RMS difference of one coordinate between the two runs.",
    ),
    tracking(
        "tracking_{coord}_final",
        Unit::Coordinate,
        EndOnly,
        "Difference of one coordinate at the runs' ends.",
    ),
    m(
        "{run}_time_to_goal",
        Unit::Second,
        Lower,
        FirstPassage,
        "First time the run is within the goal tolerance (NaN: never).",
    ),
    m(
        "slip_lateral_max",
        Unit::MeterPerSecond,
        Lower,
        RunningMax,
        "Largest sideways slip speed of any wheel's contact.",
    ),
    m(
        "slip_lateral_{n}_max",
        Unit::MeterPerSecond,
        Lower,
        RunningMax,
        "Largest sideways slip speed of robot n's wheels.",
    ),
    m(
        "slip_longitudinal_max",
        Unit::MeterPerSecond,
        Lower,
        RunningMax,
        "Largest slip speed along any wheel's rolling direction.",
    ),
    m(
        "{run}_min_clearance",
        Unit::Meter,
        Higher,
        RunningMin,
        "Smallest distance between the robot and an obstacle along the run.",
    ),
    m(
        "sim_obstacle_contacts",
        Unit::Count,
        Lower,
        RunningMax,
        "Physics steps with the robot touching an obstacle.",
    ),
    m(
        "margin_{dim}",
        Unit::Perturbation,
        Higher,
        EndOnly,
        "A gated margin: the gate when the scenario holds there (NaN when it breaks).",
    ),
    m(
        "sweep_success_rate",
        Unit::Fraction,
        Higher,
        EndOnly,
        "Fraction of a sweep's variants that pass every gate.",
    ),
    m(
        "sweep_variants",
        Unit::Count,
        Info,
        EndOnly,
        "Variants the sweep ran.",
    ),
    m(
        "sweep_final_error_median",
        Unit::Meter,
        Lower,
        EndOnly,
        "Median over a sweep's variants of the final planar error.",
    ),
    m(
        "sweep_final_error_p95",
        Unit::Meter,
        Lower,
        EndOnly,
        "95th percentile of a sweep's final planar errors.",
    ),
    m(
        "sweep_final_error_max",
        Unit::Meter,
        Lower,
        EndOnly,
        "Largest final planar error of a sweep's variants.",
    ),
    m(
        "sweep_time_to_goal_median",
        Unit::Second,
        Lower,
        EndOnly,
        "Median time to goal of a sweep's variants.",
    ),
    m(
        "sweep_time_to_goal_p95",
        Unit::Second,
        Lower,
        EndOnly,
        "95th percentile of a sweep's times to goal.",
    ),
    m(
        "sweep_time_to_goal_max",
        Unit::Second,
        Lower,
        EndOnly,
        "Longest time to goal of a sweep's variants.",
    ),
];

/// The metrics of a recorded run (`[compare] reference`), computed by
/// `crate::recording::metrics`; those in degrees need the model's heading.
/// Each is judged at the end: a prefix of the physics run is not compared
/// with the whole recording.
pub const REAL: &[Metric] = &[
    m(
        "real_goal_position",
        Unit::Meter,
        Lower,
        EndOnly,
        "Distance from the recording's last sample to the goal position.",
    ),
    m(
        "real_goal_heading_deg",
        Unit::Degree,
        Lower,
        EndOnly,
        "Heading error of the recording's last sample from the goal.",
    ),
    m(
        "real_sim_position_rms",
        Unit::Meter,
        Lower,
        EndOnly,
        "RMS distance between the recording and the physics run.",
    ),
    m(
        "real_sim_position_max",
        Unit::Meter,
        Lower,
        EndOnly,
        "Largest distance between the recording and the physics run.",
    ),
    m(
        "real_sim_heading_deg_rms",
        Unit::Degree,
        Lower,
        EndOnly,
        "RMS heading difference between the recording and the physics run.",
    ),
    m(
        "real_sim_heading_deg_max",
        Unit::Degree,
        Lower,
        EndOnly,
        "Largest heading difference between the recording and the physics run.",
    ),
    m(
        "real_ideal_position_rms",
        Unit::Meter,
        Lower,
        EndOnly,
        "RMS distance between the recording and the ideal run.",
    ),
    m(
        "real_ideal_position_max",
        Unit::Meter,
        Lower,
        EndOnly,
        "Largest distance between the recording and the ideal run.",
    ),
    m(
        "real_ideal_heading_deg_rms",
        Unit::Degree,
        Lower,
        EndOnly,
        "RMS heading difference between the recording and the ideal run.",
    ),
    m(
        "real_ideal_heading_deg_max",
        Unit::Degree,
        Lower,
        EndOnly,
        "Largest heading difference between the recording and the ideal run.",
    ),
];

/// Whether `name` is an instance of `pattern` (module docs' placeholders).
pub fn matches(pattern: &str, name: &str) -> bool {
    captures(pattern, name).is_some()
}

/// What each placeholder of `pattern` stands for in `name` (`None`: not an
/// instance), e.g. `[("run", "sim"), ("coord", "theta_deg")]`.
pub(crate) fn captures<'p, 'n>(pattern: &'p str, name: &'n str) -> Option<Vec<(&'p str, &'n str)>> {
    let Some(open) = pattern.find('{') else {
        return (pattern == name).then(Vec::new);
    };
    let rest = name.strip_prefix(&pattern[..open])?;
    let close = open + pattern[open..].find('}')?;
    let (hole, after) = (&pattern[open + 1..close], &pattern[close + 1..]);
    let fits = |s: &str| match hole {
        "run" => s == "ideal" || s == "sim",
        "n" => !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()),
        _ => !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_'),
    };
    (1..=rest.len())
        .filter(|&k| rest.is_char_boundary(k) && fits(&rest[..k]))
        .find_map(|k| {
            let mut more = captures(after, &rest[k..])?;
            more.insert(0, (hole, &rest[..k]));
            Some(more)
        })
}

/// The first row of `rows` whose name or pattern `name` is an instance of
/// (literal rows come before the patterns that would also match).
pub(crate) fn find_row<'a>(
    rows: impl IntoIterator<Item = &'a Metric>,
    name: &str,
) -> Option<&'a Metric> {
    let rows: Vec<&Metric> = rows.into_iter().collect();
    rows.iter()
        .find(|r| !r.name.contains('{') && r.name == name)
        .or_else(|| rows.iter().find(|r| matches(r.name, name)))
        .copied()
}

impl Metric {
    /// Which run metric `name` (of this row) reads, when the row's pattern
    /// names one (`{run}`: `ideal` or `sim`).
    pub fn run_of<'n>(&self, name: &'n str) -> Option<&'n str> {
        captures(self.name, name)?
            .into_iter()
            .find_map(|(hole, v)| (hole == "run").then_some(v))
    }

    /// How metric `name` (of this row) evolves when judged as an upper
    /// bound (`minimum` false) or a lower bound (`[minimums]`): the ideal
    /// run never changes with a perturbation, and a bound is certain early
    /// only when the running value moves towards breaking it.
    pub fn family_of(&self, name: &str, minimum: bool) -> Family {
        if self.run_of(name) == Some("ideal") {
            return EndOnly;
        }
        match (self.family, minimum) {
            (RunningMin, true) => RunningMin,
            (RunningMax | FirstPassage, false) => self.family,
            _ => EndOnly,
        }
    }
}

/// The value of metric `name` in a run's `(name, value)` list.
pub fn find(metrics: &[(String, f64)], name: &str) -> Option<f64> {
    metrics.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_match_their_instances_only() {
        assert!(matches("{run}_goal_{coord}", "sim_goal_theta_deg"));
        assert!(matches("{run}_goal_{coord}", "ideal_goal_x1"));
        assert!(!matches("{run}_goal_{coord}", "real_goal_x"));
        assert!(matches(
            "tracking_position_{n}_max",
            "tracking_position_2_max"
        ));
        assert!(!matches(
            "tracking_position_{n}_max",
            "tracking_position_x_max"
        ));
        assert!(matches("margin_{dim}", "margin_command_latency"));
        assert!(!matches("slip_lateral_max", "slip_lateral_maximum"));
        // A literal row wins over a pattern that also matches.
        let r = find_row(HARNESS, "sim_goal_position").unwrap();
        assert_eq!(r.name, "{run}_goal_position");
        let r = find_row(HARNESS, "sim_goal_position_2").unwrap();
        assert_eq!(r.name, "{run}_goal_position_{n}");
        let r = find_row(HARNESS, "tracking_position_max").unwrap();
        assert_eq!(r.family, RunningMax);
        assert!(find_row(HARNESS, "no_such_metric").is_none());
        assert_eq!(
            captures("tracking_{coord}_max", "tracking_theta_deg_max"),
            Some(vec![("coord", "theta_deg")])
        );
    }

    #[test]
    fn the_ideal_run_is_judged_at_the_end() {
        let r = find_row(HARNESS, "ideal_time_to_goal").unwrap();
        assert_eq!(r.family_of("ideal_time_to_goal", false), EndOnly);
        assert_eq!(r.family_of("sim_time_to_goal", false), FirstPassage);
        let c = find_row(HARNESS, "sim_min_clearance").unwrap();
        assert_eq!(c.family_of("sim_min_clearance", true), RunningMin);
        assert_eq!(c.family_of("sim_min_clearance", false), EndOnly);
    }
}
