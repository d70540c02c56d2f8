//! Open-loop plans for the wheeled models made of legs (straight lines in
//! the space of integrated inputs, ramped at both ends), and where each leg
//! ends, computed independently of the harness: in arc length, with the
//! heading in closed form and the position by composite Simpson quadrature
//! (not the harness's RK4 in time).
#![allow(dead_code)]

use anholonomy::model::Input;
use anholonomy::plan::{plan_from_legs, Limits, Plan};

/// A plan of legs `(Δ∫u0, Δ∫u1)` with rate limits `max` and ramps of `ramp` s.
pub fn plan(legs: &[(f64, f64)], max: [f64; 2], ramp: f64, dt: f64) -> Plan {
    let lim = Limits {
        max_rate: max.to_vec(),
        ramp,
        step: dt,
    };
    let l = legs
        .iter()
        .map(|(a, b)| (0, Input::from_vec(vec![*a, *b])))
        .collect();
    plan_from_legs(vec!["leg".into()], l, &lim, serde_json::Value::Null)
}

/// ∫₀¹ f by composite Simpson with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> [f64; 2], n: usize) -> [f64; 2] {
    let h = 1.0 / n as f64;
    let mut acc = [0.0; 2];
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let v = f(i as f64 * h);
        acc[0] += w * v[0];
        acc[1] += w * v[1];
    }
    [acc[0] * h / 3.0, acc[1] * h / 3.0]
}

/// Position after a leg of arc length `ds` along heading θ(σ), σ ∈ [0, 1].
fn travel(x: f64, y: f64, ds: f64, theta: impl Fn(f64) -> f64) -> (f64, f64) {
    let [cx, cy] = simpson(
        |s| {
            let t = theta(s);
            [t.cos(), t.sin()]
        },
        4000,
    );
    (x + ds * cx, y + ds * cy)
}

/// Unicycle (x, y, θ) after a leg (Δs, Δθ): θ is linear in arc length.
pub fn unicycle_leg(q: [f64; 3], ds: f64, dth: f64) -> [f64; 3] {
    let (x, y) = travel(q[0], q[1], ds, |s| q[2] + dth * s);
    [x, y, q[2] + dth]
}

/// Unicycle (x, y, θ) after `(v, ω)` held for `tau`, in closed form (an arc,
/// or a straight line for |ω| < 1e-12).
pub fn unicycle_arc(q: [f64; 3], v: f64, w: f64, tau: f64) -> [f64; 3] {
    let [x, y, th] = q;
    if w.abs() < 1e-12 {
        return [x + v * tau * th.cos(), y + v * tau * th.sin(), th];
    }
    let th1 = th + w * tau;
    [
        x + v / w * (th1.sin() - th.sin()),
        y - v / w * (th1.cos() - th.cos()),
        th1,
    ]
}

/// One mobile manipulator (unicycle + six arm joints, `q` of 9) after the
/// input `u` (v, ω, six joint rates) held for `h`, in closed form.
pub fn mobile_manipulator_step(q: &mut [f64], u: &[f64], h: f64) {
    let [x, y, th] = unicycle_arc([q[0], q[1], q[2]], u[0], u[1], h);
    q[..3].copy_from_slice(&[x, y, th]);
    for a in 0..6 {
        q[3 + a] += u[2 + a] * h;
    }
}

/// Bicycle (x, y, θ, φ) after a leg (Δs, Δφ): φ is linear in arc length,
/// so θ(s) = θ0 + (ln cos φ0 − ln cos(φ0 + k s)) / (k L), k = Δφ/Δs.
pub fn bicycle_leg(q: [f64; 4], ds: f64, dphi: f64, wheelbase: f64) -> [f64; 4] {
    if ds == 0.0 {
        return [q[0], q[1], q[2], q[3] + dphi];
    }
    let (phi0, l) = (q[3], wheelbase);
    let k = dphi / ds;
    let theta = |s: f64| {
        let s = s * ds;
        if k.abs() < 1e-9 {
            q[2] + s * phi0.tan() / l
        } else {
            q[2] + (phi0.cos().ln() - (phi0 + k * s).cos().ln()) / (k * l)
        }
    };
    let (x, y) = travel(q[0], q[1], ds, theta);
    [x, y, theta(1.0), phi0 + dphi]
}
