//! `anholonomy fit`: the parameters of the twin (`model.*`) or of the
//! physics (`sim.*`) that bring a run closest to a reference.
//!
//! **The reference** is the scenario's own physics run (`sim`: the ideal
//! run, with the trial `model.*` values, is compared with the physics run,
//! with the trial `sim.*` values; each is made once when no key moves it),
//! or a recording ([`crate::recording`]): then the ideal run is compared
//! with it when every key is a `model.*` key, the physics run when every
//! key is a `sim.*` key. Every run replays the scenario's plan as planned
//! with the file's values: the commands the robot was given.
//!
//! **The residual** is the RMS over the reference's samples of the pose
//! error, the heading error counted as its arc at a length L:
//! sqrt(mean(|Δp|² + (L·Δθ)²)); L defaults to the robot's size (the
//! farthest wheel centre from the body's origin).
//!
//! **The search** ([`optim`]): a parallel scan, then argmin's Nelder–Mead;
//! then each parameter's **sensitivity** and **interval** from the residual
//! along its axis (see [`ParamResult`]).

pub mod optim;
pub mod output;
pub mod params;
pub mod size;

use crate::engine::replay;
use crate::error::Error;
use crate::integrate::Trajectory;
use crate::plan::Plan;
use crate::record::Track;
use crate::recording::align::{align, errors, rms, Alignment, Frame, PoseIndex};
use crate::recording::clock::{self, input_error};
use crate::recording::{Recording, Source};
use crate::runner::{ideal_run, replay_error, replay_options, RunOptions};
use crate::scenario::{KeyPath, ModelConfig, PlannerConfig, Scenario};
use crate::validate::Prepared;
pub use optim::{Phase, Progress};
pub use params::{Moves, Param, ParamArg};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// A recording's time offset: given, or fitted in a range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Offset {
    /// The recording time at which the commands start, s.
    Fixed(f64),
    /// Fitted within [lo, hi].
    Fit(f64, f64),
}

/// What the runs are compared with.
#[derive(Debug, Clone, PartialEq)]
pub enum Against {
    /// The scenario's own physics run.
    Sim,
    /// A recording.
    Recording {
        /// Where it is.
        source: Source,
        /// Its time offset.
        time_offset: Offset,
        /// Its frame.
        frame: Frame,
    },
}

/// How a fit is run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The heading's length L, m (default: the robot's size).
    pub length: Option<f64>,
    /// About this many evaluations at most.
    pub budget: usize,
}

/// The residual a failed trial counts as (far above any pose error).
const FAILED: f64 = 1e6;

/// The change of the residual an interval allows: 5 %.
pub const INTERVAL_RISE: f64 = 0.05;

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ParamResult {
    /// The key (`time_offset` for a recording's fitted offset).
    pub key: String,
    /// Which run it moves.
    pub moves: Option<Moves>,
    /// Its range.
    pub range: [f64; 2],
    /// Its value in the scenario, if known.
    pub nominal: Option<f64>,
    /// The fitted value.
    pub value: f64,
    /// How fast the residual grows away from the fit, m per unit of the
    /// parameter: sqrt of the curvature of the squared residual along this
    /// parameter's axis, from three evaluations around the fit. None when
    /// the residual does not grow (flat or noisy there).
    pub sensitivity: Option<f64>,
    /// The values of this parameter alone (the others fitted) at which the
    /// residual is [`INTERVAL_RISE`] above its minimum, from that parabola,
    /// within the range. None when flat.
    pub interval: Option<[f64; 2]>,
}

/// The pose errors of one evaluation.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Residual {
    /// sqrt(mean(|Δp|² + (L·Δθ)²)), m.
    pub residual: f64,
    /// RMS position error, m.
    pub position_rms: f64,
    /// RMS heading error, degrees (None without a heading).
    pub heading_rms_deg: Option<f64>,
    /// Samples compared.
    pub samples: usize,
}

/// What a fit found.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// The scenario.
    pub scenario: String,
    /// Its file.
    pub file: PathBuf,
    /// What the runs were compared with.
    pub reference: String,
    /// Which runs were compared.
    pub compared: &'static str,
    /// How a recording was lined up (empty for `sim`).
    pub alignment: String,
    /// L, m.
    pub length: f64,
    /// Where L comes from.
    pub length_from: String,
    /// The parameters (a fitted time offset last).
    pub params: Vec<ParamResult>,
    /// The scenario as written.
    pub before: Residual,
    /// At the fitted values.
    pub after: Residual,
    /// Evaluations made (the scan, the search, the sensitivities).
    pub evaluations: usize,
    /// Nelder–Mead iterations.
    pub iterations: u64,
    /// Whether the search converged (else its budget ended it).
    pub converged: bool,
    /// Trials that could not run (each counted as a residual of 1e6 m).
    pub failed: usize,
    /// The first such failure.
    pub first_failure: Option<String>,
    /// A recording's frame, and its reference as a scenario writes it
    /// (relative to the scenario's directory), for the TOML to paste.
    #[serde(skip)]
    pub compare: Option<(String, Frame)>,
}

/// Which runs a fit compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pair {
    /// Ideal (trial) vs physics (trial).
    IdealSim,
    /// Ideal (trial) vs the recording.
    IdealReal,
    /// Physics (trial) vs the recording.
    SimReal,
}

impl Pair {
    fn text(self) -> &'static str {
        match self {
            Pair::IdealSim => "the ideal run with the physics run",
            Pair::IdealReal => "the ideal run with the recording",
            Pair::SimReal => "the physics run with the recording",
        }
    }
}

/// Whether the physics may read `key` (a declared model's parameter that
/// no drive expression names does not reach it; any other model key may).
fn physics_reads(sc: &Scenario, key: &str) -> bool {
    let Ok(kp) = KeyPath::parse(key) else {
        return true;
    };
    if kp.root() == "sim" {
        return true;
    }
    match (&sc.model, kp.0.as_slice()) {
        (ModelConfig::Declared(cfg), [_, params, crate::scenario::keypath::Segment::Key(name)])
            if *params == crate::scenario::keypath::Segment::Key("params".into()) =>
        {
            cfg.drive
                .values()
                .chain(cfg.drive_position.values())
                .any(|e| names_identifier(e, name))
        }
        _ => true,
    }
}

/// Whether expression text `e` uses the identifier `name`.
fn names_identifier(e: &str, name: &str) -> bool {
    e.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .any(|w| w == name)
}

/// A run with a plan on a prepared scenario: the ideal run's or the
/// physics replay's trajectory.
fn physics_run(prep: &Prepared, plan: &Plan) -> Result<Trajectory, Error> {
    let mut sys = prep.physics()?;
    let opts = replay_options(prep, &RunOptions::default());
    replay(sys.as_mut(), plan, &opts, &mut ())
        .map(|s| s.traj)
        .map_err(|e| replay_error(prep, e))
}

/// The fixed part of an evaluation: what is compared with what.
struct Setup<'a> {
    prep: &'a Prepared,
    params: &'a [Param],
    pair: Pair,
    idx: PoseIndex,
    length: f64,
    /// `sim`: the run no key moves, made once.
    fixed_ideal: Option<Trajectory>,
    fixed_sim: Option<Trajectory>,
    /// A recording: the recording, its clock shift, frame, and (when not
    /// fitted) its track.
    recording: Option<(Recording, f64, Frame)>,
    fixed_track: Option<Track>,
    /// The runs' span, s.
    end: f64,
    start: [f64; 3],
    failed: AtomicUsize,
    first_failure: Mutex<Option<String>>,
}

impl Setup<'_> {
    /// The residual with the parameters at `x` (a fitted offset last).
    fn evaluate(&self, x: &[f64]) -> Result<Residual, Error> {
        let values: BTreeMap<String, f64> = self
            .params
            .iter()
            .zip(x)
            .map(|(p, v)| (p.key.clone(), *v))
            .collect();
        let variant;
        let prep = if values.is_empty() {
            self.prep
        } else {
            variant = self.prep.variant(&params::variant(values))?;
            &variant
        };
        let plan = &self.prep.planned;
        let cancel = crate::cancel::Cancel::default();
        let need_ideal = self.pair != Pair::SimReal && self.fixed_ideal.is_none();
        let need_sim = self.pair != Pair::IdealReal && self.fixed_sim.is_none();
        let (ideal, sim) = rayon::join(
            || {
                need_ideal
                    .then(|| ideal_run(prep, plan, &cancel))
                    .transpose()
            },
            || need_sim.then(|| physics_run(prep, plan)).transpose(),
        );
        let (ideal, sim) = (ideal?, sim?);
        let ideal = ideal.as_ref().or(self.fixed_ideal.as_ref());
        let sim = sim.as_ref().or(self.fixed_sim.as_ref());
        let track;
        let (reference, run) = match self.pair {
            Pair::IdealSim => {
                let s = sim.expect("a physics run");
                track = self.idx.track(s, "physics");
                (&track, ideal.expect("an ideal run"))
            }
            Pair::IdealReal | Pair::SimReal => {
                let run = if self.pair == Pair::IdealReal {
                    ideal
                } else {
                    sim
                };
                let t = match &self.fixed_track {
                    Some(t) => t,
                    None => {
                        let (rec, shared, frame) = self.recording.as_ref().expect("a recording");
                        let a = Alignment {
                            shared: *shared,
                            time_offset: x[x.len() - 1],
                            frame: *frame,
                        };
                        track = align(rec, &a, self.start, self.end)
                            .map_err(|e| input_error(e, "--time-offset"))?;
                        &track
                    }
                };
                (t, run.expect("a run"))
            }
        };
        let e = errors(reference, run, &self.idx);
        Ok(Residual {
            residual: e.residual(self.length),
            position_rms: rms(&e.position),
            heading_rms_deg: self.idx.heading.map(|_| rms(&e.heading).to_degrees()),
            samples: e.t.len(),
        })
    }

    /// The residual at `x`, a failure counted as [`FAILED`].
    fn value(&self, x: &[f64]) -> f64 {
        match self.evaluate(x) {
            Ok(r) => r.residual,
            Err(e) => {
                self.failed.fetch_add(1, Ordering::SeqCst);
                let mut f = self.first_failure.lock().unwrap_or_else(|p| p.into_inner());
                if f.is_none() {
                    *f = Some(e.to_string());
                }
                FAILED
            }
        }
    }
}

/// What `fit` refuses before anything runs: a sweep, a feedback law, a
/// model without a planar pose, twin and physics keys against one
/// recording. The model's planar pose.
fn preconditions(
    prep: &Prepared,
    args: &[ParamArg],
    against: &Against,
) -> Result<PoseIndex, Error> {
    let sc = &prep.scenario;
    if sc.sweep.is_some() {
        return Err(sc.error_at(
            "sweep",
            "fit works on single runs: drop [sweep] (or fit a copy without it)",
        ));
    }
    if !prep.system.same_commands(&prep.planned) {
        return Err(sc.error_at(
            "planner.kind",
            format!(
                "fit replays the plan's commands, a function of time; `{}` is a feedback law (each run closes the loop on its own state): replay the commands it sent with a file plan (e.g. a bag's /cmd_vel)",
                sc.planner.kind()
            ),
        ));
    }
    let Some(idx) = PoseIndex::of(prep.model()) else {
        return Err(sc.error_at(
            "model.kind",
            format!(
                "model `{}` has no planar position (x, y): fit compares planar poses",
                sc.model.kind()
            ),
        ));
    };
    if matches!(against, Against::Recording { .. }) {
        let root = |a: &ParamArg| a.key.split(['.', '[']).next().unwrap_or("").to_string();
        let roots: Vec<String> = args.iter().map(root).collect();
        if roots.iter().any(|r| r == "model") && roots.iter().any(|r| r == "sim") {
            return Err(Error::input(
                "--param",
                "against a recording, fit the twin (`model.*` keys: the ideal run is compared with it) or the physics (`sim.*` keys: the physics run is), not both in one call",
            ));
        }
    }
    Ok(idx)
}

/// What a fit compares with, made ready: the pair of runs, a recording
/// (lined up once when its offset is given), and how to say it.
struct Reference {
    pair: Pair,
    recording: Option<(Recording, f64, Frame)>,
    fixed_track: Option<Track>,
    text: String,
    alignment: String,
    compare: Option<(String, Frame)>,
    /// A fitted time offset's range.
    offset: Option<(f64, f64)>,
}

fn reference(
    prep: &Prepared,
    params: &[Param],
    against: &Against,
    start: [f64; 3],
    end: f64,
) -> Result<Reference, Error> {
    let sc = &prep.scenario;
    let all = |m: Moves| params.iter().all(|p| p.moves == m);
    let mut offset_param = None;
    let (pair, recording, fixed_track, text, alignment, compare) = match against {
        Against::Sim => (
            Pair::IdealSim,
            None,
            None,
            "the scenario's physics run".to_string(),
            String::new(),
            None,
        ),
        Against::Recording {
            source,
            time_offset,
            frame,
        } => {
            let pair = if all(Moves::Model) {
                Pair::IdealReal
            } else {
                Pair::SimReal
            };
            let plan_params = match &sc.planner {
                PlannerConfig::File(p) => Some(p),
                _ => None,
            };
            let clocked = clock::read(source, plan_params, prep.model().input_names())
                .map_err(|e| input_error(e, "--against"))?;
            let (rec, shared, how) = (clocked.recording, clocked.shared, clocked.how);
            let a = |off: f64| Alignment {
                shared,
                time_offset: off,
                frame: *frame,
            };
            let (track, how) = match *time_offset {
                Offset::Fixed(off) => {
                    let t = align(&rec, &a(off), start, end)
                        .map_err(|e| input_error(e, "--time-offset"))?;
                    (
                        Some(t),
                        format!("{how}; time offset {} s", crate::numfmt::readable(off)),
                    )
                }
                Offset::Fit(lo, hi) => {
                    // It must overlap somewhere in the range.
                    let mid = 0.5 * (lo + hi);
                    align(&rec, &a(mid), start, end)
                        .map_err(|e| input_error(e, "--time-offset"))?;
                    offset_param = Some((lo, hi));
                    (
                        None,
                        format!(
                            "{how}; time offset fitted in {}..{} s",
                            crate::numfmt::readable(lo),
                            crate::numfmt::readable(hi)
                        ),
                    )
                }
            };
            let how = format!("{how}; frame `{}`", frame.name());
            let rel = relative_to(source, sc.path.parent().unwrap_or(Path::new(".")));
            (
                pair,
                Some((rec, shared, *frame)),
                track,
                source.describe(),
                how,
                Some((rel, *frame)),
            )
        }
    };
    Ok(Reference {
        pair,
        recording,
        fixed_track,
        text,
        alignment,
        compare,
        offset: offset_param,
    })
}

/// Each parameter's sensitivity and interval from the residual at the fit
/// (`r0`) and at the two probes along its axis (`probes`, `values`: two per
/// parameter, in the unit box).
fn results(
    best: &[f64],
    r0: f64,
    probes: &[Vec<f64>],
    values: &[f64],
    ranges: &[(f64, f64)],
    params: &[Param],
    nominal_offset: Option<f64>,
) -> Vec<ParamResult> {
    let x_best: Vec<f64> = best
        .iter()
        .zip(ranges)
        .map(|(u, (lo, hi))| lo + u * (hi - lo))
        .collect();
    let mut results = Vec::new();
    for (d, (lo, hi)) in ranges.iter().enumerate() {
        let w = hi - lo;
        let mut pts = vec![(best[d], r0 * r0)];
        for k in 0..2 {
            pts.push((probes[2 * d + k][d], values[2 * d + k].powi(2)));
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts.dedup_by(|a, b| a.0 == b.0);
        let curvature = if pts.len() == 3 {
            let [(xa, ya), (xb, yb), (xc, yc)] = [pts[0], pts[1], pts[2]];
            let a_u = ((yc - yb) / (xc - xb) - (yb - ya) / (xb - xa)) / (xc - xa);
            Some(a_u / (w * w))
        } else {
            None
        };
        let sensitivity = curvature
            .filter(|a| *a > 0.0 && a.is_finite())
            .map(f64::sqrt);
        let value = x_best[d];
        let interval = sensitivity.map(|sq| {
            let half = r0 * (((1.0 + INTERVAL_RISE).powi(2) - 1.0).sqrt()) / sq;
            [(value - half).max(*lo), (value + half).min(*hi)]
        });
        let (key, moves, nominal) = match params.get(d) {
            Some(p) => (p.key.clone(), Some(p.moves), p.nominal),
            None => ("time_offset".to_string(), None, nominal_offset),
        };
        results.push(ParamResult {
            key,
            moves,
            range: [*lo, *hi],
            nominal,
            value,
            sensitivity,
            interval,
        });
    }
    results
}

/// Fit `args` of a prepared scenario against `against`; `progress` sees
/// every evaluation.
pub fn fit(
    prep: &Prepared,
    args: &[ParamArg],
    against: &Against,
    s: &Settings,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, Error> {
    let sc = &prep.scenario;
    let idx = preconditions(prep, args, against)?;
    let params = params::resolve(prep, args)?;
    let (length, length_from) = match (s.length, size::robot_size(&prep.robot)) {
        (Some(l), _) => (l, "--length".to_string()),
        (None, Some((l, from))) => (l, from.to_string()),
        (None, None) => (1.0, "a robot of one link: 1 m (set --length)".to_string()),
    };
    let (start, _) = prep.start_goal();
    let start = idx.pose(start.as_slice());
    let end = crate::integrate::step_count(prep.planned.duration + sc.sim.settle, sc.sim.dt) as f64
        * sc.sim.dt;
    let Reference {
        pair,
        recording,
        fixed_track,
        text: reference,
        alignment,
        compare,
        offset: offset_param,
    } = self::reference(prep, &params, against, start, end)?;
    let moved_sim = params.iter().any(|p| physics_reads(sc, &p.key));
    let moved_ideal = params
        .iter()
        .any(|p| p.moves == Moves::Model || p.key == "sim.dt");
    let cancel = crate::cancel::Cancel::default();
    let plan = &prep.planned;
    let (fixed_ideal, fixed_sim) = if pair == Pair::IdealSim {
        let (i, p) = rayon::join(
            || {
                (!moved_ideal)
                    .then(|| ideal_run(prep, plan, &cancel))
                    .transpose()
            },
            || (!moved_sim).then(|| physics_run(prep, plan)).transpose(),
        );
        (i?, p?)
    } else {
        (None, None)
    };
    let setup = Setup {
        prep,
        params: &params,
        pair,
        idx,
        length,
        fixed_ideal,
        fixed_sim,
        recording,
        fixed_track,
        end,
        start,
        failed: AtomicUsize::new(0),
        first_failure: Mutex::new(None),
    };
    // The box: each parameter's range, then a fitted offset's.
    let mut ranges: Vec<(f64, f64)> = params.iter().map(|p| (p.lo, p.hi)).collect();
    ranges.extend(offset_param);
    let to_x = |u: &[f64]| -> Vec<f64> {
        u.iter()
            .zip(&ranges)
            .map(|(u, (lo, hi))| lo + u * (hi - lo))
            .collect()
    };
    let f = |u: &[f64]| setup.value(&to_x(u));
    let obj = optim::Objective::new(&f, s.budget, progress);
    // The scenario as written (a fitted offset at 0, within its range).
    let nominal_offset = offset_param.map(|(lo, hi)| 0.0f64.clamp(lo, hi));
    let before = {
        let mut x: Vec<f64> = Vec::new();
        let base_prep_residual = |x: &[f64]| -> Result<Residual, Error> {
            let empty: [Param; 0] = [];
            let base = Setup {
                params: &empty,
                ..setup.shallow()
            };
            base.evaluate(x)
        };
        x.extend(nominal_offset);
        base_prep_residual(&x)?
    };
    let start_u: Vec<f64> = params
        .iter()
        .map(|p| {
            p.nominal
                .map_or(0.5, |v| ((v - p.lo) / (p.hi - p.lo)).clamp(0.0, 1.0))
        })
        .chain(
            nominal_offset
                .zip(offset_param)
                .map(|(v, (lo, hi))| (v - lo) / (hi - lo)),
        )
        .collect();
    let found = optim::minimize(&obj, &start_u, s.budget);
    // Sensitivities: three points along each axis, in parallel.
    obj.phase(Phase::Sensitivity);
    let h = 0.02;
    let mut probes: Vec<Vec<f64>> = Vec::new();
    for d in 0..start_u.len() {
        for side in [-1.0, 1.0] {
            let mut u = found.best.clone();
            let mut step = side * h;
            if !(0.0..=1.0).contains(&(u[d] + step)) {
                step = -side * 2.0 * h;
            }
            u[d] += step;
            probes.push(u);
        }
    }
    let values = obj.batch(&probes);
    let x_best = to_x(&found.best);
    let after = setup.evaluate(&x_best)?;
    let r0 = after.residual;
    let results = results(
        &found.best,
        r0,
        &probes,
        &values,
        &ranges,
        &params,
        nominal_offset,
    );
    let first_failure = setup
        .first_failure
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .clone();
    Ok(Report {
        scenario: sc.name.clone(),
        file: sc.path.clone(),
        reference,
        compared: pair.text(),
        alignment,
        length,
        length_from,
        params: results,
        before,
        after,
        evaluations: obj.evaluations(),
        iterations: found.iterations,
        converged: found.converged,
        failed: setup.failed.load(Ordering::SeqCst),
        first_failure,
        compare,
    })
}

impl<'a> Setup<'a> {
    /// The same comparison, for evaluating the scenario as written.
    fn shallow(&self) -> Setup<'a> {
        Setup {
            prep: self.prep,
            params: self.params,
            pair: self.pair,
            idx: self.idx,
            length: self.length,
            fixed_ideal: self.fixed_ideal.clone(),
            fixed_sim: self.fixed_sim.clone(),
            recording: self.recording.clone(),
            fixed_track: self.fixed_track.clone(),
            end: self.end,
            start: self.start,
            failed: AtomicUsize::new(0),
            first_failure: Mutex::new(None),
        }
    }
}

/// A recording's reference as the scenario writes it: relative to the
/// scenario's directory when it is inside it.
fn relative_to(source: &Source, dir: &Path) -> String {
    let abs = |p: &Path| p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
    let (d, p) = (abs(dir), abs(source.path()));
    let shown = p
        .strip_prefix(&d)
        .map(Path::to_path_buf)
        .unwrap_or(p.clone());
    match source {
        Source::Csv(_) => shown.display().to_string(),
        Source::Bag { topic, frame, .. } => format!(
            "{}:{topic}{}",
            shown.display(),
            frame.as_ref().map(|f| format!(":{f}")).unwrap_or_default()
        ),
    }
}
