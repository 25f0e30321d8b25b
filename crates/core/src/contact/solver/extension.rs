//! The free-set extension of the preconditioner (the default, [`super::SolverConfig::extension`]).
//!
//! `M = P K⁻¹ P` answers a slow modulation `f` of the gradient over the free set F with
//! `f · P K⁻¹ 1_F`, the stiff local response of each cluster, while the restricted operator
//! answers it with the compliance of the whole surface under a load of density φ (the local
//! fraction of F): the long modes are over-weighted by about φ L / a (a the cluster size), and
//! the iteration count grows with the contact fraction and the box. The extension gives the
//! surface off F the smoothed gradient, so that `K⁻¹` sees a slow modulation as a slow field:
//!
//! `M_E = P Eᵀ K⁻¹ E P`, `E = 1_F + (1 − 1_F) Σ_t γ_t D_t⁻¹ S_t 1_F`,
//! `Eᵀ = 1_F + Σ_t γ_t 1_F S_t D_t⁻¹ (1 − 1_F)`,
//!
//! with, for each term t, `S_t = U G_t Uᵀ / c²` (`Uᵀ`: sums over cells of c × c nodes, `U`:
//! the cell's value on its nodes, `G_t`: a periodic Gaussian on the cells), `D_t = max(S_t
//! 1_F, D_min)` the smoothed density of F. Two terms share the cells: the long one (σ = 32
//! nodes, γ = 0.5) and the near one (σ = 6 nodes, γ = 0.3), which together continue the
//! gradient across the clusters' edges, where `M` alone jumps from the gradient to zero. A
//! third, far term (σ = 512 nodes, γ = 0.2) smooths on coarser cells (64 × 64 nodes, sums of
//! the 8² cells, so `S_far = U_f G U_fᵀ / c_f²` has the same form): it carries modulations
//! over many λ_l, which only boxes much larger than σ_far hold, so it is built on large boxes
//! only ([`Extension::large_box`]).
//! Any extension gives `Eᵀ K⁻¹ E ≥ (P K P)⁻¹` on F, with equality for the one of least
//! elastic energy, so the closer `E` comes to it the fewer iterations; but while the contact
//! set still moves, the near term makes it oscillate, so it is used only once the set has
//! settled ([`Extension::settled_fraction`]), and the far term once the direction is no
//! longer restarted ([`Extension::far_fraction`]; used from the first iteration it makes the
//! cold loads of a 4096² sweep crawl). `M_E` is symmetric and positive like `M` (the
//! same `D_t` on both sides), equal to `M` in full contact (`E = 1`), and costs one pass over
//! `p` and `w` for the cell sums plus two smoothings per term on the coarse grid (n/c per
//! side) per iteration. The floor `D_min` fades the extension out where F is sparse, where
//! `M` is already accurate.

use rayon::prelude::*;

use super::constraint::Constraint;
use super::deflation::{Bilinear, Deflation};
use super::level::{Level, OffBlock};
use super::operator::Operator;
use super::preconditioner::{Coefficients, Fields, PreconditionSums, Preconditioner};
use super::restricted::Restricted;

/// The preconditioner `P Eᵀ K⁻¹ E P`: the restricted one's passes with the extension's
/// rows (its input `E g`, its sums off F, its correction on F), the near and far terms and
/// the deflation switched as the contact set settles.
pub(super) struct Extended {
    restricted: Restricted,
    coarse: Coarse,
}

impl Extended {
    /// The extension with `settings` on `op`'s grid, deflated where the box is large enough.
    pub(super) fn new<O: Operator>(op: &O, settings: Extension) -> Self {
        let mut coarse = Coarse::new(op.grid().n(), op.rows_per_block(), settings);
        coarse.deflate(op);
        Self {
            restricted: Restricted::new(op),
            coarse,
        }
    }
}

impl<C: Constraint, O: Operator> Preconditioner<C, O> for Extended {
    fn settle(&mut self, changes: Option<(usize, f64)>) -> bool {
        self.coarse.settle(changes)
    }

    fn entry_margin(&self, error_scale: f64) -> f64 {
        self.coarse.entry_margin(error_scale)
    }

    /// `K⁻¹ E g` on F: the cells' sums gathered first, the input rows `E g`, the values off F
    /// summed per cell in the output pass for the correction `Σ γ S D⁻¹ (1 − 1_F) y` that
    /// the direction pass adds on F.
    fn precondition(&mut self, fields: &mut Fields<'_, O>, level: Level<C>) -> PreconditionSums {
        self.coarse
            .gather(fields.pressure, fields.separation, level);
        let coarse = &self.coarse;
        Restricted::input(fields, |i, row, p, w| coarse.input_row(i, row, p, w, level));
        let (cell, m, bilinear, blocks) = self.coarse.output_parts();
        let sums = self.restricted.output(
            fields,
            level,
            blocks.par_iter_mut(),
            |block, r, row, p, w| Coarse::output_row(cell, m, bilinear, block, r, row, p, w, level),
        );
        let (sum_b, sum_gb) = self.coarse.finish(sums[0]);
        PreconditionSums::new(sums, sum_b, sum_gb)
    }

    fn direction(&mut self, fields: &mut Fields<'_, O>, coefficients: Coefficients) -> f64 {
        let (coarse, c) = (&self.coarse, self.coarse.cell());
        self.restricted
            .transformed_direction(fields, |i, t, row, z| {
                dispatch_direction(c, coarse.back_row(i), coefficients, t, row, z)
            })
    }
}

/// Settings of the preconditioner's free-set extension.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extension {
    /// Side of the coarse cells, in grid nodes (Δl).
    pub cell: usize,
    /// Standard deviation of the Gaussian smoothing, in grid nodes (Δl).
    pub sigma: f64,
    /// Weight γ of the extension (0 gives back `P K⁻¹ P`).
    pub weight: f64,
    /// Floor `D_min` of the smoothed density of the free set (both terms).
    pub density_floor: f64,
    /// Standard deviation of the near term's Gaussian, in grid nodes (Δl): the extension
    /// within a few cells of F, which with the long term continues the gradient across
    /// the edges of the contact clusters.
    pub near_sigma: f64,
    /// Weight γ_near of the near term (0: the long term alone).
    pub near_weight: f64,
    /// The near term is used once the contact set has settled: after an iteration in which
    /// at most this fraction of the contact set left or entered it (while the set still
    /// moves it makes the iteration oscillate; docs/BENCHMARKS.md).
    pub settled_fraction: f64,
    /// Standard deviation of the far term's Gaussian, in grid nodes (Δl); the term is built
    /// on large boxes only ([`Self::large_box`]).
    pub far_sigma: f64,
    /// Weight γ_far of the far term (0: none).
    pub far_weight: f64,
    /// Side of the far term's cells, in grid nodes: a multiple of `cell`.
    pub far_cell: usize,
    /// The far term is used after an iteration in which at most this fraction of the
    /// contact set left or entered it: once the direction is no longer restarted at every
    /// iteration, before the near term (used while the set moves by more, it makes the
    /// iteration crawl; docs/BENCHMARKS.md).
    pub far_fraction: f64,
    /// Side of the blocks whose loads deflate the preconditioner once the contact set has
    /// settled (module `deflation`), in grid nodes: 0 (never) or a multiple of twice
    /// `cell`, used on large boxes ([`Self::large_box`]) that it divides into at least 2
    /// blocks per side (the default, 1024, gives 4 or more). Measured on the paper's spectrum
    /// (docs/BENCHMARKS.md): 1024 takes 13 % of the iterations of four loads near W/W0 =
    /// 0.05 away at 8192², 5 % at 4096² (512: 7 % and 1 %; 256 is not safe), but adds half
    /// again to a cold first load at W/W0 = 0.001 (hence [`Self::coarse_fraction`]).
    pub coarse_block: usize,
    /// The deflation is used only where the contact set covers at least this fraction of
    /// the box: on sparser sets it costs iterations (docs/BENCHMARKS.md).
    pub coarse_fraction: f64,
    /// While the solve's error is `e` (docs/CONVENTIONS.md), a node off the contact set
    /// joins the free set only where it interpenetrates by more than `entry_margin · e · σ_h`
    /// (σ_h: the heights' standard deviation), so shallow interpenetrations, mostly of nodes
    /// that the last step's load offset pushed off the set, wait instead of entering and
    /// leaving again at the next step. The margin falls with the error and is at most a
    /// tenth of the deepest interpenetration, which the error contains, so the converged
    /// solution meets the same tolerance. 0: none.
    pub entry_margin: f64,
    /// The one definition of a large box: the smallest side, in nodes, on which the far
    /// term, the deflation and the entry margin are used. Each pays only on large boxes
    /// (docs/BENCHMARKS.md): the far term's Gaussian (σ_far = 512 nodes) spans a smaller box,
    /// where a field centred on F smoothed over the box is about zero (the same iterations
    /// at 1024², 0.7 % fewer at 2048², 3.7 % and 4.9 % fewer at 4096² and 8192²); the
    /// deflation by blocks of 1024 nodes needs 4 blocks per side (1 % fewer at 4096², 6 % at
    /// 8192²); the entry margin saves 5 % at 8192², 3 % at 4096² and 2 % at 2048², and
    /// costs 1 % at 1024². From 4096², so that smaller boxes keep their bits.
    pub large_box: usize,
}

impl Default for Extension {
    /// The settings measured on the paper's spectrum and the bench surfaces at 1024²–4096²
    /// (docs/BENCHMARKS.md): γ = 0.7 saves a few more iterations at 1024² but makes one load
    /// at 2048² crawl (424 iterations in the replica), γ = 0.5 does not. The near term (σ =
    /// 6 nodes, γ_near = 0.3, after an iteration that changed at most 0.2 % of the contact
    /// set) takes 15 % of the paper spectrum's iterations away at 1024² and 19 % at 2048²;
    /// σ = 4–8 and γ_near = 0.3–0.4 are within 3 % of it, γ_near = 0.6 loses a third of
    /// the gain. The far term (σ = 512 nodes, γ_far = 0.2, on 64² cells) takes 4.9 % of the
    /// 8192² sweep's iterations away when used with the near term; σ = 128–2048 and γ_far =
    /// 0.2–0.3 are within 4 % of it, γ_far = 0.5 costs iterations. Used from an iteration
    /// that changed at most 3 % of the contact set (the restart threshold) instead, it takes
    /// 1.6 % and 2.4 % more away at 4096² and 8192²; 1 % and 10 % do less. The deflation
    /// takes 6 % of the 8192² sweep's iterations away (1 % at 4096²); used earlier, it loses.
    /// The entry margin κ = 0.1 takes 5 % more away at 8192² (3 % at 4096²); κ = 0.05–0.12
    /// are within 2 % of it on four loads at 4096², 0.2 loses and 0.3 and more crawl.
    fn default() -> Self {
        Self {
            cell: 8,
            sigma: 32.0,
            weight: 0.5,
            density_floor: 0.05,
            near_sigma: 6.0,
            near_weight: 0.3,
            settled_fraction: 0.002,
            far_sigma: 512.0,
            far_weight: 0.2,
            far_cell: 64,
            far_fraction: 0.03,
            coarse_block: 1024,
            coarse_fraction: 0.02,
            entry_margin: 0.1,
            large_box: 4096,
        }
    }
}

impl Extension {
    /// A message naming the invalid setting, if any.
    pub fn check(&self) -> Result<(), String> {
        if self.cell == 0 {
            return Err("extension cell must be ≥ 1 node".into());
        }
        if self.far_cell == 0 || !self.far_cell.is_multiple_of(self.cell) {
            return Err(format!(
                "extension far cell {} must be a positive multiple of the cell {}",
                self.far_cell, self.cell
            ));
        }
        for (name, sigma) in [
            ("sigma", self.sigma),
            ("near sigma", self.near_sigma),
            ("far sigma", self.far_sigma),
        ] {
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(format!("extension {name} {sigma} must be finite and > 0"));
            }
        }
        for (name, value) in [
            ("weight", self.weight),
            ("near weight", self.near_weight),
            ("far weight", self.far_weight),
            ("settled fraction", self.settled_fraction),
            ("far fraction", self.far_fraction),
            ("coarse fraction", self.coarse_fraction),
            ("entry margin", self.entry_margin),
        ] {
            if !(value.is_finite() && (0.0..=1.0).contains(&value)) {
                return Err(format!("extension {name} {value} must lie in [0, 1]"));
            }
        }
        if !self.coarse_block.is_multiple_of(2 * self.cell) {
            return Err(format!(
                "extension coarse block {} must be 0 or a multiple of {} nodes (twice the \
                 cell)",
                self.coarse_block,
                2 * self.cell
            ));
        }
        if !(self.density_floor.is_finite() && self.density_floor > 0.0) {
            return Err(format!(
                "extension density floor {} must be finite and > 0",
                self.density_floor
            ));
        }
        Ok(())
    }
}

/// One Gaussian term of the extension on the cells: its smoothing, weight and the smoothed
/// density of F.
struct Term {
    smoothing: Smoothing,
    weight: f64,
    /// Per cell: `D = max(G 1_F / c², D_min)`.
    density: Vec<f64>,
}

impl Term {
    /// A term whose Gaussian of `sigma_nodes` runs on cells of `merge` × `merge` of the m × m
    /// shared cells of `cell` nodes (`merge` divides m).
    fn new(sigma_nodes: f64, weight: f64, cell: usize, m: usize, merge: usize) -> Self {
        Self {
            smoothing: Smoothing::new(sigma_nodes, cell, m, merge),
            weight,
            density: vec![0.0; m * m],
        }
    }
}

/// A term's smoothing `S / c²` on the shared cells.
struct Smoothing {
    /// The periodic Gaussian on the term's own cells, offsets −h..=h, summing to 1.
    kernel: Vec<f64>,
    /// Shared cells per side of the term's own cells (1: its cells are the shared ones), and
    /// three values per own cell to smooth on.
    merge: usize,
    merged: [Vec<f64>; 3],
}

impl Smoothing {
    fn new(sigma_nodes: f64, cell: usize, m: usize, merge: usize) -> Self {
        let own = m / merge;
        let sigma_cells = sigma_nodes / (cell * merge) as f64;
        let h = ((4.0 * sigma_cells).ceil() as usize).min(own / 2);
        let mut kernel: Vec<f64> = (0..=2 * h)
            .map(|k| {
                let d = k as f64 - h as f64;
                (-0.5 * d * d / (sigma_cells * sigma_cells)).exp()
            })
            .collect();
        let total: f64 = kernel.iter().sum();
        kernel.iter_mut().for_each(|k| *k /= total);
        Self {
            kernel,
            merge,
            merged: if merge > 1 {
                std::array::from_fn(|_| vec![0.0; own * own])
            } else {
                Default::default()
            },
        }
    }

    /// `out = S x / c²`: the Gaussian on the shared cells, or on the term's own cells (`x`
    /// summed over each, the result spread back over its shared cells divided by their
    /// number), so that the term keeps constants and is symmetric either way.
    fn apply(&mut self, m: usize, x: &[f64], tmp: &mut [f64], out: &mut [f64]) {
        let k = self.merge;
        if k == 1 {
            return smooth(&self.kernel, m, x, tmp, out);
        }
        let own = m / k;
        let [sums, own_tmp, smoothed] = &mut self.merged;
        sums.fill(0.0);
        for (i, row) in x.chunks(m).enumerate() {
            let at = (i / k) * own;
            for (s, cells) in sums[at..at + own].iter_mut().zip(row.chunks(k)) {
                *s += cells.iter().sum::<f64>();
            }
        }
        smooth(&self.kernel, own, sums, own_tmp, smoothed);
        let spread = 1.0 / (k * k) as f64;
        out.par_chunks_mut(m).enumerate().for_each(|(i, row)| {
            let at = (i / k) * own;
            for (cells, &v) in row.chunks_mut(k).zip(&smoothed[at..at + own]) {
                cells.fill(v * spread);
            }
        });
    }
}

/// The coarse-grid state of the extension for one grid and settings.
pub(super) struct Coarse {
    settings: Extension,
    n: usize,
    cell: usize,
    /// Cells per side.
    m: usize,
    /// The long term (σ = `settings.sigma`) and the near term (`settings.near_sigma`).
    long: Term,
    near: Term,
    /// The far term, on large boxes ([`Extension::large_box`]).
    far: Option<Term>,
    /// Whether the near term is in use (see [`Extension::settled_fraction`]).
    near_on: bool,
    /// Whether the far term is in use (see [`Extension::far_fraction`]).
    far_on: bool,
    /// Per cell: `Σ_F g`.
    sum_g: Vec<f64>,
    /// Per cell: `|F|`.
    count: Vec<f64>,
    /// Per cell: the extension's value off F, `Σ_terms γ (G Uᵀ 1_F g / c²) / D`.
    value: Vec<f64>,
    /// Per cell: `Σ_terms γ G (Uᵀ (1 − 1_F) y / c²) / D`, added to `K⁻¹ E g` on F.
    back: Vec<f64>,
    /// Working values on the cells.
    work: [Vec<f64>; 3],
    blocks: Vec<OffBlock>,
    /// The coarse-space deflation, on boxes large enough for it.
    deflation: Option<Deflation>,
}

impl Coarse {
    pub(super) fn new(n: usize, rows_per_block: usize, settings: Extension) -> Self {
        let cell = settings.cell.min(n).max(1);
        let m = n.div_ceil(cell);
        let blocks = (0..n.div_ceil(rows_per_block))
            .map(|b| {
                let first = b * rows_per_block;
                let last = ((b + 1) * rows_per_block).min(n) - 1;
                let cells = last / cell - first / cell + 1;
                OffBlock {
                    first_row: first,
                    first_cell_row: first / cell,
                    sums: vec![0.0; cells * m],
                    restrict_low: 0,
                    restrict: Vec::new(),
                }
            })
            .collect();
        Self {
            settings,
            n,
            cell,
            m,
            long: Term::new(settings.sigma, settings.weight, cell, m, 1),
            near: Term::new(settings.near_sigma, settings.near_weight, cell, m, 1),
            far: far_merge(n, cell, m, &settings)
                .map(|merge| Term::new(settings.far_sigma, settings.far_weight, cell, m, merge)),
            near_on: false,
            far_on: false,
            sum_g: vec![0.0; m * m],
            count: vec![0.0; m * m],
            value: vec![0.0; m * m],
            back: vec![0.0; m * m],
            work: std::array::from_fn(|_| vec![0.0; m * m]),
            blocks,
            deflation: None,
        }
    }

    /// Adds the coarse-space deflation for `op`'s grid, when the box is large enough
    /// ([`Extension::coarse_block`]).
    pub(super) fn deflate<O: Operator>(&mut self, op: &O) {
        self.deflation = self
            .large()
            .then(|| Deflation::new(op, self.settings.coarse_block, self.cell))
            .flatten();
        if let Some(d) = &self.deflation {
            // Every block but the last holds the same number of rows.
            let rows = self.blocks.get(1).map_or(self.n, |b| b.first_row);
            for block in &mut self.blocks {
                let last = (block.first_row + rows).min(self.n) - 1;
                let (low, count) = d.bilinear.rows_reached(block.first_row, last);
                block.restrict_low = low;
                block.restrict = vec![0.0; count * d.bilinear.cells()];
            }
        }
    }

    /// Whether the box is large ([`Extension::large_box`]): the far term, the deflation and
    /// the entry margin are used.
    fn large(&self) -> bool {
        self.n >= self.settings.large_box
    }

    /// The free set's entry margin for an iteration whose error times σ_h is `error_scale`
    /// (0 below a large box).
    pub(super) fn entry_margin(&self, error_scale: f64) -> f64 {
        if self.large() {
            self.settings.entry_margin * error_scale
        } else {
            0.0
        }
    }

    /// Use the near and far terms from the next [`Self::gather`] on, or not, after an
    /// iteration that changed `changed` nodes of a contact set of `contact` nodes (none
    /// before a load's first): each once the change is at most its fraction of the set
    /// ([`Extension::settled_fraction`], [`Extension::far_fraction`]). Returns whether that
    /// switched either (the preconditioner changed: the conjugate direction must restart).
    /// In full contact both stay off: there is nothing off F to extend to, and a restart
    /// would only cost iterations.
    pub(super) fn settle(&mut self, changed: Option<(usize, f64)>) -> bool {
        let nodes = (self.n * self.n) as f64;
        let below = |fraction: f64| {
            changed.is_some_and(|(changed, contact)| {
                changed as f64 <= fraction * contact && contact < nodes
            })
        };
        let near = self.settings.near_weight > 0.0 && below(self.settings.settled_fraction);
        let far = self.far.is_some() && below(self.settings.far_fraction);
        let mut switched = near != self.near_on || far != self.far_on;
        (self.near_on, self.far_on) = (near, far);
        if let Some(d) = self.deflation.as_mut() {
            let dense = changed
                .is_some_and(|(_, contact)| contact >= self.settings.coarse_fraction * nodes);
            switched |= d.switch(near && dense);
        }
        switched
    }

    /// The cell sums of `g = w − level` and of `1_F` over F, then each term's `D` and the
    /// extension's values. One pass over `p` and `w`, in parallel over rows of cells (each
    /// summed in node order, so the same bits whatever the number of threads).
    pub(super) fn gather<C: Constraint>(&mut self, p: &[f64], w: &[f64], level: Level<C>) {
        let (n, c, m) = (self.n, self.cell, self.m);
        self.sum_g
            .par_chunks_mut(m)
            .zip(self.count.par_chunks_mut(m))
            .enumerate()
            .for_each(|(ci, (sg, cnt))| {
                sg.fill(0.0);
                cnt.fill(0.0);
                for i in ci * c..((ci + 1) * c).min(n) {
                    let (pr, wr) = (&p[i * n..(i + 1) * n], &w[i * n..(i + 1) * n]);
                    dispatch_cell_sums(c, level, sg, cnt, pr, wr);
                }
            });
        let sums = match self.deflation.as_mut().filter(|d| d.on) {
            Some(d) => {
                d.prepare(p, w, level, &self.sum_g, &self.count);
                &d.adjusted
            }
            None => &self.sum_g,
        };
        let area = (c * c) as f64;
        let floor = self.settings.density_floor;
        let [fraction, tmp, smoothed] = &mut self.work;
        self.value.fill(0.0);
        let near = self.near_on.then_some(&mut self.near);
        let far = self.far.as_mut().filter(|_| self.far_on);
        for term in std::iter::once(&mut self.long).chain(near).chain(far) {
            fraction
                .iter_mut()
                .zip(&self.count)
                .for_each(|(s, &k)| *s = k / area);
            term.smoothing.apply(m, fraction, tmp, &mut term.density);
            term.density.iter_mut().for_each(|d| *d = d.max(floor));
            fraction
                .iter_mut()
                .zip(sums)
                .for_each(|(s, &g)| *s = g / area);
            term.smoothing.apply(m, fraction, tmp, smoothed);
            let gamma = term.weight;
            self.value
                .iter_mut()
                .zip(smoothed.iter().zip(&term.density))
                .for_each(|(v, (&s, &d))| *v += gamma * s / d);
        }
    }

    /// One row of the preconditioner's input `E g`: `g` on F, the cell's extension value off
    /// it, in single precision.
    pub(super) fn input_row<C: Constraint>(
        &self,
        i: usize,
        o: &mut [f32],
        p: &[f64],
        w: &[f64],
        level: Level<C>,
    ) {
        let (c, m) = (self.cell, self.m);
        let values = &self.value[(i / c) * m..(i / c + 1) * m];
        dispatch_input(c, values, level, o, p, w);
        if let Some(d) = self.deflation.as_ref().filter(|d| d.on) {
            d.subtract_row(i, o, p, w, level);
        }
    }

    /// Adds one row of `K⁻¹ E g` off F to its block's cell sums.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn output_row<C: Constraint>(
        cell: usize,
        m: usize,
        bilinear: Option<&Bilinear>,
        block: &mut OffBlock,
        r: usize,
        row: &[f32],
        p: &[f64],
        w: &[f64],
        level: Level<C>,
    ) {
        let i = block.first_row + r;
        if r == 0 {
            block.sums.fill(0.0);
            block.restrict.fill(0.0);
        }
        if let Some(b) = bilinear {
            Deflation::restrict_row(b, block, i, row, p, w, level);
        }
        let local = i / cell - block.first_cell_row;
        let sums = &mut block.sums[local * m..(local + 1) * m];
        dispatch_off_sums(cell, level, sums, row, p, w);
    }

    /// The cell size and cells per side, for [`Self::output_row`] while the blocks are
    /// borrowed.
    pub(super) fn output_parts(&mut self) -> (usize, usize, Option<&Bilinear>, &mut [OffBlock]) {
        let bilinear = self
            .deflation
            .as_ref()
            .filter(|d| d.on)
            .map(|d| &d.bilinear);
        (self.cell, self.m, bilinear, &mut self.blocks)
    }

    /// After the output pass (`z_sum`: the sum of its rows over F): the correction on F
    /// per cell, and its sums `(Σ_F b, Σ_F g b)` (cells in order).
    pub(super) fn finish(&mut self, z_sum: f64) -> (f64, f64) {
        let m = self.m;
        let area = (self.cell * self.cell) as f64;
        let [off, tmp, smoothed] = &mut self.work;
        off.fill(0.0);
        for block in &self.blocks {
            let at = block.first_cell_row * m;
            for (s, &v) in off[at..at + block.sums.len()].iter_mut().zip(&block.sums) {
                *s += v;
            }
        }
        off.iter_mut().for_each(|s| *s /= area);
        // `value` is free until the next `gather`: it holds `y / D` of each term in turn.
        let divided = &mut self.value;
        self.back.fill(0.0);
        let near = self.near_on.then_some(&mut self.near);
        let far = self.far.as_mut().filter(|_| self.far_on);
        for term in std::iter::once(&mut self.long).chain(near).chain(far) {
            divided
                .iter_mut()
                .zip(off.iter().zip(&term.density))
                .for_each(|(q, (&y, &d))| *q = y / d);
            term.smoothing.apply(m, divided, tmp, smoothed);
            let gamma = term.weight;
            self.back
                .iter_mut()
                .zip(smoothed.iter())
                .for_each(|(b, &s)| *b += gamma * s);
        }
        if let Some(d) = self.deflation.as_mut().filter(|d| d.on) {
            d.finish(&mut self.back, &self.count, z_sum, &self.blocks);
        }
        let (mut sum_b, mut sum_gb) = (0.0, 0.0);
        for ((&b, &k), &g) in self.back.iter().zip(&self.count).zip(&self.sum_g) {
            sum_b += k * b;
            sum_gb += g * b;
        }
        (sum_b, sum_gb)
    }

    /// The correction on F of row `i`, per cell of the row.
    pub(super) fn back_row(&self, i: usize) -> &[f64] {
        let (c, m) = (self.cell, self.m);
        &self.back[(i / c) * m..(i / c + 1) * m]
    }

    pub(super) fn cell(&self) -> usize {
        self.cell
    }
}

/// The far term's cells in shared cells per side, on a large box (n nodes) when the weight
/// is positive and its cells tile the shared ones.
fn far_merge(n: usize, cell: usize, m: usize, settings: &Extension) -> Option<usize> {
    let merge = settings.far_cell / cell;
    (settings.far_weight > 0.0
        && n >= settings.large_box
        && merge >= 1
        && m.is_multiple_of(merge)
        && m / merge >= 2)
        .then_some(merge)
}

mod rows;

use rows::{dispatch_cell_sums, dispatch_direction, dispatch_input, dispatch_off_sums, smooth};

#[cfg(test)]
mod tests;
