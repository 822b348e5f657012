//! The Poincaré section just after heel strike (chain walker docs, "Section"): its coordinates,
//! lift and projection.

use super::ChainWalker;
use crate::spec::Resolved;
use pdw_hybrid::Section;

const SECTION_NAMES: [&str; 4] = ["stance", "stance_rate", "hip_rate", "swing_knee_rate"];

/// The section coordinates of a chain walker resolved as `r`: `(stance, stance_rate,
/// hip_rate)`, and `swing_knee_rate` when the swing knee is free and held by a stop or by a
/// latch with a `latch_impulse` while its leg is the stance leg — it may release at heel
/// strike, and the new swing knee then starts flexing (chain walker docs, "Section", "Latches").
pub fn section_names_of(r: &Resolved) -> &'static [&'static str] {
    let releases = r
        .free_swing
        .iter()
        .zip(r.latched.iter().zip(&r.latch_impulse))
        .any(|(free, (latched, limit))| *free && (!*latched || limit.is_some()));
    if releases {
        &SECTION_NAMES
    } else {
        &SECTION_NAMES[..3]
    }
}

impl Section for ChainWalker {
    fn section_dim(&self) -> usize {
        section_names_of(&self.r).len()
    }
    fn section_names(&self) -> &[&'static str] {
        section_names_of(&self.r)
    }
    fn section_mode(&self) -> usize {
        0
    }
    fn section_guard(&self) -> (usize, usize) {
        (self.locked_mode(), 0)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        let (m, n) = (self.m, self.n);
        x[..2 * n].fill(0.0);
        x[0] = s[0];
        x[m] = if self.r.step_down == 0.0 {
            -2.0 * s[0]
        } else {
            self.trailing_leg_angle(s[0]) - s[0]
        };
        x[n] = s[1];
        x[n + m] = s[2];
        if let (Some(fk), Some(_)) = (self.free_knee, self.trailing_free) {
            x[n + fk] = s[3];
        }
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[0];
        s[1] = x[self.n];
        s[2] = x[self.n + self.m];
        if let (Some(fk), Some(_)) = (self.free_knee, self.trailing_free) {
            s[3] = x[self.n + fk];
        }
    }
    fn max_stride_time(&self) -> f64 {
        self.r.max_stride_time
    }
}
