//! Progress of long work, reported to an [`Observer`]: the library
//! computes, the binary draws (its progress bars are `src/cmd/progress.rs`),
//! as the replay reports to a [`crate::engine::ReplayObserver`].

use std::sync::Arc;

/// The kinds of long work that report progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Work {
    /// One scenario's physics replay, in thousandths of its steps.
    Run,
    /// A sweep's variants.
    Sweep,
    /// The scenarios of one call.
    Scenarios,
}

/// Units a [`Work::Run`] counts to.
pub const RUN_UNITS: u64 = 1000;

/// Receives progress from any thread. Every method does nothing by default.
pub trait Observer: Send + Sync {
    /// `work` named `name` starts; it will count to `total`.
    fn started(&self, _work: Work, _name: &str, _total: u64) {}
    /// `work` named `name` did `by` more units.
    fn advanced(&self, _work: Work, _name: &str, _by: u64) {}
    /// `work` named `name` ended (done, failed or cancelled).
    fn finished(&self, _work: Work, _name: &str) {}
}

/// Observes nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {}

/// A shared observer, for options that are cloned into every run.
#[derive(Clone)]
pub struct Progress(pub Arc<dyn Observer>);

impl Progress {
    /// An observer that sees nothing.
    pub fn silent() -> Progress {
        Progress(Arc::new(Silent))
    }
}

impl Default for Progress {
    fn default() -> Self {
        Progress::silent()
    }
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Progress")
    }
}

impl std::ops::Deref for Progress {
    type Target = dyn Observer;
    fn deref(&self) -> &Self::Target {
        &*self.0
    }
}

/// A run's progress as [`Work::Run`] units: sends only the increments.
pub struct RunMeter<'a> {
    to: &'a dyn Observer,
    name: &'a str,
    sent: u64,
}

impl<'a> RunMeter<'a> {
    /// A run named `name` starts.
    pub fn start(to: &'a dyn Observer, name: &'a str) -> Self {
        to.started(Work::Run, name, RUN_UNITS);
        RunMeter { to, name, sent: 0 }
    }

    /// The run is `fraction` done.
    pub fn set(&mut self, fraction: f64) {
        let now = (fraction.clamp(0.0, 1.0) * RUN_UNITS as f64) as u64;
        if now > self.sent {
            self.to.advanced(Work::Run, self.name, now - self.sent);
            self.sent = now;
        }
    }
}

impl Drop for RunMeter<'_> {
    fn drop(&mut self) {
        self.to.finished(Work::Run, self.name);
    }
}
