//! `runner::thread_cpu_s` (summary.json's `wall_time_s.physics_cpu`, the
//! work-precision study's CPU time) must resolve far below a scheduler tick:
//! a clock brought up to date only at ticks (1 to 4 ms) read 0 s for a
//! replay of a few milliseconds.

use anholonomy::runner::thread_cpu_s;

#[cfg(unix)]
#[test]
fn thread_cpu_time_advances_in_small_steps() {
    let start = std::time::Instant::now();
    let mut last = thread_cpu_s().expect("a thread CPU clock on Unix");
    let mut steps = Vec::new();
    // 100 successive changes of the clock while this thread spins. CPU time
    // does not advance while the thread waits, so a busy machine cannot make
    // a step large; a tick-based clock steps by a whole tick.
    while steps.len() < 100 && start.elapsed().as_secs() < 10 {
        let now = thread_cpu_s().unwrap();
        assert!(now >= last, "thread CPU time went back: {last} -> {now}");
        if now > last {
            steps.push(now - last);
            last = now;
        }
    }
    assert_eq!(steps.len(), 100, "the thread CPU clock did not advance");
    let largest = steps.iter().cloned().fold(0.0, f64::max);
    assert!(
        largest < 5e-4,
        "a step of {largest} s: the clock is not per-thread CPU time at fine resolution"
    );
}
