//! Memory: estimates of what a run needs before the work, the limit they are checked
//! against, and the fallible sections in which an allocation failure is an error rather than
//! the end of the process.
//!
//! * **Limit**: [`set_limit`] (the CLI's `--memory-limit` / `TPTD_MEMORY_LIMIT`), otherwise
//!   the memory the kernel reports available (`MemAvailable` in `/proc/meminfo`), otherwise
//!   none. The process-wide limit is also what a capping global allocator (the binary's)
//!   enforces.
//! * **Estimates**, measured on this project's machine (docs/QUALITY-LOG.md, *Memory and
//!   scale*): the samples take their storage type's bytes per voxel ([`crate::Samples`]: 1 for
//!   `uint8`, 8 for `float64`) plus, while the file is read, a reordered copy and the file's
//!   bytes; the mesh and its analysis take about
//!   [`BYTES_PER_TET`] bytes per tetrahedron; the number of tetrahedra is estimated from the
//!   cells inside the interval and the cells a bound crosses ([`estimate_tets`]).
//! * **Fallible sections** ([`fallible`]): a capping allocator returns null inside them, so
//!   `try_reserve` reports the failure; outside them it ends the process with one line.

use std::cell::Cell;
use std::collections::TryReserveError;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::grid::ScalarGrid;

/// Bytes per output tetrahedron of meshing plus analysis (peak RSS minus the grid, 69–84 B
/// measured on the four benchmark runs of docs/QUALITY-LOG.md, *Memory and scale*, rounded up).
pub const BYTES_PER_TET: u64 = 90;

/// Tetrahedra per cell entirely inside the interval (the 6-fold split).
const TETS_PER_INSIDE_CELL: f64 = 6.0;

/// Tetrahedra per cell a bound crosses (11.5–12.2 measured on the benchmark volumes).
const TETS_PER_CROSSING_CELL: f64 = 12.5;

/// Cells visited at most by [`estimate_tets`] (whole z layers are sampled beyond that).
const SAMPLE_CELLS: usize = 1 << 22;

/// The explicit limit in bytes (0: none).
static LIMIT: AtomicU64 = AtomicU64::new(0);

thread_local! {
    static FALLIBLE: Cell<bool> = const { Cell::new(false) };
}

/// Where a memory limit comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitSource {
    /// Set by [`set_limit`] (the CLI's `--memory-limit`).
    Explicit,
    /// The memory the kernel reports available.
    Available,
}

/// A memory limit in bytes and where it comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryLimit {
    /// The limit in bytes.
    pub bytes: u64,
    /// Where it comes from.
    pub source: LimitSource,
}

/// A run that would not fit: what needs how much, and the limit.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what} needs about {} but {}", fmt_bytes(*.need), limit_text(.limit))]
pub struct MemoryError {
    /// What needs the memory (e.g. `meshing about 95 M tetrahedra`).
    pub what: String,
    /// The estimate in bytes.
    pub need: u64,
    /// The limit it exceeds.
    pub limit: MemoryLimit,
}

fn limit_text(l: &MemoryLimit) -> String {
    match l.source {
        LimitSource::Explicit => format!("the memory limit is {}", fmt_bytes(l.bytes)),
        LimitSource::Available => format!("only {} of memory are available", fmt_bytes(l.bytes)),
    }
}

/// Sets (or with `None` clears) the explicit process-wide memory limit.
pub fn set_limit(bytes: Option<u64>) {
    LIMIT.store(bytes.unwrap_or(0), Ordering::Relaxed);
}

/// The explicit limit of [`set_limit`], if any (no allocation: safe in an allocator).
pub fn explicit_limit() -> Option<u64> {
    match LIMIT.load(Ordering::Relaxed) {
        0 => None,
        b => Some(b),
    }
}

/// The limit estimates are checked against: the explicit one, else the available memory.
pub fn limit() -> Option<MemoryLimit> {
    if let Some(bytes) = explicit_limit() {
        return Some(MemoryLimit {
            bytes,
            source: LimitSource::Explicit,
        });
    }
    available_memory().map(|bytes| MemoryLimit {
        bytes,
        source: LimitSource::Available,
    })
}

/// `MemAvailable` of `/proc/meminfo` in bytes (Linux), else `None`.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// Checks an estimate `need` (bytes) for `what` against [`limit`].
///
/// # Errors
/// [`MemoryError`] when `need` exceeds the limit.
pub fn check(need: u64, what: impl Into<String>) -> Result<(), MemoryError> {
    match limit() {
        Some(limit) if need > limit.bytes => Err(MemoryError {
            what: what.into(),
            need,
            limit,
        }),
        _ => Ok(()),
    }
}

/// Estimated peak bytes of reading `voxels` samples held as `storage_size` bytes each
/// ([`crate::Samples`]), with `held` bytes of the file already in memory (a format read
/// whole with its header, or decompressed): the file's samples are read straight into their
/// storage and widened in place, and a C-order `.npy` is reordered one block at a time, so
/// the samples themselves are the peak.
pub fn read_bytes(voxels: u64, storage_size: u64, held: u64) -> u64 {
    voxels.saturating_mul(storage_size).saturating_add(held)
}

/// Estimated bytes of the grid (`bytes_per_sample` per voxel) plus a mesh of `tets`
/// tetrahedra.
pub fn mesh_bytes(voxels: u64, bytes_per_sample: u64, tets: u64) -> u64 {
    voxels
        .saturating_mul(bytes_per_sample)
        .saturating_add(tets.saturating_mul(BYTES_PER_TET))
}

/// Extra bytes per tetrahedron of the quality pass (`--quality`) over meshing in memory
/// (adjacency, local regions): 109 B per tetrahedron were measured in all on the MNI white
/// matter (4.84 M tetrahedra, peak RSS 526 MB), against [`BYTES_PER_TET`] without it.
pub const QUALITY_BYTES_PER_TET: u64 = 30;

/// Bytes per tetrahedron a streamed run keeps for the whole run: the analysis's two
/// union–finds and flags (10 B per point, about 0.2 points per tetrahedron), rounded up.
pub const STREAM_BYTES_PER_TET: u64 = 4;

/// Bytes per tetrahedron of a slab in flight (slab-local points, keys and elements, and its
/// chunk in global numbers).
pub const SLAB_BYTES_PER_TET: u64 = 120;

/// Estimated bytes of a streamed run (the mesh goes to disk slab by slab): the grid, what the
/// analysis keeps, and `in_flight` slabs of `layers` holding `tets` tetrahedra in all.
pub fn stream_bytes(
    voxels: u64,
    bytes_per_sample: u64,
    tets: u64,
    layers: u64,
    in_flight: u64,
) -> u64 {
    let per_slab = tets / layers.max(1) + 1;
    voxels
        .saturating_mul(bytes_per_sample)
        .saturating_add(tets.saturating_mul(STREAM_BYTES_PER_TET))
        .saturating_add(per_slab.saturating_mul(in_flight.saturating_mul(SLAB_BYTES_PER_TET)))
}

/// Bytes per voxel of listing the critical points (`--critical`) beyond the samples: the points
/// and regions found and the plateau labels. Peak RSS minus the samples was 81 B per voxel on
/// the noisy 256³ `float32` field (dense critical points), 25 on the MNI T1 and 26 on a 256³
/// `uint8` ball (mostly plateaus); rounded up from the largest.
pub const CRITICAL_BYTES_PER_VOXEL: u64 = 90;

/// Extra bytes per voxel of `--persistence` (the graph, the order and two union–finds): 306
/// measured on the noisy 256³ field, 35 on the MNI T1; rounded up.
pub const PERSISTENCE_BYTES_PER_VOXEL: u64 = 310;

/// Extra bytes per cell of `--spectrum` (the TPTD complex of the whole grid, and the critical
/// points found again): 2.50, 2.41 and 1.86 kB per cell in all measured on 64³ and 96³ crops
/// of the noisy field and a 96³ crop of the MNI T1; rounded up.
pub const SPECTRUM_BYTES_PER_CELL: u64 = 2600;

/// Estimated bytes of `--critical` on a grid of `voxels` samples of `bytes_per_sample` and
/// `cells` cells, with persistence and the contour spectrum when asked for.
pub fn critical_bytes(
    voxels: u64,
    cells: u64,
    bytes_per_sample: u64,
    persistence: bool,
    spectrum: bool,
) -> u64 {
    let per_voxel = bytes_per_sample
        + CRITICAL_BYTES_PER_VOXEL
        + if persistence {
            PERSISTENCE_BYTES_PER_VOXEL
        } else {
            0
        };
    let per_cell = if spectrum { SPECTRUM_BYTES_PER_CELL } else { 0 };
    voxels
        .saturating_mul(per_voxel)
        .saturating_add(cells.saturating_mul(per_cell))
}

/// Estimates the number of tetrahedra of the interval `(alpha, beta)`: 6 per cell whose
/// corners are all inside, 12.5 per cell a bound crosses. Large grids are sampled by z layer.
pub fn estimate_tets(grid: &ScalarGrid, alpha: f64, beta: f64) -> u64 {
    let [cx, cy, cz] = grid.cell_dims();
    let stride = (grid.num_cells() / SAMPLE_CELLS).clamp(1, cz.max(1));
    let layers: Vec<usize> = (0..cz).step_by(stride).collect();
    let (inside, crossing) = layers
        .par_iter()
        .map(|&k| {
            let (mut inside, mut crossing) = (0u64, 0u64);
            for j in 0..cy {
                for i in 0..cx {
                    let v = grid.cell_values(i, j, k);
                    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    if lo > alpha && hi < beta {
                        inside += 1;
                    } else if hi > alpha && lo < beta {
                        crossing += 1;
                    }
                }
            }
            (inside, crossing)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let scale = cz as f64 / layers.len().max(1) as f64;
    let tets = TETS_PER_INSIDE_CELL * inside as f64 + TETS_PER_CROSSING_CELL * crossing as f64;
    (tets * scale) as u64
}

/// Runs `f` as a fallible section: a capping allocator refuses (returns null) instead of
/// ending the process, so `try_reserve` inside `f` reports the failure.
pub fn fallible<T>(f: impl FnOnce() -> T) -> T {
    let old = FALLIBLE.with(|c| c.replace(true));
    let r = f();
    FALLIBLE.with(|c| c.set(old));
    r
}

/// Whether this thread is inside [`fallible`] (no allocation: safe in an allocator).
pub fn in_fallible_section() -> bool {
    FALLIBLE.with(Cell::get)
}

/// Reserves room for `n` more elements in `v` within a fallible section.
///
/// # Errors
/// The allocation failure (or the memory limit).
pub fn try_reserve<T>(v: &mut Vec<T>, n: usize) -> Result<(), TryReserveError> {
    fallible(|| v.try_reserve_exact(n))
}

/// Bytes for messages: `512 B`, `3.2 MiB`, `1.50 GiB`.
pub fn fmt_bytes(b: u64) -> String {
    Bytes(b).to_string()
}

/// A number of bytes that displays with the unit that fits: `512 B`, `1.0 KiB`, `3.2 MiB`,
/// `1.50 GiB`. Displaying it allocates nothing (the out-of-memory message uses it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl std::fmt::Display for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const KIB: f64 = 1024.0;
        let x = self.0 as f64;
        if x < KIB {
            write!(f, "{} B", self.0)
        } else if x < KIB * KIB {
            write!(f, "{:.1} KiB", x / KIB)
        } else if x < KIB * KIB * KIB {
            write!(f, "{:.1} MiB", x / (KIB * KIB))
        } else {
            write!(f, "{:.2} GiB", x / (KIB * KIB * KIB))
        }
    }
}

/// Parses a size: a number of bytes with an optional suffix `K`, `M`, `G`, `T` (powers of
/// 1024; `KiB`, `MB`… and lower case accepted), e.g. `512M`, `1.5G`, `4096`.
pub fn parse_size(s: &str) -> Option<u64> {
    let s = s.trim();
    let split = s
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(s.len());
    let (num, unit) = s.split_at(split);
    let x: f64 = num.parse().ok()?;
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        _ => return None,
    };
    let bytes = x * (1u64 << shift) as f64;
    (bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64).then_some(bytes as u64)
}

impl fmt::Display for LimitSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LimitSource::Explicit => "memory limit",
            LimitSource::Available => "available memory",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_size("4096"), Some(4096));
        assert_eq!(parse_size("512M"), Some(512 << 20));
        assert_eq!(parse_size("1.5g"), Some(3 << 29));
        assert_eq!(parse_size("2 GiB"), Some(2 << 30));
        for bad in ["", "x", "-1G", "0", "1Q", "1e400"] {
            assert_eq!(parse_size(bad), None, "{bad}");
        }
        assert_eq!(fmt_bytes(3 << 29), "1.50 GiB");
    }

    #[test]
    fn critical_estimate_adds_persistence_per_voxel_and_the_spectrum_per_cell() {
        let plain = critical_bytes(1000, 729, 1, false, false);
        assert_eq!(plain, 1000 * (1 + CRITICAL_BYTES_PER_VOXEL));
        assert_eq!(
            critical_bytes(1000, 729, 1, true, true),
            plain + 1000 * PERSISTENCE_BYTES_PER_VOXEL + 729 * SPECTRUM_BYTES_PER_CELL
        );
    }

    #[test]
    fn tets_of_a_full_and_an_empty_interval() {
        let values: Vec<f64> = (0..64).map(|i| (i % 4) as f64).collect();
        let g = ScalarGrid::new([4, 4, 4], values).unwrap();
        assert_eq!(estimate_tets(&g, -1.0, 10.0), 6 * 27);
        assert_eq!(estimate_tets(&g, 10.0, 20.0), 0);
        // every cell crosses 1.5
        assert_eq!(estimate_tets(&g, 1.5, 10.0), (12.5 * 9.0) as u64 + 6 * 9);
    }
}
