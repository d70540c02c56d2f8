//! Batched sweeps: the variants of a group are built into one engine world
//! ([`crate::engine::batch`]) and replayed in lockstep, then each is
//! compared and recorded as if it had run alone (bit-identical metrics;
//! `--no-batch` runs every variant alone).

use crate::cancel::Cancel;
use crate::engine::batch::{self, Built, Host, Lane};
use crate::engine::PhysicsSystem;
use crate::integrate::Trajectory;
use crate::runner::{self, Runs, Timings};
use crate::sweep::{record_line, run_variant, variant_options, SweepConfig};
use crate::validate::Prepared;
use std::time::Instant;

/// Variant groups to run together, in index order: as few groups as the
/// system's batch capacity allows (at most `ANHOLONOMY_BATCH_MAX` variants
/// per group when that is set lower), but at least one per worker thread so
/// every core stays busy. Singletons when the system cannot share a world.
/// The grouping changes only the speed, never a result.
pub fn groups(prep: &Prepared, todo: &[usize]) -> Vec<Vec<usize>> {
    let cap = prep
        .physics()
        .ok()
        .and_then(|mut sys| batch::capacity(sys.as_mut()))
        .unwrap_or(1);
    let cap = std::env::var("ANHOLONOMY_BATCH_MAX")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .map_or(cap, |max| cap.min(max));
    if cap < 2 || todo.len() < 2 {
        return todo.iter().map(|&i| vec![i]).collect();
    }
    let n = todo
        .len()
        .div_ceil(cap)
        .max(rayon::current_num_threads().min(todo.len()));
    // n groups of sizes differing by at most one.
    let (base, extra) = (todo.len() / n, todo.len() % n);
    let mut out = Vec::with_capacity(n);
    let mut at = 0;
    for g in 0..n {
        let len = base + usize::from(g < extra);
        out.push(todo[at..at + len].to_vec());
        at += len;
    }
    out
}

/// One variant of a group, built into the shared world.
struct Member {
    index: usize,
    prep: Prepared,
    sys: Box<dyn PhysicsSystem>,
    ideal: Trajectory,
    /// Wall time of its own stages so far (validation, build, ideal run), s.
    own_s: f64,
    ideal_s: f64,
}

/// Run the variants `indices` together; their `variants.jsonl` lines, in
/// index order.
pub(crate) fn run_group(
    prep: &Prepared,
    cfg: &SweepConfig,
    indices: &[usize],
    cancel: &Cancel,
) -> Vec<String> {
    let opts = variant_options(cancel);
    let mut host = Host::new();
    let mut members: Vec<Member> = Vec::new();
    let mut lines: Vec<(usize, String)> = Vec::new();
    // What an unbatched run of variant `i` records.
    let alone = |i: usize| (i, run_variant(prep, cfg, &cfg.variant(i), cancel));
    for &i in indices {
        // Stopped: nothing of this group is recorded (the caller drops it),
        // so the rest is not built.
        if cancel.is_cancelled() {
            return Vec::new();
        }
        let t0 = Instant::now();
        let v = cfg.variant(i);
        let p = match prep.variant(&v) {
            Ok(p) => p,
            Err(e) => {
                let wall = t0.elapsed().as_secs_f64();
                lines.push((i, record_line(cfg, &v, &Err(e), wall)));
                continue;
            }
        };
        let t1 = Instant::now();
        // A failing ideal run (a law's fault) is recorded as the unbatched
        // run records it.
        let Ok(ideal) = runner::ideal_run(&p, &p.planned, cancel) else {
            if cancel.is_cancelled() {
                return Vec::new();
            }
            lines.push(alone(i));
            continue;
        };
        let ideal_s = t1.elapsed().as_secs_f64();
        match host.build(|| p.physics()) {
            Ok(Built::Hosted(sys)) => members.push(Member {
                index: i,
                prep: p,
                sys,
                ideal,
                own_s: t0.elapsed().as_secs_f64(),
                ideal_s,
            }),
            // Cannot share the world (or failed to build): alone, as without batching.
            Ok(Built::Alone(_)) | Err(_) => lines.push(alone(i)),
        }
    }
    if host.is_lost() {
        for m in members.drain(..) {
            lines.push(alone(m.index));
        }
    }
    if !members.is_empty() {
        let t0 = Instant::now();
        let cpu0 = runner::thread_cpu_s();
        let mut lanes: Vec<Lane> = members
            .iter_mut()
            .map(|m| Lane {
                sys: m.sys.as_mut(),
                plan: &m.prep.planned,
                opts: runner::replay_options(&m.prep, &opts),
            })
            .collect();
        let sims = host.replay(&mut lanes, cancel);
        drop(lanes);
        // The shared replay's wall and CPU time, split evenly.
        let share = 1.0 / members.len() as f64;
        let physics_s = t0.elapsed().as_secs_f64() * share;
        let physics_cpu = runner::thread_cpu_s()
            .zip(cpu0)
            .map(|(b, a)| (b - a) * share);
        for (m, sim) in members.into_iter().zip(sims) {
            let t1 = Instant::now();
            let v = cfg.variant(m.index);
            let timings = Timings {
                plan: m.prep.plan_wall_s,
                ideal: m.ideal_s,
                physics: physics_s,
                physics_cpu,
                ..Default::default()
            };
            let res = sim
                .map_err(|e| runner::replay_error(&m.prep, e))
                .and_then(|sim| {
                    let runs = Runs {
                        ideal: m.ideal,
                        early: None,
                        sim,
                        timings,
                        started: t1,
                    };
                    runner::finish(&m.prep, &m.prep.planned, &opts, false, runs)
                })
                .map(|f| f.outcome);
            let wall = m.own_s + physics_s + t1.elapsed().as_secs_f64();
            lines.push((m.index, record_line(cfg, &v, &res, wall)));
        }
    }
    lines.sort_by_key(|(i, _)| *i);
    lines.into_iter().map(|(_, l)| l).collect()
}
