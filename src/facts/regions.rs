//! The facts of each region of a mesh of several intervals ([`RegionFacts`]), gathered chunk
//! by chunk in tet order (in memory, the mesh is one chunk): tets, volume (summed in the same
//! fixed blocks as the whole mesh's), dihedral range and Betti numbers. A region's boundary is
//! the outer boundary of its tets and the interfaces on its two levels.

use rayon::prelude::*;

use super::Components;
use crate::mesh::{BoundaryLabel, MeshChunk, TetMesh, VOLUME_BLOCK};
use crate::quality::{cosines_to_degrees, widest, NO_COSINES};

/// What the report says about one region.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionFacts {
    /// The region's name.
    pub name: String,
    /// Its lower and upper level.
    pub levels: [f64; 2],
    /// Number of tets.
    pub tets: usize,
    /// Total volume.
    pub volume: f64,
    /// Smallest and largest dihedral angle in degrees (`None`: not analysed, or no tet).
    pub dihedral: Option<(f64, f64)>,
    /// Betti numbers (`None`: not analysed).
    pub betti: Option<[usize; 3]>,
}

/// One region's running sums.
struct Acc {
    tets: usize,
    block: Vec<f64>,
    partials: Vec<f64>,
    cos_range: (f64, f64),
    components: Option<Components>,
    triangles: usize,
}

impl Acc {
    /// Adds the tets of region `k` in chunk `c` (the mesh has `n` points up to it; the
    /// chunk's tets have volumes and cosine extremes `facts`) and the triangles that bound
    /// it, in a run of `levels` levels.
    fn add(
        &mut self,
        k: u8,
        c: &MeshChunk,
        n: usize,
        facts: (&[f64], &[(f64, f64)]),
        levels: usize,
    ) {
        let (vols, cos) = facts;
        if let Some(comp) = &mut self.components {
            comp.grow(n);
        }
        for (t, (&r, &v)) in c.regions.iter().zip(vols).enumerate() {
            if r != k {
                continue;
            }
            self.tets += 1;
            self.block.push(v);
            if self.block.len() == VOLUME_BLOCK {
                self.partials.push(self.block.iter().sum());
                self.block.clear();
            }
            if let Some(&cr) = cos.get(t) {
                self.cos_range = widest(self.cos_range, cr);
            }
            if let Some(comp) = &mut self.components {
                comp.add_tet(&c.tets[t]);
            }
        }
        let triangles = c.boundary.iter().zip(&c.boundary_labels);
        for ((tri, &l), &r) in triangles.zip(&c.boundary_regions) {
            if bounds(l, r, k, levels) {
                self.triangles += 1;
                if let Some(comp) = &mut self.components {
                    comp.add_triangle(tri);
                }
            }
        }
    }
}

/// Whether a triangle labelled `l` of (lower) region `r` bounds region `k`: it bounds its own
/// region, and an interface also the region above.
#[inline]
fn bounds(l: BoundaryLabel, r: u8, k: u8, levels: usize) -> bool {
    r == k || (r + 1 == k && l.is_interface(levels))
}

/// The running facts of every region.
pub(super) struct RegionsAcc {
    levels: usize,
    acc: Vec<Acc>,
}

impl RegionsAcc {
    /// Sums for the `levels - 1` regions of a run of `levels` levels.
    pub(super) fn new(levels: usize, analyse: bool) -> Self {
        let acc = (1..levels)
            .map(|_| Acc {
                tets: 0,
                block: Vec::new(),
                partials: Vec::new(),
                cos_range: NO_COSINES,
                components: analyse.then(Components::default),
                triangles: 0,
            })
            .collect();
        RegionsAcc { levels, acc }
    }

    /// Adds chunk `c` (the mesh has `n` points up to it), whose tets have volumes `vols` and
    /// dihedral cosine extremes `cos` (empty when not analysed). The regions are independent:
    /// each takes its own tets and triangles of the chunk, in order, on its own thread.
    pub(super) fn add(&mut self, c: &MeshChunk, n: usize, vols: &[f64], cos: &[(f64, f64)]) {
        let levels = self.levels;
        (self.acc.par_iter_mut().enumerate())
            .for_each(|(k, a)| a.add(k as u8, c, n, (vols, cos), levels));
    }

    /// The facts of each region, named by `names` and bounded by `levels`.
    pub(super) fn finish(
        self,
        names: &dyn Fn(usize) -> String,
        levels: &[f64],
    ) -> Vec<RegionFacts> {
        self.acc
            .into_iter()
            .enumerate()
            .map(|(k, mut a)| {
                if !a.block.is_empty() {
                    a.partials.push(a.block.iter().sum());
                }
                let analysed = a.components.is_some();
                RegionFacts {
                    name: names(k),
                    levels: [levels[k], levels[k + 1]],
                    tets: a.tets,
                    volume: a.partials.iter().sum(),
                    dihedral: (analysed && a.tets > 0).then(|| cosines_to_degrees(a.cos_range)),
                    betti: a.components.map(|c| c.betti(a.triangles)),
                }
            })
            .collect()
    }
}

/// The mesh's regions as one chunk (the interfaces listed with the boundary, as the mesher
/// streams them).
pub(super) fn as_chunk(mesh: &TetMesh) -> MeshChunk {
    let r = &mesh.regions;
    let mut boundary = mesh.boundary.clone();
    boundary.extend_from_slice(&r.interfaces);
    let mut labels = mesh.boundary_labels.clone();
    labels.extend_from_slice(&r.interface_labels);
    let mut boundary_regions = r.boundary.clone();
    boundary_regions.extend(r.interface_labels.iter().map(|l| match l.level() {
        Some(i) => (i - 1) as u8,
        None => 0,
    }));
    MeshChunk {
        tets: mesh.tets.clone(),
        boundary,
        boundary_labels: labels,
        regions: r.tets.clone(),
        boundary_regions,
        ..MeshChunk::default()
    }
}
