//! `pdw-sweep merge`: join the shard files of one basin run into one file (a copy; see
//! `pdw_store::shard` for why not a virtual dataset), with whole-grid metrics and the PNG.

use super::basin::store_metrics;
use crate::cli::MergeArgs;
use pdw_limit::basin::{basin_metrics, DEFAULT_ENTROPY_BOX};
use pdw_store::{merge, plot_basin_attractors, read_basin, BasinMetrics};
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
    let data = read_basin(&a.out)?;
    let title = format!(
        "{} walker basin, slope {} rad (merged)",
        header.model, header.slope
    );
    plot_basin_attractors(&png, &header, data.outcome.view(), &data.attractors, &title)?;
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
