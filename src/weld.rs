//! Welding: points by [`PointKey`], first within a slab, then globally in slab order.
//!
//! Each slab (one layer of cells, meshed by one worker) welds its points by key into
//! slab-local numbers ([`Slab`]). The [`Welder`] then numbers the slabs' points globally, one
//! slab after the other in z order: a point on the plane shared with the slab below takes the
//! number it got there, every other point the next free number. Only the keys of one plane
//! are remembered, so the slabs can be handed on as [`MeshChunk`]s (points in physical
//! coordinates, elements in global numbers) and streamed to a [`crate::mesh::MeshSink`]: memory stays
//! bounded by the slabs in flight, whatever the size of the mesh. Numbering depends only on
//! the keys and the slab order, so the output is identical for every thread count and every
//! number of slabs in flight.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::clip::{ClipPoint, ClipSink};
use crate::grid::ScalarGrid;
use crate::keys::{grid_vertex, on_z_plane, vertex_key, vertex_point, PointKey, CORNER};
use crate::mesh::{grow_box, BoundaryLabel, MeshChunk, EMPTY_BOX, NUM_LABELS};

/// More points or tets (the field names which) than 32-bit numbers can number; the mesher
/// reports it as its `MeshError::TooLarge`.
#[derive(Debug)]
pub(crate) struct TooLarge(pub(crate) &'static str);

/// Points, tets and boundary triangles of one slab, numbered locally.
pub(crate) struct Slab {
    /// Slab-local id of each grid vertex on the slab's two planes (`u32::MAX`: none yet).
    corner_ids: Vec<u32>,
    /// Grid index of the first vertex of the slab's lower plane.
    plane_base: usize,
    /// Direct-mapped cache in front of `map` (points recur within and across nearby cells).
    recent: Box<[(PointKey, u32); RECENT]>,
    map: FxHashMap<PointKey, u32>,
    keys: Vec<PointKey>,
    pos: Vec<[f64; 3]>,
    val: Vec<f64>,
    pub(crate) tets: Vec<[u32; 4]>,
    /// With several regions ([`Slab::set_levels`]): the region of each tet.
    pub(crate) regions: Vec<u8>,
    /// The region the clipper is meshing now.
    pub(crate) region: u8,
    /// Index of the last level when there are several regions, else 0.
    last_level: u8,
    tris: Vec<[u32; 3]>,
    labels: Vec<BoundaryLabel>,
    /// With several regions: the region of the tet of each triangle.
    tri_regions: Vec<u8>,
    /// Cells meshed per case.
    pub(crate) cases: [u64; 6],
}

const RECENT: usize = 256;

impl Slab {
    /// An empty slab for layer `k` of a grid with `plane` vertices per z-plane.
    pub(crate) fn new(plane: usize, k: usize) -> Self {
        Slab {
            corner_ids: vec![u32::MAX; 2 * plane],
            plane_base: k * plane,
            recent: Box::new([(PointKey::MAX, 0); RECENT]),
            map: FxHashMap::with_capacity_and_hasher(plane / 4, Default::default()),
            keys: Vec::new(),
            pos: Vec::new(),
            val: Vec::new(),
            tets: Vec::new(),
            regions: Vec::new(),
            region: 0,
            last_level: 0,
            tris: Vec::new(),
            labels: Vec::new(),
            tri_regions: Vec::new(),
            cases: [0; 6],
        }
    }

    /// Reserves room for `meshed` cells (about 7 tets and 2 new points each) so the slab's
    /// vectors do not grow by copying.
    pub(crate) fn reserve(&mut self, meshed: usize) {
        self.tets.reserve(7 * meshed);
        self.keys.reserve(2 * meshed);
        self.pos.reserve(2 * meshed);
        self.val.reserve(2 * meshed);
        self.tris.reserve(meshed);
        self.labels.reserve(meshed);
    }

    /// Meshes `levels` levels (more than two: every tet and triangle is tagged with
    /// [`Slab::region`], and the triangles on a level between regions are kept once, as
    /// interfaces).
    pub(crate) fn set_levels(&mut self, levels: usize) {
        if levels > 2 {
            self.last_level = (levels - 1) as u8;
        }
    }

    /// Whether the slab tags its tets with regions.
    #[inline]
    pub(crate) fn tags_regions(&self) -> bool {
        self.last_level != 0
    }

    /// Drops the lookup structures once the slab's cells are done.
    pub(crate) fn seal(&mut self) {
        self.map = FxHashMap::default();
        self.corner_ids = Vec::new();
    }

    #[inline]
    fn push_point(&mut self, key: PointKey, pos: [f64; 3], val: f64) -> u32 {
        let i = self.keys.len() as u32;
        self.keys.push(key);
        self.pos.push(pos);
        self.val.push(val);
        i
    }

    /// Slab-local id of grid vertex `grid_index` (on one of the slab's two planes).
    #[inline]
    pub(crate) fn corner_id(&mut self, grid_index: usize, pos: [f64; 3], val: f64) -> u32 {
        let slot = grid_index - self.plane_base;
        let id = self.corner_ids[slot];
        if id != u32::MAX {
            return id;
        }
        let id = self.push_point(vertex_point(vertex_key(grid_index, CORNER)), pos, val);
        self.corner_ids[slot] = id;
        id
    }

    #[inline]
    fn id(&mut self, p: &ClipPoint) -> u32 {
        if let Some(gi) = grid_vertex(p.key) {
            return self.corner_id(gi, p.pos, p.val);
        }
        let h = ((p.key as u64) ^ ((p.key >> 64) as u64)).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56;
        let slot = &mut self.recent[h as usize % RECENT];
        if slot.0 == p.key {
            return slot.1;
        }
        if let Some(&i) = self.map.get(&p.key) {
            *slot = (p.key, i);
            return i;
        }
        let i = self.push_point(p.key, p.pos, p.val);
        self.recent[h as usize % RECENT] = (p.key, i);
        self.map.insert(p.key, i);
        i
    }
}

impl ClipSink for Slab {
    #[inline]
    fn tet(&mut self, points: &[ClipPoint], t: [usize; 4]) {
        let ids = t.map(|i| self.id(&points[i]));
        self.tets.push(ids);
        if self.tags_regions() {
            self.regions.push(self.region);
        }
    }
    #[inline]
    fn triangle(&mut self, points: &[ClipPoint], t: [usize; 3], label: BoundaryLabel) {
        if !self.keeps(label) {
            return;
        }
        let ids = t.map(|i| self.id(&points[i]));
        self.tris.push(ids);
        self.labels.push(label);
        if self.tags_regions() {
            self.tri_regions.push(self.region);
        }
    }
    /// A level between two regions is clipped from both sides: its triangles are kept once,
    /// from the region below (normals towards increasing f).
    #[inline]
    fn keeps(&self, label: BoundaryLabel) -> bool {
        !(self.tags_regions() && self.region != 0 && label.level() == Some(self.region as usize))
    }
}

/// Global numbers of the points of one z-plane shared by two slabs: grid vertices in a dense
/// array (indexed by position in the plane), every other point (cuts, saddles of z-faces) in
/// a hash map.
struct PlanePoints {
    corners: Vec<u32>,
    others: FxHashMap<PointKey, u32>,
}

impl PlanePoints {
    fn new(stride: usize) -> Self {
        PlanePoints {
            corners: vec![u32::MAX; stride],
            others: FxHashMap::default(),
        }
    }
}

/// A slab's global numbering: the global number of each slab-local point, and the local
/// points numbered first in this slab, in global order.
struct SlabNumbers {
    map: Vec<u32>,
    fresh: Vec<u32>,
    first_point: usize,
    first_tet: usize,
}

/// Numbers slabs globally, one after the other in z order (see the module documentation).
pub(crate) struct Welder {
    stride: usize,
    /// Points on the lower plane of the next slab.
    prev: PlanePoints,
    top: PlanePoints,
    next_point: u64,
    next_tet: u64,
    next_slab: usize,
    lin: Matrix3<f64>,
    origin: Vector3<f64>,
    /// The frame is left-handed: elements are flipped to keep their orientation.
    flip: bool,
}

impl Welder {
    pub(crate) fn new(grid: &ScalarGrid) -> Self {
        let stride = grid.dims[0] * grid.dims[1];
        Welder {
            stride,
            prev: PlanePoints::new(stride),
            top: PlanePoints::new(stride),
            next_point: 0,
            next_tet: 0,
            next_slab: 0,
            lin: grid.linear_matrix(),
            origin: Vector3::from(grid.origin),
            flip: grid.affine_determinant() < 0.0,
        }
    }

    /// Welds the next slabs (consecutive, starting at the next layer) into chunks.
    ///
    /// # Errors
    /// [`TooLarge`] past 2^32 − 1 points or tets.
    pub(crate) fn weld(&mut self, slabs: Vec<Slab>) -> Result<Vec<MeshChunk>, TooLarge> {
        let mut numbers = Vec::with_capacity(slabs.len());
        for s in &slabs {
            numbers.push(self.number(s)?);
        }
        Ok(slabs
            .into_par_iter()
            .zip(numbers)
            .map(|(s, n)| self.chunk(s, n))
            .collect())
    }

    /// Numbers the points of the next slab; remembers the points on its upper plane.
    fn number(&mut self, s: &Slab) -> Result<SlabNumbers, TooLarge> {
        let k = self.next_slab;
        let stride = self.stride;
        let first_point = self.next_point as usize;
        let first_tet = self.next_tet as usize;
        self.top.corners.fill(u32::MAX);
        let mut map = Vec::with_capacity(s.keys.len());
        let mut fresh = Vec::new();
        for (li, &key) in s.keys.iter().enumerate() {
            let corner = grid_vertex(key);
            let gid = match self.shared(key, corner, k) {
                Some(g) => g,
                None => {
                    let g = u32::try_from(self.next_point).map_err(|_| TooLarge("points"))?;
                    self.next_point += 1;
                    fresh.push(li as u32);
                    g
                }
            };
            match corner {
                Some(gi) if gi / stride == k + 1 => self.top.corners[gi % stride] = gid,
                Some(_) => {}
                None if on_z_plane(key, k + 1, stride) => {
                    self.top.others.insert(key, gid);
                }
                None => {}
            }
            map.push(gid);
        }
        self.next_tet += s.tets.len() as u64;
        if self.next_tet > u64::from(u32::MAX) {
            return Err(TooLarge("tets"));
        }
        std::mem::swap(&mut self.prev.corners, &mut self.top.corners);
        self.prev.others = std::mem::take(&mut self.top.others);
        self.next_slab += 1;
        Ok(SlabNumbers {
            map,
            fresh,
            first_point,
            first_tet,
        })
    }

    /// The global number `key` got in the slab below, if it lies on the shared plane `k`.
    #[inline]
    fn shared(&self, key: PointKey, corner: Option<usize>, k: usize) -> Option<u32> {
        match corner {
            Some(gi) if gi / self.stride == k => {
                Some(self.prev.corners[gi % self.stride]).filter(|&g| g != u32::MAX)
            }
            Some(_) => None,
            None if on_z_plane(key, k, self.stride) => self.prev.others.get(&key).copied(),
            None => None,
        }
    }

    /// Index-space `p` in physical coordinates, summed as the mesher always has
    /// (`origin + a·x + b·y + c·z`, left to right, `a`, `b`, `c` the columns of the linear
    /// map), which is not the association of [`ScalarGrid::to_physical`]
    /// (`origin + (a·x + b·y + c·z)`): keeping it keeps every output byte.
    #[inline]
    fn physical(&self, p: [f64; 3]) -> [f64; 3] {
        let l = &self.lin;
        let x = self.origin + l.column(0) * p[0] + l.column(1) * p[1] + l.column(2) * p[2];
        x.into()
    }

    /// Slab `s` in global numbers `n`, physical coordinates.
    fn chunk(&self, s: Slab, n: SlabNumbers) -> MeshChunk {
        let m = &n.map;
        let points = n
            .fresh
            .iter()
            .map(|&li| self.physical(s.pos[li as usize]))
            .collect();
        let values = n.fresh.iter().map(|&li| s.val[li as usize]).collect();
        let tets = s
            .tets
            .iter()
            .map(|t| {
                let g = t.map(|i| m[i as usize]);
                if self.flip {
                    [g[0], g[1], g[3], g[2]]
                } else {
                    g
                }
            })
            .collect();
        let mut label_boxes = [EMPTY_BOX; NUM_LABELS];
        let boundary = s
            .tris
            .iter()
            .zip(&s.labels)
            .map(|(t, &l)| {
                for &i in t {
                    grow_box(
                        &mut label_boxes[l.index()],
                        self.physical(s.pos[i as usize]),
                    );
                }
                let g = t.map(|i| m[i as usize]);
                if self.flip {
                    [g[0], g[2], g[1]]
                } else {
                    g
                }
            })
            .collect();
        MeshChunk {
            first_point: n.first_point,
            points,
            values,
            first_tet: n.first_tet,
            tets,
            boundary,
            boundary_labels: s.labels,
            label_boxes,
            regions: s.regions,
            boundary_regions: s.tri_regions,
        }
    }
}
