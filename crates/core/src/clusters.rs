//! Connected components ("contact clusters") of a boolean map on the periodic torus, or of
//! a map with open edges (a measured surface, [`Boundary::Open`]: no joins across the
//! edges, no wrapping, the border counted in perimeters).
//!
//! Conventions (docs/CONVENTIONS.md):
//! - The map is row-major `rows × cols` (row = y, column = x), periodic in both directions
//!   unless [`label_with`] says [`Boundary::Open`].
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

/// Neighbourhood used to link pixels; serialised as its number of neighbours (4 or 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(into = "u32", try_from = "u32")]
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
}

impl From<Connectivity> for u32 {
    fn from(c: Connectivity) -> u32 {
        c.neighbours()
    }
}

impl TryFrom<u32> for Connectivity {
    type Error = String;
    fn try_from(k: u32) -> Result<Self, String> {
        Self::from_neighbours(k).ok_or_else(|| format!("connectivity {k}: use 4 or 8"))
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

impl Labelling {
    /// Per cluster, whether one of its pixels lies on the map's border (row 0 or
    /// `rows − 1`, column 0 or `cols − 1`): on an open map, a cluster the edge of the
    /// measurement may have cut, whose true area is unknown.
    pub fn touching_border(&self) -> Vec<bool> {
        let mut touching = vec![false; self.clusters.len()];
        let (rows, cols) = (self.rows, self.cols);
        let mut mark = |k: usize| {
            let l = self.labels[k];
            if l > 0 {
                touching[l as usize - 1] = true;
            }
        };
        for c in 0..cols {
            mark(c);
            mark((rows - 1) * cols + c);
        }
        for r in 0..rows {
            mark(r * cols);
            mark(r * cols + cols - 1);
        }
        touching
    }
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

/// Union–find over runs with, per node, the shift (in periods) of its copy of the box
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

/// A maximal horizontal run of contact pixels `x0..=x1` in row `y`.
#[derive(Clone, Copy)]
struct Run {
    y: u32,
    x0: u32,
    x1: u32,
}

/// Runs of each row: `runs[row_start[y]..row_start[y + 1]]`, in order of `x0`.
fn find_runs(contact: &[bool], rows: usize, cols: usize) -> (Vec<Run>, Vec<usize>) {
    let mut runs = Vec::new();
    let mut row_start = Vec::with_capacity(rows + 1);
    for y in 0..rows {
        row_start.push(runs.len());
        let row = &contact[y * cols..(y + 1) * cols];
        let mut x = 0;
        while x < cols {
            // Skip background eight pixels at a time where possible.
            while x + 8 <= cols && row[x..x + 8].iter().all(|&c| !c) {
                x += 8;
            }
            while x < cols && !row[x] {
                x += 1;
            }
            if x == cols {
                break;
            }
            let start = x;
            while x < cols && row[x] {
                x += 1;
            }
            runs.push(Run {
                y: y as u32,
                x0: start as u32,
                x1: (x - 1) as u32,
            });
        }
    }
    row_start.push(runs.len());
    (runs, row_start)
}

/// Label the clusters of `contact` (row-major `rows × cols`, periodic).
///
/// Works on horizontal runs of contact pixels: runs of consecutive rows are joined where
/// they touch (overlap, or also touch at a corner for 8-connectivity), the last and first
/// rows and columns across the periodic edges with the shift of the periodic copy, in one
/// union–find over runs. Areas, perimeters (`4·area − 2·(adjacent pixel pairs)`) and
/// unwrapped bounding boxes are summed per run, so the cost is one scan of the map plus
/// work proportional to the number of runs.
pub fn label(
    contact: &[bool],
    rows: usize,
    cols: usize,
    connectivity: Connectivity,
) -> Result<Labelling, ClusterError> {
    label_with(contact, rows, cols, connectivity, Boundary::Periodic)
}

/// What lies beyond the map's edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Boundary {
    /// The map is one period of a periodic field (a generated surface): clusters join
    /// across the edges, and one that winds around the box is flagged.
    Periodic,
    /// Nothing is known beyond the edges (a measured surface): clusters never join across
    /// them, never wrap, and a cluster's edge on the map's border counts in its perimeter.
    Open,
}

/// [`label`] with the map's `boundary` stated.
pub fn label_with(
    contact: &[bool],
    rows: usize,
    cols: usize,
    connectivity: Connectivity,
    boundary: Boundary,
) -> Result<Labelling, ClusterError> {
    check_shape(contact, rows, cols)?;
    let eight = connectivity == Connectivity::Eight;
    let periodic = boundary == Boundary::Periodic;
    let (runs, row_start) = find_runs(contact, rows, cols);
    let (mut forest, pairs) = join_runs(&runs, &row_start, (rows, cols), eight, periodic);
    let (labels, clusters) = collect_clusters(&runs, &mut forest, &pairs, rows, cols);
    Ok(Labelling {
        rows,
        cols,
        labels,
        clusters,
    })
}

/// The map's shape checked: not empty, `rows × cols` values, labels that fit in `u32`.
fn check_shape(contact: &[bool], rows: usize, cols: usize) -> Result<(), ClusterError> {
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
    Ok(())
}

/// The union–find over runs: runs of consecutive rows joined where they touch (overlap, or
/// also touch at a corner for 8-connectivity), across the periodic edges (if `periodic`)
/// with the shift of the periodic copy; and per run its adjacent pixel pairs (4-neighbour edges inside
/// contact), for perimeters.
fn join_runs(
    runs: &[Run],
    row_start: &[usize],
    (rows, cols): (usize, usize),
    eight: bool,
    periodic: bool,
) -> (ShiftForest, Vec<u64>) {
    let last_col = (cols - 1) as u32;
    let mut forest = ShiftForest::new(runs.len());
    // Adjacent pixel pairs (4-neighbour edges inside contact) per run, for perimeters.
    let mut pairs = vec![0u64; runs.len()];

    // Horizontal pairs inside runs, and the wrap of a row's last run onto its first.
    for y in 0..rows {
        let (a, b) = (row_start[y], row_start[y + 1]);
        for r in a..b {
            pairs[r] += (runs[r].x1 - runs[r].x0) as u64;
        }
        if periodic && b > a && runs[b - 1].x1 == last_col && runs[a].x0 == 0 {
            pairs[b - 1] += 1;
            forest.union((b - 1) as u32, a as u32, (1, 0));
        }
    }

    // Rows `ya` (above) and `yb` (below, `dy` periods down): overlapping runs (vertical
    // pairs; 8-connectivity also joins runs touching at a corner) and, for
    // 8-connectivity, the diagonal links across the left–right edge.
    let mut join_rows = |ya: usize, yb: usize, dy: i32, forest: &mut ShiftForest| {
        let (a0, a1) = (row_start[ya], row_start[ya + 1]);
        let (b0, b1) = (row_start[yb], row_start[yb + 1]);
        if a0 == a1 || b0 == b1 {
            return;
        }
        let reach = u32::from(eight);
        let (mut i, mut j) = (a0, b0);
        while i < a1 && j < b1 {
            let (ra, rb) = (runs[i], runs[j]);
            if ra.x0 <= rb.x1 + reach && rb.x0 <= ra.x1 + reach {
                forest.union(i as u32, j as u32, (0, dy));
                let overlap = ra.x1.min(rb.x1) as i64 - ra.x0.max(rb.x0) as i64 + 1;
                if overlap > 0 {
                    pairs[i] += overlap as u64;
                }
            }
            if ra.x1 < rb.x1 {
                i += 1;
            } else {
                j += 1;
            }
        }
        if eight && periodic {
            // (ya, last column) – (yb, first column), and (ya, first) – (yb, last).
            if runs[a1 - 1].x1 == last_col && runs[b0].x0 == 0 {
                forest.union((a1 - 1) as u32, b0 as u32, (1, dy));
            }
            if runs[a0].x0 == 0 && runs[b1 - 1].x1 == last_col {
                forest.union(a0 as u32, (b1 - 1) as u32, (-1, dy));
            }
        }
    };
    for y in 1..rows {
        join_rows(y - 1, y, 0, &mut forest);
    }
    if periodic {
        join_rows(rows - 1, 0, 1, &mut forest);
    }

    (forest, pairs)
}

/// The clusters from the joined runs, ids in order of first appearance (runs are in
/// row-major order): the label map, and per cluster its area, perimeter, unwrapped extents
/// and whether it wraps.
fn collect_clusters(
    runs: &[Run],
    forest: &mut ShiftForest,
    pairs: &[u64],
    rows: usize,
    cols: usize,
) -> (Vec<u32>, Vec<Cluster>) {
    // Clusters: ids in order of first appearance (runs are in row-major order).
    let mut cluster_of_root = vec![0u32; runs.len()];
    let mut clusters: Vec<Cluster> = Vec::new();
    let mut bounds: Vec<[i64; 4]> = Vec::new(); // min x, max x, min y, max y
    let mut labels = vec![0u32; rows * cols];
    for (r, run) in runs.iter().enumerate() {
        let (root, shift) = forest.find(r as u32);
        let root = root as usize;
        if cluster_of_root[root] == 0 {
            clusters.push(Cluster {
                area_px: 0,
                perimeter_px: 0,
                extent_x_px: 0,
                extent_y_px: 0,
                wraps_x: forest.wraps[root].0,
                wraps_y: forest.wraps[root].1,
            });
            bounds.push([i64::MAX, i64::MIN, i64::MAX, i64::MIN]);
            cluster_of_root[root] = clusters.len() as u32;
        }
        let id = cluster_of_root[root];
        let len = (run.x1 - run.x0 + 1) as u64;
        let c = &mut clusters[id as usize - 1];
        c.area_px += len;
        // Each pixel has 4 edges; each adjacent pair hides 2.
        c.perimeter_px += 4 * len;
        c.perimeter_px -= 2 * pairs[r];
        let start = run.y as usize * cols;
        labels[start + run.x0 as usize..=start + run.x1 as usize].fill(id);
        let ox = shift.0 as i64 * cols as i64;
        let oy = shift.1 as i64 * rows as i64 + run.y as i64;
        let b = &mut bounds[id as usize - 1];
        b[0] = b[0].min(ox + run.x0 as i64);
        b[1] = b[1].max(ox + run.x1 as i64);
        b[2] = b[2].min(oy);
        b[3] = b[3].max(oy);
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
    (labels, clusters)
}
