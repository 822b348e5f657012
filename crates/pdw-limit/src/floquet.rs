//! Floquet multipliers of a period-one gait: the eigenvalues of the reduced stride-map Jacobian
//! `DP(s*)` (d_s × d_s, section coordinates), sorted by decreasing modulus. The gait is
//! asymptotically stable iff every multiplier lies strictly inside the unit circle.

use crate::error::LimitError;
use faer::Mat;

/// One Floquet multiplier `re + i·im`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Multiplier {
    pub re: f64,
    pub im: f64,
}

impl Multiplier {
    /// |λ|.
    pub fn modulus(&self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// Eigenvalues of the row-major `n × n` matrix `dp`, sorted by decreasing modulus; a conjugate pair
/// lists its `+im` member first.
pub fn multipliers(dp: &[f64], n: usize) -> Result<Vec<Multiplier>, LimitError> {
    assert_eq!(dp.len(), n * n, "dp must be n × n");
    let mut out: Vec<Multiplier> = if n == 1 {
        vec![Multiplier { re: dp[0], im: 0.0 }]
    } else {
        let a = Mat::<f64>::from_fn(n, n, |i, j| dp[i * n + j]);
        a.eigenvalues()
            .map_err(|_| LimitError::Eigen)?
            .into_iter()
            .map(|z| Multiplier { re: z.re, im: z.im })
            .collect()
    };
    if out.iter().any(|m| !(m.re.is_finite() && m.im.is_finite())) {
        return Err(LimitError::Eigen);
    }
    out.sort_by(|a, b| b.modulus().total_cmp(&a.modulus()));
    // A conjugate pair has equal moduli up to rounding: list the `+im` member first.
    for i in 1..out.len() {
        let (a, b) = (out[i - 1], out[i]);
        let scale = a.modulus().max(f64::MIN_POSITIVE);
        if a.im < 0.0
            && (a.re - b.re).abs() <= 1e-12 * scale
            && (a.im + b.im).abs() <= 1e-12 * scale
        {
            out.swap(i - 1, i);
        }
    }
    Ok(out)
}

/// Stable iff all |λ| < 1.
pub fn is_stable(m: &[Multiplier]) -> bool {
    m.iter().all(|l| l.modulus() < 1.0)
}
