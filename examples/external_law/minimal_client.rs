//! A minimal external feedback law for anholonomy in Rust (standard library
//! and serde_json only): the same law as `minimal_client.py`.
//!
//! The harness writes one JSON line per control sample to stdin
//! (`{"t": 0.0, "q": [...], "names": [...]}` first, `{"t": ..., "q": [...]}`
//! after) and reads one JSON line per sample from stdout
//! (`{"u": [...], "label": "...", "done": false}`). This law is for the
//! rolling disk (inputs theta_rate, alpha_rate): roll at a constant rate
//! and steer the heading alpha to 90 degrees with a proportional law;
//! report done after 3 s. Debug output goes to stderr. The law ends when
//! its stdin closes.
//!
//! Build: `cargo build --release --example minimal_client`; the scenario
//! `disk_heading_rust.toml` next to this file runs
//! `target/release/examples/minimal_client`.

use std::io::{BufRead, Write};

const ROLL_RATE: f64 = 2.0; // rad/s
const HEADING_GOAL: f64 = std::f64::consts::FRAC_PI_2; // rad
const GAIN: f64 = 2.0; // 1/s
const DONE_AFTER: f64 = 3.0; // s

/// The input vector, a label and whether the task is done.
fn law(t: f64, q: &[f64], names: &[String]) -> (Vec<f64>, &'static str, bool) {
    let alpha = names
        .iter()
        .position(|n| n == "alpha")
        .map(|i| q[i])
        .unwrap_or(0.0);
    let steer = -GAIN * (alpha - HEADING_GOAL);
    (vec![ROLL_RATE, steer], "steer", t >= DONE_AFTER)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let stdin = std::io::stdin().lock();
    let mut stdout = std::io::stdout().lock();
    let mut names: Vec<String> = Vec::new();
    for line in stdin.lines() {
        let msg: serde_json::Value = serde_json::from_str(&line?)?;
        if let Some(n) = msg.get("names") {
            names = serde_json::from_value(n.clone())?;
        }
        let t = msg["t"].as_f64().unwrap_or(f64::NAN);
        let q: Vec<f64> = serde_json::from_value(msg["q"].clone())?;
        let (u, label, done) = law(t, &q, &names);
        let answer = serde_json::json!({ "u": u, "label": label, "done": done });
        writeln!(stdout, "{answer}")?;
        stdout.flush()?;
    }
    Ok(())
}
