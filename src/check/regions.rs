//! The regions of a mesh of several intervals: every tet's region in range, and the faces
//! between tets of two regions exactly the listed interfaces, each on the level between two
//! consecutive regions (the level's index is the upper region's) and oriented out of the
//! region below. (That the regions together cover their domain once is the embedding check of
//! the union; each region's own boundary is then embedded too.)

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::conformity::{face_key, tet_face};
use super::{ProblemKind, Problems};
use crate::mesh::TetMesh;

/// Checks `mesh.regions` (nothing when the mesh has none). Precondition: every index in range.
pub(crate) fn regions(mesh: &TetMesh, problems: &mut Problems) {
    let r = &mesh.regions;
    if r.is_empty() {
        return;
    }
    if r.tets.len() != mesh.tets.len()
        || r.boundary.len() != mesh.boundary.len()
        || r.interface_labels.len() != r.interfaces.len()
    {
        problems.add(ProblemKind::RegionCount, Vec::new());
        return;
    }
    let count = r.count();
    let out_of_range: Vec<usize> = (0..r.tets.len())
        .into_par_iter()
        .filter(|&t| usize::from(r.tets[t]) >= count)
        .collect();
    if !out_of_range.is_empty() {
        out_of_range
            .into_iter()
            .for_each(|t| problems.add(ProblemKind::RegionCount, vec![t]));
        return;
    }
    interfaces(mesh, problems);
}

/// Matches the faces shared by tets of two regions with the listed interfaces.
fn interfaces(mesh: &TetMesh, problems: &mut Problems) {
    let r = &mesh.regions;
    // Listed interface by sorted corners: (index, orientation parity, level).
    let mut listed: FxHashMap<u128, (usize, bool, Option<usize>)> = FxHashMap::default();
    listed.reserve(r.interfaces.len());
    for (i, (&t, l)) in r.interfaces.iter().zip(&r.interface_labels).enumerate() {
        let (key, odd) = face_key(t);
        if listed.insert(key, (i, odd, l.level())).is_some() {
            problems.add(ProblemKind::InterfaceNotBetweenRegions, vec![i]);
        }
    }
    let mut keys: Vec<(u128, u32, u8)> = mesh
        .tets
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, tet)| {
            (0..4).map(move |f| (face_key(tet_face(tet, f)).0, t as u32, f as u8))
        })
        .collect();
    keys.par_sort_unstable();
    let mut matched = vec![false; r.interfaces.len()];
    for pair in keys.chunk_by(|a, b| a.0 == b.0).filter(|g| g.len() == 2) {
        let (a, b) = (pair[0].1 as usize, pair[1].1 as usize);
        let (ra, rb) = (r.tets[a], r.tets[b]);
        if ra == rb {
            continue;
        }
        let (below, f) = if ra < rb {
            (a, pair[0].2)
        } else {
            (b, pair[1].2)
        };
        let out_of_below = face_key(tet_face(&mesh.tets[below], usize::from(f))).1;
        let want = Some(usize::from(ra.max(rb)));
        match listed.get(&pair[0].0) {
            Some(&(i, odd, level))
                if ra.abs_diff(rb) == 1 && level == want && odd == out_of_below =>
            {
                matched[i] = true;
            }
            _ => problems.add(ProblemKind::UnlistedInterface, vec![a, b]),
        }
    }
    for (i, _) in matched.iter().enumerate().filter(|(_, &m)| !m) {
        problems.add(ProblemKind::InterfaceNotBetweenRegions, vec![i]);
    }
}
