//! `--critical`: the critical points and regions of the input as a table (stdout), JSON and a
//! contour-spectrum CSV, a transfer function (ParaView preset or CSV). The run is the
//! library's ([`tptd::pipeline::critical_file`]): this module turns the arguments into its
//! request and prints its table. The check of `--alpha`/`--beta` against the critical values
//! before meshing is the meshing pipeline's ([`tptd::pipeline`]).

use std::io::Write;

use anyhow::Result;
use tptd::pipeline::{critical_file, critical_table, transfer_line, CriticalRequest, NoProgress};

use crate::cli::{Cli, Spacing};
use crate::error::file_error;

/// Runs `tptd-mesh INPUT --critical ...`.
pub(crate) fn run(cli: Cli) -> Result<()> {
    let req = request(&cli);
    let run = critical_file(&req, &NoProgress)?;
    if !cli.quiet {
        if let (Some(path), Some(tf)) = (&req.transfer, &run.transfer) {
            let line = transfer_line(tf, run.points.len(), path);
            stdout_result(std::io::stdout().write_all(line.as_bytes()))?;
        }
        let table = critical_table(&req.input_name(), &run.points, run.secs);
        stdout_result(std::io::stdout().lock().write_all(table.as_bytes()))?;
    }
    Ok(())
}

/// The request of the arguments.
fn request(cli: &Cli) -> CriticalRequest {
    CriticalRequest {
        input: cli.input.clone(),
        spacing: cli.spacing.map(|Spacing(s)| s),
        min_value: cli.min_value.unwrap_or(f64::NEG_INFINITY),
        max_value: cli.max_value.unwrap_or(f64::INFINITY),
        kinds: cli.kind.clone().map(|k| k.0).unwrap_or_default(),
        min_persistence: cli.min_persistence.unwrap_or(0.0),
        persistence: cli.persistence || cli.min_persistence.is_some(),
        json: cli.json.clone(),
        spectrum: cli.spectrum.clone(),
        transfer: cli.transfer.clone(),
        transfer_design: cli.transfer_design.design(),
        transfer_width: cli.transfer_width,
        threads: cli.threads.map(|n| n as usize),
        memory_limit: cli.memory_limit,
    }
}

/// A failed write on stdout as an error, except a closed pipe (e.g. `| head`): that is not an
/// error of the run, whose files are written by then, so it ends quietly with status 0.
fn stdout_result(r: std::io::Result<()>) -> Result<()> {
    match r {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(file_error("stdout", format_args!("cannot write: {e}")))
        }
        _ => Ok(()),
    }
}
