//! Commands that read scenarios without running physics: `plan`, `list`,
//! `keys`.

use anholonomy::error::Error;
use anholonomy::integrate::simulate;
use anholonomy::validate::{prepare_all, prepare_each, Call};
use std::path::{Path, PathBuf};

pub fn plan_cmd(file: &std::path::Path, as_json: bool, max_steps: u64) -> Result<u8, Vec<Error>> {
    if file.is_dir() {
        return Err(vec![Error::input(
            file,
            "`plan` takes one scenario file, not a directory",
        )]);
    }
    let call = Call {
        max_steps: Some(max_steps),
        ..Call::default()
    };
    let preps = prepare_all(&[file.to_path_buf()], &call)?;
    let prep = &preps[0];
    let plan = &prep.planned;
    let (start, _goal) = prep.start_goal();
    let ideal = simulate(prep.model(), plan, &start, prep.scenario.sim.dt);
    let fin: Vec<f64> = ideal.last().iter().copied().collect();
    let (_, goal) = prep.start_goal();
    let paper = prep.system.paper(&start, &goal, plan);
    if as_json {
        let v = serde_json::json!({
            "scenario": prep.scenario.name,
            "planner": prep.scenario.planner,
            "state_names": prep.model().state_names(),
            "input_names": prep.model().input_names(),
            "duration_s": plan.duration,
            "labels": plan.labels,
            "segments": plan.segments,
            "details": plan.details,
            "ideal_final_state": fin,
            "paper": paper,
            "read_from_urdf": prep.reading,
        });
        say!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        say!(
            "{} ({}), duration {} s",
            prep.scenario.name,
            prep.scenario.planner.kind(),
            anholonomy::numfmt::with_digits(plan.duration, 7)
        );
        for s in &plan.segments {
            say!(
                "  {:>8.3} – {:>8.3} s  {}",
                s.start,
                s.end,
                plan.label_name(s.label)
            );
        }
        say!("  details: {}", plan.details);
        say!("  ideal final state: {}", display_state(prep.model(), &fin));
        say!("read from {}:", anholonomy::echo::path(&prep.scenario.urdf));
        for line in prep.reading.lines() {
            say!("{line}");
        }
        if !paper.is_empty() {
            say!("{}", anholonomy::paper::format_table(&paper).trim_end());
        }
    }
    Ok(0)
}

/// A state as the scenario files write it: angles in degrees, lengths in m.
fn display_state(model: &dyn anholonomy::model::KinematicModel, q: &[f64]) -> String {
    let angular = model.angular_states();
    let position = model.position_states();
    let fmt = |x: f64| anholonomy::numfmt::with_digits(x, 6);
    model
        .state_names()
        .iter()
        .zip(q)
        .enumerate()
        .map(|(i, (n, x))| {
            if angular.contains(&i) {
                format!("{n} = {} deg", fmt(x.to_degrees()))
            } else if position.is_some_and(|p| p.contains(&i)) {
                format!("{n} = {} m", fmt(*x))
            } else {
                format!("{n} = {}", fmt(*x))
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn list_cmd(paths: &[PathBuf], max_steps: u64) -> Result<u8, Vec<Error>> {
    let paths = if paths.is_empty() {
        vec![PathBuf::from("scenarios")]
    } else {
        paths.to_vec()
    };
    let call = Call {
        max_steps: Some(max_steps),
        ..Call::default()
    };
    let (preps, errors) = prepare_each(&paths, &call);
    let rows: Vec<[&str; 4]> = preps
        .iter()
        .map(|p| {
            let s = &p.scenario;
            [
                s.name.as_str(),
                s.model.kind(),
                s.planner.kind(),
                s.description.as_str(),
            ]
        })
        .collect();
    let header = ["scenario", "model", "planner", "description"];
    let width = |c: usize| {
        rows.iter()
            .chain([&header])
            .map(|r| r[c].chars().count())
            .max()
            .unwrap_or(0)
    };
    let (w0, w1, w2) = (width(0), width(1), width(2));
    for r in [&header]
        .into_iter()
        .chain(&rows)
        .take(if rows.is_empty() { 0 } else { usize::MAX })
    {
        say!("{:<w0$}  {:<w1$}  {:<w2$}  {}", r[0], r[1], r[2], r[3]);
    }
    if errors.is_empty() {
        Ok(0)
    } else {
        Err(errors)
    }
}

pub fn keys_cmd(name: Option<&str>, markdown: bool, out: Option<&Path>) -> Result<u8, Vec<Error>> {
    use anholonomy::reference::Page;
    if let Some(dir) = out {
        if !markdown {
            return Err(vec![Error::input(
                "--out",
                "writes Markdown pages: add --markdown",
            )]);
        }
        let mut pages = Vec::new();
        for p in Page::all() {
            let text = p
                .markdown()
                .map_err(|e| vec![Error::input("keys", e.to_string())])?;
            pages.push((dir.join(p.file()), text));
        }
        for (path, text) in &pages {
            let parent = path.parent().unwrap_or(Path::new("."));
            std::fs::create_dir_all(parent).map_err(|e| {
                vec![Error::Log {
                    path: parent.to_path_buf(),
                    message: e.to_string(),
                }]
            })?;
            anholonomy::log::atomic::write_file(path, |w| {
                std::io::Write::write_all(w, text.as_bytes())
            })
            .map_err(|e| {
                vec![Error::Log {
                    path: path.clone(),
                    message: e.to_string(),
                }]
            })?;
        }
        say!(
            "wrote {} pages to {}",
            pages.len(),
            anholonomy::echo::path(dir)
        );
        return Ok(0);
    }
    let Some(name) = name else {
        let models = anholonomy::scenario::ModelConfig::KINDS.join(", ");
        let planners = anholonomy::scenario::PlannerConfig::KINDS.join(", ");
        say!("anholonomy keys NAME prints the keys of:\n  scenario   the file's own tables (top level, [limits], [sim], [thresholds], [sweep], [regression])\n  models     {models}\n  planners   {planners}");
        return Ok(0);
    };
    let Some(page) = Page::find(name) else {
        let mut known = vec!["scenario"];
        known.extend(anholonomy::scenario::ModelConfig::KINDS);
        known.extend(anholonomy::scenario::PlannerConfig::KINDS);
        return Err(vec![Error::input(
            "keys",
            format!(
                "`{name}` is not a model or planner kind (known: {})",
                known.join(", ")
            ),
        )]);
    };
    let text = if markdown {
        page.markdown()
    } else {
        page.text()
    }
    .map_err(|e| vec![Error::input("keys", e.to_string())])?;
    crate::emit(&text);
    Ok(0)
}

/// `anholonomy models`: the shipped models, one line each.
pub fn models_cmd() -> Result<u8, Vec<Error>> {
    for (n, text) in anholonomy::init::models() {
        say!("{n:<20} {n}.urdf ({} bytes)", text.len());
    }
    say!("`anholonomy models export DIR [NAME...]` writes them.");
    Ok(0)
}

/// `anholonomy models export DIR [NAME...]`.
pub fn export_cmd(dir: &Path, names: &[String], force: bool) -> Result<u8, Vec<Error>> {
    for p in anholonomy::init::export_models(dir, names, force)? {
        say!("wrote {}", anholonomy::echo::path(&p));
    }
    Ok(0)
}

/// `anholonomy init DIR`.
pub fn init_cmd(dir: &Path, from: Option<&str>) -> Result<u8, Vec<Error>> {
    for (name, verdict) in anholonomy::init::init(dir, from)? {
        say!("{name}: {verdict} (baseline written)");
    }
    say!(
        "wrote a starter repository in {} (anholonomy {}); try:\n  cd {} && anholonomy check scenarios/ --baseline baselines/ --report",
        anholonomy::echo::path(dir),
        anholonomy::init::VERSION,
        anholonomy::echo::path(dir)
    );
    Ok(0)
}
