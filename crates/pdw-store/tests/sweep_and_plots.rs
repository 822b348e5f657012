//! The sweep file round trip, and the pictures: size, format, and colours where they matter.

use crate::common;

use common::*;
use pdw_store::plot::{BASIN_PNG_SIZE, BIFURCATION_PNG_SIZE, LINES_PNG_SIZE};
use pdw_store::{
    animate_gif, invalid_reasons, outcome_colours, plot_basin, plot_basin_attractors,
    plot_bifurcation, plot_lines, read_basin, read_sweep, write_sweep, BasinWriter, Bifurcation,
    Branch, Frame, OrbitDiagram, StoreError, StrideValidity, SweepData,
};

fn sweep() -> SweepData {
    let n = 40;
    let g: Vec<f64> = linspace(0.001, 0.019, n);
    let stable: Vec<bool> = g.iter().map(|&x| x < 0.0151).collect();
    SweepData {
        command: "pdw-sweep fixedpoint --sweep slope=0.001:0.019:40".into(),
        model: "simplest".into(),
        parameter: "slope".into(),
        params: "{}".into(),
        section_names: vec!["theta".into(), "thetadot".into()],
        branches: vec![
            Branch {
                name: "period-1".into(),
                period_strides: 1,
                parameter: g.clone(),
                section: g
                    .iter()
                    .map(|&x| vec![0.97 * x.cbrt(), -0.97 * x.cbrt()])
                    .collect(),
                multipliers: g
                    .iter()
                    .map(|&x| {
                        let r = 0.4 + 40.0 * x;
                        vec![(-r, 0.1), (-r, -0.1)]
                    })
                    .collect(),
                stable,
                ..Branch::default()
            },
            // A measured period-2 branch: both orbit points, per-stride step lengths and flags.
            Branch {
                name: "period-2".into(),
                period_strides: 2,
                parameter: vec![0.0152, 0.016, 0.017],
                section: vec![vec![0.25, -0.24], vec![0.26, -0.25], vec![0.27, -0.26]],
                multipliers: vec![
                    vec![(-0.9, 0.0), (0.1, 0.0)],
                    vec![(-0.5, 0.2), (-0.5, -0.2)],
                    vec![(0.2, 0.0), (0.01, 0.0)],
                ],
                stable: vec![true, true, true],
                orbit: vec![
                    vec![vec![0.25, -0.24], vec![0.23, -0.22]],
                    vec![vec![0.26, -0.25], vec![0.22, -0.21]],
                    vec![vec![0.27, -0.26], vec![0.21, -0.20]],
                ],
                period: vec![7.8, 7.79, 7.78],
                step_length: vec![vec![0.47, 0.49], vec![0.48, 0.50], vec![0.49, 0.51]],
                speed: vec![0.1231, 0.1245, 0.1259],
                validity: (0..3)
                    .map(|i| {
                        (0..2)
                            .map(|j| StrideValidity {
                                checked: true,
                                valid: i != 2,
                                swing_foot_scuffs: i == 2 && j == 1,
                                min_normal_force: 0.8 + 0.01 * j as f64,
                                max_friction_required: 0.25,
                                min_knee_torque: 0.5,
                                ..StrideValidity::default()
                            })
                            .collect()
                    })
                    .collect(),
            },
        ],
        bifurcations: vec![
            Bifurcation {
                kind: "period-doubling".into(),
                parameter: 0.0151,
                branch: 0,
                section: vec![0.24, -0.24],
            },
            Bifurcation {
                kind: "fold".into(),
                parameter: 0.0185,
                branch: 0,
                section: vec![0.26, -0.26],
            },
        ],
        orbit: Some(OrbitDiagram {
            coordinate: "theta".into(),
            parameter: linspace(0.012, 0.019, 30),
            points: (0..30)
                .map(|k| {
                    (0..8)
                        .map(|s| {
                            if k > 25 && s == 3 {
                                f64::NAN
                            } else {
                                0.2 + 0.001 * (k * s) as f64
                            }
                        })
                        .collect()
                })
                .collect(),
        }),
        settings: vec![
            ("continuation".into(), r#"{"ds_max":1e-4}"#.into()),
            ("grid".into(), r#"{"n":40}"#.into()),
        ],
        elapsed_s: 1.25,
    }
}

#[test]
fn sweep_file_round_trips_and_is_not_overwritten_without_force() {
    let dir = scratch("sweep");
    let p = dir.join("bif.h5");
    let s = sweep();
    write_sweep(&p, false, &s).unwrap();
    let r = read_sweep(&p).unwrap();
    // NaN ≠ NaN: compare the orbit diagram bitwise, the rest structurally.
    let bits = |o: &OrbitDiagram| {
        o.points
            .iter()
            .flatten()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        bits(r.orbit.as_ref().unwrap()),
        bits(s.orbit.as_ref().unwrap())
    );
    let (mut a, mut b) = (r.clone(), s.clone());
    a.orbit = None;
    b.orbit = None;
    assert_eq!(a, b);

    let before = bytes(&p);
    let err = write_sweep(&p, false, &s).unwrap_err();
    assert!(matches!(err, StoreError::Exists { .. }), "{err}");
    assert_eq!(bytes(&p), before);
    write_sweep(&p, true, &s).unwrap();

    let mut bad = s.clone();
    bad.branches[1].orbit[2].pop();
    assert!(matches!(
        write_sweep(dir.join("x.h5"), false, &bad),
        Err(StoreError::Invalid { .. })
    ));
    let mut bad = s.clone();
    bad.branches[0].stable.pop();
    assert!(matches!(
        write_sweep(dir.join("x.h5"), false, &bad),
        Err(StoreError::Invalid { .. })
    ));
    assert!(!dir.join("x.h5").exists());
}

/// Width, height and RGBA pixels of a PNG.
fn decode_png(p: &std::path::Path) -> (u32, u32, Vec<u8>, png::ColorType) {
    let dec = png::Decoder::new(std::fs::File::open(p).unwrap());
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf, info.color_type)
}

#[test]
fn basin_png_has_stated_size_and_paints_cells_in_outcome_colours() {
    let dir = scratch("basinpng");
    let (nx, ny) = (60, 45);
    let h = header(nx, ny);
    let p = dir.join("b.h5");
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 32); // rows 32.. stay "not computed"
    drop(w);
    let d = read_basin(&p).unwrap();
    let png_path = dir.join("basin.png");
    plot_basin(
        &png_path,
        &d.header,
        d.outcome.view(),
        Some((0.2003, -0.1998)),
        "simplest, γ = 0.009",
    )
    .unwrap();
    let (w, hgt, px, ct) = decode_png(&png_path);
    assert_eq!((w, hgt), BASIN_PNG_SIZE);
    assert_eq!(ct, png::ColorType::Rgb);
    // Every outcome colour present in the grid appears in the picture, and the gait colour
    // covers a share of the picture's pixels comparable to its share of the cells.
    let colours = outcome_colours(&d.header.legend);
    let count = |c: [u8; 3]| px.chunks(3).filter(|q| q == &c).count();
    for (code, c) in &colours {
        if d.outcome.iter().any(|o| o == code) {
            assert!(count(*c) > 0, "colour of outcome {code} missing");
        }
    }
    let gait_cells = d.outcome.iter().filter(|o| **o == 0).count() as f64 / (nx * ny) as f64;
    let plot_px = 0.55 * (w * hgt) as f64; // rough plotting-area share of the picture
    let gait_px = count(colours[0].1) as f64 / plot_px;
    assert!(
        (gait_px / gait_cells - 1.0).abs() < 0.35,
        "gait share: cells {gait_cells:.3}, pixels {gait_px:.3}"
    );

    // Wrong shape is refused.
    let err = plot_basin(
        dir.join("x.png"),
        &h,
        d.outcome.slice(ndarray::s![..10, ..]),
        None,
        "",
    );
    assert!(matches!(err, Err(StoreError::Invalid { .. })));
}

/// A physically invalid attractor is drawn apart on a basin picture: its orbit hollow with a red
/// ring, "(invalid)" in its legend entry and what fails in red under the legend; the same
/// attractors all valid draw no red at all.
#[test]
fn invalid_attractors_are_hollow_red_and_named_on_the_basin_png() {
    let dir = scratch("basininvalid");
    let h = header(40, 30);
    let p = dir.join("b.h5");
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 30);
    drop(w);
    let d = read_basin(&p).unwrap();
    let atts = attractors();
    assert!(
        atts[1].validity.reasons().is_some(),
        "the fixture has an invalid orbit"
    );
    let mut valid = atts.clone();
    valid[1].validity = pdw_store::OrbitCheck::Valid;
    let (with, without) = (dir.join("with.png"), dir.join("without.png"));
    plot_basin_attractors(&with, &d.header, d.outcome.view(), &atts, "t").unwrap();
    plot_basin_attractors(&without, &d.header, d.outcome.view(), &valid, "t").unwrap();
    let red = |path: &std::path::Path| {
        let (w, _, px, _) = decode_png(path);
        let legend_x = w - 220;
        let (mut plot, mut legend) = (0, 0);
        for (i, q) in px.chunks(3).enumerate() {
            if q == [200, 0, 0] {
                if (i as u32 % w) < legend_x {
                    plot += 1
                } else {
                    legend += 1
                }
            }
        }
        (plot, legend)
    };
    let (plot, legend) = red(&with);
    assert!(
        plot > 20,
        "no red ring on the invalid orbit's points ({plot} px)"
    );
    assert!(legend > 100, "no red legend mark and reasons ({legend} px)");
    assert_eq!(red(&without), (0, 0));
}

/// Invalid gaits are told apart from valid ones: the reasons come from the strides' flags, and
/// the PNG rings exactly the invalid points (the same data with every stride valid draws no
/// ring: the pixels differ only where the rings and their legend entry are).
#[test]
fn invalid_gaits_are_ringed_and_named_in_the_bifurcation_png() {
    let data = sweep();
    let p2 = &data.branches[1];
    assert_eq!(invalid_reasons(p2, 0), None);
    assert_eq!(invalid_reasons(p2, 1), None);
    // Point 2: stride 0 invalid with no named flag, stride 1 scuffs.
    assert_eq!(
        invalid_reasons(p2, 2),
        Some(vec!["invalid", "the swing foot scuffs"])
    );
    // Unmeasured (the period-1 branch) and unchecked strides are never "invalid".
    assert_eq!(invalid_reasons(&data.branches[0], 0), None);
    let mut unchecked = p2.clone();
    for v in unchecked.validity.iter_mut().flatten() {
        *v = StrideValidity::unchecked();
    }
    assert_eq!(invalid_reasons(&unchecked, 2), None);

    let dir = scratch("invalidpng");
    let (with, without) = (dir.join("with.png"), dir.join("without.png"));
    plot_bifurcation(&with, &data, 0).unwrap();
    let mut all_valid = data.clone();
    for v in all_valid.branches[1].validity.iter_mut().flatten() {
        v.valid = true;
        v.swing_foot_scuffs = false;
    }
    plot_bifurcation(&without, &all_valid, 0).unwrap();
    let (w, h, a, _) = decode_png(&with);
    let (_, _, b, _) = decode_png(&without);
    let differs = |rows: std::ops::Range<u32>| {
        rows.flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let k = ((y * w + x) * 3) as usize;
                a[k..k + 3] != b[k..k + 3]
            })
            .count()
    };
    // Rings on the |λ| panel and on the section panel; none on the Re λ panel.
    assert!(differs(0..h / 3) > 20, "no ring on the |λ| panel");
    assert!(differs(h / 3..2 * h / 3) == 0, "the Re λ panel changed");
    assert!(
        differs(2 * h / 3..h) > 40,
        "no rings or legend entry on the section panel"
    );
}

#[test]
fn bifurcation_and_line_pngs_have_stated_sizes() {
    let dir = scratch("otherpng");
    let p = dir.join("bif.png");
    plot_bifurcation(&p, &sweep(), 0).unwrap();
    let (w, h, px, _) = decode_png(&p);
    assert_eq!((w, h), BIFURCATION_PNG_SIZE);
    // Period-doubling markers are pure red.
    assert!(
        px.chunks(3).any(|q| q == [255, 0, 0]),
        "no period-doubling marker drawn"
    );
    // Three panels of equal height: |λ|, Re λ, the section coordinate. Only the middle one
    // carries the dashed red λ = −1 line across its width (the others have red markers only),
    // so period doublings (−1) and folds (+1) are told apart at a glance.
    let red_in = |rows: std::ops::Range<u32>| {
        rows.map(|y| {
            px[(y * w * 3) as usize..((y + 1) * w * 3) as usize]
                .chunks(3)
                .filter(|q| *q == [255, 0, 0])
                .count()
        })
        .collect::<Vec<_>>()
    };
    let mid = red_in(h / 3..2 * h / 3);
    let widest = *mid.iter().max().unwrap();
    assert!(
        widest as f64 > 0.3 * w as f64,
        "no λ = −1 line in the middle panel (widest red row {widest} px of {w})"
    );
    let top = red_in(0..h / 3);
    assert!(
        (*top.iter().max().unwrap() as f64) < 0.1 * w as f64,
        "the |λ| panel has no red line"
    );
    assert!(plot_bifurcation(dir.join("x.png"), &sweep(), 2).is_err());

    let series = vec![
        (
            "dopri5".to_string(),
            vec![(1e-3, 1e-4), (3e-3, 1e-7), (1e-2, 1e-10)],
        ),
        (
            "rk4".to_string(),
            vec![(2e-3, 1e-3), (8e-3, 1e-6), (3e-2, 1e-9), (0.05, 0.0)],
        ),
    ];
    for (lx, ly) in [(false, false), (true, false), (false, true), (true, true)] {
        let q = dir.join(format!("lines-{lx}-{ly}.png"));
        plot_lines(
            &q,
            "work-precision",
            "time per stride (s)",
            "error",
            &series,
            lx,
            ly,
        )
        .unwrap();
        let (w, h, _, _) = decode_png(&q);
        assert_eq!((w, h), LINES_PNG_SIZE);
    }
    // nothing finite: the axes alone, at the stated size
    let empty = vec![("none".to_string(), vec![(0.0, f64::NAN)])];
    plot_lines(dir.join("e.png"), "t", "x", "y", &empty, false, false).unwrap();
    let (w, h, _, _) = decode_png(&dir.join("e.png"));
    assert_eq!((w, h), LINES_PNG_SIZE);
}

#[test]
fn gait_gif_has_one_frame_per_input_frame_at_stated_size() {
    let dir = scratch("gif");
    let p = dir.join("gait.gif");
    let n = 12;
    let gamma: f64 = 0.05;
    let frames: Vec<Frame> = (0..n)
        .map(|k| {
            let t = k as f64 / n as f64;
            let hip = (t, 1.0 - 0.05 * (std::f64::consts::TAU * t).sin());
            let stance = (0.0, 0.0);
            let swing = (2.0 * t - 0.3, 0.02);
            Frame {
                links: vec![(stance, hip), (hip, swing)],
                joints: vec![hip, stance, swing],
                slope: ((0.0, 0.0), (gamma.cos(), -gamma.sin())),
                trace: (0..=k)
                    .map(|j| (2.0 * j as f64 / n as f64 - 0.3, 0.02))
                    .collect(),
                label: format!("t = {t:.2}"),
            }
        })
        .collect();
    animate_gif(&p, &frames, (480, 360), 50, "compass gait").unwrap();
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(&p).unwrap()).unwrap();
    assert_eq!((dec.width(), dec.height()), (480, 360));
    let mut count = 0;
    while dec.read_next_frame().unwrap().is_some() {
        count += 1;
    }
    assert_eq!(count, n);
    assert!(animate_gif(dir.join("e.gif"), &[], (480, 360), 50, "").is_err());
}

#[test]
fn basin_stability_file_round_trips_refuses_bad_rows_and_draws_its_chart() {
    use pdw_store::plot::STABILITY_PNG_SIZE;
    use pdw_store::{
        plot_basin_stability, read_stability, write_stability, StabilityAttractor, StabilityData,
    };
    let dir = scratch("stability");
    let d = StabilityData {
        command: "pdw-sweep basin --over slope=0.009:0.019:3".into(),
        model: "simplest".into(),
        parameter: "slope".into(),
        params: "{}".into(),
        box_json: r#"{"x":{"name":"theta"}}"#.into(),
        max_strides: 100,
        values: vec![0.009, 0.014, 0.019],
        columns: vec![
            "gait".into(),
            "period-2".into(),
            "fall".into(),
            "timeout".into(),
            "other".into(),
        ],
        kinds: vec![
            "attractor".into(),
            "attractor".into(),
            "fall".into(),
            "timeout".into(),
            "other".into(),
        ],
        fractions: vec![
            vec![0.25, 0.0, 0.75, 0.0, 0.0],
            vec![0.125, 0.0, 0.75, 0.125, 0.0],
            vec![0.0, 0.5, 0.25, 0.0, 0.25],
        ],
        outcome_columns: vec!["gait".into(), "other".into()],
        outcome_fractions: vec![vec![0.25, 0.75], vec![0.125, 0.875], vec![0.0, 1.0]],
        attractors: vec![
            vec![StabilityAttractor {
                name: "gait".into(),
                period_strides: 1,
                period_time: Some(3.8),
                points: vec![vec![0.2, -0.2]],
                multipliers: vec![[-0.5, 0.1], [-0.5, -0.1]],
                validity: "valid".into(),
                invalid_reasons: vec![],
            }],
            vec![],
            vec![StabilityAttractor {
                name: "chaotic".into(),
                period_strides: 0,
                period_time: None,
                points: vec![vec![0.24, -0.23], vec![0.26, -0.25]],
                multipliers: vec![],
                validity: "not checked".into(),
                invalid_reasons: vec![],
            }],
        ],
        settings: vec![("options".into(), r#"{"threads":2}"#.into())],
        elapsed_s: 0.5,
    };
    let p = dir.join("bs.h5");
    write_stability(&p, false, &d).unwrap();
    assert_eq!(read_stability(&p).unwrap(), d);
    assert!(matches!(
        write_stability(&p, false, &d),
        Err(StoreError::Exists { .. })
    ));
    let mut bad = d.clone();
    bad.fractions[1][0] = 0.2; // the row sums to 1.075
    let err = write_stability(dir.join("bad.h5"), false, &bad).unwrap_err();
    assert!(err.to_string().contains("sum"), "{err}");
    assert!(!dir.join("bad.h5").exists());

    let png_path = dir.join("bs.png");
    plot_basin_stability(&png_path, &d, "slope [rad]", "basin stability").unwrap();
    let (w, h, px, _) = decode_png(&png_path);
    assert_eq!((w, h), STABILITY_PNG_SIZE);
    // Stacked bands in the basin picture's colours: the gait green and the falls red cover a
    // share of the top panel.
    let count = |c: [u8; 3]| px.chunks(3).filter(|q| *q == c).count();
    assert!(count([44, 160, 44]) > 1000, "gait band missing");
    assert!(count([214, 39, 40]) > 10000, "fall band missing");
    // no attractor is invalid: no red outline
    let ring = [200, 0, 0];
    assert_eq!(count(ring), 0);
    // the gait found physically invalid at the first value: its band is outlined in red (in
    // the top panel: the band's edge and the legend swatch)
    let mut inv = d.clone();
    inv.attractors[0][0].validity = "invalid".into();
    inv.attractors[0][0].invalid_reasons = vec!["a knee lock must pull".into()];
    assert!(inv.invalid_column("gait") && !inv.invalid_column("chaotic"));
    let q = dir.join("bs-invalid.png");
    plot_basin_stability(&q, &inv, "slope [rad]", "basin stability").unwrap();
    let (_, _, px2, _) = decode_png(&q);
    let red_rows: Vec<usize> = px2
        .chunks(3 * w as usize)
        .enumerate()
        .filter(|(_, row)| row.chunks(3).any(|q| *q == ring))
        .map(|(y, _)| y)
        .collect();
    assert!(
        red_rows.len() > 20,
        "no red outline ({} rows)",
        red_rows.len()
    );
    assert!(
        red_rows.iter().all(|&y| y < h as usize / 2),
        "outline outside the top panel"
    );
    // read back, the validity is kept
    let p2 = dir.join("bs-invalid.h5");
    write_stability(&p2, false, &inv).unwrap();
    assert_eq!(read_stability(&p2).unwrap(), inv);
}

/// The first frame of a GIF (RGBA), its size and delay (centiseconds), and the frame count.
fn decode_gif(p: &std::path::Path) -> (u32, u32, Vec<u8>, u16, usize) {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(p).unwrap()).unwrap();
    let (w, h) = (dec.width() as u32, dec.height() as u32);
    let first = dec.read_next_frame().unwrap().unwrap();
    let (px, delay) = (first.buffer.to_vec(), first.delay);
    // the first frame covers the picture (plotters writes whole frames)
    assert_eq!(px.len(), (w * h * 4) as usize);
    let mut count = 1;
    while dec.read_next_frame().unwrap().is_some() {
        count += 1;
    }
    (w, h, px, delay, count)
}

#[test]
fn a_long_gif_title_is_fitted_inside_the_picture() {
    use pdw_store::plot::GIF_CAPTION_H;
    let dir = scratch("giftitle");
    let frame = |label: &str| Frame {
        links: vec![((0.0, 0.0), (0.1, 1.0))],
        joints: vec![(0.1, 1.0)],
        slope: ((0.0, 0.0), (1.0, -0.05)),
        trace: vec![],
        label: label.into(),
    };
    let title = "a_walker_spec_with_a_very_long_name_indeed walker, slope 0.0523 rad: UNSTABLE \
                 gait (FLAGGED), period 0.7340";
    for (w, h) in [(640, 400), (320, 240)] {
        let p = dir.join(format!("t{w}.gif"));
        let frames = [frame("t = 0.000   stride 1"), frame("t = 0.060   stride 1")];
        animate_gif(&p, &frames, (w, h), 60, title).unwrap();
        let (gw, gh, px, delay, count) = decode_gif(&p);
        assert_eq!((gw, gh, delay, count), (w, h, 6, 2));
        // dark pixels of the caption band (title and label): some, and none within 3 px of
        // either edge (a title wider than the picture runs into both edges when centred)
        let dark: Vec<u32> = (0..GIF_CAPTION_H.min(h))
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let i = ((y * w + x) * 4) as usize;
                px[i] < 110 && px[i + 1] < 110 && px[i + 2] < 110
            })
            .map(|(x, _)| x)
            .collect();
        assert!(dark.len() > 100, "no caption drawn at {w} px");
        let (lo, hi) = (*dark.iter().min().unwrap(), *dark.iter().max().unwrap());
        assert!(lo >= 3 && hi + 3 < w, "caption spans x = {lo}..{hi} of {w}");
    }
}

#[test]
fn status_markers_appear_where_their_designs_lie() {
    use pdw_store::{plot_lines_marked, MarkerShape, Markers};
    let dir = scratch("markers");
    let p = dir.join("m.png");
    let (orange, purple) = ([255, 127, 14], [148, 103, 189]);
    // the line occupies the middle; one invalid design at the upper left, one unstable at
    // the lower right: the legend takes the upper right (the first empty corner)
    let line = vec![(
        "best so far".to_string(),
        vec![(1.0, 5.0), (5.0, 5.0), (10.0, 5.0)],
    )];
    let markers = [
        Markers {
            name: "invalid".into(),
            points: vec![(1.5, 9.5)],
            colour: orange,
            shape: MarkerShape::Triangle,
        },
        Markers {
            name: "unstable".into(),
            points: vec![(9.5, 0.5)],
            colour: purple,
            shape: MarkerShape::Square,
        },
    ];
    plot_lines_marked(&p, "t", "x", "y", &line, &markers, (false, false)).unwrap();
    let (w, h, px, ct) = decode_png(&p);
    assert_eq!((w, h), LINES_PNG_SIZE);
    assert_eq!(ct, png::ColorType::Rgb);
    let at = |c: [u8; 3]| -> Vec<(u32, u32)> {
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let i = ((y * w + x) * 3) as usize;
                px[i..i + 3] == c
            })
            .collect()
    };
    let (left, right, top, bottom) = (
        0.35 * w as f64,
        0.65 * w as f64,
        0.35 * h as f64,
        0.65 * h as f64,
    );
    let o = at(orange);
    let u = at(purple);
    // each marker where its design lies, and not in the other's corner
    assert!(
        o.iter()
            .any(|&(x, y)| (x as f64) < left && (y as f64) < top),
        "no invalid marker at the upper left"
    );
    assert!(
        u.iter()
            .any(|&(x, y)| (x as f64) > right && (y as f64) > bottom),
        "no unstable marker at the lower right"
    );
    assert!(!o
        .iter()
        .any(|&(x, y)| (x as f64) > right && (y as f64) > bottom));
    assert!(!u
        .iter()
        .any(|&(x, y)| (x as f64) < left && (y as f64) < top));
    // both named in the legend (upper right): each colour there too
    for c in [&o, &u] {
        assert!(
            c.iter()
                .any(|&(x, y)| (x as f64) > right && (y as f64) < top),
            "legend entry missing"
        );
    }
}

/// A long walk's survival curve (two million steps, 16 MB as raw doubles) is stored chunked and
/// deflated: the file is a small part of that, and reads back the same values.
#[test]
fn a_long_survival_curve_is_compressed_and_reads_back_exactly() {
    let (walkers, max_steps) = (1000u64, 2_000_000u64);
    // walker i falls after 2000 (i + 1) steps: survival(k) = #(T ≥ k) / N in steps of 1/N
    let survival: Vec<f64> = (0..=max_steps)
        .map(|k| (walkers - (k.saturating_sub(1) / 2000).min(walkers)) as f64 / walkers as f64)
        .collect();
    let data = pdw_store::MfptData {
        command: "pdw-sweep mfpt --model rimless --sd 1.25deg --max-steps 2000000".into(),
        model: "rimless".into(),
        params: "{}".into(),
        method: "monte carlo".into(),
        terrain: "slope".into(),
        distribution: "normal".into(),
        terrain_unit: "rad".into(),
        mean: 0.14,
        sd: 0.02,
        seed: 1,
        walkers,
        max_steps,
        falls: walkers,
        censored: 0,
        total_steps: 1,
        mfpt: 1.0,
        stderr: 0.1,
        restricted_mean: 1.0,
        restricted_stderr: 0.1,
        estimator: "steps / falls".into(),
        survival: survival.clone(),
        failures: vec![("rolls back".into(), walkers)],
        start: vec![1.4],
        start_names: vec!["thetadot".into()],
        elapsed_s: 1.0,
        chain: vec![],
    };
    data.validate().unwrap();
    let dir = scratch("longsurvival");
    let path = dir.join("long.h5");
    pdw_store::write_mfpt(&path, false, &data).unwrap();
    let bytes = std::fs::metadata(&path).unwrap().len();
    eprintln!("{bytes} bytes for {} survival values", survival.len());
    assert!(bytes < 2_000_000, "{bytes} bytes for a 16 MB curve");
    let back = pdw_store::read_mfpt(&path).unwrap();
    assert_eq!(back.survival, survival);
}

/// Every fixed outcome of a basin file (codes 0–12: eight fall classes among them) has its own
/// colour, so a picture never paints two outcomes alike.
#[test]
fn every_fixed_outcome_has_its_own_colour() {
    let names = [
        "gait",
        "other",
        "fall_forward",
        "fall_backward",
        "fall_hip_below_ground",
        "fall_no_heel_strike",
        "fall",
        "timeout",
        "nonfinite",
        "integrator_failure",
        "fall_knee_bent",
        "fall_knee_buckled",
        "fall_rolls_back",
    ];
    let legend: Vec<(u8, String)> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (i as u8, n.to_string()))
        .collect();
    let c = outcome_colours(&legend);
    for i in 0..c.len() {
        for j in 0..i {
            assert_ne!(c[i].1, c[j].1, "{} and {}", names[i], names[j]);
        }
    }
}
