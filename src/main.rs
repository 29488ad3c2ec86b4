//! The `genpath` command line: argument parsing and dispatch; each command is a file in
//! `cli/`.

mod cli;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use cli::{bench, check, compare, learn, merge, reference, render, settings, sweep};

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
    /// Learn a method's state (pg, ga, ga-pt: the GA plan, the spatial guide) once, as
    /// `render` would, and save it in a plan file for `render --plan` (docs/shards.md).
    ///
    /// Takes the scene and method flags and --spp of the render it is for; a render with
    /// --plan and other settings, scene, size, seed or build is refused.
    Learn(learn::LearnArgs),
    /// Merge shards of one render (`render --shard K/N`, `reference --shard K/N`) into its
    /// image (docs/shards.md).
    ///
    /// Their per-pixel sums and sample counts are added; any subset of the shards gives an
    /// image with fewer samples.
    Merge(merge::MergeArgs),
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
    /// Every method setting with its one name, flag, default and meaning (docs/settings.md
    /// is this output), or with --toml the defaults as a file for --config.
    Settings(settings::SettingsCommandArgs),
}

fn main() {
    // The matches tell which settings were given on the command line (the rest come from
    // --config or the defaults).
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let sub = matches.subcommand().map_or(&matches, |(_, m)| m);
    let result = match cli.command {
        Command::Render(args) => render::run_render(args, sub),
        Command::Learn(args) => learn::run_learn(args, sub),
        Command::Merge(args) => merge::run_merge(args),
        Command::Compare(args) => compare::run_compare(args),
        Command::Reference(args) => reference::run_reference(args, sub),
        Command::Sweep(args) => sweep::run_sweep(args, sub),
        Command::Bench(args) => bench::run_bench(args, sub),
        Command::Check(args) => check::run_check(args),
        Command::Settings(args) => settings::run_settings(args),
    };
    if let Err(error) = result {
        if let Some(stopped) = error.downcast_ref::<cli::resume::Interrupted>() {
            eprintln!("genpath: {stopped}");
            std::process::exit(stopped.exit_code());
        }
        if let Some(stopped) = error.downcast_ref::<cli::resume::LearnInterrupted>() {
            eprintln!("genpath: {stopped}");
            std::process::exit(stopped.exit_code());
        }
        eprintln!("genpath: error: {error:#}");
        std::process::exit(1);
    }
}

/// docs/cli.md: every command's `--help`, as clap renders it from this file's and `cli/`'s
/// definitions.
#[cfg(all(
    test,
    feature = "embree",
    feature = "obvhs",
    feature = "oiio",
    feature = "testing"
))]
fn cli_markdown() -> String {
    let mut command = Cli::command().term_width(100);
    let mut out = String::from(
        "# Command line\n\nGenerated from the code by `GENPATH_WRITE_DOCS=1 cargo test --bin genpath`; \
         do not edit. Every command that renders takes the scene options (`-D NAME=VALUE` for Mitsuba XML scenes, `--max-bounces`, \
         `--seed`, `--threads`, `--accel`, `--width`, `--height`, `--quiet`); the method \
         settings are in [settings.md](settings.md). Errors (a malformed scene, a missing \
         file, a NaN vertex, a scene without emitters, an unwritable output, an impossible \
         flag) name the file, line and field, exit with status 1, and leave no output: files \
         are written under a temporary name and renamed.\n",
    );
    let help = command.render_long_help().to_string();
    out.push_str(&format!(
        "\n## genpath\n\n```text\n{}\n```\n",
        help.trim_end()
    ));
    for sub in command.get_subcommands_mut() {
        let name = sub.get_name().to_string();
        let help = sub.render_long_help().to_string();
        out.push_str(&format!(
            "\n## genpath {name}\n\n```text\n{}\n```\n",
            help.trim_end()
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clap's own consistency checks (duplicate names, defaults that fail their parsers).
    #[test]
    fn command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    /// docs/cli.md is the help the code renders; `GENPATH_WRITE_DOCS=1` rewrites it. The
    /// help depends on the features (the default back-end, the test-only method): checked
    /// in the build with all of them.
    #[cfg(all(
        feature = "embree",
        feature = "obvhs",
        feature = "oiio",
        feature = "testing"
    ))]
    #[test]
    fn cli_documentation_is_generated_from_the_code() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/cli.md");
        let text = cli_markdown();
        if std::env::var_os("GENPATH_WRITE_DOCS").is_some() {
            std::fs::write(&path, &text).unwrap();
        }
        let docs = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            docs == text,
            "docs/cli.md is stale: GENPATH_WRITE_DOCS=1 cargo test --profile release-tests --all-features --bin genpath"
        );
    }
}
