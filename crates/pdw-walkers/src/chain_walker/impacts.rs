//! The impacts (chain walker docs, "Impacts", "Resets"): the heel strike's kernel impact, the
//! impact problem of each reset with its unilateral contacts and stops, whether it buckles a stance
//! knee or releases the trailing knee, and the impact report.

use super::{ChainWalker, FMAX, FREE};
use crate::validity::{ImpactReport, ImpulseEntry, ImpulseKind};
use pdw_hybrid::Scratch;
#[cfg(doc)]
use pdw_model::Walker;

/// What a constraint of an impact problem is, for the report's names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Knee strike: the stance foot (rolling or pinned, held).
    StanceFoot,
    /// Heel strike: the swing foot that strikes (the new stance foot).
    NewStanceFoot,
    /// Heel strike: the old stance foot (must leave the ground).
    TrailingFoot,
    /// Knee strike: the knee that strikes its stop (joint index).
    StrikingKnee(usize),
    /// Knee strike: a stance knee (held by its stop; releasing it buckles the stance leg).
    StanceKnee(usize),
    /// Knee strike: another swing knee (three-segment legs).
    SwingKnee(usize),
    /// Heel strike: a knee of the old stance leg (the new swing leg).
    TrailingKnee(usize),
    /// Heel strike: a knee of the old swing leg (the new stance leg; releasing it buckles).
    NewStanceKnee(usize),
}

/// The impact problem of a reset (chain walker docs, "Impacts"): the floating chain's configuration
/// and pre-impact rates, the constraints, the model's active set and which releases are a fall.
pub(super) struct ImpactProblem {
    q: [f64; FMAX],
    qd: [f64; FMAX],
    items: [pdw_soa::ImpactItem; pdw_soa::unilateral::MAX_ITEMS],
    roles: [Role; pdw_soa::unilateral::MAX_ITEMS],
    hold: [bool; pdw_soa::unilateral::MAX_ITEMS],
    /// the pulling impulse each item's hardware holds (a latch's `latch_impulse`, else 0)
    limit: [f64; pdw_soa::unilateral::MAX_ITEMS],
    len: usize,
}

impl ImpactProblem {
    fn push(&mut self, row: pdw_soa::ImpactRow, unilateral: bool, hold: bool, role: Role) {
        self.items[self.len] = pdw_soa::ImpactItem { row, unilateral };
        self.roles[self.len] = role;
        self.hold[self.len] = hold;
        self.len += 1;
    }

    /// [`ImpactProblem::push`] of a knee: a stop (unilateral), an ideal latch (bilateral) or
    /// a latch with `latch_impulse` `limit` (it may release: unilateral for the solver, released
    /// by the model where it would pull more than `limit`, chain walker docs "Latches").
    fn push_knee(
        &mut self,
        row: pdw_soa::ImpactRow,
        latched: bool,
        limit: Option<f64>,
        role: Role,
    ) {
        let i = self.len;
        self.push(row, !latched || limit.is_some(), true, role);
        self.limit[i] = limit.filter(|_| latched).unwrap_or(0.0);
    }
}

impl ChainWalker {
    /// The heel-strike impact at the pre-impact state `x` (every knee held): floating-chain rates
    /// `(ẏ, ż, q̇…)` after the impact into `qd_post` (length `n + 2`), before the leg swap; the
    /// ground's impulse on the new stance foot `[Λ_y, Λ_z]` is returned.
    pub fn heel_strike(&self, ws: &mut Scratch, x: &[f64], qd_post: &mut [f64]) -> [f64; 2] {
        let n = self.n;
        let s = self.scratch(ws);
        s.q[..2].fill(0.0);
        s.qd[..2].fill(0.0);
        s.q[2..n + 2].copy_from_slice(&x[..n]);
        s.qd[2..n + 2].copy_from_slice(&x[n..2 * n]);
        if self.radius > 0.0 {
            // the stance arc centre rolls: ẏ = −r q̇₀; the contact point r below the swing arc
            // centre (the chain's tip)
            s.qd[0] = -self.radius * x[n];
            return match pdw_soa::contact_impact(
                &self.floating,
                &s.q[..n + 2],
                &s.qd[..n + 2],
                self.landing_offset(),
                &self.floating_knees,
                qd_post,
                None,
            ) {
                Ok(imp) => imp,
                Err(_) => {
                    qd_post.iter_mut().for_each(|v| *v = f64::NAN);
                    [f64::NAN; 2]
                }
            };
        }
        let nl = 2 + self.floating_knees.len();
        let ok = pdw_soa::tip_impact(
            &self.floating,
            &mut s.fws,
            &s.q[..n + 2],
            &s.qd[..n + 2],
            &self.floating_knees,
            qd_post,
            &mut s.imp[..nl],
        )
        .is_ok();
        if ok {
            [-s.imp[0], -s.imp[1]]
        } else {
            qd_post.iter_mut().for_each(|v| *v = f64::NAN);
            [f64::NAN; 2]
        }
    }

    /// The impact of the reset of `mode` (the knee strike in the free mode, the heel strike in
    /// the locked mode) at the pre-impact state `x`, on the floating chain (chain walker docs).
    fn impact_problem(&self, mode: usize, x: &[f64]) -> ImpactProblem {
        use pdw_soa::ImpactRow::{BaseContact, Stop, TipContact};
        let (n, m, r) = (self.n, self.m, self.radius);
        let mut p = ImpactProblem {
            q: [0.0; FMAX],
            qd: [0.0; FMAX],
            items: [pdw_soa::ImpactItem {
                row: Stop {
                    joint: 0,
                    sign: 1.0,
                },
                unilateral: false,
            }; pdw_soa::unilateral::MAX_ITEMS],
            roles: [Role::StanceFoot; pdw_soa::unilateral::MAX_ITEMS],
            hold: [false; pdw_soa::unilateral::MAX_ITEMS],
            limit: [0.0; pdw_soa::unilateral::MAX_ITEMS],
            len: 0,
        };
        p.q[2..n + 2].copy_from_slice(&x[..n]);
        p.qd[2..n + 2].copy_from_slice(&x[n..2 * n]);
        // the stance arc centre rolls: ẏ = −r q̇₀ (0 for point feet)
        p.qd[0] = -r * x[n];
        // a stance knee flexes with q > 0, a swing knee with q < 0 (chain walker docs)
        let stop = |j: usize| Stop {
            joint: j + 2,
            sign: if j < m { 1.0 } else { -1.0 },
        };
        match (self.free_knee, mode) {
            (Some(fk), FREE) => {
                p.push(BaseContact { radius: r }, false, true, Role::StanceFoot);
                p.push(stop(fk), false, true, Role::StrikingKnee(fk));
                for &j in &self.locked[FREE] {
                    let role = if j < m {
                        Role::StanceKnee(j)
                    } else {
                        Role::SwingKnee(j)
                    };
                    p.push_knee(stop(j), self.latched[j], self.latch_impulse, role);
                }
            }
            _ => {
                p.push(
                    TipContact {
                        offset: self.landing_offset(),
                    },
                    false,
                    true,
                    Role::NewStanceFoot,
                );
                p.push(BaseContact { radius: r }, true, false, Role::TrailingFoot);
                for &j in &self.locked[self.locked_mode()] {
                    let role = if j < m {
                        Role::TrailingKnee(j)
                    } else {
                        Role::NewStanceKnee(j)
                    };
                    p.push_knee(stop(j), self.latched[j], self.latch_impulse, role);
                }
            }
        }
        p
    }

    /// Whether the impact of `mode` at `x` buckles a stance knee: the impact's complementarity
    /// problem (contacts and stops push only, [`pdw_soa::unilateral_impact`]) releases a knee of
    /// the leg that is the stance leg after the impact. `false` where the problem has no
    /// solution (the reset then reports the failure).
    ///
    /// A latch with a `latch_impulse` `L` (chain walker docs, "Latches") buckles where, in the
    /// model's impact map ([`ChainWalker::impact_map`]: every knee held but a released trailing
    /// knee), the stance knee's latch would pull more than it holds: impulse `< −L`.
    pub fn stance_knee_buckles(&self, mode: usize, x: &[f64]) -> bool {
        if self.latch_impulse.is_some() {
            let mut v = [0.0; FMAX];
            return match self.impact_map(mode, x, &mut v, None) {
                Ok((p, sol)) => (0..p.len).any(|i| {
                    matches!(p.roles[i], Role::StanceKnee(_) | Role::NewStanceKnee(_))
                        && sol.items[i].impulse[0] < -p.limit[i]
                }),
                Err(_) => false,
            };
        }
        let p = self.impact_problem(mode, x);
        let stance_knee =
            |i: usize| matches!(p.roles[i], Role::StanceKnee(_) | Role::NewStanceKnee(_));
        if !(0..p.len).any(|i| stance_knee(i) && p.items[i].unilateral) {
            // no stance knee in the problem (a compass gait), or only latched ones (bilateral:
            // held in every active set the solve may choose): none can buckle, no solve needed
            return false;
        }
        let nf = self.n + 2;
        let mut v = [0.0; FMAX];
        match pdw_soa::unilateral_impact(
            &self.floating,
            &p.q[..nf],
            &p.qd[..nf],
            &p.items[..p.len],
            None,
            &mut v[..nf],
            None,
        ) {
            Ok(sol) => (0..p.len).any(|i| stance_knee(i) && !sol.items[i].active),
            Err(_) => false,
        }
    }

    /// The model's impact map of `mode` at `x` on the floating chain (every knee held but a
    /// trailing free knee whose stop would pull, the trailing foot released at heel strike):
    /// floating-chain rates after the impact into `v` (length `n + 2`) and, if given, the
    /// Jacobian `[∂q̇_F⁺/∂q_F | ∂q̇_F⁺/∂q̇_F⁻]`.
    pub(super) fn impact_map(
        &self,
        mode: usize,
        x: &[f64],
        v: &mut [f64],
        jac: Option<&mut [f64]>,
    ) -> Result<(ImpactProblem, pdw_soa::ImpactSolution), pdw_soa::SoaError> {
        let mut p = self.impact_problem(mode, x);
        let nf = self.n + 2;
        if let Some(i) = self.trailing_release_item(mode, &p) {
            p.hold[i] = false;
        }
        let sol = pdw_soa::unilateral_impact(
            &self.floating,
            &p.q[..nf],
            &p.qd[..nf],
            &p.items[..p.len],
            Some(&p.hold[..p.len]),
            &mut v[..nf],
            jac,
        )?;
        Ok((p, sol))
    }

    /// At a heel strike of a walker whose trailing free knee is held by a stop or a latch with
    /// a `latch_impulse` `L` (`trailing_free`): the index of that knee's item in `p` if it would
    /// have to pull (more than `L`) with every constraint of the model held (an impulse below
    /// `−L`; `L = 0` for a stop), i.e. if the model releases it. The released problem is then consistent for that knee: with the others held, the
    /// stop's impulse and the knee's flexion rate after release have opposite signs (the
    /// Schur complement `e 𝓜⁻¹ eᵀ` restricted to the held rows is positive).
    fn trailing_release_item(&self, mode: usize, p: &ImpactProblem) -> Option<usize> {
        let tk = self.trailing_free?;
        if self.free_knee.is_some() && mode == FREE {
            return None;
        }
        let i = (0..p.len).find(|&i| p.roles[i] == Role::TrailingKnee(tk))?;
        let nf = self.n + 2;
        let mut v = [0.0; FMAX];
        let sol = pdw_soa::unilateral_impact(
            &self.floating,
            &p.q[..nf],
            &p.qd[..nf],
            &p.items[..p.len],
            Some(&p.hold[..p.len]),
            &mut v[..nf],
            None,
        )
        .ok()?;
        (sol.items[i].impulse[0] < -p.limit[i]).then_some(i)
    }

    /// Whether the model releases the trailing free knee at the heel strike at the pre-impact
    /// state `x` (its stop would have to pull; the new swing knee then starts flexing).
    pub fn trailing_knee_releases_at(&self, x: &[f64]) -> bool {
        if self.trailing_free.is_none() {
            return false;
        }
        let mode = self.locked_mode();
        let p = self.impact_problem(mode, x);
        self.trailing_release_item(mode, &p).is_some()
    }

    /// Name of a knee joint in a report: `prefix` and the knee's number for three-segment
    /// legs (`"stance_knee2"` is the state's `stance_knee2`).
    fn knee_name(&self, prefix: &str, j: usize) -> String {
        let state = &self.state_names[j];
        let digits = state.trim_start_matches(|c: char| !c.is_ascii_digit());
        format!("{prefix}{digits}")
    }

    /// The impulses of the reset of `mode` at the pre-impact state `x` (see
    /// [`Walker::impact_report`]).
    pub fn impact_report_at(&self, mode: usize, x: &[f64]) -> Option<ImpactReport> {
        let mut v = [0.0; FMAX];
        let (p, sol) = self.impact_map(mode, x, &mut v, None).ok()?;
        let mut entries = Vec::with_capacity(2 * p.len);
        let mut friction = f64::INFINITY;
        for i in 0..p.len {
            let (it, res) = (&p.items[i], &sol.items[i]);
            let (name, contact) = match p.roles[i] {
                Role::StanceFoot => ("stance_foot".to_string(), true),
                Role::NewStanceFoot => ("new_stance_foot".to_string(), true),
                Role::TrailingFoot => ("trailing_foot".to_string(), true),
                Role::StrikingKnee(j) => (self.knee_name("striking_knee", j), false),
                Role::StanceKnee(j) => (self.knee_name("stance_knee", j), false),
                Role::SwingKnee(j) => (self.knee_name("swing_knee", j), false),
                Role::TrailingKnee(j) => (self.knee_name("trailing_knee", j), false),
                Role::NewStanceKnee(j) => (self.knee_name("new_stance_knee", j), false),
            };
            let (impulse, rate) = match p.roles[i] {
                // the landing line's tangent (cos Δ, −sin Δ) and normal (sin Δ, cos Δ)
                Role::NewStanceFoot if self.tilt != 0.0 => {
                    let (s, c) = self.tilt_sc;
                    let along = |v: [f64; 2]| [v[0] * c - v[1] * s, v[0] * s + v[1] * c];
                    (along(res.impulse), along(res.rate))
                }
                _ => (res.impulse, res.rate),
            };
            if contact {
                if !it.unilateral {
                    friction = if impulse[1] > 0.0 {
                        (impulse[0] / impulse[1]).abs()
                    } else {
                        f64::INFINITY
                    };
                }
                for (kind, c) in [
                    (ImpulseKind::ContactTangential, 0),
                    (ImpulseKind::ContactNormal, 1),
                ] {
                    entries.push(ImpulseEntry {
                        name: name.clone(),
                        kind,
                        unilateral: it.unilateral,
                        active: res.active,
                        impulse: impulse[c],
                        rate_after: if res.active { 0.0 } else { rate[c] },
                        pull_limit: 0.0,
                    });
                }
            } else {
                entries.push(ImpulseEntry {
                    name,
                    kind: ImpulseKind::KneeStop,
                    unilateral: it.unilateral,
                    active: res.active,
                    impulse: impulse[0],
                    rate_after: if res.active { 0.0 } else { rate[0] },
                    pull_limit: p.limit[i],
                });
            }
        }
        let event = if self.free_knee.is_some() && mode == FREE {
            "knee_strike"
        } else {
            "heel_strike"
        };
        Some(ImpactReport {
            event: event.into(),
            entries,
            friction_required: friction,
            energy_lost: sol.energy_lost,
        })
    }
}
