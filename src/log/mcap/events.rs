//! The time-ordered messages of a run's MCAP log, and their encoding.
//!
//! Encoding is most of the writing time, and each message's bytes depend
//! on that message alone: [`Topics::log`] encodes a window of messages in
//! parallel, then logs the window in order, so the file is the same on any
//! number of threads.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use foxglove::messages::{FrameTransform, FrameTransforms};
use foxglove::{Encode, PartialMetadata, RawChannel};
use rayon::prelude::*;

use crate::log::mcap::{quat, timestamp, vec3, JsonMsg, Keys, WORLD_FRAME};
use crate::log::scene::{label_at, nanos, segment_name};
use crate::log::LogError;
use crate::record::RunRecord;

/// Messages encoded together before any is logged: enough to keep both
/// cores busy, few enough that a window's bytes stay small (~1 MB).
const WINDOW: usize = 2048;

/// What to log next, in time order.
#[derive(Clone, Copy)]
pub(super) enum Ev {
    Series(usize, usize),
    Command(usize),
    /// A step of the physics run while the plan was in force (the one at
    /// `plan_steps` marks its end).
    SimCommand(usize),
    Ideal(usize),
    Sim(usize),
    Channels(usize),
    Error(usize),
    /// A row of `link_poses` (not a sample index: poses are thinned).
    Tf(usize),
}

/// Every message of the run with its log time, in time order (a stable sort
/// keeps the topics' order at equal times). `channels`: whether the physics
/// recorded channels (`/sim/channels`).
pub(super) fn events(rec: &RunRecord<'_>, channels: bool) -> Vec<(u64, Ev)> {
    let (ideal, sim, cmp) = (rec.ideal, rec.sim, rec.comparison);
    let mut evs: Vec<(u64, Ev)> =
        Vec::with_capacity(2 * ideal.len() + 2 * sim.traj.len() + cmp.t.len());
    for (k, &t) in ideal.t.iter().enumerate() {
        evs.push((nanos(t), Ev::Command(k)));
        evs.push((nanos(t), Ev::Ideal(k)));
    }
    // Steps while the plan was in force, then the plan's end (a zero).
    for (k, &t) in sim.traj.t.iter().enumerate().take(plan_end(rec) + 1) {
        evs.push((nanos(t), Ev::SimCommand(k)));
    }
    for (k, &t) in sim.traj.t.iter().enumerate() {
        evs.push((nanos(t), Ev::Sim(k)));
        if channels {
            evs.push((nanos(t), Ev::Channels(k)));
        }
    }
    for (row, t) in sim.link_pose_times().enumerate() {
        evs.push((nanos(t), Ev::Tf(row)));
    }
    for (k, &t) in cmp.t.iter().enumerate() {
        evs.push((nanos(t), Ev::Error(k)));
    }
    for (i, s) in rec.series.iter().enumerate() {
        for (k, &t) in s.t.iter().enumerate() {
            evs.push((nanos(t), Ev::Series(i, k)));
        }
    }
    evs.sort_by_key(|&(ns, _)| ns);
    evs
}

/// The physics step at which the plan ended (its `/sim/command` is a zero).
fn plan_end(rec: &RunRecord<'_>) -> usize {
    rec.sim
        .plan_steps
        .min(rec.sim.traj.t.len().saturating_sub(1))
}

/// The channels of the time-ordered topics and what encoding needs.
pub(super) struct Topics<'a> {
    pub(super) rec: &'a RunRecord<'a>,
    pub(super) tmp: &'a Path,
    pub(super) cmd: Arc<RawChannel>,
    pub(super) sim_cmd: Arc<RawChannel>,
    pub(super) ideal: Arc<RawChannel>,
    pub(super) sim: Arc<RawChannel>,
    pub(super) err: Arc<RawChannel>,
    pub(super) chan: Option<Arc<RawChannel>>,
    pub(super) series: Vec<Arc<RawChannel>>,
    pub(super) tf: Arc<RawChannel>,
    pub(super) keys_value: Keys,
    pub(super) keys_input: Keys,
    pub(super) keys_state: Keys,
    pub(super) keys_channel: Keys,
    pub(super) keys_error: Keys,
    /// Error-row slots: coordinates, then `position`, then per robot.
    pub(super) error_len: usize,
    pub(super) state_len: usize,
    /// `/tf` child frame ids, in link order.
    pub(super) frames: Vec<String>,
}

impl Topics<'_> {
    /// Log every event, in order.
    pub(super) fn log(&self, evs: &[(u64, Ev)]) -> Result<(), LogError> {
        for window in evs.chunks(WINDOW) {
            let encoded: Vec<_> = window
                .par_iter()
                .map(|&(ns, ev)| {
                    let mut buf = Vec::with_capacity(512);
                    self.encode(ns, ev, &mut buf).map(|ch| (ch, buf))
                })
                .collect();
            for (&(ns, _), e) in window.iter().zip(encoded) {
                if let (Some(ch), buf) = e? {
                    ch.log_with_meta(&buf, PartialMetadata::with_log_time(ns));
                }
            }
        }
        Ok(())
    }

    fn json<'c>(
        &self,
        ch: &'c RawChannel,
        msg: &JsonMsg<'_>,
        buf: &mut Vec<u8>,
    ) -> Result<Option<&'c RawChannel>, LogError> {
        msg.write(buf).map_err(|source| LogError::Json {
            path: self.tmp.to_path_buf(),
            source,
        })?;
        Ok(Some(ch))
    }

    /// Write event `ev`'s message into `buf`; its channel (none: a topic
    /// this run does not have).
    fn encode(&self, ns: u64, ev: Ev, buf: &mut Vec<u8>) -> Result<Option<&RawChannel>, LogError> {
        let rec = self.rec;
        let (ideal, sim, cmp) = (rec.ideal, rec.sim, rec.comparison);
        let json = |ch, msg: JsonMsg<'_>, buf: &mut Vec<u8>| self.json(ch, &msg, buf);
        match ev {
            Ev::Series(i, k) => {
                let s = &rec.series[i];
                let msg = JsonMsg {
                    t: s.t[k],
                    segment: "",
                    keys: &self.keys_value,
                    values: &s.values[k..k + 1],
                };
                json(&self.series[i], msg, buf)
            }
            Ev::Command(k) => {
                let seg = segment_name(rec.labels, ideal.label[k]);
                let msg = JsonMsg {
                    t: ideal.t[k],
                    segment: &seg,
                    keys: &self.keys_input,
                    values: ideal.u[k].as_slice(),
                };
                json(&self.cmd, msg, buf)
            }
            Ev::SimCommand(k) => {
                let seg = segment_name(rec.labels, sim.traj.label[k]);
                // Only the plan's end (one message) holds zeros.
                let zeros;
                let values = if k < plan_end(rec) {
                    sim.traj.u[k].as_slice()
                } else {
                    zeros = vec![0.0; rec.input_names.len()];
                    &zeros
                };
                let msg = JsonMsg {
                    t: sim.traj.t[k],
                    segment: &seg,
                    keys: &self.keys_input,
                    values,
                };
                json(&self.sim_cmd, msg, buf)
            }
            Ev::Ideal(k) => {
                let seg = segment_name(rec.labels, ideal.label[k]);
                let msg = JsonMsg {
                    t: ideal.t[k],
                    segment: &seg,
                    keys: &self.keys_state,
                    values: ideal.q[k].as_slice(),
                };
                json(&self.ideal, msg, buf)
            }
            Ev::Sim(k) => {
                let seg = segment_name(rec.labels, sim.traj.label[k]);
                let msg = JsonMsg {
                    t: sim.traj.t[k],
                    segment: &seg,
                    keys: &self.keys_state,
                    values: sim.traj.q[k].as_slice(),
                };
                json(&self.sim, msg, buf)
            }
            Ev::Channels(k) => {
                let Some(ch) = &self.chan else {
                    return Ok(None);
                };
                let seg = segment_name(rec.labels, sim.traj.label[k]);
                let row: Vec<f64> = sim.channels.iter().map(|(_, v)| v[k]).collect();
                let msg = JsonMsg {
                    t: sim.traj.t[k],
                    segment: &seg,
                    keys: &self.keys_channel,
                    values: &row,
                };
                json(&**ch, msg, buf)
            }
            Ev::Error(k) => {
                let t = cmp.t[k];
                let mut row = vec![0.0; self.error_len];
                for (slot, series) in row.iter_mut().zip(&cmp.coord_error) {
                    *slot = series[k];
                }
                if let Some(p) = &cmp.position_error {
                    row[self.state_len] = p[k];
                }
                // Per-robot position errors (several robots) come last.
                let first = row.len() - cmp.robot_position_error.len();
                for (slot, series) in row[first..].iter_mut().zip(&cmp.robot_position_error) {
                    *slot = series[k];
                }
                let seg = match label_at(ideal, t) {
                    Some(l) => segment_name(rec.labels, l),
                    None => Cow::Borrowed(""),
                };
                let msg = JsonMsg {
                    t,
                    segment: &seg,
                    keys: &self.keys_error,
                    values: &row,
                };
                json(&self.err, msg, buf)
            }
            Ev::Tf(row) => {
                let ts = Some(timestamp(ns));
                let transforms = sim.link_poses[row]
                    .iter()
                    .zip(&self.frames)
                    .map(|(p, frame)| FrameTransform {
                        timestamp: ts,
                        parent_frame_id: WORLD_FRAME.to_string(),
                        child_frame_id: frame.clone(),
                        translation: Some(vec3(p.translation)),
                        rotation: Some(quat(p.rotation)),
                    })
                    .collect();
                FrameTransforms { transforms }
                    .encode(buf)
                    .expect("protobuf encodes into a growable buffer");
                Ok(Some(&*self.tf))
            }
        }
    }
}
