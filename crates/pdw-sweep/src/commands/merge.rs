//! `pdw-sweep merge`: join the shard files of one basin run into one file (a copy; see
//! `pdw::store::shard` for why not a virtual dataset), with whole-grid metrics and the PNG.

use super::basin::store_metrics;
use super::output::{Format, Input, Output};
use crate::cli::MergeArgs;
use pdw::limit::basin::{basin_metrics_slices, DEFAULT_ENTROPY_BOX};
use pdw::store::{merge, plot_basin_attractors, read_basin, BasinHeader, BasinMetrics};
use std::process::ExitCode;

pub fn run(a: &MergeArgs) -> anyhow::Result<ExitCode> {
    let png = a.png.clone().unwrap_or_else(|| a.out.with_extension("png"));
    let inputs: Vec<&std::path::Path> = a.shards.iter().map(|p| p.as_path()).collect();
    let shard_inputs: Vec<Input> = inputs
        .iter()
        .map(|p| Input {
            flag: "shard",
            path: p,
        })
        .collect();
    let _claim = super::output::claim(
        &[
            Output {
                flag: "--out",
                path: &a.out,
                format: Format::Hdf5,
                may_exist: false,
            },
            Output {
                flag: "--png",
                path: &png,
                format: Format::Png,
                may_exist: false,
            },
        ],
        &shard_inputs,
        a.force,
    )?;
    check_same_numerics(&inputs, a.force)?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let mut failure: Option<String> = None;
    // the claim refused an existing --out without --force; its placeholder is replaced
    let header = merge(&a.shards, &a.out, true, &command, |h, outcome| {
        let flat: Vec<u8> = outcome.iter().copied().collect();
        match basin_metrics_slices(&flat, h.nx(), h.ny(), h.nz(), DEFAULT_ENTROPY_BOX) {
            Ok(m) => store_metrics(&m, &h.legend, h.nx(), h.ny()),
            Err(e) => {
                failure = Some(e.to_string());
                BasinMetrics {
                    fractions: Vec::new(),
                    basin_entropy: f64::NAN,
                    boundary_entropy: f64::NAN,
                    entropy_box: DEFAULT_ENTROPY_BOX,
                }
            }
        }
    })?;
    if let Some(f) = failure {
        anyhow::bail!("metrics of the merged grid: {f}");
    }
    // Provenance: the merge's own, each shard's kept in /provenance/shards; the shards' units
    // and slice; the grid's dimension scales.
    let mut prov = super::provenance(serde_json::json!({
        "shards": a.shards.len(),
        "entropy_box": DEFAULT_ENTROPY_BOX,
    }));
    // the shards' resolved walker spec (one model: their headers agree), so the merged file
    // rebuilds a user's own walker as each shard does
    prov.model_spec = pdw::store::provenance::read_model_spec(&a.shards[0])?.unwrap_or_default();
    pdw::store::provenance::annotate_merged(&a.out, &inputs, &prov)?;
    draw(&a.out, &png, &header)?;
    let nz = header
        .z
        .as_ref()
        .map_or(String::new(), |z| format!("x{}", z.values.len()));
    crate::outln!(
        "merged {} shard(s) into {} ({}x{}{nz} cells) and {}",
        a.shards.len(),
        a.out.display(),
        header.nx(),
        header.ny(),
        png.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The merged file's picture (a 3-D grid's: its middle z-slice, recorded in `/slice`).
fn draw(out: &std::path::Path, png: &std::path::Path, header: &BasinHeader) -> anyhow::Result<()> {
    let data = read_basin(out)?;
    let slice = pdw::store::provenance::read_slice(out)?;
    // Orbit points are drawn only where the slice passes through the gait (files without
    // /slice: as before): off the slice their projection would mislead.
    let on_slice = slice.as_ref().is_none_or(|s| s.on_fixed_point);
    let shown: &[_] = if on_slice { &data.attractors } else { &[] };
    let mut labelled = header.clone();
    for (name, ds) in [
        (&mut labelled.x_name, "grid/x"),
        (&mut labelled.y_name, "grid/y"),
    ] {
        if let Some(u) = pdw::store::provenance::read_units(out, ds)? {
            *name = format!("{name} [{u}]");
        }
    }
    let (view, label) = match &header.z {
        Some(z) => {
            let unit = pdw::store::provenance::read_units(out, "grid/z")?.unwrap_or_default();
            let k = z.values.len() / 2;
            let (view, label) = super::basin::slice_view(out, header, &data.outcome, k, &unit)?;
            (view, Some(label))
        }
        None => (data.outcome.clone(), None),
    };
    let title = match &slice {
        Some(s) => format!(
            "{} (merged)",
            super::basin::basin_title(
                &header.model,
                header.slope,
                header.max_strides,
                s,
                label.as_deref()
            )
        ),
        None => format!(
            "{} walker basin, slope {} rad (merged)",
            header.model, header.slope
        ),
    };
    plot_basin_attractors(png, &labelled, view.view(), shown, &title)?;
    Ok(())
}

/// Shards written by different builds (crate version, git commit) or numeric contracts may
/// differ in the last bit of a state, so a cell on a basin boundary could be labelled
/// differently by each: refuse to join them unless `--force`. Every instruction-set path of one
/// build gives the same bits (tested), so differing `simd_path`s alone are accepted.
fn check_same_numerics(shards: &[&std::path::Path], force: bool) -> anyhow::Result<()> {
    let provs = pdw::store::provenance::shard_provenance(shards)?;
    let key = |p: &Option<pdw::store::Provenance>| {
        p.as_ref().map(|p| {
            (
                p.crate_version.clone(),
                p.git_commit.clone(),
                p.numerics.clone(),
            )
        })
    };
    let first = key(&provs[0]);
    let odd: Vec<String> = shards
        .iter()
        .zip(&provs)
        .filter(|(_, p)| key(p) != first)
        .map(|(s, p)| match p {
            Some(p) => format!(
                "{} (version {}, commit {}, numerics '{}')",
                s.display(),
                p.crate_version,
                p.git_commit,
                p.numerics
            ),
            None => format!("{} (no provenance)", s.display()),
        })
        .collect();
    if odd.is_empty() || force {
        if !odd.is_empty() {
            eprintln!(
                "warning: --force: joining shards from different builds: {}",
                odd.join("; ")
            );
        }
        return Ok(());
    }
    let f = match &provs[0] {
        Some(p) => format!(
            "version {}, commit {}, numerics '{}'",
            p.crate_version, p.git_commit, p.numerics
        ),
        None => "no provenance".into(),
    };
    Err(crate::args::InputError(format!(
        "shards come from different builds, whose numbers may differ in the last bit: {} has \
         {f}; differing: {}. Recompute them with one build, or pass --force to join them anyway",
        shards[0].display(),
        odd.join("; ")
    ))
    .into())
}
