//! The files `--inspect` reads and writes, and the check before any work that no output is
//! an input file or another output (meshing and `--critical` check theirs in the library,
//! [`tptd::pipeline`]).

use anyhow::Result;
use tptd::io::{check_clashes, input_run_files, mesh_files, output_run_files, RunFile};

use crate::cli::Cli;

/// Refuses, before any sample is read, an output of the run (`--json`; the others are refused
/// with `--inspect`) that is the same file as a file of the input (`--volume` with its
/// detached data files, every file of every `--inspect` mesh) or as another output. A clash
/// is a [`tptd::io::FileClash`] (exit 2).
pub(crate) fn check_files(cli: &Cli) -> Result<()> {
    let mut inputs = match cli.input.as_ref().or(cli.volume.as_ref()) {
        Some(input) => input_run_files(input, cli.function.as_deref())?,
        None => Vec::new(),
    };
    for mesh in &cli.inspect {
        let role = format!("the mesh {}", mesh.display());
        inputs.extend(mesh_files(mesh).into_iter().map(|f| RunFile::new(&role, f)));
    }
    let outputs = output_run_files(&[
        ("--report", cli.report.as_deref()),
        ("--json", cli.json.as_deref()),
        ("--spectrum", cli.spectrum.as_deref()),
        ("--transfer", cli.transfer.as_deref()),
    ]);
    check_clashes(&inputs, &outputs)?;
    Ok(())
}
