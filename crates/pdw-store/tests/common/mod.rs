//! Shared fixtures: a scratch directory per test and a deterministic synthetic basin.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use pdw_store::{Attractor, BasinHeader, BasinMetrics, BasinWriter, OrbitCheck, ShardSpec};

/// A fresh empty directory under the system temp dir, unique per process and test; removed
/// when the test passes, kept for inspection when it fails.
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

pub fn scratch(test: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("pdw-store-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            if n == 1 {
                a
            } else {
                a + (b - a) * i as f64 / (n - 1) as f64
            }
        })
        .collect()
}

pub const LEGEND: [(u8, &str); 6] = [
    (0, "gait"),
    (1, "other"),
    (2, "fall_forward"),
    (3, "fall_backward"),
    (4, "timeout"),
    (5, "nonfinite"),
];

pub fn header(nx: usize, ny: usize) -> BasinHeader {
    BasinHeader {
        command: "pdw-sweep basin --grid test".into(),
        model: "simplest".into(),
        slope: 0.009,
        params: r#"{"gamma":0.009}"#.into(),
        model_resolved: String::new(),
        integrator: "dopri5".into(),
        tolerances: r#"{"atol":1e-12,"rtol":1e-10}"#.into(),
        max_strides: 100,
        x_name: "theta".into(),
        x: linspace(0.15, 0.25, nx),
        y_name: "thetadot".into(),
        y: linspace(-0.25, -0.15, ny),
        z: None,
        state_names: vec!["theta".into(), "thetadot".into()],
        legend: LEGEND.iter().map(|(c, n)| (*c, n.to_string())).collect(),
        shard: None,
    }
}

pub fn shard_header(nx: usize, ny: usize, index: usize, count: usize) -> BasinHeader {
    BasinHeader {
        shard: Some(ShardSpec { index, count }),
        command: format!("pdw-sweep basin --shard {index}/{count}"),
        ..header(nx, ny)
    }
}

/// splitmix64: a seeded, portable hash for synthetic cell values.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Synthetic cell (row i, column j): a band of `gait` along the diagonal, falls either side,
/// a sprinkle of every other outcome; `nonfinite` cells carry NaN final states.
pub fn cell(h: &BasinHeader, i: usize, j: usize) -> (u8, u16, [f64; 2]) {
    let r = mix(((i as u64) << 32) ^ j as u64 ^ 0x5EED);
    let (u, v) = (j as f64 / h.nx() as f64, i as f64 / h.ny() as f64);
    let code = match r % 23 {
        0 => 1,
        1 => 4,
        2 => 5,
        _ if (u - v).abs() < 0.15 => 0,
        _ if u > v => 2,
        _ => 3,
    };
    let strides = (r >> 8) as u16 % 101;
    let fin = if code == 5 {
        [f64::NAN, f64::INFINITY]
    } else {
        [
            h.x[j] + (r >> 20) as f64 * 1e-30,
            h.y[i] - strides as f64 * 1e-3,
        ]
    };
    (code, strides, fin)
}

/// Rows `r0 .. r0 + k` as the flat row-major blocks `write_rows` takes.
pub fn block(h: &BasinHeader, r0: usize, k: usize) -> (Vec<u8>, Vec<u16>, Vec<f64>) {
    let (mut o, mut s, mut f) = (Vec::new(), Vec::new(), Vec::new());
    for i in r0..r0 + k {
        for j in 0..h.nx() {
            let (c, st, fin) = cell(h, i, j);
            o.push(c);
            s.push(st);
            f.extend_from_slice(&fin);
        }
    }
    (o, s, f)
}

pub fn write_block(w: &mut BasinWriter, r0: usize, k: usize) {
    let (o, s, f) = block(&w.header().clone(), r0, k);
    w.write_rows(r0, &o, &s, &f).unwrap();
}

/// Fractions per outcome of the codes in `outcome` (the test's independent metrics).
pub fn fractions(h: &BasinHeader, outcome: &[u8]) -> BasinMetrics {
    let n = outcome.len() as f64;
    BasinMetrics {
        fractions: h
            .legend
            .iter()
            .map(|(c, name)| {
                (
                    name.clone(),
                    outcome.iter().filter(|o| *o == c).count() as f64 / n,
                )
            })
            .collect(),
        basin_entropy: 0.25,
        boundary_entropy: 0.5,
        entropy_box: 5,
    }
}

pub fn attractors() -> Vec<Attractor> {
    vec![
        Attractor {
            name: "gait".into(),
            period_strides: 1,
            period_time: 3.812_140_6,
            section: vec![vec![0.200_310_900_544_287_4, -0.199_832_473_004_977_74]],
            multipliers: vec![(-0.19, 0.58), (-0.19, -0.58)],
            validity: OrbitCheck::Valid,
        },
        Attractor {
            name: "period2".into(),
            period_strides: 2,
            period_time: 7.6,
            section: vec![vec![0.21, -0.2], vec![0.19, -0.19]],
            multipliers: vec![(0.5, 0.0), (0.01, 0.0)],
            validity: OrbitCheck::Invalid(vec![
                "a knee lock must pull".into(),
                "the swing foot scuffs".into(),
            ]),
        },
    ]
}

pub fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap()
}
