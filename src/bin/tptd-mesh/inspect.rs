//! `--inspect MESH...`: reads each mesh, has the library inspect it
//! ([`tptd::inspect::inspect`]; with `--volume`, against the trilinear interval) and prints
//! one column per mesh; `--json` writes one object per mesh. An unreadable mesh ends the run
//! with one line naming it (exit 1) before anything is written; an invalid mesh is a result,
//! not an error (exit 0).

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use tptd::inspect::{inspect, reference, table, InspectOptions, Reference, ReferenceOptions};
use tptd::io::{check_writable, read_mesh, read_volume, write_atomically};
use tptd::ScalarGrid;

use crate::cli::{Cli, Spacing};
use crate::error::{file_error, write_error};
use crate::progress::Stage;
use tptd::pipeline::text::fmt_interval;

/// Runs `tptd-mesh --inspect MESH... [--volume VOLUME --alpha A --beta B] [--json FILE]`.
pub(crate) fn run(cli: Cli) -> Result<()> {
    if let Some(n) = cli.threads {
        // the pool is built once, here, before any parallel work
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global();
    }
    if let Some(j) = &cli.json {
        check_writable(j).map_err(write_error)?;
    }
    crate::files::check_files(&cli)?;
    let volume = match &cli.volume {
        Some(path) => Some(read_reference(&cli, path)?),
        None => None,
    };
    let opts = InspectOptions {
        volume: volume.as_ref().map(|(g, r)| (g, r)),
        ..InspectOptions::default()
    };
    let mut all = Vec::with_capacity(cli.inspect.len());
    for path in &cli.inspect {
        let name = path.display().to_string();
        let stage = Stage::start(format!("inspecting {name}"), cli.quiet);
        let file = read_mesh(path)?;
        all.push(inspect(&name, file.mesh, &opts));
        stage.finish();
    }
    if let Some(path) = &cli.json {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &all).map_err(std::io::Error::other)?;
            writeln!(w)
        })
        .map_err(write_error)?;
    }
    if !cli.quiet {
        let reference = volume.as_ref().zip(cli.volume.as_deref());
        let text = table(&all, reference.map(|((_, r), p)| (r, p)));
        if let Err(e) = std::io::stdout().write_all(text.as_bytes()) {
            if e.kind() != std::io::ErrorKind::BrokenPipe {
                return Err(file_error("stdout", format_args!("cannot write: {e}")));
            }
        }
    }
    Ok(())
}

/// Reads `--volume` (with `--spacing`) and computes the reference of the interval.
fn read_reference(cli: &Cli, path: &Path) -> Result<(ScalarGrid, Reference)> {
    let name = path.display().to_string();
    let stage = Stage::start(format!("reading {name}"), cli.quiet);
    let mut grid = read_volume(path)?;
    if let Some(Spacing(s)) = cli.spacing {
        grid = ScalarGrid::with_geometry(grid.dims, s, grid.origin, grid.direction, grid.values)
            .map_err(|e| file_error(&name, format_args!("--spacing: {e}")))?;
    }
    stage.finish();
    let alpha = cli.alpha.unwrap_or(f64::NEG_INFINITY);
    let beta = cli.beta.unwrap_or(f64::INFINITY);
    if alpha >= beta {
        return Err(file_error(
            &name,
            format_args!("empty interval: --alpha ({alpha}) must be less than --beta ({beta})"),
        ));
    }
    let stage = Stage::start(
        format!("the trilinear interval {}", fmt_interval(alpha, beta)),
        cli.quiet,
    );
    let r = reference(&grid, alpha, beta, &ReferenceOptions::default())
        .map_err(|e| file_error(&name, e))?;
    stage.finish();
    Ok((grid, r))
}
