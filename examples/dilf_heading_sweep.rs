//! Seed 004: the ideal run of a `dilf` scenario over many goal headings (and
//! random starts), to map where the feedback law converges and where it
//! stalls. Physics is not run.
//!
//! ```text
//! cargo run --release --example dilf_heading_sweep -- scenarios/dilf_single_door.toml
//!     [--headings FROM:TO:STEP]   goal headings, deg (default -180:180:15)
//!     [--random N] [--seed S]     N runs with a random goal heading and a
//!                                 random start (x, y, heading) instead
//!     [--start-box X0:X1:Y0:Y1]   where random starts are drawn (default:
//!                                 the file's start ± 1 m)
//!     [--no-stall]                planner.stall.time = 0: run to the horizon
//!     [--unguarded]               planner.hold_guard = false
//!     [--set KEY=VALUE]           any numeric scenario key, e.g.
//!                                 planner.kv_exponent=10 (repeatable)
//!     [--ascent]                  from each run that did not converge,
//!                                 climb V holonomically to its maximum and
//!                                 report where (x, y), V there and the
//!                                 largest eigenvalue of V's Hessian there
//!                                 (all negative: a strict local maximum)
//! ```
//!
//! One line per run: start, goal heading, how the run ended (the plan
//! label of its last sample: `converged`, `stalled`, a branch name when
//! it ran to the horizon, ...), when, how far from the goal, and V there.

use anholonomy::integrate::simulate;
use anholonomy::robots::mobile_manipulator::dilf::potential::Scene;
use anholonomy::scenario::{ModelConfig, PlannerConfig, Scenario, Variant};
use anholonomy::validate::Prepared;
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;
use std::path::PathBuf;

struct Args {
    file: PathBuf,
    headings: Vec<f64>,
    random: Option<usize>,
    seed: u64,
    start_box: Option<[f64; 4]>,
    no_stall: bool,
    ascent: bool,
    unguarded: bool,
    set: Vec<(String, f64)>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        file: PathBuf::new(),
        headings: Vec::new(),
        random: None,
        seed: 1,
        start_box: None,
        no_stall: false,
        ascent: false,
        unguarded: false,
        set: Vec::new(),
    };
    let nums = |s: &str| -> Result<Vec<f64>, String> {
        s.split(':')
            .map(|x| x.parse::<f64>().map_err(|e| format!("`{s}`: {e}")))
            .collect()
    };
    let mut range = vec![-180.0, 180.0, 15.0];
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--headings" => range = nums(&value("--headings")?)?,
            "--random" => a.random = Some(value("--random")?.parse().map_err(|e| format!("{e}"))?),
            "--seed" => a.seed = value("--seed")?.parse().map_err(|e| format!("{e}"))?,
            "--start-box" => {
                let v = nums(&value("--start-box")?)?;
                a.start_box = Some(v.try_into().map_err(|_| "--start-box X0:X1:Y0:Y1")?);
            }
            "--no-stall" => a.no_stall = true,
            "--ascent" => a.ascent = true,
            "--unguarded" => a.unguarded = true,
            "--set" => {
                let kv = value("--set")?;
                let (k, v) = kv.split_once('=').ok_or("--set KEY=VALUE")?;
                let v = v.parse().map_err(|e| format!("--set {kv}: {e}"))?;
                a.set.push((k.to_string(), v));
            }
            f if !f.starts_with("--") && a.file.as_os_str().is_empty() => a.file = f.into(),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    if a.file.as_os_str().is_empty() {
        return Err("usage: dilf_heading_sweep SCENARIO [options] (see the file's docs)".into());
    }
    let [from, to, step]: [f64; 3] = range
        .try_into()
        .map_err(|_| "--headings FROM:TO:STEP".to_string())?;
    if step.is_nan() || step <= 0.0 {
        return Err("--headings: STEP must be > 0".into());
    }
    let mut h = from;
    while h <= to + 1e-9 {
        // −180 and 180 are one heading.
        if !(h > 180.0 - 1e-9 && from <= -180.0 + 1e-9) {
            a.headings.push(h);
        }
        h += step;
    }
    Ok(a)
}

/// Holonomic gradient ascent of V from `q` (steps along f/‖f‖, halved until
/// V rises), then the Hessian of V by central differences of ∂V/∂q there:
/// (the end, V there, the Hessian's largest eigenvalue).
fn ascend(scene: &Scene, q: &[f64], power: f64) -> Option<(Vec<f64>, f64, f64)> {
    let mut warm = scene.warm();
    let mut q = q.to_vec();
    let mut step = 2e-3;
    for _ in 0..20_000 {
        let (e, f) = scene.field(&q, &mut warm).ok()?;
        let nf = f.iter().map(|x| x * x).sum::<f64>().sqrt();
        if nf < 1e-9 {
            break;
        }
        let mut moved = false;
        while step > 1e-12 {
            let trial: Vec<f64> = q.iter().zip(&f).map(|(a, b)| a + step * b / nf).collect();
            if scene
                .evaluate::<f64>(&trial, &mut warm)
                .is_ok_and(|t| t.v > e.v)
            {
                q = trial;
                moved = true;
                break;
            }
            step *= 0.5;
        }
        if !moved {
            break;
        }
        step = (step * 1.5).min(2e-3);
    }
    let n = q.len();
    let grad = |x: &[f64], warm: &mut _| -> Option<Vec<f64>> {
        let (e, f) = scene.field(x, warm).ok()?;
        let s = e.d.powf(power);
        Some(f.iter().map(|g| g / s).collect())
    };
    let eps = 1e-5;
    let mut h = nalgebra::DMatrix::<f64>::zeros(n, n);
    for j in 0..n {
        let (mut a, mut b) = (q.clone(), q.clone());
        a[j] += eps;
        b[j] -= eps;
        let (ga, gb) = (grad(&a, &mut warm)?, grad(&b, &mut warm)?);
        for i in 0..n {
            h[(i, j)] = (ga[i] - gb[i]) / (2.0 * eps);
        }
    }
    let sym = (&h + h.transpose()) * 0.5;
    let top = sym.symmetric_eigenvalues().max();
    let v = scene.evaluate::<f64>(&q, &mut warm).ok()?.v;
    Some((q, v, top))
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let text = match std::fs::read_to_string(&args.file) {
        Ok(t) if args.unguarded => t.replacen("[planner]", "[planner]\nhold_guard = false", 1),
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {}: {e}", args.file.display());
            std::process::exit(2);
        }
    };
    let base = match Scenario::parse(&args.file, &text) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.seed);
    let s0 = base.start.clone();
    let bx = args
        .start_box
        .unwrap_or([s0[0] - 1.0, s0[0] + 1.0, s0[1] - 1.0, s0[1] + 1.0]);
    let runs: Vec<BTreeMap<String, f64>> = match args.random {
        None => args
            .headings
            .iter()
            .map(|h| BTreeMap::from([("goal[2]".to_string(), *h)]))
            .collect(),
        Some(n) => (0..n)
            .map(|_| {
                BTreeMap::from([
                    ("goal[2]".to_string(), rng.random_range(-180.0..180.0)),
                    ("start[0]".to_string(), rng.random_range(bx[0]..bx[1])),
                    ("start[1]".to_string(), rng.random_range(bx[2]..bx[3])),
                    ("start[2]".to_string(), rng.random_range(-180.0..180.0)),
                ])
            })
            .collect(),
    };
    println!(
        "{:>4} {:>7} {:>7} {:>7} {:>7}  {:<22} {:>7} {:>8} {:>8} {:>10}{}",
        "run",
        "x0 m",
        "y0 m",
        "th0 deg",
        "goal th",
        "ended",
        "at s",
        "dist m",
        "dth deg",
        "V",
        if args.ascent {
            "   max of V at: x m, y m, th deg; V; top eigenvalue of its Hessian"
        } else {
            ""
        }
    );
    let mut tally: BTreeMap<String, usize> = BTreeMap::new();
    for (i, mut params) in runs.into_iter().enumerate() {
        if args.no_stall {
            params.insert("planner.stall.time".into(), 0.0);
        }
        params.extend(args.set.iter().cloned());
        let v = Variant {
            index: i,
            seed: 0,
            mass_scale: 1.0,
            sigma_rate: None,
            params,
        };
        let prep = match base.variant(&v).and_then(Prepared::new) {
            Ok(p) => p,
            Err(e) => {
                println!("{i:>4} refused: {e}");
                *tally.entry("refused".into()).or_default() += 1;
                continue;
            }
        };
        let (start, goal) = prep.start_goal();
        let plan = prep.plan().expect("validated");
        let tr = simulate(prep.model(), &plan, &start, prep.scenario.sim.dt);
        let end = tr.last().as_slice();
        let ended = plan
            .label_name(*tr.label.last().expect("a sample"))
            .to_string();
        let (ModelConfig::MobileManipulator(m), PlannerConfig::Dilf(p)) =
            (&prep.scenario.model, &prep.scenario.planner)
        else {
            eprintln!("error: not a dilf scenario");
            std::process::exit(2);
        };
        let scene =
            anholonomy::robots::mobile_manipulator::task_scene(m, p, start.as_slice(), &goal)
                .expect("validated");
        let v_end = scene
            .evaluate::<f64>(end, &mut scene.warm())
            .map_or(f64::NAN, |e| e.v);
        let dist = (end[0] - goal[0]).hypot(end[1] - goal[1]);
        let dth = anholonomy::compare::wrap_angle(end[2] - goal[2]).to_degrees();
        let mut line = format!(
            "{i:>4} {:>7.2} {:>7.2} {:>7.1} {:>7.1}  {:<22} {:>7.2} {:>8.3} {:>8.1} {:>10.4e}",
            start[0],
            start[1],
            start[2].to_degrees(),
            goal[2].to_degrees(),
            ended,
            tr.t.last().expect("a sample"),
            dist,
            dth,
            v_end
        );
        if args.ascent && ended != "converged" {
            match ascend(&scene, end, p.field_power) {
                Some((q, _, _)) if (q[0] - goal[0]).hypot(q[1] - goal[1]) < 0.1 => {
                    line.push_str("   none: the climb reaches the goal")
                }
                Some((q, v, top)) => line.push_str(&format!(
                    "   {:>6.2} {:>6.2} {:>7.1}  {v:.4e}  {top:+.2e}",
                    q[0],
                    q[1],
                    q[2].to_degrees()
                )),
                None => line.push_str("   (ascent failed)"),
            }
        }
        println!("{line}");
        *tally.entry(ended).or_default() += 1;
    }
    println!("{tally:?}");
}
