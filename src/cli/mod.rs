//! Command-line interface: clap derive structs that only parse, and one function per
//! command that calls the library and prints.
//!
//! Every line goes out through `outln!`/`out!` (stdout) or `note!` (stderr), never
//! `println!`/`eprintln!`, which panic when the stream fails: stdout closed by its reader
//! (`appell ... | head`) ends the process quietly with exit code 0, any other stdout error (a
//! full disk) ends it with exit code 1 and the reason on stderr; a stderr that cannot be
//! written is ignored.

/// `println!` to stdout; a failed write ends the process ([`stdout_failed`]).
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout().lock(), $($t)*) {
            $crate::cli::stdout_failed(e);
        }
    }};
}

/// `print!` with the same handling of a failed write as `outln!`.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout().lock(), $($t)*) {
            $crate::cli::stdout_failed(e);
        }
    }};
}

/// `eprintln!` that ignores a stderr that cannot be written (a full disk, a closed pipe)
/// instead of panicking: the exit code still says how the command ended.
macro_rules! note {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($t)*);
    }};
}

/// A line about what a command wrote: on stdout, or on stderr (`note!`) when the output itself
/// goes to stdout (`--out -`, `/dev/stdout`), so the output stays whole.
macro_rules! status {
    ($to_stderr:expr, $($t:tt)*) => {{
        if $to_stderr {
            note!($($t)*);
        } else {
            outln!($($t)*);
        }
    }};
}

/// End the process after stdout failed: quietly with exit code 0 when its reader closed it
/// (a broken pipe: `appell ... | head` read what it wanted), else with exit code 1 and the
/// reason on stderr (a full disk: the output is incomplete).
pub fn stdout_failed(e: std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    note!("error: writing the standard output: {e}");
    std::process::exit(1);
}

mod bench;
mod convert;
mod fit;
mod inspect;
mod plan;
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

// Parsed once per process: the fit's many flags make its variant large, which costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
enum Command {
    /// What a recording holds (format, markers, times, units, which pair looks like the
    /// slider and the bob) and every option still missing, with the commands to run.
    Inspect(inspect::Args),
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
    /// they pin down mu or, with friction laws to weigh, tell the laws apart.
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
    // The main thread is one of the pool's threads: it runs its share of each parallel step
    // instead of sleeping while two others do (this machine's two cores, one thread fewer to
    // start and to wake). Only the first pool built wins; an error leaves rayon's default.
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
    appell::output::remove_temporaries_on_signal();
    let result = match cli.command {
        Command::Inspect(args) => inspect::run(args),
        Command::Fit(args) => fit::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Regions(args) => regions::run(args),
        Command::Convert(args) => convert::run(args),
        Command::Synth(args) => synth::run(args),
        Command::Plan(args) => plan::run(args),
    };
    // What is still buffered goes out now, so a full disk is an error and not exit 0.
    if let Err(e) = std::io::Write::flush(&mut std::io::stdout().lock()) {
        stdout_failed(e);
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            let (Failure::Input(e) | Failure::Run(e)) = &failure;
            // An output into a pipe its reader closed (`--out - | head`): a quiet end.
            let closed = e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            });
            if closed {
                return ExitCode::SUCCESS;
            }
            let messages = messages(e);
            note!("error: {}", messages[0]);
            for cause in &messages[1..] {
                note!("  caused by: {cause}");
            }
            ExitCode::from(failure.code())
        }
    }
}

/// The messages of an error and its causes ([`appell::pipeline::messages`]).
pub fn messages(e: &anyhow::Error) -> Vec<String> {
    appell::pipeline::messages(e)
}
