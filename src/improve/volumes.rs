//! The volumes the pass keeps ([`Volumes`]): the whole mesh's and, with several regions,
//! each region's.

use crate::mesh::TetMesh;

/// The volume of a mesh and of each of its regions (none for one interval).
#[derive(Clone, Debug)]
pub(super) struct Volumes {
    /// The whole mesh's volume.
    pub(super) whole: f64,
    /// Each region's volume (empty for one interval).
    pub(super) regions: Vec<f64>,
}

impl Volumes {
    /// The volume of each region of `mesh` (empty for one interval), summed in tet order.
    pub(super) fn of_regions(mesh: &TetMesh) -> Vec<f64> {
        let mut out = vec![0.0; mesh.regions.count()];
        if out.is_empty() {
            return out;
        }
        for (t, &r) in mesh.regions.tets.iter().enumerate() {
            out[r as usize] += mesh.tet_volume(t);
        }
        out
    }

    /// How far `mesh` is off these volumes: the largest of the relative differences of the
    /// whole volume and of every region's.
    pub(super) fn off(&self, mesh: &TetMesh) -> f64 {
        let whole = (mesh.volume() - self.whole).abs() / self.whole.abs();
        Self::of_regions(mesh)
            .iter()
            .zip(&self.regions)
            .map(|(now, plain)| (now - plain).abs() / plain.abs())
            .fold(whole, f64::max)
    }
}
