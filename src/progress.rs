//! A progress bar that only appears once a run has taken more than a second.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::cell::Cell;
use std::time::{Duration, Instant};

/// Progress bar shown on stderr after a delay (never when disabled or not a terminal).
pub struct Delayed {
    bar: ProgressBar,
    start: Instant,
    shown: Cell<bool>,
    enabled: bool,
}

const RESOLUTION: u64 = 1000;

impl Delayed {
    /// A hidden bar for the scenario `name`.
    pub fn new(name: &str, enabled: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(RESOLUTION), ProgressDrawTarget::hidden());
        if let Ok(style) =
            ProgressStyle::with_template("{prefix:>24} [{bar:40}] {percent:>3}% {elapsed}/{eta}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(name.to_string());
        Self {
            bar,
            start: Instant::now(),
            shown: Cell::new(false),
            enabled,
        }
    }

    /// Report progress as a fraction in [0, 1].
    pub fn set(&self, fraction: f64) {
        if self.enabled && !self.shown.get() && self.start.elapsed() > Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown.set(true);
        }
        self.bar
            .set_position((fraction.clamp(0.0, 1.0) * RESOLUTION as f64) as u64);
    }

    /// Remove the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
