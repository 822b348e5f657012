//! Round feet on random slopes (pdw-limit's `terrain`, "Round feet"): the stance foot rolls on
//! the last line, the swing foot lands on the next one tilted against it. Checked against the
//! point-foot walk in rotated frames, which is written independently of tilted lines: point
//! feet walk the same on tilted lines; round feet of a vanishing radius walk as point feet
//! (through the rolling-base dynamics, a separate code path); a tilt of zero is the ordinary
//! stride bit for bit; the walk does not depend on the thread count.

use pdw::mfpt;
use pdw_limit::terrain::{self, Fate, SlopeTerrain, SlopeWalk, TerrainKind};
use pdw_limit::{StrideMap, StrideOutcome};

const MEAN: f64 = 0.05235987755982988; // the compass preset's 3°

/// The compass preset with round feet of radius `r`.
pub fn compass_with_radius(r: f64) -> pdw::BuiltModel {
    let text = pdw_walkers::registry::preset_text("compass").unwrap();
    let round = text.replacen(
        "[parameters]",
        &format!("foot_radius = {r:?}\n\n[parameters]"),
        1,
    );
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("pdw-tilt-{}-{k}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("round.toml");
    std::fs::write(&path, round).unwrap();
    let m = pdw::build(path.to_str().unwrap(), &[]).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    m
}

fn slopes(sd: f64, seed: u64) -> SlopeTerrain {
    SlopeTerrain {
        mean: MEAN,
        sd,
        seed,
        kind: TerrainKind::Slope,
        dist: Default::default(),
    }
}

/// Every walker's post-heel-strike states (mean frame) and fate, stride by stride.
fn walk_states(
    walk: &SlopeWalk,
    t: &SlopeTerrain,
    x0: &[f64],
    walker: u64,
    steps: usize,
) -> (Vec<Vec<f64>>, Fate) {
    let mut integ = walk.integrator(x0.len()).unwrap();
    let (mut x, mut last, mut out) = (x0.to_vec(), t.mean, Vec::new());
    for k in 0..steps {
        let s = t.slope(walker, k as u64 + 1);
        let st = walk.stride_from(&mut integ, &x, last, s).unwrap();
        if !st.outcome.is_ok() {
            return (
                out,
                Fate {
                    steps: k,
                    end: Some(st.outcome),
                },
            );
        }
        x = st.post;
        out.push(x.clone());
        last = s;
    }
    (out, Fate { steps, end: None })
}

fn largest_difference(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(u, v)| u.iter().zip(v).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Walkers `0..walkers` by both walks: (fates that differ, the largest state difference over
/// the first `upto` strides both completed, falls of the first walk).
fn compare(
    (a, b): (&SlopeWalk, &SlopeWalk),
    t: &SlopeTerrain,
    x0: &[f64],
    walkers: u64,
    steps: usize,
    upto: usize,
) -> (usize, f64, usize) {
    let (mut differ, mut worst, mut falls) = (0, 0.0f64, 0);
    for i in 0..walkers {
        let (sa, fa) = walk_states(a, t, x0, i, steps);
        let (sb, fb) = walk_states(b, t, x0, i, steps);
        if fa != fb {
            differ += 1;
        }
        let k = sa.len().min(sb.len()).min(upto);
        worst = worst.max(largest_difference(&sa[..k], &sb[..k]));
        falls += usize::from(fa.end.is_some());
    }
    (differ, worst, falls)
}

/// The integrator options of the walks at tolerance `tol`.
fn at_tolerance(tol: f64) -> pdw_hybrid::Options {
    let mut o = mfpt::default_integrator();
    o.rtol = tol;
    o.atol = tol;
    o
}

#[test]
fn point_feet_walk_the_same_on_tilted_landing_lines_as_in_rotated_frames() {
    let m = compass_with_radius(0.0);
    let (x0, _) = mfpt::start(&m).unwrap();
    let at = mfpt::model_at(&m);
    let t = slopes(0.5f64.to_radians(), 5);
    let mut worst = Vec::new();
    for tol in [1e-10, 1e-12] {
        let rotated = SlopeWalk::new(&at, MEAN, at_tolerance(tol)).unwrap();
        let tilted = SlopeWalk::with_tilted_lines(&at, MEAN, at_tolerance(tol)).unwrap();
        assert!(!rotated.tilted() && tilted.tilted());
        let first = compare((&rotated, &tilted), &t, &x0, 200, 60, 1);
        let all = compare((&rotated, &tilted), &t, &x0, 200, 60, 60);
        println!(
            "point feet, tolerance {tol:e}: {} of 200 fates differ, largest state difference \
             {:e} after one stride, {:e} over every stride; {} falls",
            all.0, first.1, all.1, all.2
        );
        assert!(all.2 > 100, "the terrain makes walkers fall: {}", all.2);
        assert_eq!(all.0, 0, "the same fates");
        assert!(first.1 < 1e-12, "one stride: {:e}", first.1);
        worst.push(all.1);
    }
    // the same motion in two frames: what differs is integration error, which the tolerance
    // shrinks (the strides before a fall amplify it)
    assert!(worst[1] < worst[0] / 3.0 && worst[1] < 1e-8, "{worst:?}");
}

#[test]
fn round_feet_of_a_vanishing_radius_walk_random_slopes_as_point_feet() {
    let point = compass_with_radius(0.0);
    let (x0, _) = mfpt::start(&point).unwrap();
    let at_p = mfpt::model_at(&point);
    let rotated = SlopeWalk::new(&at_p, MEAN, at_tolerance(1e-12)).unwrap();
    let t = slopes(0.5f64.to_radians(), 6);
    let walkers = 100;
    let points: Vec<_> = (0..walkers)
        .map(|i| walk_states(&rotated, &t, &x0, i, 60))
        .collect();
    // every walker from the point-foot gait: the distance to the point-foot walk stride by
    // stride over the first 10 strides, per unit radius
    let mut per_radius = Vec::new();
    for r in [1e-6, 1e-7, 1e-9] {
        let round = compass_with_radius(r);
        let at_r = mfpt::model_at(&round);
        let rolled = SlopeWalk::new(&at_r, MEAN, at_tolerance(1e-12)).unwrap();
        assert!(
            rolled.tilted(),
            "round feet walk random slopes on tilted lines"
        );
        let mut scaled = Vec::new();
        let mut differ = 0;
        for (i, (sp, fp)) in points.iter().enumerate() {
            let (sr, fr) = walk_states(&rolled, &t, &x0, i as u64, 60);
            differ += usize::from(fr != *fp);
            for k in 0..sp.len().min(sr.len()).min(10) {
                let d = largest_difference(&sp[k..k + 1], &sr[k..k + 1]);
                scaled.push(d / r);
            }
        }
        println!(
            "r = {r:e}: {differ} of {walkers} fates differ from point feet; first stride {:.6} r",
            scaled[0]
        );
        if r == 1e-9 {
            // the walkers that wander longest near the edge amplify a difference by 10⁵ in
            // 20 strides (walker 40: 25 steps on point feet, 20 at r = 1e-6, 26 at 1e-7):
            // by r = 1e-9 every fate is the point feet's
            assert_eq!(differ, 0, "r = {r:e}");
        } else {
            per_radius.push(scaled);
        }
    }
    // first order in r with the same coefficient at every stride of every walker: the walk
    // tends to the point-foot walk as r → 0
    let worst = per_radius[0]
        .iter()
        .zip(&per_radius[1])
        .map(|(a, b)| (a - b).abs() / b.max(1e-3))
        .fold(0.0, f64::max);
    println!("largest relative change of the first-order coefficient: {worst:e}");
    assert!(worst < 0.05, "{worst}");
}

#[test]
fn round_feet_on_slopes_a_tilt_of_zero_is_the_ordinary_stride_and_threads_do_not_matter() {
    let m = compass_with_radius(0.1);
    assert!(mfpt::tilted(&m));
    assert!(mfpt::check_model_for(&m, TerrainKind::Slope).is_ok());
    let e = mfpt::check_chain_terrain(&m, TerrainKind::Slope, "--chain").unwrap_err();
    assert!(
        e.0.contains("--chain") && e.0.contains("foot_radius"),
        "{}",
        e.0
    );
    assert!(mfpt::check_chain_terrain(&m, TerrainKind::StepDown, "--chain").is_ok());
    let (x0, s0) = mfpt::start(&m).unwrap();
    let at = mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, MEAN, mfpt::default_integrator()).unwrap();
    // a stride of one slope is refused, naming why
    let mut integ = walk.integrator(x0.len()).unwrap();
    let e = walk.stride(&mut integ, &x0, MEAN).unwrap_err().to_string();
    assert!(e.contains("last line"), "{e}");
    // last = next = the mean: the ordinary stride map, bit for bit
    let map = StrideMap::new(m.walker.as_ref(), mfpt::default_integrator()).unwrap();
    let plain = map.stride(&s0).unwrap();
    let st = walk.stride_from(&mut integ, &x0, MEAN, MEAN).unwrap();
    assert_eq!(st.outcome, StrideOutcome::Ok);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&st.post), bits(&plain.post_event));
    // one and two threads, in walker order
    let t = slopes(0.5f64.to_radians(), 7);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        terrain::monte_carlo(&walk, &t, &x0, 64, 200, &pool, &|_| {}).unwrap()
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two);
    assert!(one.iter().filter(|f| f.end.is_some()).count() > 32);
}

/// The single disturbance (one steeper or shallower line, then nominal ground) walks round feet
/// on tilted lines too: as the radius vanishes the largest disturbance survived is the point
/// feet's, and with r = 0.1 it is another (the feet change the answer).
#[test]
fn round_feet_of_a_vanishing_radius_survive_the_point_feets_largest_disturbance() {
    let integ = mfpt::default_integrator();
    let tol = 1e-5;
    let edge = |r: f64, sign: f64| {
        pdw::disturb::largest(
            &compass_with_radius(r),
            TerrainKind::Slope,
            sign,
            tol,
            0.3,
            100,
            integ,
        )
        .unwrap()
    };
    for sign in [1.0, -1.0] {
        let point = edge(0.0, sign);
        let tiny = edge(1e-7, sign);
        let round = edge(0.1, sign);
        println!("sign {sign}: point {point:?}, r = 1e-7 {tiny:?}, r = 0.1 {round:?}");
        assert!((point.0 - tiny.0).abs() <= tol, "{point:?} vs {tiny:?}");
        assert!(
            (point.0 - round.0).abs() > 10.0 * tol,
            "{point:?} vs {round:?}"
        );
    }
}
