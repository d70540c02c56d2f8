//! Choosing the rectangle: candidate configurations (fixed side and value,
//! mirrored about the goal), goal branches θ̄0 + 2πk, the first feasible
//! cycle count of each, the joint-travel and duration limits, and the
//! cheapest of what remains (issue 13 item 1).
//!
//! With a fixed λ the far side γ exists only when one cycle can produce
//! θ̄0/n (|cos γ| ≤ 1), and the sign of the width λ − θ1f must match the sign
//! of the rotation: the paper's λ = 125° rotates the vehicle one way only,
//! its mirror 2θ1f − λ the other. With a fixed γ every rotation has a λ, but
//! large rotations give degenerate rectangles (λ of thousands of degrees).

use crate::numfmt::readable;
use crate::robots::space_robot::stokes::params::{
    check_params, Cost, FixedSide, StokesSpaceParams,
};
use crate::robots::space_robot::stokes::params::{PAPER_GAMMA_DEG, PAPER_LAMBDA_DEG};
use crate::robots::space_robot::stokes::*;

/// One configuration tried: a fixed side (λ or γ), its value, and where it came from.
#[derive(Debug, Clone, Copy)]
struct Config {
    side: FixedSide,
    value: f64,
    origin: &'static str,
}

impl Config {
    fn label(&self, theta0_bar: f64) -> String {
        let s = if self.side == FixedSide::Gamma {
            "γ"
        } else {
            "λ"
        };
        format!(
            "{s} = {:.3}° ({}), θ̄0 = {:.3}°",
            self.value.to_degrees(),
            self.origin,
            theta0_bar.to_degrees()
        )
    }
}

/// The configurations in the order tried: the configured one first (when
/// not `auto`), then its mirror and the paper's λ and γ with their mirrors.
fn configs(params: &StokesSpaceParams, g: [f64; 2]) -> Vec<Config> {
    let mirror = |side: FixedSide, v: f64| match side {
        FixedSide::Gamma => 2.0 * g[1] - v,
        _ => 2.0 * g[0] - v,
    };
    let mut out: Vec<Config> = Vec::new();
    let mut push = |c: Config| {
        let dup = out
            .iter()
            .any(|o| o.side == c.side && (o.value - c.value).abs() < 1e-9);
        if !dup {
            out.push(c);
        }
    };
    if let Some(v) = params.fixed_deg() {
        let v = v.to_radians();
        let side = params.fixed_side;
        push(Config {
            side,
            value: v,
            origin: "configured",
        });
        push(Config {
            side,
            value: mirror(side, v),
            origin: "configured, mirrored",
        });
    }
    for (side, v) in [
        (FixedSide::Lambda, PAPER_LAMBDA_DEG),
        (FixedSide::Gamma, PAPER_GAMMA_DEG),
    ] {
        let v = v.to_radians();
        push(Config {
            side,
            value: v,
            origin: "paper",
        });
        push(Config {
            side,
            value: mirror(side, v),
            origin: "paper, mirrored",
        });
    }
    out
}

/// A rectangle for one configuration and θ̄0.
struct Rect {
    cycles: usize,
    k: f64,
    lambda: f64,
    gamma: f64,
    width: f64,
    shift: f64,
    rejected: Vec<String>,
}

/// Why a configuration gave no rectangle.
enum Fail {
    /// The configured value itself is unusable (a parameter error).
    Invalid(PlanError),
    /// Every cycle count was rejected, with reasons.
    Rejected(Vec<String>),
}

/// The first cycle count n ∈ [cycles, max_cycles] whose rectangle exists
/// and meets the joint limit (translating it along BA when allowed).
fn rectangle(
    robot: &SpaceRobot,
    g: [f64; 2],
    theta0_bar: f64,
    cfg: &Config,
    params: &StokesSpaceParams,
    limit: Option<f64>,
) -> Result<Rect, Fail> {
    let fixed = cfg.value;
    let mut rejected = Vec::new();
    for n in params.cycles..=params.max_cycles {
        let k = k_per_cycle(robot, theta0_bar, n);
        let (lambda, gamma) = match cfg.side {
            FixedSide::Gamma => match solve_lambda(robot, g, fixed, k) {
                Some(l) => (l, fixed),
                None => return Err(Fail::Invalid(invalid(
                    "fixed_value_deg",
                    "cos γ = cos θ2f: such a rectangle is a repeatable motion and cannot rotate the vehicle",
                ))),
            },
            _ => {
                if (fixed - g[0]).abs() < 1e-12 {
                    return Err(Fail::Invalid(invalid(
                        "fixed_value_deg",
                        "λ equals the goal θ1: the rectangle has zero width",
                    )));
                }
                match solve_gamma(robot, g, fixed, k) {
                    Some(gm) => (fixed, gm),
                    None => {
                        rejected.push(format!(
                            "n = {n}: no real γ for λ = {:.3}°",
                            fixed.to_degrees()
                        ));
                        continue;
                    }
                }
            }
        };
        let w = lambda - g[0];
        let shift = match (params.shift_deg.map(f64::to_radians), limit) {
            (Some(s), _) if s > w.abs() + 1e-12 => {
                rejected.push(format!(
                    "n = {n}: shift {:.3}° exceeds the width {:.3}°",
                    s.to_degrees(),
                    w.abs().to_degrees()
                ));
                continue;
            }
            (Some(s), None) => s.min(w.abs()),
            (Some(s), Some(l)) => match feasible_shifts(g[0], w, l) {
                Some([lo, hi]) if s >= lo - 1e-12 && s <= hi + 1e-12 => s.min(w.abs()),
                _ => {
                    let sp = span(g, w, s);
                    rejected.push(format!(
                        "n = {n}: θ1 span [{:.3}°, {:.3}°] violates the limit",
                        sp[0].to_degrees(),
                        sp[1].to_degrees()
                    ));
                    continue;
                }
            },
            (None, None) => 0.0,
            (None, Some(l)) => match feasible_shifts(g[0], w, l) {
                Some([lo, hi]) => {
                    if lo <= 1e-12 {
                        0.0
                    } else if hi >= w.abs() - 1e-12 {
                        w.abs()
                    } else {
                        lo
                    }
                }
                None => {
                    rejected.push(format!(
                        "n = {n}: width {:.3}° does not fit within |θ1| ≤ {:.3}° by translation",
                        w.abs().to_degrees(),
                        l.to_degrees()
                    ));
                    continue;
                }
            },
        };
        // Snap near-corner translations so A is exactly a corner (4-leg loop).
        let shift = if shift < 1e-12 {
            0.0
        } else if (shift - w.abs()).abs() < 1e-12 {
            w.abs()
        } else {
            shift
        };
        return Ok(Rect {
            cycles: n,
            k,
            lambda,
            gamma,
            width: w,
            shift,
            rejected,
        });
    }
    Err(Fail::Rejected(rejected))
}

/// A feasible candidate with its measures.
struct Candidate {
    /// Index into the configurations (0 = the configured one, when not auto).
    config: usize,
    label: String,
    theta0_bar: f64,
    rect: Rect,
    legs: Vec<[f64; 2]>,
    travel: f64,
    duration: f64,
}

impl Candidate {
    fn cost(&self, c: Cost) -> f64 {
        match c {
            Cost::Duration => self.duration,
            Cost::Travel => self.travel,
        }
    }
}

/// The cheapest candidate (the first of equals).
fn cheapest<'a>(cands: impl Iterator<Item = &'a Candidate>, cost: Cost) -> Option<&'a Candidate> {
    cands.fold(None, |best, c| match best {
        Some(b) if b.cost(cost) <= c.cost(cost) => Some(b),
        _ => Some(c),
    })
}

/// Chooses the rectangle (cycles, λ, γ, translation) for start → goal;
/// cost by joint travel when no rate limits are given (see [`search`]).
pub fn design(
    robot: &SpaceRobot,
    start: &State,
    goal: &State,
    params: &StokesSpaceParams,
) -> Result<Design, PlanError> {
    search(robot, start, goal, params, None)
}

/// Chooses the rectangle for start → goal: every configuration (see
/// [`FixedSide`]) on every goal branch, the cheapest feasible plan within
/// the travel and duration limits. An explicit `fixed_side` is kept whenever
/// it gives such a plan; the others are tried only when it does not (and
/// `alternatives` allows). `limits` times the legs for the duration (without
/// them the duration is taken as the travel at 1 rad/s).
pub fn search(
    robot: &SpaceRobot,
    start: &State,
    goal: &State,
    params: &StokesSpaceParams,
    limits: Option<&Limits>,
) -> Result<Design, PlanError> {
    robot
        .validate()
        .map_err(|r| invalid("model", r.to_string()))?;
    check_params(params)?;
    check_state("start", start)?;
    check_state("goal", goal)?;
    let g = [goal[1], goal[2]];
    let limit = params.theta1_limit_deg.map(f64::to_radians);
    if let Some(l) = limit {
        for (name, q) in [("start", start), ("goal", goal)] {
            if q[1].abs() > l + 1e-12 {
                return Err(PlanError::Unreachable(format!(
                    "{name} θ1 = {:.3}° violates the joint limit |θ1| ≤ {:.3}°",
                    q[1].to_degrees(),
                    l.to_degrees()
                )));
            }
        }
    }
    let drift_oa = segment_rotation(robot, [start[1], start[2]], g);
    let theta0_d = start[0] + drift_oa;
    let mut theta0_bar = goal[0] - theta0_d;
    if params.wrap_vehicle_angle {
        theta0_bar = wrap(theta0_bar);
    }
    let oa = [g[0] - start[1], g[1] - start[2]];
    let mut d = Design {
        coeff_a: robot.coeff_a(),
        coeff_b: robot.coeff_b(),
        drift_oa,
        theta0_d,
        theta0_bar,
        cycles: 0,
        k: 0.0,
        lambda: g[0],
        gamma: g[1],
        width: 0.0,
        shift: 0.0,
        theta1_span: [g[0], g[0]],
        cycle_legs: vec![],
        rejected: vec![],
        choice: "none needed".into(),
        joint_travel: oa[0].abs() + oa[1].abs(),
    };
    if theta0_bar.abs() < 1e-14 {
        return Ok(d);
    }
    let explicit = params.fixed_side != FixedSide::Auto;
    let mut cfgs = configs(params, g);
    if explicit && !params.alternatives {
        cfgs.truncate(1);
    }
    // The goal branches θ̄0 + 2πk, nearest first.
    let branches: &[f64] = if params.wrap_vehicle_angle {
        &[0.0, -1.0, 1.0]
    } else {
        &[0.0]
    };
    let measure = |legs: &[[f64; 2]], n: usize| {
        let leg_travel = |l: &[f64; 2]| l[0].abs() + l[1].abs();
        let travel = leg_travel(&oa) + n as f64 * legs.iter().map(leg_travel).sum::<f64>();
        let duration = match limits {
            Some(lim) => {
                let time = |l: &[f64; 2]| lim.profile(&Input::from_vec(l.to_vec())).duration;
                time(&oa) + n as f64 * legs.iter().map(time).sum::<f64>()
            }
            None => travel,
        };
        (travel, duration)
    };
    let mut feasible: Vec<Candidate> = Vec::new();
    let mut over: Vec<(Candidate, String, &str)> = Vec::new();
    let mut reasons: Vec<String> = Vec::new();
    for (ci, cfg) in cfgs.iter().enumerate() {
        for k in branches {
            let bar = theta0_bar + 2.0 * PI * k;
            let label = cfg.label(bar);
            let rect = match rectangle(robot, g, bar, cfg, params, limit) {
                Ok(r) => r,
                Err(Fail::Invalid(e)) if explicit && ci == 0 => return Err(e),
                Err(Fail::Invalid(e)) => {
                    reasons.push(format!("[{label}] {e}"));
                    break; // the same for every branch
                }
                Err(Fail::Rejected(r)) => {
                    reasons.push(format!("[{label}] {}", summarize_rejections(&r)));
                    continue;
                }
            };
            let legs = cycle_legs(g, rect.width, rect.gamma, rect.shift);
            let (travel, duration) = measure(&legs, rect.cycles);
            let c = Candidate {
                config: ci,
                label,
                theta0_bar: bar,
                rect,
                legs,
                travel,
                duration,
            };
            let travel_deg = travel.to_degrees();
            if travel_deg > params.max_joint_travel_deg {
                let why = format!(
                    "joint travel {}° over max_joint_travel_deg = {}",
                    readable(travel_deg),
                    readable(params.max_joint_travel_deg)
                );
                reasons.push(format!("[{}] {why}", c.label));
                over.push((c, why, "max_joint_travel_deg"));
            } else if limits.is_some() && duration > params.max_duration_s {
                let why = format!(
                    "duration {} s over max_duration_s = {}",
                    readable(duration),
                    readable(params.max_duration_s)
                );
                reasons.push(format!("[{}] {why}", c.label));
                over.push((c, why, "max_duration_s"));
            } else {
                feasible.push(c);
            }
        }
    }
    // An explicit choice is kept when it gives a plan.
    let primary = explicit
        .then(|| cheapest(feasible.iter().filter(|c| c.config == 0), params.cost))
        .flatten();
    let best = primary.or_else(|| cheapest(feasible.iter(), params.cost));
    let Some(best) = best else {
        let tried = format!(
            "no rectangle with {} to {} cycles is feasible",
            params.cycles, params.max_cycles
        );
        let single = cfgs.len() == 1 && branches.len() == 1;
        if let Some((c, why, key)) = over
            .iter()
            .min_by(|a, b| a.0.cost(params.cost).total_cmp(&b.0.cost(params.cost)))
        {
            return Err(PlanError::Unreachable(format!(
                "{tried} within the limits: the cheapest plan [{}, {} cycles, {} s] has {why} (raise planner.{key} to accept it); tried: {}",
                c.label,
                c.rect.cycles,
                readable(c.duration),
                reasons.join("; ")
            )));
        }
        let detail = if single {
            reasons
                .iter()
                .map(|r| r.split_once("] ").map_or(r.as_str(), |(_, b)| b))
                .collect::<Vec<_>>()
                .join("; ")
        } else {
            reasons.join("; ")
        };
        return Err(PlanError::Unreachable(format!("{tried}: {detail}")));
    };
    let r = &best.rect;
    d.theta0_bar = best.theta0_bar;
    d.cycles = r.cycles;
    d.k = r.k;
    d.lambda = r.lambda;
    d.gamma = r.gamma;
    d.width = r.width;
    d.shift = r.shift;
    d.theta1_span = span(g, r.width, r.shift);
    d.cycle_legs = best.legs.clone();
    d.choice = best.label.clone();
    d.joint_travel = best.travel;
    d.rejected = r.rejected.clone();
    // What else was tried, and why it lost.
    for c in feasible.iter().filter(|c| !std::ptr::eq(*c, best)) {
        d.rejected.push(format!(
            "[{}] feasible but costlier ({} cycles, {} s, {}° travel)",
            c.label,
            c.rect.cycles,
            readable(c.duration),
            readable(c.travel.to_degrees())
        ));
    }
    d.rejected.extend(reasons);
    Ok(d)
}
