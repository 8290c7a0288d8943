//! The choice between streaming the mesh to disk and holding it in memory, and the memory
//! estimate of the run, checked against the limit before the work (see [`crate::memory`]).

use std::path::Path;

use crate::io::SurfaceFormat;
use crate::memory::{estimate_tets, mesh_bytes, stream_bytes};
use crate::ScalarGrid;

use super::request::Job;
use super::text::fmt_interval;
use super::{Mode, Param, ParamNames, PipelineError};
use crate::allocator::OutOfMemory;

/// The output the mesh goes straight to, slab by slab: a volume mesh output without the
/// quality pass (which needs the whole mesh), a curvilinear mapping or the check (which reads
/// the whole mesh). `None`: the mesh is held in memory.
pub(crate) fn streams<'a>(job: &'a Job, curvilinear: bool) -> Option<&'a Path> {
    let output = job.output.as_deref()?;
    let stream = job.req.quality.is_none()
        && job.req.grade.is_none()
        && !job.req.check
        && !curvilinear
        && SurfaceFormat::from_path(output).is_none();
    stream.then_some(output)
}

/// Whether a caller's sink can take the mesh slab by slab as it is made, in place of the
/// mesh held in memory: nothing after meshing reads the whole mesh (no output, quality pass,
/// graded interior, curvilinear mapping or check) and it is not the demo (compared after
/// meshing).
pub(crate) fn hands_on(job: &Job, curvilinear: bool) -> bool {
    job.output.is_none()
        && job.req.quality.is_none()
        && job.req.grade.is_none()
        && !job.req.check
        && !curvilinear
        && !job.demo()
}

/// Checks the memory estimate of meshing, analysis, the quality pass and the check before
/// the work.
pub(crate) fn check_memory(
    grid: &ScalarGrid,
    job: &Job,
    streaming: bool,
) -> Result<(), PipelineError> {
    let tets = estimate_tets(grid, job.opts.alpha, job.opts.beta);
    let bytes = grid.values.bytes_per_sample() as u64;
    let voxels = grid.num_vertices() as u64;
    let need = if streaming {
        let layers = grid.cell_dims()[2] as u64;
        // Two windows: one meshed while the other is handed on.
        stream_bytes(voxels, bytes, tets, layers, 2 * job.opts.window() as u64)
    } else {
        let pass = if job.req.quality.is_some() {
            tets.saturating_mul(crate::memory::QUALITY_BYTES_PER_TET)
        } else {
            0
        };
        let checker = if job.req.check {
            tets.saturating_mul(crate::check::CHECK_BYTES_PER_TET)
        } else {
            0
        };
        mesh_bytes(voxels, bytes, tets)
            .saturating_add(pass)
            .saturating_add(checker)
    };
    let what = format!(
        "meshing {} (about {:.1} M tetrahedra)",
        fmt_interval(job.opts.alpha, job.opts.beta),
        tets as f64 / 1e6
    );
    crate::memory::check(need, what).map_err(|e| {
        PipelineError::memory(
            &job.input_name,
            format_args!(
                "{e}; narrow the interval, crop the volume or raise {}",
                job.req.names.of(Param::MemoryLimit)
            ),
        )
    })
}

/// Writes the out-of-memory line of a run in `mode` (without a program prefix, with its
/// newline): what was refused, and what helps, naming the parameters by `names`. It allocates
/// nothing, as [`crate::allocator::OutOfMemoryMessage`] requires.
pub fn out_of_memory_line(
    w: &mut dyn std::io::Write,
    m: OutOfMemory,
    mode: Mode,
    names: ParamNames,
) -> std::io::Result<()> {
    let size = m.size;
    match m.limit {
        Some(l) => write!(
            w,
            "out of memory: {size} more would exceed the memory limit of {l}; raise {}, ",
            names.of(Param::MemoryLimit)
        )?,
        None => write!(w, "out of memory: the system refused {size}; ")?,
    }
    match (mode, m.limit) {
        (Mode::Critical, _) => writeln!(
            w,
            "crop the volume or leave out {} and {}",
            names.of(Param::Spectrum),
            names.of(Param::Persistence)
        ),
        (_, Some(_)) => writeln!(w, "crop the volume or narrow the interval"),
        (_, None) => writeln!(
            w,
            "crop the volume, narrow the interval or use {}",
            names.of(Param::NoAnalysis)
        ),
    }
}
