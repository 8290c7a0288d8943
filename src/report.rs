//! The machine-readable run report (`--report FILE.json`) of `tptd-mesh`.
//!
//! [`build_report`] only assembles data; it does no I/O and prints nothing.

use std::collections::BTreeMap;

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use crate::decompose::CellCase;
use crate::extract::{MeshStats, Method};
use crate::facts::MeshFacts;
use crate::mesh::BoundaryLabel;
use crate::pass_report::{ForcedReport, ImproveReport, TargetCounts};
use crate::quality::QualitySummary;

/// A bound of the interval: finite values serialize as JSON numbers, infinities as the strings
/// `"-inf"` / `"inf"` (JSON has no infinity), so the report is always valid JSON.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound(pub f64);

impl Serialize for Bound {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.is_finite() {
            s.serialize_f64(self.0)
        } else if self.0 > 0.0 {
            s.serialize_str("inf")
        } else if self.0 < 0.0 {
            s.serialize_str("-inf")
        } else {
            s.serialize_none()
        }
    }
}

/// Cell count of one decomposition case.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CaseCount {
    /// Number of cells decomposed with this case.
    pub count: u64,
    /// `count` divided by the number of cells meshed (cells not entirely outside the interval);
    /// 0 when no cell was meshed.
    pub ratio: f64,
}

/// Cell counts per decomposition case, in case order (`i`, `ii`, `iii`, `iv`, `v`,
/// `fallback`); serializes as a JSON object with the keys in that order.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseCounts(pub Vec<(&'static str, CaseCount)>);

impl CaseCounts {
    /// The entry of case `name`, if present.
    pub fn get(&self, name: &str) -> Option<&CaseCount> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, c)| c)
    }
}

impl Serialize for CaseCounts {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (name, count) in &self.0 {
            m.serialize_entry(name, count)?;
        }
        m.end()
    }
}

/// Wall-clock time of each stage, in seconds. The stages add up to `total`: `read + checks +
/// mesh + quality + map + analysis + check + write + other`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Reading (or generating) the input volume.
    pub read: f64,
    /// The checks before meshing: the arguments, the bounds against the grid values and the
    /// critical values, the memory estimate.
    pub checks: f64,
    /// Meshing (with the warping of `--quality`).
    pub mesh: f64,
    /// Betti numbers and dihedral angles (0 when skipped), and the demo's comparison with a
    /// method of the other kind.
    pub analysis: f64,
    /// The quality step (`--quality` only): the sum of `quality_stages`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quality: Option<f64>,
    /// The parts of the quality step (`--quality` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quality_stages: Option<QualityTimings>,
    /// Mapping the mesh through a curvilinear grid's geometry (curvilinear inputs only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map: Option<f64>,
    /// The validity check (`--check` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<f64>,
    /// Grading the interior (`--max-edge` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grade: Option<f64>,
    /// Writing the output mesh.
    pub write: f64,
    /// The rest: `total` less the stages above.
    pub other: f64,
    /// Whole run (up to writing the report).
    pub total: f64,
    /// The mesh went to disk slab by slab while it was made: `mesh` then includes the
    /// analysis of the mesh (and `analysis` is only the demo's comparison).
    pub streamed: bool,
    /// The mesh was analysed slab by slab while it was made (streamed, or held in memory
    /// with nothing changing it afterwards): `mesh` then includes the analysis.
    pub analysed_while_meshing: bool,
}

impl Timings {
    /// Sets `other` to `total` less the stages, so that they add up.
    pub fn close(&mut self) {
        let stages = self.read
            + self.checks
            + self.mesh
            + self.analysis
            + self.quality.unwrap_or(0.0)
            + self.map.unwrap_or(0.0)
            + self.check.unwrap_or(0.0)
            + self.grade.unwrap_or(0.0)
            + self.write;
        self.other = (self.total - stages).max(0.0);
    }
}

/// The parts of the quality step (seconds; they add up to [`Timings::quality`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct QualityTimings {
    /// The quality summary before the pass.
    pub before: f64,
    /// The pass ([`ImproveReport::seconds`], whose `stage_seconds` add up to it).
    pub pass: f64,
    /// What the pass left: the tets off the targets and the reasons of those below the floor.
    pub outcome: f64,
}

impl QualityTimings {
    /// The whole quality step.
    pub fn total(&self) -> f64 {
        self.before + self.pass + self.outcome
    }
}

/// Smallest and largest dihedral angle, in degrees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Dihedral {
    /// Smallest dihedral angle.
    pub min: f64,
    /// Largest dihedral angle.
    pub max: f64,
}

/// Everything `tptd-mesh` reports about one run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// Input path, or `"demo"` for the generated volume.
    pub input: String,
    /// Output path.
    pub output: String,
    /// Grid vertices along x, y, z.
    pub dims: [usize; 3],
    /// Grid spacing along x, y, z.
    pub spacing: [f64; 3],
    /// Storage type of the samples (`uint8`, `int16`, `uint16`, `float32`, `float64`).
    pub samples: &'static str,
    /// Decomposition method name.
    pub method: &'static str,
    /// Lower bound of the interval.
    pub alpha: Bound,
    /// Upper bound of the interval.
    pub beta: Bound,
    /// Number of mesh nodes.
    pub nodes: usize,
    /// Number of tetrahedra.
    pub tets: usize,
    /// The levels of a run of several regions (`--levels` with three or more; absent for one
    /// interval, whose bounds are `alpha` and `beta`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub levels: Vec<Bound>,
    /// Labelled triangles per label (`alpha`, `beta`, `box`; with several regions `level1`,
    /// …, `box`, the levels between regions counting their interface triangles).
    pub boundary_triangles: BTreeMap<String, usize>,
    /// The regions of a run of several levels, in order (absent for one interval).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionReport>,
    /// Cells in the grid.
    pub cells_total: u64,
    /// Cells not entirely outside the interval (the sum over `cells_by_case`).
    pub cells_meshed: u64,
    /// Meshed cells per decomposition case (`i`, `ii`, `iii`, `iv`, `v`, `fallback`).
    pub cells_by_case: CaseCounts,
    /// Total volume of the mesh (physical units).
    pub volume: f64,
    /// Betti numbers `[b0, b1, b2]`; `null` when the analysis was skipped.
    pub betti: Option<[usize; 3]>,
    /// Dihedral angle range in degrees; `null` when the analysis was skipped.
    pub dihedral_degrees: Option<Dihedral>,
    /// The quality pass (`--quality` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quality: Option<QualitySection>,
    /// The isosurface written (surface outputs `.obj`, `.ply`, `.stl` only; set by the caller
    /// after [`build_report`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface: Option<crate::surface::analysis::SurfaceAnalysis>,
    /// The validity check of the mesh (`--check` only; set by the caller after
    /// [`build_report`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<crate::check::CheckReport>,
    /// The graded interior (`--max-edge` only; set by the caller after [`build_report`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grade: Option<crate::grade::GradeReport>,
    /// Worker threads used.
    pub threads: usize,
    /// Stage timings.
    pub timings_seconds: Timings,
    /// Every warning the run printed on stderr, in order, without the `tptd-mesh: warning: `
    /// prefix (set by the caller after [`build_report`]; empty when there was none).
    pub warnings: Vec<String>,
}

/// One region of a run of several levels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RegionReport {
    /// Its name (`--region-names`, default `region1`, …).
    pub name: String,
    /// Its lower and upper level.
    pub levels: [Bound; 2],
    /// Number of tetrahedra.
    pub tets: usize,
    /// Its volume (physical units).
    pub volume: f64,
    /// Betti numbers `[b0, b1, b2]`; `null` when the analysis was skipped.
    pub betti: Option<[usize; 3]>,
    /// Dihedral angle range in degrees; `null` when the analysis was skipped.
    pub dihedral_degrees: Option<Dihedral>,
}

/// What the quality pass did, with the element quality before and after it (both `None` when
/// the analysis was skipped).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QualitySection {
    /// Target smallest and largest dihedral angle (degrees).
    pub target_degrees: [f64; 2],
    /// The `--boundary-collapse-ratio` used (`None`: no limit, `inf`).
    pub boundary_collapse_ratio: Option<f64>,
    /// The `--split-sag` used (`None`: never, `inf`).
    pub split_sag: Option<f64>,
    /// Quality of the mesh as extracted.
    pub before: Option<QualitySummary>,
    /// Quality after the pass.
    pub after: Option<QualitySummary>,
    /// The pass's operation counts and time.
    pub pass: ImproveReport,
    /// The tets left below the floor after the pass, with their reasons (`None` with
    /// `--no-analysis`).
    pub forced: Option<ForcedReport>,
    /// The floor (degrees): tets below it are counted apart and given a reason (`forced`).
    pub floor_degrees: f64,
    /// The tets of the mesh written that miss the targets, or are below the floor.
    pub outcome: TargetCounts,
    /// Some tet misses the targets ([`TargetCounts::missed`]).
    pub target_missed: bool,
}

/// Everything about a run that is not derived from the mesh itself.
#[derive(Clone, Debug)]
pub struct RunInfo<'a> {
    /// Input path, or `"demo"`.
    pub input: &'a str,
    /// Output path.
    pub output: &'a str,
    /// Grid vertices along x, y, z.
    pub dims: [usize; 3],
    /// Grid spacing.
    pub spacing: [f64; 3],
    /// Storage type of the samples.
    pub samples: crate::SampleStorage,
    /// Method used.
    pub method: Method,
    /// Lower bound.
    pub alpha: f64,
    /// Upper bound.
    pub beta: f64,
    /// The levels of several regions (empty for one interval).
    pub levels: &'a [f64],
    /// Worker threads used.
    pub threads: usize,
}

/// Assembles the report of a run from its inputs, mesh, counters and (optional) analysis.
/// Pure: no I/O.
pub fn build_report(
    run: &RunInfo<'_>,
    facts: &MeshFacts,
    stats: &MeshStats,
    quality: Option<QualitySection>,
    timings: Timings,
) -> Report {
    let n = facts.level_count();
    let boundary_triangles: BTreeMap<String, usize> = BoundaryLabel::of_levels(n)
        .map(|l| (l.name_in(n), facts.boundary_triangles[l.index()]))
        .collect();
    let regions = (facts.regions.iter())
        .map(|r| RegionReport {
            name: r.name.clone(),
            levels: r.levels.map(Bound),
            tets: r.tets,
            volume: r.volume,
            betti: r.betti,
            dihedral_degrees: r.dihedral.map(|(min, max)| Dihedral { min, max }),
        })
        .collect();
    let cells_meshed: u64 = stats.cells_by_case.iter().sum();
    let cells_by_case = CaseCounts(
        CellCase::ALL
            .iter()
            .map(|&c| {
                let count = stats.cells_by_case[c as usize];
                let ratio = if cells_meshed == 0 {
                    0.0
                } else {
                    count as f64 / cells_meshed as f64
                };
                (c.name(), CaseCount { count, ratio })
            })
            .collect(),
    );
    Report {
        input: run.input.to_string(),
        output: run.output.to_string(),
        dims: run.dims,
        samples: run.samples.name(),
        spacing: run.spacing,
        method: run.method.name(),
        alpha: Bound(run.alpha),
        beta: Bound(run.beta),
        nodes: facts.nodes,
        tets: facts.tets,
        levels: match run.levels.len() > crate::mesh::INTERVAL_LEVELS {
            true => run.levels.iter().map(|&l| Bound(l)).collect(),
            false => Vec::new(),
        },
        boundary_triangles,
        regions,
        cells_total: stats.cells_total,
        cells_meshed,
        cells_by_case,
        volume: facts.volume,
        betti: facts.betti,
        dihedral_degrees: facts.dihedral.map(|(min, max)| Dihedral { min, max }),
        quality,
        surface: None,
        check: None,
        grade: None,
        threads: run.threads,
        timings_seconds: timings,
        warnings: Vec::new(),
    }
}

impl Report {
    /// The report as pretty-printed JSON (always valid JSON: non-finite numbers never occur
    /// unquoted).
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serializes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TetMesh;

    #[test]
    fn infinite_bounds_serialize_as_strings() {
        let mesh = TetMesh {
            regions: Default::default(),
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            values: vec![0.0; 4],
            tets: vec![[0, 1, 2, 3]],
            boundary: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            boundary_labels: vec![
                BoundaryLabel::Box,
                BoundaryLabel::Box,
                BoundaryLabel::ALPHA,
                BoundaryLabel::ALPHA,
            ],
        };
        let stats = MeshStats {
            cells_by_case: [1, 0, 0, 0, 0, 0],
            cells_total: 8,
        };
        let run = RunInfo {
            input: "demo",
            output: "x.vtu",
            dims: [3, 3, 3],
            spacing: [1.0; 3],
            samples: crate::SampleStorage::U8,
            method: Method::Ctd,
            alpha: f64::NEG_INFINITY,
            beta: f64::INFINITY,
            levels: &[],
            threads: 1,
        };
        let facts = MeshFacts::of(&mesh, false, &[]);
        let r = build_report(&run, &facts, &stats, None, Timings::default());
        let v: serde_json::Value = serde_json::from_str(&r.to_json_pretty()).unwrap();
        assert_eq!(v["alpha"], "-inf");
        assert_eq!(v["samples"], "uint8");
        assert_eq!(v["beta"], "inf");
        assert_eq!(v["boundary_triangles"]["box"], 2);
        assert_eq!(v["boundary_triangles"]["beta"], 0);
        assert_eq!(v["cells_by_case"]["i"]["ratio"], 1.0);
        assert!((r.volume - 1.0 / 6.0).abs() < 1e-12);
        assert!(v["betti"].is_null());
    }
}
