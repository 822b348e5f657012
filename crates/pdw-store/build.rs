//! Embeds the git commit and the cargo profile of this build for the files' provenance
//! (`pdw_store::provenance::GIT_COMMIT`, `BUILD_PROFILE`). Without git or outside a checkout
//! (a crates.io tarball) the commit is "unknown"; a clean clone in CI has git and its commit.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let o = Command::new("git").args(args).output().ok()?;
    if !o.status.success() {
        return None;
    }
    let s = String::from_utf8(o.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn main() {
    let commit = git(&["rev-parse", "HEAD"]);
    let dirty =
        // --no-optional-locks: status must not refresh (write) the index watched below.
        commit.is_some()
            && git(&[
                "--no-optional-locks",
                "status",
                "--porcelain",
                "--untracked-files=no",
            ])
            .is_some();
    let text = match commit {
        Some(c) if dirty => format!("{c}-dirty"),
        Some(c) => c,
        None => "unknown".into(),
    };
    println!("cargo:rustc-env=PDW_GIT_COMMIT={text}");
    println!(
        "cargo:rustc-env=PDW_BUILD_PROFILE={}",
        std::env::var("PROFILE").unwrap_or_else(|_| "unknown".into())
    );
    // Rebuild when HEAD moves (a commit, a checkout) or the index changes (staging, which
    // also follows most edits that matter for `-dirty`).
    for p in ["HEAD", "index"] {
        if let Some(f) = git(&["rev-parse", "--git-path", p]) {
            println!("cargo:rerun-if-changed={f}");
        }
    }
    if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
        if let Some(f) = git(&["rev-parse", "--git-path", &r]) {
            println!("cargo:rerun-if-changed={f}");
        }
    }
    println!("cargo:rerun-if-changed=build.rs");
}
