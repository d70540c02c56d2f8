//! V and ∂V/∂q by hand-written adjoints: the fast path of [`Scene::field`].
//!
//! Why: in forward dual numbers ([`Scene::field_dual`]) every operation
//! carries all 9k derivatives, although each contact value β depends on the
//! poses of two ellipsoids only and everything after the contact solves is a
//! cheap function of per-pair scalars. Here V is evaluated once in f64, by the
//! same operations in the same order as [`Scene::evaluate`] (so V is
//! bit-identical), and its gradient is then propagated backwards:
//!
//! * V → ln of the numerator, Σ‖h2‖² and the dipoles γ_r (closed form);
//! * per part, Eq. 9 and the proximities in reverse → adjoints of each β_pi,
//!   of the part's point h_p and of the offsets h_p − h_Oi;
//! * β_pi → the poses of its two ellipsoids by the envelope theorem:
//!   β = b_B(x*) + μ b_A(x*) with x* fixed, and moving ellipsoid E rigidly
//!   changes b_E(x*) as the force −∇b_E(x*) applied at x* would (the
//!   minimised side A with weight μ, the other B with weight 1);
//! * the forces on a robot's links become wrenches (F, M about the world
//!   origin), and joint j (axis z_j through p_j) gets z_j · (M − p_j × F)
//!   of everything it moves; the platform's x, y, θ likewise;
//! * the beam: its segments move rigidly with robot 1's tool (a wrench) and
//!   deform with q_f; ∂/∂q_f of the segments' adjoint-weighted poses and of
//!   b_f in dual numbers over q_f, chained through q_f's derivatives over
//!   rigid motions of both tool frames (`beam_wrenches`).
//!
//! The generic dual-number evaluation stays as the reference; tests compare
//! the two at random configurations.

use crate::model::spatial::{self, Pose, M3, V3};
use crate::robots::mobile_manipulator::dilf::contact::{Contact, ContactError};
use crate::robots::mobile_manipulator::dilf::object::{BeamState, Carried};
use crate::robots::mobile_manipulator::dilf::point_world::{switch_exponent, switch_log};
use crate::robots::mobile_manipulator::dilf::potential::{
    placed_generic, DipoleProduct, Evaluation, GoalFrame, GraspCorrection, Scene, Warm,
};
use crate::robots::mobile_manipulator::dilf::scratch::{Pair, PartStage, Side};
use crate::robots::mobile_manipulator::ellipsoid::PlacedEllipsoid;
use crate::robots::mobile_manipulator::kinematics::{self as mm, Link, Part, DOF};
use num_dual::DualSVec64;

/// Derivatives with respect to rigid motions (v, ω) of the two tool frames.
type D12 = DualSVec64<12>;
/// Derivatives with respect to one arm's six joints.
type D6 = DualSVec64<6>;
/// Derivatives with respect to the beam's q_f and gravity in its end-0 frame.
type D15 = DualSVec64<15>;

/// How many joints move a link (0: the platform only).
fn depth(link: Link) -> usize {
    match link {
        Link::Base => 0,
        Link::Arm(i) => (i as usize).clamp(1, 6),
        Link::Tool => 6,
    }
}

/// Where the reverse pass puts forces on shapes.
struct Sink<'a> {
    parts: &'a [Part],
    wrench: &'a mut [[(V3<f64>, V3<f64>); 7]],
    seg_bar: &'a mut [(V3<f64>, M3<f64>)],
    segs: &'a [PlacedEllipsoid<f64>],
}

impl Sink<'_> {
    /// ∂V/∂(rigid motion of `side`) gains the force `f` applied at `at`.
    fn force(&mut self, side: Side, f: V3<f64>, at: V3<f64>) {
        match side {
            Side::Static => {}
            Side::Part(j) => {
                let n = self.parts.len();
                let w = &mut self.wrench[j / n][depth(self.parts[j % n].link)];
                w.0 = spatial::add(w.0, f);
                w.1 = spatial::add(w.1, spatial::cross(at, f));
            }
            Side::Segment(j) => {
                // `at` = c + R R₀ᵀ (at − c₀) moves with the segment's (c, R).
                let e = &self.segs[j];
                let local = spatial::mul_mtv(&e.rot, spatial::sub(at, e.center));
                let (cb, rb) = &mut self.seg_bar[j];
                *cb = spatial::add(*cb, f);
                for (row, fa) in rb.iter_mut().zip(f) {
                    for (x, l) in row.iter_mut().zip(local) {
                        *x += fa * l;
                    }
                }
            }
        }
    }
}

/// `g += w · eps(x)`.
fn add_eps<const N: usize>(g: &mut [f64; N], x: &DualSVec64<N>, w: f64) {
    if let Some(e) = &x.eps.0 {
        for (gi, ei) in g.iter_mut().zip(e.iter()) {
            *gi += w * ei;
        }
    }
}

/// A world point or axis `x` under the rigid motion y ↦ y + ω × y + v with
/// (v, ω) the dual variables `off..off + 6` (v only if `translate`).
fn moved(x: V3<f64>, off: usize, translate: bool) -> V3<D12> {
    let seed = |i: usize| D12::from_re(0.0).derivative(i);
    let w = [seed(off + 3), seed(off + 4), seed(off + 5)];
    std::array::from_fn(|a| {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        // (ω × x)_a = ω_b x_c − ω_c x_b.
        let y = D12::from_re(x[a]) + w[b] * x[c] - w[c] * x[b];
        if translate {
            y + seed(off + a)
        } else {
            y
        }
    })
}

/// A world frame under the rigid motion of [`moved`].
fn moved_frame(p: &Pose<f64>, off: usize) -> Pose<D12> {
    let cols: [V3<D12>; 3] = std::array::from_fn(|j| moved(spatial::col(&p.r, j), off, false));
    Pose {
        r: std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i])),
        p: moved(p.p, off, true),
    }
}

/// Wrenches (force, moment about the origin) on the two robots' tool frames
/// from the beam segments' adjoints and ∂V/∂ln b_f (`ln_bar`). The segments
/// are end0 ∘ (their frame in end 0, a function of q_f and of gravity in
/// the end-0 frame g): they move rigidly with end 0, i.e. with robot 1's
/// tool, and deform with (q_f, g), which depend on both tools. The first
/// part is a plain wrench; the second is ∂/∂(q_f, g) in dual numbers over
/// those 15, chained through their derivatives over rigid motions of the
/// tools (12-wide, but only the FE map, not the segments). With the printed
/// bound and rigid wrists nothing depends on g directly, and its three
/// adjoints are zero.
fn beam_wrenches(
    o: &Carried,
    st: &BeamState<f64>,
    tools: [&Pose<f64>; 2],
    segs: &[PlacedEllipsoid<f64>],
    seg_bar: &[(V3<f64>, M3<f64>)],
    ln_bar: f64,
) -> [(V3<f64>, V3<f64>); 2] {
    let q_f: [D15; 12] = std::array::from_fn(|i| D15::from_re(st.q_f[i]).derivative(i));
    let grav: [D15; 3] = std::array::from_fn(|i| D15::from_re(st.gravity[i]).derivative(12 + i));
    let mut a = [0.0; 15];
    if let Some(l) = o.ln_admissible(&q_f, &grav) {
        add_eps(&mut a, &l, ln_bar);
    }
    let r0 = &st.end0.r;
    let (mut f, mut m) = ([0.0; 3], [0.0; 3]);
    let frames = o.segment_frames(&q_f, &grav);
    for (frame, (e, (cb, rb))) in frames.iter().zip(segs.iter().zip(seg_bar)) {
        // Rigid: ⟨R̄, [ω]× R⟩ = ω · vee(R̄Rᵀ − RR̄ᵀ).
        let mm: M3<f64> =
            std::array::from_fn(|i| std::array::from_fn(|l| spatial::dot(rb[i], e.rot[l])));
        let tau = [
            mm[2][1] - mm[1][2],
            mm[0][2] - mm[2][0],
            mm[1][0] - mm[0][1],
        ];
        f = spatial::add(f, *cb);
        m = spatial::add(m, spatial::add(spatial::cross(e.center, *cb), tau));
        // Deformation: the adjoints in end-0 coordinates, R₀ᵀ c̄ and R₀ᵀ R̄.
        let cl = spatial::mul_mtv(r0, *cb);
        for (x, w) in frame.p.iter().zip(cl) {
            add_eps(&mut a, x, w);
        }
        for (i, row) in frame.r.iter().enumerate() {
            for (l, x) in row.iter().enumerate() {
                let w = (0..3).map(|n| r0[n][i] * rb[n][l]).sum::<f64>();
                add_eps(&mut a, x, w);
            }
        }
    }
    let moved_st = o.state_from_tools(&moved_frame(tools[0], 0), &moved_frame(tools[1], 6));
    let mut g = [0.0; 12];
    for (x, w) in moved_st.q_f.iter().zip(a) {
        add_eps(&mut g, x, w);
    }
    if a[12..].iter().any(|w| *w != 0.0) {
        for (x, w) in moved_st.gravity.iter().zip(&a[12..]) {
            add_eps(&mut g, x, *w);
        }
    }
    [
        (
            spatial::add(f, [g[0], g[1], g[2]]),
            spatial::add(m, [g[3], g[4], g[5]]),
        ),
        ([g[6], g[7], g[8]], [g[9], g[10], g[11]]),
    ]
}

/// d(Rz(θ)ᵀ v)/dθ with (s, c) = (sin θ, cos θ).
fn d_rot_z_t(s: f64, c: f64, v: V3<f64>) -> V3<f64> {
    [-s * v[0] + c * v[1], -c * v[0] - s * v[1], 0.0]
}

impl Scene {
    /// V, D and the field f = D^p ∂V/∂q (Eq. 17, p = `field_power`) at q;
    /// the gradient by hand-written adjoints (see [`crate::robots::mobile_manipulator::dilf::adjoint`]), equal
    /// to [`Scene::field_dual`]'s to round-off.
    pub fn field(
        &self,
        q: &[f64],
        warm: &mut Warm,
    ) -> Result<(Evaluation<f64>, Vec<f64>), ContactError> {
        self.field_with(q, None, warm)
    }

    /// As [`Scene::field`], with the beam at the measured flanges
    /// ([`GraspCorrection`]).
    pub fn field_with(
        &self,
        q: &[f64],
        measured: Option<&GraspCorrection>,
        warm: &mut Warm,
    ) -> Result<(Evaluation<f64>, Vec<f64>), ContactError> {
        let Warm { slots, scratch: s } = warm;
        let (n, k) = (self.parts.len(), self.robots);
        s.frames.clear();
        s.placed.clear();
        for r in 0..k {
            let f = mm::frames::<f64>(&q[DOF * r..DOF * (r + 1)]);
            s.placed.extend(
                self.parts
                    .iter()
                    .map(|p| placed_generic(&p.shape, f.link(p.link))),
            );
            s.frames.push(f);
        }
        // The beam (its derivatives come in the reverse pass).
        s.segs.clear();
        let tools = match (measured, self.object.is_some()) {
            (Some(c), true) => [s.frames[0].tool.then(&c[0]), s.frames[1].tool.then(&c[1])],
            (_, true) => [s.frames[0].tool, s.frames[1].tool],
            _ => [Pose::identity(); 2],
        };
        let beam = self.object.as_ref().map(|o| {
            let st = o.state_from_tools(&tools[0], &tools[1]);
            s.segs.extend((0..o.segments).map(|j| o.segment(&st, j)));
            (
                o.ln_admissible(&st.q_f, &st.gravity),
                st.max_deformation(),
                o.margin(&st.q_f, &st.gravity),
                st,
            )
        });

        // Forward: Scene::evaluate in f64, keeping what the reverse pass needs.
        let ln_lambda = self.params.lambda.ln();
        let (mut ln_num, mut d, mut gamma) = (0.0, 0.0, 1.0);
        let mut min_beta = f64::INFINITY;
        let mut slot = 0;
        let mut collided = false;
        s.pairs.clear();
        s.parts.clear();
        s.gammas.clear();
        for r in 0..k {
            let qr = &q[DOF * r..DOF * (r + 1)];
            let base_rot = spatial::rot_z(qr[2]);
            let heading = spatial::rot_z(self.goal[DOF * r + 2]);
            for i in 0..n {
                let pid = r * n + i;
                let part = s.placed[pid];
                let c = part.center;
                let platform = i != 0 && self.params.goal_frame == GoalFrame::Platform;
                let (h_now, rot) = if platform {
                    let base_p = [qr[0], qr[1], 0.0];
                    (
                        spatial::mul_mtv(&base_rot, spatial::sub(c, base_p)),
                        base_rot,
                    )
                } else {
                    (spatial::mul_mtv(&heading, c), heading)
                };
                let h = spatial::sub(h_now, self.goal_points[pid]);
                let start = s.pairs.len();
                let mut seen = |sol: &Contact, beta: f64, sides: [Side; 3], o_center: V3<f64>| {
                    min_beta = min_beta.min(sol.value);
                    collided |= sol.value <= 0.0;
                    s.pairs
                        .push(Pair::new(beta, sol, sides, spatial::sub(c, o_center)));
                };
                for o in &self.obstacles {
                    let sol = self.solve(&part, &o.shape, &mut slots[slot])?;
                    slot += 1;
                    let beta = part.value(sol.x) * sol.mu + sol.value;
                    let sides = [Side::Part(pid), Side::Static, Side::Static];
                    seen(&sol, beta, sides, o.shape.center);
                }
                for j in (0..k)
                    .filter(|&o| o != r)
                    .flat_map(|o| (0..n).map(move |j| o * n + j))
                {
                    let o = &s.placed[j];
                    let sol = self.solve(&part, o, &mut slots[slot])?;
                    slot += 1;
                    let sides = [Side::Part(pid), Side::Part(j), Side::Part(j)];
                    seen(&sol, sol.beta(&part, o), sides, o.center);
                }
                if let Some(obj) = &self.object {
                    for (j, o) in s.segs.iter().enumerate() {
                        let s_slot = slot;
                        slot += 1;
                        if obj.held(r, &self.parts[i], j) {
                            continue;
                        }
                        // Roles swapped, as in Scene::evaluate.
                        let sol = self.solve(o, &part, &mut slots[s_slot])?;
                        let sides = [Side::Segment(j), Side::Part(pid), Side::Segment(j)];
                        seen(&sol, sol.beta(o, &part), sides, o.center);
                    }
                }
                if collided {
                    continue;
                }
                let pairs = &mut s.pairs[start..];
                s.ln_b.clear();
                s.ln_b.extend(pairs.iter().map(|p| p.lb));
                let hh = spatial::dot(h, h);
                let switched = hh > 1e-24 && !pairs.is_empty();
                let mut shift = [0.0; 3];
                let (mut ln_h, mut total) = (0.0, 0.0);
                if switched {
                    ln_h = hh.ln() * 0.5;
                    total = s.ln_b.iter().copied().sum();
                    for p in pairs.iter_mut() {
                        p.sigma = switch_log(switch_exponent(ln_h, p.lb, total, ln_lambda));
                        p.sqrt_b = (p.lb * 0.5).exp();
                        let a = p.sigma * (p.sqrt_b - 1.0);
                        shift = spatial::add(shift, spatial::scale(p.delta, a));
                    }
                }
                for p in pairs.iter_mut() {
                    p.moved = spatial::add(p.delta, shift);
                    let ratio = spatial::dot(p.moved, p.moved) / spatial::dot(p.delta, p.delta);
                    ln_num += ratio.ln() * 0.5;
                }
                let h2 = spatial::add(h, spatial::mul_mtv(&rot, shift));
                d += spatial::dot(h2, h2);
                if i == 0 {
                    let g = if h2[0] >= 0.0 { h2[0] } else { -h2[0] };
                    gamma *= g;
                    s.gammas.push(g);
                }
                s.parts.push(PartStage {
                    pairs: (start, s.pairs.len()),
                    c,
                    h,
                    hh,
                    switched,
                    ln_h,
                    total,
                    shift,
                    h2,
                    rot,
                    platform,
                });
            }
        }
        // The beam's segments against the static obstacles (after all parts,
        // as in Scene::evaluate): a factor b̃ = β/(1+β) each; the segment is
        // the minimised side, so its adjoint is the force −μ ∇b_seg(x*).
        s.seg_static.clear();
        if self.object.is_some() {
            for (j, seg) in s.segs.iter().enumerate() {
                for o in &self.obstacles {
                    let sol = self.solve(seg, &o.shape, &mut slots[slot])?;
                    slot += 1;
                    min_beta = min_beta.min(sol.value);
                    collided |= sol.value <= 0.0;
                    if !collided {
                        let b = seg.value(sol.x) * sol.mu + sol.value;
                        ln_num += (b / (b + 1.0)).ln();
                        s.seg_static.push((j, b, sol.x, sol.mu));
                    }
                }
            }
        }
        // Singularity enclosures, with their derivatives over the arm joints.
        let mut min_singular = f64::INFINITY;
        s.singular.clear();
        for r in 0..k {
            let arm: [D6; 6] =
                std::array::from_fn(|j| D6::from_re(q[DOF * r + 3 + j]).derivative(j));
            let mut g = [0.0; 6];
            for sv in self.params.singularity.value_array(&arm).iter().flatten() {
                let sf = sv.re;
                min_singular = min_singular.min(sf);
                if sf > 0.0 {
                    // ln(s/(s+1)), derivative s'/(s(s+1)).
                    ln_num += (sf / (sf + 1.0)).ln();
                    add_eps(&mut g, sv, 1.0 / (sf * (sf + 1.0)));
                }
            }
            s.singular.push(g);
        }
        let (max_deformation, admissible, beam) = match beam {
            Some((ln_bf, m, margin, st)) => {
                if let Some(l) = ln_bf {
                    ln_num += l;
                }
                (m, margin, Some(st))
            }
            None => (0.0, f64::INFINITY, None),
        };
        // The same factors: ln b_f is None exactly when the margin is ≤ 0.
        let overstrained = admissible <= 0.0;
        let evaluation = |v: f64| Evaluation {
            v,
            d,
            min_beta,
            min_singular,
            max_deformation,
            admissible,
        };
        if collided || overstrained || min_singular <= 0.0 {
            return Ok((evaluation(0.0), vec![0.0; DOF * k]));
        }
        let geometric = self.params.dipole == DipoleProduct::GeometricMean && k > 1;
        let formation = self.params.dipole == DipoleProduct::Formation;
        let inv_k = 1.0 / k as f64;
        let decay = (ln_num * (1.0 / self.params.kv)).exp();
        // The formation's dipole: |mean of the platforms' signed x|.
        let x_mean = s.parts.iter().step_by(n).map(|st| st.h2[0]).sum::<f64>() * inv_k;
        let dipole = match (formation, geometric) {
            (true, _) => x_mean.abs(),
            (false, true) => gamma.powf(inv_k),
            (false, false) => gamma,
        };
        let v = dipole * decay / d;

        // Reverse: V's adjoints, then each part's stage.
        let ln_bar = v / self.params.kv;
        let d_bar = -v / d;
        let gamma_bar = |r: usize| {
            let others: f64 = (0..k).filter(|&o| o != r).map(|o| s.gammas[o]).product();
            let dg = if geometric {
                inv_k * gamma.powf(inv_k - 1.0) * others
            } else {
                others
            };
            dg * decay / d
        };
        let mut grad = vec![0.0; DOF * k];
        s.wrench.clear();
        s.wrench.resize(k, [([0.0; 3], [0.0; 3]); 7]);
        s.seg_bar.clear();
        s.seg_bar.resize(s.segs.len(), ([0.0; 3], [[0.0; 3]; 3]));
        let mut sink = Sink {
            parts: &self.parts,
            wrench: &mut s.wrench,
            seg_bar: &mut s.seg_bar,
            segs: &s.segs,
        };
        let center = |side: Side| match side {
            Side::Static => [0.0; 3],
            Side::Part(j) => s.placed[j].center,
            Side::Segment(j) => s.segs[j].center,
        };
        let grad_at = |side: Side, x: V3<f64>| match side {
            Side::Static => [0.0; 3],
            Side::Part(j) => s.placed[j].grad(x),
            Side::Segment(j) => s.segs[j].grad(x),
        };
        for (pid, st) in s.parts.iter().enumerate() {
            let (r, i) = (pid / n, pid % n);
            let (sn, cs) = q[DOF * r + 2].sin_cos();
            let mut h2_bar = spatial::scale(st.h2, 2.0 * d_bar);
            if i == 0 && formation {
                // ∂|x̄|/∂x_r = sign(x̄)/k, sign(0) = +1.
                let gb = inv_k * decay / d;
                h2_bar[0] += if x_mean >= 0.0 { gb } else { -gb };
            } else if i == 0 {
                let gb = gamma_bar(r);
                h2_bar[0] += if st.h2[0] >= 0.0 { gb } else { -gb };
            }
            let mut h_bar = h2_bar;
            let mut shift_bar = spatial::mul_mv(&st.rot, h2_bar);
            if st.platform {
                grad[DOF * r + 2] += spatial::dot(h2_bar, d_rot_z_t(sn, cs, st.shift));
            }
            let pairs = &s.pairs[st.pairs.0..st.pairs.1];
            // Proximities: ½ ln(‖δ + shift‖² / ‖δ‖²) each.
            s.bar.clear();
            for p in pairs {
                let m_bar = spatial::scale(p.moved, ln_bar / spatial::dot(p.moved, p.moved));
                let dd_bar = spatial::scale(p.delta, ln_bar / spatial::dot(p.delta, p.delta));
                s.bar.push((spatial::sub(m_bar, dd_bar), 0.0));
                shift_bar = spatial::add(shift_bar, m_bar);
            }
            // Eq. 9: shift = Σ σ_j (√b̃_j − 1) δ_j, σ_j = 1 / (1 + e^{r_j}).
            if st.switched {
                let (mut total_bar, mut ln_h_bar) = (0.0, 0.0);
                for (p, b) in pairs.iter().zip(s.bar.iter_mut()) {
                    let a_bar = spatial::dot(shift_bar, p.delta);
                    b.0 = spatial::add(b.0, spatial::scale(shift_bar, p.sigma * (p.sqrt_b - 1.0)));
                    let sigma_bar = a_bar * (p.sqrt_b - 1.0);
                    b.1 = 0.5 * p.sqrt_b * a_bar * p.sigma;
                    let rj = switch_exponent(st.ln_h, p.lb, st.total, ln_lambda);
                    // dσ/dr = −e^{−|r|} / (1 + e^{−|r|})², accurate at both tails.
                    let e = (-rj.abs()).exp();
                    let r_bar = -sigma_bar * e / ((1.0 + e) * (1.0 + e));
                    b.1 += 2.0 * r_bar;
                    total_bar -= r_bar;
                    ln_h_bar -= r_bar;
                }
                for b in s.bar.iter_mut() {
                    b.1 += total_bar;
                }
                h_bar = spatial::add(h_bar, spatial::scale(st.h, ln_h_bar / st.hh));
            }
            let me = Side::Part(pid);
            for (p, b) in pairs.iter().zip(&s.bar) {
                // ln b̃ = ln β − ln(β + 1); then the envelope theorem.
                let beta_bar = b.1 / (p.beta * (p.beta + 1.0));
                if p.mu != 0.0 {
                    let g = grad_at(p.minimised, p.x);
                    sink.force(p.minimised, spatial::scale(g, -beta_bar * p.mu), p.x);
                }
                let g = grad_at(p.other, p.x);
                sink.force(p.other, spatial::scale(g, -beta_bar), p.x);
                sink.force(me, b.0, st.c);
                sink.force(p.obstacle, spatial::scale(b.0, -1.0), center(p.obstacle));
            }
            // h = rotᵀ c − goal, or rotᵀ (c − (x, y, 0)) − goal with rot = Rz(θ).
            let c_bar = spatial::mul_mv(&st.rot, h_bar);
            sink.force(me, c_bar, st.c);
            if st.platform {
                let b = [q[DOF * r], q[DOF * r + 1], 0.0];
                grad[DOF * r] -= c_bar[0];
                grad[DOF * r + 1] -= c_bar[1];
                grad[DOF * r + 2] += spatial::dot(h_bar, d_rot_z_t(sn, cs, spatial::sub(st.c, b)));
            }
        }
        for &(j, b, x, mu) in &s.seg_static {
            let beta_bar = ln_bar / (b * (b + 1.0));
            let g = s.segs[j].grad(x);
            sink.force(Side::Segment(j), spatial::scale(g, -beta_bar * mu), x);
        }
        if let (Some(o), Some(st)) = (&self.object, &beam) {
            let w = beam_wrenches(o, st, [&tools[0], &tools[1]], &s.segs, &s.seg_bar, ln_bar);
            for (r, (f, m)) in w.into_iter().enumerate() {
                let t = &mut s.wrench[r][6];
                t.0 = spatial::add(t.0, f);
                t.1 = spatial::add(t.1, m);
            }
        }
        // Wrenches → joints (each moves everything at its depth and beyond).
        for r in 0..k {
            let (mut f, mut m) = ([0.0; 3], [0.0; 3]);
            for j in (0..7).rev() {
                f = spatial::add(f, s.wrench[r][j].0);
                m = spatial::add(m, s.wrench[r][j].1);
                if j > 0 {
                    let a = &s.frames[r].arm[j - 1];
                    let z = spatial::col(&a.r, 2);
                    let moment = spatial::sub(m, spatial::cross(a.p, f));
                    grad[DOF * r + 2 + j] += spatial::dot(z, moment);
                }
            }
            let (x, y) = (q[DOF * r], q[DOF * r + 1]);
            grad[DOF * r] += f[0];
            grad[DOF * r + 1] += f[1];
            grad[DOF * r + 2] += m[2] - (x * f[1] - y * f[0]);
            for (g, sg) in grad[DOF * r + 3..DOF * (r + 1)]
                .iter_mut()
                .zip(s.singular[r])
            {
                *g += ln_bar * sg;
            }
        }
        let dp = d.powf(self.params.field_power);
        for g in grad.iter_mut() {
            *g *= dp;
        }
        Ok((evaluation(v), grad))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::mobile_manipulator::dilf::object::table_i_start_and_goal_ahead;
    use crate::robots::mobile_manipulator::dilf::object::tests::{perturbed, scene as beam_scene};
    use crate::robots::mobile_manipulator::dilf::potential::tests::{random_q, scene};
    use crate::robots::mobile_manipulator::dilf::potential::PotentialParams;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Relative difference.
    fn rel_diff(a: f64, b: f64) -> f64 {
        (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
    }

    /// The adjoint field against the dual-number reference, from fresh warm
    /// starts: V bit for bit as `evaluate::<f64>` gives it (dual numbers
    /// divide by multiplying with the reciprocal, so they differ in the last
    /// bits), f to `rel` of its largest component.
    fn assert_matches_dual(s: &Scene, q: &[f64], rel: f64, what: &str) {
        let (e, f) = s.field(q, &mut s.warm()).unwrap();
        let (e_ref, f_ref) = s.field_dual(q, &mut s.warm()).unwrap();
        let plain = s.evaluate::<f64>(q, &mut s.warm()).unwrap();
        assert_eq!((e.v, e.d), (plain.v, plain.d), "{what}: V, D");
        assert_eq!(e.min_beta, plain.min_beta, "{what}");
        assert_eq!(e.min_singular, plain.min_singular, "{what}");
        assert_eq!(e.max_deformation, plain.max_deformation, "{what}");
        assert!(
            rel_diff(e.v, e_ref.v) < 1e-13,
            "{what}: V {} vs {}",
            e.v,
            e_ref.v
        );
        assert!(rel_diff(e.d, e_ref.d) < 1e-13, "{what}: D");
        assert_eq!(f.len(), f_ref.len());
        let scale = f_ref.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0 && scale.is_finite(), "{what}: f = {f_ref:?}");
        for (i, (a, b)) in f.iter().zip(&f_ref).enumerate() {
            assert!(
                (a - b).abs() <= rel * scale,
                "{what} coord {i}: adjoint {a:e}, dual {b:e} (largest {scale:e})"
            );
        }
    }

    #[test]
    fn one_robot_alone_matches_dual_numbers() {
        let with_obstacles = scene(1, GoalFrame::Platform);
        let s = Scene::new(
            1,
            with_obstacles.parts.clone(),
            Vec::new(),
            with_obstacles.goal.clone(),
            with_obstacles.params,
        )
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for trial in 0..20 {
            let q = random_q(&s, &mut rng);
            assert_matches_dual(&s, &q, 1e-10, &format!("alone, trial {trial}"));
        }
    }

    #[test]
    fn one_robot_among_obstacles_matches_dual_numbers() {
        for frame in [GoalFrame::Platform, GoalFrame::World] {
            let s = scene(1, frame);
            let mut rng = ChaCha8Rng::seed_from_u64(2);
            for trial in 0..20 {
                let q = random_q(&s, &mut rng);
                assert_matches_dual(&s, &q, 1e-10, &format!("{frame:?}, trial {trial}"));
            }
        }
    }

    #[test]
    fn two_robots_match_dual_numbers() {
        for dipole in [
            DipoleProduct::GeometricMean,
            DipoleProduct::Printed,
            DipoleProduct::Formation,
        ] {
            let mut s = scene(2, GoalFrame::Platform);
            s.params = PotentialParams { dipole, ..s.params };
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            for trial in 0..12 {
                let q = random_q(&s, &mut rng);
                assert_matches_dual(&s, &q, 1e-10, &format!("{dipole:?}, trial {trial}"));
            }
        }
    }

    #[test]
    fn two_robots_with_the_beam_match_dual_numbers() {
        let (q0, goal) = table_i_start_and_goal_ahead();
        for frame in [GoalFrame::Platform, GoalFrame::World] {
            // The goal points depend on the frame: build the scene anew.
            let base = beam_scene(&q0, goal.clone(), 0.5);
            let params = PotentialParams {
                goal_frame: frame,
                ..base.params
            };
            let s = Scene::new(2, base.parts.clone(), Vec::new(), goal.clone(), params)
                .unwrap()
                .with_object(base.object.clone().unwrap());
            let mut rng = ChaCha8Rng::seed_from_u64(4);
            let mut checked = 0;
            while checked < 12 {
                let q = perturbed(&q0, &mut rng, 0.15);
                let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
                if !(e.v > 0.0 && e.min_beta > 0.0) {
                    continue;
                }
                checked += 1;
                assert_matches_dual(&s, &q, 1e-10, &format!("beam {frame:?}, sample {checked}"));
            }
        }
    }

    /// The beam's segments against static obstacles (a box above and one
    /// below the beam's middle, 0.3–0.4 m off): the term's gradient goes
    /// through the segments' adjoints to both tools, against dual numbers and
    /// central differences.
    #[test]
    fn the_beam_among_obstacles_matches_dual_numbers_and_differences() {
        use crate::robots::mobile_manipulator::dilf::potential::tests::assert_field_is_scaled_gradient;
        use crate::robots::mobile_manipulator::dilf::potential::Obstacle;
        use crate::robots::mobile_manipulator::ellipsoid::Superellipsoid;
        let (q0, goal) = table_i_start_and_goal_ahead();
        let (a, b) = (mm::grasp_point(&q0[..DOF]), mm::grasp_point(&q0[DOF..]));
        let mid = spatial::scale(spatial::add(a, b), 0.5);
        let boxed = |name: &str, dz: f64| Obstacle {
            name: name.into(),
            shape: Superellipsoid {
                center: spatial::add(mid, [0.0, 0.0, dz]),
                semi_axes: [0.3, 0.3, 0.1],
                exponent: 4.0,
                rpy: [0.0; 3],
            }
            .at_rest(),
        };
        let base = beam_scene(&q0, goal.clone(), 0.5);
        let obstacles = vec![boxed("above", 0.45), boxed("below", -0.5)];
        let s = Scene::new(2, base.parts.clone(), obstacles, goal, base.params)
            .unwrap()
            .with_object(base.object.clone().unwrap());
        let bare = base.clone();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut checked = 0;
        while checked < 8 {
            let q = perturbed(&q0, &mut rng, 0.05);
            let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
            if !(e.v > 0.0 && e.min_beta > 0.0) {
                continue;
            }
            checked += 1;
            let what = format!("beam among obstacles, sample {checked}");
            assert_matches_dual(&s, &q, 1e-10, &what);
            assert_field_is_scaled_gradient(&s, &q, 1e-6, &what);
            // The obstacles matter: without them the field differs.
            let (_, f) = s.field(&q, &mut s.warm()).unwrap();
            let (_, f_bare) = bare.field(&q, &mut bare.warm()).unwrap();
            let scale = f.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let gap = f
                .iter()
                .zip(&f_bare)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(gap > 1e-3 * scale, "{what}: the obstacles do not act");
        }
    }

    /// Along a sequence of nearby states with one warm cache (as the
    /// controller calls it), the two paths stay together.
    #[test]
    fn warm_sequence_matches_dual_numbers() {
        let (q0, goal) = table_i_start_and_goal_ahead();
        let s = beam_scene(&q0, goal, 4.0);
        let (mut w1, mut w2) = (s.warm(), s.warm());
        for i in 0..30 {
            let q: Vec<f64> = q0
                .iter()
                .enumerate()
                .map(|(j, x)| x + 0.01 * i as f64 * (j as f64 * 0.7).sin())
                .collect();
            let (e, f) = s.field(&q, &mut w1).unwrap();
            let (e_ref, f_ref) = s.field_dual(&q, &mut w2).unwrap();
            assert!(rel_diff(e.v, e_ref.v) < 1e-13, "state {i}");
            let scale = f_ref.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (a, b) in f.iter().zip(&f_ref) {
                assert!((a - b).abs() <= 1e-10 * scale, "state {i}: {a:e} vs {b:e}");
            }
        }
    }

    /// Where V = 0 (parts overlapping) both paths give a zero field.
    #[test]
    fn collision_gives_a_zero_field_on_both_paths() {
        let s = scene(1, GoalFrame::Platform);
        let mut q = s.goal.clone();
        q[0] = 0.0;
        q[1] = 3.0;
        let (e, f) = s.field(&q, &mut s.warm()).unwrap();
        let (e_ref, f_ref) = s.field_dual(&q, &mut s.warm()).unwrap();
        assert!(e.min_beta <= 0.0);
        assert_eq!((e.v, e.d), (e_ref.v, e_ref.d));
        assert_eq!(f, f_ref);
        assert!(f.iter().all(|x| *x == 0.0));
    }
}
