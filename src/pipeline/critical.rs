//! The critical points of a volume as a library call: [`critical_file`] takes a
//! [`CriticalRequest`] (input, filters, outputs, transfer-function design, threads, memory
//! limit) and does what `tptd-mesh --critical` does between parsing its arguments and
//! printing its table ([`critical_table`]): it checks that the outputs can be written and
//! that none is an input file or another output, reads the input, checks the memory
//! estimate, finds the points, builds the transfer function and writes the JSON, the contour
//! spectrum and the transfer function atomically. Nothing here prints. [`critical_grid`] is
//! the same run on a volume given in memory (a binding's array).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::critical::{
    contour_spectrum, find_critical_with_options, transfer_function, CriticalKind, CriticalOptions,
    CriticalPoint, TransferDesign, TransferFunction, TransferOptions,
};
use crate::io::{
    check_clashes, check_writable, input_run_files, output_run_files, write_atomically,
    write_transfer, TransferFormat, TransferTable,
};
use crate::ScalarGrid;

use super::progress::{Progress, Reporter, StageKind};
use super::read::with_spacing;
use super::{check_threads, read_grid, Param, ParamNames, PipelineError};

/// One run of the critical points: the input, the filters of the points, the outputs and the
/// design of the transfer function. Plain data; [`CriticalRequest::default`] lists the
/// critical points of the demo volume without persistence, as `tptd-mesh --demo --critical`.
#[derive(Clone, Debug, PartialEq)]
pub struct CriticalRequest {
    /// The input volume; `None`: the demo volume ([`crate::demo::demo_volume`]).
    pub input: Option<PathBuf>,
    /// The grid spacing instead of the file's.
    pub spacing: Option<[f64; 3]>,
    /// Keep points with value `>= min_value` (the range of the contour spectrum too).
    pub min_value: f64,
    /// Keep points with value `<= max_value` (the range of the contour spectrum too).
    pub max_value: f64,
    /// Keep these kinds (all when empty).
    pub kinds: Vec<CriticalKind>,
    /// Keep points with persistence `>= min_persistence` (see
    /// [`CriticalOptions::min_persistence`]).
    pub min_persistence: f64,
    /// Compute the persistence of each point.
    pub persistence: bool,
    /// Where to write the points as JSON, if anywhere.
    pub json: Option<PathBuf>,
    /// Where to write the contour spectrum as CSV, if anywhere.
    pub spectrum: Option<PathBuf>,
    /// Where to write the transfer function (`.json`: a ParaView preset, `.csv`), if anywhere.
    pub transfer: Option<PathBuf>,
    /// The design of the transfer function.
    pub transfer_design: TransferDesign,
    /// The width of its opacity elevations and hue descents (`None`: 2 % of the range).
    pub transfer_width: Option<f64>,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// The memory limit of the estimates ([`crate::memory::set_limit`]; `None`: the
    /// available memory).
    pub memory_limit: Option<u64>,
    /// How messages name the parameters.
    pub names: ParamNames,
}

impl Default for CriticalRequest {
    fn default() -> Self {
        CriticalRequest {
            input: None,
            spacing: None,
            min_value: f64::NEG_INFINITY,
            max_value: f64::INFINITY,
            kinds: Vec::new(),
            min_persistence: 0.0,
            persistence: false,
            json: None,
            spectrum: None,
            transfer: None,
            transfer_design: TransferDesign::Intervals,
            transfer_width: None,
            threads: None,
            memory_limit: None,
            names: ParamNames::NEUTRAL,
        }
    }
}

impl CriticalRequest {
    /// The input as named in messages (`demo` for the demo volume).
    pub fn input_name(&self) -> String {
        match &self.input {
            Some(p) => p.display().to_string(),
            None => "demo".to_string(),
        }
    }

    /// The options of the search for the points.
    fn options(&self) -> CriticalOptions {
        CriticalOptions {
            min_value: self.min_value,
            max_value: self.max_value,
            kinds: self.kinds.clone(),
            min_persistence: self.min_persistence,
            threads: self.threads,
            persistence: self.persistence,
        }
    }
}

/// The result of [`critical_file`].
#[derive(Clone, Debug)]
pub struct CriticalRun {
    /// The critical points and regions that pass the filters.
    pub points: Vec<CriticalPoint>,
    /// The seconds taken to read the input and find the points.
    pub secs: f64,
    /// The transfer function, when the request asked for one (written by then).
    pub transfer: Option<TransferFunction>,
}

/// Runs `req`: checks the outputs, reads the input, checks the memory estimate, finds the
/// critical points, builds the transfer function and writes the outputs. Stages go to
/// `progress`.
///
/// # Errors
/// The first failure, as one line naming the file; an output that is an input file or
/// another output is a usage error ([`PipelineError::is_usage`]). Parameters of the transfer
/// function it refuses leave no output.
pub fn critical_file(
    req: &CriticalRequest,
    progress: &dyn Progress,
) -> Result<CriticalRun, PipelineError> {
    let input = req.input_name();
    run_on(req, &input, progress, |reporter| {
        let stage = reporter.stage(&format!("reading {input}"), StageKind::Step);
        let grid = read_grid(req.input.as_deref(), req.spacing, req.names)?;
        stage.finish();
        Ok(grid)
    })
}

/// Runs `req` on `grid`, a volume given in memory and named `name` in messages, as
/// [`critical_file`] runs it on its input file (whose path is not read): the same checks,
/// points and outputs; the request's spacing, if given, replaces the grid's.
///
/// # Errors
/// As [`critical_file`], naming `name`.
pub fn critical_grid(
    grid: ScalarGrid,
    name: &str,
    req: &CriticalRequest,
    progress: &dyn Progress,
) -> Result<CriticalRun, PipelineError> {
    let req = CriticalRequest {
        input: None,
        ..req.clone()
    };
    run_on(&req, name, progress, |_| {
        with_spacing(grid, req.spacing, name, req.names)
    })
}

/// A run of `req` on the volume `grid` gives (read from a file or given in memory, named
/// `input`), for [`critical_file`] and [`critical_grid`]: the memory limit set, the outputs
/// checked before `grid` is called, then the points and the outputs; the seconds count from
/// the start.
fn run_on(
    req: &CriticalRequest,
    input: &str,
    progress: &dyn Progress,
    grid: impl FnOnce(&Reporter) -> Result<ScalarGrid, PipelineError>,
) -> Result<CriticalRun, PipelineError> {
    let t = Instant::now();
    crate::memory::set_limit(req.memory_limit);
    let reporter = Reporter::new(progress);
    let transfer_format = check_outputs(req)?;
    let grid = grid(&reporter)?;
    find_and_write(&grid, input, req, transfer_format, (&reporter, t))
}

/// Checks the thread count and the outputs: writable, the transfer function's format (which
/// it returns), no output an input file or another output.
fn check_outputs(req: &CriticalRequest) -> Result<Option<TransferFormat>, PipelineError> {
    check_threads(req.threads, req.names)?;
    for out in [&req.json, &req.spectrum, &req.transfer]
        .into_iter()
        .flatten()
    {
        check_writable(out)?;
    }
    let transfer_format = req.transfer.as_deref().map(transfer_format).transpose()?;
    check_files(req)?;
    Ok(transfer_format)
}

/// The work of a run on `grid` (named `input`) once the outputs are checked: the memory
/// estimate, the points, the transfer function and the outputs; the seconds count from `t`.
fn find_and_write(
    grid: &ScalarGrid,
    input: &str,
    req: &CriticalRequest,
    transfer_format: Option<TransferFormat>,
    (reporter, t): (&Reporter, Instant),
) -> Result<CriticalRun, PipelineError> {
    let opts = req.options();
    check_memory(
        grid,
        (input, req.names),
        opts.persistence,
        req.spectrum.is_some(),
    )?;
    let stage = reporter.stage("finding the critical points", StageKind::Step);
    let points =
        find_critical_with_options(grid, &opts).map_err(|e| PipelineError::file(input, e))?;
    stage.finish();
    let secs = t.elapsed().as_secs_f64();
    // built before any file is written, so that bad parameters leave no output
    let transfer = match &req.transfer {
        Some(path) => Some(build_transfer(req, grid, &points, path)?),
        None => None,
    };
    let _stage = reporter.stage("writing the outputs", StageKind::Step);
    if let Some(path) = &req.json {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &points).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    if let Some(path) = &req.spectrum {
        write_spectrum(grid, path, &opts)?;
    }
    if let (Some(path), Some(format), Some(tf)) = (&req.transfer, transfer_format, &transfer) {
        write_transfer_function(tf, input, path, format)?;
    }
    Ok(CriticalRun {
        points,
        secs,
        transfer,
    })
}

/// Refuses, before any sample is read, an output (the JSON, the spectrum, the transfer function) that
/// is the same file as a file of the input or as another output. A clash is a usage error.
fn check_files(req: &CriticalRequest) -> Result<(), PipelineError> {
    let inputs = match &req.input {
        Some(input) => input_run_files(input, None).map_err(PipelineError::from)?,
        None => Vec::new(),
    };
    let n = req.names;
    let outputs = output_run_files(&[
        (n.of(Param::Json), req.json.as_deref()),
        (n.of(Param::Spectrum), req.spectrum.as_deref()),
        (n.of(Param::Transfer), req.transfer.as_deref()),
    ]);
    check_clashes(&inputs, &outputs)?;
    Ok(())
}

/// Checks the memory estimate of the critical points (with persistence and the contour
/// spectrum when asked for) before the work (see [`crate::memory::critical_bytes`]).
fn check_memory(
    grid: &ScalarGrid,
    (input, names): (&str, ParamNames),
    persistence: bool,
    spectrum: bool,
) -> Result<(), PipelineError> {
    let need = crate::memory::critical_bytes(
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
    crate::memory::check(need, what).map_err(|e| {
        PipelineError::memory(
            input,
            format_args!(
                "{e}; crop the volume, leave out {} and {} or raise {}",
                names.of(Param::Spectrum),
                names.of(Param::Persistence),
                names.of(Param::MemoryLimit)
            ),
        )
    })
}

/// The format of the transfer-function output `path` from its extension.
fn transfer_format(path: &Path) -> Result<TransferFormat, PipelineError> {
    TransferFormat::from_path(path).ok_or_else(|| {
        PipelineError::file(
            path.display(),
            "unknown transfer-function format; use .json (ParaView preset) or .csv",
        )
    })
}

/// The transfer function of the request's design built from the critical values of `points`
/// over the data range (errors name the output `path`).
fn build_transfer(
    req: &CriticalRequest,
    grid: &ScalarGrid,
    points: &[CriticalPoint],
    path: &Path,
) -> Result<TransferFunction, PipelineError> {
    let opts = TransferOptions {
        design: req.transfer_design,
        hue_width: req.transfer_width,
        opacity_width: req.transfer_width,
        ..TransferOptions::default()
    };
    let values: Vec<f64> = points.iter().map(|p| p.value).collect();
    transfer_function(&values, grid.value_range(), &opts)
        .map_err(|e| PipelineError::file(path.display(), e))
}

/// Writes `tf` (built from the critical points of `input`) to `path`.
fn write_transfer_function(
    tf: &TransferFunction,
    input: &str,
    path: &Path,
    format: TransferFormat,
) -> Result<(), PipelineError> {
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
    write_transfer(path, format, &table)?;
    Ok(())
}

/// Writes the contour spectrum over the filtered value range as CSV.
fn write_spectrum(
    grid: &ScalarGrid,
    path: &Path,
    opts: &CriticalOptions,
) -> Result<(), PipelineError> {
    // the spectrum needs every critical value of the range, whatever the kind/persistence filter
    let all = CriticalOptions {
        kinds: Vec::new(),
        min_persistence: 0.0,
        persistence: false,
        ..opts.clone()
    };
    let points = find_critical_with_options(grid, &all)
        .map_err(|e| PipelineError::file(path.display(), e))?;
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
    })?;
    Ok(())
}

/// The line that says where the transfer function `tf`, built from `n_points` critical
/// points, was written (`path`), with its newline.
pub fn transfer_line(tf: &TransferFunction, n_points: usize, path: &Path) -> String {
    format!(
        "transfer function ({}, {} critical values from {n_points} points): {}\n",
        tf.design.name(),
        tf.values.len(),
        path.display()
    )
}

/// The table of the critical points of `input` found in `secs` seconds: a title line, a
/// header and one line per point, each with its newline.
pub fn critical_table(input: &str, points: &[CriticalPoint], secs: f64) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{input}: {} critical points and regions ({secs:.2} s)",
        points.len()
    );
    let _ = writeln!(
        out,
        "{:>14}  {:<15} {:>30}  {:>12}  {:<5} {:<5} region",
        "value", "kind", "position (x, y, z)", "persistence", "f>=w", "f<=w"
    );
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
        let _ = writeln!(
            out,
            "{:>14}  {:<15} {:>30}  {:>12}  {:<5} {:<5} {region}",
            format!("{:.6}", p.value),
            p.kind.name(),
            pos,
            pers,
            yes(p.superlevel),
            yes(p.sublevel)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::NoProgress;

    #[test]
    fn the_demo_lists_its_points_and_refuses_a_clash() {
        let run = critical_file(&CriticalRequest::default(), &NoProgress).unwrap();
        assert!(!run.points.is_empty());
        assert!(run.transfer.is_none());
        let table = critical_table("demo", &run.points, 0.0);
        assert!(table.starts_with(&format!(
            "demo: {} critical points and regions (0.00 s)\n",
            run.points.len()
        )));
        assert_eq!(table.lines().count(), run.points.len() + 2);
        let dir = tempfile::tempdir().unwrap();
        let same = dir.path().join("x.json");
        let req = CriticalRequest {
            json: Some(same.clone()),
            spectrum: Some(same),
            ..CriticalRequest::default()
        };
        let e = critical_file(&req, &NoProgress).unwrap_err();
        assert!(e.is_usage(), "{e}");
    }

    #[test]
    fn a_grid_in_memory_gives_the_points_of_its_file() {
        let req = CriticalRequest {
            persistence: true,
            ..CriticalRequest::default()
        };
        let file = critical_file(&req, &NoProgress).unwrap();
        let grid = crate::demo::demo_volume();
        let given = critical_grid(grid, "volume", &req, &NoProgress).unwrap();
        assert_eq!(given.points, file.points);
        let spaced = CriticalRequest {
            spacing: Some([1.0, 0.0, 1.0]),
            ..req
        };
        let e = critical_grid(crate::demo::demo_volume(), "volume", &spaced, &NoProgress);
        assert!(e.unwrap_err().message().starts_with("volume: spacing: "));
    }
}
