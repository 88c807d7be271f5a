//! `robokrige demo`: the whole job on the default COMAU campaign, in about a
//! minute — fit JS and EJS, compare the papers' methods by 10-fold CV,
//! compensate the Ø100 mm circle and the 30 verification poses on the
//! simulated robot, and diagnose a campaign with an undeclared effect.
//! Writes the data, models, SVG plots and a Markdown report to a folder.

use super::progress::{steps, with_bar};
use clap::Args;
use robokrige::Result;
use robokrige::demo::{Demo, run_demo};
use robokrige::plot::demo_plots;
use robokrige::report::demo as report;
use std::path::PathBuf;
use std::time::Instant;

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
    Demo::create_folders(out)?;
    let report_md = out.join("report.md");
    super::check_files(&[], &[Some(report_md.as_path()), a.json.as_deref()])?;
    let (demo, secs) = with_bar(robokrige::demo::STEPS as u64 + 2, "demo", |pb| {
        let demo = run_demo(&Default::default(), &steps(pb))?;
        pb.set_message("writing the data, models and plots");
        demo.write_files(out)?;
        let figures = demo_plots(&demo, &out.join("plots"))?;
        pb.inc(1);
        pb.set_message("writing the report");
        let secs = t0.elapsed().as_secs_f64();
        let report = report::markdown(&demo, &figures, secs, out);
        robokrige::output::write_text(&report_md, &report)?;
        pb.inc(1);
        Ok::<_, robokrige::Error>((demo, secs))
    })?;
    say_part!("{}", report::summary(&demo, secs));
    let v = report::json(&demo, out, secs);
    super::json_to(a.json.as_deref(), &v, "demo summary")?;
    say!(
        "\nwrote {} (report.md, plots/, models/, data/)",
        out.display()
    );
    Ok(())
}
