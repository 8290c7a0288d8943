//! The later rounds on the part of the mesh they can reach.
//!
//! After the first round, what still needs work is a small part of the mesh, but a round's
//! marking, region extraction and splice each scan the whole mesh. The later rounds therefore
//! run on a copy of the tets within [`RINGS`] rings of the vertices that need work, its *rim*
//! (points with a tet outside the copy) pinned. They do there exactly what they would do on
//! the whole mesh as long as no vertex that needs work is on the rim: a region then never
//! reaches a tet outside, and every point it would free is inside. That is checked at every
//! marking; when it fails, the copy is written back and cut again around the new work.
//!
//! Writing back leaves the tets and faces in the order the rounds would have left them in
//! the whole mesh: each splice keeps what its regions did not touch in order and appends what
//! they made, so the tets (faces) that no round touched stay where they were and the rest
//! follow them in the copy's order. Rounds add no points (only the last stage's splits do);
//! points added here would get the ids the whole mesh would have given them.

use rayon::prelude::*;

use super::region::{retain_flagged, Regions};
use crate::mesh::TetMesh;

/// Rings of tets around the vertices that need work that the copy takes in. More rings copy
/// more; fewer make the work reach the rim more often, and each new cut scans the mesh
/// (measured on the MNI volumes: 3 rings cut once on the white matter, 2.1 · 10⁵ of its
/// 4.6 · 10⁶ tets, and twice on the T1 band; 2 rings cut three times on the T1 band; 4 and 6
/// rings copy 1.5 and 3.2 · 10⁶ of its 7.7 · 10⁶ tets).
pub const RINGS: usize = 3;

/// Not in the copy.
const NONE: u32 = u32::MAX;

/// A copy of part of a mesh with the pass state of its tets and points.
pub struct SubMesh {
    /// The copy (its points in the order of their global ids).
    pub mesh: TetMesh,
    /// Per tet of the copy: its quality.
    pub quality: Vec<f64>,
    /// Per point of the copy: its volume drift.
    pub drift: Vec<f64>,
    /// Per point of the copy: on the rim (a tet outside the copy uses it).
    pub rim: Vec<bool>,
    /// Per point of the copy: on the rim, what the whole mesh said of it
    /// ([`super::thin::rim_marks`]); 0 elsewhere.
    pub rim_marks: Vec<crate::mesh::LabelBits>,
    /// Points of the copy merged away (copy ids).
    pub removed: Vec<u32>,
    /// What the splices left untouched.
    pub untouched: Untouched,
    /// Global id of each point of the copy (ascending) it was cut with.
    points: Vec<u32>,
    /// Global ids of the tets the copy was cut with (ascending).
    tets: Vec<u32>,
    /// Global indices of the boundary faces the copy was cut with (ascending).
    faces: Vec<u32>,
}

/// The tets and faces of a copy that no splice has touched: its first ones, in order.
pub struct Untouched {
    /// Global ids of those tets.
    tets: Vec<u32>,
    /// Global indices of those faces.
    faces: Vec<u32>,
}

/// Whether some point that needs work is on the rim (`work` and `rim` per point of a copy).
pub fn reaches_rim(work: &[bool], rim: &[bool]) -> bool {
    work.par_iter().zip(rim).any(|(&w, &r)| w && r)
}

impl SubMesh {
    /// The tets of `mesh` within `rings` (at least 1) rings of the points `work`, with their
    /// `quality` and their points' `drift` (per tet and per point of `mesh`).
    pub fn cut(
        mesh: &TetMesh,
        work: &[bool],
        rings: usize,
        (quality, drift): (&[f64], &[f64]),
        marks: &[crate::mesh::LabelBits],
    ) -> SubMesh {
        let mut near = work.to_vec();
        for _ in 1..rings {
            super::mark::grow(mesh, &mut near);
        }
        let tets = touching(mesh, &near);
        let mut in_copy = vec![false; mesh.points.len()];
        super::mark::mark_corners(mesh, &mut in_copy, |t| touches(mesh, t as u32, &near));
        let mut local = vec![NONE; mesh.points.len()];
        let mut points = Vec::new();
        for (v, id) in local.iter_mut().enumerate() {
            if in_copy[v] {
                *id = points.len() as u32;
                points.push(v as u32);
            }
        }
        let rim = rim_of(mesh, &near, &local, &points);
        let faces: Vec<u32> = (0..mesh.boundary.len() as u32)
            .into_par_iter()
            .filter(|&f| {
                mesh.boundary[f as usize]
                    .iter()
                    .all(|&v| local[v as usize] != NONE)
            })
            .collect();
        let to_local = |v: &u32| local[*v as usize];
        let sub = TetMesh {
            regions: crate::mesh::Regions {
                levels: mesh.regions.levels,
                tets: match mesh.regions.is_empty() {
                    true => Vec::new(),
                    false => tets
                        .par_iter()
                        .map(|&t| mesh.regions.tets[t as usize])
                        .collect(),
                },
                ..Default::default()
            },
            points: points
                .par_iter()
                .map(|&v| mesh.points[v as usize])
                .collect(),
            values: points
                .par_iter()
                .map(|&v| mesh.values[v as usize])
                .collect(),
            tets: tets
                .par_iter()
                .map(|&t| mesh.tets[t as usize].each_ref().map(to_local))
                .collect(),
            boundary: faces
                .par_iter()
                .map(|&f| mesh.boundary[f as usize].each_ref().map(to_local))
                .collect(),
            boundary_labels: faces
                .par_iter()
                .map(|&f| mesh.boundary_labels[f as usize])
                .collect(),
        };
        SubMesh {
            mesh: sub,
            quality: tets.par_iter().map(|&t| quality[t as usize]).collect(),
            drift: points.par_iter().map(|&v| drift[v as usize]).collect(),
            rim_marks: points
                .iter()
                .zip(&rim)
                .map(|(&v, &r)| if r { marks[v as usize] } else { 0 })
                .collect(),
            rim,
            removed: Vec::new(),
            untouched: Untouched {
                tets: tets.clone(),
                faces: faces.clone(),
            },
            points,
            tets,
            faces,
        }
    }

    /// Writes the copy back into `mesh` (cut from it), with its quality (into `quality`,
    /// per tet), drift (into `drift`, per point) and merged points (appended to `removed`).
    pub fn write_back(
        self,
        mesh: &mut TetMesh,
        quality: &mut Vec<f64>,
        drift: &mut Vec<f64>,
        removed: &mut Vec<u32>,
    ) {
        let n = self.points.len();
        let mut global = self.points;
        for (i, (&x, &f)) in self.mesh.points.iter().zip(&self.mesh.values).enumerate() {
            if i < n {
                let g = global[i] as usize;
                mesh.points[g] = x;
                mesh.values[g] = f;
                drift[g] = self.drift[i];
            } else {
                global.push(mesh.points.len() as u32);
                mesh.points.push(x);
                mesh.values.push(f);
            }
        }
        let to_global = |v: &u32| global[*v as usize];
        removed.extend(self.removed.iter().map(to_global));
        // What stays where it is: everything but the copy's touched tets (faces).
        let keep = |all: &[u32], untouched: &[u32], len: usize| {
            let mut out = vec![true; len];
            for &i in all {
                out[i as usize] = false;
            }
            for &i in untouched {
                out[i as usize] = true;
            }
            out
        };
        let stay = keep(&self.tets, &self.untouched.tets, mesh.tets.len());
        retain_flagged(&mut mesh.tets, &stay);
        retain_flagged(quality, &stay);
        let from = self.untouched.tets.len();
        let tets = &self.mesh.tets[from..];
        mesh.tets
            .extend(tets.iter().map(|t| t.each_ref().map(to_global)));
        if !mesh.regions.is_empty() {
            retain_flagged(&mut mesh.regions.tets, &stay);
            mesh.regions
                .tets
                .extend_from_slice(&self.mesh.regions.tets[from..]);
        }
        quality.extend_from_slice(&self.quality[from..]);
        let stay = keep(&self.faces, &self.untouched.faces, mesh.boundary.len());
        retain_flagged(&mut mesh.boundary, &stay);
        retain_flagged(&mut mesh.boundary_labels, &stay);
        let from = self.untouched.faces.len();
        let faces = &self.mesh.boundary[from..];
        mesh.boundary
            .extend(faces.iter().map(|f| f.each_ref().map(to_global)));
        mesh.boundary_labels
            .extend_from_slice(&self.mesh.boundary_labels[from..]);
        drift.resize(mesh.points.len(), 0.0);
    }
}

impl Untouched {
    /// Keeps those that the splice of `regions` into `mesh` (the copy) keeps where they are
    /// (call before that splice).
    pub fn before_splice(&mut self, mesh: &TetMesh, regions: &Regions) {
        let mut i = 0;
        self.tets.retain(|_| {
            i += 1;
            regions.keeps_tet(i - 1)
        });
        let mut i = 0;
        self.faces.retain(|_| {
            i += 1;
            regions.keeps_face(mesh.boundary[i - 1])
        });
    }
}

/// The tets (ascending) with a corner in `near` (per point).
fn touching(mesh: &TetMesh, near: &[bool]) -> Vec<u32> {
    (0..mesh.tets.len() as u32)
        .into_par_iter()
        .filter(|&t| touches(mesh, t, near))
        .collect()
}

/// Whether tet `t` has a corner in `near`.
fn touches(mesh: &TetMesh, t: u32, near: &[bool]) -> bool {
    mesh.tets[t as usize].iter().any(|&v| near[v as usize])
}

/// Per point of the copy (`local`: copy id per mesh point, `NONE` outside; `points`: the
/// copy's points in copy order; the copy's tets are those with a corner in `near`): whether a
/// tet outside the copy uses it.
fn rim_of(mesh: &TetMesh, near: &[bool], local: &[u32], points: &[u32]) -> Vec<bool> {
    let mut used_outside = vec![false; mesh.points.len()];
    super::mark::mark_corners(mesh, &mut used_outside, |t| {
        let t = t as u32;
        !touches(mesh, t, near) && touches_copy(mesh, t, local)
    });
    points
        .par_iter()
        .map(|&v| used_outside[v as usize])
        .collect()
}

/// Whether tet `t` has a corner in the copy.
fn touches_copy(mesh: &TetMesh, t: u32, local: &[u32]) -> bool {
    mesh.tets[t as usize]
        .iter()
        .any(|&v| local[v as usize] != NONE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::improve::fixtures::{wavy_torus, wavy_torus_mesh, wavy_torus_mesh_at};
    use crate::improve::pass::improve_in;
    use crate::improve::quality_cache::tet_qualities;
    use crate::improve::QualityOptions;

    #[test]
    fn a_copy_written_back_unchanged_leaves_the_mesh_as_it_was() {
        let grid = wavy_torus();
        let (mesh, ctx) = wavy_torus_mesh(&grid);
        let quality = tet_qualities(&mesh, &ctx);
        let drift: Vec<f64> = (0..mesh.points.len()).map(|v| v as f64).collect();
        let work: Vec<bool> = (0..mesh.points.len()).map(|v| v % 97 == 0).collect();
        for rings in [1, 2, 3] {
            let sub = SubMesh::cut(
                &mesh,
                &work,
                rings,
                (&quality, &drift),
                &vec![0; mesh.points.len()],
            );
            assert!(sub.mesh.tets.len() < mesh.tets.len(), "{rings} rings");
            assert!(sub.rim.contains(&true) && sub.rim.contains(&false));
            let (mut back, mut q, mut d, mut removed) =
                (mesh.clone(), quality.clone(), drift.clone(), Vec::new());
            sub.write_back(&mut back, &mut q, &mut d, &mut removed);
            assert_eq!(back, mesh, "{rings} rings");
            assert_eq!((q, d), (quality.clone(), drift.clone()));
            assert!(removed.is_empty());
        }
    }

    #[test]
    fn later_rounds_on_a_copy_give_the_mesh_of_the_whole_mesh() {
        // One ring makes the work reach the rim often: the copy is cut again each time. At
        // this interval the default pass needs a second round.
        let grid = wavy_torus();
        let (alpha, beta) = (-10.0, 2.0);
        let (mesh, _) = wavy_torus_mesh_at(&grid, (alpha, beta));
        let staged = QualityOptions {
            min_angle: 25.0,
            max_angle: 145.0,
            ..QualityOptions::default()
        };
        let mut later = 0;
        for opts in [QualityOptions::default(), staged] {
            let run = |rings| {
                let mut m = mesh.clone();
                let (r, _) = improve_in(
                    &mut m,
                    &grid,
                    &crate::Levels::interval(alpha, beta),
                    &opts,
                    rings,
                    &[],
                );
                (m, r)
            };
            let (whole, report) = run(None);
            later += usize::from(report.rounds > 1);
            for rings in [1, 3] {
                let (copy, r) = run(Some(rings));
                assert_eq!(copy, whole, "{rings} rings, {}°", opts.min_angle);
                assert_eq!(
                    (r.rounds, r.collapses, r.flips, r.smoothed),
                    (
                        report.rounds,
                        report.collapses,
                        report.flips,
                        report.smoothed
                    )
                );
            }
        }
        assert!(later > 0, "no pass needed a later round");
    }
}
