//! Problem set-up from a [`MeshFile`]: conductivity per tet, Dirichlet values on named node
//! groups, the boundary nodes, and the solvability check.

use tptd::io::MeshFile;
use tptd::union_find::UnionFind;
use tptd::TetMesh;

use crate::SolveError;

/// Conductivity of every tet: `default`, replaced by `k` in the regions named in `per_region`.
///
/// # Errors
/// [`SolveError::UnknownGroup`] for a region the mesh does not have, [`SolveError::Invalid`]
/// for a `k` that is not finite and positive.
pub fn conductivity(
    file: &MeshFile,
    default: f64,
    per_region: &[(String, f64)],
) -> Result<Vec<f64>, SolveError> {
    let mut k_region = vec![default; file.regions.len()];
    for (name, k) in per_region {
        let lower = name.to_ascii_lowercase();
        let r = file
            .regions
            .iter()
            .position(|r| *r == lower)
            .ok_or_else(|| SolveError::UnknownGroup {
                kind: "region",
                name: name.clone(),
                available: file.regions.join(", "),
            })?;
        k_region[r] = *k;
    }
    for &k in k_region.iter().chain([&default]) {
        if !(k.is_finite() && k > 0.0) {
            return Err(SolveError::Invalid(format!(
                "conductivity {k} is not positive"
            )));
        }
    }
    Ok(if file.tet_region.is_empty() {
        vec![default; file.mesh.tets.len()]
    } else {
        file.tet_region
            .iter()
            .map(|&r| k_region[r as usize])
            .collect()
    })
}

/// Per node the Dirichlet value from `specs` (`NaN` for free nodes). Groups are applied in
/// order, so a node in two groups gets the value of the later one.
///
/// # Errors
/// [`SolveError::UnknownGroup`] for a name that is not a node group of the mesh,
/// [`SolveError::EmptyGroup`] for a group without nodes, [`SolveError::Invalid`] for a
/// non-finite value.
pub fn dirichlet_values(file: &MeshFile, specs: &[(String, f64)]) -> Result<Vec<f64>, SolveError> {
    let mut g = vec![f64::NAN; file.mesh.points.len()];
    for (name, value) in specs {
        let group = file.group(name).ok_or_else(|| SolveError::UnknownGroup {
            kind: "node group",
            name: name.clone(),
            available: file
                .node_groups
                .iter()
                .map(|g| g.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
        if group.nodes.is_empty() {
            return Err(SolveError::EmptyGroup(name.clone()));
        }
        if !value.is_finite() {
            return Err(SolveError::Invalid(format!(
                "Dirichlet value {value} for {name:?}"
            )));
        }
        for &i in &group.nodes {
            g[i as usize] = *value;
        }
    }
    Ok(g)
}

/// The nodes on the boundary of the mesh (on a face that belongs to one tet only), ascending.
pub fn boundary_nodes(mesh: &TetMesh) -> Vec<u32> {
    let mut faces: Vec<[u32; 3]> = mesh
        .tets
        .iter()
        .flat_map(|t| {
            [
                [t[0], t[1], t[2]],
                [t[0], t[1], t[3]],
                [t[0], t[2], t[3]],
                [t[1], t[2], t[3]],
            ]
            .map(|mut f| {
                f.sort_unstable();
                f
            })
        })
        .collect();
    faces.sort_unstable();
    let mut on = vec![false; mesh.points.len()];
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j] == faces[i] {
            j += 1;
        }
        if j - i == 1 {
            faces[i].iter().for_each(|&v| on[v as usize] = true);
        }
        i = j;
    }
    (0..mesh.points.len() as u32)
        .filter(|&v| on[v as usize])
        .collect()
}

/// Checks that the system is non-singular: every node is in a tet and every connected part
/// of the mesh has a Dirichlet node.
///
/// # Errors
/// [`SolveError::Singular`] naming the problem.
pub fn check_solvable(mesh: &TetMesh, dirichlet: &[f64]) -> Result<(), SolveError> {
    if dirichlet.iter().all(|g| g.is_nan()) {
        return Err(SolveError::Singular(
            "no Dirichlet node (give --dirichlet NAME=VALUE)".into(),
        ));
    }
    let n = mesh.points.len();
    let mut parts = UnionFind::new(n);
    let mut used = vec![false; n];
    for t in &mesh.tets {
        used[t[0] as usize] = true;
        for &v in &t[1..] {
            used[v as usize] = true;
            parts.union(t[0], v);
        }
    }
    if let Some(v) = used.iter().position(|u| !u) {
        return Err(SolveError::Singular(format!(
            "node {} is in no tetrahedron",
            v + 1
        )));
    }
    let mut fixed = vec![false; n];
    for v in 0..n as u32 {
        if !dirichlet[v as usize].is_nan() {
            let r = parts.find(v);
            fixed[r as usize] = true;
        }
    }
    for v in 0..n as u32 {
        if !fixed[parts.find(v) as usize] {
            return Err(SolveError::Singular(format!(
                "the connected part of the mesh containing node {} has no Dirichlet node",
                v + 1
            )));
        }
    }
    Ok(())
}
