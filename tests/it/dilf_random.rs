//! Seed 004 on goals nobody picked: seeded random tasks for the pair
//! carrying the beam and for one robot behind a wall, run with the
//! planner's defaults.
//!
//! * **Pairs** (`dilf_pair_open`'s model, gains and gates): the start is
//!   Table I's formation turned about its centroid by a heading uniform over
//!   the circle; the goal is that formation turned by a further φ uniform
//!   in ±90° about its centroid and moved by a displacement of length
//!   uniform in [0, 4] m in a direction uniform over the circle (sideways
//!   included). Every goal is a rigid motion of the start, so a solid
//!   object fits both.
//! * **One robot** (`dilf_single_door`'s wall, door, table and gains): the
//!   start uniform in x ∈ [−4, −2] m, y ∈ [−3, 3] m, heading over the circle;
//!   the goal behind the wall, x ∈ [2, 4] m, y ∈ [−1.5, 1.5] m, heading
//!   uniform over the circle (drawn again while it puts the robot in the
//!   table).
//! * **One robot, goals turned ±90°** (`wall90`): the same starts, goals
//!   behind the wall at x ∈ [1, 4] m turned ±90° (along the wall) by up to
//!   ±15°, where the paper's law stalls (`seed-004-stall.md`).
//!
//! The ideal run's recorded inputs are integrated again in closed form (the
//! unicycle's arcs): that end must match the RK4 run within 1e-6 and lie
//! within the task's tolerance for a case to count as converged.
//!
//! Each case either converges (ideal run) and passes every gate of its
//! scenario but the shipped task's time gates (physics), or ends `stalled`,
//! and the table gives the reason (the law's labels over the stall window,
//! and the plan's note when no sequence converged). Every case runs the
//! planner's defaults, no per-case setting: the shipped files' settings
//! less what they pin to reproduce the paper (`[planner.sequence]`,
//! `speed`, `align_joint_gain`). The paper's law alone is tabled by the
//! ignored `*_paper_law` test (the note's "before" table). Another seed
//! (a held-out set): `DILF_RANDOM_SEED=N`.
//!
//! ```text
//! cargo test --release --test it dilf_random:: -- --nocapture                 # ideal runs
//! cargo test --release --test it -- --ignored pass_in_physics --nocapture    # physics (.ci/run)
//! cargo test --release --test it -- --ignored 90_degrees_behind_a_wall_in_physics --nocapture
//! cargo test --release --test it -- --ignored random_goals_paper_law --nocapture  # the paper's law
//! ```
//!
//! Each table is also written to `$CARGO_TARGET_TMPDIR/dilf_random/`
//! (`target/tmp/dilf_random/`).

use crate::common::*;
use anholonomy::compare::wrap_angle;
use anholonomy::integrate::simulate;
use anholonomy::robots::mobile_manipulator::dilf::{sequence::rigid, STOPS};
use anholonomy::robots::mobile_manipulator::kinematics::{DOF, INPUTS};
use anholonomy::scenario::{PlannerConfig, Scenario};
use anholonomy::validate::Prepared;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The seed of the pair and single-robot sets (fixed: the goals are the
/// test's data).
const SEED: u64 = 40;
/// The seed of the goals turned ±90° behind the wall (drawn once, by the
/// rule of [`single_cases`], before any was run).
const WALL90_SEED: u64 = 51;
/// Cases per set.
const CASES: usize = 20;
/// Physics floors: the issue's goals (16 pairs and 19 single-robot goals
/// of 20; 20 and 20 measured).
const PAIR_PHYSICS_FLOOR: usize = 16;
const SINGLE_PHYSICS_FLOOR: usize = 19;

/// One random task.
struct Case {
    /// Short description (the draw).
    what: String,
    start: Vec<f64>,
    goal: Vec<f64>,
}

/// Which scenario a set is drawn for.
#[derive(Clone, Copy, PartialEq)]
enum Set {
    Pair,
    Single,
    /// One robot behind the wall, goals turned ±90° (along the wall).
    Wall90,
}

impl Set {
    fn base(self) -> &'static str {
        match self {
            Set::Pair => "dilf_pair_open.toml",
            Set::Single | Set::Wall90 => "dilf_single_door.toml",
        }
    }
    fn name(self) -> &'static str {
        match self {
            Set::Pair => "pair",
            Set::Single => "single",
            Set::Wall90 => "wall90",
        }
    }
    /// The set's seed: fixed (the goals are the test's data), or
    /// `DILF_RANDOM_SEED` (a held-out set).
    fn seed(self) -> u64 {
        let fixed = match self {
            Set::Pair | Set::Single => SEED,
            Set::Wall90 => WALL90_SEED,
        };
        std::env::var("DILF_RANDOM_SEED").map_or(fixed, |s| s.parse().unwrap())
    }
    fn cases(self) -> Vec<Case> {
        let seed = self.seed();
        match self {
            Set::Pair => pair_cases(seed),
            Set::Single => single_cases(seed, false),
            Set::Wall90 => single_cases(seed, true),
        }
    }
}

/// Which law a case runs.
#[derive(Clone, Copy, PartialEq)]
enum Law {
    /// The planner's defaults (the shipped files' own settings, minus what
    /// they pin to reproduce the paper).
    Defaults,
    /// The paper's law: Eq. 18a's sign speed, Eq. 18c's joint rates
    /// throughout, no intermediate goals.
    Paper,
}

/// The scenario text of `case` on `set`'s shipped file: its start and goal
/// and `law`, the file's gates but for the time gates (the shipped task's
/// time says nothing of a random goal's: they are dropped; a run ends at
/// its plan's budget, the horizon per phase).
fn scenario_text(set: Set, case: &Case, law: Law) -> String {
    let path = scenario(set.base());
    let mut v: toml::Value = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let deg = |q: &[f64]| -> toml::Value {
        toml::Value::Array(
            q.chunks(DOF)
                .flat_map(|r| {
                    let mut out = vec![r[0], r[1]];
                    out.extend(r[2..].iter().map(|a| a.to_degrees()));
                    out
                })
                .map(toml::Value::Float)
                .collect(),
        )
    };
    let t = v.as_table_mut().unwrap();
    t.insert("name".into(), format!("dilf_random_{}", set.name()).into());
    t.insert("start".into(), deg(&case.start));
    t.insert("goal".into(), deg(&case.goal));
    let planner = t["planner"].as_table_mut().unwrap();
    // What a shipped file pins to reproduce the paper goes: the defaults
    // remain.
    for key in ["speed", "align_joint_gain", "sequence"] {
        planner.remove(key);
    }
    if law == Law::Paper {
        planner.insert("speed".into(), "sign".into());
        planner.insert("align_joint_gain".into(), 0.0.into());
        let mut s = toml::map::Map::new();
        s.insert("mode".into(), "off".into());
        planner.insert("sequence".into(), toml::Value::Table(s));
    }
    let th = t["thresholds"].as_table_mut().unwrap();
    for k in ["ideal_time_to_goal", "sim_time_to_goal"] {
        th.remove(k);
    }
    toml::to_string(&v).unwrap()
}

fn prepare(set: Set, case: &Case, law: Law) -> Result<Prepared, String> {
    let text = scenario_text(set, case, law);
    // A path beside the shipped files: the URDF path resolves as theirs.
    let path = scenario(&format!("dilf_random_{}.toml", set.name()));
    let sc = Scenario::parse(&path, &text).map_err(|e| e.to_string())?;
    Prepared::new(sc).map_err(|e| e.to_string())
}

/// Table I's start formation (rad) with its centroid at the origin.
fn table_i_formation() -> Vec<f64> {
    let mut q = anholonomy::robots::mobile_manipulator::dilf::object::table_i_start();
    for r in 0..2 {
        q[DOF * r] += 9.5;
        q[DOF * r + 1] -= 3.0;
    }
    q
}

fn pair_cases(seed: u64) -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let base = table_i_formation();
    (0..CASES)
        .map(|_| {
            let heading = rng.random_range(-180.0f64..180.0);
            let turn = rng.random_range(-90.0f64..90.0);
            let length = rng.random_range(0.0f64..4.0);
            let dir = rng.random_range(-180.0f64..180.0);
            let start = rigid(&base, [0.0, 0.0], heading.to_radians(), [0.0, 0.0]);
            let shift = [
                length * dir.to_radians().cos(),
                length * dir.to_radians().sin(),
            ];
            let goal = rigid(&start, [0.0, 0.0], turn.to_radians(), shift);
            // The displacement's direction against the start formation's
            // heading (the platforms' −90° in Table I, turned by `heading`):
            // 0° ahead, ±90° sideways.
            let rel = wrap_angle((dir - (heading - 90.0)).to_radians()).to_degrees();
            Case {
                what: format!(
                    "start {heading:+.0}°, turn {turn:+.0}°, {length:.2} m at {rel:+.0}°"
                ),
                start,
                goal,
            }
        })
        .collect()
}

/// One robot: starts in front of the wall, goals behind it. `wall90`:
/// goals anywhere behind the wall (x ∈ [1, 4] m), turned ±90° (along the
/// wall; the sign alternating from case to case) by up to ±15°, where the
/// paper's law meets V's spurious maximum (`seed-004-stall.md`).
fn single_cases(seed: u64, wall90: bool) -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let base = prepared(&scenario("dilf_single_door.toml"));
    let (s0, g0) = base.start_goal();
    let mut out = Vec::new();
    while out.len() < CASES {
        let mut start = s0.as_slice().to_vec();
        start[0] = rng.random_range(-4.0..-2.0);
        start[1] = rng.random_range(-3.0..3.0);
        start[2] = rng.random_range(-180.0f64..180.0).to_radians();
        // Draw the goal again while the planner refuses it (in the table).
        loop {
            let mut goal = g0.as_slice().to_vec();
            if wall90 {
                let side = if out.len() % 2 == 0 { 90.0 } else { -90.0 };
                goal[0] = rng.random_range(1.0..4.0);
                goal[1] = rng.random_range(-1.5..1.5);
                goal[2] = (side + rng.random_range(-15.0f64..15.0)).to_radians();
            } else {
                goal[0] = rng.random_range(2.0..4.0);
                goal[1] = rng.random_range(-1.5..1.5);
                goal[2] = rng.random_range(-180.0f64..180.0).to_radians();
            }
            let case = Case {
                what: format!(
                    "({:+.2}, {:+.2}, {:+.0}°) to ({:.2}, {:+.2}, {:+.0}°)",
                    start[0],
                    start[1],
                    start[2].to_degrees(),
                    goal[0],
                    goal[1],
                    goal[2].to_degrees()
                ),
                start: start.clone(),
                goal,
            };
            if scenario_free(&case) {
                out.push(case);
                break;
            }
        }
    }
    out
}

/// Whether the single-robot scenario accepts the case's start and goal.
fn scenario_free(case: &Case) -> bool {
    let text = scenario_text(Set::Single, case, Law::Paper);
    let path = scenario("dilf_random_single.toml");
    let sc = Scenario::parse(&path, &text).unwrap();
    match Prepared::new(sc) {
        Ok(_) => true,
        Err(e) => {
            let e = e.to_string();
            assert!(e.contains("inside obstacle"), "unexpected refusal: {e}");
            false
        }
    }
}

/// How one run ended.
struct Outcome {
    converged: bool,
    /// `converged`, `stalled`, a stop (`collision`, ...), or `horizon`.
    ended: String,
    /// Worse robot's distance from its goal (m) and heading error (deg).
    position: f64,
    heading: f64,
    /// Time to goal, s (NaN if never).
    time: f64,
    /// Why it did not converge: the labels of the stall window, or the
    /// broken gates.
    reason: String,
    /// The plan's sequence choice ("direct", or the approach heading).
    plan: String,
}

fn worse_error(q: &[f64], goal: &[f64]) -> (f64, f64) {
    (0..q.len() / DOF)
        .map(|r| {
            let i = DOF * r;
            (
                (q[i] - goal[i]).hypot(q[i + 1] - goal[i + 1]),
                wrap_angle(q[i + 2] - goal[i + 2]).abs().to_degrees(),
            )
        })
        .fold((0.0f64, 0.0f64), |a, b| (a.0.max(b.0), a.1.max(b.1)))
}

fn plan_choice(prep: &Prepared) -> String {
    let d = &prep.planned.details["sequence"];
    match d["chosen"].as_str() {
        Some("sequence") => format!(
            "ψ {:+.0}° ({} tried)",
            d["approach_heading_deg"].as_f64().unwrap_or(f64::NAN),
            d["tried"]
        ),
        Some(c) => format!("{c} ({} tried)", d["tried"]),
        None => "paper".into(),
    }
}

/// The independent integrator: the run's recorded (held) inputs integrated
/// in closed form (arcs), and how far its end lies from the harness's RK4
/// end (largest coordinate difference).
fn exact_gap(start: &[f64], tr: &anholonomy::integrate::Trajectory) -> (Vec<f64>, f64) {
    let mut q = start.to_vec();
    for k in 0..tr.t.len() - 1 {
        let h = tr.t[k + 1] - tr.t[k];
        for (r, qr) in q.chunks_mut(DOF).enumerate() {
            legs::mobile_manipulator_step(qr, &tr.u[k].as_slice()[INPUTS * r..], h);
        }
    }
    let last = tr.last();
    let gap = q
        .iter()
        .zip(last.as_slice())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    (q, gap)
}

/// The ideal run of a prepared case. A converged run counts only if the
/// independent integrator lands within the task's tolerance too.
fn ideal(prep: &Prepared) -> Outcome {
    let (start, goal) = prep.start_goal();
    let plan = &prep.planned;
    let tr = simulate(prep.model(), plan, &start, prep.scenario.sim.dt);
    let (exact_end, gap) = exact_gap(start.as_slice(), &tr);
    assert!(gap < 1e-6, "exact re-integration ends {gap} from RK4");
    let ended = plan.label_name(*tr.label.last().unwrap()).to_string();
    let PlannerConfig::Dilf(p) = &prep.scenario.planner else {
        panic!("not dilf")
    };
    let converged = ended == "converged" && p.tolerance.reached(&exact_end, goal.as_slice());
    let end_t = *tr.t.last().unwrap();
    let ended = if STOPS.contains(&ended.as_str()) {
        ended
    } else {
        "horizon".into()
    };
    let (position, heading) = worse_error(tr.last().as_slice(), goal.as_slice());
    // The labels over the stall window (the last `stall.time` seconds).
    let mut tally: BTreeMap<&str, usize> = BTreeMap::new();
    let mut n = 0;
    for (l, t) in tr.label.iter().zip(&tr.t) {
        if *t >= end_t - p.stall.time && *t < end_t {
            *tally.entry(plan.label_name(*l)).or_default() += 1;
            n += 1;
        }
    }
    let reason = if converged {
        String::new()
    } else {
        let mut v: Vec<_> = tally.into_iter().collect();
        v.sort_by_key(|x| std::cmp::Reverse(x.1));
        v.iter()
            .take(2)
            .map(|(l, c)| format!("{l} {:.0}%", 100.0 * *c as f64 / n.max(1) as f64))
            .collect::<Vec<_>>()
            .join(", ")
    };
    // The plan's own account when no sequence converged (what each
    // candidate did with its time).
    let reason = match plan.details["note"].as_str() {
        Some(note) if !converged => format!("{reason}; {note}"),
        _ => reason,
    };
    Outcome {
        converged,
        ended,
        position,
        heading,
        time: if converged { end_t } else { f64::NAN },
        reason,
        plan: plan_choice(prep),
    }
}

/// The physics replay (and the ideal run) of a prepared case: passes when
/// every gate of the scenario holds.
fn physics(prep: &Prepared, set: Set) -> Outcome {
    let o = run_prepared(prep, None);
    let m = |n: &str| o.metric(n).unwrap_or(f64::NAN);
    let heading = match set {
        Set::Pair => m("sim_goal_theta1_deg").max(m("sim_goal_theta2_deg")),
        Set::Single | Set::Wall90 => m("sim_goal_theta_deg"),
    };
    let stall = m("sim_stall_time");
    let ended = if o.passed {
        "passed".to_string()
    } else if stall.is_finite() {
        format!("stalled at {stall:.1} s")
    } else {
        "failed".to_string()
    };
    Outcome {
        converged: o.passed,
        ended,
        position: m("sim_goal_position"),
        heading,
        time: m("sim_time_to_goal"),
        reason: o
            .failures
            .iter()
            .map(|f| f.split(" (").next().unwrap_or(f).to_string())
            .collect::<Vec<_>>()
            .join("; "),
        plan: plan_choice(prep),
    }
}

/// Run every case of a set (ideal only, or with physics), table it, and
/// return the outcomes (ideal, physics).
fn run_set(set: Set, law: Law, with_physics: bool) -> Vec<(Outcome, Option<Outcome>)> {
    let cases = set.cases();
    let mut table = format!(
        "| case | task | plan | ideal | ideal error | ideal time | {}stall reason |\n|---|---|---|---|---|---|{}---|\n",
        if with_physics {
            "physics | sim error | sim time | "
        } else {
            ""
        },
        if with_physics { "---|---|---|" } else { "" }
    );
    let t0 = std::time::Instant::now();
    // The cases are independent (each run is deterministic on any number
    // of threads): run them side by side, table them in order.
    let runs: Vec<(Outcome, Option<Outcome>)> = cases
        .par_iter()
        .enumerate()
        .map(|(i, case)| {
            let prep = prepare(set, case, law).unwrap_or_else(|e| panic!("case {i}: {e}"));
            (ideal(&prep), with_physics.then(|| physics(&prep, set)))
        })
        .collect();
    let mut out = Vec::new();
    for ((i, case), (id, sim)) in cases.iter().enumerate().zip(runs) {
        let err = |o: &Outcome| format!("{:.3} m, {:.1}°", o.position, o.heading);
        let time = |t: f64| {
            if t.is_finite() {
                format!("{t:.1} s")
            } else {
                "–".into()
            }
        };
        write!(
            table,
            "| {i} | {} | {} | {} | {} | {} |",
            case.what,
            id.plan,
            id.ended,
            err(&id),
            time(id.time)
        )
        .unwrap();
        if let Some(s) = &sim {
            write!(table, " {} | {} | {} |", s.ended, err(s), time(s.time)).unwrap();
        }
        let mut reason = id.reason.clone();
        if let Some(s) = sim.as_ref().filter(|s| !s.converged) {
            if !reason.is_empty() {
                reason.push_str("; ");
            }
            write!(reason, "physics: {}", s.reason).unwrap();
        }
        writeln!(table, " {reason} |").unwrap();
        out.push((id, sim));
    }
    let ideal_ok = out.iter().filter(|(i, _)| i.converged).count();
    write!(
        table,
        "\n{} of {} converge in the ideal run",
        ideal_ok,
        out.len()
    )
    .unwrap();
    if with_physics {
        let sim_ok = out
            .iter()
            .filter(|(_, s)| s.as_ref().is_some_and(|s| s.converged))
            .count();
        write!(table, ", {sim_ok} pass every gate in physics").unwrap();
    }
    writeln!(
        table,
        " ({} s wall).",
        (t0.elapsed().as_secs_f64() * 10.0).round() / 10.0
    )
    .unwrap();
    eprintln!("{table}");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("dilf_random");
    std::fs::create_dir_all(&dir).unwrap();
    let file = format!(
        "{}_{}_{}.md",
        set.name(),
        match law {
            Law::Defaults => format!("defaults_seed{}", set.seed()),
            Law::Paper => format!("paper_seed{}", set.seed()),
        },
        if with_physics { "physics" } else { "ideal" }
    );
    std::fs::write(dir.join(file), &table).unwrap();
    out
}

/// Every ideal run converges or ends `stalled` (none reaches the end of
/// its budget, none stops for another reason), at least `min` of them
/// converged.
fn assert_ideal(out: &[(Outcome, Option<Outcome>)], min: usize) {
    for (i, (o, _)) in out.iter().enumerate() {
        assert!(
            o.converged || o.ended == "stalled",
            "case {i} ended {} ({})",
            o.ended,
            o.reason
        );
    }
    let n = out.iter().filter(|(o, _)| o.converged).count();
    assert!(n >= min, "{n} of {} converged, {min} required", out.len());
}

/// 20 random rigid-consistent goals for the pair, the planner's defaults:
/// at least 18 converge in the ideal run, the others end `stalled`.
#[test]
fn random_pair_goals_converge_in_the_ideal_run() {
    let out = run_set(Set::Pair, Law::Defaults, false);
    assert_ideal(&out, 18);
}

/// 20 random goals behind the wall for one robot, the planner's defaults:
/// at least 19 converge.
#[test]
fn random_goals_behind_a_wall_converge_in_the_ideal_run() {
    let out = run_set(Set::Single, Law::Defaults, false);
    assert_ideal(&out, 19);
}

/// 20 goals behind the wall turned ±90°, where the paper's law stalls in
/// front of the wall (`seed-004-stall.md`), the planner's defaults: each
/// converges or ends `stalled` saying why (the plan's note: what every
/// candidate did), and at least 19 converge.
#[test]
fn goals_turned_90_degrees_behind_a_wall_converge_or_say_why() {
    let out = run_set(Set::Wall90, Law::Defaults, false);
    for (i, (o, _)) in out.iter().enumerate() {
        assert!(
            o.converged || o.reason.contains("sequence: no candidate converged"),
            "case {i}: {} without the plan's reason ({})",
            o.ended,
            o.reason
        );
    }
    assert_ideal(&out, 19);
}

/// The physics half of the pair set: every case converges in the ideal run,
/// and at least `PAIR_PHYSICS_FLOOR` pass every gate of `dilf_pair_open` in
/// physics.
#[test]
#[ignore = "physics replays: minutes; .ci/run runs it (documented in the seed-004 note)"]
fn random_pair_goals_pass_in_physics() {
    let out = run_set(Set::Pair, Law::Defaults, true);
    assert_ideal(&out, 18);
    let n = out
        .iter()
        .filter(|(_, s)| s.as_ref().unwrap().converged)
        .count();
    assert!(n >= PAIR_PHYSICS_FLOOR, "{n} of 20 pass in physics");
}

/// The single robot's physics half: every case converges in the ideal run,
/// at least `SINGLE_PHYSICS_FLOOR` pass every gate in physics.
#[test]
#[ignore = "physics replays: minutes; .ci/run runs it (documented in the seed-004 note)"]
fn random_goals_behind_a_wall_pass_in_physics() {
    let out = run_set(Set::Single, Law::Defaults, true);
    assert_ideal(&out, 19);
    let n = out
        .iter()
        .filter(|(_, s)| s.as_ref().unwrap().converged)
        .count();
    assert!(n >= SINGLE_PHYSICS_FLOOR, "{n} of 20 pass in physics");
}

/// The ±90° goals in physics, tabled (the research note's numbers; not
/// gated beyond the ideal runs').
#[test]
#[ignore = "physics replays of the ±90° wall goals: the seed-004 note's table"]
fn goals_turned_90_degrees_behind_a_wall_in_physics() {
    let out = run_set(Set::Wall90, Law::Defaults, true);
    assert_ideal(&out, 19);
}

/// The "before" tables: the paper's law alone on the same goals (ideal
/// runs and physics), for the research note; nothing gated.
#[test]
#[ignore = "the paper's law on the random goals: the note's before table"]
fn random_goals_paper_law() {
    run_set(Set::Pair, Law::Paper, true);
    run_set(Set::Single, Law::Paper, true);
    run_set(Set::Wall90, Law::Paper, false);
}

/// Every case as a scenario file (the planner's defaults), for `anholonomy
/// run` and `--set` experiments: `DILF_RANDOM_DUMP=DIR
/// [DILF_RANDOM_SEED=N] cargo test --release --test it -- --ignored
/// dilf_random::dump_cases` writes `DIR/pair_N.toml`, `DIR/single_N.toml`
/// and `DIR/wall90_N.toml` (the URDF path made absolute).
#[test]
#[ignore = "writes the cases' scenario files to $DILF_RANDOM_DUMP"]
fn dump_cases() {
    let Ok(dir) = std::env::var("DILF_RANDOM_DUMP") else {
        return;
    };
    let dir = std::path::PathBuf::from(dir);
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = scenario("../models/mobile_manipulator.urdf");
    let urdf = urdf.canonicalize().unwrap();
    for set in [Set::Pair, Set::Single, Set::Wall90] {
        for (i, case) in set.cases().iter().enumerate() {
            let text = scenario_text(set, case, Law::Defaults).replace(
                "\"../models/mobile_manipulator.urdf\"",
                &format!("{:?}", urdf.display().to_string()),
            );
            std::fs::write(dir.join(format!("{}_{i}.toml", set.name())), text).unwrap();
        }
    }
}
