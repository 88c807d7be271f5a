//! Subcommands. Exit codes: 0 ok, 1 failed (bad data, numerical failure),
//! 2 bad usage (clap).

mod simulate;

use clap::{Parser, Subcommand};

/// robokrige: Kriging error models over the extended joint space [θ, λ] for
/// industrial robot accuracy.
#[derive(Debug, Parser)]
#[command(name = "robokrige", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate a laser-tracker campaign on a "true robot" (geometric errors,
    /// backlash, compliance, noise, optional undeclared effects).
    Simulate(simulate::SimulateArgs),
}

/// Run a parsed command.
pub fn run(cli: Cli) -> robokrige::Result<()> {
    match cli.command {
        Command::Simulate(a) => simulate::run(a),
    }
}
