//! Round-trip tests of the MCAP and Rerun log writers on a synthetic run.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::f64::consts::FRAC_1_SQRT_2;
use std::path::Path;
use std::time::Instant;

use anholonomy::integrate::Trajectory;
use anholonomy::log::{write_mcap, write_rrd, LogError};
use anholonomy::record::{Comparison, LinkVisual, Pose, RunRecord, Shape, SimTrajectory, Visual};
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Decode;
use nalgebra::DVector;

const STATE: [&str; 4] = ["x", "y", "theta", "phi"];
const INPUT: [&str; 2] = ["v", "omega"];

/// A car-like body driving along a gentle curve: 4 coordinates, 2 links
/// (box chassis + cylinder/sphere/capsule "wheel" link).
struct Fixture {
    labels: Vec<String>,
    goal: Vec<f64>,
    ideal: Trajectory,
    sim: SimTrajectory,
    comparison: Comparison,
    links: Vec<LinkVisual>,
    metrics: Vec<(String, f64)>,
}

fn yaw(theta: f64) -> [f64; 4] {
    [0.0, 0.0, (0.5 * theta).sin(), (0.5 * theta).cos()]
}

impl Fixture {
    fn new(n: usize) -> Self {
        let dt = 0.01;
        let state = |t: f64, bias: f64| {
            DVector::from_vec(vec![
                t + bias,
                0.2 * (0.5 * t).sin() + bias,
                0.1 * t,
                0.05 * (t).cos(),
            ])
        };
        let mut ideal = Trajectory::default();
        let mut sim = SimTrajectory::default();
        for k in 0..n {
            let t = k as f64 * dt;
            let label = if k < n / 2 { 0 } else { 1 };
            ideal.t.push(t);
            ideal.q.push(state(t, 0.0));
            ideal
                .u
                .push(DVector::from_vec(vec![1.0, 0.1 * label as f64]));
            ideal.label.push(label);

            let q = state(t, 0.001 * t);
            let base = Pose {
                translation: [q[0], q[1], 0.1],
                rotation: yaw(q[2]),
            };
            let wheel = Pose {
                translation: [q[0] + 0.3, q[1], 0.1],
                rotation: yaw(q[2] + q[3]),
            };
            sim.traj.t.push(t);
            sim.traj.q.push(q);
            sim.traj
                .u
                .push(DVector::from_vec(vec![1.0, 0.1 * label as f64]));
            sim.traj.label.push(label);
            sim.link_poses.push(vec![base, wheel]);
        }
        sim.channels.push((
            "slip".to_string(),
            (0..n).map(|k| 1e-3 * k as f64).collect(),
        ));
        sim.steps = n;
        let coord_error = (0..STATE.len())
            .map(|i| (0..n).map(|k| sim.traj.q[k][i] - ideal.q[k][i]).collect())
            .collect();
        let position_error = (0..n)
            .map(|k| {
                let (a, b) = (&sim.traj.q[k], &ideal.q[k]);
                (a[0] - b[0]).hypot(a[1] - b[1])
            })
            .collect();
        let comparison = Comparison {
            t: ideal.t.clone(),
            coord_error,
            position_error: Some(position_error),
        };
        let visual = |shape, origin| Visual {
            shape,
            origin,
            rgba: [0.3, 0.4, 0.8, 1.0],
        };
        let links = vec![
            LinkVisual {
                name: "base_link".into(),
                visuals: vec![visual(
                    Shape::Box {
                        size: [0.5, 0.3, 0.1],
                    },
                    Pose::IDENTITY,
                )],
            },
            LinkVisual {
                name: "wheel".into(),
                visuals: vec![
                    visual(
                        Shape::Cylinder {
                            radius: 0.05,
                            length: 0.03,
                        },
                        Pose {
                            translation: [0.0; 3],
                            rotation: [FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2],
                        },
                    ),
                    visual(Shape::Sphere { radius: 0.02 }, Pose::IDENTITY),
                    visual(
                        Shape::Capsule {
                            radius: 0.01,
                            length: 0.1,
                        },
                        Pose {
                            translation: [0.0, 0.0, 0.05],
                            rotation: [0.0, 0.0, 0.0, 1.0],
                        },
                    ),
                ],
            },
        ];
        Fixture {
            labels: vec!["straight".into(), "turn".into()],
            goal: vec![1.0, 0.0, 0.1, 0.0],
            ideal,
            sim,
            comparison,
            links,
            metrics: vec![
                ("final_position_error".into(), 0.0123),
                ("steps".into(), n as f64),
            ],
        }
    }

    fn record(&self) -> RunRecord<'_> {
        RunRecord {
            scenario: "synthetic_line",
            state_names: &STATE,
            input_names: &INPUT,
            angular: &[2, 3],
            position: Some([0, 1]),
            goal: &self.goal,
            labels: &self.labels,
            ideal: &self.ideal,
            sim: &self.sim,
            comparison: &self.comparison,
            links: &self.links,
            metrics: &self.metrics,
            goal_heading: self.goal.get(2).copied(),
            overlays: &[],
            series: &[],
        }
    }
}

fn tmp_of(path: &Path) -> std::path::PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".tmp");
    s.into()
}

#[test]
fn mcap_roundtrip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let fx = Fixture::new(100);
    write_mcap(&path, &fx.record()).unwrap();
    assert!(!tmp_of(&path).exists(), "temporary file left behind");

    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("MCAP has a summary section");
    let by_topic: HashMap<&str, _> = summary
        .channels
        .values()
        .map(|c| (c.topic.as_str(), c.clone()))
        .collect();

    for topic in [
        "/plan/command",
        "/ideal/state",
        "/sim/state",
        "/tracking/error",
    ] {
        let ch = by_topic
            .get(topic)
            .unwrap_or_else(|| panic!("missing topic {topic}"));
        assert_eq!(ch.message_encoding, "json", "{topic}");
        let schema = ch
            .schema
            .as_ref()
            .unwrap_or_else(|| panic!("{topic} has no schema"));
        assert_eq!(schema.encoding, "jsonschema", "{topic}");
        let js: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        assert_eq!(js["type"], "object");
        assert!(js["properties"]["values"]["properties"].is_object());
    }
    for (topic, schema_name) in [
        ("/tf", "foxglove.FrameTransforms"),
        ("/scene", "foxglove.SceneUpdate"),
        ("/scene/paths", "foxglove.SceneUpdate"),
    ] {
        let ch = by_topic
            .get(topic)
            .unwrap_or_else(|| panic!("missing topic {topic}"));
        assert_eq!(ch.message_encoding, "protobuf", "{topic}");
        let schema = ch.schema.as_ref().unwrap();
        assert_eq!(schema.name, schema_name);
        assert_eq!(schema.encoding, "protobuf");
    }

    // Message counts, times and contents.
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut last_time = 0;
    let mut first: HashMap<String, serde_json::Value> = HashMap::new();
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        assert!(
            msg.log_time >= last_time,
            "messages are written in time order"
        );
        last_time = msg.log_time;
        let topic = msg.channel.topic.clone();
        *counts.entry(topic.clone()).or_default() += 1;
        if topic == "/scene" {
            let scene = SceneUpdate::decode(&msg.data[..]).unwrap();
            assert_eq!(scene.entities.len(), 2);
            let base = &scene.entities[0];
            assert_eq!(
                (base.id.as_str(), base.frame_id.as_str()),
                ("base_link", "base_link")
            );
            assert!(base.frame_locked && base.lifetime.is_none());
            assert_eq!(base.cubes.len(), 1);
            let wheel = &scene.entities[1];
            // cylinder + capsule body; sphere + two capsule caps
            assert_eq!((wheel.cylinders.len(), wheel.spheres.len()), (2, 3));
        }
        if topic == "/scene/paths" {
            let scene = SceneUpdate::decode(&msg.data[..]).unwrap();
            let ids: Vec<&str> = scene.entities.iter().map(|e| e.id.as_str()).collect();
            assert_eq!(ids, ["ideal_path", "sim_path", "goal"]);
            assert_eq!(scene.entities[0].lines[0].points.len(), fx.ideal.len());
            assert!(scene.entities[1].lines[0].points.iter().all(|p| p.z == 0.0));
        }
        if topic == "/tf" {
            let tf = FrameTransforms::decode(&msg.data[..]).unwrap();
            let pairs: Vec<(&str, &str)> = tf
                .transforms
                .iter()
                .map(|t| (t.parent_frame_id.as_str(), t.child_frame_id.as_str()))
                .collect();
            assert_eq!(pairs, [("world", "base_link"), ("world", "wheel")]);
        }
        if msg.channel.message_encoding == "json" {
            let v: serde_json::Value = serde_json::from_slice(&msg.data).unwrap();
            let t = v["t"].as_f64().unwrap();
            assert_eq!(
                msg.log_time,
                (t * 1e9).round() as u64,
                "log time = sim time in ns"
            );
            first.entry(topic).or_insert(v);
        }
    }
    let n_ideal = fx.ideal.len();
    let n_sim = fx.sim.traj.len();
    assert_eq!(counts["/plan/command"], n_ideal);
    assert_eq!(counts["/ideal/state"], n_ideal);
    assert_eq!(counts["/sim/state"], n_sim);
    assert_eq!(counts["/tracking/error"], fx.comparison.t.len());
    assert_eq!(counts["/tf"], n_sim);
    assert_eq!(counts["/scene"], 1);
    assert_eq!(counts["/scene/paths"], 1);
    let stats = summary.stats.as_ref().unwrap();
    assert_eq!(stats.message_count as usize, counts.values().sum::<usize>());

    let cmd = &first["/plan/command"];
    assert_eq!(cmd["segment"], "straight");
    assert_eq!(cmd["values"]["v"], 1.0);
    let keys = |v: &serde_json::Value| -> Vec<String> {
        v["values"].as_object().unwrap().keys().cloned().collect()
    };
    assert_eq!(keys(cmd), ["omega", "v"]);
    assert_eq!(keys(&first["/ideal/state"]).len(), 4);
    let err_keys: BTreeSet<String> = keys(&first["/tracking/error"]).into_iter().collect();
    let want: BTreeSet<String> = ["x", "y", "theta", "phi", "position"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(err_keys, want);

    // Metrics metadata.
    let idx = summary
        .metadata_indexes
        .iter()
        .find(|m| m.name == "anholonomy.metrics")
        .expect("metrics metadata");
    let meta = mcap::read::metadata(&bytes, idx).unwrap();
    assert_eq!(
        meta.metadata["final_position_error"]
            .parse::<f64>()
            .unwrap(),
        0.0123
    );
    assert!(summary
        .metadata_indexes
        .iter()
        .any(|m| m.name == "anholonomy.run"));
}

#[test]
fn rrd_roundtrip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.rrd");
    let fx = Fixture::new(100);
    write_rrd(&path, &fx.record()).unwrap();
    assert!(!tmp_of(&path).exists(), "temporary file left behind");

    let bytes = std::fs::read(&path).unwrap();
    assert!(
        bytes.len() > 1000,
        "rrd suspiciously small: {} bytes",
        bytes.len()
    );
    // re_log_encoding 0.36.3, src/rrd/mod.rs: `RRD_FOURCC = *b"RRF2"` (stream header);
    // src/rrd/frames.rs: stream footer ends with fourcc + b"FOOT" + u32 entry count.
    assert_eq!(&bytes[..4], b"RRF2");
    assert_eq!(&bytes[bytes.len() - 12..bytes.len() - 4], b"RRF2FOOT");

    // Decode and check the entities and row counts.
    use rerun::external::re_log_encoding::DecoderApp;
    use rerun::log::{Chunk, LogMsg};
    let mut rows: HashMap<String, usize> = HashMap::new();
    let mut blueprint_msgs = 0;
    for msg in DecoderApp::decode_eager(std::io::BufReader::new(&bytes[..])).unwrap() {
        match msg.unwrap() {
            LogMsg::ArrowMsg(store, arrow) => {
                if store.kind() == rerun::StoreKind::Blueprint {
                    blueprint_msgs += 1;
                    continue;
                }
                let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
                *rows.entry(chunk.entity_path().to_string()).or_default() += chunk.num_rows();
            }
            LogMsg::SetStoreInfo(_) | LogMsg::BlueprintActivationCommand(_) => {}
        }
    }
    assert!(blueprint_msgs > 0, "blueprint stored in the file");
    for e in [
        "/robot/base_link",
        "/robot/base_link/visual_0",
        "/robot/wheel/visual_2",
        "/paths/ideal",
        "/paths/sim",
        "/paths/goal",
        "/state/x/ideal",
        "/state/phi/sim",
        "/errors/theta",
        "/errors/position",
        "/command/omega",
        "/sim/slip",
        "/segment",
    ] {
        assert!(
            rows.contains_key(e),
            "entity {e} missing; have {:?}",
            rows.keys()
        );
    }
    // 100 scalar rows + 1 static style row.
    assert_eq!(rows["/state/x/ideal"], 101);
    assert_eq!(rows["/segment"], 2);
}

#[test]
fn missing_directory_is_an_error_and_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir");
    let fx = Fixture::new(20);
    for (ext, result) in [
        ("mcap", write_mcap(&missing.join("run.mcap"), &fx.record())),
        ("rrd", write_rrd(&missing.join("run.rrd"), &fx.record())),
    ] {
        let err = result.expect_err("writing into a missing directory must fail");
        let text = err.to_string();
        println!("{ext}: {text}");
        assert!(
            text.contains("no/such/dir"),
            "{ext}: error names the path: {text}"
        );
        assert!(
            matches!(err, LogError::Io { .. } | LogError::Rerun { .. }),
            "{ext}: {err:?}"
        );
    }
    assert!(!missing.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn invalid_record_keeps_previous_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut fx = Fixture::new(20);
    fx.sim.link_poses.pop(); // one pose row short
    for name in ["run.mcap", "run.rrd"] {
        let path = dir.path().join(name);
        std::fs::write(&path, b"previous").unwrap();
        let r = if name.ends_with("mcap") {
            write_mcap(&path, &fx.record())
        } else {
            write_rrd(&path, &fx.record())
        };
        let err = r.expect_err("inconsistent record is rejected");
        assert!(matches!(err, LogError::InvalidRecord { .. }), "{err}");
        assert!(err.to_string().contains("link pose"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"previous");
        assert!(!tmp_of(&path).exists());
    }
}

#[test]
fn overwrite_and_no_planar_position() {
    let dir = tempfile::tempdir().unwrap();
    let fx = Fixture::new(30);
    let cmp = Comparison {
        t: fx.comparison.t.clone(),
        coord_error: fx.comparison.coord_error.clone(),
        position_error: None,
    };
    let mut rec = fx.record();
    rec.position = None;
    rec.comparison = &cmp;
    let mcap_path = dir.path().join("a.mcap");
    let rrd_path = dir.path().join("a.rrd");
    for _ in 0..2 {
        write_mcap(&mcap_path, &rec).unwrap();
        write_rrd(&rrd_path, &rec).unwrap();
    }
    let bytes = std::fs::read(&mcap_path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    assert!(!summary.channels.values().any(|c| c.topic == "/scene/paths"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn write_time_3000_samples() {
    let dir = tempfile::tempdir().unwrap();
    let fx = Fixture::new(3000);
    let rec = fx.record();
    // First (cold) writes also initialise lazy statics / thread pools.
    let t0 = Instant::now();
    write_mcap(&dir.path().join("cold.mcap"), &rec).unwrap();
    let cold_mcap = t0.elapsed();
    let t1 = Instant::now();
    write_rrd(&dir.path().join("cold.rrd"), &rec).unwrap();
    let cold_rrd = t1.elapsed();
    println!(
        "3000 samples, cold: mcap {:.1} ms, rrd {:.1} ms",
        cold_mcap.as_secs_f64() * 1e3,
        cold_rrd.as_secs_f64() * 1e3
    );

    let t0 = Instant::now();
    write_mcap(&dir.path().join("big.mcap"), &rec).unwrap();
    let t_mcap = t0.elapsed();
    let t1 = Instant::now();
    write_rrd(&dir.path().join("big.rrd"), &rec).unwrap();
    let t_rrd = t1.elapsed();
    let size = |n: &str| std::fs::metadata(dir.path().join(n)).unwrap().len();
    println!(
        "3000 samples, 4 coordinates, 2 links: mcap {:.1} ms ({} KiB), rrd {:.1} ms ({} KiB)",
        t_mcap.as_secs_f64() * 1e3,
        size("big.mcap") / 1024,
        t_rrd.as_secs_f64() * 1e3,
        size("big.rrd") / 1024,
    );
    if !cfg!(debug_assertions) {
        assert!((t_mcap + t_rrd).as_secs_f64() < 0.5, "log writing too slow");
        assert!(
            (cold_mcap + cold_rrd).as_secs_f64() < 0.5,
            "cold log writing too slow"
        );
    }
}
