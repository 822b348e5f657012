//! Validity located on the dense solution (`pdw_limit::validity`): minima between accepted
//! steps, the clearance rule per model, impact margins, margins on a natural scale.

use pdw_hybrid::{GuardKind, GuardSpec, HybridSystem, Options, Scratch, Section};
use pdw_limit::trajectory::{self, TrajectoryOptions};
use pdw_limit::{find_fixed_point, FixedPoint, NewtonOptions, StrideMap, Validity};
use pdw_walkers::{
    ChainWalker, ClearanceRule, ConstraintForces, GaitGuess, ImpactReport, Pose, Scales, StepFlags,
    Walker, WalkerSpec,
};

fn fixed_point(w: &dyn Walker, guess: &[f64]) -> Option<FixedPoint> {
    let map = StrideMap::new(w, Options::dop853(1e-14)).unwrap();
    let opts = NewtonOptions {
        tol: 1e-12,
        ..NewtonOptions::default()
    };
    find_fixed_point(&map, guess, &opts).ok()
}

fn spec_walker(file: &str) -> ChainWalker {
    let path = format!("{}/../models/{file}", env!("CARGO_MANIFEST_DIR"));
    ChainWalker::from_spec(WalkerSpec::from_file(std::path::Path::new(&path)).unwrap()).unwrap()
}

/// The state after heel strike at the model's first gait guess.
fn guess_state(w: &dyn Walker) -> Vec<f64> {
    let g = w.gait_guesses().into_iter().next().unwrap();
    let mut x = vec![0.0; w.dim()];
    w.lift(&g.section, &mut x);
    x
}

/// A chain walker whose impact guards fire as resets even where its impact model says a
/// stance knee buckles (the terminal twin guards `*_buckles` are never admissible): the stride
/// of a design whose knee strike buckles (seed5_walking, kneed) can then be followed through
/// its swing, to check the swing on its own. Without such guards it is the walker itself.
struct ThroughBuckling<'a>(&'a ChainWalker);

impl ThroughBuckling<'_> {
    fn twin(&self, mode: usize) -> Option<usize> {
        self.0
            .guards(mode)
            .iter()
            .position(|g| matches!(g.kind, GuardKind::Terminal(_)) && g.name.ends_with("_buckles"))
    }
}

pdw_hybrid::integrate_through_dyn!(ThroughBuckling<'_>);
impl HybridSystem for ThroughBuckling<'_> {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn error_dim(&self) -> usize {
        self.0.error_dim()
    }
    fn n_modes(&self) -> usize {
        self.0.n_modes()
    }
    fn guards(&self, mode: usize) -> &[GuardSpec] {
        self.0.guards(mode)
    }
    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        self.0.flow(ws, mode, x, dx)
    }
    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        self.0.guard(ws, mode, k, x)
    }
    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        self.0.guards_with_rates(ws, mode, x, f, g, rate)
    }
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        self.0.guard_is_linear(mode, k)
    }
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        match self.twin(mode) {
            Some(t) if k == t => false,
            Some(t) if k == 0 => self.0.admissible(mode, 0, x) || self.0.admissible(mode, t, x),
            _ => self.0.admissible(mode, k, x),
        }
    }
    fn guard_tolerance(&self, mode: usize, k: usize) -> f64 {
        self.0.guard_tolerance(mode, k)
    }
    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        self.0.reset(ws, mode, k, x, out)
    }
    fn flow_jacobian(&self, ws: &mut Scratch, mode: usize, x: &[f64], jac: &mut [f64]) {
        self.0.flow_jacobian(ws, mode, x, jac)
    }
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        self.0.guard_gradient(ws, mode, k, x, grad)
    }
    fn reset_jacobian(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], jac: &mut [f64]) {
        self.0.reset_jacobian(ws, mode, k, x, jac)
    }
}

impl Section for ThroughBuckling<'_> {
    fn section_dim(&self) -> usize {
        self.0.section_dim()
    }
    fn section_names(&self) -> &[&'static str] {
        self.0.section_names()
    }
    fn section_mode(&self) -> usize {
        self.0.section_mode()
    }
    fn section_guard(&self) -> (usize, usize) {
        self.0.section_guard()
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        self.0.lift(s, x)
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        self.0.project(x, s)
    }
    fn max_stride_time(&self) -> f64 {
        self.0.max_stride_time()
    }
}

impl Walker for ThroughBuckling<'_> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn state_names(&self) -> Vec<String> {
        self.0.state_names()
    }
    fn param_values(&self) -> Vec<(String, f64)> {
        self.0.param_values()
    }
    fn step_length(&self, x_pre: &[f64]) -> f64 {
        self.0.step_length(x_pre)
    }
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        self.0.gait_guesses()
    }
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        self.0.pose(x)
    }
    fn constraint_forces(&self, mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        self.0.constraint_forces(mode, x)
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        self.0.step_flags(mode, x)
    }
    fn energy(&self, x: &[f64]) -> Option<f64> {
        self.0.energy(x)
    }
    fn impact_report(&self, mode: usize, guard: usize, x: &[f64]) -> Option<ImpactReport> {
        self.0.impact_report(mode, guard, x)
    }
    fn scales(&self) -> Option<Scales> {
        self.0.scales()
    }
    fn swing_clearance(&self, mode: usize, x: &[f64]) -> Option<f64> {
        self.0.swing_clearance(mode, x)
    }
    fn clearance_rule(&self) -> ClearanceRule {
        self.0.clearance_rule()
    }
}

/// A scalar criterion at `(mode, x)`.
type Criterion<'a> = &'a dyn Fn(usize, &[f64]) -> Option<f64>;

/// The smallest value of `f` at the samples of one stride of `w` from `x0` within `window`.
fn sampled_min(
    w: &dyn Walker,
    x0: &[f64],
    dt_out: Option<f64>,
    window: (f64, f64),
    f: Criterion,
) -> f64 {
    let opts = TrajectoryOptions {
        dt_out,
        ..TrajectoryOptions::new(1)
    };
    let tr = trajectory::simulate(w, x0, &opts).unwrap();
    (0..tr.len())
        .filter(|&i| tr.step[i] == 0 && tr.t[i] > window.0 && tr.t[i] < window.1)
        .filter_map(|i| f(tr.mode[i] as usize, tr.state(i)))
        .fold(f64::INFINITY, f64::min)
}

/// The kneed walker's mid-swing clearance dip and its stance knee's smallest lock torque fall
/// between accepted DOP853 steps: located on the dense solution, both agree to 1e-9 (of l and
/// of m g l) with a sampling every 1e-5 s, while the accepted steps alone miss them by more.
#[test]
fn minima_between_accepted_steps_agree_with_fine_sampling() {
    let c = spec_walker("kneed.toml");
    let w = ThroughBuckling(&c);
    let g = w.gait_guesses().into_iter().next().unwrap();
    let x0 = fixed_point(&w, &g.section).map_or_else(|| guess_state(&w), |f| f.state);
    let v = Validity::along_step(&w, &x0).unwrap();
    assert!(v.continuous && v.evaluations > v.samples);
    let s = w.scales().unwrap();
    let clearance = |m: usize, x: &[f64]| w.swing_clearance(m, x);
    let knee = |m: usize, x: &[f64]| w.constraint_forces(m, x).and_then(|f| f.knee_torque[0]);
    let knee_margin = v.margin("stance_knee_torque").unwrap();
    let cases: [(Criterion, f64, f64, f64); 2] = [
        (
            &clearance,
            v.min_clearance.unwrap(),
            v.t_min_clearance,
            s.length,
        ),
        (&knee, knee_margin.raw, knee_margin.t, s.torque()),
    ];
    for (f, located, t, scale) in cases {
        // a window around the minimum (the clearance is 0 at the swing's ends)
        let window = (t - 0.05, t + 0.05);
        let fine = sampled_min(&w, &x0, Some(1e-5), window, f);
        let steps = sampled_min(&w, &x0, None, window, f);
        assert!(
            (located - fine).abs() <= 1e-9 * scale,
            "located {located}, fine sampling {fine}"
        );
        assert!(
            steps - located > 1e-9 * scale,
            "accepted steps {steps} do not miss the minimum {located}"
        );
    }
}

/// seed5_walking (issue: "validity sampled at accepted steps") has its straight swing foot
/// below the slope before mid-stance: 12.5 mm from t = 0.416 s to 0.595 s of its stride. With
/// knees, the whole swing is checked: flagged, with that depth and interval, and it binds.
#[test]
fn seed5_walking_swing_foot_below_the_slope_is_flagged() {
    let c = spec_walker("seed5_walking.toml");
    let w = ThroughBuckling(&c);
    let g = w.gait_guesses().into_iter().next().unwrap();
    let fp = fixed_point(&w, &g.section).expect("the stride through the knee strike repeats");
    let v = Validity::along_step(&w, &fp.state).unwrap();
    assert_eq!(v.clearance_rule, Some(ClearanceRule::WholeSwing));
    assert!(v.swing_foot_scuffs && !v.valid(), "{v:?}");
    let m = v.min_clearance.unwrap();
    assert!((m + 0.0125).abs() < 5e-4, "deepest {m} m");
    assert_eq!(v.scuff_depth, -m);
    let scuffs: Vec<_> = v
        .violations
        .iter()
        .filter(|x| x.criterion == "swing_clearance")
        .collect();
    assert_eq!(scuffs.len(), 1, "{scuffs:?}");
    assert!((scuffs[0].t_start - 0.416).abs() < 5e-3, "{scuffs:?}");
    assert!((scuffs[0].t_end - 0.595).abs() < 5e-3, "{scuffs:?}");
    assert_eq!(scuffs[0].worst, m);
    assert_eq!(v.scuff_intervals, [(scuffs[0].t_start, scuffs[0].t_end)]);
    // the located ends are roots of the clearance
    assert!(v.t_min_clearance > scuffs[0].t_start && v.t_min_clearance < scuffs[0].t_end);
    let b = v.binding().unwrap();
    assert!(b.relative < 0.0, "{b:?}");
    // impacts: where the model reports them, every entry with a negative margin is a violation
    for i in v.impacts.iter().filter_map(|i| i.report.as_ref()) {
        for e in &i.entries {
            if e.margin().is_some_and(|m| m < 0.0) {
                let name = format!("{}:{}", i.event, e.name);
                assert!(v.impact_violation);
                assert!(v.violations.iter().any(|x| x.criterion == name), "{name}");
            }
        }
    }
}

/// The simplest walker's straight swing leg passes through the slope at mid-stance; its
/// convention (Garcia et al. 1998) ignores that scuff, which is reported: 6.4e-5 l at γ = 0.009,
/// ending exactly at mid-stance (the legs coincide, the foot is on the slope). The gait is valid
/// and its heel strike's impulses push (the trailing foot separates).
#[test]
fn simplest_keeps_the_mid_stance_convention_and_reports_the_scuff() {
    let w = pdw_walkers::build("simplest", &[]).unwrap();
    let g = w.gait_guesses().into_iter().next().unwrap();
    let fp = fixed_point(w.as_ref(), &g.section).unwrap();
    let v = Validity::along_step(w.as_ref(), &fp.state).unwrap();
    assert!(v.valid(), "{v:?}");
    assert_eq!(v.clearance_rule, Some(ClearanceRule::AfterMidStance));
    assert!(!v.swing_foot_scuffs);
    assert!((v.scuff_depth - 6.384e-5).abs() < 1e-8, "{}", v.scuff_depth);
    let tm = v.t_mid_stance.unwrap();
    assert_eq!(v.scuff_intervals.len(), 1);
    let (a, b) = v.scuff_intervals[0];
    assert!(a > 0.0 && a < tm && (b - tm).abs() < 1e-9, "{a} {b} {tm}");
    // the normal force is smallest at the heel strike (both sides of the event are checked)
    assert!((v.min_normal_force - 0.912_461_215).abs() < 1e-8);
    let imp = v.impacts[0].report.as_ref().unwrap();
    let (m, _) = imp.min_margin().unwrap();
    assert!(m > 0.0 && !v.impact_violation);
    // |Λ_t / Λ_n| = |tan θ⁻| at the heel strike: the stance friction need at the same instant
    assert!((imp.friction_required - v.max_friction_required).abs() < 1e-9);
    // the model's own units: relative margins are the raw numbers
    for m in &v.margins {
        assert_eq!(m.relative, m.raw, "{m:?}");
    }
}

/// Every margin is its raw value over the natural scale its name says (compass: m = 20 kg,
/// l = 1 m, g = 9.81), and the binding criterion is the smallest.
#[test]
fn relative_margins_are_raw_over_their_scales() {
    let w = pdw_walkers::build("compass", &[]).unwrap();
    let g = w.gait_guesses().into_iter().next().unwrap();
    let fp = fixed_point(w.as_ref(), &g.section).unwrap();
    let v = Validity::along_step(w.as_ref(), &fp.state).unwrap();
    let s = v.scales.unwrap();
    assert!(!v.margins.is_empty());
    for m in &v.margins {
        let scale = match m.scale_name {
            "m g" => s.force(),
            "m g l" => s.torque(),
            "l" => s.length,
            "m sqrt(g l)" => s.impulse(),
            "m l sqrt(g l)" => s.angular_impulse(),
            "sqrt(g l)" => s.speed(),
            "sqrt(g/l)" => s.rate(),
            o => panic!("unknown scale {o}"),
        };
        assert_eq!(m.scale, scale, "{m:?}");
        assert_eq!(m.relative, m.raw / scale, "{m:?}");
    }
    let nf = v.margin("normal_force").unwrap();
    assert_eq!(nf.raw, v.min_normal_force);
    assert!((nf.relative - v.min_normal_force / (20.0 * 9.81)).abs() < 1e-15);
    let b = v.binding().unwrap();
    assert!(v.margins.iter().all(|m| m.relative >= b.relative));
    assert_eq!(v.min_relative_margin(), Some(b.relative));
}

/// The heel strike's mode change inside the stride map: seed5_walking with stops, followed
/// through its knee-strike buckle ([`ThroughBuckling`]), releases its trailing knee at heel
/// strike (its stop would pull) and the new swing knee starts flexing; the section's fourth
/// coordinate `swing_knee_rate` carries that rate. The stride map's exact Jacobian (variational
/// equations through the released impact's exact Jacobian) agrees with Richardson differences
/// of the stride map to 1e-7 of its largest entry, and the released rate agrees with the one the
/// independent reference model gives at the gait's heel strike (−1.80 rad/s) to 0.1 rad/s.
#[test]
fn released_trailing_knee_keeps_the_stride_map_jacobian_exact() {
    let c = spec_walker("seed5_walking.toml");
    let w = ThroughBuckling(&c);
    assert_eq!(
        w.section_names(),
        &["stance", "stance_rate", "hip_rate", "swing_knee_rate"]
    );
    let map = StrideMap::new(&w as &dyn Walker, Options::dop853(1e-13)).unwrap();
    let mut s = c.gait_guesses().into_iter().next().unwrap().section;
    assert_eq!(s.len(), 4);
    s = map.apply(&s).unwrap();
    assert!(
        (s[3] + 1.80).abs() < 0.1,
        "one stride from the old gait: the trailing knee is released, swing_knee_rate {}",
        s[3]
    );
    let (_, dp) = pdw_limit::dp_variational(&map, &s).unwrap();
    let fd =
        pdw_limit::richardson_jacobian(|a, b| b.copy_from_slice(&map.apply(a).unwrap()), &s, 4);
    let scale = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let err = dp
        .iter()
        .zip(&fd)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!("stride map with a released trailing knee at {s:?}: |DP − Richardson| = {err:.2e} (max |DP| {scale:.3})");
    assert!(
        err <= 1e-7 * scale,
        "variational {dp:?} vs Richardson {fd:?}: {err:e}"
    );
    // the fourth column is alive: the knee's rate at the start changes the stride
    assert!((0..4).any(|i| dp[i * 4 + 3].abs() > 1e-6), "{dp:?}");
}
