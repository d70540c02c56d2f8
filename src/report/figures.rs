//! The report's figures: a single run's paths, states, tracking errors,
//! commands and channels against time (shaded by the policy's mode), and a
//! sweep's distributions and table of variants.

use crate::log::series::{Series, SeriesFile};
use crate::report::markup::{esc, num, tracking_meaningful};
use crate::report::plots::{self, HLine, Line, Marker, Path2, PlotError, Shade};
use serde_json::Value;
use std::fmt::Write as _;

const DEG: f64 = 180.0 / std::f64::consts::PI;

fn scaled(s: &Series, scale: f64) -> Vec<Option<f64>> {
    s.v.iter().map(|v| v.map(|x| x as f64 * scale)).collect()
}

fn end_time(sf: &SeriesFile) -> f64 {
    [&sf.ideal, &sf.sim, &sf.errors, &sf.commands, &sf.channels]
        .iter()
        .flat_map(|g| g.iter())
        .filter_map(|s| s.t.last().copied())
        .fold(0.0f32, f32::max) as f64
}

/// Most shaded spans per chart: a feedback policy can switch labels every
/// sample period (hundreds of one-pixel spans, most of a page's bytes).
const MAX_SHADES: usize = 120;

/// Segment shading and the legend that names the colours. More than
/// [`MAX_SHADES`] spans are merged into that many equal time bins, each
/// shaded with the label that covers most of it.
fn shades(sf: &SeriesFile) -> (Vec<Shade>, String) {
    let mut names: Vec<&str> = Vec::new();
    let mut out = Vec::new();
    // The simulated run's own segments when it has them (a feedback policy
    // switches modes on the simulated state, and may run past the ideal run's end).
    let (segments, whose) = if sf.sim_segments.is_empty() {
        (&sf.segments, "Plan segments")
    } else {
        (&sf.sim_segments, "Plan segments of the simulated run")
    };
    for s in segments {
        let k = match names.iter().position(|n| *n == s.label) {
            Some(k) => k,
            None => {
                names.push(&s.label);
                names.len() - 1
            }
        };
        out.push((s.start, s.end, k));
    }
    if out.len() > MAX_SHADES {
        out = bin_shades(&out, MAX_SHADES);
    }
    let mut legend = format!("<p>{whose} (shaded in every time plot): ");
    for (k, n) in names.iter().enumerate() {
        let c = plots::label_color(k);
        let _ = write!(
            legend,
            "<span class=\"seg\"><i style=\"background:rgba({},{},{},0.35)\"></i>{}</span>",
            c.0,
            c.1,
            c.2,
            esc(n)
        );
    }
    legend.push_str("</p>");
    (out, legend)
}

/// `spans` merged into `n` equal time bins (each with the label covering
/// most of it), adjacent bins of one label joined.
fn bin_shades(spans: &[Shade], n: usize) -> Vec<Shade> {
    let (t0, t1) = (
        spans.first().map_or(0.0, |s| s.0),
        spans.last().map_or(0.0, |s| s.1),
    );
    let w = (t1 - t0) / n as f64;
    if w <= 0.0 {
        return spans.to_vec();
    }
    let mut out: Vec<Shade> = Vec::new();
    let mut j = 0;
    for b in 0..n {
        let (a, z) = (t0 + b as f64 * w, t0 + (b + 1) as f64 * w);
        let mut cover: Vec<(usize, f64)> = Vec::new();
        while j < spans.len() && spans[j].1 <= a {
            j += 1;
        }
        for s in spans[j..].iter().take_while(|s| s.0 < z) {
            let len = s.1.min(z) - s.0.max(a);
            match cover.iter_mut().find(|(k, _)| *k == s.2) {
                Some(c) => c.1 += len,
                None => cover.push((s.2, len)),
            }
        }
        let Some(&(k, _)) = cover.iter().max_by(|x, y| x.1.total_cmp(&y.1)) else {
            continue;
        };
        match out.last_mut() {
            Some(last) if last.2 == k && (last.1 - a).abs() < 1e-9 => last.1 = z,
            _ => out.push((a, z, k)),
        }
    }
    out
}

/// Display name, scale and unit of state coordinate `i`.
fn coord(sf: &SeriesFile, i: usize) -> (String, f64, &'static str) {
    let name = sf
        .state_names
        .get(i)
        .cloned()
        .unwrap_or_else(|| format!("q{i}"));
    if sf.angular.contains(&i) {
        (name, DEG, "deg")
    } else if sf.position.is_some_and(|p| p.contains(&i)) {
        (name, 1.0, "m")
    } else {
        (name, 1.0, "")
    }
}

fn unit_suffix(u: &str) -> String {
    if u.is_empty() {
        String::new()
    } else {
        format!(" ({u})")
    }
}

pub(super) fn single_figures(summary: &Value, sf: &SeriesFile) -> Result<String, PlotError> {
    let t_end = end_time(sf);
    let (sh, legend) = shades(sf);
    let th = |k: &str| summary["thresholds"][k].as_f64();
    let mut b = String::new();

    if let Some([ix, iy]) = sf.position {
        let mut paths = Vec::new();
        for o in sf.overlays.iter().filter(|o| o.link.is_none()) {
            paths.push(Path2 {
                name: "obstacles",
                points: o.points.iter().map(|p| (p[0], p[1])).collect(),
                color: plotters::style::RGBColor(
                    (o.rgba[0] * 255.0) as u8,
                    (o.rgba[1] * 255.0) as u8,
                    (o.rgba[2] * 255.0) as u8,
                ),
                width: 1,
            });
        }
        let pp = |p: &[[f32; 2]]| p.iter().map(|q| (q[0] as f64, q[1] as f64)).collect();
        let robots = std::iter::once(([ix, iy], &sf.path_ideal, &sf.path_sim)).chain(
            sf.other_robots
                .iter()
                .map(|r| (r.position, &r.ideal, &r.sim)),
        );
        let mut markers = Vec::new();
        for (r, ([ix, iy], ideal, sim)) in robots.enumerate() {
            paths.push(Path2 {
                name: "ideal",
                points: pp(ideal),
                color: plots::IDEAL,
                width: 3,
            });
            paths.push(Path2 {
                name: "simulated",
                points: pp(sim),
                color: plots::SIM,
                width: 2,
            });
            let at = |q: &[f64]| {
                (
                    q.get(ix).copied().unwrap_or(0.0),
                    q.get(iy).copied().unwrap_or(0.0),
                )
            };
            markers.push(Marker {
                name: "start",
                at: at(&sf.start),
                heading: None,
                color: plots::GREY,
            });
            markers.push(Marker {
                name: "goal",
                at: at(&sf.goal),
                // The goal heading is the first robot's.
                heading: sf.goal_heading.filter(|_| r == 0),
                color: plots::RED,
            });
        }
        if !sf.path_real.is_empty() {
            paths.push(Path2 {
                name: "recorded",
                points: pp(&sf.path_real),
                color: plots::REAL,
                width: 2,
            });
        }
        b.push_str("<h2>Planar path</h2><div class=\"grid\">");
        b.push_str(&plots::path_chart(&paths, &markers)?);
        b.push_str("</div>");
    }

    b.push_str("<h2>Tracking error (simulated − ideal)</h2>");
    b.push_str(&legend);
    b.push_str("<div class=\"grid\">");
    let errors: &[Series] = if tracking_meaningful(summary) {
        &sf.errors
    } else {
        let _ =
            write!(
            b,
            "<p class=\"muted\">Not shown: {}. Compare the final states and the paths instead.</p>",
            esc(summary["not_meaningful"]["tracking"].as_str().unwrap_or("not meaningful"))
        );
        &[]
    };
    for s in errors {
        let i = sf.state_names.iter().position(|n| *n == s.name);
        let (scale, unit, key) = match i {
            Some(i) => {
                let (_, sc, u) = coord(sf, i);
                let key = if sc == DEG {
                    format!("{}_deg", s.name)
                } else {
                    s.name.clone()
                };
                (sc, u, key)
            }
            None => (1.0, "m", s.name.clone()),
        };
        let mut hl = Vec::new();
        if let Some(m) = th(&format!("tracking_{key}_max")) {
            hl.push(HLine {
                y: m,
                name: format!("max threshold {m}"),
                color: plots::RED,
            });
            // Coordinate errors are signed; position errors (`position`,
            // `position_1`, …) are distances.
            if i.is_some() {
                hl.push(HLine {
                    y: -m,
                    name: String::new(),
                    color: plots::RED,
                });
            }
        }
        if let Some(m) = th(&format!("tracking_{key}_rms")) {
            hl.push(HLine {
                y: m,
                name: format!("rms threshold {m}"),
                color: plots::GREY,
            });
        }
        let line = Line {
            name: format!("error {}", s.name),
            t: &s.t,
            v: scaled(s, scale),
            color: plots::BLUE,
            step: false,
        };
        b.push_str(&plots::time_chart(
            &format!("tracking error: {}{}", s.name, unit_suffix(unit)),
            &format!("{}{}", s.name, unit_suffix(unit)),
            &[line],
            &hl,
            &sh,
            t_end,
        )?);
    }
    b.push_str("</div><h2>State: ideal vs simulated</h2><div class=\"grid\">");
    for (i, (a, s)) in sf.ideal.iter().zip(&sf.sim).enumerate() {
        let (name, scale, unit) = coord(sf, i);
        let lines = [
            Line {
                name: format!("{name} ideal"),
                t: &a.t,
                v: scaled(a, scale),
                color: plots::IDEAL,
                step: false,
            },
            Line {
                name: format!("{name} simulated"),
                t: &s.t,
                v: scaled(s, scale),
                color: plots::SIM,
                step: false,
            },
        ];
        let goal: Vec<HLine> = sf
            .goal
            .get(i)
            .map(|g| HLine {
                y: g * scale,
                name: "goal".into(),
                color: plots::RED,
            })
            .into_iter()
            .collect();
        b.push_str(&plots::time_chart(
            &format!("{name}{}", unit_suffix(unit)),
            &format!("{name}{}", unit_suffix(unit)),
            &lines,
            &goal,
            &sh,
            t_end,
        )?);
    }
    b.push_str("</div><h2>Commands</h2><div class=\"grid\">");
    for (k, c) in sf.commands.iter().enumerate() {
        let title = format!("command: {}", c.name);
        b.push_str(&one_series(
            &title,
            c,
            plots::series_color(k),
            true,
            &sh,
            t_end,
        )?);
    }
    b.push_str("</div>");
    if !sf.channels.is_empty() {
        b.push_str("<h2>Physics channels</h2><div class=\"grid\">");
        for c in &sf.channels {
            b.push_str(&one_series(&c.name, c, plots::BLUE, false, &sh, t_end)?);
        }
        b.push_str("</div>");
    }
    Ok(b)
}

/// A time chart of one series (a command or a channel), unscaled.
fn one_series(
    title: &str,
    c: &Series,
    color: plotters::style::RGBColor,
    step: bool,
    sh: &[Shade],
    t_end: f64,
) -> Result<String, PlotError> {
    let line = Line {
        name: c.name.clone(),
        t: &c.t,
        v: scaled(c, 1.0),
        color,
        step,
    };
    plots::time_chart(title, &c.name, &[line], &[], sh, t_end)
}

pub(super) fn sweep_figures(s: &Value) -> Result<String, PlotError> {
    let results = s["results"].as_array().cloned().unwrap_or_default();
    let f = |r: &Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    let cfg = &s["sweep"];
    let limit = cfg["success_max"].as_f64();
    let metric = cfg["success_metric"].as_str().unwrap_or("final error");
    let errors: Vec<f64> = results.iter().map(|r| f(r, "final_error")).collect();
    let times: Vec<f64> = results
        .iter()
        .filter(|r| r["success"].as_bool() == Some(true))
        .map(|r| f(r, "time_to_goal"))
        .collect();
    let mut b = String::from("<h2>Distributions</h2><div class=\"grid\">");
    b.push_str(&plots::histogram(
        &format!("final error ({metric})"),
        metric,
        &errors,
        20,
        limit.map(|l| (l, "success limit")),
    )?);
    match cfg["time_metric"].as_str() {
        Some(m) => b.push_str(&plots::histogram(
            &format!("time to goal, {m} (successes)"),
            "t (s)",
            &times,
            20,
            None,
        )?),
        None => b.push_str(
            "<p class=\"muted\">Time to goal: no time metric for this model (set <code>sweep.time_metric</code> to name one).</p>",
        ),
    }
    b.push_str("</div><h2>Success against each randomised parameter</h2><div class=\"grid\">");
    // Every swept parameter: the [sweep.vary] keys (and the friction shorthand) under
    // `params`, and the mass scale.
    let mut keys: Vec<String> = results
        .first()
        .and_then(|r| r["params"].as_object())
        .map(|m| m.keys().map(|k| format!("params/{k}")).collect())
        .unwrap_or_default();
    keys.push("mass_scale".into());
    let param = |r: &Value, key: &str| match key.strip_prefix("params/") {
        Some(k) => r["params"][k].as_f64().unwrap_or(f64::NAN),
        None => f(r, key),
    };
    let label_of = |key: &str| match key.strip_prefix("params/") {
        Some("sim.friction") => "friction coefficient (sim.friction)".to_string(),
        Some(k) => k.to_string(),
        None => "mass scale".to_string(),
    };
    // The keys whose values differ between variants (a failed variant's
    // values count too: its `params` are recorded like a success's).
    let varied: Vec<&String> = keys
        .iter()
        .filter(|key| {
            let vals: Vec<f64> = results
                .iter()
                .map(|r| param(r, key))
                .filter(|v| v.is_finite())
                .collect();
            vals.iter().any(|v| (v - vals[0]).abs() > 1e-12)
        })
        .collect();
    for key in &varied {
        let label = label_of(key);
        let label = label.as_str();
        let key = key.as_str();
        let pts: Vec<(f64, f64, bool)> = results
            .iter()
            .map(|r| {
                (
                    param(r, key),
                    f(r, "final_error"),
                    r["success"].as_bool() == Some(true),
                )
            })
            .collect();
        b.push_str(&plots::scatter(
            &format!("final error vs {label}"),
            label,
            metric,
            &pts,
            limit.map(|l| (l, "success limit")),
        )?);
    }
    if cfg["sigma_rate"].is_number() {
        // The σ signal differs per variant through its seed: plot against the variant index.
        let pts: Vec<(f64, f64, bool)> = results
            .iter()
            .map(|r| {
                (
                    f(r, "index"),
                    f(r, "final_error"),
                    r["success"].as_bool() == Some(true),
                )
            })
            .collect();
        b.push_str(&plots::scatter(
            "final error vs variant (σ seed)",
            "variant index",
            metric,
            &pts,
            limit.map(|l| (l, "success limit")),
        )?);
    }
    b.push_str("</div>");
    let failed: Vec<&Value> = results
        .iter()
        .filter(|r| r["success"].as_bool() != Some(true))
        .collect();
    if !failed.is_empty() {
        b.push_str("<h2>Failed variants</h2><table><tr><th>index</th>");
        for key in &varied {
            let _ = write!(b, "<th>{}</th>", esc(&label_of(key)));
        }
        b.push_str("<th>final error</th><th class=\"l\">error</th></tr>");
        for r in failed {
            let _ = write!(b, "<tr><td>{}</td>", r["index"]);
            for key in &varied {
                let _ = write!(b, "<td>{}</td>", num(Some(param(r, key))));
            }
            let _ = write!(
                b,
                "<td>{}</td><td class=\"l\">{}</td></tr>",
                num(r["final_error"].as_f64()),
                esc(r["error"].as_str().unwrap_or(""))
            );
        }
        b.push_str("</table>");
    }
    Ok(b)
}

#[cfg(test)]
mod shade_tests {
    use super::bin_shades;

    #[test]
    fn many_spans_become_at_most_n_bins_with_the_dominant_label() {
        // 470 spans of 20 ms alternating 0, 1, 0, 1 ..., with label 2 over [4, 6) s.
        let mut spans = Vec::new();
        for i in 0..470 {
            let (a, b) = (i as f64 * 0.02, (i + 1) as f64 * 0.02);
            let k = if (4.0..6.0).contains(&a) { 2 } else { i % 2 };
            spans.push((a, b, k));
        }
        let out = bin_shades(&spans, 120);
        assert!(out.len() <= 120, "{}", out.len());
        assert_eq!(out.first().unwrap().0, 0.0);
        assert!((out.last().unwrap().1 - 9.4).abs() < 1e-9);
        for w in out.windows(2) {
            assert!((w[0].1 - w[1].0).abs() < 1e-9 && w[0].2 != w[1].2);
        }
        // The long span keeps its label across its bins, merged into one.
        let long: Vec<_> = out.iter().filter(|s| s.2 == 2).collect();
        assert_eq!(long.len(), 1);
        assert!(long[0].0 <= 4.1 && long[0].1 >= 5.9, "{long:?}");
    }
}
