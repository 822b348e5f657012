//! Writes a synthetic basin file of a chosen size through `BasinWriter` and reports its size
//! and write time: `cargo run --release -p pdw-store --example synthetic_basin -- 1000 1000 out.h5`.
//!
//! The cells imitate a real basin's statistics: a smooth band of `gait` whose final states sit
//! within 1e-9 of a fixed point (so their low mantissa bits vary, as a tolerance-based
//! classification leaves them), falls on either side with final states that vary smoothly with
//! the initial condition, and strides that grow towards the band. It also draws the PNG.

use std::time::Instant;

use pdw_store::{
    plot_basin, read_basin_outcome, BasinHeader, BasinMetrics, BasinWriter, BLOCK_ROWS,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let nx: usize = args.get(1).map_or(Ok(1000), |s| s.parse())?;
    let ny: usize = args.get(2).map_or(Ok(1000), |s| s.parse())?;
    let out = args
        .get(3)
        .cloned()
        .unwrap_or_else(|| "synthetic_basin.h5".into());
    let lin = |a: f64, b: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|i| a + (b - a) * i as f64 / (n.max(2) - 1) as f64)
            .collect()
    };
    let h = BasinHeader {
        command: args.join(" "),
        model: "simplest".into(),
        slope: 0.009,
        params: r#"{"gamma":0.009}"#.into(),
        model_resolved: String::new(),
        integrator: "dopri5".into(),
        tolerances: r#"{"atol":1e-12,"rtol":1e-10}"#.into(),
        max_strides: 100,
        x_name: "theta".into(),
        x: lin(0.15, 0.25, nx),
        y_name: "thetadot".into(),
        y: lin(-0.25, -0.15, ny),
        z: None,
        state_names: vec!["theta".into(), "thetadot".into()],
        legend: vec![
            (0, "gait".into()),
            (1, "other".into()),
            (2, "fall_forward".into()),
            (3, "fall_backward".into()),
            (4, "timeout".into()),
            (5, "nonfinite".into()),
        ],
        shard: None,
    };
    let t0 = Instant::now();
    let mut w = BasinWriter::create(&out, &h, true)?;
    let fp = (0.200_310_900_544_287_4, -0.199_832_473_004_977_74);
    for r0 in (0..ny).step_by(BLOCK_ROWS) {
        let k = BLOCK_ROWS.min(ny - r0);
        let (mut o, mut s, mut f) = (Vec::new(), Vec::new(), Vec::new());
        for i in r0..r0 + k {
            for j in 0..nx {
                let (x, y) = (h.x[j], h.y[i]);
                let band = (x - fp.0) + 0.8 * (y - fp.1) + 0.01 * (40.0 * y).sin();
                let (code, strides, fin) = if band.abs() < 0.01 {
                    let eps = 1e-9 * ((i * 7919 + j * 104_729) % 1000) as f64 / 1000.0;
                    (
                        0u8,
                        (20.0 + 2000.0 * band.abs()) as u16,
                        [fp.0 + eps, fp.1 - eps],
                    )
                } else if band > 0.0 {
                    (2, (1.0 + 0.05 / band) as u16, [0.4 + x * y, -1.0 + 0.3 * x])
                } else {
                    (3, (1.0 - 0.05 / band) as u16, [-0.3 + x * y, 0.2 * y])
                };
                o.push(code);
                s.push(strides.min(100));
                f.extend_from_slice(&fin);
            }
        }
        w.write_rows(r0, &o, &s, &f)?;
    }
    let outcome = w.read_outcome()?;
    let n = outcome.len() as f64;
    let frac = |c: u8| outcome.iter().filter(|&&o| o == c).count() as f64 / n;
    let m = BasinMetrics {
        fractions: h
            .legend
            .iter()
            .map(|(c, name)| (name.clone(), frac(*c)))
            .collect(),
        basin_entropy: f64::NAN,
        boundary_entropy: f64::NAN,
        entropy_box: 5,
    };
    w.finish(&m, &[])?;
    let secs = t0.elapsed().as_secs_f64();
    let size = std::fs::metadata(&out)?.len();
    println!(
        "{nx}x{ny}: {size} bytes ({:.2} MB, {:.2} bytes/cell), written in {secs:.2} s",
        size as f64 / 1e6,
        size as f64 / (nx * ny) as f64
    );
    let (hh, oc) = read_basin_outcome(&out)?;
    let png = format!("{out}.png");
    let t1 = Instant::now();
    plot_basin(&png, &hh, oc.view(), Some(fp), "synthetic basin")?;
    println!("plot {png} in {:.2} s", t1.elapsed().as_secs_f64());
    Ok(())
}
