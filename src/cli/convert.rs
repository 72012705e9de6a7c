//! `appell convert INPUT... OUTPUT.csv`: read any supported recording and write the canonical
//! wide CSV.

use super::Failure;
use anyhow::anyhow;
use appell::data::{read_recording, synth};
use appell::pipeline::RecordingArgs;
use std::path::PathBuf;

/// Arguments of `appell convert`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Input file(s). Formats with one marker per file (Tracker) take their files together:
    /// `appell convert tests/data/tracker_slider.txt tests/data/tracker_bob.txt out.csv`.
    #[arg(required = true, num_args = 1.., value_name = "INPUT")]
    inputs: Vec<PathBuf>,
    /// The canonical CSV to write (last).
    #[arg(required = true, value_name = "OUTPUT.csv")]
    output: PathBuf,
    #[command(flatten)]
    recording: RecordingArgs,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let opts = args
        .recording
        .resolve()
        .map_err(|e| Failure::Input(anyhow!(e)))?;
    let (output, inputs) = (&args.output, &args.inputs);
    super::refuse_input(Some(output), inputs)?;
    let rec = read_recording(inputs, &opts).map_err(|e| Failure::Input(e.into()))?;
    let quiet = appell::output::names_stdout(output);
    if quiet {
        note!("{}", rec.summary().trim_end());
    } else {
        out!("{}", rec.summary());
    }
    synth::write(output, &rec, &Default::default()).map_err(|e| Failure::Run(e.into()))?;
    status!(
        quiet,
        "wrote {} frames to {} ({})",
        rec.len(),
        output.display(),
        synth::output_format(output)
    );
    Ok(())
}
