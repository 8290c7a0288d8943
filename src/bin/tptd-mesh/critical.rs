//! `--critical`: the critical points and regions of the input as a table (stdout), JSON and a
//! contour-spectrum CSV, a transfer function (ParaView preset or CSV). The check of
//! `--alpha`/`--beta` against the critical values before meshing is the pipeline's
//! ([`tptd::pipeline`]).

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use tptd::critical::{
    contour_spectrum, find_critical_with_options, transfer_function, CriticalOptions,
    CriticalPoint, TransferFunction, TransferOptions,
};
use tptd::io::{check_writable, write_atomically, write_transfer, TransferFormat, TransferTable};
use tptd::ScalarGrid;

use crate::cli::Cli;
use crate::error::{file_error, write_error};
use crate::run::read_grid;

/// Runs `tptd-mesh INPUT --critical ...`.
pub(crate) fn run(cli: Cli) -> Result<()> {
    let t = Instant::now();
    let input = match &cli.input {
        Some(p) => p.display().to_string(),
        None => "demo".to_string(),
    };
    for out in [&cli.json, &cli.spectrum, &cli.transfer]
        .into_iter()
        .flatten()
    {
        check_writable(out).map_err(write_error)?;
    }
    let transfer_format = cli.transfer.as_deref().map(transfer_format).transpose()?;
    crate::files::check_files(&cli, None)?;
    let grid = read_grid(&cli)?;
    let opts = CriticalOptions {
        min_value: cli.min_value.unwrap_or(f64::NEG_INFINITY),
        max_value: cli.max_value.unwrap_or(f64::INFINITY),
        kinds: cli.kind.clone().map(|k| k.0).unwrap_or_default(),
        min_persistence: cli.min_persistence.unwrap_or(0.0),
        threads: cli.threads.map(|n| n as usize),
        persistence: cli.persistence || cli.min_persistence.is_some(),
    };
    check_memory(&grid, &input, opts.persistence, cli.spectrum.is_some())?;
    let points = find_critical_with_options(&grid, &opts).map_err(|e| file_error(&input, e))?;
    let secs = t.elapsed().as_secs_f64();
    // built before any file is written, so that bad parameters leave no output
    let transfer = match &cli.transfer {
        Some(path) => Some(build_transfer(&cli, &grid, &points, path)?),
        None => None,
    };
    if let Some(path) = &cli.json {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &points).map_err(std::io::Error::other)?;
            writeln!(w)
        })
        .map_err(write_error)?;
    }
    if let Some(path) = &cli.spectrum {
        write_spectrum(&grid, path, &opts)?;
    }
    if let (Some(path), Some(format), Some(tf)) = (&cli.transfer, transfer_format, &transfer) {
        write_transfer_function(&cli, tf, points.len(), &input, path, format)?;
    }
    if !cli.quiet {
        stdout_result(print_table(&input, &points, secs))?;
    }
    Ok(())
}

/// Checks the memory estimate of the critical points (with persistence and the contour
/// spectrum when asked for) before the work (see [`tptd::memory::critical_bytes`]).
fn check_memory(grid: &ScalarGrid, input: &str, persistence: bool, spectrum: bool) -> Result<()> {
    let need = tptd::memory::critical_bytes(
        grid.num_vertices() as u64,
        grid.num_cells() as u64,
        grid.values.bytes_per_sample() as u64,
        persistence,
        spectrum,
    );
    let what = match (persistence, spectrum) {
        (false, false) => "finding the critical points",
        (true, false) => "finding the critical points with persistence",
        (false, true) => "finding the critical points and the contour spectrum",
        (true, true) => "finding the critical points with persistence and the contour spectrum",
    };
    tptd::memory::check(need, what).map_err(|e| {
        file_error(
            input,
            format_args!(
                "{e}; crop the volume, leave out --spectrum and --persistence or raise \
                 --memory-limit"
            ),
        )
    })
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

/// The format of `--transfer FILE` from its extension.
fn transfer_format(path: &Path) -> Result<TransferFormat> {
    TransferFormat::from_path(path).ok_or_else(|| {
        file_error(
            path.display(),
            "unknown transfer-function format; use .json (ParaView preset) or .csv",
        )
    })
}

/// The transfer function of `--transfer-design` built from the critical values of `points`
/// over the data range (errors name the output `path`).
fn build_transfer(
    cli: &Cli,
    grid: &ScalarGrid,
    points: &[CriticalPoint],
    path: &Path,
) -> Result<TransferFunction> {
    let opts = TransferOptions {
        design: cli.transfer_design.design(),
        hue_width: cli.transfer_width,
        opacity_width: cli.transfer_width,
        ..TransferOptions::default()
    };
    let values: Vec<f64> = points.iter().map(|p| p.value).collect();
    transfer_function(&values, grid.value_range(), &opts).map_err(|e| file_error(path.display(), e))
}

/// Writes `tf` (built from `n_points` critical points of `input`) to `path`.
fn write_transfer_function(
    cli: &Cli,
    tf: &TransferFunction,
    n_points: usize,
    input: &str,
    path: &Path,
    format: TransferFormat,
) -> Result<()> {
    let design = tf.design.name();
    let base = Path::new(input)
        .file_name()
        .map_or(input.into(), |n| n.to_string_lossy());
    let name = format!("tptd {design} {base}");
    let table = TransferTable {
        name: &name,
        colors: &tf.colors,
        opacity: &tf.opacity,
    };
    write_transfer(path, format, &table).map_err(write_error)?;
    if !cli.quiet {
        stdout_result(writeln!(
            std::io::stdout(),
            "transfer function ({design}, {} critical values from {n_points} points): {}",
            tf.values.len(),
            path.display()
        ))?;
    }
    Ok(())
}

/// Writes the contour spectrum over the filtered value range as CSV.
fn write_spectrum(grid: &ScalarGrid, path: &std::path::Path, opts: &CriticalOptions) -> Result<()> {
    // the spectrum needs every critical value of the range, whatever the kind/persistence filter
    let all = CriticalOptions {
        kinds: Vec::new(),
        min_persistence: 0.0,
        persistence: false,
        ..opts.clone()
    };
    let points =
        find_critical_with_options(grid, &all).map_err(|e| file_error(path.display(), e))?;
    let steps = contour_spectrum(grid, &points, opts.min_value, opts.max_value);
    write_atomically(path, |w| {
        writeln!(w, "lo,hi,b0,b1,b2")?;
        for s in &steps {
            writeln!(
                w,
                "{},{},{},{},{}",
                s.lo, s.hi, s.betti[0], s.betti[1], s.betti[2]
            )?;
        }
        writeln!(w, "# critical values by kind: value,kind")?;
        for p in points.iter().filter(|p| p.superlevel) {
            writeln!(w, "# {},{}", p.value, p.kind.name())?;
        }
        Ok(())
    })
    .map_err(write_error)?;
    Ok(())
}

/// The table on stdout.
fn print_table(input: &str, points: &[CriticalPoint], secs: f64) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{input}: {} critical points and regions ({secs:.2} s)",
        points.len()
    )?;
    writeln!(
        out,
        "{:>14}  {:<15} {:>30}  {:>12}  {:<5} {:<5} region",
        "value", "kind", "position (x, y, z)", "persistence", "f>=w", "f<=w"
    )?;
    let yes = |b: bool| if b { "yes" } else { "-" };
    for p in points {
        let pos = format!(
            "{:.3}, {:.3}, {:.3}",
            p.position[0], p.position[1], p.position[2]
        );
        let pers = p.persistence.map_or("-".to_string(), |x| format!("{x:.6}"));
        let region = p
            .region
            .as_ref()
            .map_or(String::new(), |r| format!("{} vertices", r.vertices));
        writeln!(
            out,
            "{:>14}  {:<15} {:>30}  {:>12}  {:<5} {:<5} {region}",
            format!("{:.6}", p.value),
            p.kind.name(),
            pos,
            pers,
            yes(p.superlevel),
            yes(p.sublevel)
        )?;
    }
    Ok(())
}
