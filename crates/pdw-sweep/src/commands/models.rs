//! `pdw-sweep models`: every model, its parameters (units, defaults) and coordinates.

use crate::cli::ModelsArgs;
use pdw::walkers::models;
use std::process::ExitCode;

pub fn run(a: &ModelsArgs) -> anyhow::Result<ExitCode> {
    if let Some(name) = &a.spec {
        return match pdw::walkers::preset_text(name) {
            Some(text) => {
                crate::outln!("{}", text.trim_end());
                Ok(ExitCode::SUCCESS)
            }
            None => Err(crate::args::InputError(format!(
                "`{name}` is not a chain-walker preset; presets with a spec file: {}",
                pdw::walkers::PRESETS
                    .iter()
                    .map(|p| p.0)
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
            .into()),
        };
    }
    let all = models();
    // What the coordinates and modes mean, from each model built at its defaults.
    let described: Vec<(Vec<String>, Vec<String>)> = all
        .iter()
        .map(|m| {
            pdw::walkers::build(&m.name, &[])
                .map(|w| (w.coordinate_meanings(), w.mode_names()))
                .unwrap_or_default()
        })
        .collect();
    if a.json {
        let list: Vec<serde_json::Value> = all
            .iter()
            .zip(&described)
            .map(|(m, (coords, modes))| {
                serde_json::json!({
                    "name": m.name,
                    "description": m.description,
                    "state_names": m.state_names,
                    "coordinates": coords,
                    "modes": modes,
                    "section_names": m.section_names,
                    "params": m.params.iter().map(|p| serde_json::json!({
                        "name": p.name, "unit": p.unit, "default": p.default,
                        "description": p.description,
                    })).collect::<Vec<_>>(),
                })
            })
            .collect();
        crate::outln!("{}", serde_json::to_string_pretty(&list)?);
        return Ok(ExitCode::SUCCESS);
    }
    for (m, (coords, modes)) in all.iter().zip(&described) {
        crate::outln!("{} — {}", m.name, m.description);
        crate::outln!("  state:   {}", m.state_names.join(", "));
        for (name, meaning) in m.state_names.iter().zip(coords) {
            crate::outln!("    {name:<18} {meaning}");
        }
        crate::outln!("  modes:   {}", numbered(modes));
        crate::outln!("  section: {}", m.section_names.join(", "));
        crate::outln!("  parameters:");
        for p in &m.params {
            crate::outln!(
                "    {:<14} {:>12} {:<6} {}",
                p.name,
                short(p.default),
                p.unit,
                p.description
            );
        }
        crate::outln!();
    }
    Ok(ExitCode::SUCCESS)
}

/// A default value in at most 12 characters (`0.0523598776`, not `0.05235987755982988`).
fn short(v: f64) -> String {
    let s = format!("{v}");
    if s.len() <= 12 {
        s
    } else {
        format!("{v:.10}").trim_end_matches('0').to_string()
    }
}

/// `0 = first, 1 = second`.
fn numbered(names: &[String]) -> String {
    names
        .iter()
        .enumerate()
        .map(|(k, n)| format!("{k} = {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}
