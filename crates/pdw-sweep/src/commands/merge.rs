//! `pdw-sweep merge`: join the shard files of one basin run into one file (a copy; see
//! `pdw_store::shard` for why not a virtual dataset), with whole-grid metrics and the PNG.

use super::basin::store_metrics;
use crate::cli::MergeArgs;
use pdw_limit::basin::{basin_metrics, DEFAULT_ENTROPY_BOX};
use pdw_store::{merge, plot_basin, read_basin, BasinMetrics};
use std::process::ExitCode;

pub fn run(a: &MergeArgs) -> anyhow::Result<ExitCode> {
    let png = a.png.clone().unwrap_or_else(|| a.out.with_extension("png"));
    let inputs: Vec<&std::path::Path> = a.shards.iter().map(|p| p.as_path()).collect();
    crate::args::check_outputs(
        &[
            crate::args::Output {
                flag: "--out",
                path: &a.out,
                may_exist: false,
            },
            crate::args::Output {
                flag: "--png",
                path: &png,
                may_exist: false,
            },
        ],
        &inputs,
        a.force,
    )?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let mut failure: Option<String> = None;
    let header = merge(&a.shards, &a.out, a.force, &command, |h, outcome| {
        let flat: Vec<u8> = outcome.iter().copied().collect();
        match basin_metrics(&flat, h.nx(), h.ny(), DEFAULT_ENTROPY_BOX) {
            Ok(m) => store_metrics(&m, h.nx(), h.ny()),
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
    let prov = super::provenance(serde_json::json!({
        "shards": a.shards.len(),
        "entropy_box": DEFAULT_ENTROPY_BOX,
    }));
    pdw_store::provenance::annotate_merged(&a.out, &inputs, &prov)?;
    let data = read_basin(&a.out)?;
    let marker = data
        .attractors
        .first()
        .and_then(|at| at.section.first())
        .and_then(|s| {
            let ix = header
                .state_names
                .iter()
                .position(|n| *n == header.x_name)?;
            let iy = header
                .state_names
                .iter()
                .position(|n| *n == header.y_name)?;
            Some((s[ix], s[iy]))
        });
    let slice = pdw_store::provenance::read_slice(&a.out)?;
    // The gait is drawn only where it lies on the slice (files without /slice: as before).
    let marker = marker.filter(|_| slice.as_ref().is_none_or(|s| s.on_fixed_point));
    let title = match &slice {
        Some(s) => format!(
            "{} (merged)",
            super::basin::basin_title(&header.model, header.slope, header.max_strides, s)
        ),
        None => format!(
            "{} walker basin, slope {} rad (merged)",
            header.model, header.slope
        ),
    };
    let mut labelled = header.clone();
    for (name, ds) in [
        (&mut labelled.x_name, "grid/x"),
        (&mut labelled.y_name, "grid/y"),
    ] {
        if let Some(u) = pdw_store::provenance::read_units(&a.out, ds)? {
            *name = format!("{name} [{u}]");
        }
    }
    plot_basin(&png, &labelled, data.outcome.view(), marker, &title)?;
    crate::outln!(
        "merged {} shard(s) into {} ({}x{} cells) and {}",
        a.shards.len(),
        a.out.display(),
        header.nx(),
        header.ny(),
        png.display()
    );
    Ok(ExitCode::SUCCESS)
}
