//! Seed 004: the ideal run of a `dilf` scenario, traced at every policy
//! sample, to see why the law stops where it stops (physics is not run).
//!
//! ```text
//! cargo run --release --example dilf_trace -- SCENARIO [--set KEY=VALUE]... [--out FILE.csv]
//! ```
//!
//! `--set` takes any numeric scenario key (`goal[0]=-9.1`,
//! `planner.kv_gain=3`, ...). One CSV row per policy sample (stdout
//! without `--out`), then a summary on stderr. Columns:
//!
//! * `t`, `label` (the plan label: each robot's Eq. 18b branch, `(guarded)`
//!   when the hold guard scaled the input down, or the stop), `guard_scale`
//!   (the applied input over Eq. 18's, 1 unguarded);
//! * `v`, `ln_v`, then each factor of ln V ([`Terms::named`]: `dipole`,
//!   `goal` = −ln Σ‖h2‖², `obstacles`, `robots`, `beam_parts`,
//!   `beam_obstacles`, `singular`, `admissible`; they sum to ln V);
//! * per robot r (1-based): `x_r`, `y_r`, `th_r` (deg), `dist_r` (m from its
//!   goal), `dth_r` (heading error, deg), `gamma_r` (its dipole), `v_r`,
//!   `w_r` (applied inputs), and the gradient of ln V on its platform:
//!   `along_r` (along its heading: what Eq. 18a's speed follows), `across_r`
//!   (across it: what the wheels cannot follow), `dtheta_r` (∂/∂θ, rad⁻¹),
//!   `arm_r` (‖∂/∂q_arm‖);
//! * per factor F and robot r: `F.along_r`, `F.across_r`, `F.dtheta_r`: that
//!   factor's share of the three (the shares sum to the totals);
//! * `margin` (the beam's least admissibility factor: 1 − (|F|/F_max)² or
//!   1 − (|M|/M_max)² at the worse grasp), `wrench_ratio` = √(1 − margin),
//!   `min_beta` (least obstacle function), `grasp_distance` (m).
//!
//! [`Terms::named`]: anholonomy::robots::mobile_manipulator::dilf::potential::Terms::named

use anholonomy::integrate::simulate;
use anholonomy::robots::mobile_manipulator::dilf::object::grasp_distance;
use anholonomy::robots::mobile_manipulator::kinematics::{DOF, INPUTS};
use anholonomy::scenario::{ModelConfig, PlannerConfig, Scenario, Variant};
use anholonomy::validate::Prepared;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

const FACTORS: [&str; 8] = [
    "dipole",
    "goal",
    "obstacles",
    "robots",
    "beam_parts",
    "beam_obstacles",
    "singular",
    "admissible",
];

const HELP: &str = "\
Trace the ideal run of a dilf scenario at every policy sample: one CSV row
per sample with ln V and its factors, each factor's gradient along and
across each platform's heading and in theta, the branches, the hold
guard's scale and the rod's wrench ratio (columns: the file's docs).

usage: dilf_trace SCENARIO [--set KEY=VALUE]... [--out FILE.csv]
  --set KEY=VALUE  any numeric scenario key, e.g. goal[0]=-9.1, planner.kv_gain=3
  --out FILE       write the CSV there (default: stdout); a summary goes to stderr";

fn fail(msg: impl std::fmt::Display) -> ! {
    eprintln!("error: {msg}");
    std::process::exit(2);
}

fn main() {
    let mut file = None;
    let mut out: Option<PathBuf> = None;
    let mut set = BTreeMap::new();
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--set" => {
                let kv = it.next().unwrap_or_else(|| fail("--set needs KEY=VALUE"));
                let (k, v) = kv
                    .split_once('=')
                    .unwrap_or_else(|| fail("--set KEY=VALUE"));
                let v: f64 = v
                    .parse()
                    .unwrap_or_else(|e| fail(format!("--set {kv}: {e}")));
                set.insert(k.to_string(), v);
            }
            "--out" => {
                out = Some(
                    it.next()
                        .unwrap_or_else(|| fail("--out needs a file"))
                        .into(),
                )
            }
            "-h" | "--help" => {
                println!("{HELP}");
                return;
            }
            f if !f.starts_with("--") && file.is_none() => file = Some(PathBuf::from(f)),
            other => fail(format!("unknown argument `{other}`")),
        }
    }
    let file = file.unwrap_or_else(|| fail("usage: dilf_trace SCENARIO [--set K=V]... [--out F]"));
    let text =
        std::fs::read_to_string(&file).unwrap_or_else(|e| fail(format!("{}: {e}", file.display())));
    let base = Scenario::parse(&file, &text).unwrap_or_else(|e| fail(e));
    let v = Variant {
        index: 0,
        seed: 0,
        mass_scale: 1.0,
        sigma_rate: None,
        params: set,
    };
    let prep = base
        .variant(&v)
        .and_then(Prepared::new)
        .unwrap_or_else(|e| fail(e));
    let (ModelConfig::MobileManipulator(m), PlannerConfig::Dilf(p)) =
        (&prep.scenario.model, &prep.scenario.planner)
    else {
        fail("not a dilf scenario")
    };
    let (start, goal) = prep.start_goal();
    let plan = prep.plan().unwrap_or_else(|e| fail(e));
    let tr = simulate(prep.model(), &plan, &start, prep.scenario.sim.dt);
    let scene = anholonomy::robots::mobile_manipulator::task_scene(m, p, start.as_slice(), &goal)
        .unwrap_or_else(|e| fail(e));
    let robots = scene.robots;
    let every = (p.period / prep.scenario.sim.dt).round().max(1.0) as usize;
    let gains = p.gains();

    let mut csv = String::from("t,label,guard_scale,v,ln_v");
    for f in FACTORS {
        write!(csv, ",{f}").unwrap();
    }
    for r in 1..=robots {
        for c in [
            "x", "y", "th", "dist", "dth", "gamma", "v", "w", "along", "across", "dtheta", "arm",
        ] {
            write!(csv, ",{c}_{r}").unwrap();
        }
    }
    for f in FACTORS {
        for r in 1..=robots {
            for c in ["along", "across", "dtheta"] {
                write!(csv, ",{f}.{c}_{r}").unwrap();
            }
        }
    }
    csv.push_str(",margin,wrench_ratio,min_beta,grasp_distance\n");

    let mut warm = scene.warm();
    let g = goal.as_slice();
    for k in (0..tr.t.len()).step_by(every) {
        let q = tr.q[k].as_slice();
        let u = tr.u[k].as_slice();
        let label = plan.label_name(tr.label[k]);
        let Ok((e, f)) = scene.field(q, &mut warm) else {
            continue;
        };
        // Eq. 18 unguarded (the hand-over state is not known here: robots
        // the label says align are taken as aligning).
        let aligning: Vec<bool> = label
            .split(' ')
            .next()
            .unwrap_or("")
            .split('/')
            .map(|b| b == "align")
            .collect();
        let (u0, _) = anholonomy::robots::mobile_manipulator::dilf::control::control_aligning(
            q, &f, g, &gains, &aligning,
        );
        let norm = |x: &[f64]| x.iter().map(|a| a * a).sum::<f64>().sqrt();
        let guard_scale = if norm(&u0) > 0.0 {
            norm(u) / norm(&u0)
        } else {
            1.0
        };
        let terms = scene.term_gradients(q).ok().flatten();
        write!(
            csv,
            "{:.3},{label},{guard_scale:.4},{:.6e},{:.6}",
            tr.t[k],
            e.v,
            e.v.ln()
        )
        .unwrap();
        match &terms {
            Some(t) => {
                for (_, x, _) in &t.terms {
                    write!(csv, ",{x:.6}").unwrap();
                }
            }
            None => csv.push_str(&",".repeat(FACTORS.len())),
        }
        let split = |grad: &[f64], r: usize| {
            let i = DOF * r;
            let (s, c) = q[i + 2].sin_cos();
            let along = grad[i] * c + grad[i + 1] * s;
            let across = -grad[i] * s + grad[i + 1] * c;
            (along, across, grad[i + 2], norm(&grad[i + 3..i + DOF]))
        };
        // ∂ ln V/∂q = f / (V d^p).
        let scale = 1.0 / (e.v * e.d.powf(p.field_power));
        let gl: Vec<f64> = f.iter().map(|x| x * scale).collect();
        for r in 0..robots {
            let i = DOF * r;
            let dist = (q[i] - g[i]).hypot(q[i + 1] - g[i + 1]);
            let dth = anholonomy::compare::wrap_angle(q[i + 2] - g[i + 2]).to_degrees();
            let gamma = terms.as_ref().map_or(f64::NAN, |t| t.gammas[r]);
            let (al, ac, dt, arm) = split(&gl, r);
            write!(
                csv,
                ",{:.4},{:.4},{:.2},{dist:.4},{dth:.2},{gamma:.5},{:.4},{:.4},{al:.5},{ac:.5},{dt:.5},{arm:.5}",
                q[i],
                q[i + 1],
                q[i + 2].to_degrees(),
                u[INPUTS * r],
                u[INPUTS * r + 1]
            )
            .unwrap();
        }
        for fi in 0..FACTORS.len() {
            for r in 0..robots {
                match &terms {
                    Some(t) => {
                        let (al, ac, dt, _) = split(&t.terms[fi].2, r);
                        write!(csv, ",{al:.5},{ac:.5},{dt:.5}").unwrap();
                    }
                    None => csv.push_str(",,,"),
                }
            }
        }
        let margin = e.admissible;
        let ratio = if margin.is_finite() {
            (1.0 - margin).max(0.0).sqrt()
        } else {
            f64::NAN
        };
        let gd = if robots == 2 {
            grasp_distance(q)
        } else {
            f64::NAN
        };
        writeln!(csv, ",{margin:.5},{ratio:.4},{:.5e},{gd:.4}", e.min_beta).unwrap();
    }
    match out {
        Some(path) => std::fs::write(&path, csv).unwrap_or_else(|e| fail(e)),
        None => std::io::stdout().write_all(csv.as_bytes()).unwrap(),
    }
    let end = tr.last().as_slice();
    let ended = plan.label_name(*tr.label.last().expect("a sample"));
    let mut summary = format!("{ended} at {:.2} s;", tr.t.last().unwrap());
    for r in 0..robots {
        let i = DOF * r;
        write!(
            summary,
            " robot {}: {:.3} m, {:.1} deg off;",
            r + 1,
            (end[i] - g[i]).hypot(end[i + 1] - g[i + 1]),
            anholonomy::compare::wrap_angle(end[i + 2] - g[i + 2]).to_degrees()
        )
        .unwrap();
    }
    eprintln!("{summary}");
}
