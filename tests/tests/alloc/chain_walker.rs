//! The chain walker allocates nothing per right-hand side (scalar or batched), flow Jacobian,
//! guard, guard gradient, admissibility, reset, reset Jacobian or trajectory sample (constraint forces, step
//! flags, energy) once its scratch is filled; body points allocate only the value they return.

use crate::allocs;
use crate::chain_common::{all_presets, random_state};
use faer::Mat;
use pdw_hybrid::{HybridSystem, Scratch};
use pdw_model::Walker;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn flow_jacobian_and_resets_allocate_nothing_after_the_first_call() {
    let mut r = ChaCha8Rng::seed_from_u64(4);
    for (name, w) in all_presets() {
        let d = w.dim();
        let lanes = 64;
        let mut ws = Scratch::new();
        let modes: Vec<usize> = (0..w.n_modes()).collect();
        let states: Vec<Vec<Vec<f64>>> = modes
            .iter()
            .map(|&m| (0..lanes).map(|_| random_state(&w, &mut r, m)).collect())
            .collect();
        let xs: Vec<Mat<f64>> = states
            .iter()
            .map(|s| Mat::from_fn(lanes, d, |l, j| s[l][j]))
            .collect();
        let mut dx = Mat::<f64>::zeros(lanes, d);
        let (mut f, mut jac, mut out) = (vec![0.0; d], vec![0.0; d * d], vec![0.0; d]);
        let mut counts = [0usize; 9];
        let mut run = |ws: &mut Scratch, counts: &mut [usize; 9]| {
            let tick = |i: usize, c: &mut [usize; 9], before: usize| {
                c[i] += allocs() - before;
            };
            for &m in &modes {
                let b = allocs();
                w.flow_batch(ws, m, xs[m].as_ref(), dx.as_mut());
                tick(0, counts, b);
                for s in &states[m][..4] {
                    let b = allocs();
                    w.flow(ws, m, s, &mut f);
                    tick(1, counts, b);
                    let b = allocs();
                    w.flow_jacobian(ws, m, s, &mut jac);
                    tick(2, counts, b);
                    let b = allocs();
                    w.guard(ws, m, 0, s);
                    tick(3, counts, b);
                    let b = allocs();
                    w.reset(ws, m, 0, s, &mut out);
                    tick(4, counts, b);
                    let b = allocs();
                    w.reset_jacobian(ws, m, 0, s, &mut jac);
                    tick(5, counts, b);
                    let mut g = [0.0; 16];
                    let b = allocs();
                    w.guard_gradient(ws, m, 0, s, &mut g[..d]);
                    tick(6, counts, b);
                    let b = allocs();
                    let sample = (
                        w.constraint_forces_in(ws, m, s),
                        w.step_flags_in(ws, m, s),
                        w.energy_in(ws, s),
                    );
                    tick(7, counts, b);
                    assert!(sample.0.is_some() && sample.1.is_some() && sample.2.is_some());
                    // admissibility of every guard: the impact's complementarity problem for
                    // a stance knee's buckling at the impact guard
                    let b = allocs();
                    for k in 0..w.guards(m).len() {
                        std::hint::black_box(w.admissible(m, k, s));
                    }
                    tick(8, counts, b);
                }
            }
        };
        run(&mut ws, &mut [0; 9]); // fills the scratch
        run(&mut ws, &mut counts);
        assert_eq!(
            counts, [0; 9],
            "{name}: allocations in [flow_batch, flow, flow_jacobian, guard, reset, \
             reset_jacobian, guard_gradient, trajectory sample, admissible]"
        );
        // body points: the kinematics run in the scratch's workspace; only the returned value
        // allocates (its point list, its name list and one string per name), while the call
        // without a scratch also builds a kernel workspace
        let x = &states[0][0];
        let b = allocs();
        let bp = w
            .body_points_in(&mut ws, x)
            .expect("chain walkers give body points");
        let used = allocs() - b;
        assert_eq!(
            used,
            2 + bp.names.len(),
            "{name}: body_points_in allocations"
        );
        let b = allocs();
        let fresh = w.body_points(x).expect("chain walkers give body points");
        let used_fresh = allocs() - b;
        assert!(used_fresh > used + 10, "{name}: {used_fresh} vs {used}");
        assert_eq!(fresh.names, bp.names);
        let bits = |p: &[[f64; 2]]| p.iter().map(|v| v.map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&fresh.points), bits(&bp.points), "{name}");
        assert_eq!(
            fresh.com.map(f64::to_bits),
            bp.com.map(f64::to_bits),
            "{name}"
        );
        // the reused scratch carries nothing from one sample to the next: the same bits as a
        // fresh scratch per call
        for &m in &modes {
            for s in &states[m][..4] {
                assert_eq!(
                    w.constraint_forces_in(&mut ws, m, s),
                    w.constraint_forces(m, s)
                );
                assert_eq!(w.step_flags_in(&mut ws, m, s), w.step_flags(m, s));
                let bits = |e: Option<f64>| e.map(f64::to_bits);
                assert_eq!(bits(w.energy_in(&mut ws, s)), bits(w.energy(s)), "{name}");
            }
        }
    }
}
