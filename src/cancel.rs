//! Stopping a run from outside: a caller that runs scenarios on another
//! thread (the Python package, on Ctrl-C or when a feedback law raised)
//! cancels the token, and the ideal run, the physics replay and a sweep's
//! variants stop at their next step with an error. The CLI never cancels:
//! its token is the default one, which cannot be set.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A cancellation flag shared between a run and its caller. Clones share
/// the flag; [`Cancel::default`] has none and is never cancelled.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Option<Arc<AtomicBool>>);

/// The error text of a cancelled run.
pub const CANCELLED: &str = "run cancelled";

impl Cancel {
    /// A token that [`Cancel::cancel`] can set.
    pub fn new() -> Cancel {
        Cancel(Some(Arc::new(AtomicBool::new(false))))
    }

    /// Ask every run holding this token (or a clone) to stop.
    pub fn cancel(&self) {
        if let Some(f) = &self.0 {
            f.store(true, Ordering::Relaxed);
        }
    }

    /// Whether the run should stop.
    pub fn is_cancelled(&self) -> bool {
        self.0.as_ref().is_some_and(|f| f.load(Ordering::Relaxed))
    }
}

#[cfg(test)]
mod tests {
    use super::Cancel;

    #[test]
    fn clones_share_the_flag_and_the_default_never_cancels() {
        let c = Cancel::new();
        let d = c.clone();
        assert!(!d.is_cancelled());
        c.cancel();
        assert!(d.is_cancelled());
        let none = Cancel::default();
        none.cancel();
        assert!(!none.is_cancelled());
    }
}
