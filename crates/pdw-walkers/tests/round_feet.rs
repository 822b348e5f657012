//! Round (arc) feet rolling without slip: the kernel's rolling base against the closed-form
//! rolling arc (McGeer 1990), the limit r → 0 against the point foot, energy conservation along
//! the flow, batched guards = scalar guards bit for bit, exact Jacobians against Richardson
//! differences, and clear errors for a bad radius (the batched flow in every lane against an
//! independent round-foot model: the tests crate's `round_foot_kneed_reference.rs`).

use crate::chain_common;
use chain_common::{all_presets, random_state};
use faer::Mat;
use pdw_hybrid::{HybridSystem, Scratch};
use pdw_soa::{ChainBuilder, Link};
use pdw_walkers::{presets, ChainWalker, Walker};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The preset `w` with round feet of radius `r` (same parameter values).
fn with_radius(w: &ChainWalker, r: f64) -> ChainWalker {
    let mut spec = w.spec().clone();
    spec.foot_radius = pdw_walkers::spec::Num::Value(r);
    let values: Vec<f64> = w.param_values().into_iter().map(|p| p.1).collect();
    ChainWalker::new(spec, &values).unwrap()
}

fn kneed_like() -> Vec<(&'static str, ChainWalker)> {
    vec![
        ("compass", presets::compass(&[]).unwrap()),
        ("kneed", presets::kneed(&[]).unwrap()),
        (
            "seed5 free knee",
            presets::seed5(&[("free_swing_knee", 1.0)]).unwrap(),
        ),
    ]
}

/// A one-link body whose arc foot (radius r, centre a distance ρ below the COM along the link)
/// rolls on a slope γ: with θ the link's angle from the slope normal, the arc centre at
/// `(−rθ, r)` and the COM at `(−rθ − ρ sin θ, r + ρ cos θ)` (y downhill, z up),
/// Lagrange's equation is (McGeer 1990, the rolling arc foot)
///
/// `(I + m(r² + ρ² + 2rρ cos θ)) θ̈ − m r ρ sin θ θ̇² + m g (sin γ (r + ρ cos θ) − cos γ ρ sin θ) = 0`,
///
/// and the ground force is `F = m a_COM − m g⃗`. The kernel's rolling base (floating chain with
/// the constant-Jacobian rolling constraint) must give both to roundoff.
#[test]
fn one_link_rolling_arc_matches_lagranges_equation_and_newtons_law() {
    let (m, inertia, g, gamma) = (2.0, 0.15, 9.81, 0.1);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for (r, rho) in [(0.3, 0.5), (0.5, 0.2), (0.25, -0.1), (1.0, 0.0), (0.0, 0.7)] {
        let base = Link {
            to_next: [0.0, 0.0],
            com: [0.0, 0.0],
            mass: pdw_walkers::chain_walker::FLOATING_BASE_MASS,
            inertia: 0.0,
        };
        let body = Link {
            to_next: [0.0, 1.0],
            com: [0.0, rho],
            mass: m,
            inertia,
        };
        let chain = ChainBuilder::new()
            .gravity(g)
            .slope(gamma)
            .prismatic([1.0, 0.0], base)
            .prismatic([0.0, 1.0], base)
            .revolute(body)
            .build()
            .unwrap();
        for _ in 0..20 {
            let th: f64 = rng.random_range(-1.2..1.2);
            let w: f64 = rng.random_range(-3.0..3.0);
            let (mut qdd, mut tau) = ([0.0], [0.0; 3]);
            pdw_soa::rolling_base_dynamics(&chain, r, &[th], &[w], &[false], &mut qdd, &mut tau)
                .unwrap();
            let d = inertia + m * (r * r + rho * rho + 2.0 * r * rho * th.cos());
            let rhs = m * r * rho * th.sin() * w * w
                - m * g * (gamma.sin() * (r + rho * th.cos()) - gamma.cos() * rho * th.sin());
            let expect = rhs / d;
            assert!(
                (qdd[0] - expect).abs() <= 1e-13 * (1.0 + expect.abs()),
                "r {r} rho {rho} θ {th}: θ̈ {} vs closed form {expect}",
                qdd[0]
            );
            // ground force from Newton's law on the COM
            let a = [
                -r * expect - rho * th.cos() * expect + rho * th.sin() * w * w,
                -rho * th.sin() * expect - rho * th.cos() * w * w,
            ];
            let f = [
                m * a[0] - m * g * gamma.sin(),
                m * a[1] + m * g * gamma.cos(),
            ];
            for i in 0..2 {
                assert!(
                    (tau[i] - f[i]).abs() <= 1e-12 * (1.0 + f[i].abs()),
                    "r {r} rho {rho}: ground force {i}: {} vs {}",
                    tau[i],
                    f[i]
                );
            }
            // the rolling contact's torque about the arc centre, r f_y (the joint is passive)
            assert!((tau[2] - r * tau[0]).abs() <= 1e-12 * (1.0 + tau[2].abs()));
        }
    }
}

/// The rolling disc (COM at the arc centre): uniform acceleration `g sin γ / (1 + I/(m r²))`
/// down the slope, the textbook result.
#[test]
fn rolling_disc_accelerates_as_the_textbook_says() {
    let (m, inertia, g, gamma, r) = (3.0, 0.2, 9.81, 0.2, 0.4);
    let base = Link {
        to_next: [0.0, 0.0],
        com: [0.0, 0.0],
        mass: pdw_walkers::chain_walker::FLOATING_BASE_MASS,
        inertia: 0.0,
    };
    let chain = ChainBuilder::new()
        .gravity(g)
        .slope(gamma)
        .prismatic([1.0, 0.0], base)
        .prismatic([0.0, 1.0], base)
        .revolute(Link {
            to_next: [0.0, 1.0],
            com: [0.0, 0.0],
            mass: m,
            inertia,
        })
        .build()
        .unwrap();
    let (mut qdd, mut tau) = ([0.0], [0.0; 3]);
    pdw_soa::rolling_base_dynamics(&chain, r, &[0.7], &[2.0], &[false], &mut qdd, &mut tau)
        .unwrap();
    let a = -r * qdd[0];
    let expect = g * gamma.sin() / (1.0 + inertia / (m * r * r));
    assert!((a - expect).abs() <= 1e-14 * expect, "{a} vs {expect}");
}

/// r → 0: the rolling base at r = 0 is the pinned point foot to roundoff, the walker at
/// r = 1e-9 differs from the point foot by O(r), and `foot_radius = 0` is the point foot bit for
/// bit (the same code path).
#[test]
fn vanishing_radius_is_the_point_foot() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for (name, w) in all_presets() {
        let n = w.dim() / 2;
        let w0 = with_radius(&w, 0.0);
        let wr = with_radius(&w, 1e-9);
        let mut ws = Scratch::new();
        for mode in 0..w.n_modes() {
            for _ in 0..5 {
                let x = random_state(&w, &mut rng, mode);
                let (mut f, mut f0, mut fr) =
                    (vec![0.0; 2 * n], vec![0.0; 2 * n], vec![0.0; 2 * n]);
                w.flow(&mut ws, mode, &x, &mut f);
                w0.flow(&mut ws, mode, &x, &mut f0);
                wr.flow(&mut ws, mode, &x, &mut fr);
                for j in 0..2 * n {
                    assert_eq!(f[j].to_bits(), f0[j].to_bits(), "{name}: r = 0 flow {j}");
                    assert!(
                        (fr[j] - f[j]).abs() <= 1e-7 * (1.0 + f[j].abs()),
                        "{name} mode {mode}: r = 1e-9 flow {j}: {} vs {}",
                        fr[j],
                        f[j]
                    );
                }
                // the rolling-base code at exactly r = 0 against the pinned kernel
                let mut qdd = vec![0.0; n];
                let mut tau = vec![0.0; n + 2];
                let locked: Vec<bool> =
                    (0..n).map(|k| w.locked_joints(mode).contains(&k)).collect();
                pdw_soa::rolling_base_dynamics(
                    w.floating_chain(),
                    0.0,
                    &x[..n],
                    &x[n..],
                    &locked,
                    &mut qdd,
                    &mut tau,
                )
                .unwrap();
                for j in 0..n {
                    assert!(
                        (qdd[j] - f[n + j]).abs() <= 1e-11 * (1.0 + f[n + j].abs()),
                        "{name} mode {mode}: rolling base at r = 0, q̈{j} {} vs {}",
                        qdd[j],
                        f[n + j]
                    );
                }
                let (c, cr) = (
                    w.constraint_forces_ws(&mut ws, mode, &x),
                    wr.constraint_forces_ws(&mut ws, mode, &x),
                );
                let scale = c.normal.abs().max(1.0);
                assert!((c.normal - cr.normal).abs() <= 1e-7 * scale, "{name}");
                assert!(
                    (c.tangential - cr.tangential).abs() <= 1e-7 * scale,
                    "{name}"
                );
                for (a, b) in c.knee_torque.iter().zip(&cr.knee_torque) {
                    assert_eq!(a.is_some(), b.is_some());
                    if let (Some(a), Some(b)) = (a, b) {
                        assert!((a - b).abs() <= 1e-7 * scale, "{name}: knee {a} vs {b}");
                    }
                }
                let (e, er) = (w.energy(&x).unwrap(), wr.energy(&x).unwrap());
                assert!(
                    (e - er).abs() <= 1e-7 * e.abs().max(1.0),
                    "{name}: {e} vs {er}"
                );
            }
        }
        // heel strike: post-impact rates and the ground impulse
        let mode = w.locked_mode();
        let mut x = random_state(&w, &mut rng, mode);
        x[0] = -0.2;
        x[n / 2] = 0.4;
        let (mut v, mut vr) = (vec![0.0; n + 2], vec![0.0; n + 2]);
        let imp = w.heel_strike(&mut ws, &x, &mut v);
        let impr = wr.heel_strike(&mut ws, &x, &mut vr);
        for j in 0..n + 2 {
            assert!(
                (v[j] - vr[j]).abs() <= 1e-7 * (1.0 + v[j].abs()),
                "{name}: v{j}"
            );
        }
        for i in 0..2 {
            assert!(
                (imp[i] - impr[i]).abs() <= 1e-7 * (1.0 + imp[i].abs()),
                "{name}: impulse {i}: {} vs {}",
                imp[i],
                impr[i]
            );
        }
    }
}

/// Energy `T + V` (the arc centre's travel along the slope included) is conserved along the
/// flow of both modes with round feet: classical RK4 at h = 1e-3 over 0.4 s.
#[test]
fn energy_is_conserved_along_the_round_foot_flow() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for (name, w) in kneed_like() {
        let w = with_radius(&w, 0.2 * w.leg_length());
        let d = w.dim();
        let mut ws = Scratch::new();
        for mode in 0..w.n_modes() {
            let mut x = random_state(&w, &mut rng, mode);
            let e0 = w.energy(&x).unwrap();
            let h = 1e-3;
            let mut k = vec![vec![0.0; d]; 4];
            let mut xt = vec![0.0; d];
            let mut worst = 0.0f64;
            for _ in 0..400 {
                w.flow(&mut ws, mode, &x, &mut k[0]);
                for (c, a) in [(1, 0.5), (2, 0.5), (3, 1.0)] {
                    for j in 0..d {
                        xt[j] = x[j] + a * h * k[c - 1][j];
                    }
                    w.flow(&mut ws, mode, &xt, &mut k[c]);
                }
                for j in 0..d {
                    x[j] += h / 6.0 * (k[0][j] + 2.0 * k[1][j] + 2.0 * k[2][j] + k[3][j]);
                }
                worst = worst.max((w.energy(&x).unwrap() - e0).abs());
            }
            let scale = e0.abs().max(1.0);
            assert!(
                worst <= 1e-9 * scale,
                "{name} mode {mode}: energy drift {worst:.3e} of {e0}"
            );
        }
    }
}

/// The batched guards (the swing-foot height four lanes at a time) equal the scalar guards bit
/// for bit with round feet, for 1, 5 and 300 lanes. (The batched flow is checked in every lane
/// against the independent round-foot model of the tests crate, `round_foot_kneed_reference.rs`.)
#[test]
fn batched_guards_equal_scalar_guards_bit_for_bit_with_round_feet() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    for (name, w) in kneed_like() {
        let w = with_radius(&w, 0.15 * w.leg_length());
        let d = w.dim();
        let mut ws = Scratch::new();
        for mode in 0..w.n_modes() {
            for lanes in [1usize, 5, 300] {
                let states: Vec<Vec<f64>> = (0..lanes)
                    .map(|_| random_state(&w, &mut rng, mode))
                    .collect();
                let x = Mat::from_fn(lanes, d, |l, j| states[l][j]);
                for k in 0..w.guards(mode).len() {
                    let mut g = vec![0.0; lanes];
                    w.guard_batch(&mut ws, mode, k, x.as_ref(), &mut g);
                    for (l, s) in states.iter().enumerate() {
                        assert_eq!(
                            g[l].to_bits(),
                            w.guard(&mut ws, mode, k, s).to_bits(),
                            "{name} mode {mode} lanes {lanes} lane {l} guard {k}"
                        );
                    }
                }
            }
        }
    }
}

/// Central differences of `f` at `x`, extrapolated (Richardson, steps h and h/2).
fn richardson(f: &mut dyn FnMut(&[f64], &mut [f64]), x: &[f64], n_out: usize) -> Vec<f64> {
    let n = x.len();
    let mut jac = vec![0.0; n_out * n];
    let (mut fp, mut fm) = (vec![0.0; n_out], vec![0.0; n_out]);
    let mut xp = x.to_vec();
    for j in 0..n {
        let mut d = [vec![0.0; n_out], vec![0.0; n_out]];
        for (k, h) in [1e-4, 5e-5].into_iter().enumerate() {
            xp[j] = x[j] + h;
            f(&xp, &mut fp);
            xp[j] = x[j] - h;
            f(&xp, &mut fm);
            xp[j] = x[j];
            for i in 0..n_out {
                d[k][i] = (fp[i] - fm[i]) / (2.0 * h);
            }
        }
        for i in 0..n_out {
            jac[i * n + j] = (4.0 * d[1][i] - d[0][i]) / 3.0;
        }
    }
    jac
}

fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    let scale = b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for (i, (u, v)) in a.iter().zip(b).enumerate() {
        assert!(
            (u - v).abs() <= tol * scale,
            "{what}: entry {i}: exact {u} vs differences {v}"
        );
    }
}

#[test]
fn exact_jacobians_with_round_feet_match_richardson_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    for (name, w) in kneed_like() {
        let w = with_radius(&w, 0.22 * w.leg_length());
        let d = w.dim();
        let mut ws = Scratch::new();
        let mut ws2 = Scratch::new();
        for mode in 0..w.n_modes() {
            for _ in 0..4 {
                let x = random_state(&w, &mut rng, mode);
                let mut jac = vec![0.0; d * d];
                w.flow_jacobian(&mut ws, mode, &x, &mut jac);
                let fd = richardson(&mut |x, f| w.flow(&mut ws2, mode, x, f), &x, d);
                assert_close(
                    &jac,
                    &fd,
                    1e-8,
                    &format!("{name} flow jacobian mode {mode}"),
                );
                for k in 0..w.guards(mode).len() {
                    let mut g = vec![0.0; d];
                    w.guard_gradient(&mut ws, mode, k, &x, &mut g);
                    let fd =
                        richardson(&mut |x, out| out[0] = w.guard(&mut ws2, mode, k, x), &x, 1);
                    assert_close(&g, &fd, 1e-8, &format!("{name} guard {k} mode {mode}"));
                }
                let mut jr = vec![0.0; d * d];
                w.reset_jacobian(&mut ws, mode, 0, &x, &mut jr);
                let fd = richardson(
                    &mut |x, out| {
                        w.reset(&mut ws2, mode, 0, x, out);
                    },
                    &x,
                    d,
                );
                assert_close(
                    &jr,
                    &fd,
                    1e-8,
                    &format!("{name} reset jacobian mode {mode}"),
                );
            }
        }
    }
}

/// After a round-foot heel strike the new stance foot rolls: the contact point (r below the
/// new stance arc centre) is at rest, i.e. the arc centre moves at `−r θ̇` along the slope.
#[test]
fn heel_strike_leaves_the_new_contact_point_at_rest() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    for (name, w) in kneed_like() {
        let r = 0.2 * w.leg_length();
        let w = with_radius(&w, r);
        let n = w.dim() / 2;
        let mode = w.locked_mode();
        let mut x = random_state(&w, &mut rng, mode);
        x[0] = -0.2;
        x[n / 2] = 0.4;
        let mut v = vec![0.0; n + 2];
        let mut ws = Scratch::new();
        let imp = w.heel_strike(&mut ws, &x, &mut v);
        // velocity of the swing arc centre (the chain's tip) on the floating chain
        let mut q = vec![0.0; n + 2];
        q[2..].copy_from_slice(&x[..n]);
        let mut jt = vec![0.0; 2 * (n + 2)];
        let mut pos = [0.0; 2];
        pdw_soa::tip_position_derivatives(w.floating_chain(), &q, &mut pos, &mut jt).unwrap();
        let vc: Vec<f64> = (0..2)
            .map(|i| (0..n + 2).map(|k| jt[i * (n + 2) + k] * v[k]).sum())
            .collect();
        let omega: f64 = v[2..].iter().sum(); // swing shank's absolute rate
        assert!(
            (vc[0] + r * omega).abs() <= 1e-12 * (1.0 + vc[0].abs()) && vc[1].abs() <= 1e-12,
            "{name}: arc centre velocity {vc:?}, −rω = {}",
            -r * omega
        );
        assert!(imp[1] > 0.0, "{name}: the ground pushes: impulse {imp:?}");
    }
}

#[test]
fn a_radius_off_the_lowest_segment_is_refused_naming_the_field() {
    let w = presets::kneed(&[]).unwrap();
    let mut spec = w.spec().clone();
    spec.foot_radius = pdw_walkers::spec::Num::Value(0.6);
    let e = ChainWalker::from_spec(spec.clone())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("foot_radius") && e.contains("0.6") && e.contains("[0, 0.5)"),
        "{e}"
    );
    spec.foot_radius = pdw_walkers::spec::Num::Value(-0.1);
    let e = ChainWalker::from_spec(spec.clone())
        .unwrap_err()
        .to_string();
    assert!(e.contains("foot_radius") && e.contains(">= 0"), "{e}");
    spec.foot_radius = pdw_walkers::spec::Num::Expr("radius".into());
    let e = ChainWalker::from_spec(spec).unwrap_err().to_string();
    assert!(
        e.contains("foot_radius") && e.contains("unknown parameter"),
        "{e}"
    );
}

/// Round feet on a step (`step_down = h`), checked against plane geometry written here: every
/// arc centre stands `r` above the line its foot touches, so with straight legs of length `L`
/// the hip-to-centre length is `ℓ = L − r`, and (stance centre at the origin, angles from the
/// slope normal, positive with the foot downhill of the hip) the hip is at
/// `(−ℓ sin q₀, ℓ cos q₀)` and the other centre at the hip plus `(ℓ sin ψ, −ℓ cos ψ)`.
/// - The lift just after a strike onto `h` puts the trailing foot behind, touching the line
///   `h` above the new stance foot's: its centre `h` above the stance centre.
/// - Before the strike, a swing foot ahead whose arc touches the foothold `h` below (its centre
///   `h` below the stance centre) is on the heel-strike guard's zero, and the strike is
///   admissible; raised by δ it is δ above the zero.
/// - A step of `ℓ` or more is refused, naming the rule; the point foot keeps its rule.
#[test]
fn round_feet_take_steps_where_plane_geometry_puts_them() {
    let l_leg = 1.0; // the compass preset: a + b
    for r in [0.0, 0.1] {
        let base = with_radius(&presets::compass(&[]).unwrap(), r);
        let ell = l_leg - r;
        for h in [0.05, -0.05, -0.2] {
            let values: Vec<f64> = base
                .param_values()
                .into_iter()
                .map(|(n, v)| if n == "step_down" { h } else { v })
                .collect();
            let w = ChainWalker::new(base.spec().clone(), &values).unwrap();
            // just after the strike: the trailing centre h above the stance centre, behind it
            let q0 = 0.7;
            let mut x = vec![0.0; w.dim()];
            pdw_hybrid::Section::lift(&w, &[q0, -1.0, 0.7], &mut x);
            let psi = x[0] + x[1];
            let rel = [
                -ell * q0.sin() + ell * psi.sin(),
                ell * q0.cos() - ell * psi.cos(),
            ];
            assert!((rel[1] - h).abs() < 1e-14, "r {r}, h {h}: {rel:?}");
            assert!(rel[0] < 0.0, "r {r}, h {h}: the trailing foot is behind");
            let model = w.swing_foot(&x);
            assert!(
                (model[0] - rel[0]).abs() < 1e-14 && (model[1] - rel[1]).abs() < 1e-14,
                "r {r}: {model:?} against {rel:?}"
            );
            // before the strike: the swing arc on the foothold h below, ahead
            let q0: f64 = -0.4;
            let psi = (q0.cos() + h / ell).acos();
            let mut x = vec![0.0; w.dim()];
            x[0] = q0;
            x[1] = psi - q0;
            let mut ws = Scratch::new();
            let g = w.guard(&mut ws, 0, 0, &x);
            assert!(g.abs() < 1e-14, "r {r}, h {h}: guard {g}");
            assert!(w.admissible(0, 0, &x), "r {r}, h {h}");
            let d = 1e-3;
            let psi = (q0.cos() + (h - d) / ell).acos();
            x[1] = psi - q0;
            let g = w.guard(&mut ws, 0, 0, &x);
            assert!(
                (g - d).abs() < 1e-12,
                "r {r}, h {h}: raised by {d}, guard {g}"
            );
        }
        let values: Vec<f64> = base
            .param_values()
            .into_iter()
            .map(|(n, v)| if n == "step_down" { ell } else { v })
            .collect();
        let e = match ChainWalker::new(base.spec().clone(), &values) {
            Ok(_) => panic!("r {r}: a step of the hip's reach is taken"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("step_down"), "{e}");
        assert!(
            e.contains(if r > 0.0 {
                "arc centre"
            } else {
                "one leg length"
            }),
            "{e}"
        );
    }
}

/// A tilted landing line (random slopes with round feet), from plane geometry written here: the
/// stance arc centre at the origin, its contact point `c = (0, −r)`, the landing line through
/// `c` with tangent `t = (cos Δ, −sin Δ)` and normal `n = (sin Δ, cos Δ)`; straight legs put the
/// hip at `ℓ(−sin q₀, cos q₀)` and the swing arc centre at the hip plus `ℓ(sin ψ, −cos ψ)`
/// (`ℓ = L − r`). The guard is the swing arc's distance to the line less `r`; at a touch the
/// heel strike leaves the new contact point `S − r n` at rest and the ground pushes along `n`;
/// the exact gradient and rate agree with differences, the batched guard with the scalar one.
#[test]
fn a_tilted_landing_line_is_where_plane_geometry_puts_it() {
    let l_leg = 1.0; // the compass preset: a + b
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    for r in [0.0, 0.1] {
        let base = with_radius(&presets::compass(&[]).unwrap(), r);
        let ell = l_leg - r;
        for delta in [0.03, -0.05, 0.2] {
            let w = base.with_tilt(delta).unwrap();
            assert_eq!(w.tilt(), delta);
            let (s, c) = (delta.sin(), delta.cos());
            let geometric = |q0: f64, psi: f64| {
                let hip = [-ell * q0.sin(), ell * q0.cos()];
                let sc = [hip[0] + ell * psi.sin(), hip[1] - ell * psi.cos()];
                ((sc[0] * s + (sc[1] + r) * c) - r, sc)
            };
            let mut ws = Scratch::new();
            for _ in 0..20 {
                let q0: f64 = rng.random_range(-0.5..0.5);
                let psi: f64 = rng.random_range(-0.6..0.6);
                let mut x = vec![0.0; w.dim()];
                x[0] = q0;
                x[1] = psi - q0;
                let (g, _) = geometric(q0, psi);
                let got = w.guard(&mut ws, 0, 0, &x);
                assert!((got - g).abs() < 1e-14, "r {r}, Δ {delta}: {got} vs {g}");
            }
            // a touch ahead: the swing leg's angle ψ where the arc meets the line (bisection)
            let q0: f64 = -0.3;
            let (mut lo, mut hi) = (q0 + 0.02, 1.2);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                // below the line at lo (the legs nearly together), above it at hi
                if geometric(q0, mid).0 > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let psi = 0.5 * (lo + hi);
            let sc = geometric(q0, psi).1;
            let mut x = vec![0.0; w.dim()];
            x[0] = q0;
            x[1] = psi - q0;
            x[2] = -1.1;
            x[3] = 0.8;
            let g = w.guard(&mut ws, 0, 0, &x);
            assert!(g.abs() < 1e-13, "r {r}, Δ {delta}: guard {g} at a touch");
            assert!(w.admissible(0, 0, &x), "r {r}, Δ {delta}: a touch ahead");
            // the point of the arc nearest the line is on the line, ahead of c
            let touch = [sc[0] - r * s, sc[1] - r * c];
            let along = touch[0] * c - (touch[1] + r) * s;
            let across = touch[0] * s + (touch[1] + r) * c;
            assert!(along > 0.0 && across.abs() < 1e-13, "{touch:?}");
            let mut v = vec![0.0; 4];
            let imp = w.heel_strike(&mut ws, &x, &mut v);
            let mut q = vec![0.0; 4];
            q[2..].copy_from_slice(&x[..2]);
            let mut jt = vec![0.0; 8];
            let mut pos = [0.0; 2];
            pdw_soa::tip_position_derivatives(w.floating_chain(), &q, &mut pos, &mut jt).unwrap();
            let vs: Vec<f64> = (0..2)
                .map(|i| (0..4).map(|k| jt[i * 4 + k] * v[k]).sum())
                .collect();
            let omega = v[2] + v[3]; // the swing leg's absolute rate
                                     // contact point velocity: Ṡ + ω × (−r n), ω × (a, b) = ω (−b, a)
            let vc = [vs[0] + omega * r * c, vs[1] - omega * r * s];
            assert!(
                vc[0].abs() < 1e-12 && vc[1].abs() < 1e-12,
                "r {r}, Δ {delta}: the new contact point moves at {vc:?}"
            );
            assert!(imp[0] * s + imp[1] * c > 0.0, "the ground pushes: {imp:?}");
            // gradient and rate against differences, batched = scalar
            for _ in 0..5 {
                let x = random_state(&w, &mut rng, 0);
                let mut grad = vec![0.0; 4];
                w.guard_gradient(&mut ws, 0, 0, &x, &mut grad);
                let mut ws2 = Scratch::new();
                let fd = richardson(&mut |x, out| out[0] = w.guard(&mut ws2, 0, 0, x), &x, 1);
                assert_close(&grad, &fd, 1e-8, &format!("tilted guard gradient r {r}"));
                let mut f = vec![0.0; 4];
                w.flow(&mut ws, 0, &x, &mut f);
                let ng = w.guards(0).len();
                let (mut gs, mut rates) = (vec![0.0; ng], vec![0.0; ng]);
                w.guards_with_rates(&mut ws, 0, &x, &f, &mut gs, &mut rates);
                let dot: f64 = grad.iter().zip(&f).map(|(a, b)| a * b).sum();
                assert!((rates[0] - dot).abs() < 1e-12 * (1.0 + dot.abs()), "rate");
                assert_eq!(gs[0].to_bits(), w.guard(&mut ws, 0, 0, &x).to_bits());
                let xm = Mat::from_fn(3, 4, |_, j| x[j]);
                let mut gb = vec![0.0; 3];
                w.guard_batch(&mut ws, 0, 0, xm.as_ref(), &mut gb);
                assert!(gb.iter().all(|v| v.to_bits() == gs[0].to_bits()));
            }
        }
        // refused: a tilt of π/4 or more, and a tilt together with a step height
        assert!(base.with_tilt(std::f64::consts::FRAC_PI_4).is_err());
        let values: Vec<f64> = base
            .param_values()
            .into_iter()
            .map(|(n, v)| if n == "step_down" { 0.05 } else { v })
            .collect();
        let stepped = ChainWalker::new(base.spec().clone(), &values).unwrap();
        let e = stepped.with_tilt(0.01).unwrap_err().to_string();
        assert!(e.contains("step_down"), "{e}");
        // Δ = 0 is the model itself
        assert_eq!(
            base.with_tilt(0.0).unwrap().fingerprint(),
            base.fingerprint()
        );
    }
}
