//! The report of a run, and the last step of one: the report written and both files renamed
//! onto their names, so that a failure leaves neither.

use std::path::Path;

use crate::io::{write_pending, PendingFile};
use crate::report::{build_report, Report, RunInfo, Timings};
use crate::ScalarGrid;

use super::request::Job;
use super::run::Written;
use super::PipelineError;

/// The report of the run (without its warnings).
pub(crate) fn make_report(
    job: &Job,
    grid: &ScalarGrid,
    w: &mut Written,
    timings: Timings,
) -> Report {
    let threads = job
        .opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let output_name = job
        .output
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    let mut report = build_report(
        &RunInfo {
            input: &job.input_name,
            output: &output_name,
            dims: grid.dims,
            spacing: grid.spacing,
            samples: grid.values.storage(),
            method: job.opts.method,
            alpha: job.opts.alpha,
            beta: job.opts.beta,
            levels: &job.opts.levels,
            threads,
        },
        &w.facts,
        &w.stats,
        w.quality.take(),
        timings,
    );
    report.surface = w.surface.take();
    report.check = w.check.take();
    report.grade = w.grade.take();
    report
}

/// Writes the JSON report (to `path`, if any), then renames the output (if any) and the
/// report onto their names. When the report cannot be written, neither file is: dropping
/// `output` removes its temporary.
pub(crate) fn commit(
    report: &Report,
    path: Option<&Path>,
    output: Option<PendingFile>,
) -> Result<(), PipelineError> {
    let report_file = match path {
        Some(path) => {
            let mut json = report.to_json_pretty();
            json.push('\n');
            Some(write_pending(path, |w| w.write_all(json.as_bytes()))?)
        }
        None => None,
    };
    if let Some(output) = output {
        output.commit()?;
    }
    if let Some(f) = report_file {
        f.commit()?;
    }
    Ok(())
}
