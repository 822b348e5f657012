//! Measurements of continuation on the simplest walker (printed, not asserted): the period-one
//! branch with its bifurcations, the period-doubling cascade, a 400-point branch and an orbit
//! diagram, each timed. Run with
//! `cargo run --release -p pdw-experiments --bin continuation_measure`.

use pdw_limit::{continue_branch, period_doubling_cascade, ContinuationOptions};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use std::time::Instant;

fn family(g: f64) -> Result<Box<Simplest>, pdw_walkers::WalkerError> {
    Simplest::new(SimplestParams {
        slope: g,
        ..Default::default()
    })
    .map(Box::new)
}

fn measure_simplest_branch_and_cascade() {
    let opts = ContinuationOptions::new(0.001, 0.0195);
    let t = Instant::now();
    let b = continue_branch(&family, &[0.2003, -0.1998], 0.009, 1, &opts).unwrap();
    println!(
        "period-1 branch from γ=0.009 up: {} points in {:.3} s, end {:?}",
        b.points.len(),
        t.elapsed().as_secs_f64(),
        b.end
    );
    for bif in &b.bifurcations {
        println!(
            "  {:?} at γ = {:.12} (bracket {:.1e}) s = {:?} λ = {:?}",
            bif.kind, bif.param, bif.param_bracket, bif.section, bif.multipliers
        );
    }
    let p = b.points.last().unwrap();
    println!(
        "  last point γ = {} s = {:?} period {}",
        p.param, p.section, p.period
    );
    let t = Instant::now();
    let mut o = ContinuationOptions::new(0.009, 0.0195);
    o.ds_max = 2e-3;
    let (pds, brs) = period_doubling_cascade(&family, &[0.2003, -0.1998], 0.009, 5, &o).unwrap();
    println!("cascade in {:.3} s", t.elapsed().as_secs_f64());
    for (i, pd) in pds.iter().enumerate() {
        println!(
            "  PD {}: period {} → {} at γ = {:.12} (bracket {:.1e})",
            i + 1,
            pd.period_strides,
            2 * pd.period_strides,
            pd.param,
            pd.param_bracket
        );
    }
    for br in &brs {
        println!(
            "  branch k={} points {} end {:?}",
            br.period_strides,
            br.points.len(),
            br.end
        );
        for p in br.points.iter().step_by((br.points.len() / 8).max(1)) {
            println!(
                "     γ={:.10} s={:?} it={} t={:?} |λ|max={:.4}",
                p.param,
                p.section,
                p.newton_iters,
                p.tangent,
                p.multipliers[0].modulus()
            );
        }
    }
    for i in 2..pds.len() {
        let r = (pds[i - 1].param - pds[i - 2].param) / (pds[i].param - pds[i - 1].param);
        println!("  ratio δ_{} = {r:.4}", i - 1);
    }
}

fn measure_400_point_continuation_and_orbit_diagram() {
    use pdw_limit::{orbit_diagram, ContinuationMethod, OrbitOptions, OrbitStart};
    let mut o = ContinuationOptions::new(0.001, 0.019);
    o.method = ContinuationMethod::Natural;
    o.direction = -1.0;
    o.ds_init = (0.009 - 0.001) / 178.0;
    o.ds_max = o.ds_init;
    o.max_points = 400;
    let t = Instant::now();
    let b = continue_branch(&family, &[0.2003, -0.1998], 0.009, 1, &o).unwrap();
    println!(
        "natural continuation: {} points in {:.3} s (end {:?})",
        b.points.len(),
        t.elapsed().as_secs_f64(),
        b.end
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let params: Vec<f64> = (0..1000)
        .map(|i| 0.014 + 0.005 * i as f64 / 999.0)
        .collect();
    let opts = OrbitOptions {
        transient: 400,
        record: 100,
        ..Default::default()
    };
    let t = Instant::now();
    let cols = orbit_diagram(
        &family,
        &params,
        &OrbitStart::FollowPrevious(vec![0.2371, -0.2319]),
        &opts,
        &pool,
    )
    .unwrap();
    let strides: usize = cols
        .iter()
        .map(|c| c.fall.map(|f| f.0 + 1).unwrap_or(500))
        .sum();
    println!(
        "orbit diagram 1000 slopes × 500 strides (dop853 1e-10, 2 threads): {:.3} s, {strides} strides, falls {}",
        t.elapsed().as_secs_f64(),
        cols.iter().filter(|c| c.fall.is_some()).count()
    );
}

fn main() {
    measure_simplest_branch_and_cascade();
    measure_400_point_continuation_and_orbit_diagram();
}
