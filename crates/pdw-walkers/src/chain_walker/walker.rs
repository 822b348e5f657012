//! The chain walker's model-level extras ([`Walker`]): names, fingerprint, gait guesses, pose
//! and body points, constraint forces, energy, units, impact reports and clearance.

use super::{ChainWalker, FMAX};
use crate::validity::{ClearanceRule, ConstraintForces, ImpactReport, Scales, StepFlags};
use pdw_hybrid::{Scratch, Section};
use pdw_model::{BodyPoints, GaitGuess, Pose, StepHeight, Walker};

impl ChainWalker {
    /// The spec's gaits as given, or the generic start.
    fn gait_guesses3(&self) -> Vec<GaitGuess> {
        if self.r.gaits.is_empty() {
            // Goswami's compass gait at 3° scaled by √(g/L): a start that reaches the
            // period-one gait of most straight-legged walkers on small slopes.
            let w = (self.r.gravity / self.leg_length).sqrt();
            return vec![GaitGuess {
                gait: "stable".into(),
                section: vec![0.27, -0.35 * w, 0.23 * w],
                source: "generic start (the compass gait's at 3°, rates scaled by √(g/L)); the \
                         spec gives no gait"
                    .into(),
            }];
        }
        self.r
            .gaits
            .iter()
            .map(|(name, section, source)| GaitGuess {
                gait: name.clone(),
                section: section.clone(),
                source: source.clone(),
            })
            .collect()
    }
}

impl Walker for ChainWalker {
    /// `q₀` is the one absolute angle (Garcia's θ, chain walker docs "Coordinates"; gravity enters
    /// as the base acceleration of slope γ, so the stance leg's world angle is `q₀ − γ`): it grows
    /// by
    /// `s' − s`. Round feet: `None` — the stance arc's contact point moves along the line, so a
    /// change of line is not a rotation about the contact point.
    fn terrain_frame(&self) -> Option<(usize, f64)> {
        (self.radius == 0.0).then_some((0, 1.0))
    }
    /// `q₀`, from the slope normal for point and round feet alike.
    fn absolute_angle(&self) -> Option<(usize, f64)> {
        Some((0, 1.0))
    }
    /// The hip angle `q_m` of a walker whose knees stay locked (one mode): both legs straight
    /// and equally long, so the feet (or the arc centres, `r` above each foot) are level at
    /// `q_m = 0`.
    fn legs_together(&self) -> Option<usize> {
        (self.masks.len() == 1).then_some(self.m)
    }
    /// Point and round feet (chain walker docs, "Step down").
    fn step_height(&self) -> Option<&dyn StepHeight> {
        Some(self as &dyn StepHeight)
    }
    /// [`ChainWalker::with_tilt`] (chain walker docs, "Landing on a tilted line").
    fn on_tilted_line(&self, delta: f64) -> Option<Result<Box<dyn Walker>, String>> {
        Some(
            self.with_tilt(delta)
                .map(|w| Box::new(w) as Box<dyn Walker>)
                .map_err(|e| e.to_string()),
        )
    }
    /// `stance_reverses` counts while `q₀ > slope` (`ChainWalker::admissible_on`).
    fn admissible_on_slope(&self, mode: usize, k: usize, x: &[f64], slope: f64) -> bool {
        self.admissible_on(mode, k, x, slope, self.r.step_down)
    }
    fn name(&self) -> &str {
        &self.spec.name
    }
    fn state_names(&self) -> Vec<String> {
        self.state_names.clone()
    }
    /// Module docs, "Coordinates": `q₀` absolute from the slope normal, every other joint
    /// relative to the segment above it.
    fn coordinate_meanings(&self) -> Vec<String> {
        self.state_names
            .iter()
            .map(|n| chain_coordinate(n))
            .collect()
    }
    /// Module docs, "Modes".
    fn mode_names(&self) -> Vec<String> {
        if self.free_knee.is_some() {
            vec!["swing knee free".into(), "knees locked".into()]
        } else {
            vec!["knees locked".into()]
        }
    }
    /// The resolved geometry (every segment, knee and foot at the current
    /// parameter values), not the expressions that gave it: two specs that resolve to the
    /// same walker have the same fingerprint. Gait guesses are left out (they start Newton
    /// and do not change the dynamics).
    fn fingerprint(&self) -> String {
        let r = &self.r;
        let mut s = format!(
            "model = {}\nkind = chain walker\nslope = {:?}\ngravity = {:?}\n\
             max_stride_time = {:?}\nhip_mass = {:?}\nfoot_radius = {:?}\n",
            self.spec.name, r.slope, r.gravity, r.max_stride_time, r.hip_mass, r.foot_radius
        );
        // level ground names the model as before step heights existed
        if r.step_down != 0.0 {
            s.push_str(&format!("step_down = {:?}\n", r.step_down));
        }
        if self.tilt != 0.0 {
            s.push_str(&format!("tilt = {:?}\n", self.tilt));
        }
        for (k, g) in r.segments.iter().enumerate() {
            let [l, m, c, cn, i] = *g;
            s.push_str(&format!(
                "segments[{k}] = length {l:?}, mass {m:?}, com {c:?}, com_normal {cn:?}, \
                 inertia {i:?}\n"
            ));
        }
        for (k, (free, latch)) in r.free_swing.iter().zip(&r.latched).enumerate() {
            s.push_str(&format!(
                "knees[{k}] = free_swing {free}, hold {}",
                if *latch { "latch" } else { "stop" }
            ));
            // limits named where declared (an ideal latch's line as before they existed)
            if let Some(l) = r.latch_torque[k] {
                s.push_str(&format!(", latch_torque {l:?}"));
            }
            if let Some(l) = r.latch_impulse[k] {
                s.push_str(&format!(", latch_impulse {l:?}"));
            }
            s.push('\n');
        }
        s
    }
    fn param_values(&self) -> Vec<(String, f64)> {
        self.table
            .names
            .iter()
            .cloned()
            .zip(self.table.values.iter().copied())
            .collect()
    }
    fn step_length(&self, x_pre: &[f64]) -> f64 {
        self.swing_foot(x_pre)[0]
    }
    /// The spec's gaits (or a generic start); a section with the swing knee's rate starts it at
    /// 0 where a gait gives only `(stance, stance_rate, hip_rate)`.
    /// With `w = √(g/L)` (L the leg length): the stance leg's angle from 0.02 to 0.6 rad just
    /// after heel strike (legs apart up to 69°), its rate from −2w to 0 (rolling forward), the
    /// hip's and the swing knee's rates from −2w to 2w. The compass gait's `(0.27, −0.35w,
    /// 0.23w)` at 3° (Goswami et al. 1998) and Hsu Chen's kneed gait lie well inside.
    fn section_box(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let w = (self.r.gravity / self.leg_length).sqrt();
        let (mut lo, mut hi) = (vec![0.02, -2.0 * w, -2.0 * w], vec![0.6, 0.0, 2.0 * w]);
        if self.section_dim() == 4 {
            lo.push(-2.0 * w);
            hi.push(2.0 * w);
        }
        Some((lo, hi))
    }
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        let ds = self.section_dim();
        let mut v = self.gait_guesses3();
        for g in &mut v {
            if g.section.len() < ds {
                g.section.resize(ds, 0.0);
            }
        }
        v
    }
    /// The chain drawn from the stance contact point; with round feet the chain starts at the
    /// stance arc centre `r` above it, and each foot is drawn as its arc (±0.6 rad about the
    /// foot's end) with the shank continued to the foot's end.
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        let mut p = crate::registry::chain_pose(&x[..self.n], &self.len);
        let r = self.radius;
        if r > 0.0 {
            for l in p.links.iter_mut() {
                l[0][1] += r;
                l[1][1] += r;
            }
            for j in p.joints.iter_mut() {
                j[1] += r;
            }
            let th_st = x[0];
            let th_sw: f64 = x[..self.n].iter().sum();
            let cs = p.links[self.n - 1][1];
            let arc = |c: [f64; 2], th: f64| -> Vec<[[f64; 2]; 2]> {
                let pt = |a: f64| [c[0] + r * (th + a).sin(), c[1] - r * (th + a).cos()];
                let mut v = vec![[c, pt(0.0)]];
                for i in 0..8 {
                    let (a, b) = (-0.6 + 0.15 * i as f64, -0.6 + 0.15 * (i + 1) as f64);
                    v.push([pt(a), pt(b)]);
                }
                v
            };
            p.links.extend(arc([0.0, r], th_st));
            p.links.extend(arc(cs, th_sw));
            p.swing_foot = Some([cs[0], cs[1] - r]);
        }
        Some(p)
    }
    /// The kernel's joint points and tip ([`pdw_soa::forward_kinematics`]): the stance foot
    /// (joint 0), the stance knees, the hip (joint `m`), the swing knees (each named as its
    /// state coordinate) and the swing foot; the centre of mass is the link masses' weighted
    /// mean of the kernel's link COMs (the hip mass is part of the top stance link). With
    /// round feet the chain's root is the stance arc centre, `r` above the contact point at
    /// the origin (as in [`Walker::pose`]), and the feet are the arc centres.
    fn body_points(&self, x: &[f64]) -> Option<BodyPoints> {
        self.body_points_in(&mut Scratch::new(), x)
    }
    /// [`Walker::body_points`] with the kinematics in the scratch's kernel workspace.
    fn body_points_in(&self, ws: &mut Scratch, x: &[f64]) -> Option<BodyPoints> {
        let ws = &mut self.scratch(ws).ws;
        pdw_soa::forward_kinematics(&self.chain, ws, &x[..self.n]).ok()?;
        let r = self.radius;
        let up = |p: [f64; 2]| [p[0], p[1] + r];
        let mut points = Vec::with_capacity(self.n + 1);
        points.extend(ws.joint_positions().iter().copied().map(up));
        points.push(up(ws.tip_position()));
        let mut names = Vec::with_capacity(self.n + 1);
        names.push("stance_foot".to_string());
        for k in 1..self.n {
            names.push(if k == self.m {
                "hip".to_string()
            } else {
                self.state_names[k].clone()
            });
        }
        names.push("swing_foot".to_string());
        let links = self.chain.links();
        let total: f64 = links.iter().map(|l| l.mass).sum();
        let mut com = [0.0; 2];
        for (l, c) in links.iter().zip(ws.com_positions()) {
            com[0] += l.mass * c[0] / total;
            com[1] += l.mass * c[1] / total;
        }
        Some(BodyPoints {
            names,
            points,
            com: up(com),
        })
    }
    fn constraint_forces(&self, mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        self.constraint_forces_in(&mut Scratch::new(), mode, x)
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        self.step_flags_in(&mut Scratch::new(), mode, x)
    }
    /// `T + V` by the kernel's `total_energy` (potential zero at the stance foot).
    fn energy(&self, x: &[f64]) -> Option<f64> {
        self.energy_in(&mut Scratch::new(), x)
    }
    fn constraint_forces_in(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
    ) -> Option<ConstraintForces> {
        Some(self.constraint_forces_ws(ws, mode, x))
    }
    fn step_flags_in(&self, ws: &mut Scratch, mode: usize, x: &[f64]) -> Option<StepFlags> {
        Some(self.check_state_ws(ws, mode, x))
    }
    /// `T + V` by the kernel's `total_energy` in the scratch's workspaces.
    fn energy_in(&self, ws: &mut Scratch, x: &[f64]) -> Option<f64> {
        let s = self.scratch(ws);
        let n = self.n;
        if self.radius > 0.0 {
            // the floating chain at the rolling base (y = −r q₀, ż = 0): the potential counts
            // the arc centre's travel along the slope
            let mut q = [0.0; FMAX];
            let mut qd = [0.0; FMAX];
            q[0] = -self.radius * x[0];
            qd[0] = -self.radius * x[n];
            q[2..n + 2].copy_from_slice(&x[..n]);
            qd[2..n + 2].copy_from_slice(&x[n..2 * n]);
            return pdw_soa::total_energy(&self.floating, &mut s.fws, &q[..n + 2], &qd[..n + 2])
                .ok();
        }
        pdw_soa::total_energy(&self.chain, &mut s.ws, &x[..n], &x[n..2 * n]).ok()
    }
    /// The spec's energy unit: J for SI specs, `M L^2/T^2` for a spec in its own units `L`,
    /// `M`, `T` (Hsu Chen's).
    fn energy_unit(&self) -> &str {
        match self.spec.unit_system() {
            crate::units::UnitSystem::Si => "J",
            crate::units::UnitSystem::Abstract => "M L^2/T^2",
        }
    }
    /// Time in the unit the spec declares for `max_stride_time` (`"s"` if none); lengths in m
    /// for a time in s, else in the spec's reference length `l`; forces and torques in N, N m
    /// for SI specs, in `M L/T^2` and `M L^2/T^2` for a spec in its own units `L`, `M`, `T`.
    fn units(&self) -> pdw_model::ModelUnits {
        let own = self.spec.unit_system() == crate::units::UnitSystem::Abstract;
        let time = self
            .spec
            .parameters
            .get("max_stride_time")
            .map(|p| p.unit.clone())
            .filter(|u| !u.is_empty())
            .unwrap_or_else(|| if own { "T" } else { "s" }.to_string());
        let length = if time == "s" && !own { "m" } else { "l" };
        let (force, torque) = if own {
            ("M L/T^2", "M L^2/T^2")
        } else {
            ("N", "N m")
        };
        pdw_model::ModelUnits {
            time: time.into(),
            length: length.into(),
            force: force.into(),
            torque: torque.into(),
        }
    }
    fn impact_report(&self, mode: usize, guard: usize, x_pre: &[f64]) -> Option<ImpactReport> {
        (guard == 0)
            .then(|| self.impact_report_at(mode, x_pre))
            .flatten()
    }
    /// A latch's `latch_torque` for both knees (it is one knee spec), else 0.
    fn knee_pull_limits(&self) -> [f64; 2] {
        [self.latch_torque.unwrap_or(0.0); 2]
    }
    /// Total mass (both legs and the hip mass), leg length, gravity.
    fn scales(&self) -> Option<Scales> {
        let legs: f64 = self.r.segments.iter().map(|s| s[1]).sum();
        Some(Scales {
            mass: 2.0 * legs + self.r.hip_mass,
            length: self.leg_length,
            gravity: self.r.gravity,
        })
    }
    /// Height of the swing foot's lowest point above the slope: with round feet both arc
    /// centres are `r` above their feet's lowest points (the stance one on the slope), so it is
    /// the height of the chain's tip over its root, as for point feet.
    /// With a step down (`h > 0`) the ground ahead of the stance foot is the foothold's line
    /// `h` lower (chain walker docs, "Step down"), so a swing foot ahead is measured from there.
    fn swing_clearance(&self, _mode: usize, x: &[f64]) -> Option<f64> {
        let [y, z] = self.swing_foot(x);
        if self.tilt != 0.0 && self.swing_ahead(x) {
            return Some(self.above_tilted([y, z], [0.0; 2]).0);
        }
        let h = self.r.step_down;
        Some(if h > 0.0 && y > 0.0 { z + h } else { z })
    }
    /// Walkers with knees must clear the ground over the whole swing; straight-legged ones
    /// (the compass gait) keep the point-foot literature's mid-stance convention.
    fn clearance_rule(&self) -> ClearanceRule {
        if self.m > 1 {
            ClearanceRule::WholeSwing
        } else {
            ClearanceRule::AfterMidStance
        }
    }
}

/// What a chain walker's state component `name` measures (chain walker docs, "Coordinates").
fn chain_coordinate(name: &str) -> String {
    if let Some(base) = name.strip_suffix("_rate") {
        return format!("rate of {base} (rad per time unit)");
    }
    match name {
        "stance" => "angle of the stance leg's lowest segment from the slope normal (rad); \
                     positive: stance foot downhill of the hip"
            .into(),
        "hip" => "swing leg relative to the stance leg at the hip (rad); 0: legs together".into(),
        n if n.starts_with("stance_knee") => {
            "stance knee flexion relative to the segment below (rad); flexes with q > 0, \
             straight at 0"
                .into()
        }
        n if n.starts_with("swing_knee") => {
            "swing knee flexion relative to the segment above (rad); flexes with q < 0, \
             straight at 0"
                .into()
        }
        n => format!("joint {n} (rad)"),
    }
}
