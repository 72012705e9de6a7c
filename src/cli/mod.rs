//! Command-line interface: clap derive structs that only parse, and one function per
//! command that calls the library and prints.

/// `println!` that ends the process quietly when stdout is closed (`appell ... | head`),
/// instead of panicking on the broken pipe.
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout().lock(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

/// `print!` with the same broken-pipe handling as `outln!`.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if write!(std::io::stdout().lock(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

mod bench;
mod convert;
mod fit;
mod plan;
pub mod recording_args;
mod regions;
mod simulate;
mod synth;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Simulate, fit and plan experiments on a Painleve-Appell friction rig.
#[derive(Debug, Parser)]
#[command(name = "appell", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Fit mu and the initial state to a recording (or a directory of recordings).
    Fit(fit::Args),
    /// Simulate a scene and print its event timeline.
    Simulate(simulate::Args),
    /// Time the simulator on a scene (median of repeats), or run the work-precision
    /// benchmark (run time against error per integrator and tolerance).
    Bench(bench::Args),
    /// Regions of the stick and sliding models in the (theta, theta') plane, the paradox
    /// band, and phase portraits.
    Regions(regions::Args),
    /// Read a recording (CSV family or MCAP) and write the canonical wide CSV.
    Convert(convert::Args),
    /// Write a synthetic recording of a scene (CSV or MCAP) with noise, dropouts, outliers.
    Synth(synth::Args),
    /// Plan releases that make the wanted mode transitions observable, ranked by how well
    /// they pin down mu.
    Plan(plan::Args),
}

/// A failed command: bad input (exit code 2) or a run that could not finish (exit code 1).
#[derive(Debug)]
pub enum Failure {
    /// The user's input is unusable: a file, a key, a value.
    Input(anyhow::Error),
    /// The input was fine but the computation failed (numerics, I/O on output).
    Run(anyhow::Error),
}

impl Failure {
    fn code(&self) -> u8 {
        match self {
            Failure::Input(_) => 2,
            Failure::Run(_) => 1,
        }
    }
}

/// Refuse, as bad input (exit 2), an output path that names one of the command's inputs.
fn refuse_input<P: AsRef<std::path::Path>>(
    output: Option<&std::path::Path>,
    inputs: &[P],
) -> Result<(), Failure> {
    match output {
        Some(out) => appell::output::refuse_input(out, inputs)
            .map_err(|e| Failure::Input(anyhow::anyhow!(e))),
        None => Ok(()),
    }
}

/// Parse arguments, run the command, print errors with their causes.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    appell::output::remove_temporaries_on_signal();
    let result = match cli.command {
        Command::Fit(args) => fit::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Regions(args) => regions::run(args),
        Command::Convert(args) => convert::run(args),
        Command::Synth(args) => synth::run(args),
        Command::Plan(args) => plan::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            let (Failure::Input(e) | Failure::Run(e)) = &failure;
            let messages = messages(e);
            eprintln!("error: {}", messages[0]);
            for cause in &messages[1..] {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::from(failure.code())
        }
    }
}

/// The messages of an error and its causes, leaving out a cause whose message the one before
/// it already contains (errors that print their source, as most of the library's do), so
/// nothing is said twice. Never empty.
pub fn messages(e: &anyhow::Error) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for cause in e.chain() {
        let m = cause.to_string();
        if !out.last().is_some_and(|prev| prev.contains(&m)) {
            out.push(m);
        }
    }
    out
}
