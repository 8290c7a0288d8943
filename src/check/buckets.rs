//! A uniform grid of buckets over the bounding boxes of a triangle set: each triangle is
//! listed in every bucket its bounding box overlaps (compressed rows, in triangle order).

use rayon::prelude::*;

/// Buckets over triangles. Preconditions: every point finite.
pub(crate) struct Buckets {
    /// Lowest corner of the grid.
    pub(crate) origin: [f64; 3],
    /// Edge length of a (cubic) bucket.
    pub(crate) size: f64,
    /// Buckets along each axis.
    pub(crate) dims: [usize; 3],
    /// `start[b]..start[b + 1]` indexes `items` for bucket `b`.
    start: Vec<u32>,
    /// Triangle ids, grouped by bucket, ascending within a bucket.
    items: Vec<u32>,
    /// Per triangle: the lowest and highest bucket coordinates of its bounding box.
    pub(crate) ranges: Vec<[[u32; 3]; 2]>,
}

/// Bounding box `[min, max]` of a triangle.
pub(crate) fn bbox(t: &[[f64; 3]; 3]) -> [[f64; 3]; 2] {
    let mut b = [t[0], t[0]];
    for p in &t[1..] {
        for k in 0..3 {
            b[0][k] = b[0][k].min(p[k]);
            b[1][k] = b[1][k].max(p[k]);
        }
    }
    b
}

impl Buckets {
    /// Buckets for `tris` (their corner positions): about one bucket per triangle, and no
    /// bucket smaller than the mean bounding-box extent, so a triangle spans a few at most.
    pub(crate) fn new(tris: &[[[f64; 3]; 3]]) -> Self {
        let boxes: Vec<[[f64; 3]; 2]> = tris.par_iter().map(bbox).collect();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut extent = 0.0;
        for b in &boxes {
            for k in 0..3 {
                lo[k] = lo[k].min(b[0][k]);
                hi[k] = hi[k].max(b[1][k]);
                extent += b[1][k] - b[0][k];
            }
        }
        if boxes.is_empty() {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        let n = tris.len().max(1) as f64;
        let mean = extent / (3.0 * n);
        let side = [0, 1, 2].map(|k| (hi[k] - lo[k]).max(0.0));
        let vol = side
            .iter()
            .map(|s| s.max(mean).max(f64::MIN_POSITIVE))
            .product::<f64>();
        let mut size = (vol / n).cbrt().max(mean);
        if !(size.is_finite() && size > 0.0) {
            size = 1.0;
        }
        // At most 2^21 buckets per axis.
        let dims = side.map(|s| ((s / size) as usize + 1).min(1 << 21));
        let cell = |x: f64, k: usize| -> u32 {
            let c = ((x - lo[k]) / size).max(0.0) as usize;
            c.min(dims[k] - 1) as u32
        };
        let ranges: Vec<[[u32; 3]; 2]> = boxes
            .par_iter()
            .map(|b| {
                [
                    [0, 1, 2].map(|k| cell(b[0][k], k)),
                    [0, 1, 2].map(|k| cell(b[1][k], k)),
                ]
            })
            .collect();
        let nb = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; nb + 1];
        let index =
            |c: [u32; 3]| c[0] as usize + dims[0] * (c[1] as usize + dims[1] * c[2] as usize);
        let each = |r: &[[u32; 3]; 2], f: &mut dyn FnMut(usize)| {
            for z in r[0][2]..=r[1][2] {
                for y in r[0][1]..=r[1][1] {
                    for x in r[0][0]..=r[1][0] {
                        f(index([x, y, z]));
                    }
                }
            }
        };
        for r in &ranges {
            each(r, &mut |b| count[b + 1] += 1);
        }
        for b in 0..nb {
            count[b + 1] += count[b];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[nb] as usize];
        for (t, r) in ranges.iter().enumerate() {
            each(r, &mut |b| {
                items[fill[b] as usize] = t as u32;
                fill[b] += 1;
            });
        }
        Buckets {
            origin: lo,
            size,
            dims,
            start: count,
            items,
            ranges,
        }
    }

    /// Number of buckets.
    pub(crate) fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Linear index of bucket `c`.
    pub(crate) fn index(&self, c: [u32; 3]) -> usize {
        c[0] as usize + self.dims[0] * (c[1] as usize + self.dims[1] * c[2] as usize)
    }

    /// The triangles listed in bucket `b`.
    pub(crate) fn items(&self, b: usize) -> &[u32] {
        &self.items[self.start[b] as usize..self.start[b + 1] as usize]
    }

    /// Bucket coordinate of `x` along axis `k`, clamped to the grid (the same rounding as the
    /// triangles' ranges, so a point of a triangle's box lies in one of its buckets).
    pub(crate) fn cell(&self, x: f64, k: usize) -> u32 {
        let c = ((x - self.origin[k]) / self.size).max(0.0) as usize;
        c.min(self.dims[k] - 1) as u32
    }
}
