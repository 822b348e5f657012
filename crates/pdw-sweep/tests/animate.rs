//! `animate`: strides, frame rate and size read back from the GIF; `--from` a trajectory file
//! draws the file's states (the hip and stance foot where the stored angles put them); bad
//! values refused with messages naming them.

use crate::common;
use common::*;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Size, delay of the first frame (centiseconds) and frame count of a GIF.
fn gif_info(p: &Path) -> (u16, u16, u16, usize) {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(p).unwrap()).unwrap();
    let (w, h) = (dec.width(), dec.height());
    let mut delay = None;
    let mut n = 0;
    while let Some(f) = dec.read_next_frame().unwrap() {
        delay.get_or_insert(f.delay);
        n += 1;
    }
    (w, h, delay.unwrap(), n)
}

/// The compass preset's gait period (s).
fn compass_period() -> f64 {
    let m = pdw::build("compass", &[]).unwrap();
    pdw::animate::gait(&m).unwrap().0.unwrap().metrics.period
}

#[test]
fn animate_draws_the_strides_at_the_frame_rate_and_size_asked() {
    let dir = tempfile::tempdir().unwrap();
    let period = compass_period();
    // the Goswami compass walks a stride in about 0.73 s
    assert!((period - 0.734).abs() < 0.01, "period {period}");
    let g = dir.path().join("a.gif");
    let o = run(&[
        "animate",
        "--model",
        "compass",
        "--strides",
        "3",
        "--fps",
        "20",
        "--size",
        "320x240",
        "--out",
        s(&g),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // 20 fps: 5 cs per frame, 0.05 s of model time per frame (real time); a stride gets
    // round(T / 0.05) frames, and the GIF strides · n + 1
    let n = (period / 0.05).round() as usize;
    assert_eq!(gif_info(&g), (320, 240, 5, 3 * n + 1));
    assert!(stderr(&o).contains("real time"), "{}", stderr(&o));
    // the defaults: 2 strides, 60 ms, 640 × 400
    let d = dir.path().join("d.gif");
    let o = run(&["animate", "--model", "compass", "--out", s(&d)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let n = (period / 0.06).round() as usize;
    assert_eq!(gif_info(&d), (640, 400, 6, 2 * n + 1));
}

#[test]
fn animate_from_a_trajectory_draws_the_stored_states() {
    let dir = tempfile::tempdir().unwrap();
    let t = dir.path().join("t.h5");
    // samples every 0.05 s: the frame times of 20 fps, so each frame is a stored state
    let o = run(&[
        "simulate",
        "--model",
        "compass",
        "--steps",
        "3",
        "--dt-out",
        "0.05",
        "--out",
        s(&t),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let data = pdw::store::read_trajectory_h5(&t).unwrap();
    let m = pdw::animate_trajectory::model(&data, &t).unwrap();
    assert_eq!(m.info.name, "compass");
    let opts = pdw::animate::AnimOptions {
        fps: 20.0,
        ..Default::default()
    };
    let frames = pdw::animate_trajectory::frames(&m, &data, &opts, &t).unwrap();
    let time = &data.column("t").unwrap().values;
    let names: Vec<String> =
        serde_json::from_str(&data.attrs.iter().find(|a| a.0 == "state_names").unwrap().1).unwrap();
    let q0 = &data.column(&names[0]).unwrap().values;
    let step = &data.column("step").unwrap().values;
    let t_end = time[time.len() - 1];
    assert_eq!(
        frames.len(),
        ((t_end - time[0]) / 0.05 + 1e-9).floor() as usize + 1
    );
    // the stance foot advances by the chord between the feet at each heel strike: both feet
    // on the slope under the hip, two legs of length l = a + b = 1 m, the stance leg at q0
    // from the slope's normal: 2 l |sin q0|
    let (l, gamma) = (1.0, m.slope());
    let ev = &data.events;
    let chords: Vec<f64> = (0..ev.t.len())
        .filter(|&k| ev.kind[k] == "heel_strike")
        .map(|k| 2.0 * l * ev.pre[k * data.dim].sin().abs())
        .collect();
    assert_eq!(chords.len(), 3);
    let world = |x: f64, y: f64| {
        (
            x * gamma.cos() + y * gamma.sin(),
            -x * gamma.sin() + y * gamma.cos(),
        )
    };
    let mut checked = 0;
    for (k, f) in frames.iter().enumerate() {
        let tk = time[0] + k as f64 * 0.05;
        // the last stored sample at the frame's time
        let Some(i) = (0..time.len()).rev().find(|&i| (time[i] - tk).abs() < 1e-9) else {
            continue;
        };
        let foot: f64 = chords[..step[i] as usize].iter().sum();
        let stance = world(foot, 0.0);
        let hip = world(foot - l * q0[i].sin(), l * q0[i].cos());
        let near = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1) < 1e-9;
        assert!(
            near(f.links[0].0, stance),
            "frame {k}: stance foot {:?} vs {stance:?}",
            f.links[0].0
        );
        assert!(
            near(f.joints[0], hip),
            "frame {k}: hip {:?} vs {hip:?}",
            f.joints[0]
        );
        // the swing foot closes the second leg: at l from the hip
        let sw = f.links[1].1;
        assert!(((sw.0 - hip.0).hypot(sw.1 - hip.1) - l).abs() < 1e-9);
        checked += 1;
    }
    assert!(
        checked + 2 >= frames.len(),
        "{checked} of {} frames on samples",
        frames.len()
    );
    // the CLI draws the same file
    let g = dir.path().join("t.gif");
    let o = run(&["animate", "--from", s(&t), "--fps", "20", "--out", s(&g)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(gif_info(&g), (640, 400, 5, frames.len()));
}

#[test]
fn animate_from_a_walk_that_falls_ends_on_the_fall() {
    let dir = tempfile::tempdir().unwrap();
    let t = dir.path().join("fall.h5");
    // far too fast a start: the walker falls within the first steps
    let o = run(&[
        "simulate",
        "--model",
        "compass",
        "--state",
        "0.3,-2.5,2.0",
        "--steps",
        "5",
        "--out",
        s(&t),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let data = pdw::store::read_trajectory_h5(&t).unwrap();
    let fell = pdw::animate_trajectory::fall(&data).expect("the walk falls");
    let m = pdw::animate_trajectory::model(&data, &t).unwrap();
    let frames = pdw::animate_trajectory::frames(&m, &data, &Default::default(), &t).unwrap();
    let last = frames.last().unwrap();
    let t_end = data.column("t").unwrap().values.last().copied().unwrap();
    assert!(last.label.contains("FELL"), "{}", last.label);
    assert!(last.label.contains(&fell), "{}", last.label);
    assert!(
        last.label.starts_with(&format!("t = {t_end:.3}")),
        "{}",
        last.label
    );
}

#[test]
fn animate_refuses_bad_values_with_clear_messages() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("x.gif");
    for (args, says) in [
        (
            vec!["--strides", "0"],
            "--strides: 0 strides is outside 1..=1000",
        ),
        // the old spelling, a hidden alias, still parses
        (
            vec!["--steps", "1001"],
            "--strides: 1001 strides is outside 1..=1000",
        ),
        (
            vec!["--fps", "100"],
            "--fps: 100 frames per second is outside 0.5..=50",
        ),
        (vec!["--fps", "nan"], "--fps"),
        (vec!["--size", "10x10"], "--size: 10x10 pixels is outside"),
        (vec!["--size", "640"], "is not a size WIDTHxHEIGHT"),
        (vec!["--from", "missing.h5"], "missing.h5"),
        (
            vec!["--from", "t.h5", "--slope", "0.01"],
            "cannot be used with",
        ),
    ] {
        let mut a = vec!["animate", "--out", s(&g)];
        a.extend(args.iter().copied());
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(says), "{args:?}: {e}");
        assert!(!e.contains("panicked") && !e.contains("{ "), "{e}");
        assert!(!g.exists());
    }
    // a file that is not a trajectory: its model cannot be rebuilt
    let notraj = dir.path().join("n.h5");
    let o = run(&[
        "fixedpoint",
        "--model",
        "compass",
        "--sweep",
        "slope=0.04:0.05:3",
        "--out",
        s(&notraj),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(&["animate", "--from", s(&notraj), "--out", s(&g)]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("n.h5") && !e.contains("panicked"), "{e}");
}
