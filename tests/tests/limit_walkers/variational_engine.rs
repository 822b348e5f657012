//! The variational stride as the engine runs it: the wrapper's guard rates and the model's
//! one-pass flow-and-Jacobian change its cost, never its bits; nor does the scalar
//! integrator's register loop change the bits of a plain stride.

use pdw_hybrid::{GuardSpec, HybridSystem, Options, Scratch, Section};
use pdw_limit::{richardson_jacobian, StrideMap, Variational};
use pdw_walkers::simplest::{GarciaGait, Simplest, SimplestParams};

fn walker(gamma: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap()
}

/// A system that hides the guard rates of the one it wraps (the trait's default: every step is
/// sampled on the state's interpolant) and computes flow and Jacobian by the two separate
/// calls. It keeps the affine declarations: they choose how a located root is refined (Newton
/// on the guard's polynomial, or Illinois on states), which changes the last bits of an event.
struct Plain<'a, S: ?Sized>(&'a S);

impl<S: HybridSystem + ?Sized> pdw_hybrid::IntegrateConcrete for Plain<'_, S> {
    fn integrate_concrete(
        &self,
        integ: &mut pdw_hybrid::Integrator,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        obs: Option<&mut dyn FnMut(f64, &[f64]) -> bool>,
    ) -> pdw_hybrid::StopReason {
        integ.run_dyn(self, mode, t, x, t_end, resume, obs)
    }
}

impl<S: HybridSystem + ?Sized> HybridSystem for Plain<'_, S> {
    fn dim(&self) -> usize {
        self.0.dim()
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
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        self.0.admissible(mode, k, x)
    }
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        self.0.guard_is_linear(mode, k)
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
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], g: &mut [f64]) {
        self.0.guard_gradient(ws, mode, k, x, g)
    }
    fn reset_jacobian(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], j: &mut [f64]) {
        self.0.reset_jacobian(ws, mode, k, x, j)
    }
}

#[test]
fn one_pass_flow_and_jacobian_equal_the_two_calls_bit_for_bit() {
    let m = walker(0.009);
    let mut ws = Scratch::new();
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut uniform = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..1000 {
        let x: Vec<f64> = (0..4).map(|_| 2.0 * uniform() - 1.0).collect();
        let (mut f1, mut j1) = ([0.0; 4], [0.0; 16]);
        let (mut f2, mut j2) = ([0.0; 4], [0.0; 16]);
        m.flow_with_jacobian(&mut ws, 0, &x, &mut f1, &mut j1);
        m.flow(&mut ws, 0, &x, &mut f2);
        m.flow_jacobian(&mut ws, 0, &x, &mut j2);
        assert_eq!(f1.map(f64::to_bits), f2.map(f64::to_bits), "at {x:?}");
        assert_eq!(j1.map(f64::to_bits), j2.map(f64::to_bits), "at {x:?}");
    }
}

/// A whole variational stride (state, tangent block, event time) from the Garcia guess: on the
/// model itself (the wrapper forwards its exact guard rates, so most steps skip sampling, and
/// flow and Jacobian come from one pass) and on the model behind [`Plain`] (no rates, two
/// calls): the same bits, for DOP853 at two tolerances and DOPRI5.
#[test]
fn variational_stride_with_guard_rates_equals_the_one_without_bit_for_bit() {
    let m = walker(0.009);
    let (sm, sg) = m.section_guard();
    let s = GarciaGait::LongPeriod.section_guess(0.009);
    for opts in [
        Options::dop853(1e-14),
        Options::dop853(1e-9),
        Options::dopri5(1e-10),
    ] {
        let map = StrideMap::new(&m, opts).unwrap();
        let mut z0 = map.lift(&s);
        z0.extend_from_slice(&richardson_jacobian(|a, b| m.lift(a, b), &s, 4));
        let fast = Variational::new(&m, 2).poincare_at(sm, sg);
        let hidden = Plain(&m);
        let slow = Variational::new(&hidden, 2).poincare_at(sm, sg);
        let a = pdw_hybrid::run_scalar(&fast, &map.driver(), &z0, &opts).unwrap();
        let b = pdw_hybrid::run_scalar(&slow, &map.driver(), &z0, &opts).unwrap();
        assert!(a.outcome.is_ok(), "{:?}", a.outcome);
        assert_eq!(a.t.to_bits(), b.t.to_bits(), "{opts:?}");
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.post), bits(&b.post), "{opts:?}");
        assert_eq!(bits(&a.pre), bits(&b.pre), "{opts:?}");
    }
}

/// The simplest walker at γ = 0.009 and 0.016 and the chain-walker presets (compass, kneed,
/// seed5), each with the section state of its first gait guess.
fn gait_walkers() -> Vec<(String, Box<dyn pdw_walkers::Walker>, Vec<f64>)> {
    let mut walkers: Vec<(String, Box<dyn pdw_walkers::Walker>, Vec<f64>)> = Vec::new();
    for gamma in [0.009, 0.016] {
        let s = GarciaGait::LongPeriod.section_guess(gamma);
        walkers.push((
            format!("simplest {gamma}"),
            Box::new(walker(gamma)),
            s.to_vec(),
        ));
    }
    for name in ["compass", "kneed", "seed5"] {
        let w = pdw_walkers::build(name, &[]).unwrap();
        let s = w.gait_guesses()[0].section.clone();
        walkers.push((name.to_string(), w, s));
    }
    walkers
}

/// With the step-size control on the state alone ([`ErrorControl::State`]), the variational
/// stride takes the plain stride's steps, events and resets: its stride (image, period, pre-
/// and post-event states, step length, events) is [`StrideMap::stride`]'s bit for bit, for the
/// simplest walker and the chain-walker presets (compass, kneed with its knee strike, seed5),
/// DOP853 at two tolerances and DOPRI5. With full control the steps differ, so the image
/// differs in the last digits (here only checked to be close: the control matters).
#[test]
fn state_controlled_variational_stride_is_the_plain_stride_bit_for_bit() {
    use pdw_limit::{dp_variational_with, ErrorControl};
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let walkers = gait_walkers();
    let mut full_differs = 0;
    for (name, w, s) in &walkers {
        for opts in [
            Options::dop853(1e-14),
            Options::dop853(1e-9),
            Options::dopri5(1e-10),
        ] {
            let map: StrideMap<'_> = StrideMap::new(w.as_ref(), opts).unwrap();
            let plain = map.stride(s).unwrap();
            assert!(
                plain.outcome.is_ok(),
                "{name} {opts:?}: {:?}",
                plain.outcome
            );
            let (var, dp) = dp_variational_with(&map, s, ErrorControl::State).unwrap();
            let what = format!("{name} {opts:?}");
            assert_eq!(var.outcome, plain.outcome, "{what}");
            assert_eq!(bits(&var.next), bits(&plain.next), "{what}");
            assert_eq!(var.period.to_bits(), plain.period.to_bits(), "{what}");
            assert_eq!(bits(&var.pre_event), bits(&plain.pre_event), "{what}");
            assert_eq!(bits(&var.post_event), bits(&plain.post_event), "{what}");
            assert_eq!(var.events, plain.events, "{what}");
            assert!(dp.iter().all(|v| v.is_finite()), "{what}");
            let (full, _) = dp_variational_with(&map, s, ErrorControl::Full).unwrap();
            let gap = full
                .next
                .iter()
                .zip(&plain.next)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                gap <= 1e3 * opts.rtol,
                "{what}: full control off by {gap:.2e}"
            );
            if gap > 0.0 {
                full_differs += 1;
            }
        }
    }
    assert!(full_differs > 0, "full control never changed a step");
}

/// The scalar integrator's register loop and its general step loop give every walker the same
/// stride bit for bit (image, period, pre- and post-event states, events) and the same work
/// counters: simplest at γ = 0.009 and 0.016, compass, kneed (knee strike), seed5; DOP853 at
/// 1e-14 and 1e-9, DOPRI5 at 1e-10 and 1e-6.
#[test]
fn register_loop_stride_is_the_general_loop_stride_bit_for_bit() {
    use pdw_hybrid::Integrator;
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let walkers = gait_walkers();
    for (name, w, s) in &walkers {
        for opts in [
            Options::dop853(1e-14),
            Options::dop853(1e-9),
            Options::dopri5(1e-10),
            Options::dopri5(1e-6),
        ] {
            let map: StrideMap<'_> = StrideMap::new(w.as_ref(), opts).unwrap();
            let d = w.dim();
            let (mut fast, mut general) = (
                Integrator::new(d, opts).unwrap(),
                Integrator::new(d, opts).unwrap(),
            );
            general.set_register_loop(false);
            let a = map.stride_with(&mut fast, s).unwrap();
            let b = map.stride_with(&mut general, s).unwrap();
            let what = format!("{name} {opts:?}");
            assert!(a.outcome.is_ok(), "{what}: {:?}", a.outcome);
            assert_eq!(a.outcome, b.outcome, "{what}");
            assert_eq!(bits(&a.next), bits(&b.next), "{what}");
            assert_eq!(a.period.to_bits(), b.period.to_bits(), "{what}");
            assert_eq!(bits(&a.pre_event), bits(&b.pre_event), "{what}");
            assert_eq!(bits(&a.post_event), bits(&b.post_event), "{what}");
            assert_eq!(a.events, b.events, "{what}");
            assert_eq!(fast.stats(), general.stats(), "{what}");
            assert!(fast.stats().accepted > 5, "{what}");
        }
    }
}
