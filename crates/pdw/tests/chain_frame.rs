//! The Markov chain's mesh along the walkers' principal axes against the axis-aligned mesh, on
//! the simplest walker, whose visited states lie along an oblique band of (θ, θ̇) and whose
//! basin is thin across it: the Monte Carlo walkers are the reference, the mesh refinement the
//! chain's own check.

use pdw::mfpt::{self, ChainPlan, MfptPlan};
use pdw_limit::terrain::{SlopeTerrain, TerrainKind};

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
}

#[test]
fn the_principal_axes_mesh_resolves_the_simplest_walkers_band_where_the_axis_box_does_not() {
    let m = pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.009,
            sd: 0.04_f64.to_radians(),
            seed: 1,
            kind: TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers: 4000,
        max_strides: 1000,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let pool = pool();
    let (_, mc) = mfpt::run(&m, &plan, &x0, &pool, &|_| {}).unwrap();
    assert_eq!(mc.censored, 0, "every walker falls at this σ");
    // measured: 37.2 ± 0.23 with 20 000 walkers (seeds 1 and 2)
    assert!((30.0..45.0).contains(&mc.mfpt), "Monte Carlo {}", mc.mfpt);
    let c = |mesh| ChainPlan {
        nodes: 11,
        mesh,
        bounds: None,
        section: Default::default(),
        layout: Default::default(),
    };

    // the axis-aligned box of the visited states: not converged, and the check says so
    let axis = mfpt::visited_box(&m, &plan, &x0, &pool).unwrap();
    let a60 = mfpt::chain(&m, &plan, &c(60), &axis, &x0, &pool).unwrap();
    let a120 = mfpt::chain(&m, &plan, &c(120), &axis, &x0, &pool).unwrap();
    assert!(mfpt::refinement_warning(&a60, &a120, 60).is_some());
    assert!(
        a120.mfpt < 0.75 * mc.mfpt,
        "axis box, mesh 120: {}",
        a120.mfpt
    );

    // the principal frame: its box is far smaller than the axis box, no widening is needed,
    // the two meshes agree within the refinement tolerance and with the walkers within 10 %
    let cb = mfpt::chain_box(&m, &plan, &c(60), &x0, &pool, &|_| {}).unwrap();
    assert!(!cb.frame.is_identity());
    assert_eq!(cb.passes, 0, "box exits {:.3} of absorption", cb.out_share);
    let (_, edges) = cb.frame.edges(&cb.bounds);
    let area = (edges[0][0] * edges[1][1] - edges[0][1] * edges[1][0]).abs();
    let axis_area = (axis.1[0] - axis.0[0]) * (axis.1[1] - axis.0[1]);
    assert!(
        area < 0.5 * axis_area,
        "frame box {area} vs axis box {axis_area}"
    );
    let on_frame = |n: usize| {
        mfpt::chain_in(&m, &plan, &c(n), &cb.frame, &cb.bounds, &x0, &pool, &|_| {}).unwrap()
    };
    let (f60, f120) = (on_frame(60), on_frame(120));
    assert!(
        mfpt::refinement_warning(&f60, &f120, 60).is_none(),
        "{} / {}",
        f60.mfpt,
        f120.mfpt
    );
    assert!(
        (f120.mfpt - mc.mfpt).abs() < 0.1 * mc.mfpt,
        "frame mesh 120: {} against the walkers' {} ± {}",
        f120.mfpt,
        mc.mfpt,
        mc.stderr
    );
    assert!((f120.mfpt - mc.mfpt).abs() < 0.5 * (a120.mfpt - mc.mfpt).abs());
}

#[test]
fn the_refinement_change_is_relative_to_the_larger_and_flags_non_finite_results() {
    let r = |mfpt: f64| pdw_limit::markov::ChainResult {
        mfpt,
        lambda: 0.9,
        mfpt_lambda: 9.0,
        mfpt_quasi_stationary: 9.0,
        out_of_mesh: 0.0,
        fall_per_step: 0.1,
        residual: 1e-13,
        states: 4,
    };
    assert!((mfpt::refinement_change(&r(90.0), &r(100.0)) - 0.1).abs() < 1e-15);
    assert!((mfpt::refinement_change(&r(100.0), &r(90.0)) - 0.1).abs() < 1e-15);
    assert_eq!(mfpt::refinement_change(&r(0.0), &r(0.0)), 0.0);
    assert_eq!(mfpt::refinement_change(&r(f64::NAN), &r(3.0)), 1.0);
    assert!(mfpt::refinement_warning(&r(95.0), &r(100.0), 60).is_none());
    let w = mfpt::refinement_warning(&r(40.0), &r(100.0), 60).unwrap();
    assert!(w.contains("60 % from mesh 60 to mesh 120"), "{w}");
}
