//! Presets and random states shared by the chain-walker tests (the merged binary and the
//! allocation test).

use pdw_hybrid::{HybridSystem, Section};
use pdw_walkers::{presets, ChainWalker};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Every chain-walker preset, and seed5 with its free swing knee.
pub fn all_presets() -> Vec<(&'static str, ChainWalker)> {
    vec![
        ("compass", presets::compass(&[]).unwrap()),
        ("kneed", presets::kneed(&[]).unwrap()),
        ("seed5", presets::seed5(&[]).unwrap()),
        (
            "seed5 free knee",
            presets::seed5(&[("free_swing_knee", 1.0)]).unwrap(),
        ),
    ]
}

/// A state near the gait: section state lifted, perturbed, with a bent free knee in mode 0.
pub fn random_state(w: &ChainWalker, r: &mut ChaCha8Rng, mode: usize) -> Vec<f64> {
    let mut x = vec![0.0; w.dim()];
    // a section with the swing knee's rate starts it at 0 (the knee's stop held)
    let mut s = vec![0.0; w.section_dim()];
    s[..3].copy_from_slice(&[0.2, -1.0, 0.5]);
    w.lift(&s, &mut x);
    for v in x.iter_mut() {
        *v += r.random_range(-0.3..0.3);
    }
    let n = w.dim() / 2;
    for (k, v) in x.iter_mut().enumerate().take(n) {
        if w.locked_joints(mode).contains(&k) {
            *v = 0.0;
            // locked joints carry no rate either
        }
    }
    for &k in w.locked_joints(mode) {
        x[n + k] = 0.0;
    }
    if let (Some(k), 0) = (w.free_knee(), mode) {
        x[k] = -r.random_range(0.05..0.6);
    }
    x
}
