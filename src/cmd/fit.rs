//! `anholonomy fit FILE --param KEY[=LO..HI]... [--against sim|BAG:TOPIC|CSV]`.

use anholonomy::error::Error;
use anholonomy::fit::{self, Against, Offset, ParamArg, Phase, Progress, Settings};
use anholonomy::recording::align::Frame;
use anholonomy::recording::Source;
use anholonomy::validate::{prepare_all, Call};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};

/// Arguments of `anholonomy fit`.
#[derive(clap::Args, Debug)]
pub struct FitArgs {
    /// The scenario file.
    pub file: PathBuf,
    /// A number to fit, with its range (repeat for several): a `model.*`
    /// key (the twin: `model.params.eta=0.5..1`) or a `sim.*` key (the
    /// physics: `sim.friction=0.3..1.5`, `sim.perturb.wheel_radius_scale=0.9..1.1`).
    /// Without a range: half to twice the scenario's value.
    #[arg(long = "param", value_name = "KEY[=LO..HI]", required = true)]
    pub params: Vec<String>,
    /// What the runs are compared with: `sim` (the scenario's own physics
    /// run: the ideal run is fitted to it), a recording `BAG:TOPIC` (an
    /// Odometry, PoseStamped or PoseWithCovarianceStamped topic of a rosbag2
    /// bag), `BAG:/tf:FRAME` (a tf child frame) or a CSV `t,x,y,theta`
    /// [default: the scenario's `[compare] reference`, else `sim`].
    #[arg(long, value_name = "sim|BAG:TOPIC|CSV")]
    pub against: Option<String>,
    /// A recording's time at which the plan's commands start, s, or a range
    /// LO..HI to fit it in [default: the scenario's `[compare] time_offset`,
    /// else 0; a recording in the plan's own bag is on the bag's clock].
    #[arg(long, value_name = "S|LO..HI", allow_hyphen_values = true)]
    pub time_offset: Option<String>,
    /// A recording's frame: `start` (moved so that its pose at the first
    /// command is the scenario's start), `recorded` (its coordinates are
    /// the scenario's) or `fit` (laid over the run by the best rotation and
    /// shift, for a noisy start) [default: the scenario's `[compare] frame`,
    /// else start].
    #[arg(long, value_name = "start|recorded|fit")]
    pub frame: Option<String>,
    /// The length L, m, at which a heading error counts as a position
    /// error in the residual sqrt(mean(|dp|^2 + (L dtheta)^2)) [default: the
    /// robot's size, its farthest wheel centre from the body's origin].
    #[arg(long, value_name = "L", allow_negative_numbers = true)]
    pub length: Option<f64>,
    /// About this many evaluations at most (each one run per trial).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 200,
        allow_negative_numbers = true
    )]
    pub max_evals: i64,
    /// Print the result as JSON: {"params": {KEY: value}, "residual_before", "residual_after", ...}.
    #[arg(long)]
    pub json: bool,
    /// Print nothing on stderr while fitting.
    #[arg(long)]
    pub quiet: bool,
    /// Step budget per run (as for `run`).
    #[arg(long, value_name = "N", default_value_t = anholonomy::validate::DEFAULT_MAX_STEPS)]
    pub max_steps: u64,
}

fn bad(opt: &str, m: impl Into<String>) -> Vec<Error> {
    vec![Error::input(opt, m.into())]
}

/// `--time-offset`: a number or LO..HI.
fn parse_offset(s: &str) -> Result<Offset, Vec<Error>> {
    let num = |x: &str| x.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    if let Some((lo, hi)) = s.split_once("..") {
        let (Some(lo), Some(hi)) = (num(lo), num(hi)) else {
            return Err(bad(
                "--time-offset",
                format!("`{s}`: write seconds, or a range LO..HI"),
            ));
        };
        if lo >= hi {
            return Err(bad(
                "--time-offset",
                format!(
                    "`{s}`: {} range: write LO..HI with LO < HI",
                    if lo == hi { "an empty" } else { "an inverted" }
                ),
            ));
        }
        return Ok(Offset::Fit(lo, hi));
    }
    num(s).map(Offset::Fixed).ok_or_else(|| {
        bad(
            "--time-offset",
            format!("`{s}`: write seconds, or a range LO..HI"),
        )
    })
}

/// What to compare with, from the options and the scenario's `[compare]`.
fn against(a: &FitArgs, prep: &anholonomy::validate::Prepared) -> Result<Against, Vec<Error>> {
    let sc = &prep.scenario;
    let cfg = sc.compare.as_ref();
    // Paths on the command line as typed (relative to the working directory).
    let here = Path::new("");
    let (source, base_offset, base_frame) = match (&a.against, cfg) {
        (Some(s), _) if s == "sim" => (None, 0.0, Frame::Start),
        (Some(s), _) => (
            Some(Source::parse(s, here).map_err(|e| bad("--against", e.to_string()))?),
            0.0,
            Frame::Start,
        ),
        (None, Some(c)) => (
            Some(
                Source::parse(&c.reference, sc.path.parent().unwrap_or(Path::new(".")))
                    .map_err(|e| vec![sc.error_at("compare.reference", e)])?,
            ),
            c.time_offset,
            c.frame,
        ),
        (None, None) => (None, 0.0, Frame::Start),
    };
    let Some(source) = source else {
        for (opt, given) in [
            ("--time-offset", a.time_offset.is_some()),
            ("--frame", a.frame.is_some()),
        ] {
            if given {
                return Err(bad(
                    opt,
                    "only with a recording (`--against BAG:TOPIC` or a CSV)",
                ));
            }
        }
        return Ok(Against::Sim);
    };
    let time_offset = match &a.time_offset {
        Some(s) => parse_offset(s)?,
        None => Offset::Fixed(base_offset),
    };
    let frame = match &a.frame {
        Some(f) => Frame::parse(f)
            .ok_or_else(|| bad("--frame", format!("`{f}`: one of start, recorded, fit")))?,
        None => base_frame,
    };
    Ok(Against::Recording {
        source,
        time_offset,
        frame,
    })
}

fn progress_bar(quiet: bool, budget: usize) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(budget as u64), target);
    if let Ok(style) =
        ProgressStyle::with_template("fit [{bar:30}] {pos}/~{len} evaluations {msg} {elapsed}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// `anholonomy fit`: exit 0, 2 (bad input, nothing fitted) or 3 (a run failed).
pub fn fit_cmd(a: &FitArgs) -> Result<u8, Vec<Error>> {
    let args: Vec<ParamArg> = a
        .params
        .iter()
        .map(|p| ParamArg::parse(p))
        .collect::<Result<_, _>>()
        .map_err(|e| vec![e])?;
    if let Some(l) = a.length {
        if !(l.is_finite() && l >= 0.0) {
            return Err(bad("--length", format!("{l}: must be a length >= 0 m")));
        }
    }
    if !(10..=100_000).contains(&a.max_evals) {
        return Err(bad(
            "--max-evals",
            format!("{}: must be in 10..=100000", a.max_evals),
        ));
    }
    let call = Call {
        log_root: None,
        sharded: false,
        max_steps: Some(a.max_steps),
    };
    let preps = prepare_all(std::slice::from_ref(&a.file), &call)?;
    let prep = &preps[0];
    let against = against(a, prep)?;
    let budget = a.max_evals as usize;
    let bar = progress_bar(a.quiet, budget);
    let progress = |p: &Progress| {
        bar.set_position(p.evaluations as u64);
        let phase = match p.phase {
            Phase::Scan => "scan",
            Phase::Search => "search",
            Phase::Sensitivity => "sensitivity",
        };
        bar.set_message(format!(
            "({phase}, best {} m)",
            anholonomy::numfmt::readable(p.best)
        ));
    };
    let settings = Settings {
        length: a.length,
        budget,
    };
    let report = fit::fit(prep, &args, &against, &settings, &progress);
    bar.finish_and_clear();
    let report = report.map_err(|e| vec![e])?;
    if a.json {
        say!(
            "{}",
            serde_json::to_string_pretty(&fit::output::to_json(&report)).unwrap_or_default()
        );
    } else {
        crate::emit(&fit::output::text(&report));
    }
    Ok(0)
}
