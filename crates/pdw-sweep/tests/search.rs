//! `fixedpoint --search`: every gait without a guess, on the command line — Garcia's two gaits
//! at γ = 0.009 (REFERENCES §1) with the starts that reached them, the automatic scan when the
//! guesses find no gait of the kind asked (the period-2 attractor at γ = 0.016, past the first
//! period doubling), and the bad boxes and conflicts refused with exit 2.

use crate::common::run;

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn search_lists_both_garcia_gaits_with_their_starts() {
    let o = run(&[
        "fixedpoint",
        "--slope",
        "0.009",
        "--search",
        "256",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let fps = v["fixed_points"].as_array().unwrap();
    assert_eq!(fps.len(), 2);
    let theta: Vec<f64> = fps
        .iter()
        .map(|f| f["section"][0].as_f64().unwrap())
        .collect();
    for want in [0.20031090049483, 0.19393736960624] {
        assert!(theta.iter().any(|t| (t - want).abs() < 1e-9), "{theta:?}");
    }
    let scan = &v["scan"];
    assert_eq!(scan["starts"], 256);
    let settled: u64 = fps
        .iter()
        .map(|f| f["starts_settled"].as_u64().unwrap())
        .sum();
    assert_eq!(
        settled + scan["fell"].as_u64().unwrap() + scan["unsettled"].as_u64().unwrap(),
        256
    );
    // the table names the starts too
    let o = run(&["fixedpoint", "--slope", "0.009", "--search", "256"]);
    let out = text(&o.stdout);
    assert!(
        out.contains("scan of the section: 256 starts (Halton)"),
        "{out}"
    );
    assert!(out.contains("Newton converged to it from"), "{out}");
}

#[test]
fn when_the_guesses_find_no_stable_gait_the_section_is_scanned() {
    // at γ = 0.016 the stable period-one gait has period-doubled: the guesses find only the
    // unstable ones, and the scan finds the stable period-2 orbit
    let o = run(&["fixedpoint", "--slope", "0.016", "--gait", "stable"]);
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "{err}");
    assert!(err.contains("scanning the section (256 starts"), "{err}");
    assert!(out.contains("stable period-2 orbit"), "{out}");
}

#[test]
fn bad_boxes_and_conflicts_are_refused_naming_the_option() {
    for (args, words) in [
        (
            vec![
                "fixedpoint",
                "--search",
                "8",
                "--search-box",
                "theta=0.5:0.2",
            ],
            vec!["--search-box", "inverted"],
        ),
        (
            vec!["fixedpoint", "--search", "8", "--search-box", "phi=0:1"],
            vec!["--search-box", "no section coordinate 'phi'"],
        ),
        (
            vec!["fixedpoint", "--search", "--guess", "0.2,-0.2"],
            vec!["--search", "--guess"],
        ),
        (
            vec!["fixedpoint", "--search-box", "theta=0.1:0.2"],
            vec!["--search"],
        ),
        (vec!["fixedpoint", "--search", "0"], vec!["--search", "'0'"]),
    ] {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = text(&o.stderr);
        for w in words {
            assert!(e.contains(w), "{args:?}: {e}");
        }
        assert!(!e.contains("panicked"));
    }
}
