//! The scalar grid and THE numbering conventions every table in the crate uses.
//!
//! # Conventions
//! * Grid vertex `(i, j, k)` has linear index `i + nx * (j + ny * k)` (x fastest).
//! * Cell `(i, j, k)` spans grid vertices `(i..=i+1, j..=j+1, k..=k+1)`.
//! * Cell corner `c` in `0..8` is the vertex at offset `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`.
//! * Cell face `f` in `0..6` has normal axis `f / 2` and side `f % 2`
//!   (0 = `-x`, 1 = `+x`, 2 = `-y`, 3 = `+y`, 4 = `-z`, 5 = `+z`).
//! * Index coordinates `(i + u, j + v, k + w)` map to physical coordinates by
//!   `origin + direction * (spacing ⊙ index)` (see [`ScalarGrid::to_physical`]).

use nalgebra::{Affine3, Matrix3, Matrix4, Point3};

use crate::algebra::{array3, matrix3, rows};
pub use crate::samples::{SampleStorage, Samples};

/// A scalar field sampled at the vertices of a regular (possibly oriented) grid.
///
/// Invariants: `values.len() == dims[0] * dims[1] * dims[2]`, every value finite,
/// every dimension at least 2 (checked by [`ScalarGrid::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarGrid {
    /// Number of grid vertices along x, y, z.
    pub dims: [usize; 3],
    /// Distance between neighbouring vertices along each index axis (physical units).
    pub spacing: [f64; 3],
    /// Physical position of vertex (0, 0, 0).
    pub origin: [f64; 3],
    /// Row-major 3×3 matrix whose columns are the unit directions of the index axes.
    pub direction: [[f64; 3]; 3],
    /// Values at the grid vertices, x fastest, in their storage type (see [`Samples`]).
    pub values: Samples,
}

/// Why a grid could not be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GridError {
    /// Some dimension is below 2 (a grid needs at least one cell along each axis).
    #[error("grid dimensions {0:?} must each be at least 2")]
    TooSmall([usize; 3]),
    /// The number of values does not match the dimensions.
    #[error("grid has {got} values but dimensions {dims:?} need {want}")]
    WrongLength {
        /// The grid dimensions.
        dims: [usize; 3],
        /// `dims[0] * dims[1] * dims[2]`.
        want: usize,
        /// The number of values given.
        got: usize,
    },
    /// A value is NaN or infinite; the vertex `(i, j, k)` and the value.
    #[error("value at grid vertex ({0}, {1}, {2}) is not finite ({3})")]
    NotFinite(usize, usize, usize, f64),
    /// A spacing is zero, NaN or infinite.
    #[error("spacing {0:?} must be finite and non-zero")]
    BadSpacing([f64; 3]),
    /// The direction matrix (or the origin) is singular or not finite.
    #[error("direction matrix is singular (its axes are linearly dependent) or not finite")]
    BadDirection,
    /// A curvilinear grid's point has a NaN or infinite coordinate; the vertex `(i, j, k)` and
    /// its position.
    #[error("grid point ({0}, {1}, {2}) has a coordinate that is not finite: {3:?}")]
    NotFinitePoint(usize, usize, usize, [f64; 3]),
}

/// Identity direction matrix.
pub const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Face bit mask of the faces at corner 0 (`-x`, `-y`, `-z`: faces 0, 2, 4).
pub const LOW_FACES: u8 = 0b01_0101;

/// Face bit mask of the faces at corner 7 (`+x`, `+y`, `+z`: faces 1, 3, 5).
pub const HIGH_FACES: u8 = 0b10_1010;

/// Offset of cell corner `c` along each axis.
#[inline]
pub const fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

/// The four corners of cell face `f`, in the cyclic order
/// `(lo, lo) → (hi, lo) → (hi, hi) → (lo, hi)` over the face's two in-plane axes
/// (the lower-numbered in-plane axis first). Entry 0 is the face's smallest corner and
/// entry 2 its largest, so the diagonal `0–2` is the one the conforming 2-triangle split uses.
pub const fn face_corners(f: usize) -> [usize; 4] {
    let axis = f / 2;
    let side = f % 2;
    let (a, b) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let base = side << axis;
    let ea = 1 << a;
    let eb = 1 << b;
    [base, base | ea, base | ea | eb, base | eb]
}

/// The three faces that meet at corner `c`.
pub const fn corner_faces(c: usize) -> [usize; 3] {
    let o = corner_offset(c);
    [o[0], 2 + o[1], 4 + o[2]]
}

/// Bit mask of the grid-box planes that cell `c` lies on (bit `f` for box face `f`, same
/// numbering as cell faces), in a grid of `cell_dims` cells. Zero for interior cells.
#[inline]
pub fn cell_box_planes(c: [usize; 3], cell_dims: [usize; 3]) -> u8 {
    let mut planes = 0u8;
    for axis in 0..3 {
        if c[axis] == 0 {
            planes |= 1 << (2 * axis);
        }
        if c[axis] + 1 == cell_dims[axis] {
            planes |= 1 << (2 * axis + 1);
        }
    }
    planes
}

impl ScalarGrid {
    /// Builds a grid with unit spacing, zero origin and identity direction.
    ///
    /// # Errors
    /// See [`GridError`].
    pub fn new(dims: [usize; 3], values: impl Into<Samples>) -> Result<Self, GridError> {
        Self::with_geometry(dims, [1.0; 3], [0.0; 3], IDENTITY, values)
    }

    /// Builds a grid with the given geometry and checks all invariants.
    ///
    /// # Errors
    /// See [`GridError`].
    pub fn with_geometry(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        direction: [[f64; 3]; 3],
        values: impl Into<Samples>,
    ) -> Result<Self, GridError> {
        let values = values.into();
        if dims.iter().any(|&d| d < 2) {
            return Err(GridError::TooSmall(dims));
        }
        let want = dims[0]
            .checked_mul(dims[1])
            .and_then(|v| v.checked_mul(dims[2]))
            .unwrap_or(usize::MAX);
        if values.len() != want {
            return Err(GridError::WrongLength {
                dims,
                want,
                got: values.len(),
            });
        }
        if spacing.iter().any(|s| !s.is_finite() || *s == 0.0) {
            return Err(GridError::BadSpacing(spacing));
        }
        let g = ScalarGrid {
            dims,
            spacing,
            origin,
            direction,
            values,
        };
        let det = g.affine_determinant();
        if !det.is_finite()
            || det == 0.0
            || condition_number(&direction) >= SINGULAR_CONDITION
            || origin.iter().any(|o| !o.is_finite())
        {
            return Err(GridError::BadDirection);
        }
        let float = !g.values.storage().is_integer();
        let bad = float && g.values.par_any(|v| !v.is_finite());
        if let Some(p) = bad.then(|| g.values.position(|v| !v.is_finite())).flatten() {
            let [i, j, k] = g.vertex_ijk(p);
            return Err(GridError::NotFinite(i, j, k, g.values.get(p)));
        }
        Ok(g)
    }

    /// Number of grid vertices.
    pub fn num_vertices(&self) -> usize {
        self.values.len()
    }

    /// Number of cells along each axis.
    pub fn cell_dims(&self) -> [usize; 3] {
        [self.dims[0] - 1, self.dims[1] - 1, self.dims[2] - 1]
    }

    /// Number of cells.
    pub fn num_cells(&self) -> usize {
        let c = self.cell_dims();
        c[0] * c[1] * c[2]
    }

    /// Linear index of grid vertex (i, j, k).
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// (i, j, k) of a linear vertex index.
    #[inline]
    pub fn vertex_ijk(&self, idx: usize) -> [usize; 3] {
        let i = idx % self.dims[0];
        let r = idx / self.dims[0];
        [i, r % self.dims[1], r / self.dims[1]]
    }

    /// Value at grid vertex (i, j, k).
    #[inline]
    pub fn value(&self, i: usize, j: usize, k: usize) -> f64 {
        self.values.get(self.index(i, j, k))
    }

    /// The eight corner values of cell (i, j, k), in corner order.
    #[inline]
    pub fn cell_values(&self, i: usize, j: usize, k: usize) -> [f64; 8] {
        let base = self.index(i, j, k);
        let sx = 1;
        let sy = self.dims[0];
        let sz = self.dims[0] * self.dims[1];
        self.values.gather([
            base,
            base + sx,
            base + sy,
            base + sx + sy,
            base + sz,
            base + sx + sz,
            base + sy + sz,
            base + sx + sy + sz,
        ])
    }

    /// Linear map from index space to physical space: `direction * diag(spacing)`.
    pub fn linear_map(&self) -> [[f64; 3]; 3] {
        rows(&self.linear_matrix())
    }

    /// [`ScalarGrid::linear_map`] as a `nalgebra` matrix: column `a` is the physical step
    /// along index axis `a`.
    #[inline]
    pub fn linear_matrix(&self) -> Matrix3<f64> {
        let mut m = self.direction_matrix();
        for (c, s) in self.spacing.iter().enumerate() {
            m.column_mut(c).scale_mut(*s);
        }
        m
    }

    /// The direction matrix as a `nalgebra` matrix (columns: unit index-axis directions).
    pub fn direction_matrix(&self) -> Matrix3<f64> {
        matrix3(&self.direction)
    }

    /// The physical position of vertex (0, 0, 0) as a `nalgebra` point.
    pub fn origin_point(&self) -> Point3<f64> {
        Point3::from(self.origin)
    }

    /// The whole index-to-physical map, `x = origin + linear_map · index`, as a `nalgebra`
    /// affine transformation (apply it with `transform_point`).
    pub fn affine(&self) -> Affine3<f64> {
        let mut h = Matrix4::identity();
        h.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&self.linear_matrix());
        h.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&self.origin_point().coords);
        Affine3::from_matrix_unchecked(h)
    }

    /// Builds a grid whose index-to-physical map is `affine` (see [`ScalarGrid::affine`]):
    /// spacing from the column norms of its linear part, direction from the normalised
    /// columns, origin from its translation.
    ///
    /// # Errors
    /// [`GridError::BadSpacing`] for a zero or non-finite column, else see
    /// [`ScalarGrid::with_geometry`].
    pub fn with_affine(
        dims: [usize; 3],
        affine: &Affine3<f64>,
        values: impl Into<Samples>,
    ) -> Result<Self, GridError> {
        let h = affine.matrix();
        let lin: Matrix3<f64> = h.fixed_view::<3, 3>(0, 0).into_owned();
        let origin = array3(&h.fixed_view::<3, 1>(0, 3).into_owned());
        let spacing: [f64; 3] = std::array::from_fn(|c| lin.column(c).norm());
        if spacing.iter().any(|s| !s.is_finite() || *s == 0.0) {
            return Err(GridError::BadSpacing(spacing));
        }
        let direction = std::array::from_fn(|r| std::array::from_fn(|c| lin[(r, c)] / spacing[c]));
        Self::with_geometry(dims, spacing, origin, direction, values)
    }

    /// Determinant of the index-to-physical map; negative means left-handed placement.
    pub fn affine_determinant(&self) -> f64 {
        self.linear_matrix().determinant()
    }

    /// Physical position of index-space point `p`.
    #[inline]
    pub fn to_physical(&self, p: [f64; 3]) -> [f64; 3] {
        self.to_physical_point(&Point3::from(p)).into()
    }

    /// [`ScalarGrid::to_physical`] on `nalgebra` points: `origin + linear_map · p`.
    #[inline]
    pub fn to_physical_point(&self, p: &Point3<f64>) -> Point3<f64> {
        self.origin_point() + self.linear_matrix() * p.coords
    }

    /// Smallest and largest value.
    pub fn value_range(&self) -> (f64, f64) {
        self.values.min_max()
    }
}

/// Condition number at which a direction matrix counts as singular: its inverse has lost
/// every significant digit of an `f64`.
pub const SINGULAR_CONDITION: f64 = 1e15;

/// Condition number above which a direction matrix is *nearly* singular: its tetrahedra come
/// out nearly flat (the CLI warns).
pub const NEAR_SINGULAR_CONDITION: f64 = 1e3;

pub use crate::algebra::{condition_number, det3};

/// A curvilinear (structured, warped) grid: scalar values and a physical position at every
/// vertex of a `dims` lattice. In each cell both the field and the geometry are trilinear in
/// the cell's parameter space (isoparametric hexahedra, as VTK interpolates them).
///
/// `values` is the field on the parameter-space lattice (unit spacing, zero origin, identity
/// direction): the mesher decomposes and clips there, and `crate::curvilinear` maps the
/// result through the cells' trilinear geometry maps.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvilinearGrid {
    /// The field on the parameter-space lattice (index space).
    pub values: ScalarGrid,
    /// Physical position of each grid vertex, numbered like `values` (x fastest).
    pub points: Vec<[f64; 3]>,
}

impl CurvilinearGrid {
    /// Builds a curvilinear grid from vertex values and positions (both x fastest).
    ///
    /// # Errors
    /// The [`GridError`]s of [`ScalarGrid::new`]; [`GridError::WrongLength`] when `points`
    /// does not have one position per vertex; [`GridError::NotFinitePoint`] for the first
    /// position (x fastest) with a NaN or infinite coordinate.
    pub fn new(
        dims: [usize; 3],
        values: impl Into<Samples>,
        points: Vec<[f64; 3]>,
    ) -> Result<Self, GridError> {
        let values = ScalarGrid::new(dims, values)?;
        if points.len() != values.values.len() {
            return Err(GridError::WrongLength {
                dims,
                want: values.values.len(),
                got: points.len(),
            });
        }
        if let Some(n) = points.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            let [i, j, k] = values.vertex_ijk(n);
            return Err(GridError::NotFinitePoint(i, j, k, points[n]));
        }
        Ok(CurvilinearGrid { values, points })
    }

    /// The eight corner positions of cell `c` (corner order of the numbering conventions).
    pub fn cell_points(&self, c: [usize; 3]) -> [[f64; 3]; 8] {
        std::array::from_fn(|k| {
            let o = corner_offset(k);
            self.points[self.values.index(c[0] + o[0], c[1] + o[1], c[2] + o[2])]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn condition_number_of_rotations_shears_and_singular_matrices() {
        let (c, s) = (0.6, 0.8);
        let rot = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        assert!((condition_number(&IDENTITY) - 1.0).abs() < 1e-12);
        assert!((condition_number(&rot) - 1.0).abs() < 1e-12);
        let shear = [[1.0, 1.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1.0]];
        assert!(condition_number(&shear) > NEAR_SINGULAR_CONDITION);
        // the 2-norm condition number itself, not an estimate within a factor of 3
        let thin = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 5e-4]];
        let k = condition_number(&thin);
        assert!((k / 2000.0 - 1.0).abs() < 1e-6, "{k}");
        let (c, s) = (1e-3f64.cos(), 1e-3f64.sin());
        let unit_shear = [[1.0, c, 0.0], [0.0, s, 0.0], [0.0, 0.0, 1.0]];
        let k = condition_number(&unit_shear);
        assert!((k - (1.0 + c) / s).abs() < 1e-6 * k, "{k}");
        assert!(k > NEAR_SINGULAR_CONDITION);
        let flat = [[1.0, 2.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(condition_number(&flat), f64::INFINITY);
    }

    #[test]
    fn the_affine_map_as_nalgebra_types_matches_the_arrays() {
        let (c, s) = (0.6, 0.8);
        let dir = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, -1.0]];
        let vals: Vec<f64> = (0..24).map(|x| x as f64).collect();
        let g = ScalarGrid::with_geometry([2, 3, 4], [0.5, 2.0, 1.5], [1.0, -2.0, 3.0], dir, vals)
            .unwrap();
        assert_eq!(crate::algebra::rows(&g.linear_matrix()), g.linear_map());
        assert_eq!(crate::algebra::rows(&g.direction_matrix()), g.direction);
        let p = [0.25, 1.5, 2.75];
        let x = g.to_physical(p);
        let a = g.affine().transform_point(&Point3::from(p));
        for r in 0..3 {
            assert!((a[r] - x[r]).abs() < 1e-12);
        }
        assert_eq!(g.to_physical_point(&Point3::from(p)), Point3::from(x));
        assert!(g.affine_determinant() < 0.0);
        let back = ScalarGrid::with_affine(g.dims, &g.affine(), g.values.clone()).unwrap();
        for r in 0..3 {
            assert!((back.origin[r] - g.origin[r]).abs() < 1e-15);
            assert!((back.spacing[r] - g.spacing[r]).abs() < 1e-15);
            for c in 0..3 {
                assert!((back.direction[r][c] - g.direction[r][c]).abs() < 1e-15);
            }
        }
        let flat = Affine3::from_matrix_unchecked(Matrix4::from_diagonal(&nalgebra::Vector4::new(
            1.0, 0.0, 1.0, 1.0,
        )));
        assert!(matches!(
            ScalarGrid::with_affine([2, 2, 2], &flat, vec![0.0; 8]),
            Err(GridError::BadSpacing(_))
        ));
    }

    #[test]
    fn face_corners_lie_on_their_face_and_cycle() {
        for f in 0..6 {
            let fc = face_corners(f);
            let axis = f / 2;
            for &c in &fc {
                assert_eq!(corner_offset(c)[axis], f % 2);
            }
            // consecutive corners differ in exactly one bit (cyclic order)
            for t in 0..4 {
                let d = fc[t] ^ fc[(t + 1) % 4];
                assert_eq!(d.count_ones(), 1);
            }
            assert_eq!(fc[0], *fc.iter().min().unwrap());
            assert_eq!(fc[2], *fc.iter().max().unwrap());
        }
        for c in 0..8 {
            for f in corner_faces(c) {
                assert!(face_corners(f).contains(&c));
            }
        }
    }

    #[test]
    fn cell_values_follow_corner_order() {
        let dims = [3, 4, 5];
        let vals: Vec<f64> = (0..60).map(|x| x as f64).collect();
        let g = ScalarGrid::new(dims, vals).unwrap();
        let cv = g.cell_values(1, 2, 3);
        for (c, v) in cv.iter().enumerate() {
            let o = corner_offset(c);
            assert_eq!(*v, g.value(1 + o[0], 2 + o[1], 3 + o[2]));
        }
    }

    #[test]
    fn rejects_bad_grids() {
        assert!(matches!(
            ScalarGrid::new([1, 2, 2], vec![0.0; 4]),
            Err(GridError::TooSmall(_))
        ));
        assert!(matches!(
            ScalarGrid::new([2, 2, 2], vec![0.0; 7]),
            Err(GridError::WrongLength { .. })
        ));
        let mut v = vec![0.0; 8];
        v[5] = f64::NAN;
        assert!(matches!(
            ScalarGrid::new([2, 2, 2], v),
            Err(GridError::NotFinite(1, 0, 1, _))
        ));
    }
}
