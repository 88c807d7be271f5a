//! Measurement-order candidates: a slow drift (the row index and its
//! square, [`Feature::Row`]), a step at one row (0 before it, 1 from it on,
//! [`Feature::Step`]) scanned at every scanned row but a margin at either
//! end ([`step_rows`]), and a block of rows (1 inside `[from, to)`, 0
//! outside: a bump that returns, added as two steps) with both edges
//! scanned on a lattice of about 32 edges, then resolved row by row around
//! the lattice's best ([`Zoom`](super::Zoom)).

use super::{EffectKind, Family, GridPoint, Sink, params, zscore};
use crate::diagnose::rows::ScanRows;
use crate::features::Feature;
use std::collections::BTreeMap;

/// Edges of the block lattice: its grid has about `BLOCK_EDGES²/2` points
/// (one column each), as many as the step family's at 1 000 rows.
const BLOCK_EDGES: usize = 32;

/// Rows before the first and after the last step or block edge scanned.
fn order_margin(m: usize) -> usize {
    (m / 20).max(5)
}

/// The rows a step is scanned at in a campaign of `m` rows (the step
/// family's grid: the one that grows with the campaign, one value a row).
pub fn step_rows(m: usize) -> std::ops::Range<usize> {
    let margin = order_margin(m);
    margin..m.saturating_sub(margin).max(margin)
}

/// Rows between two edges of the block lattice: about [`BLOCK_EDGES`]
/// edges evenly from the margin to `m − margin`.
fn block_spacing(m: usize) -> usize {
    let span = m.saturating_sub(2 * order_margin(m));
    span.div_ceil(BLOCK_EDGES).max(1)
}

/// Grid point of the block of scanned positions `[from, to)`: one indicator
/// column (a bump of one height, back at its end), added to the model as
/// two steps at the campaign rows of its edges (each edge its own height: a
/// second step need not return to the first level).
fn block_point(rows: &ScanRows, from: usize, to: usize) -> GridPoint {
    let (a, b) = (rows.row(from), rows.row(to));
    GridPoint::new(
        params(&[("from_row", a as f64), ("to_row", b as f64)]),
        vec![
            (0..rows.len())
                .map(|i| if (from..to).contains(&i) { 1.0 } else { 0.0 })
                .collect(),
        ],
        vec![Feature::Step { row: a }, Feature::Step { row: b }],
    )
}

/// Grid point of a step at scanned position `t` (the campaign row there).
fn step_point(rows: &ScanRows, t: usize) -> GridPoint {
    let row = rows.row(t);
    GridPoint::new(
        params(&[("row", row as f64)]),
        vec![
            (0..rows.len())
                .map(|i| if i >= t { 1.0 } else { 0.0 })
                .collect(),
        ],
        vec![Feature::Step { row }],
    )
}

/// [`Zoom`](super::Zoom) of a block: each edge moved a scanned row at a time within one
/// lattice spacing, the other held.
fn zoom_block(point: &GridPoint, rows: &ScanRows, _: &crate::dataset::Dataset) -> Vec<GridPoint> {
    let (from, to) = (
        rows.position(point.params["from_row"] as usize),
        rows.position(point.params["to_row"] as usize),
    );
    let m = rows.len();
    let margin = order_margin(m);
    let s = block_spacing(m);
    let near = |c: usize| c.saturating_sub(s).max(margin)..(c + s + 1).min(m - margin);
    let mut out: Vec<GridPoint> = near(from)
        .filter(|&a| to >= a + margin)
        .map(|a| block_point(rows, a, to))
        .collect();
    out.extend(
        near(to)
            .filter(|&b| b >= from + margin && b != to)
            .map(|b| block_point(rows, from, b)),
    );
    out
}

/// The measurement order (of `m` rows): a slow drift on all rows, a step
/// and a block of rows at each scanned row.
pub(super) fn order_families(m: usize, rows: &ScanRows, out: &mut Sink) {
    // measurement order: slow drift and a change point
    let row = zscore(&(0..m).map(|i| i as f64).collect::<Vec<_>>());
    out.push(Family {
        kind: EffectKind::Order,
        source: vec!["row".into()],
        label: "drift over the measurement order".into(),
        grid: vec![GridPoint::new(
            BTreeMap::new(),
            vec![
                row.clone(),
                zscore(&row.iter().map(|r| r * r).collect::<Vec<_>>()),
            ],
            vec![Feature::Row],
        )],
        zoom: None,
    });
    // the order families on the scanned rows: a step, a block's edges at
    // each of them
    let ms = rows.len();
    if !step_rows(ms).is_empty() {
        out.push_scanned(Family {
            kind: EffectKind::Order,
            source: vec!["row".into()],
            label: "step in the measurement order".into(),
            grid: step_rows(ms).map(|t| step_point(rows, t)).collect(),
            zoom: None,
        });
    }
    // a block of rows: a bump that returns (a tracker knocked and put back,
    // a warm-up that settles), both edges scanned on a lattice, the reported
    // ones then row by row ([`zoom_block`]); one column, so a bump is not
    // split into two steps that each explain half of it
    let margin = order_margin(ms);
    if ms > 3 * margin {
        let edges: Vec<usize> = (margin..ms - margin).step_by(block_spacing(ms)).collect();
        let grid: Vec<GridPoint> = edges
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| {
                edges[i + 1..]
                    .iter()
                    .filter(move |&&b| b >= a + margin)
                    .map(move |&b| block_point(rows, a, b))
            })
            .collect();
        if !grid.is_empty() {
            out.push_scanned(Family {
                kind: EffectKind::Order,
                source: vec!["row".into()],
                label: "block of rows (a bump, back at its end)".into(),
                grid,
                zoom: Some(zoom_block),
            });
        }
    }
}
