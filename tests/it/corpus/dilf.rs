//! Seed 004's carried beam: the wrench bound and the compliant wrists.

use super::*;

pub fn cases(c: &mut Corpus) {
    let po = shipped("dilf_pair_open.toml");
    c.sc(
        "wrist stiffness negative",
        edit(
            &po,
            "kind = \"compliant\"",
            "kind = \"compliant\"\nstiffness = [400.0, -400.0, 400.0, 50.0, 50.0, 50.0]",
        ),
        Some("stiffness = [400.0, -400.0"),
        Some("model.wrist.stiffness[1]"),
    );
    c.sc(
        "wrist travel zero",
        edit(
            &po,
            "kind = \"compliant\"",
            "kind = \"compliant\"\ntravel = [0.2, 0.2, 0.0, 0.35, 0.35, 0.35]",
        ),
        Some("travel = [0.2, 0.2, 0.0"),
        Some("model.wrist.travel[2]"),
    );
    c.sc(
        "wrist travel negative",
        edit(
            &po,
            "kind = \"compliant\"",
            "kind = \"compliant\"\ntravel = [0.2, 0.2, 0.2, -0.35, 0.35, 0.35]",
        ),
        Some("travel = [0.2, 0.2, 0.2, -0.35"),
        Some("model.wrist.travel[3]"),
    );
    c.sc(
        "wrench bound force zero",
        edit(
            &po,
            "bound = \"wrench\"",
            "bound = \"wrench\"\nmax_force = 0.0",
        ),
        Some("max_force"),
        Some("model.beam.max_force"),
    );
    c.sc(
        "wrench bound force negative",
        edit(
            &po,
            "bound = \"wrench\"",
            "bound = \"wrench\"\nmax_force = -60.0",
        ),
        Some("max_force"),
        Some("model.beam.max_force"),
    );
    c.sc(
        "wrench bound moment zero",
        edit(
            &po,
            "bound = \"wrench\"",
            "bound = \"wrench\"\nmax_moment = 0.0",
        ),
        Some("max_moment"),
        Some("model.beam.max_moment"),
    );
    c.sc(
        "unknown bound kind",
        edit(&po, "bound = \"wrench\"", "bound = \"elastic\""),
        Some("bound = \"elastic\""),
        Some("model.beam.bound"),
    );
    c.sc(
        "unknown wrist kind",
        edit(&po, "kind = \"compliant\"", "kind = \"spring\""),
        Some("kind = \"spring\""),
        Some("model.wrist.kind"),
    );
    c.sc(
        "q_F with the wrench bound",
        edit(
            &po,
            "bound = \"wrench\"",
            "bound = \"wrench\"\nmax_deformation = 0.3",
        ),
        Some("max_deformation"),
        Some("model.beam.max_deformation"),
    );
    c.sc(
        "arm torque limit zero",
        edit(
            &po,
            "max_torque = [97.6, 186.4, 89.4, 24.2, 20.1, 21.3]",
            "max_torque = [97.6, 186.4, 0.0, 24.2, 20.1, 21.3]",
        ),
        Some("max_torque"),
        Some("model.arm_servo.max_torque[2]"),
    );
    c.sc(
        "arm armature negative",
        edit(
            &po,
            "max_torque = [97.6, 186.4, 89.4, 24.2, 20.1, 21.3]",
            "max_torque = [97.6, 186.4, 89.4, 24.2, 20.1, 21.3]\narmature = [0.0, 0.0, 0.0, -0.19, 0.17, 0.19]",
        ),
        Some("armature = [0.0, 0.0, 0.0, -0.19"),
        Some("model.arm_servo.armature[3]"),
    );
    c.sc(
        "approach cap zero",
        edit(
            &po,
            "grasps = \"measured\"",
            "grasps = \"measured\"\n\n[planner.approach]\nradius = 0.5\nheading_deg = 0.0",
        ),
        Some("heading_deg = 0.0"),
        Some("planner.approach.heading_deg"),
    );
    c.sc(
        "sequence turn zero",
        edit(
            &po,
            "grasps = \"measured\"",
            "grasps = \"measured\"\n\n[planner.sequence]\nmode = \"auto\"\nmax_turn_deg = 0.0",
        ),
        Some("max_turn_deg = 0.0"),
        Some("planner.sequence.max_turn_deg"),
    );
    c.sc(
        "unknown sequence mode",
        edit(
            &po,
            "grasps = \"measured\"",
            "grasps = \"measured\"\n\n[planner.sequence]\nmode = \"sometimes\"",
        ),
        Some("mode = \"sometimes\""),
        Some("planner.sequence.mode"),
    );
    c.sc(
        "unknown grasps source",
        edit(&po, "grasps = \"measured\"", "grasps = \"sensed\""),
        Some("grasps = \"sensed\""),
        Some("planner.grasps"),
    );
}
