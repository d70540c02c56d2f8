//! Which clock a recording is on: a recording in the bag a file plan reads
//! shares the bag's clock with the commands (log or header time, as the
//! plan reads them), so plan time 0 is the first command; any other
//! recording keeps its own clock (a CSV's `t`, a topic's time since its
//! first message), lined up by a time offset.

use crate::error::Error;
use crate::recording::{bag, Recording, RecordingError, Source};
use crate::sources::file::{BagTime, FilePlanParams};
use std::path::PathBuf;

/// A recording and how it lines up with the plan in time.
#[derive(Debug, Clone)]
pub struct Clocked {
    /// The recording.
    pub recording: Recording,
    /// The shift that puts its t on the plan's clock (0: its own clock).
    pub shared: f64,
    /// How, in a sentence.
    pub how: String,
}

fn same_files(a: &[PathBuf], b: &[PathBuf]) -> bool {
    let canon = |v: &[PathBuf]| -> Vec<PathBuf> {
        v.iter()
            .map(|p| p.canonicalize().unwrap_or_else(|_| p.clone()))
            .collect()
    };
    !a.is_empty() && canon(a) == canon(b)
}

/// Read `source` for a plan read from `plan` (a file plan's parameters,
/// when the scenario has one) by a model with `inputs`.
pub fn read(
    source: &Source,
    plan: Option<&FilePlanParams>,
    inputs: &[&str],
) -> Result<Clocked, RecordingError> {
    if let (Some(p), Source::Bag { path, .. }) = (plan, source) {
        let plan_path = p.bag_dir().unwrap_or_else(|| p.file());
        let (_, rec_files) = bag::storage_files(path)?;
        let plan_files = bag::storage_files(&plan_path).ok().map(|(_, f)| f);
        if plan_files.is_some_and(|f| same_files(&rec_files, &f)) {
            let time = p.time.unwrap_or_default();
            let (_, plan_ns) = bag::commands_start(&plan_path, inputs, &p.bag_keys())?;
            let recording = Recording::read(source, time)?;
            let rec_ns = recording.bag_clock.as_ref().map_or(plan_ns, |c| c.1);
            let shared = crate::recording::align::shared_clock(rec_ns, plan_ns);
            return Ok(Clocked {
                recording,
                shared,
                how: format!(
                    "on the bag's clock ({} time): plan time 0 is the first command, {} s after the recording's first sample",
                    time.name(),
                    crate::numfmt::readable(-shared)
                ),
            });
        }
    }
    let recording = Recording::read(source, BagTime::Log)?;
    let how = match source {
        Source::Csv(_) => "the CSV's t is the recording's clock".to_string(),
        Source::Bag { .. } => {
            "the recording's clock starts at its first message (log time; the plan is not read from this bag)"
                .to_string()
        }
    };
    Ok(Clocked {
        recording,
        shared: 0.0,
        how,
    })
}

/// A recording's problem as bad input: a file's at its file and line,
/// any other about `what` (the option or key that names the recording).
pub fn input_error(e: RecordingError, what: &str) -> Error {
    match e {
        RecordingError::File(f) => Error::Input {
            path: f.path.clone(),
            line: f.line,
            key: None,
            message: f.message.clone(),
        },
        RecordingError::Spec(m) | RecordingError::Alignment(m) => Error::input(what, m),
    }
}
