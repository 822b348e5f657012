//! `pdw-sweep design`: search free design parameters of a walker for the most robust (or most
//! stable) passive gait that is physically valid along the whole stride; every evaluated
//! design in an HDF5 file that a rerun continues. The plan, the search, the files and the
//! report are [`pdw::design_command`]'s; this file turns the options into its input, shows the
//! progress and prints the report.

use crate::cli::DesignArgs;
use pdw::design_command::DesignInput;
use pdw::pipeline::Spelling;
use std::process::ExitCode;

pub fn run(a: &DesignArgs) -> anyhow::Result<ExitCode> {
    let input = DesignInput {
        model: super::choice(&a.model),
        free: a.free.clone(),
        objective: a.objective.name().to_string(),
        budget: a.budget as i64,
        seed: a.seed,
        init: a.init,
        starts: a.starts as i64,
        mu: a.mu,
        knee_margin: a.knee_margin,
        min_margin: a.min_margin,
        basin_grid: a.basin_grid as i64,
        basin_box: a.basin_box,
        max_strides: i64::from(a.max_strides),
        out: Some(a.out.clone()),
        png: a.png.clone(),
        threads: a.threads,
        force: a.force,
        command: super::command_line(),
    };
    let run =
        pdw::design_command::plan(&input, Spelling::Cli)?.run(&super::sink::Bar::new(a.quiet))?;
    super::print_report(&run.report, a.json)?;
    if let Some(b) = &run.report.best {
        for w in &b.on_bound {
            eprintln!("warning: {w}");
        }
    }
    Ok(if run.report.feasible() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
