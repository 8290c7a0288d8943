//! Isosurfaces: the level sets f = alpha and f = beta as welded, consistently oriented
//! triangle surfaces ([`level_surface`]), and their analysis ([`analysis::analyse_surface`]:
//! area, Betti numbers, closed 2-manifold).
//!
//! The surface is taken from the meshed interval volume: its boundary triangles labelled
//! `alpha` / `beta` already are the level sets of the piecewise-linear field on the
//! decomposition, so with `tptd`/`ctd` they have the topology of the trilinear level sets,
//! and welding (by point identity in the mesher) carries over.

pub mod analysis;

use crate::mesh::{BoundaryLabel, TetMesh, TriSurface};

/// Options of [`level_surface`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceOptions {
    /// Also output the triangles on the grid box (the caps that close the surface).
    pub caps: bool,
    /// The interval's upper bound. When it is infinite (a one-sided interval `f > alpha`), the
    /// caps are oriented into the domain like the alpha level set, so the closed surface is
    /// consistently oriented; otherwise they point out of the domain.
    pub beta: f64,
}

impl Default for SurfaceOptions {
    /// No caps, `beta = +inf`.
    fn default() -> Self {
        SurfaceOptions {
            caps: false,
            beta: f64::INFINITY,
        }
    }
}

/// Whether a boundary triangle with `label` is output, and flipped.
fn selection(label: BoundaryLabel, opts: &SurfaceOptions) -> Option<bool> {
    match label {
        // the mesh boundary points out of {f > alpha}: flip to point towards increasing f
        BoundaryLabel::Level(0) => Some(true),
        // out of {f < beta} (and the interfaces between regions out of the region below):
        // already towards increasing f
        BoundaryLabel::Level(_) => Some(false),
        BoundaryLabel::Box if opts.caps => Some(opts.beta == f64::INFINITY),
        BoundaryLabel::Box => None,
    }
}

/// The level sets of the meshed interval `mesh` (its boundary triangles labelled alpha and
/// beta, plus the box caps with [`SurfaceOptions::caps`]; with several regions every level,
/// the ones between regions from the interfaces), oriented with normals pointing towards
/// increasing f. Triangles are grouped by label in tag order (the levels, then the box), in
/// mesh order within a label; points are numbered by first use, so the output depends only
/// on `mesh` (never on the thread count).
pub fn level_surface(mesh: &TetMesh, opts: &SurfaceOptions) -> TriSurface {
    let mut new_id = vec![u32::MAX; mesh.points.len()];
    let mut out = TriSurface {
        levels: mesh.regions.levels,
        ..TriSurface::default()
    };
    let r = &mesh.regions;
    for label in BoundaryLabel::of_levels(mesh.level_count()) {
        let Some(flip) = selection(label, opts) else {
            continue;
        };
        let outer = mesh.boundary.iter().zip(&mesh.boundary_labels);
        let inner = r.interfaces.iter().zip(&r.interface_labels);
        for (t, _) in outer.chain(inner).filter(|(_, &l)| l == label) {
            let mut ids = t.map(|p| {
                let slot = &mut new_id[p as usize];
                if *slot == u32::MAX {
                    *slot = out.points.len() as u32;
                    out.points.push(mesh.points[p as usize]);
                    out.values.push(mesh.values[p as usize]);
                }
                *slot
            });
            if flip {
                ids.swap(1, 2);
            }
            out.triangles.push(ids);
            out.labels.push(label);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{mesh_interval, MeshOptions, Method, ScalarGrid};

    fn ball(n: usize) -> ScalarGrid {
        let c = (n as f64 - 1.0) / 2.0;
        let mut v = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d = [i as f64 - c, j as f64 - c, k as f64 - c];
                    v.push((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
                }
            }
        }
        ScalarGrid::new([n, n, n], v).unwrap()
    }

    #[test]
    fn a_ball_gives_a_sphere_with_normals_towards_increasing_f() {
        let g = ball(9);
        let m = mesh_interval(&g, &MeshOptions::new(2.5, f64::INFINITY, Method::Ctd))
            .unwrap()
            .mesh;
        let s = level_surface(&m, &SurfaceOptions::default());
        assert!(s.labels.iter().all(|&l| l == BoundaryLabel::ALPHA));
        let a = analysis::analyse_surface(&s);
        assert_eq!(a.betti, [1, 0, 1]);
        assert!(a.closed_manifold && a.oriented);
        // f grows outwards: normals point away from the centre
        let c = 4.0;
        for t in &s.triangles {
            let [p, q, r] = t.map(|i| s.points[i as usize]);
            let n = crate::geom::cross(crate::geom::sub(q, p), crate::geom::sub(r, p));
            let m = [p[0] - c, p[1] - c, p[2] - c];
            assert!(crate::geom::dot(n, m) > 0.0);
        }
        assert!((a.area - 4.0 * std::f64::consts::PI * 6.25).abs() < 0.1 * a.area);
    }

    #[test]
    fn caps_close_a_cut_ball_consistently() {
        let g = ball(9);
        // both levels meet the box (face centres at distance 4, corners at 6.9); two-sided, the
        // caps point out of the domain and the alpha level into it: not consistently oriented
        for (alpha, beta) in [(f64::NEG_INFINITY, 4.5), (4.5, f64::INFINITY), (4.5, 6.5)] {
            let m = mesh_interval(&g, &MeshOptions::new(alpha, beta, Method::Ctd))
                .unwrap()
                .mesh;
            let open = analysis::analyse_surface(&level_surface(&m, &SurfaceOptions::default()));
            assert!(!open.closed_manifold, "({alpha}, {beta}) touches the box");
            let opts = SurfaceOptions { caps: true, beta };
            let closed = analysis::analyse_surface(&level_surface(&m, &opts));
            assert!(closed.closed_manifold, "({alpha}, {beta})");
            assert_eq!(
                closed.oriented,
                alpha == f64::NEG_INFINITY || beta.is_infinite()
            );
        }
    }
}
