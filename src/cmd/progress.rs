//! The terminal's progress bars, drawn from the library's progress
//! reports (`anholonomy::progress::Observer`): one bar per scenario run
//! (shown once the run has taken a second), per sweep, and one counting
//! the scenarios of a call.

use anholonomy::progress::{Observer, Work};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// An open bar: the bar, when its work started, and whether it is drawn.
type Open = (ProgressBar, Instant, bool);

/// Progress bars on stderr.
#[derive(Default)]
pub struct Bars {
    open: Mutex<HashMap<(Work, String), Open>>,
}

fn bar(name: &str, total: u64, template: &str, target: ProgressDrawTarget) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(total), target);
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(name.to_string());
    bar
}

impl Observer for Bars {
    fn started(&self, work: Work, name: &str, total: u64) {
        let (template, target) = match work {
            // A run's bar appears only once it has taken a second.
            Work::Run => (
                "{prefix:>24} [{bar:40}] {percent:>3}% {elapsed}/{eta}",
                ProgressDrawTarget::hidden(),
            ),
            Work::Sweep | Work::Scenarios => (
                "{prefix:>24} [{bar:40}] {pos}/{len} {elapsed}/{eta}",
                ProgressDrawTarget::stderr(),
            ),
        };
        let b = bar(name, total, template, target);
        if let Ok(mut open) = self.open.lock() {
            let shown = work != Work::Run;
            open.insert((work, name.to_string()), (b, Instant::now(), shown));
        }
    }

    fn advanced(&self, work: Work, name: &str, by: u64) {
        let Ok(mut open) = self.open.lock() else {
            return;
        };
        if let Some((b, start, shown)) = open.get_mut(&(work, name.to_string())) {
            if !*shown && start.elapsed() > Duration::from_secs(1) {
                b.set_draw_target(ProgressDrawTarget::stderr());
                *shown = true;
            }
            b.inc(by);
        }
    }

    fn finished(&self, work: Work, name: &str) {
        if let Ok(mut open) = self.open.lock() {
            if let Some((b, _, _)) = open.remove(&(work, name.to_string())) {
                b.finish_and_clear();
            }
        }
    }
}
