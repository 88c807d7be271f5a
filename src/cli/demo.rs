//! `robokrige demo`: the whole job on the default COMAU campaign, in about a
//! minute — fit JS and EJS, compare the papers' methods by 10-fold CV,
//! compensate the Ø100 mm circle and the 30 verification poses on the
//! simulated robot, and diagnose a campaign with an undeclared effect.
//! Writes the data, models, SVG plots and a Markdown report to a folder.

use super::progress::bar;
use clap::Args;
use robokrige::dataset::write_csv;
use robokrige::demo::run_demo;
use robokrige::plot::demo_plots;
use robokrige::report::demo as report;
use robokrige::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Run the main job on the shipped COMAU campaign and write a report.
#[derive(Debug, Args)]
#[command(after_help = "\
The campaigns are simulated in-process with the same commands as
datasets/generate.sh (so they equal the shipped files) and copied to OUT/data.

Example:
  robokrige demo -o robokrige-demo")]
pub struct DemoArgs {
    /// Output folder.
    #[arg(short, long, default_value = "robokrige-demo")]
    output: PathBuf,
    /// Also write the figures as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(a: DemoArgs) -> Result<()> {
    let t0 = Instant::now();
    let out = &a.output;
    for sub in ["data", "models", "plots"] {
        let d = out.join(sub);
        std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
    }
    let report_md = out.join("report.md");
    let outputs: Vec<&Path> = std::iter::once(report_md.as_path())
        .chain(a.json.as_deref())
        .collect();
    robokrige::output::check_outputs(&[], &outputs)?;
    let pb = bar(robokrige::demo::STEPS as u64 + 2, "demo");
    let demo = run_demo(&Default::default(), &|done, what| {
        pb.set_position(done as u64);
        pb.set_message(what.to_string());
    });
    let demo = demo.inspect_err(|_| pb.finish_and_clear())?;
    pb.set_message("writing the data, models and plots");
    write_csv(&out.join("data/comau_lhs.csv"), &demo.lhs)?;
    write_csv(&out.join("data/comau_verify.csv"), &demo.verify)?;
    demo.circle.write_csv(&out.join("data/comau_circle.csv"))?;
    write_csv(&out.join("data/comau_tracker_step.csv"), &demo.tracker_step)?;
    demo.js.save(&out.join("models/js.json"))?;
    demo.ejs.save(&out.join("models/ejs.json"))?;
    demo.ejs_ga.save(&out.join("models/ejs_ga.json"))?;
    let figures = demo_plots(&demo, &out.join("plots"))?;
    pb.inc(1);
    pb.set_message("writing the report");
    let secs = t0.elapsed().as_secs_f64();
    let report = report::markdown(&demo, &figures, secs, out);
    robokrige::output::write_text(&report_md, &report)?;
    pb.inc(1);
    pb.finish_and_clear();
    say_part!("{}", report::summary(&demo, secs));
    if let Some(path) = &a.json {
        super::write_json(path, &report::json(&demo, out, secs), "demo summary")?;
    }
    say!(
        "\nwrote {} (report.md, plots/, models/, data/)",
        out.display()
    );
    Ok(())
}
