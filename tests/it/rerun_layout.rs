//! The Rerun default layout, read back from `.rrd` files: every time-series
//! view opens on the whole run (not a trailing window), the analysis tab comes
//! first, and no plot mixes quantities (a force with a torque).

use std::collections::BTreeMap;
use std::path::Path;

use anholonomy::log::write_rrd;
use anholonomy::record::Series;
use re_log_encoding::DecoderApp;
use re_sdk::log::{Chunk, LogMsg};
use re_sdk::{ComponentIdentifier, StoreKind};
use re_sdk_types::blueprint::components::{
    IncludedContent, QueryExpression, TimeRange, ViewClass, VisibleTimeRange,
};
use re_sdk_types::components::Name;
use re_sdk_types::datatypes::TimeRangeBoundary;
use re_sdk_types::Component;

use crate::common::log_fixture;
use log_fixture::Fixture;

/// The blueprint's chunks by entity, and the recording's last `sim_time` (ns).
struct Rrd {
    blueprint: BTreeMap<String, Vec<Chunk>>,
    end_ns: i64,
}

fn read(path: &Path) -> Rrd {
    let bytes = std::fs::read(path).unwrap();
    let mut blueprint: BTreeMap<String, Vec<Chunk>> = BTreeMap::new();
    let mut end_ns = i64::MIN;
    for msg in DecoderApp::decode_eager(std::io::BufReader::new(&bytes[..])).unwrap() {
        let LogMsg::ArrowMsg(store, arrow) = msg.unwrap() else {
            continue;
        };
        let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
        match store.kind() {
            StoreKind::Blueprint => blueprint
                .entry(chunk.entity_path().to_string())
                .or_default()
                .push(chunk),
            StoreKind::Recording => {
                for (name, col) in chunk.timelines() {
                    if name.as_str() == "sim_time" {
                        end_ns = end_ns.max(col.time_range().max().as_i64());
                    }
                }
            }
        }
    }
    assert!(end_ns > 0, "no sim_time data in {}", path.display());
    Rrd { blueprint, end_ns }
}

impl Rrd {
    /// Every value of component `id` (of type `C`) logged on `entity`.
    fn values<C: Component>(&self, entity: &str, id: &'static str) -> Vec<C> {
        self.blueprint
            .get(entity)
            .into_iter()
            .flatten()
            .flat_map(|c| {
                c.iter_component::<C>(ComponentIdentifier::from(id))
                    .flat_map(|v| v.to_vec())
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// The time-series views: (entity, title).
    fn time_series_views(&self) -> Vec<(String, String)> {
        self.blueprint
            .keys()
            .filter(|e| e.starts_with("/view/") && e.matches('/').count() == 2)
            .filter(|e| {
                self.values::<ViewClass>(e, "ViewBlueprint:class_identifier")
                    .iter()
                    .any(|c| c.0.as_str() == "TimeSeries")
            })
            .map(|e| {
                let name = self.values::<Name>(e, "ViewBlueprint:display_name");
                (
                    e.clone(),
                    name.first().map_or(String::new(), |n| n.to_string()),
                )
            })
            .collect()
    }

    /// Every time-series view opens on [0, end of the run] and shows all data
    /// (its visible range is unbounded).
    fn check_whole_run(&self, what: &str) {
        let views = self.time_series_views();
        assert!(!views.is_empty(), "{what}: no time-series views");
        for (v, title) in &views {
            let range = self.values::<TimeRange>(&format!("{v}/TimeAxis"), "TimeAxis:view_range");
            let r = range
                .first()
                .unwrap_or_else(|| panic!("{what}: view `{title}` has no time axis range"));
            let (TimeRangeBoundary::Absolute(a), TimeRangeBoundary::Absolute(b)) =
                (r.0.start, r.0.end)
            else {
                panic!("{what}: view `{title}` range {:?} is not absolute", r.0);
            };
            assert_eq!(a.0, 0, "{what}: `{title}` starts at {} ns", a.0);
            // The run's last sample, rounded up to the nanosecond.
            assert!(
                (b.0 - self.end_ns).abs() <= 1,
                "{what}: `{title}` ends at {} ns, the run at {} ns",
                b.0,
                self.end_ns
            );
            let visible = self.values::<VisibleTimeRange>(
                &format!("{v}/VisibleTimeRanges"),
                "VisibleTimeRanges:ranges",
            );
            assert!(
                visible
                    .iter()
                    .any(|r| r.0.range.start == TimeRangeBoundary::Infinite
                        && r.0.range.end == TimeRangeBoundary::Infinite),
                "{what}: `{title}` shows a window of the data: {visible:?}"
            );
        }
    }

    /// The entity queries of view `v`.
    fn queries(&self, v: &str) -> Vec<String> {
        self.values::<QueryExpression>(&format!("{v}/ViewContents"), "ViewContents:query")
            .iter()
            .flat_map(|q| q.0.as_str().lines().map(String::from).collect::<Vec<_>>())
            .collect()
    }

    /// Names of the tabs of the tab container, in order.
    fn tabs(&self) -> Vec<String> {
        let containers: Vec<&String> = self
            .blueprint
            .keys()
            .filter(|e| e.starts_with("/container/"))
            .collect();
        let kind = |e: &str| {
            self.values::<re_sdk_types::blueprint::components::ContainerKind>(
                e,
                "ContainerBlueprint:container_kind",
            )
        };
        let tabs = containers
            .iter()
            .find(|e| kind(e).contains(&re_sdk_types::blueprint::components::ContainerKind::Tabs))
            .expect("a tab container");
        let children = self.values::<IncludedContent>(tabs, "ContainerBlueprint:contents");
        children
            .iter()
            .map(|c| {
                let path = format!("/{}", c.0.to_string().trim_start_matches('/'));
                let grid = self.values::<Name>(&path, "ContainerBlueprint:display_name");
                let view = self.values::<Name>(&path, "ViewBlueprint:display_name");
                grid.into_iter()
                    .chain(view)
                    .next()
                    .map_or(path, |n| n.to_string())
            })
            .collect()
    }
}

/// A run whose analysis series and simulated run end after the ideal run
/// (a feedback policy's physics run taking longer), with grasp channels.
#[test]
fn every_view_opens_on_the_whole_run_and_the_analysis_tab_comes_first() {
    let dir = tempfile::tempdir().unwrap();
    let mut fx = Fixture::new(200);
    let t_sim = fx.sim.traj.t.clone();
    let n = t_sim.len();
    for (name, scale) in [
        ("grasp1_force", 50.0),
        ("grasp1_torque", 5.0),
        ("grasp2_force", 40.0),
        ("grasp2_torque", 4.0),
    ] {
        fx.sim.channels.push((
            name.into(),
            (0..n).map(|k| scale * (k as f64).sin()).collect(),
        ));
    }
    // The analysis series run 20 % past the other data: the views must
    // still end at the last sample of all.
    let t_end = 1.2 * t_sim.last().copied().unwrap();
    let series: Vec<Series> = ["V/sim", "grasp_force/sim", "grasp_force/bound"]
        .iter()
        .map(|name| {
            let mut s = Series::new(name.to_string());
            for k in 0..=50 {
                s.push(t_end * k as f64 / 50.0, k as f64);
            }
            s
        })
        .collect();
    let mut rec = fx.record();
    rec.series = &series;
    let path = dir.path().join("run.rrd");
    write_rrd(&path, &rec).unwrap();
    let rrd = read(&path);
    assert_eq!(rrd.end_ns, (t_end * 1e9).round() as i64);
    rrd.check_whole_run("synthetic run");

    let tabs = rrd.tabs();
    assert_eq!(
        tabs.first().map(String::as_str),
        Some("analysis"),
        "{tabs:?}"
    );
    let pos = |t: &str| tabs.iter().position(|x| x.starts_with(t)).unwrap();
    assert!(pos("commands") > pos("state"), "{tabs:?}");

    // One quantity per plot: each robot's grasp force together, never with a torque.
    let views = rrd.time_series_views();
    for (v, title) in &views {
        let q = rrd.queries(v).join(" ");
        assert!(
            !(q.contains("force") && q.contains("torque")),
            "`{title}` mixes force and torque: {q}"
        );
    }
    let force = views
        .iter()
        .find(|(v, _)| rrd.queries(v).iter().any(|q| q.contains("grasp1_force")))
        .expect("a grasp force plot");
    assert!(
        rrd.queries(&force.0)
            .iter()
            .any(|q| q.contains("grasp2_force")),
        "both grasps' force in one plot"
    );
}

/// A shipped scenario's log: the car parking run, written by the binary.
#[test]
fn a_real_runs_views_open_on_the_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/car_parking.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(["run", "--quiet", "--logs"])
        .arg(dir.path())
        .arg(&scenario)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rrd = read(&dir.path().join("car_parking/run.rrd"));
    rrd.check_whole_run("car_parking");
    assert_eq!(rrd.tabs().first().map(String::as_str), Some("analysis"));
}
