//! The `genpath` command line: argument parsing and dispatch; each command is a file in
//! `cli/`.

mod cli;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use cli::{bench, check, compare, reference, render, sweep};

#[derive(Parser)]
#[command(
    name = "genpath",
    version,
    about = "Genetic path generation: a Monte Carlo renderer that evolves per-pixel path generators"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to one or more images (format by extension: .exr, .png, …).
    Render(render::RenderArgs),
    /// Compare an image with a reference: relMSE, MSE, MAPE, fraction of NaN/Inf/negative pixels.
    Compare(compare::CompareArgs),
    /// Render a long path-tracing reference in two independent halves, with its own noise
    /// estimate (relMSE between the halves / 4) in the JSON.
    Reference(reference::ReferenceArgs),
    /// Error against run time: render methods at increasing budgets, compare each render with
    /// a reference, write PREFIX.csv and PREFIX.svg (relMSE against seconds, log-log).
    Sweep(sweep::SweepArgs),
    /// Throughput: rays/s per back-end (coherent/incoherent, single/packet), test paths and
    /// fitness evaluations per second, and render time against the number of threads.
    Bench(bench::BenchArgs),
    /// Check the numerical invariants on a scene at a small size: no NaN/Inf/negative pixel
    /// with any method, finite positive sampled densities, finite fitness values, and image
    /// means that agree with pt's. Exits with status 1 when one fails.
    Check(check::CheckArgs),
}

fn main() {
    // The matches tell which settings were given on the command line (the rest come from
    // --config or the defaults).
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let sub = matches.subcommand().map_or(&matches, |(_, m)| m);
    let result = match cli.command {
        Command::Render(args) => render::run_render(args, sub),
        Command::Compare(args) => compare::run_compare(args),
        Command::Reference(args) => reference::run_reference(args, sub),
        Command::Sweep(args) => sweep::run_sweep(args, sub),
        Command::Bench(args) => bench::run_bench(args, sub),
        Command::Check(args) => check::run_check(args),
    };
    if let Err(error) = result {
        eprintln!("genpath: error: {error:#}");
        std::process::exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clap's own consistency checks (duplicate names, defaults that fail their parsers).
    #[test]
    fn command_line_is_consistent() {
        Cli::command().debug_assert();
    }
}
