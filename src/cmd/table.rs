//! The results table `run`, `check` and `baseline` print.

use anholonomy::runner::RunOutcome;

/// A metric for the table: 4 significant digits at any magnitude (a goal
/// error of 1e300 from a runaway plan is `1e300`, not 300 digits).
fn fmt_metric(o: &RunOutcome, name: &str) -> String {
    o.metric(name)
        .map(anholonomy::numfmt::readable)
        .unwrap_or_else(|| "-".into())
}

/// The coordinate the table reports: the planar position when the model has
/// one, else its first coordinate (the first `ideal_goal_*` metric).
fn primary(o: &RunOutcome) -> Option<&str> {
    o.metrics
        .iter()
        .find_map(|(n, _)| n.strip_prefix("ideal_goal_"))
}

/// A tracking column: the number, or `n/a` when tracking means nothing for the run.
fn fmt_tracking(o: &RunOutcome, name: &str) -> String {
    if o.tracking_meaningful {
        fmt_metric(o, name)
    } else {
        "n/a".into()
    }
}

/// The result column: the verdict, and the `[margins]` gates that held.
fn result(o: &RunOutcome) -> String {
    let mut v = o.verdict.describe(&o.failures, o.expect_reason.as_deref());
    if !o.notes.is_empty() {
        v = format!("{v} ({})", o.notes.join("; "));
    }
    match &o.plan_note {
        Some(n) => format!("{v} [{n}]"),
        None => v,
    }
}

pub fn print_table(rows: &[RunOutcome]) {
    say!(
        "{:<30} {:<17} {:>7} {:>9} {:>7} {:>14} {:>10} {:>10} {:>10} {:>10}  result",
        "scenario",
        "planner",
        "steps",
        "steps/s",
        "wall s",
        "coordinate",
        "ideal goal",
        "sim goal",
        "track rms",
        "track max"
    );
    for o in rows {
        let c = primary(o).unwrap_or("-");
        say!(
            "{:<30} {:<17} {:>7} {:>9.0} {:>7.3} {:>14} {:>10} {:>10} {:>10} {:>10}  {}",
            o.name,
            o.planner,
            o.steps,
            o.steps as f64 / o.timings.physics.max(1e-9),
            o.timings.total,
            c,
            fmt_metric(o, &format!("ideal_goal_{c}")),
            fmt_metric(o, &format!("sim_goal_{c}")),
            fmt_tracking(o, &format!("tracking_{c}_rms")),
            fmt_tracking(o, &format!("tracking_{c}_max")),
            result(o)
        );
    }
    if rows.iter().any(|o| !o.tracking_meaningful) {
        say!("n/a: tracking error means nothing for a feedback policy (each run closes the loop on its own state and reaches the goal at its own time); see sim goal.");
    }
}
