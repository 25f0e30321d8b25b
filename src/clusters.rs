//! Connected components ("contact clusters") of a boolean map on the periodic torus.
//!
//! Conventions (docs/CONVENTIONS.md):
//! - The map is row-major `rows × cols` (row = y, column = x), periodic in both directions.
//! - Connectivity 8 (default, as the paper's flood fill) links the 8 surrounding pixels,
//!   including diagonal ones; connectivity 4 links edge neighbours only.
//! - Cluster ids are `1, 2, …` in the order in which a row-major scan first meets a pixel
//!   of the cluster; 0 labels pixels out of contact.
//! - Per cluster: `area_px` (pixels), `perimeter_px` (pixel edges facing a pixel out of
//!   contact, periodic; independent of the connectivity), the extent of its bounding box
//!   in x and y once unwrapped from the torus, and whether it wraps around the box. A
//!   cluster that wraps (it contains a loop winding around the torus, e.g. a band across
//!   the box) has no finite unwrapped extent: it is flagged `percolating` and its extent in
//!   a wrapped direction is reported as the box size.
//!
//! **Method** (linear time, no recursion): a raster scan labels the open box with a
//! union–find over provisional labels (the classic two-pass algorithm); the periodic edges
//! are then joined by a second union–find over those patches that records, for each
//! patch, which periodic copy of the box it sits in relative to its root (an integer shift
//! vector). Joining two pixels of one cluster through different shifts means the cluster
//! winds around the torus (Machta et al. 1996; Newman & Ziff 2001).

use thiserror::Error;

/// Neighbourhood used to link pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Connectivity {
    /// Edge neighbours only.
    Four,
    /// Edge and corner neighbours (the paper's choice).
    #[default]
    Eight,
}

impl Connectivity {
    /// From the number of neighbours, 4 or 8.
    pub fn from_neighbours(k: u32) -> Option<Self> {
        match k {
            4 => Some(Self::Four),
            8 => Some(Self::Eight),
            _ => None,
        }
    }

    /// The number of neighbours, 4 or 8.
    pub fn neighbours(self) -> u32 {
        match self {
            Self::Four => 4,
            Self::Eight => 8,
        }
    }

    fn offsets(self) -> &'static [(isize, isize)] {
        match self {
            Self::Four => &[(-1, 0), (1, 0), (0, -1), (0, 1)],
            Self::Eight => &[
                (-1, -1),
                (-1, 0),
                (-1, 1),
                (0, -1),
                (0, 1),
                (1, -1),
                (1, 0),
                (1, 1),
            ],
        }
    }
}

/// One cluster's measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Cluster {
    /// Pixels in the cluster.
    pub area_px: u64,
    /// Pixel edges facing a pixel out of contact (4 for an isolated pixel).
    pub perimeter_px: u64,
    /// Width of the unwrapped bounding box in x (columns), `cols` if it wraps in x.
    pub extent_x_px: u32,
    /// Height of the unwrapped bounding box in y (rows), `rows` if it wraps in y.
    pub extent_y_px: u32,
    /// Winds around the torus in x.
    pub wraps_x: bool,
    /// Winds around the torus in y.
    pub wraps_y: bool,
}

impl Cluster {
    /// Wraps around the periodic box in at least one direction.
    pub fn percolating(&self) -> bool {
        self.wraps_x || self.wraps_y
    }
}

/// The labelled map and its clusters.
#[derive(Debug, Clone, PartialEq)]
pub struct Labelling {
    pub rows: usize,
    pub cols: usize,
    /// Row-major cluster id per pixel (0: out of contact; id `k` is `clusters[k - 1]`).
    pub labels: Vec<u32>,
    pub clusters: Vec<Cluster>,
}

/// Invalid input to the labelling.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum ClusterError {
    #[error("contact map has {got} values, expected rows × cols = {rows} × {cols}")]
    BadLength {
        rows: usize,
        cols: usize,
        got: usize,
    },
    #[error("contact map is empty ({rows} × {cols}); it needs at least one pixel")]
    Empty { rows: usize, cols: usize },
    #[error("contact map has {rows} × {cols} pixels; labels are 32-bit, at most 2³² − 1")]
    TooLarge { rows: usize, cols: usize },
}

/// Union–find over provisional labels (no shifts: within the open box).
struct Forest {
    parent: Vec<u32>,
}

impl Forest {
    fn make(&mut self) -> u32 {
        let id = self.parent.len() as u32;
        self.parent.push(id);
        id
    }

    fn find(&mut self, mut x: u32) -> u32 {
        // Path halving.
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }

    /// Join the sets of `a` and `b`; the smaller root becomes the root (keeps the
    /// labelling independent of the order of unions).
    fn union(&mut self, a: u32, b: u32) -> u32 {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi as usize] = lo;
        lo
    }
}

/// Union–find over patches with, per node, the shift (in periods) of its copy of the box
/// relative to its parent's, and per root the winding flags.
struct ShiftForest {
    parent: Vec<u32>,
    shift: Vec<(i32, i32)>,
    wraps: Vec<(bool, bool)>,
}

impl ShiftForest {
    fn new(len: usize) -> Self {
        Self {
            parent: (0..len as u32).collect(),
            shift: vec![(0, 0); len],
            wraps: vec![(false, false); len],
        }
    }

    /// Root of `x` and the shift of `x`'s copy relative to the root's; compresses the path.
    fn find(&mut self, x: u32) -> (u32, (i32, i32)) {
        // First pass: the root and the total shift.
        let (mut root, mut total) = (x, (0, 0));
        while self.parent[root as usize] != root {
            let s = self.shift[root as usize];
            total = (total.0 + s.0, total.1 + s.1);
            root = self.parent[root as usize];
        }
        // Second pass: point every node of the path at the root with its own total.
        let (mut node, mut remaining) = (x, total);
        while self.parent[node as usize] != root && node != root {
            let next = self.parent[node as usize];
            let s = self.shift[node as usize];
            self.parent[node as usize] = root;
            self.shift[node as usize] = remaining;
            remaining = (remaining.0 - s.0, remaining.1 - s.1);
            node = next;
        }
        (root, total)
    }

    /// Record that patch `b`'s copy is shifted by `s` from patch `a`'s copy.
    fn union(&mut self, a: u32, b: u32, s: (i32, i32)) {
        let (ra, sa) = self.find(a);
        let (rb, sb) = self.find(b);
        // Copy of b relative to ra: sa + s; relative to rb: sb.
        let want = (sa.0 + s.0, sa.1 + s.1);
        if ra == rb {
            let w = &mut self.wraps[ra as usize];
            w.0 |= want.0 != sb.0;
            w.1 |= want.1 != sb.1;
            return;
        }
        // Shift of rb relative to ra: want − sb. Smaller root stays root.
        let rel = (want.0 - sb.0, want.1 - sb.1);
        let wrap_b = self.wraps[rb as usize];
        let wrap_a = self.wraps[ra as usize];
        let merged = (wrap_a.0 | wrap_b.0, wrap_a.1 | wrap_b.1);
        if ra < rb {
            self.parent[rb as usize] = ra;
            self.shift[rb as usize] = rel;
            self.wraps[ra as usize] = merged;
        } else {
            self.parent[ra as usize] = rb;
            self.shift[ra as usize] = (-rel.0, -rel.1);
            self.wraps[rb as usize] = merged;
        }
    }
}

/// Label the clusters of `contact` (row-major `rows × cols`, periodic).
pub fn label(
    contact: &[bool],
    rows: usize,
    cols: usize,
    connectivity: Connectivity,
) -> Result<Labelling, ClusterError> {
    if rows == 0 || cols == 0 {
        return Err(ClusterError::Empty { rows, cols });
    }
    if contact.len() != rows * cols {
        return Err(ClusterError::BadLength {
            rows,
            cols,
            got: contact.len(),
        });
    }
    if (rows * cols) as u64 >= u32::MAX as u64 {
        return Err(ClusterError::TooLarge { rows, cols });
    }
    let eight = connectivity == Connectivity::Eight;

    // Pass 1: provisional labels over the open box (raster scan, already-visited
    // neighbours: left, and the three above for 8-connectivity).
    const NONE: u32 = u32::MAX;
    let mut labels = vec![NONE; rows * cols];
    let mut forest = Forest {
        parent: Vec::with_capacity(64),
    };
    for y in 0..rows {
        let row = y * cols;
        for x in 0..cols {
            if !contact[row + x] {
                continue;
            }
            let mut label = NONE;
            let join = |other: u32, label: &mut u32, forest: &mut Forest| {
                if other != NONE {
                    *label = if *label == NONE {
                        other
                    } else {
                        forest.union(*label, other)
                    };
                }
            };
            if x > 0 {
                join(labels[row + x - 1], &mut label, &mut forest);
            }
            if y > 0 {
                let up = row - cols;
                join(labels[up + x], &mut label, &mut forest);
                if eight {
                    if x > 0 {
                        join(labels[up + x - 1], &mut label, &mut forest);
                    }
                    if x + 1 < cols {
                        join(labels[up + x + 1], &mut label, &mut forest);
                    }
                }
            }
            labels[row + x] = if label == NONE { forest.make() } else { label };
        }
    }

    // Patches: the components of the open box, numbered 0.. by provisional root.
    let provisional = forest.parent.len();
    let mut patch_of = vec![NONE; provisional];
    let mut patches = 0u32;
    for l in 0..provisional as u32 {
        let r = forest.find(l);
        if patch_of[r as usize] == NONE {
            patch_of[r as usize] = patches;
            patches += 1;
        }
        patch_of[l as usize] = patch_of[r as usize];
    }
    for l in labels.iter_mut().filter(|l| **l != NONE) {
        *l = patch_of[*l as usize];
    }

    // Pass 2: join patches across the periodic edges, recording the shift between copies.
    let mut torus = ShiftForest::new(patches as usize);
    let offsets = connectivity.offsets();
    let (ri, ci) = (rows as isize, cols as isize);
    let mut ring = |y: usize, x: usize| {
        let a = labels[y * cols + x];
        if a == NONE {
            return;
        }
        for &(dy, dx) in offsets {
            let (uy, ux) = (y as isize + dy, x as isize + dx);
            let (sy, sx) = (uy.div_euclid(ri), ux.div_euclid(ci));
            if sy == 0 && sx == 0 {
                continue; // inside the open box: joined in pass 1
            }
            let (wy, wx) = (uy.rem_euclid(ri) as usize, ux.rem_euclid(ci) as usize);
            let b = labels[wy * cols + wx];
            if b != NONE {
                torus.union(a, b, (sx as i32, sy as i32));
            }
        }
    };
    for x in 0..cols {
        ring(0, x);
        if rows > 1 {
            ring(rows - 1, x);
        }
    }
    for y in 1..rows.saturating_sub(1) {
        ring(y, 0);
        if cols > 1 {
            ring(y, cols - 1);
        }
    }

    // Clusters: ids in order of first appearance; area, perimeter and unwrapped bounding
    // box (patch coordinates shifted by the patch's copy).
    let mut cluster_of_root = vec![0u32; patches as usize];
    let mut root_shift = vec![(0i32, 0i32); patches as usize];
    let mut patch_root = vec![0u32; patches as usize];
    for p in 0..patches {
        let (r, s) = torus.find(p);
        patch_root[p as usize] = r;
        root_shift[p as usize] = s;
    }
    let mut clusters: Vec<Cluster> = Vec::new();
    let mut bounds: Vec<[i64; 4]> = Vec::new(); // min x, max x, min y, max y
    for y in 0..rows {
        for x in 0..cols {
            let i = y * cols + x;
            let p = labels[i];
            if p == NONE {
                labels[i] = 0;
                continue;
            }
            let root = patch_root[p as usize] as usize;
            if cluster_of_root[root] == 0 {
                clusters.push(Cluster {
                    area_px: 0,
                    perimeter_px: 0,
                    extent_x_px: 0,
                    extent_y_px: 0,
                    wraps_x: torus.wraps[root].0,
                    wraps_y: torus.wraps[root].1,
                });
                bounds.push([i64::MAX, i64::MIN, i64::MAX, i64::MIN]);
                cluster_of_root[root] = clusters.len() as u32;
            }
            let id = cluster_of_root[root];
            labels[i] = id;
            let c = &mut clusters[id as usize - 1];
            c.area_px += 1;
            let up = if y == 0 { rows - 1 } else { y - 1 };
            let down = if y + 1 == rows { 0 } else { y + 1 };
            let left = if x == 0 { cols - 1 } else { x - 1 };
            let right = if x + 1 == cols { 0 } else { x + 1 };
            c.perimeter_px += [
                contact[up * cols + x],
                contact[down * cols + x],
                contact[y * cols + left],
                contact[y * cols + right],
            ]
            .iter()
            .filter(|&&v| !v)
            .count() as u64;
            let s = root_shift[p as usize];
            let ux = x as i64 + s.0 as i64 * cols as i64;
            let uy = y as i64 + s.1 as i64 * rows as i64;
            let b = &mut bounds[id as usize - 1];
            b[0] = b[0].min(ux);
            b[1] = b[1].max(ux);
            b[2] = b[2].min(uy);
            b[3] = b[3].max(uy);
        }
    }
    for (c, b) in clusters.iter_mut().zip(&bounds) {
        c.extent_x_px = if c.wraps_x {
            cols as u32
        } else {
            (b[1] - b[0] + 1) as u32
        };
        c.extent_y_px = if c.wraps_y {
            rows as u32
        } else {
            (b[3] - b[2] + 1) as u32
        };
    }
    Ok(Labelling {
        rows,
        cols,
        labels,
        clusters,
    })
}
