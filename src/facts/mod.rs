//! [`MeshFacts`]: the numbers the report and the summary give about a mesh (counts, volume,
//! dihedral range, Betti numbers), from a mesh in memory ([`MeshFacts::of`]) or gathered
//! chunk by chunk while it streams to disk ([`FactsSink`]). Both give the same numbers, bit
//! for bit: the volume is summed in the same fixed blocks, the extremes and the component
//! counts do not depend on order.

use std::io;

use rayon::prelude::*;

use crate::geom::signed_volume;
mod regions;

pub use regions::RegionFacts;

pub use crate::mesh::Tee;
use crate::mesh::{BoundaryLabel, MeshChunk, MeshSink, INTERVAL_LEVELS};
use crate::mesh::{TetMesh, NUM_LABELS, VOLUME_BLOCK};
use crate::quality::{cosine_extremes, cosines_to_degrees, dihedral_range, widest, NO_COSINES};
use crate::topology::betti;
use crate::union_find::UnionFind;

/// What the report says about a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFacts {
    /// Number of nodes.
    pub nodes: usize,
    /// Number of tets.
    pub tets: usize,
    /// Boundary triangles per label, in [`crate::BoundaryLabel::ALL`] order.
    pub boundary_triangles: [usize; NUM_LABELS],
    /// Total volume.
    pub volume: f64,
    /// Smallest and largest dihedral angle in degrees (`None`: not analysed, or no tet).
    pub dihedral: Option<(f64, f64)>,
    /// Betti numbers (`None`: not analysed).
    pub betti: Option<[usize; 3]>,
    /// With several regions, the facts of each (empty for one interval).
    pub regions: Vec<RegionFacts>,
}

impl MeshFacts {
    /// Number of levels the labels name: 2 for one interval.
    pub fn level_count(&self) -> usize {
        match self.regions.len() {
            0 => INTERVAL_LEVELS,
            n => n + 1,
        }
    }
}

impl MeshFacts {
    /// The facts of `mesh`; `analyse`: with the dihedral range and the Betti numbers. With
    /// several regions, `levels` are the run's levels (the regions' bounds in the facts).
    pub fn of(mesh: &TetMesh, analyse: bool, levels: &[f64]) -> Self {
        let mut boundary_triangles = [0; NUM_LABELS];
        let labels = mesh.boundary_labels.iter();
        for &l in labels.chain(&mesh.regions.interface_labels) {
            boundary_triangles[l.index()] += 1;
        }
        MeshFacts {
            nodes: mesh.points.len(),
            tets: mesh.tets.len(),
            boundary_triangles,
            volume: mesh.volume(),
            dihedral: if analyse { dihedral_range(mesh) } else { None },
            betti: analyse.then(|| betti(mesh)),
            regions: region_facts(mesh, analyse, levels),
        }
    }
}

/// The facts of each region of `mesh` (none for one interval).
fn region_facts(mesh: &TetMesh, analyse: bool, levels: &[f64]) -> Vec<RegionFacts> {
    let r = &mesh.regions;
    if r.is_empty() {
        return Vec::new();
    }
    let mut acc = regions::RegionsAcc::new(r.levels, analyse);
    let corners = |t: &[u32; 4]| t.map(|i| mesh.points[i as usize]);
    let vols: Vec<f64> = (mesh.tets.par_iter())
        .map(|t| {
            let [a, b, c, d] = corners(t);
            signed_volume(a, b, c, d)
        })
        .collect();
    let cos: Vec<(f64, f64)> = match analyse {
        true => (mesh.tets.par_iter())
            .map(|t| cosine_extremes(corners(t)))
            .collect(),
        false => Vec::new(),
    };
    acc.add(&regions::as_chunk(mesh), mesh.points.len(), &vols, &cos);
    acc.finish(&|k| r.name(k), levels)
}

/// Union–find of the tets' and the boundary triangles' vertices, grown chunk by chunk.
#[derive(Default)]
struct Components {
    solid: UnionFind,
    surface: UnionFind,
    used: Vec<bool>,
    on_boundary: Vec<bool>,
}

impl Components {
    /// Makes room for points `0..n`.
    fn grow(&mut self, n: usize) {
        if n > self.used.len() {
            self.solid.grow(n);
            self.surface.grow(n);
            self.used.resize(n, false);
            self.on_boundary.resize(n, false);
        }
    }

    #[inline]
    fn add_tet(&mut self, t: &[u32; 4]) {
        for &v in t {
            self.used[v as usize] = true;
        }
        self.solid.union_all(t);
    }

    #[inline]
    fn add_triangle(&mut self, t: &[u32; 3]) {
        for &v in t {
            self.on_boundary[v as usize] = true;
        }
        self.surface.union_all(t);
    }

    /// Adds the tets and the outer boundary triangles of `c` (not its interfaces).
    fn add(&mut self, c: &MeshChunk, levels: usize) {
        self.grow(c.first_point + c.points.len());
        c.tets.iter().for_each(|t| self.add_tet(t));
        for (t, l) in c.boundary.iter().zip(&c.boundary_labels) {
            if !l.is_interface(levels) {
                self.add_triangle(t);
            }
        }
    }

    /// Betti numbers, as [`betti`] computes them from the same counts.
    fn betti(mut self, boundary_triangles: usize) -> [usize; 3] {
        if !self.used.iter().any(|&u| u) {
            return [0, 0, 0];
        }
        let b0 = self.solid.count_roots(&self.used);
        let surfaces = self.surface.count_roots(&self.on_boundary);
        let vb = self.on_boundary.iter().filter(|&&x| x).count() as i64;
        crate::topology::betti_from_counts(b0, surfaces, vb, boundary_triangles as i64)
    }
}

/// A [`MeshSink`] gathering [`MeshFacts`] while the mesh streams (it keeps the points of the
/// last two chunks: a tet uses points of its own chunk and of the one before).
pub struct FactsSink {
    analyse: bool,
    nodes: usize,
    tets: usize,
    boundary_triangles: [usize; NUM_LABELS],
    /// Volumes of the tets of the unfinished block, and the sums of the finished ones.
    block: Vec<f64>,
    partials: Vec<f64>,
    cos_range: (f64, f64),
    components: Option<Components>,
    prev: (usize, Vec<[f64; 3]>),
    cur: (usize, Vec<[f64; 3]>),
    /// The run's levels (two for one interval).
    levels: Vec<f64>,
    /// With several regions: their names and running facts.
    regions: Option<(Vec<String>, regions::RegionsAcc)>,
}

impl FactsSink {
    /// A sink for an empty mesh; `analyse`: also the dihedral range and the Betti numbers.
    pub fn new(analyse: bool) -> Self {
        FactsSink {
            analyse,
            nodes: 0,
            tets: 0,
            boundary_triangles: [0; NUM_LABELS],
            block: Vec::with_capacity(VOLUME_BLOCK),
            partials: Vec::new(),
            cos_range: NO_COSINES,
            components: analyse.then(|| Components {
                solid: UnionFind::new(0),
                surface: UnionFind::new(0),
                used: Vec::new(),
                on_boundary: Vec::new(),
            }),
            prev: (0, Vec::new()),
            cur: (0, Vec::new()),
            levels: Vec::new(),
            regions: None,
        }
    }

    /// Also gathers the facts of each region of a run of several `levels` (more than two),
    /// named by `names` (missing ones: [`crate::mesh::region_name`]).
    pub fn with_regions(mut self, levels: &[f64], names: Vec<String>) -> Self {
        if levels.len() > INTERVAL_LEVELS {
            let acc = regions::RegionsAcc::new(levels.len(), self.analyse);
            self.regions = Some((names, acc));
            self.levels = levels.to_vec();
        }
        self
    }

    /// The facts of everything received.
    pub fn finish(mut self) -> MeshFacts {
        if !self.block.is_empty() {
            self.partials.push(self.block.iter().sum());
        }
        let dihedral = (self.analyse && self.tets > 0).then(|| cosines_to_degrees(self.cos_range));
        let levels = self.levels.len().max(INTERVAL_LEVELS);
        let nb = (BoundaryLabel::ALL.iter())
            .filter(|&&l| !l.is_interface(levels))
            .map(|l| self.boundary_triangles[l.index()])
            .sum();
        MeshFacts {
            nodes: self.nodes,
            tets: self.tets,
            boundary_triangles: self.boundary_triangles,
            volume: self.partials.iter().sum(),
            dihedral,
            betti: self.components.map(|c| c.betti(nb)),
            regions: match self.regions {
                Some((names, acc)) => {
                    acc.finish(&|k| crate::mesh::region_name(&names, k), &self.levels)
                }
                None => Vec::new(),
            },
        }
    }

    /// The corners of tet `t` (of the current chunk).
    #[inline]
    fn corners(&self, t: &[u32; 4]) -> [[f64; 3]; 4] {
        t.map(|i| {
            let i = i as usize;
            if i >= self.cur.0 {
                self.cur.1[i - self.cur.0]
            } else {
                self.prev.1[i - self.prev.0]
            }
        })
    }

    /// Adds the volumes of `tets` to the block sums, in order; returns them.
    fn add_volumes(&mut self, tets: &[[u32; 4]]) -> Vec<f64> {
        let vols: Vec<f64> = tets
            .par_iter()
            .map(|t| {
                let [a, b, c, d] = self.corners(t);
                signed_volume(a, b, c, d)
            })
            .collect();
        for &v in &vols {
            self.block.push(v);
            if self.block.len() == VOLUME_BLOCK {
                self.partials.push(self.block.iter().sum());
                self.block.clear();
            }
        }
        vols
    }

    /// Widens the range of dihedral cosines by the tets of `tets`; returns each tet's
    /// extremes when `per_tet`.
    fn add_cosines(&mut self, tets: &[[u32; 4]], per_tet: bool) -> Vec<(f64, f64)> {
        if per_tet {
            let each: Vec<(f64, f64)> = (tets.par_iter())
                .map(|t| cosine_extremes(self.corners(t)))
                .collect();
            self.cos_range = each.iter().copied().fold(self.cos_range, widest);
            return each;
        }
        let r = tets
            .par_iter()
            .map(|t| cosine_extremes(self.corners(t)))
            .reduce(|| NO_COSINES, widest);
        self.cos_range = widest(self.cos_range, r);
        Vec::new()
    }
}

impl MeshSink for FactsSink {
    fn chunk(&mut self, c: &MeshChunk) -> io::Result<()> {
        self.prev = std::mem::take(&mut self.cur);
        self.cur = (c.first_point, c.points.clone());
        self.nodes += c.points.len();
        self.tets += c.tets.len();
        for &l in &c.boundary_labels {
            self.boundary_triangles[l.index()] += 1;
        }
        let vols = self.add_volumes(&c.tets);
        let per_tet = self.regions.is_some();
        let cos = match self.analyse {
            true => self.add_cosines(&c.tets, per_tet),
            false => Vec::new(),
        };
        let levels = self.levels.len().max(INTERVAL_LEVELS);
        // The whole mesh's components and the regions' facts are independent.
        let (components, regions) = (&mut self.components, &mut self.regions);
        rayon::join(
            || {
                if let Some(comp) = components {
                    comp.add(c, levels);
                }
            },
            || {
                if let Some((_, acc)) = regions {
                    acc.add(c, c.first_point + c.points.len(), &vols, &cos);
                }
            },
        );
        Ok(())
    }
}
