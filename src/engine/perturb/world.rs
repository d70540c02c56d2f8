//! The world perturbations applied to a URDF before it is built: worn
//! wheels (`wheel_radius_scale`) and heavier links (`mass_scale`).

/// `robot` with its wheels' collision radius scaled by `s`
/// (`wheel_radius_scale`): itself when `s` is 1, else
/// [`shrink_round_collisions`] of `links`.
pub(crate) fn worn_wheels<'r>(
    robot: &'r urdf_rs::Robot,
    links: &[&str],
    s: f64,
) -> std::borrow::Cow<'r, urdf_rs::Robot> {
    if s == 1.0 {
        std::borrow::Cow::Borrowed(robot)
    } else {
        std::borrow::Cow::Owned(shrink_round_collisions(robot, links, s, None))
    }
}

/// `robot` with the collision radius of every sphere and cylinder of the
/// named links multiplied by `s` (wheel wear), or shrunk by `by` m when
/// `absolute` (tyres worn by the same depth everywhere).
pub(crate) fn shrink_round_collisions(
    robot: &urdf_rs::Robot,
    links: &[&str],
    s: f64,
    absolute: Option<f64>,
) -> urdf_rs::Robot {
    let mut out = robot.clone();
    for l in out
        .links
        .iter_mut()
        .filter(|l| links.contains(&l.name.as_str()))
    {
        for c in &mut l.collision {
            match &mut c.geometry {
                urdf_rs::Geometry::Sphere { radius }
                | urdf_rs::Geometry::Cylinder { radius, .. } => {
                    *radius = match absolute {
                        Some(by) => *radius - by,
                        None => *radius * s,
                    };
                }
                _ => {}
            }
        }
    }
    out
}

/// `robot` with every link's mass and inertia multiplied by `s` (`None` at 1).
pub(crate) fn scaled_masses(robot: &urdf_rs::Robot, s: f64) -> Option<urdf_rs::Robot> {
    if s == 1.0 {
        return None;
    }
    let mut out = robot.clone();
    for l in &mut out.links {
        l.inertial.mass.value *= s;
        let i = &mut l.inertial.inertia;
        for x in [
            &mut i.ixx, &mut i.ixy, &mut i.ixz, &mut i.iyy, &mut i.iyz, &mut i.izz,
        ] {
            *x *= s;
        }
    }
    Some(out)
}
