//! Sweeps of any scenario key, streamed `variants.jsonl`, `--resume` after a
//! SIGKILL, shards from the scheduler's environment, and `merge`: a resumed
//! and a merged sweep write the same `sweep.json` as an uninterrupted,
//! unsharded one (byte for byte, everything but the wall times).

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A cheap disk sweep over a written key, defaulted keys (inserted), an angle
/// in degrees, a grid, and the friction/mass shorthands.
fn scenario() -> String {
    let base = disk_scenario(&model("rolling_disk.urdf"), "name = \"s\"", "")
        .replace("dt = 0.001", "dt = 0.004")
        .replace(
            "goal = [-0.4, 1.0, 180.0, 22.5]",
            "goal = [-0.2, 0.3, 90.0, 10.0]",
        );
    format!(
        "{base}\n[sweep]\ncount = 8\nseed = 11\nfriction = [0.6, 1.0]\nmass_scale = [0.9, 1.1]\n\
         success_max = 0.05\ntime_metric = \"sim_goal_position\"\n\n[sweep.vary]\n\
         \"planner.slant\" = {{ uniform = [0.3, 0.7] }}\n\"start[0]\" = {{ normal = [0.0, 0.01] }}\n\
         \"goal[3]\" = {{ values = [10.0, 15.0] }}\n\"limits.ramp\" = {{ grid = [0.2, 0.3] }}\n"
    )
}

fn bin(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_anholonomy"));
    c.args(args).current_dir(dir);
    for k in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_MAX",
        "SLURM_ARRAY_TASK_STEP",
        "JOB_COMPLETION_INDEX",
        "ANHOLONOMY_SHARDS",
    ] {
        c.env_remove(k);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}\n{}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Exit 2 with exactly one error line containing `want`.
fn bad(o: &Output, want: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: ") && err.contains(want), "{err}");
}

/// `sweep.json` without its last member, `wall_time_s` (the only clock-dependent part).
fn statistics(path: &Path) -> String {
    let t = std::fs::read_to_string(path).unwrap();
    let cut = t.rfind("\"wall_time_s\"").expect("wall_time_s last");
    let v: serde_json::Value = serde_json::from_str(&t).unwrap();
    assert!(
        v["results"].is_array() && v["final_error"].is_object(),
        "{t}"
    );
    t[..cut].to_string()
}

/// An edit of a shard file's text, or none.
type Edit<'a> = Option<&'a dyn Fn(String) -> String>;

fn lines(p: &Path) -> Vec<String> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn any_key_is_swept_and_applied_to_the_variant() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("s.toml");
    std::fs::write(&f, scenario()).unwrap();
    let p = prepared(&f);
    let cfg = p.scenario.sweep.clone().unwrap();
    let mut ramps = Vec::new();
    for i in 0..4 {
        let v = cfg.variant(i);
        let sc = p.scenario.variant(&v).unwrap();
        assert!(sc.sweep.is_none());
        assert_eq!(sc.sim.friction, v.params["sim.friction"]);
        assert_eq!(sc.ramp, v.params["limits.ramp"]);
        assert_eq!(sc.start[0], v.params["start[0]"]);
        assert_eq!(sc.goal[3], v.params["goal[3]"].to_radians());
        let planner = serde_json::to_value(&sc.planner).unwrap();
        assert_eq!(
            planner["slant"].as_f64().unwrap(),
            v.params["planner.slant"]
        );
        assert!((0.3..=0.7).contains(&v.params["planner.slant"]));
        assert_ne!(v.params["start[0]"], 0.0);
        ramps.push(v.params["limits.ramp"]);
        // The variant is the scenario with those numbers: everything else is unchanged.
        assert_eq!(sc.sim.dt, p.scenario.sim.dt);
        assert_eq!(sc.goal[0], p.scenario.goal[0]);
    }
    assert_eq!(
        ramps,
        [0.2, 0.3, 0.2, 0.3],
        "grid axis cycles with the index"
    );
}

/// Wait until `path` has at least `n` lines, or the child exits.
fn wait_lines(child: &mut std::process::Child, path: &Path, n: usize) -> usize {
    let t0 = Instant::now();
    loop {
        let k = std::fs::read_to_string(path)
            .map(|t| t.matches('\n').count())
            .unwrap_or(0);
        if k >= n || child.try_wait().unwrap().is_some() || t0.elapsed() > Duration::from_secs(60) {
            return k;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn killed_resumed_and_merged_sweeps_equal_the_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), scenario()).unwrap();

    // The reference: one uninterrupted, unsharded run on 2 threads.
    ok(&bin(
        d,
        &["run", "s.toml", "--quiet", "--logs", "ref"],
        &[("RAYON_NUM_THREADS", "2")],
    ));
    let reference = statistics(&d.join("ref/s/sweep.json"));
    let recs = lines(&d.join("ref/s/variants.jsonl"));
    assert_eq!(recs.len(), 9, "header and 8 records");
    assert!(recs[0].contains("\"scenario_sha256\""));
    let r: serde_json::Value = serde_json::from_str(&recs[1]).unwrap();
    for k in [
        "index",
        "params",
        "metrics",
        "success",
        "final_error",
        "wall_s",
    ] {
        assert!(r.get(k).is_some(), "record lacks {k}: {r}");
    }
    assert!(r["metrics"]["sim_goal_position"].is_number());

    // Killed (SIGKILL) after two variants, a torn last line added, then resumed
    // (batched). Unbatched, so that lines arrive one variant at a time: a
    // batched sweep on one thread writes its one group's lines together.
    let jsonl = d.join("killed/s/variants.jsonl");
    let mut child = Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(["run", "s.toml", "--quiet", "--logs", "killed", "--no-batch"])
        .env("RAYON_NUM_THREADS", "1")
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let seen = wait_lines(&mut child, &jsonl, 3);
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(
        (3..9).contains(&seen) && !d.join("killed/s/sweep.json").exists(),
        "the sweep was not killed mid-run ({seen} lines)"
    );
    let before = lines(&jsonl).len();
    {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&jsonl)
            .unwrap();
        f.write_all(b"{\"index\":7,\"seed\":12").unwrap();
    }
    let out = bin(
        d,
        &["run", "s.toml", "--quiet", "--logs", "killed", "--resume"],
        &[],
    );
    ok(&out);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains(&format!("{} resumed", before - 1)),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert_eq!(
        lines(&jsonl).len(),
        9,
        "torn line dropped, every variant once"
    );
    assert_eq!(statistics(&d.join("killed/s/sweep.json")), reference);

    // Four shards, from --shard, Slurm's and Kubernetes' variables, then merged.
    ok(&bin(
        d,
        &["run", "s.toml", "--quiet", "--logs", "sh", "--shard", "0/4"],
        &[],
    ));
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "2"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
        ("SLURM_ARRAY_TASK_MAX", "4"),
    ];
    ok(&bin(
        d,
        &["run", "s.toml", "--quiet", "--logs", "sh"],
        &slurm,
    ));
    ok(&bin(
        d,
        &["run", "s.toml", "--quiet", "--logs", "sh", "--shards", "4"],
        &[("JOB_COMPLETION_INDEX", "2")],
    ));
    ok(&bin(
        d,
        &["run", "s.toml", "--quiet", "--logs", "sh"],
        &[("JOB_COMPLETION_INDEX", "3"), ("ANHOLONOMY_SHARDS", "4")],
    ));
    let shard = |i: usize| d.join(format!("sh/s/variants-shard-{i}-of-4.jsonl"));
    for i in 0..4 {
        assert_eq!(lines(&shard(i)).len(), 3, "shard {i}: header and 2 records");
    }
    ok(&bin(d, &["merge", "sh/s"], &[]));
    assert_eq!(statistics(&d.join("sh/s/sweep.json")), reference);

    // Bad shards: exit 2, one line naming the shard, nothing written.
    let case = |name: &str, files: &[(usize, Edit)]| -> PathBuf {
        let c = d.join(name);
        std::fs::create_dir_all(&c).unwrap();
        for (k, (i, edit)) in files.iter().enumerate() {
            let text = std::fs::read_to_string(shard(*i)).unwrap();
            let text = edit.map_or(text.clone(), |e| e(text));
            std::fs::write(c.join(format!("variants-shard-{k}-x.jsonl")), text).unwrap();
        }
        c
    };
    let merge_bad = |c: &Path, want: &str| {
        bad(&bin(d, &["merge", c.to_str().unwrap()], &[]), want);
        assert!(!c.join("sweep.json").exists());
    };
    merge_bad(
        &case("missing", &[(0, None), (1, None), (3, None)]),
        "variants-shard-2-of-4.jsonl",
    );
    merge_bad(
        &case(
            "twice",
            &[(0, None), (1, None), (1, None), (2, None), (3, None)],
        ),
        "given twice",
    );
    let other_seed = |t: String| t.replacen("\"seed\":11", "\"seed\":12", 1);
    merge_bad(
        &case(
            "foreign",
            &[(0, None), (1, Some(&other_seed)), (2, None), (3, None)],
        ),
        "another sweep",
    );
    let cut = |t: String| {
        t.lines()
            .take(2)
            .map(|l| format!("{l}\n"))
            .collect::<String>()
    };
    merge_bad(
        &case("short", &[(0, None), (1, None), (2, Some(&cut)), (3, None)]),
        "incomplete: 1 of 2",
    );
    let garble = |t: String| t.replacen("\n{", "\n{garbage\n{", 1);
    merge_bad(
        &case(
            "corrupt",
            &[(0, Some(&garble)), (1, None), (2, None), (3, None)],
        ),
        "line 2",
    );

    // Bad resumes: exit 2, one line, the records and sweep.json untouched.
    let unchanged = |what: &str, want: &str, prepare: &dyn Fn()| {
        let j = d.join("killed/s/variants.jsonl");
        let saved = std::fs::read(&j).unwrap();
        prepare();
        let now = std::fs::read(&j).unwrap();
        let json = std::fs::read(d.join("killed/s/sweep.json")).unwrap();
        bad(
            &bin(
                d,
                &["run", "s.toml", "--quiet", "--logs", "killed", "--resume"],
                &[],
            ),
            want,
        );
        assert_eq!(std::fs::read(&j).unwrap(), now, "{what}: records changed");
        assert_eq!(
            std::fs::read(d.join("killed/s/sweep.json")).unwrap(),
            json,
            "{what}"
        );
        std::fs::write(&j, saved).unwrap();
    };
    unchanged(
        "a shard's records",
        "written by shard 0/4, not the unsharded sweep",
        &|| {
            std::fs::copy(shard(0), &jsonl).unwrap();
        },
    );
    unchanged("corrupt records", "line 3", &|| {
        let t = std::fs::read_to_string(&jsonl).unwrap();
        let mut l: Vec<&str> = t.lines().collect();
        l[2] = "{\"index\": oops";
        std::fs::write(&jsonl, l.join("\n") + "\n").unwrap();
    });
    unchanged("not a records file", "line 1", &|| {
        std::fs::write(&jsonl, "hello\n").unwrap();
    });
    let text = std::fs::read_to_string(d.join("s.toml")).unwrap();
    unchanged("an edited scenario", "SHA-256 differs", &|| {
        std::fs::write(
            d.join("s.toml"),
            text.replace("seed = 11", "seed = 11 # edited"),
        )
        .unwrap();
    });
    std::fs::write(d.join("s.toml"), &text).unwrap();

    // A shard index the environment gets wrong is bad input too.
    bad(
        &bin(
            d,
            &["run", "s.toml", "--quiet", "--logs", "x"],
            &[("JOB_COMPLETION_INDEX", "4"), ("ANHOLONOMY_SHARDS", "4")],
        ),
        "not below the shard count 4",
    );
    bad(
        &bin(
            d,
            &["run", "s.toml", "--quiet", "--logs", "x"],
            &[("JOB_COMPLETION_INDEX", "1")],
        ),
        "--shards N",
    );
    assert!(!d.join("x").exists());
}

/// Each `variants.jsonl` record of a sweep run in-process on `threads`
/// worker threads, in index order, without its wall time.
fn records(
    prep: &anholonomy::runner::Prepared,
    batch: bool,
    threads: usize,
    logs: &Path,
) -> Vec<serde_json::Value> {
    let opts = anholonomy::runner::RunOptions {
        log_root: Some(logs.to_path_buf()),
        batch,
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| anholonomy::sweep::run_sweep(prep, &opts, None))
        .unwrap();
    let name = &prep.scenario.name;
    let mut out: Vec<serde_json::Value> = lines(&logs.join(name).join("variants.jsonl"))[1..]
        .iter()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("wall_s");
            v
        })
        .collect();
    out.sort_by_key(|v| v["index"].as_u64());
    out
}

/// A shipped scenario as a sweep of `count` variants over friction and
/// masses (its own `[sweep]` table, if it has one, with `count` variants),
/// its relative paths made absolute.
/// A scenario's text without its `[[model.obstacles]]` and the gates on them.
fn without_obstacles(text: &str) -> String {
    let mut out = Vec::new();
    let mut skipping = false;
    for l in text.lines() {
        if l.starts_with('[') {
            skipping = l.trim() == "[[model.obstacles]]";
        }
        if skipping || l.starts_with("sim_obstacle_contacts") || l.starts_with("sim_min_clearance")
        {
            continue;
        }
        out.push(l);
    }
    out.join("\n")
}

fn shipped_sweep(name: &str, count: usize) -> String {
    let text = std::fs::read_to_string(root().join("scenarios").join(format!("{name}.toml")))
        .unwrap()
        .replace("\"../", &format!("\"{}/", root().display()));
    match text.find("count = ") {
        Some(_) => {
            let re = text.lines().find(|l| l.starts_with("count = ")).unwrap();
            text.replace(re, &format!("count = {count}"))
        }
        None => format!(
            "{text}\n[sweep]\ncount = {count}\nseed = 3\nfriction = [0.6, 1.0]\n\
             mass_scale = [0.8, 1.2]\nsuccess_max = 0.05\n"
        ),
    }
}

/// Batched sweeps (variants stepped together in shared engine worlds) record
/// exactly what unbatched ones do: every metric of every variant, bit for
/// bit, on one worker thread (one group) and on two (two groups). The
/// rover's variants differ in friction, masses and σ and end at different
/// steps (feedback primitives with a stop rule); the perturbed rover adds
/// command latency, an actuator lag and state noise and latency (the
/// replay's own perturbations, per variant); the disk's variants also differ
/// in their plans; the car replays a plan file, the sphere its geometric
/// plan, the differential drive an
/// external feedback law (one process per variant, all alive at once).
#[test]
fn batched_sweep_equals_unbatched() {
    let dir = tempfile::tempdir().unwrap();
    let rover = shipped_sweep("rover_sweep", 7);
    let perturbed = rover.replacen(
        "[sim]\n",
        "[sim.perturb]\ncommand_latency = 0.006\nactuator_tau = 0.02\n\
         state_noise = 0.002\nstate_latency = 0.01\nseed = 5\n\n[sim]\n",
        1,
    );
    assert_ne!(perturbed, rover);
    std::fs::write(dir.path().join("rover.toml"), rover).unwrap();
    std::fs::write(dir.path().join("perturbed.toml"), perturbed).unwrap();
    std::fs::write(dir.path().join("disk.toml"), scenario()).unwrap();
    // The car without its neighbours: a robot among obstacles runs in a
    // world of its own (its obstacles must not meet other robots).
    std::fs::write(
        dir.path().join("car.toml"),
        without_obstacles(&shipped_sweep("car_parking", 4)),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("sphere.toml"),
        shipped_sweep("sphere_geometric_paper", 4),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("diff_drive.toml"),
        shipped_sweep("diff_drive_go_to_pose", 4),
    )
    .unwrap();
    // (file, variants, whether its variants must end at different steps)
    let cases = [
        ("rover.toml", 7, true),
        ("perturbed.toml", 7, true),
        ("disk.toml", 8, true),
        ("car.toml", 4, false),
        ("sphere.toml", 4, false),
        ("diff_drive.toml", 4, false),
    ];
    for (file, count, ends_differ) in cases {
        let p = prepared(&dir.path().join(file));
        // Every variant joins its group's world (else the comparison below
        // would compare unbatched runs with themselves).
        let mut host = anholonomy::engine::batch::Host::new();
        let cfg = p.scenario.sweep.as_ref().unwrap();
        for i in 0..count {
            let v = p.variant(&cfg.variant(i)).unwrap();
            let built = host.build(|| v.physics()).unwrap();
            assert!(
                matches!(built, anholonomy::engine::batch::Built::Hosted(_)),
                "{file}: variant {i} not hosted"
            );
        }
        assert_eq!(host.len(), count, "{file}");
        let todo: Vec<usize> = (0..count).collect();
        let groups = anholonomy::sweep::batch::groups(&p, &todo);
        assert!(groups.iter().any(|g| g.len() > 1), "{file}: {groups:?}");
        let out = |batch: bool, threads: usize| {
            let logs = dir.path().join(format!("{file}-{batch}-{threads}"));
            records(&p, batch, threads, &logs)
        };
        let alone = out(false, 2);
        assert_eq!(alone.len(), count);
        let steps: std::collections::BTreeSet<u64> =
            alone.iter().map(|r| r["steps"].as_u64().unwrap()).collect();
        assert!(
            steps.len() > 1 || !ends_differ,
            "{file}: variants of equal length {steps:?}"
        );
        for a in &alone {
            assert!(a["error"].is_null(), "{file}: {a}");
        }
        for threads in [1, 2] {
            let batched = out(true, threads);
            assert_eq!(batched.len(), count);
            for (b, a) in batched.iter().zip(&alone) {
                // serde_json prints f64 shortest round-trip: equal text is equal bits.
                assert_eq!(b.to_string(), a.to_string(), "{file}, {threads} threads");
            }
        }
    }
}

/// A batched replay stops when its token is cancelled (checked before
/// every lockstep step): every lane ends `Cancelled`; the same lanes replay
/// to the end without the token.
#[test]
fn cancelled_batched_replay_stops() {
    use anholonomy::engine::batch::{Built, Host, Lane};
    use anholonomy::engine::ReplayError;
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("rover.toml");
    std::fs::write(&f, shipped_sweep("rover_sweep", 3)).unwrap();
    let p = prepared(&f);
    let cfg = p.scenario.sweep.as_ref().unwrap();
    let variants: Vec<_> = (0..3)
        .map(|i| p.variant(&cfg.variant(i)).unwrap())
        .collect();
    for cancelled in [true, false] {
        let mut host = Host::new();
        let mut systems: Vec<_> = variants
            .iter()
            .map(|v| match host.build(|| v.physics()).unwrap() {
                Built::Hosted(sys) => sys,
                Built::Alone(_) => panic!("not hosted"),
            })
            .collect();
        let mut lanes: Vec<Lane> = systems
            .iter_mut()
            .zip(&variants)
            .map(|(sys, v)| Lane {
                sys: sys.as_mut(),
                plan: &v.planned,
                opts: anholonomy::engine::ReplayOptions {
                    dt: v.scenario.sim.dt,
                    settle: v.scenario.sim.settle,
                    link_pose_every: None,
                    perturbation: v.scenario.sim.perturb,
                },
            })
            .collect();
        let cancel = anholonomy::cancel::Cancel::new();
        if cancelled {
            cancel.cancel();
        }
        let out = host.replay(&mut lanes, &cancel);
        assert_eq!(out.len(), 3);
        for r in out {
            match (cancelled, r) {
                (true, Err(ReplayError::Cancelled)) => {}
                (false, Ok(sim)) => assert!(sim.steps > 1000, "{}", sim.steps),
                (c, r) => panic!("cancelled {c}: {:?}", r.map(|s| s.steps)),
            }
        }
    }
}
