//! `run CONFIG`: repeatable runs from a config file. Each step is a
//! subcommand with its options, turned into the same argument list the
//! command line would give and parsed by the same parser, so a step does
//! exactly what the flags do.

use clap::{Args, CommandFactory, Parser};
use robokrige::{Error, Result};
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
#[command(after_help = "\
The config file (TOML) lists steps; each names a subcommand and sets its
options by their long names (positional arguments by their names: data,
traj, export, …). Top-level keys are defaults for every step that has that
option. Paths are relative to the config file's folder. Flags are true/false;
a list repeats the option.

Example robokrige.toml:
  data = \"datasets/comau_lhs.csv\"     # every step that takes `data`
  robot = \"comau-nj220\"

  [[step]]
  command = \"fit\"
  output = \"model.json\"

  [[step]]
  command = \"cv\"
  folds = 10
  json = \"cv.json\"

  [[step]]
  command = \"compensate\"
  model = \"model.json\"
  traj = \"datasets/comau_circle.csv\"
  output = \"circle_comp.csv\"
  iterative = true

Example:
  robokrige run robokrige.toml            # run the steps in order
  robokrige run robokrige.toml --dry-run  # print the equivalent command lines")]
pub struct RunArgs {
    /// The config file (TOML).
    config: PathBuf,
    /// Print each step's command line without running it.
    #[arg(long)]
    dry_run: bool,
    /// Write what ran (each step's command line and outcome) as JSON to FILE
    /// ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(a: RunArgs) -> Result<()> {
    let source = a.config.display().to_string();
    let text = std::fs::read_to_string(&a.config).map_err(|e| Error::io(&a.config, e))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| Error::Input {
        source_name: source.clone(),
        message: format!("not a config file: {}", e.message()),
    })?;
    let steps = steps(&table, &source)?;
    let folder = a
        .config
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let json_out = a.json.as_ref().map(|p| {
        if super::is_stdout(p) || p.is_absolute() {
            p.clone()
        } else {
            std::env::current_dir()
                .map(|d| d.join(p))
                .unwrap_or_else(|_| p.clone())
        }
    });
    std::env::set_current_dir(&folder).map_err(|e| Error::io(&folder, e))?;
    let mut log = Vec::new();
    for (k, argv) in steps.iter().enumerate() {
        let line = argv.iter().map(|s| quote(s)).collect::<Vec<_>>().join(" ");
        say!("step {} of {}: {line}", k + 1, steps.len());
        if a.dry_run {
            log.push(serde_json::json!({"step": k + 1, "command": argv}));
            continue;
        }
        let cli = super::Cli::try_parse_from(argv).map_err(|e| Error::Input {
            source_name: source.clone(),
            message: format!(
                "step {}: {}",
                k + 1,
                e.render()
                    .to_string()
                    .lines()
                    .next()
                    .unwrap_or("")
                    .trim_start_matches("error: ")
            ),
        })?;
        let t0 = std::time::Instant::now();
        let r = super::dispatch(cli.command);
        let secs = t0.elapsed().as_secs_f64();
        log.push(serde_json::json!({
            "step": k + 1, "command": argv, "seconds": secs,
            "error": r.as_ref().err().map(ToString::to_string),
        }));
        if let Err(e) = r {
            return Err(Error::Input {
                source_name: source.clone(),
                message: format!("step {} ({}) failed: {e}", k + 1, argv[1]),
            });
        }
    }
    if let Some(p) = &json_out {
        let v = serde_json::json!({"config": a.config, "folder": folder, "steps": log});
        super::write_json(p, &v, "run log")?;
    }
    Ok(())
}

/// Shell-quote an argument when it needs it (for the printed command lines).
fn quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./,:=+".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// Every step's argument list (`robokrige SUBCOMMAND …`).
fn steps(table: &toml::Table, source: &str) -> Result<Vec<Vec<String>>> {
    let bad = |message: String| Error::Input {
        source_name: source.into(),
        message,
    };
    let Some(toml::Value::Array(list)) = table.get("step") else {
        return Err(bad(
            "no [[step]] (each step names a command and its options)".into(),
        ));
    };
    let defaults: Vec<(&String, &toml::Value)> =
        table.iter().filter(|(k, _)| k.as_str() != "step").collect();
    let root = super::Cli::command();
    let mut out = Vec::new();
    for (k, step) in list.iter().enumerate() {
        let at = |m: String| bad(format!("step {}: {m}", k + 1));
        let toml::Value::Table(step) = step else {
            return Err(at("expected a table".into()));
        };
        let Some(toml::Value::String(name)) = step.get("command") else {
            return Err(at(
                "no command = \"…\" (e.g. \"fit\", \"physics identify\")".into(),
            ));
        };
        let path: Vec<&str> = name.split_whitespace().collect();
        if matches!(path.first(), Some(&"run")) {
            return Err(at("a config cannot run another config".into()));
        }
        let mut cmd = &root;
        for p in &path {
            cmd = cmd
                .find_subcommand(p)
                .ok_or_else(|| at(format!("no subcommand '{name}'")))?;
        }
        let mut argv: Vec<String> = std::iter::once("robokrige".to_string())
            .chain(path.iter().map(|s| s.to_string()))
            .collect();
        let mut positional: Vec<(usize, String)> = Vec::new();
        let mut options: Vec<String> = Vec::new();
        let given = step.iter().filter(|(key, _)| key.as_str() != "command");
        let inherited = defaults
            .iter()
            .copied()
            .filter(|(key, _)| !step.contains_key(key.as_str()) && find_arg(cmd, key).is_some());
        for (key, value) in given.chain(inherited) {
            let arg = find_arg(cmd, key).ok_or_else(|| {
                let known: Vec<String> = cmd
                    .get_arguments()
                    .filter(|a| a.get_id() != "help")
                    .map(|a| a.get_id().to_string())
                    .collect();
                at(format!(
                    "{name} has no option '{key}' (it has: {})",
                    known.join(", ")
                ))
            })?;
            let values = scalars(value).map_err(|m| at(format!("{key}: {m}")))?;
            if arg.is_positional() {
                let index = arg.get_index().unwrap_or(0);
                for v in values {
                    positional.push((index, v));
                }
            } else if !arg.get_action().takes_values() {
                match value {
                    toml::Value::Boolean(true) => options.push(format!("--{}", long(arg))),
                    toml::Value::Boolean(false) => {}
                    _ => return Err(at(format!("{key} is a flag: true or false"))),
                }
            } else {
                for v in values {
                    options.push(format!("--{}", long(arg)));
                    options.push(v);
                }
            }
        }
        positional.sort_by_key(|(i, _)| *i);
        argv.extend(positional.into_iter().map(|(_, v)| v));
        argv.extend(options);
        out.push(argv);
    }
    Ok(out)
}

fn find_arg<'a>(cmd: &'a clap::Command, key: &str) -> Option<&'a clap::Arg> {
    let id = key.replace('-', "_");
    cmd.get_arguments()
        .find(|a| a.get_id() == id.as_str() || a.get_long() == Some(key))
}

fn long(arg: &clap::Arg) -> String {
    arg.get_long()
        .map_or_else(|| arg.get_id().to_string().replace('_', "-"), String::from)
}

/// A value as command-line words: a scalar is one, a list is one per item.
fn scalars(v: &toml::Value) -> std::result::Result<Vec<String>, String> {
    match v {
        toml::Value::String(s) => Ok(vec![s.clone()]),
        toml::Value::Integer(i) => Ok(vec![i.to_string()]),
        toml::Value::Float(f) => Ok(vec![f.to_string()]),
        toml::Value::Boolean(b) => Ok(vec![b.to_string()]),
        toml::Value::Array(items) => items
            .iter()
            .map(|i| scalars(i).and_then(|w| w.into_iter().next().ok_or_else(|| "empty".into())))
            .collect(),
        _ => Err("expected a string, number, boolean or a list of them".into()),
    }
}
