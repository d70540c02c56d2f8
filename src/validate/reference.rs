//! `[compare] reference`: the recording read, lined up with the plan and
//! checked before anything runs (a missing topic, a recording that does not
//! overlap the plan: bad input).

use crate::error::Error;
use crate::plan::Plan;
use crate::record::Track;
use crate::recording::align::{align, Alignment, PoseIndex};
use crate::recording::{clock, metrics, Source};
use crate::robots::System;
use crate::scenario::{PlannerConfig, Scenario};
use std::path::Path;
use std::sync::Arc;

/// The `real_*` metrics a scenario's runs report (none without `[compare]`).
pub fn metric_names(sc: &Scenario, system: &dyn System) -> Vec<String> {
    match (&sc.compare, PoseIndex::of(system.model())) {
        (Some(_), Some(idx)) => metrics::names(idx.heading.is_some()),
        _ => Vec::new(),
    }
}

/// The recording of `[compare]`, in plan time and the scenario's frame.
pub fn load(
    sc: &Scenario,
    system: &dyn System,
    planned: &Plan,
) -> Result<Option<Arc<Track>>, Error> {
    let Some(c) = &sc.compare else {
        return Ok(None);
    };
    let key = "compare.reference";
    let Some(idx) = PoseIndex::of(system.model()) else {
        return Err(sc.error_at(
            key,
            format!(
                "model `{}` has no planar position (x, y) to compare a recording with",
                sc.model.kind()
            ),
        ));
    };
    let base = sc.path.parent().unwrap_or(Path::new("."));
    let source = Source::parse(&c.reference, base).map_err(|e| sc.error_at(key, e))?;
    let plan = match &sc.planner {
        PlannerConfig::File(p) => Some(p),
        _ => None,
    };
    let at_key = |e: crate::recording::RecordingError| match e {
        crate::recording::RecordingError::File(_) => clock::input_error(e, key),
        other => sc.error_at(key, other),
    };
    let clocked = clock::read(&source, plan, system.model().input_names()).map_err(at_key)?;
    let start = idx.pose(&sc.start);
    let end = crate::integrate::step_count(planned.duration + sc.sim.settle, sc.sim.dt) as f64
        * sc.sim.dt;
    let a = Alignment {
        shared: clocked.shared,
        time_offset: c.time_offset,
        frame: c.frame,
    };
    let track = align(&clocked.recording, &a, start, end).map_err(at_key)?;
    Ok(Some(Arc::new(track)))
}
