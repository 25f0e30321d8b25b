//! The cluster table: one row per cluster of every map, as `clusters --out`, `wear` and
//! the Python package write it.

use crate::clusters;

/// One row per cluster of every map, as `clusters --out` and `wear` write them.
#[derive(Default)]
pub struct ClusterRows {
    load_index: Vec<u32>,
    cluster_id: Vec<u32>,
    area_px: Vec<u64>,
    perimeter_px: Vec<u64>,
    extent_x_px: Vec<u32>,
    extent_y_px: Vec<u32>,
    wraps_x: Vec<bool>,
    wraps_y: Vec<bool>,
    percolating: Vec<bool>,
    touches_edge: Vec<bool>,
}

impl ClusterRows {
    pub fn push(&mut self, map: usize, labelling: &clusters::Labelling) {
        self.touches_edge.extend(labelling.touching_border());
        for (k, c) in labelling.clusters.iter().enumerate() {
            self.load_index.push(map as u32);
            self.cluster_id.push(k as u32 + 1);
            self.area_px.push(c.area_px);
            self.perimeter_px.push(c.perimeter_px);
            self.extent_x_px.push(c.extent_x_px);
            self.extent_y_px.push(c.extent_y_px);
            self.wraps_x.push(c.wraps_x);
            self.wraps_y.push(c.wraps_y);
            self.percolating.push(c.percolating());
        }
    }

    /// The clusters' areas in pixels, in row order.
    pub fn areas(&self) -> &[u64] {
        &self.area_px
    }

    /// The maps' indices, in row order.
    pub fn maps(&self) -> &[u32] {
        &self.load_index
    }

    /// The table; `touches_edge` (a pixel on the map's border) only for `open` maps.
    pub fn frame(&self, open: bool) -> anyhow::Result<polars::prelude::DataFrame> {
        use crate::store::table::col;
        let rows = self.area_px.len();
        let mut columns = vec![
            col("load_index", self.load_index.clone()),
            col("cluster_id", self.cluster_id.clone()),
            col("area_px", self.area_px.clone()),
            col("perimeter_px", self.perimeter_px.clone()),
            col("extent_x_px", self.extent_x_px.clone()),
            col("extent_y_px", self.extent_y_px.clone()),
            col("wraps_x", self.wraps_x.clone()),
            col("wraps_y", self.wraps_y.clone()),
            col("percolating", self.percolating.clone()),
        ];
        if open {
            columns.push(col("touches_edge", self.touches_edge.clone()));
        }
        Ok(polars::prelude::DataFrame::new(rows, columns)?)
    }
}
