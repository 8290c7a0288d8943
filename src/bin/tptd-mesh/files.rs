//! The files `--inspect` reads and writes, and the check before any work that no output is
//! an input file or another output (meshing and `--critical` check theirs in the library,
//! [`tptd::pipeline`]).

use anyhow::Result;
use tptd::io::{check_clashes, input_files, mesh_files, RunFile};

use crate::cli::Cli;

/// Refuses, before any sample is read, an output of the run (`--json`; the others are refused
/// with `--inspect`) that is the same file as a file of the input (`--volume` with its
/// detached data files, every file of every `--inspect` mesh) or as another output. A clash
/// is a [`tptd::io::FileClash`] (exit 2).
pub(crate) fn check_files(cli: &Cli) -> Result<()> {
    let mut inputs = Vec::new();
    if let Some(input) = cli.input.as_ref().or(cli.volume.as_ref()) {
        let files = input_files(input, cli.function.as_deref())?;
        let read_with = format!("read with the input {}", input.display());
        for (n, f) in files.into_iter().enumerate() {
            let role = if n == 0 { "the input" } else { &read_with };
            inputs.push(RunFile::new(role, f));
        }
    }
    for mesh in &cli.inspect {
        let role = format!("the mesh {}", mesh.display());
        for f in mesh_files(mesh) {
            inputs.push(RunFile::new(role.clone(), f));
        }
    }
    let outputs: Vec<RunFile> = [
        ("--report", cli.report.as_deref()),
        ("--json", cli.json.as_deref()),
        ("--spectrum", cli.spectrum.as_deref()),
        ("--transfer", cli.transfer.as_deref()),
    ]
    .into_iter()
    .filter_map(|(role, path)| path.map(|p| RunFile::new(role, p)))
    .collect();
    check_clashes(&inputs, &outputs)?;
    Ok(())
}
