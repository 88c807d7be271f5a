//! Config files (`robokrige.toml`) of `robokrige run`: steps, each a
//! subcommand with its options, turned into the argument list the command
//! line would give, so that a step, parsed by the same parser, does exactly
//! what its flags do.
//!
//! A step names its subcommand (`command = "fit"`, `"physics identify"`)
//! and sets options by their long names, positional arguments by their
//! names (`data`, `traj`, …). Top-level keys are defaults for every step
//! that has that option. Flags are `true`/`false`; a list repeats the
//! option. Cargo feature `cli` (the grammar is the command line's, read
//! from its `clap::Command`).

use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// Every step of the config file `path` as an argument list
/// (`robokrige SUBCOMMAND …`) for the command line `root`; a step that
/// names no subcommand of `root`, or an option its subcommand does not
/// have, is refused with the step's number.
pub fn read_steps(path: &Path, root: &clap::Command) -> Result<Vec<Vec<String>>> {
    let source = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| Error::Input {
        source_name: source.clone(),
        message: format!("not a config file: {}", e.message()),
    })?;
    steps(&table, &source, root)
}

/// The folder of the config file `path`, which its paths are relative to.
pub fn folder(path: &Path) -> PathBuf {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf()
}

/// An output path of `run` made absolute against the current folder, as
/// the run then moves into the config's folder; `-` (standard output) and
/// an absolute path stay as they are.
pub fn output_path(path: &Path) -> PathBuf {
    if crate::output::is_stdout(path) || path.is_absolute() {
        return path.to_path_buf();
    }
    std::env::current_dir().map_or_else(|_| path.to_path_buf(), |d| d.join(path))
}

/// An argument list as one shell line, each argument quoted when it needs
/// it.
pub fn command_line(argv: &[String]) -> String {
    argv.iter().map(|s| quote(s)).collect::<Vec<_>>().join(" ")
}

/// Step `step` (1-based) of the config file `source` refused by the
/// command line's parser: the first line of its message.
pub fn parse_error(source: &str, step: usize, e: &clap::Error) -> Error {
    let rendered = e.render().to_string();
    let first = rendered.lines().next().unwrap_or("");
    Error::Input {
        source_name: source.into(),
        message: format!("step {step}: {}", first.trim_start_matches("error: ")),
    }
}

/// What [`run_steps`] ran: the record of every step announced
/// ([`crate::report::run::step`]: with its wall time and error once it
/// ran), and the failure that stopped the run, if one did.
#[derive(Debug)]
pub struct StepsRun {
    /// One record per step announced, the failed one included.
    pub log: Vec<serde_json::Value>,
    /// The error that stopped the run: a step that could not be parsed or
    /// failed, named by its number and subcommand.
    pub failure: Option<Error>,
}

/// Run `steps`, the argument lists of the config file `source`, in order,
/// each announced first by `announce("step K of N: COMMAND LINE")`; with
/// `dry_run` none runs. `parse` turns a step into a command (a refusal is
/// [`parse_error`]) and `run` runs it; the first step that fails stops the
/// run. The record of what ran is kept either way, so a `--json` log can
/// say which step failed and why.
pub fn run_steps<C>(
    (source, steps): (&str, &[Vec<String>]),
    dry_run: bool,
    announce: impl Fn(&str),
    parse: impl Fn(&[String]) -> std::result::Result<C, clap::Error>,
    mut run: impl FnMut(C) -> Result<()>,
) -> StepsRun {
    let mut log = Vec::new();
    for (k, argv) in steps.iter().enumerate() {
        let line = command_line(argv);
        announce(&format!("step {} of {}: {line}", k + 1, steps.len()));
        if dry_run {
            log.push(crate::report::run::step(k + 1, argv, None));
            continue;
        }
        let command = match parse(argv) {
            Ok(c) => c,
            Err(e) => {
                let failure = Some(parse_error(source, k + 1, &e));
                return StepsRun { log, failure };
            }
        };
        let t0 = std::time::Instant::now();
        let r = run(command);
        let ran = (
            t0.elapsed().as_secs_f64(),
            r.as_ref().err().map(ToString::to_string),
        );
        log.push(crate::report::run::step(k + 1, argv, Some(ran)));
        if let Err(e) = r {
            let failure = Some(Error::Input {
                source_name: source.into(),
                message: format!("step {} ({}) failed: {e}", k + 1, argv[1]),
            });
            return StepsRun { log, failure };
        }
    }
    StepsRun { log, failure: None }
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

/// Every step's argument list (`robokrige SUBCOMMAND …`) for `root`.
fn steps(table: &toml::Table, source: &str, root: &clap::Command) -> Result<Vec<Vec<String>>> {
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
        let mut cmd = root;
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
                    // a file named `-` would run the step, then fail or
                    // write `./-`: the rule of the command line
                    if v == "-" && refuses_dash(arg) {
                        let default = if step.contains_key(key.as_str()) {
                            ""
                        } else {
                            " (a top-level default)"
                        };
                        return Err(at(format!(
                            "{key} = \"-\"{default}: {}",
                            dash_reason(key, arg)
                        )));
                    }
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
    // a top-level key no step has (a misspelt `robt`) would be dropped
    let commands: Vec<&clap::Command> = list
        .iter()
        .filter_map(|s| s.get("command")?.as_str())
        .filter_map(|name| {
            name.split_whitespace()
                .try_fold(root, |c, p| c.find_subcommand(p))
        })
        .collect();
    if let Some((key, _)) = defaults
        .iter()
        .find(|(key, _)| commands.iter().all(|c| find_arg(c, key).is_none()))
    {
        return Err(bad(format!(
            "the top-level key '{key}' is an option of none of the steps' commands \
             (top-level keys are defaults for the steps that have that option)"
        )));
    }
    Ok(out)
}

/// Why the argument list `argv` (a command line of `root`, program name
/// first) is refused, if it gives `-` to an option that may not take it
/// (every option that takes a value but `--json`): `-` is standard
/// output for the JSON reports, and nothing reads standard input. `None`
/// when it does not, or when `root` does not parse `argv` (its parser
/// then says why). The command line checks its arguments with it before
/// any work; `run` applies the same rule to every step's keys before any
/// step runs.
pub fn dash_refusal(root: &clap::Command, argv: &[String]) -> Option<String> {
    let matches = root.clone().try_get_matches_from(argv).ok()?;
    let (mut cmd, mut m) = (root, &matches);
    while let Some((name, sub)) = m.subcommand() {
        cmd = cmd.find_subcommand(name)?;
        m = sub;
    }
    let arg = cmd.get_arguments().filter(|a| refuses_dash(a)).find(|a| {
        m.try_get_raw(a.get_id().as_str())
            .ok()
            .flatten()
            .is_some_and(|mut v| v.any(|v| v == "-"))
    })?;
    let name = match arg.get_short() {
        Some(c) => format!("-{c}/--{}", long(arg)),
        None => format!("--{}", long(arg)),
    };
    Some(format!("{name} -: {}", dash_reason(&name, arg)))
}

/// Whether `arg` may not be given `-`: every option that takes a value
/// but `--json`, whose `-` is standard output.
fn refuses_dash(arg: &clap::Arg) -> bool {
    !arg.is_positional() && arg.get_action().takes_values() && arg.get_long() != Some("json")
}

/// Why the option `name` (`arg`) may not be `-`: a file option would
/// write or read a file named `-`; any other takes a value of its own.
fn dash_reason(name: &str, arg: &clap::Arg) -> String {
    if arg.get_value_parser().type_id() == std::any::TypeId::of::<PathBuf>() {
        format!(
            "'-' would be a file named '-': only the --json reports go to standard output (--json -), and no input is read from it; give {name} a path"
        )
    } else {
        format!("'-' is standard output, which only --json takes; give {name} its value")
    }
}

/// The argument of `cmd` a config key names: its id or its long name.
fn find_arg<'a>(cmd: &'a clap::Command, key: &str) -> Option<&'a clap::Arg> {
    let id = key.replace('-', "_");
    cmd.get_arguments()
        .find(|a| a.get_id() == id.as_str() || a.get_long() == Some(key))
}

/// The long name of an option (its id, dashed, if it has none).
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
