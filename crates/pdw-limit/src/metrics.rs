//! Gait metrics of a stride: period `T`, step length `L` (model-provided, from the pre-impact
//! state) and average progression speed `v = L / T` along the slope.

use crate::stride::Stride;

/// Period, step length and speed of one stride (model units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitMetrics {
    /// Stride duration.
    pub period: f64,
    /// Distance between the feet at the section event, if the model provides it.
    pub step_length: Option<f64>,
    /// `step_length / period`.
    pub speed: Option<f64>,
}

impl GaitMetrics {
    /// Metrics of a completed stride.
    pub fn from_stride(st: &Stride) -> Self {
        Self {
            period: st.period,
            step_length: st.step_length,
            speed: st.step_length.map(|l| l / st.period),
        }
    }
}
