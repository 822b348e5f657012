//! Resume and design continuation know what they continue: a model file edited between two
//! runs (the same name and parameter values, another resolved walker) is refused, naming the
//! first quantity that differs; the unedited model continues.

use std::path::Path;
use std::process::{Command, Output};

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The compass spec written to `dir/my.toml`, and the same with its COM expression scaled.
fn specs(dir: &Path) -> (String, String) {
    let o = run_in(dir, &["models", "--spec", "compass"]);
    assert!(o.status.success(), "{}", err(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("com = \"a\""),
        "the compass spec changed:\n{text}"
    );
    let edited = text.replacen("com = \"a\"", "com = \"a * 1.01\"", 1);
    std::fs::write(dir.join("my.toml"), &text).unwrap();
    (text, edited)
}

#[test]
fn basin_resume_refuses_a_spec_edited_under_the_same_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, edited) = specs(d);
    let args = [
        "basin",
        "--model",
        "my.toml",
        "--grid",
        "12x10",
        "--max-strides",
        "20",
        "--quiet",
        "--out",
        "b.h5",
    ];
    let first = run_in(d, &args);
    assert!(first.status.success(), "{}", err(&first));
    let before = std::fs::read(d.join("b.h5")).unwrap();
    std::fs::write(d.join("my.toml"), &edited).unwrap();
    let again = run_in(d, &[&args[..], &["--resume"]].concat());
    let e = err(&again);
    assert_eq!(again.status.code(), Some(2), "{e}");
    assert!(e.contains("resolved model"), "{e}");
    assert!(
        e.contains("segments[0]"),
        "the differing quantity is named: {e}"
    );
    assert_eq!(
        std::fs::read(d.join("b.h5")).unwrap(),
        before,
        "a refused resume left the file as it was"
    );
    // the unedited model continues (here: already complete)
    let (text, _) = specs(d);
    std::fs::write(d.join("my.toml"), text).unwrap();
    let same = run_in(d, &[&args[..], &["--resume"]].concat());
    assert!(same.status.success(), "{}", err(&same));
    assert!(
        String::from_utf8_lossy(&same.stdout).contains("already complete"),
        "{}",
        String::from_utf8_lossy(&same.stdout)
    );
}

#[test]
fn design_continuation_refuses_a_spec_edited_under_the_same_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, edited) = specs(d);
    let args = [
        "design",
        "--model",
        "my.toml",
        "--free",
        "hip_mass=5:15",
        "--budget",
        "3",
        "--init",
        "2",
        "--quiet",
        "--out",
        "d.h5",
    ];
    let first = run_in(d, &args);
    assert!(first.status.success(), "{}", err(&first));
    std::fs::write(d.join("my.toml"), &edited).unwrap();
    let again = run_in(d, &args);
    let e = err(&again);
    assert_eq!(again.status.code(), Some(2), "{e}");
    assert!(e.contains("a different model"), "{e}");
    assert!(e.contains("segments[0]"), "{e}");
}
