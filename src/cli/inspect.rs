//! `appell inspect FILE...`: what a recording holds and every option still missing to read it
//! as the rig, said at once, with the commands to run.

use super::Failure;
use anyhow::anyhow;
use appell::data::inspect::inspect;
use appell::data::{detect, Format, ReadOptions};
use appell::pipeline::RecordingArgs;
use appell::report::inspect::{inspect_json, inspect_text, rig_template};
use std::path::{Path, PathBuf};

/// Arguments of `appell inspect`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Recording file(s), or a directory of recordings: each is reported in turn; Tracker files
    /// given one after another are one recording (one file per marker), as `convert` reads them.
    #[arg(required = true, num_args = 1.., value_name = "FILE")]
    files: Vec<PathBuf>,
    /// Print one JSON object per recording (one a line), for scripts.
    #[arg(long)]
    json: bool,
    /// Write a rig file for the recording to this path (the one the text shows under "rig
    /// file"): the `[rig]` keys a lab measures, with what the file tells filled in and upper-case
    /// placeholders for the rest. An existing file is not overwritten.
    #[arg(long, value_name = "RIG.toml")]
    rig_template: Option<PathBuf>,
    /// Recording flags already known (`--fps 100`, `--slider NAME`): used in the reading and
    /// carried into the suggested commands.
    #[command(flatten)]
    recording: RecordingArgs,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let opts = args
        .recording
        .resolve()
        .map_err(|e| Failure::Input(anyhow!(e)))?;
    let mut files = Vec::new();
    for f in &args.files {
        if f.is_dir() {
            files.extend(super::fit::directory_files(f, opts.format.is_some())?);
        } else {
            files.push(f.clone());
        }
    }
    let groups = recordings(&files, &opts);
    if let Some(out) = &args.rig_template {
        super::refuse_input(Some(out), &files)?;
        if out.symlink_metadata().is_ok() {
            return Err(Failure::Input(anyhow!(
                "{}: exists, not overwritten (a rig file holds the lab's measurements): remove it or give another name",
                out.display()
            )));
        }
        if groups.len() != 1 {
            return Err(Failure::Input(anyhow!(
                "--rig-template writes the rig file of one recording; {} were given",
                groups.len()
            )));
        }
    }
    if let [one] = groups.as_slice() {
        let ins = inspect(one, &opts).map_err(|e| Failure::Input(e.into()))?;
        print(&ins, args.json);
        // Described as far as it goes, and refused as convert refuses it.
        if let Some(why) = &ins.refused {
            return Err(Failure::Input(anyhow!("{why}")));
        }
        if let Some(out) = &args.rig_template {
            write_template(&ins, out)?;
        }
        return Ok(());
    }
    let mut failed = 0;
    for (k, group) in groups.iter().enumerate() {
        if k > 0 && !args.json {
            outln!();
        }
        match inspect(group, &opts) {
            Ok(ins) => {
                print(&ins, args.json);
                if let Some(why) = &ins.refused {
                    failed += 1;
                    note!("error: {why}");
                }
            }
            Err(e) => {
                failed += 1;
                note!("error: {e}");
            }
        }
    }
    if failed > 0 {
        return Err(Failure::Input(anyhow!(
            "{failed} of {} recordings could not be inspected or are refused (their errors are above)",
            groups.len()
        )));
    }
    Ok(())
}

/// Write the recording's rig file to `out`, never over an existing file: a rig file holds a
/// lab's measurements.
fn write_template(ins: &appell::data::inspect::Inspection, out: &Path) -> Result<(), Failure> {
    if !ins.rig.looks_like_rig {
        return Err(Failure::Input(anyhow!(
            "{}: no rig file written: no pair of markers moves like a slider and a bob ({})",
            out.display(),
            ins.rig.why
        )));
    }
    let text = rig_template(ins);
    appell::output::write_atomic(out, |w| w.write_all(text.as_bytes()))
        .map_err(|e| Failure::Run(anyhow!("{}: cannot write: {e}", out.display())))?;
    note!(
        "wrote {}: replace its upper-case values with the rig's masses and rod length as measured, then run the fit command above",
        out.display()
    );
    Ok(())
}

fn print(ins: &appell::data::inspect::Inspection, json: bool) {
    if json {
        outln!("{}", inspect_json(ins));
    } else {
        out!("{}", inspect_text(ins));
    }
}

/// The recordings among the files: Tracker files in a row are one (a file per marker, as
/// `convert` joins them); any other file is one by itself, as is a file whose format cannot be
/// told (its reading then says why).
fn recordings(files: &[PathBuf], opts: &ReadOptions) -> Vec<Vec<PathBuf>> {
    let tracker =
        |f: &PathBuf| opts.format.map_or_else(|| detect(f).ok(), Some) == Some(Format::Tracker);
    let mut groups: Vec<Vec<PathBuf>> = Vec::new();
    let mut last_tracker = false;
    for f in files {
        let t = tracker(f);
        match groups.last_mut() {
            Some(g) if t && last_tracker => g.push(f.clone()),
            _ => groups.push(vec![f.clone()]),
        }
        last_tracker = t;
    }
    groups
}
