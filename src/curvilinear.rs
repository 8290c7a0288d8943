//! Curvilinear grids: the interval volume is meshed in parameter space (where the grid is the
//! unit lattice and the field is trilinear per cell, so the topology is exactly that of the
//! uniform-grid case) and every point is then mapped through its cell's trilinear geometry
//! map ([`map_mesh`]). Points on a shared face or edge map identically from either cell (the
//! trilinear map restricted to a face is the face's bilinear map), so the mesh stays
//! conforming. Every tet is checked after mapping: a grid whose map would invert one is
//! rejected with the cell named, never written.

use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::extract::{mesh_interval, MeshError, MeshOptions, MeshOutput};
use crate::geom::signed_volume;
use crate::grid::{corner_offset, CurvilinearGrid};
use crate::mesh::TetMesh;

/// Why a curvilinear grid could not be meshed.
#[derive(Debug, thiserror::Error)]
pub enum CurvilinearError {
    /// Meshing in parameter space failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The geometry map of a cell is singular or folded at a corner, or its orientation
    /// differs from the first cell's.
    #[error(
        "cell ({}, {}, {}) is degenerate or folded: its corner Jacobians are {} (the grid's \
         first cell is {})",
        .cell[0], .cell[1], .cell[2], .got, .want
    )]
    FoldedCell {
        /// The cell `(i, j, k)` (its smallest corner).
        cell: [usize; 3],
        /// What its corner Jacobian determinants are.
        got: &'static str,
        /// The orientation of the first cell.
        want: &'static str,
    },
    /// Mapping a tetrahedron through the geometry of cell `cell` would invert or flatten it
    /// (the cell is too strongly curved for its decomposition).
    #[error(
        "cell ({}, {}, {}) is too strongly curved: mapping it through its trilinear geometry \
         inverts a tetrahedron of its decomposition (volume {volume:e}); refine the grid there",
        .cell[0], .cell[1], .cell[2]
    )]
    InvertedTet {
        /// The cell `(i, j, k)` holding the tetrahedron.
        cell: [usize; 3],
        /// The tetrahedron's signed volume after mapping.
        volume: f64,
    },
}

/// Orientation of cell `c`'s geometry map at its 8 corners: 1 all positive, -1 all negative,
/// 0 mixed or singular.
fn cell_orientation(g: &CurvilinearGrid, c: [usize; 3]) -> i8 {
    let x = g.cell_points(c);
    let mut sign = 0i8;
    for k in 0..8 {
        // columns: derivative along each axis at corner k (the edge vector through it)
        let m = Matrix3::from_fn(|r, a| {
            let (lo, hi) = (k & !(1 << a), k | (1 << a));
            x[hi][r] - x[lo][r]
        });
        let d = m.determinant();
        let s = if d > 0.0 {
            1
        } else if d < 0.0 {
            -1
        } else {
            return 0;
        };
        if sign != 0 && s != sign {
            return 0;
        }
        sign = s;
    }
    sign
}

fn sign_name(s: i8) -> &'static str {
    match s {
        1 => "all positive",
        -1 => "all negative",
        _ => "mixed or zero",
    }
}

/// Whether the grid is left-handed (every cell's map has negative corner Jacobians).
///
/// # Errors
/// [`CurvilinearError::FoldedCell`] for the first cell (x fastest) that is singular or
/// folded at a corner, or oriented unlike cell (0, 0, 0).
pub fn left_handed(g: &CurvilinearGrid) -> Result<bool, CurvilinearError> {
    let cd = g.values.cell_dims();
    let cell = |n: usize| [n % cd[0], (n / cd[0]) % cd[1], n / (cd[0] * cd[1])];
    let first = cell_orientation(g, [0, 0, 0]);
    let bad = (0..cd[0] * cd[1] * cd[2])
        .into_par_iter()
        .find_first(|&n| first == 0 || cell_orientation(g, cell(n)) != first);
    match bad {
        Some(n) => Err(CurvilinearError::FoldedCell {
            cell: cell(n),
            got: sign_name(cell_orientation(g, cell(n))),
            want: sign_name(first),
        }),
        None => Ok(first < 0),
    }
}

/// The cell holding parameter-space point `p` (clamped into the grid) and `p`'s local
/// coordinates in it.
fn locate(g: &CurvilinearGrid, p: [f64; 3]) -> ([usize; 3], [f64; 3]) {
    let mut c = [0usize; 3];
    let mut u = [0.0; 3];
    for a in 0..3 {
        let n = g.values.dims[a] - 2;
        c[a] = (p[a].floor().max(0.0) as usize).min(n);
        u[a] = p[a] - c[a] as f64;
    }
    (c, u)
}

/// The physical position of parameter-space point `p`: its cell's trilinear geometry map.
pub fn map_point(g: &CurvilinearGrid, p: [f64; 3]) -> [f64; 3] {
    let (c, u) = locate(g, p);
    let x = g.cell_points(c);
    let mut out = [0.0; 3];
    for (k, xk) in x.iter().enumerate() {
        let o = corner_offset(k);
        let mut w = 1.0;
        for a in 0..3 {
            w *= if o[a] == 1 { u[a] } else { 1.0 - u[a] };
        }
        for r in 0..3 {
            out[r] += w * xk[r];
        }
    }
    out
}

/// Maps `mesh`, made in parameter space (by [`mesh_interval`] on `g.values`), to physical
/// space: every point through its cell's trilinear map; a left-handed grid flips every tet
/// and boundary triangle so orientations stay positive and outward.
///
/// # Errors
/// [`CurvilinearError::FoldedCell`] (see [`left_handed`]) or
/// [`CurvilinearError::InvertedTet`] for the first tet (in mesh order) whose mapped volume is
/// not positive; `mesh` is left unchanged on error.
pub fn map_mesh(mesh: &mut TetMesh, g: &CurvilinearGrid) -> Result<(), CurvilinearError> {
    let flip = left_handed(g)?;
    let mapped: Vec<[f64; 3]> = mesh.points.par_iter().map(|&p| map_point(g, p)).collect();
    let volume = |t: &[u32; 4]| {
        let [a, b, c, d] = t.map(|i| mapped[i as usize]);
        let v = signed_volume(a, b, c, d);
        if flip {
            -v
        } else {
            v
        }
    };
    // `v <= 0` or NaN
    let bad = |v: f64| v.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater);
    if let Some(t) = mesh.tets.par_iter().position_first(|t| bad(volume(t))) {
        let tet = mesh.tets[t];
        let mut centre = [0.0; 3];
        for &i in &tet {
            for a in 0..3 {
                centre[a] += mesh.points[i as usize][a] / 4.0;
            }
        }
        return Err(CurvilinearError::InvertedTet {
            cell: locate(g, centre).0,
            volume: volume(&tet),
        });
    }
    mesh.points = mapped;
    if flip {
        mesh.tets.par_iter_mut().for_each(|t| t.swap(2, 3));
        mesh.boundary.par_iter_mut().for_each(|t| t.swap(1, 2));
    }
    Ok(())
}

/// Meshes `{alpha < f < beta}` of a curvilinear grid: [`mesh_interval`] in parameter space,
/// then [`map_mesh`].
///
/// # Errors
/// See [`CurvilinearError`].
pub fn mesh_curvilinear(
    g: &CurvilinearGrid,
    opts: &MeshOptions,
) -> Result<MeshOutput, CurvilinearError> {
    let mut out = mesh_interval(&g.values, opts)?;
    map_mesh(&mut out.mesh, g)?;
    Ok(out)
}
