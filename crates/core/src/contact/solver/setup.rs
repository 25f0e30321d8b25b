//! Making a solver: the surface checked and every buffer allocated once.

use super::complementarity::Complementarity;
use super::error::ContactError;
use super::history;
use super::operator::Operator;
use super::passes::MAX_SPARSE;
use super::rows::{GradientStats, LANES};
use super::state::{BlockSums, NodeFields, Parts, Solver, WarmStart};
use super::update::UpdateAcc;

impl<'a, C: Complementarity, O: Operator> Solver<'a, C, O> {
    /// Check the surface and allocate every buffer: 4 n² doubles (the transform's rows, `p`,
    /// `w`, `t`), n²/8 for the lists of changed nodes, and n²/2 more at the first
    /// preconditioned solve (`z`, single precision), n²/4 at a sweep's second load (the
    /// solution before the last, bfloat16); besides the heights and the operator's
    /// kernel (n²/2).
    pub fn with_constraint(
        op: &'a O,
        heights: &'a [f64],
        constraint: C,
    ) -> Result<Self, ContactError> {
        let n = op.grid().n();
        let len = n * n;
        if heights.len() != len {
            return Err(ContactError::BadLength {
                expected: len,
                got: heights.len(),
            });
        }
        if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ContactError::NonFinite {
                row: i / n,
                col: i % n,
                value: *v,
            });
        }
        let mean = heights.iter().sum::<f64>() / len as f64;
        let height_std =
            (heights.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / len as f64).sqrt();
        let chunk = op.rows_per_block() * n;
        let blocks = len.div_ceil(chunk);
        let (lo, hi) = heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        Ok(Self {
            op,
            constraint,
            heights,
            height_std,
            flat: lo == hi,
            ws: op.make_workspace(),
            fields: NodeFields {
                pressure: crate::pages::filled(len, 0.0),
                separation: crate::pages::filled(len, 0.0),
                direction: crate::pages::filled(len, 0.0),
                gap_level: 0.0,
            },
            blocks: BlockSums {
                chunk,
                lane_sums: vec![[0.0; LANES]; blocks],
                block_stats: vec![GradientStats::EMPTY; blocks],
                update_acc: (0..blocks).map(|_| UpdateAcc::new()).collect(),
                offset_acc: vec![[[0.0; LANES]; 2]; blocks],
                // As many as the constraint's load restoration reads (under a ceiling, every
                // node the step projected).
                changes: (0..blocks)
                    .map(|_| Vec::with_capacity(C::listed_changes(chunk).max(MAX_SPARSE)))
                    .collect(),
                moving: vec![(Vec::new(), 0.0); blocks],
                sparse: Vec::with_capacity(MAX_SPARSE),
            },
            warm: WarmStart {
                has_solution: false,
                solved_mean: 0.0,
                solved_contact: 0,
                history: history::History::new(),
                separation_exact: false,
            },
            parts: Parts {
                preconditioner: None,
                choice: None,
                suspended: None,
            },
        })
    }
}
