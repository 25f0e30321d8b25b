//! Periodic cluster labelling against hand-built cases and an independent breadth-first
//! search.

use std::collections::VecDeque;

use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use wearcoef::clusters::{label, Cluster, ClusterError, Connectivity, Labelling};

/// Map from a picture: '#' in contact, '.' not; rows top to bottom.
fn map(picture: &[&str]) -> (Vec<bool>, usize, usize) {
    let rows = picture.len();
    let cols = picture[0].len();
    let m = picture
        .iter()
        .flat_map(|r| {
            assert_eq!(r.len(), cols);
            r.chars().map(|c| c == '#')
        })
        .collect();
    (m, rows, cols)
}

fn areas(l: &Labelling) -> Vec<u64> {
    let mut a: Vec<u64> = l.clusters.iter().map(|c| c.area_px).collect();
    a.sort_unstable_by(|x, y| y.cmp(x));
    a
}

/// Reference: breadth-first search on the torus in row-major start order, tracking each
/// pixel's unwrapped position to detect winding and measure extents.
pub fn bfs(
    contact: &[bool],
    rows: usize,
    cols: usize,
    conn: Connectivity,
) -> (Vec<u32>, Vec<Cluster>) {
    let offsets: Vec<(i64, i64)> = match conn {
        Connectivity::Four => vec![(-1, 0), (1, 0), (0, -1), (0, 1)],
        Connectivity::Eight => (-1..=1)
            .flat_map(|dy| (-1..=1).map(move |dx| (dy, dx)))
            .filter(|&(dy, dx)| (dy, dx) != (0, 0))
            .collect(),
    };
    let (r, c) = (rows as i64, cols as i64);
    let mut labels = vec![0u32; rows * cols];
    let mut pos = vec![(0i64, 0i64); rows * cols];
    let mut clusters = Vec::new();
    for start in 0..rows * cols {
        if !contact[start] || labels[start] != 0 {
            continue;
        }
        let id = clusters.len() as u32 + 1;
        let mut cl = Cluster {
            area_px: 0,
            perimeter_px: 0,
            extent_x_px: 0,
            extent_y_px: 0,
            wraps_x: false,
            wraps_y: false,
        };
        let (mut min_x, mut max_x, mut min_y, mut max_y) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        labels[start] = id;
        pos[start] = ((start / cols) as i64, (start % cols) as i64);
        let mut queue = VecDeque::from([start]);
        while let Some(i) = queue.pop_front() {
            let (py, px) = pos[i];
            cl.area_px += 1;
            min_x = min_x.min(px);
            max_x = max_x.max(px);
            min_y = min_y.min(py);
            max_y = max_y.max(py);
            for (dy, dx) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let j = ((py + dy).rem_euclid(r) * c + (px + dx).rem_euclid(c)) as usize;
                if !contact[j] {
                    cl.perimeter_px += 1;
                }
            }
            for &(dy, dx) in &offsets {
                let (uy, ux) = (py + dy, px + dx);
                let j = (uy.rem_euclid(r) * c + ux.rem_euclid(c)) as usize;
                if !contact[j] {
                    continue;
                }
                if labels[j] == 0 {
                    labels[j] = id;
                    pos[j] = (uy, ux);
                    queue.push_back(j);
                } else if pos[j] != (uy, ux) {
                    cl.wraps_y |= pos[j].0 != uy;
                    cl.wraps_x |= pos[j].1 != ux;
                }
            }
        }
        cl.extent_x_px = if cl.wraps_x {
            cols as u32
        } else {
            (max_x - min_x + 1) as u32
        };
        cl.extent_y_px = if cl.wraps_y {
            rows as u32
        } else {
            (max_y - min_y + 1) as u32
        };
        clusters.push(cl);
    }
    (labels, clusters)
}

#[test]
fn single_pixels_have_perimeter_four() {
    let (m, r, c) = map(&["....", ".#..", "...#", "...."]);
    let l = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(l.clusters.len(), 2);
    for cl in &l.clusters {
        assert_eq!((cl.area_px, cl.perimeter_px), (1, 4));
        assert_eq!((cl.extent_x_px, cl.extent_y_px), (1, 1));
        assert!(!cl.percolating());
    }
}

#[test]
fn diagonal_links_count_only_with_eight_neighbours() {
    let (m, r, c) = map(&["#....", ".#...", "..#..", ".....", "....."]);
    let eight = label(&m, r, c, Connectivity::Eight).unwrap();
    let four = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(areas(&eight), vec![3]);
    assert_eq!(eight.clusters[0].perimeter_px, 12);
    assert_eq!(
        (eight.clusters[0].extent_x_px, eight.clusters[0].extent_y_px),
        (3, 3)
    );
    assert_eq!(areas(&four), vec![1, 1, 1]);
}

#[test]
fn clusters_merge_across_each_edge_and_a_corner() {
    // Left–right edge.
    let (m, r, c) = map(&["......", "#....#", "......", "......"]);
    let l = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(areas(&l), vec![2]);
    assert_eq!(
        (l.clusters[0].extent_x_px, l.clusters[0].extent_y_px),
        (2, 1)
    );
    assert_eq!(l.clusters[0].perimeter_px, 6);
    // Top–bottom edge.
    let (m, r, c) = map(&["..#...", "......", "......", "..#..."]);
    let l = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(areas(&l), vec![2]);
    assert_eq!(
        (l.clusters[0].extent_x_px, l.clusters[0].extent_y_px),
        (1, 2)
    );
    // The four corners form one 2×2 block across both edges (4-connected).
    let (m, r, c) = map(&["#....#", "......", "......", "#....#"]);
    let l = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(areas(&l), vec![4]);
    assert_eq!(
        (l.clusters[0].extent_x_px, l.clusters[0].extent_y_px),
        (2, 2)
    );
    assert_eq!(l.clusters[0].perimeter_px, 8);
    // Two opposite corners touch only diagonally across the corner of the box.
    let (m, r, c) = map(&["#.....", "......", "......", ".....#"]);
    assert_eq!(
        areas(&label(&m, r, c, Connectivity::Eight).unwrap()),
        vec![2]
    );
    assert_eq!(
        areas(&label(&m, r, c, Connectivity::Four).unwrap()),
        vec![1, 1]
    );
    // Diagonal link across the left–right edge only.
    let (m, r, c) = map(&["......", ".....#", "#.....", "......"]);
    assert_eq!(
        areas(&label(&m, r, c, Connectivity::Eight).unwrap()),
        vec![2]
    );
    assert_eq!(
        areas(&label(&m, r, c, Connectivity::Four).unwrap()),
        vec![1, 1]
    );
}

#[test]
fn bands_across_the_box_are_flagged_as_percolating() {
    let (m, r, c) = map(&["......", "######", "......", "..#..."]);
    let l = label(&m, r, c, Connectivity::Eight).unwrap();
    assert_eq!(l.clusters.len(), 2);
    let band = &l.clusters[0];
    assert!(band.wraps_x && !band.wraps_y && band.percolating());
    assert_eq!((band.extent_x_px, band.extent_y_px), (6, 1));
    assert_eq!(band.perimeter_px, 12);
    assert!(!l.clusters[1].percolating());
    // A diagonal staircase winding in both directions (8-connected only).
    let (m, r, c) = map(&["#...", ".#..", "..#.", "...#"]);
    let l = label(&m, r, c, Connectivity::Eight).unwrap();
    assert_eq!(l.clusters.len(), 1);
    assert!(l.clusters[0].wraps_x && l.clusters[0].wraps_y);
    let l = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(l.clusters.len(), 4);
    assert!(l.clusters.iter().all(|c| !c.percolating()));
    // A U shape joined across the left–right edge but not winding: not percolating.
    let (m, r, c) = map(&["#....#", "#....#", "##..##", "......"]);
    let l = label(&m, r, c, Connectivity::Four).unwrap();
    assert_eq!(l.clusters.len(), 1);
    assert!(!l.clusters[0].percolating());
    assert_eq!(
        (l.clusters[0].extent_x_px, l.clusters[0].extent_y_px),
        (4, 3)
    );
}

#[test]
fn empty_and_full_maps() {
    let l = label(&[false; 12], 3, 4, Connectivity::Eight).unwrap();
    assert!(l.clusters.is_empty());
    assert!(l.labels.iter().all(|&v| v == 0));
    for conn in [Connectivity::Four, Connectivity::Eight] {
        let l = label(&[true; 12], 3, 4, conn).unwrap();
        assert_eq!(l.clusters.len(), 1);
        let c = l.clusters[0];
        assert_eq!((c.area_px, c.perimeter_px), (12, 0));
        assert!(c.wraps_x && c.wraps_y);
        assert_eq!((c.extent_x_px, c.extent_y_px), (4, 3));
        assert!(l.labels.iter().all(|&v| v == 1));
    }
}

#[test]
fn bad_input_is_an_error() {
    assert_eq!(
        label(&[true; 5], 2, 3, Connectivity::Eight),
        Err(ClusterError::BadLength {
            rows: 2,
            cols: 3,
            got: 5
        })
    );
    assert_eq!(
        label(&[], 0, 3, Connectivity::Eight),
        Err(ClusterError::Empty { rows: 0, cols: 3 })
    );
}

#[test]
fn random_maps_match_breadth_first_search() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let mut percolating_seen = 0;
    for trial in 0..400 {
        let rows = rng.random_range(1..=24usize);
        let cols = rng.random_range(1..=24usize);
        let fill = [0.05, 0.2, 0.4, 0.6, 0.8][trial % 5];
        let m: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(fill)).collect();
        for conn in [Connectivity::Four, Connectivity::Eight] {
            let l = label(&m, rows, cols, conn).unwrap();
            let (labels, clusters) = bfs(&m, rows, cols, conn);
            assert_eq!(l.labels, labels, "trial {trial} {rows}×{cols} {conn:?}");
            assert_eq!(l.clusters, clusters, "trial {trial} {rows}×{cols} {conn:?}");
            percolating_seen += clusters.iter().filter(|c| c.percolating()).count();
        }
    }
    assert!(
        percolating_seen > 50,
        "the sample must exercise winding clusters"
    );
}

/// Reference for open edges: breadth-first search on the rectangle, neighbours beyond the
/// edges absent (and each border edge of a contact pixel counted in the perimeter).
fn open_bfs(
    contact: &[bool],
    rows: usize,
    cols: usize,
    conn: Connectivity,
) -> (Vec<u32>, Vec<Cluster>) {
    let reach: i64 = 1;
    let (r, c) = (rows as i64, cols as i64);
    let inside = |y: i64, x: i64| (0..r).contains(&y) && (0..c).contains(&x);
    let mut labels = vec![0u32; rows * cols];
    let mut clusters = Vec::new();
    for start in 0..rows * cols {
        if !contact[start] || labels[start] != 0 {
            continue;
        }
        let id = clusters.len() as u32 + 1;
        let mut cl = Cluster {
            area_px: 0,
            perimeter_px: 0,
            extent_x_px: 0,
            extent_y_px: 0,
            wraps_x: false,
            wraps_y: false,
        };
        let (mut min_x, mut max_x, mut min_y, mut max_y) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        labels[start] = id;
        let mut queue = VecDeque::from([start]);
        while let Some(i) = queue.pop_front() {
            let (py, px) = ((i / cols) as i64, (i % cols) as i64);
            cl.area_px += 1;
            (min_x, max_x, min_y, max_y) =
                (min_x.min(px), max_x.max(px), min_y.min(py), max_y.max(py));
            for (dy, dx) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (y, x) = (py + dy, px + dx);
                if !inside(y, x) || !contact[(y * c + x) as usize] {
                    cl.perimeter_px += 1;
                }
            }
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let diagonal = dy != 0 && dx != 0;
                    if (dy, dx) == (0, 0) || (diagonal && conn == Connectivity::Four) {
                        continue;
                    }
                    let (y, x) = (py + dy, px + dx);
                    if !inside(y, x) {
                        continue;
                    }
                    let j = (y * c + x) as usize;
                    if contact[j] && labels[j] == 0 {
                        labels[j] = id;
                        queue.push_back(j);
                    }
                }
            }
        }
        cl.extent_x_px = (max_x - min_x + 1) as u32;
        cl.extent_y_px = (max_y - min_y + 1) as u32;
        clusters.push(cl);
    }
    (labels, clusters)
}

/// Open edges: a band across the map is one cluster on the torus (winding) but, with open
/// edges, the pixels on opposite edges stay apart; on random maps of every density, shape
/// and both connectivities, labels and clusters equal the open breadth-first search.
#[test]
fn open_edges_never_join_and_match_an_open_search() {
    use wearcoef::clusters::{label_with, Boundary};
    let (m, r, c) = map(&["#...#", ".....", "#...#", "#...."]);
    let torus = label_with(&m, r, c, Connectivity::Eight, Boundary::Periodic).unwrap();
    let open = label_with(&m, r, c, Connectivity::Eight, Boundary::Open).unwrap();
    assert_eq!(torus.clusters.len(), 1, "the corners meet on the torus");
    assert_eq!(open.clusters.len(), 4);
    assert!(open.clusters.iter().all(|cl| !cl.percolating()));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for trial in 0..200 {
        let (rows, cols) = (rng.random_range(1..40usize), rng.random_range(1..40usize));
        let density = rng.random_range(0.05..0.95);
        let m: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(density)).collect();
        for conn in [Connectivity::Four, Connectivity::Eight] {
            let l = label_with(&m, rows, cols, conn, Boundary::Open).unwrap();
            let (labels, clusters) = open_bfs(&m, rows, cols, conn);
            assert_eq!(l.labels, labels, "trial {trial}, {rows} × {cols}, {conn:?}");
            assert_eq!(
                l.clusters, clusters,
                "trial {trial}, {rows} × {cols}, {conn:?}"
            );
        }
    }
}

/// A cluster with a pixel on any of the four edges touches the border; one inside does
/// not; on random maps, against a direct scan of each cluster's pixels.
#[test]
fn clusters_touching_the_border_are_flagged() {
    use wearcoef::clusters::{label_with, Boundary};
    let (m, r, c) = map(&[
        "..#....", ".......", "...##..", ".......", "#.....#", "...#...",
    ]);
    let l = label_with(&m, r, c, Connectivity::Eight, Boundary::Open).unwrap();
    let touching = l.touching_border();
    let inside: Vec<bool> = l.clusters.iter().map(|cl| cl.area_px == 2).collect();
    assert_eq!(l.clusters.len(), 5);
    for (t, i) in touching.iter().zip(&inside) {
        assert_eq!(*t, !*i);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for _ in 0..100 {
        let (rows, cols) = (rng.random_range(1..30usize), rng.random_range(1..30usize));
        let m: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(0.4)).collect();
        let l = label_with(&m, rows, cols, Connectivity::Eight, Boundary::Open).unwrap();
        let mut expected = vec![false; l.clusters.len()];
        for (k, &id) in l.labels.iter().enumerate() {
            let (y, x) = (k / cols, k % cols);
            if id > 0 && (y == 0 || x == 0 || y + 1 == rows || x + 1 == cols) {
                expected[id as usize - 1] = true;
            }
        }
        assert_eq!(l.touching_border(), expected);
    }
}
