//! Exact derivatives by dual numbers through the kernel's step functions: their values equal the
//! kernel's forward dynamics, impacts and tip position, their Jacobians equal
//! Richardson-extrapolated central differences of those kernel functions, and no call allocates.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use crate::common;
use common::*;
use faer::Mat;
use pdw_soa::derivatives::MAX_DOF;
use pdw_soa::*;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The test binary's allocator: the system's, counting per thread what the tests on that thread
/// allocate (the other tests of the binary run on threads of their own and count nothing here).
struct Counting;

thread_local! {
    /// Allocations made by this thread (tests run on separate threads).
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
    /// Bytes requested by this thread's allocations.
    static BYTES: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        ALLOCS.with(|c| c.set(c.get() + 1));
        BYTES.with(|c| c.set(c.get() + l.size()));
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocs() -> usize {
    ALLOCS.with(|c| c.get())
}

fn bytes() -> usize {
    BYTES.with(|c| c.get())
}

/// Jacobian (`r × p`, row-major) of `f: R^p → R^r` at `x` by central differences with steps
/// `h, h/2, h/4`, extrapolated twice (Richardson: error `O(h⁶)` plus rounding `~ ε|f|/h`).
fn richardson(x: &[f64], r: usize, h: f64, mut f: impl FnMut(&[f64], &mut [f64])) -> Vec<f64> {
    let p = x.len();
    let mut jac = vec![0.0; r * p];
    let (mut xp, mut fp, mut fm) = (x.to_vec(), vec![0.0; r], vec![0.0; r]);
    let mut d = [vec![0.0; r], vec![0.0; r], vec![0.0; r]];
    for j in 0..p {
        for (level, dl) in d.iter_mut().enumerate() {
            let hl = h / f64::from(1u32 << level);
            xp[j] = x[j] + hl;
            f(&xp, &mut fp);
            xp[j] = x[j] - hl;
            f(&xp, &mut fm);
            xp[j] = x[j];
            for i in 0..r {
                dl[i] = (fp[i] - fm[i]) / (2.0 * hl);
            }
        }
        for i in 0..r {
            let r1a = (4.0 * d[1][i] - d[0][i]) / 3.0;
            let r1b = (4.0 * d[2][i] - d[1][i]) / 3.0;
            jac[i * p + j] = (16.0 * r1b - r1a) / 15.0;
        }
    }
    jac
}

/// First step of the Richardson differences (rad or m): small enough for the `O(h⁶)` truncation
/// near the stiffest configurations drawn, large enough for rounding `~ ε |f| / h`.
const H: f64 = 5e-3;

/// `‖a − b‖ / ‖b‖` (Frobenius; `‖b‖` floored at 1e-300).
fn rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    diff_norm(a, b) / norm(b).max(1e-300)
}

/// Columns `c0..c0+w` of an `r × c` row-major matrix.
fn cols(m: &[f64], r: usize, c: usize, c0: usize, w: usize) -> Vec<f64> {
    (0..r)
        .flat_map(|i| m[i * c + c0..i * c + c0 + w].iter().copied())
        .collect()
}

/// A floating chain as the walkers use for impacts: two prismatic base joints `(y, z)` with a
/// light base link, then `legs` revolute segments hanging roughly downwards.
fn floating_chain(r: &mut ChaCha8Rng, legs: usize) -> Chain {
    let base = Link {
        to_next: [0.0, 0.0],
        com: [0.0, 0.0],
        mass: 1e-3,
        inertia: 0.0,
    };
    let mut b = ChainBuilder::new()
        .gravity(9.81)
        .slope(r.random_range(-0.1..0.1))
        .prismatic([1.0, 0.0], base)
        .prismatic([0.0, 1.0], base);
    for _ in 0..legs {
        let len = r.random_range(0.3..1.0);
        let ang: f64 = r.random_range(-0.4..0.4);
        let to_next = [len * ang.sin(), -len * ang.cos()];
        b = b.revolute(Link {
            to_next,
            com: [
                r.random_range(0.3..0.7) * to_next[0] + r.random_range(-0.05..0.05),
                r.random_range(0.3..0.7) * to_next[1],
            ],
            mass: r.random_range(0.5..5.0),
            inertia: r.random_range(0.01..0.2),
        });
    }
    b.build().unwrap()
}

/// Random chains of every supported size: fixed-base with and without prismatic joints, and
/// floating-base ones (2 prismatic + 1..=6 revolute).
fn chains(r: &mut ChaCha8Rng) -> Vec<Chain> {
    let mut out = Vec::new();
    for n in 1..=MAX_DOF {
        out.push(random_chain(r, n, false));
        out.push(random_chain(r, n, true));
    }
    for legs in 1..=MAX_DOF - 2 {
        out.push(floating_chain(r, legs));
    }
    out
}

/// Largest relative errors seen, printed for the record (`--nocapture`).
#[derive(Default)]
struct Worst {
    value: f64,
    jac: f64,
}

impl Worst {
    fn see(&mut self, value: f64, jac: f64) {
        self.value = self.value.max(value);
        self.jac = self.jac.max(jac);
    }
}

fn check_forward_dynamics(with_locks: bool) -> Worst {
    let mut r = rng(if with_locks { 91 } else { 90 });
    let mut worst = Worst::default();
    for chain in chains(&mut r) {
        let n = chain.dof();
        let mut ws = Workspace::new(&chain);
        for _ in 0..4 {
            let (q, qd) = random_state(&mut r, &chain);
            let tau = random_vec(&mut r, n, -3.0, 3.0);
            let mut locked = vec![false; n];
            let mut list = Vec::new();
            if with_locks {
                for (k, l) in locked.iter_mut().enumerate() {
                    if r.random_range(0.0..1.0) < 0.35 {
                        *l = true;
                        list.push(k);
                    }
                }
            }
            let (mut qdd, mut jq, mut jqd) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
            aba_derivatives(&chain, &q, &qd, &tau, &locked, &mut qdd, &mut jq, &mut jqd).unwrap();

            // the kernel's forward dynamics, as a function of x = (q, q̇)
            let mut lock_torque = vec![0.0; n];
            let mut fd = |x: &[f64], out: &mut [f64]| {
                if with_locks {
                    pseudo_joint_dynamics(
                        &chain,
                        &mut ws,
                        &x[..n],
                        &x[n..],
                        &tau,
                        &list,
                        None,
                        out,
                        &mut lock_torque,
                    )
                    .unwrap();
                } else {
                    aba(&chain, &mut ws, &x[..n], &x[n..], &tau, None, out).unwrap();
                }
            };
            let x: Vec<f64> = q.iter().chain(&qd).copied().collect();
            let mut want = vec![0.0; n];
            fd(&x, &mut want);
            let ev = rel(&qdd, &want);
            assert!(ev <= 1e-13, "value n={n}: rel {ev:e}");

            let num = richardson(&x, n, H, &mut fd);
            let (nq, nqd) = (cols(&num, n, 2 * n, 0, n), cols(&num, n, 2 * n, n, n));
            let (eq, eqd) = (rel(&jq, &nq), rel(&jqd, &nqd));
            assert!(eq <= 1e-9, "∂q̈/∂q n={n} locked={list:?}: rel {eq:e}");
            assert!(eqd <= 1e-9, "∂q̈/∂q̇ n={n} locked={list:?}: rel {eqd:e}");
            for &k in &list {
                assert!(jq[k * n..(k + 1) * n].iter().all(|&v| v == 0.0));
                assert!(jqd[k * n..(k + 1) * n].iter().all(|&v| v == 0.0));
                assert_eq!(qdd[k], 0.0);
            }
            worst.see(ev, eq.max(eqd));
        }
    }
    worst
}

#[test]
fn aba_derivatives_equal_aba_and_richardson_differences_of_it() {
    let w = check_forward_dynamics(false);
    eprintln!("aba: value rel ≤ {:e}, Jacobian rel ≤ {:e}", w.value, w.jac);
}

#[test]
fn locked_aba_derivatives_equal_pseudo_joint_dynamics_and_richardson_differences_of_it() {
    let w = check_forward_dynamics(true);
    eprintln!(
        "pseudo joints: value rel ≤ {:e}, Jacobian rel ≤ {:e}",
        w.value, w.jac
    );
}

#[test]
fn aba_derivatives_value_is_the_kernels_recursion_bit_for_bit() {
    let mut r = rng(92);
    for chain in chains(&mut r) {
        let n = chain.dof();
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let tau = random_vec(&mut r, n, -3.0, 3.0);
        let locked: Vec<bool> = (0..n).map(|k| k % 3 == 1).collect();
        let list: Vec<usize> = (0..n).filter(|&k| locked[k]).collect();
        let (mut qdd, mut jq, mut jqd) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
        let (mut want, mut lt) = (vec![0.0; n], vec![0.0; n]);
        aba_derivatives(
            &chain,
            &q,
            &qd,
            &tau,
            &vec![false; n],
            &mut qdd,
            &mut jq,
            &mut jqd,
        )
        .unwrap();
        aba(&chain, &mut ws, &q, &qd, &tau, None, &mut want).unwrap();
        assert!(qdd
            .iter()
            .zip(&want)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        aba_derivatives(&chain, &q, &qd, &tau, &locked, &mut qdd, &mut jq, &mut jqd).unwrap();
        pseudo_joint_dynamics(
            &chain, &mut ws, &q, &qd, &tau, &list, None, &mut want, &mut lt,
        )
        .unwrap();
        assert!(qdd
            .iter()
            .zip(&want)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}

/// Impact derivatives against the kernel's impact map (`tip`: heel strike, else knee strike).
fn check_impact(tip: bool) -> Worst {
    let mut r = rng(if tip { 93 } else { 94 });
    let mut worst = Worst::default();
    let mut cases = 0;
    for chain in chains(&mut r) {
        let n = chain.dof();
        let mut ws = Workspace::new(&chain);
        for trial in 0..4 {
            // locked joints: none or some (heel strike), at least one (knee strike)
            let base = if tip { 2 } else { 0 };
            if base + usize::from(!tip) > n {
                continue;
            }
            let max_locks = n - base;
            let nl = if tip {
                (trial % 3).min(max_locks)
            } else {
                1 + trial % max_locks.min(3)
            };
            let mut list: Vec<usize> = Vec::new();
            while list.len() < nl {
                let k = r.random_range(0..n);
                if !list.contains(&k) {
                    list.push(k);
                }
            }
            let (q, qd) = random_state(&mut r, &chain);
            let mut imp = vec![0.0; base + nl];
            let mut kernel = |x: &[f64], out: &mut [f64]| {
                if tip {
                    tip_impact(&chain, &mut ws, &x[..n], &x[n..], &list, out, &mut imp)
                } else {
                    joint_lock_impact(&chain, &mut ws, &x[..n], &x[n..], &list, out, &mut imp)
                }
            };
            let x: Vec<f64> = q.iter().chain(&qd).copied().collect();
            let mut want = vec![0.0; n];
            if kernel(&x, &mut want).is_err() {
                continue; // dependent constraint rows in this configuration
            }
            let (mut post, mut jac) = (vec![0.0; n], vec![0.0; 2 * n * n]);
            if tip {
                tip_impact_derivatives(&chain, &q, &qd, &list, &mut post, &mut jac).unwrap();
            } else {
                joint_lock_impact_derivatives(&chain, &q, &qd, &list, &mut post, &mut jac).unwrap();
            }
            // the kernel's operations in the kernel's order: the same bits
            assert!(
                post.iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "value n={n} locked={list:?}: {post:?} vs {want:?}"
            );
            if base + nl == n {
                // as many constraints as joints: q̇⁺ ≡ 0 near q, so the map and its
                // Jacobian vanish (to rounding)
                assert!(norm(&post) <= 1e-13 * norm(&qd), "n={n}: {post:?}");
                assert!(norm(&jac) <= 1e-13 * (1.0 + norm(&qd)), "n={n}: {jac:?}");
                continue;
            }
            let ev = rel(&post, &want);
            assert!(ev <= 1e-13, "value n={n} locked={list:?}: rel {ev:e}");
            let num = richardson(&x, n, H, |x, out| kernel(x, out).unwrap());
            let ej = rel(&jac, &num);
            assert!(ej <= 1e-9, "Jacobian n={n} locked={list:?}: rel {ej:e}");
            worst.see(ev, ej);
            cases += 1;
        }
    }
    assert!(cases >= 40, "only {cases} impact cases ran");
    worst
}

#[test]
fn tip_impact_derivatives_equal_tip_impact_and_richardson_differences_of_it() {
    let w = check_impact(true);
    eprintln!(
        "tip impact: value rel ≤ {:e}, Jacobian rel ≤ {:e}",
        w.value, w.jac
    );
}

#[test]
fn joint_lock_impact_derivatives_equal_joint_lock_impact_and_richardson_differences_of_it() {
    let w = check_impact(false);
    eprintln!(
        "joint-lock impact: value rel ≤ {:e}, Jacobian rel ≤ {:e}",
        w.value, w.jac
    );
}

#[test]
fn tip_position_derivatives_equal_tip_position_and_the_linear_tip_jacobian() {
    let mut r = rng(95);
    let mut worst = Worst::default();
    for chain in chains(&mut r) {
        let n = chain.dof();
        let mut ws = Workspace::new(&chain);
        for _ in 0..4 {
            let (q, _) = random_state(&mut r, &chain);
            let (mut pos, mut jac) = ([0.0; 2], vec![0.0; 2 * n]);
            tip_position_derivatives(&chain, &q, &mut pos, &mut jac).unwrap();
            let want = tip_position(&chain, &mut ws, &q).unwrap();
            assert_eq!(pos[0].to_bits(), want[0].to_bits());
            assert_eq!(pos[1].to_bits(), want[1].to_bits());
            let jl = tip_jacobian_linear(&chain, &mut ws, &q).unwrap();
            let jl: Vec<f64> = (0..2)
                .flat_map(|i| (0..n).map(move |k| (i, k)))
                .map(|(i, k)| jl[(i, k)])
                .collect();
            let ek = rel(&jac, &jl);
            assert!(ek <= 1e-14, "n={n}: against J_lin rel {ek:e}");
            let num = richardson(&q, 2, H, |x, out| {
                out.copy_from_slice(&tip_position(&chain, &mut ws, x).unwrap())
            });
            let ej = rel(&jac, &num);
            assert!(ej <= 1e-9, "n={n}: against differences rel {ej:e}");
            worst.see(ek, ej);
        }
    }
    eprintln!(
        "tip position: Jacobian vs J_lin rel ≤ {:e}, vs differences rel ≤ {:e}",
        worst.value, worst.jac
    );
}

#[test]
fn derivative_calls_do_not_allocate() {
    let mut r = rng(96);
    for legs in [1, 3, MAX_DOF - 2] {
        let chain = floating_chain(&mut r, legs);
        let n = chain.dof();
        let (q, qd) = random_state(&mut r, &chain);
        let tau = random_vec(&mut r, n, -1.0, 1.0);
        let locked: Vec<bool> = (0..n).map(|k| k == n - 1).collect();
        let (mut qdd, mut jq, mut jqd) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
        let (mut post, mut jac) = (vec![0.0; n], vec![0.0; 2 * n * n]);
        let (mut pos, mut tj) = ([0.0; 2], vec![0.0; 2 * n]);
        let knee = [n - 1];
        let before = allocs();
        for _ in 0..10 {
            aba_derivatives(&chain, &q, &qd, &tau, &locked, &mut qdd, &mut jq, &mut jqd).unwrap();
            tip_impact_derivatives(&chain, &q, &qd, &[], &mut post, &mut jac).unwrap();
            joint_lock_impact_derivatives(&chain, &q, &qd, &knee, &mut post, &mut jac).unwrap();
            tip_position_derivatives(&chain, &q, &mut pos, &mut tj).unwrap();
        }
        assert_eq!(allocs() - before, 0, "n = {n}");
    }
}

/// The scalar kernels (forward kinematics, RNEA, ABA, CRBA forward dynamics, energy) and the
/// batched ABA / RNEA on a block allocate nothing on their second and later calls: every
/// intermediate lives in the caller's [`Workspace`] / [`BatchWorkspace`].
#[test]
fn scalar_and_batched_kernels_do_not_allocate_after_the_workspace_is_built() {
    let mut r = rng(98);
    for (n, prismatic) in [(1, false), (4, true), (12, false)] {
        let chain = random_chain(&mut r, n, prismatic);
        let (q, qd) = random_state(&mut r, &chain);
        let tau = random_vec(&mut r, n, -1.0, 1.0);
        let (mut qdd, mut tau_out) = (vec![0.0; n], vec![0.0; n]);
        let lanes = pdw_soa::batch::BLOCK;
        let qb = Mat::from_fn(lanes, n, |l, k| q[k] + 1e-3 * l as f64);
        let qdb = Mat::from_fn(lanes, n, |_, k| qd[k]);
        let taub = Mat::from_fn(lanes, n, |_, k| tau[k]);
        let (mut qddb, mut taubo) = (Mat::<f64>::zeros(lanes, n), Mat::<f64>::zeros(lanes, n));
        let mut ws = Workspace::new(&chain);
        let mut bw = BatchWorkspace::new(&chain, lanes);
        let mut energy = 0.0;
        let mut counts = [0usize; 7];
        // the first round is the first call: the process's first batched call reads the
        // PDW_SIMD override once (one allocation, pdw-simd caches the path it selects)
        for round in 0..6 {
            let mut tick = |i: usize, b: usize| {
                if round > 0 {
                    counts[i] += allocs() - b;
                }
            };
            let b = allocs();
            forward_kinematics(&chain, &mut ws, &q).unwrap();
            tick(0, b);
            let b = allocs();
            aba(
                &chain,
                &mut ws,
                &q,
                &qd,
                &tau,
                Some([0.1, 0.2, 0.3]),
                &mut qdd,
            )
            .unwrap();
            tick(1, b);
            let b = allocs();
            rnea(&chain, &mut ws, &q, &qd, &qdd, None, &mut tau_out).unwrap();
            tick(2, b);
            let b = allocs();
            forward_dynamics_crba(&chain, &mut ws, &q, &qd, &tau, None, &mut qdd).unwrap();
            tick(3, b);
            let b = allocs();
            energy += total_energy(&chain, &mut ws, &q, &qd).unwrap();
            tick(4, b);
            let b = allocs();
            batch_aba(&chain, &mut bw, &qb, &qdb, &taub, None, &mut qddb).unwrap();
            tick(5, b);
            let b = allocs();
            batch_rnea(&chain, &mut bw, &qb, &qdb, &qddb, None, &mut taubo).unwrap();
            tick(6, b);
        }
        assert_eq!(
            counts, [0; 7],
            "n = {n}: allocations in [kinematics, aba, rnea, crba, energy, batch_aba, batch_rnea]"
        );
        assert!(energy.is_finite());
        // the batched round trip returns the applied torques (an independent check that the
        // calls above did their work)
        for l in 0..lanes {
            for k in 0..n {
                let (a, b) = (taubo[(l, k)], taub[(l, k)]);
                assert!(
                    (a - b).abs() <= 1e-8 * (1.0 + b.abs()),
                    "lane {l} joint {k}"
                );
            }
        }
    }
}

#[test]
fn derivatives_reject_bad_arguments() {
    let mut r = rng(97);
    let big = random_chain(&mut r, MAX_DOF + 1, false);
    let n = big.dof();
    let z = vec![0.0; n];
    let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * n]);
    assert!(matches!(
        aba_derivatives(&big, &z, &z, &z, &vec![false; n], &mut a, &mut b, &mut c),
        Err(SoaError::DimensionMismatch { .. })
    ));
    let chain = random_chain(&mut r, 4, false);
    let z = vec![0.0; 4];
    let (mut post, mut jac) = (vec![0.0; 4], vec![0.0; 32]);
    assert!(matches!(
        joint_lock_impact_derivatives(&chain, &z, &z, &[1, 1], &mut post, &mut jac),
        Err(SoaError::InvalidJointIndex { index: 1, n: 4 })
    ));
    assert!(matches!(
        tip_impact_derivatives(&chain, &z, &z, &[4], &mut post, &mut jac),
        Err(SoaError::InvalidJointIndex { index: 4, n: 4 })
    ));
    assert!(matches!(
        tip_impact_derivatives(&chain, &z, &z, &[0, 1, 2], &mut post, &mut jac),
        Err(SoaError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        tip_impact_derivatives(&chain, &z, &z, &[], &mut post, &mut jac[..31]),
        Err(SoaError::DimensionMismatch { .. })
    ));
}

/// The size queries tell what building a workspace will allocate, byte for byte: the scalar
/// [`Workspace`] for chains of 1–12 joints, the [`BatchWorkspace`] for lane counts below, at
/// and above one block (where it stops growing).
#[test]
fn workspace_size_queries_equal_what_building_them_allocates() {
    let mut r = rng(99);
    for n in 1..=12 {
        let chain = random_chain(&mut r, n, n % 3 == 0);
        let b = bytes();
        let ws = Workspace::new(&chain);
        assert_eq!(
            bytes() - b,
            Workspace::scratch_bytes(n),
            "Workspace, n = {n}"
        );
        drop(ws);
        for lanes in [1, 7, 16, 255, 256, 257, 5000] {
            let b = bytes();
            let bw = BatchWorkspace::new(&chain, lanes);
            assert_eq!(
                bytes() - b,
                BatchWorkspace::scratch_bytes(n, lanes),
                "BatchWorkspace, n = {n}, lanes = {lanes}"
            );
            drop(bw);
        }
    }
    assert_eq!(
        BatchWorkspace::scratch_bytes(5, 1 << 20),
        BatchWorkspace::scratch_bytes(5, pdw_soa::batch::BLOCK)
    );
}
