//! Runaway runs (issue 13 item 4): scenarios that are valid key by key but
//! would run for ever or allocate gigabytes. They are refused up front by the
//! step budget, naming the key responsible.

use super::*;

pub fn cases(c: &mut Corpus) {
    let d = disk();
    // dt = 1e-12: 4.4e12 steps for the paper's 4.4 s plan (ran for ever).
    c.sc(
        "runaway: dt 1e-12",
        edit(&d, "dt = 0.001", "dt = 1e-12"),
        Some("dt = 1e-12"),
        Some("sim.dt"),
    );
    // settle = 1e9 s: 1e12 steps (aborted allocating 8 TB).
    c.sc(
        "runaway: settle 1e9",
        disk_scenario(&model("rolling_disk.urdf"), "name = \"d\"", "settle = 1e9"),
        Some("settle = 1e9"),
        Some("sim.settle"),
    );
    // A disk goal 100 km away: a plan of ~1e5 s (multi-GB samples).
    c.sc(
        "runaway: disk goal 100 km away",
        edit(
            &d,
            "goal = [-0.4, 1.0, 180.0, 22.5]",
            "goal = [100000.0, 1.0, 180.0, 22.5]",
        ),
        Some("dt = 0.001"),
        Some("sim.dt"),
    );
    // A goal at 1e300 m: a plan duration of 1e302 s.
    c.sc(
        "runaway: disk goal 1e300 m away",
        edit(
            &d,
            "goal = [-0.4, 1.0, 180.0, 22.5]",
            "goal = [1e300, 1.0, 180.0, 22.5]",
        ),
        Some("goal = [1e300"),
        Some("goal"),
    );
    // The rover 8 km from its goal with a long horizon: the closed loop's
    // horizon is the run's length.
    let rover = edit(
        &edit(
            &shipped("rover_paper.toml"),
            "goal = [8.0, 2.0",
            "goal = [8000.0, 2.0",
        ),
        "horizon = 300.0",
        "horizon = 100000.0",
    );
    c.sc(
        "runaway: rover goal 8 km away, long horizon",
        rover.clone(),
        Some("dt = 0.002"),
        Some("sim.dt"),
    );
    // The same with the open-loop replay: the planner records the closed loop
    // while planning, so the horizon is refused before planning.
    let open_loop = edit(
        &edit(
            &shipped("rover_open_loop.toml"),
            "goal = [8.0, 2.0",
            "goal = [8000.0, 2.0",
        ),
        "horizon = 300.0",
        "horizon = 100000.0",
    );
    c.sc(
        "runaway: rover open-loop replay, long horizon",
        open_loop,
        Some("horizon = 100000.0"),
        Some("planner.horizon"),
    );
}
