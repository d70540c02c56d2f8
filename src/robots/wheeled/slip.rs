//! Metrics shared by the wheeled systems (rover, differential drive, car).

use crate::record::SimTrajectory;

/// Names of [`slip_metrics`].
pub const SLIP_METRICS: [&str; 2] = ["slip_lateral_max", "slip_longitudinal_max"];

/// The largest |slip| across and along any wheel over the physics run, m/s,
/// from the `slip_<wheel>_lat` and `slip_<wheel>_lon` channels.
pub fn slip_metrics(sim: &SimTrajectory) -> Vec<(String, f64)> {
    let max_abs = |suffix: &str| {
        sim.channels
            .iter()
            .filter(|(n, _)| n.starts_with("slip_") && n.ends_with(suffix))
            .flat_map(|(_, v)| v.iter())
            .fold(0.0, |m: f64, v| m.max(v.abs()))
    };
    vec![
        (SLIP_METRICS[0].into(), max_abs("_lat")),
        (SLIP_METRICS[1].into(), max_abs("_lon")),
    ]
}
