//! Round-trip tests of the MCAP and Rerun log writers on a synthetic run.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use anholonomy::log::{write_mcap, write_rrd, LogError};
use anholonomy::record::Comparison;
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Decode;

use crate::common::log_fixture;
use log_fixture::Fixture;

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
    use re_log_encoding::DecoderApp;
    use re_sdk::log::{Chunk, LogMsg};
    let mut rows: HashMap<String, usize> = HashMap::new();
    let mut blueprint_msgs = 0;
    for msg in DecoderApp::decode_eager(std::io::BufReader::new(&bytes[..])).unwrap() {
        match msg.unwrap() {
            LogMsg::ArrowMsg(store, arrow) => {
                if store.kind() == re_sdk::StoreKind::Blueprint {
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
    // Link pose rows that do not line up with their sample indices.
    type Corrupt = fn(&mut Fixture);
    let cases: [(&str, Corrupt); 3] = [
        ("rows but", |fx| {
            fx.sim.link_poses.pop(); // one pose row short
        }),
        ("not increasing", |fx| fx.sim.link_pose_index.swap(3, 4)),
        ("but sim has", |fx| {
            *fx.sim.link_pose_index.last_mut().unwrap() = 20;
        }),
    ];
    for (needle, corrupt) in cases {
        let mut fx = Fixture::new(20);
        corrupt(&mut fx);
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
            assert!(err.to_string().contains(needle), "{err}");
            assert_eq!(std::fs::read(&path).unwrap(), b"previous");
            assert!(!tmp_of(&path).exists());
        }
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
        robot_position_error: Vec::new(),
    };
    let mut rec = fx.record();
    rec.robot_positions.clear();
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

/// 3000 samples write complete files (their write time is a criterion
/// benchmark: `cargo bench --bench harness -- log_write`).
#[test]
fn write_3000_samples() {
    let dir = tempfile::tempdir().unwrap();
    let fx = Fixture::new(3000);
    let rec = fx.record();
    write_mcap(&dir.path().join("big.mcap"), &rec).unwrap();
    write_rrd(&dir.path().join("big.rrd"), &rec).unwrap();
    let bytes = std::fs::read(dir.path().join("big.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let sim_state = summary
        .channels
        .values()
        .find(|c| c.topic == "/sim/state")
        .unwrap()
        .id;
    assert_eq!(
        summary.stats.unwrap().channel_message_counts[&sim_state],
        3000
    );
    assert!(std::fs::metadata(dir.path().join("big.rrd")).unwrap().len() > 10_000);
}

/// Messages are encoded in parallel windows and logged in order: the file
/// is the same, byte for byte, on one thread and on three.
#[test]
fn the_mcap_file_does_not_depend_on_threads() {
    let dir = tempfile::tempdir().unwrap();
    let fx = Fixture::new(3000);
    let rec = fx.record();
    let written = |threads: usize| {
        let path = dir.path().join(format!("t{threads}.mcap"));
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| write_mcap(&path, &rec).unwrap());
        std::fs::read(path).unwrap()
    };
    let one = written(1);
    assert!(one.len() > 100_000, "several encoding windows");
    assert!(one == written(3), "the files differ");
}

/// Several robots: every robot's ideal and simulated path and goal in both
/// logs (`ideal_path_2`, `paths/ideal_2`, ...), the first robot's under the
/// one-robot names; the goal heading is the first robot's.
#[test]
fn every_robots_paths_and_goal_are_logged() {
    let dir = tempfile::tempdir().unwrap();
    let fx = Fixture::new(100);
    let mut rec = fx.record();
    // The fixture's (theta, phi) stand in for a second robot's (x, y).
    rec.robot_positions = vec![[0, 1], [2, 3]];
    let mcap_path = dir.path().join("run.mcap");
    write_mcap(&mcap_path, &rec).unwrap();
    let bytes = std::fs::read(&mcap_path).unwrap();
    let scene = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .find(|m| m.channel.topic == "/scene/paths")
        .map(|m| SceneUpdate::decode(&m.data[..]).unwrap())
        .expect("a /scene/paths message");
    let ids: Vec<&str> = scene.entities.iter().map(|e| e.id.as_str()).collect();
    assert_eq!(
        ids,
        [
            "ideal_path",
            "sim_path",
            "ideal_path_2",
            "sim_path_2",
            "goal",
            "goal_2"
        ]
    );
    let second: Vec<(f64, f64)> = scene.entities[2].lines[0]
        .points
        .iter()
        .map(|p| (p.x, p.y))
        .collect();
    let want: Vec<(f64, f64)> = fx.ideal.q.iter().map(|q| (q[2], q[3])).collect();
    assert_eq!(second, want, "robot 2's ideal path is its own coordinates");
    assert_eq!(scene.entities[4].arrows.len(), 1, "robot 1's goal heading");
    assert!(scene.entities[5].arrows.is_empty());
    let sphere = &scene.entities[5].spheres[0];
    let at = sphere.pose.as_ref().unwrap().position.as_ref().unwrap();
    assert_eq!((at.x, at.y), (fx.goal[2], fx.goal[3]));

    let rrd_path = dir.path().join("run.rrd");
    write_rrd(&rrd_path, &rec).unwrap();
    use re_log_encoding::DecoderApp;
    use re_sdk::log::{Chunk, LogMsg};
    let rrd = std::fs::read(&rrd_path).unwrap();
    let mut entities = BTreeSet::new();
    for msg in DecoderApp::decode_eager(std::io::BufReader::new(&rrd[..])).unwrap() {
        if let LogMsg::ArrowMsg(store, arrow) = msg.unwrap() {
            if store.kind() == re_sdk::StoreKind::Recording {
                let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
                entities.insert(chunk.entity_path().to_string());
            }
        }
    }
    for e in [
        "/paths/ideal",
        "/paths/sim",
        "/paths/goal",
        "/paths/ideal_2",
        "/paths/sim_2",
        "/paths/ideal_2/now",
        "/paths/goal_2",
    ] {
        assert!(
            entities.contains(e),
            "entity {e} missing; have {entities:?}"
        );
    }
    assert!(!entities.contains("/paths/goal_2/heading"));

    // The report's data: the first robot's paths as before, the others beside.
    let sf = anholonomy::log::series::SeriesFile::from_record(&rec);
    assert_eq!(sf.path_ideal.len(), fx.ideal.len());
    assert_eq!(sf.other_robots.len(), 1);
    assert_eq!(sf.other_robots[0].position, [2, 3]);
    let last = fx.sim.traj.q.last().unwrap();
    assert_eq!(
        sf.other_robots[0].sim.last(),
        Some(&[last[2] as f32, last[3] as f32])
    );
}
