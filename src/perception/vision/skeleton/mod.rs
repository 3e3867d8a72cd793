//! One path per cable from the mask's skeleton (cablecell's fast instance
//! method, in the manner of mBEST: Choi et al., "mBEST: Realtime
//! Deformable Linear Object Detection Through Minimal Bending Energy
//! Skeleton Pixel Traversals", 2023).
//!
//! The mask is thinned (Zhang–Suen) to a one-pixel, 8-connected skeleton;
//! its end points and junctions become graph nodes and the pixel runs
//! between them edges. Short spurs (thinning artefacts at blunt ends and
//! ragged edges) are pruned; junctions joined by an edge shorter than a few
//! cable widths are merged, because two cables crossing at a shallow angle
//! thin into two 3-way junctions rather than one 4-way one; so are two
//! 3-way junctions further apart whose other branches pair far more
//! cheaply as one crossing than as two junctions. Two cables lying
//! together for a stretch thin into one run down the middle of the pair,
//! forked at each end: that run is split into one for each cable, moved
//! onto its centre line. At each
//! (merged) junction the branches are paired so that the total bending is
//! least, each branch's direction followed back along its curve into the
//! junction, and, given the image, pairing branches of unlike colour costs
//! more (off paint, branches of unlike hues are never paired): a cable
//! goes on through a crossing as it bends and keeps its colour, and its
//! path is bridged across the crossing by a cubic Hermite
//! curve; a loop's two ends are not paired with each other, since a cable
//! that loops across itself goes on through the crossing. Walking edges
//! and pairings from end to end gives one pixel path
//! per cable; a path that turns sharply is two cables and is cut there.
//! `paths.rs` then finishes the paths as it does the superpixel method's.
//!
//! - `thin.rs`: the mask thinned to a skeleton;
//! - `graph.rs`: the skeleton's graph, its spurs pruned and its crossings'
//!   junctions merged;
//! - `direction.rs`: a branch's direction at its junction;
//! - `pairing.rs`: junctions merged where one crossing pairs their branches
//!   more cheaply, runs that two cables share found, and each junction's
//!   branches paired;
//! - `walk.rs`: the paths walked through the pairings, and cut at corners.

mod direction;
mod graph;
mod pairing;
mod thin;
mod walk;

use opencv::core::Mat;

use super::error::VisionError;
use super::paths::{FoundPaths, finish_paths, tangent_span_px};
use graph::Graph;
use thin::Skeleton;
use walk::cut_at_corners;

/// Spurs shorter than this many cable widths (plus [`SPUR_EXTRA_PX`]) are
/// pruned: thinning a blunt end or a ragged edge leaves spurs of about one
/// half to one width.
const SPUR_WIDTHS: f64 = 1.5;

/// Added to the spur length so that thin cables still lose their spurs.
const SPUR_EXTRA_PX: f64 = 4.0;

/// Finds the cables in a CV_8U mask (non-zero = cable): one path each, from
/// end to end, of at least `min_length_px`, pieces joined across gaps of
/// up to `join_gap_widths` cable widths (see [`JOIN_GAP_WIDTHS`]). With the
/// BGR `image` the mask was found in (of its size), crossings also pair
/// branches by colour, and never those of unlike hues unless the
/// background is `painted`, where one cable's branches can read as far
/// apart.
///
/// [`JOIN_GAP_WIDTHS`]: super::paths::JOIN_GAP_WIDTHS
pub fn paths_from_mask(
    mask: &Mat,
    image: Option<&Mat>,
    painted: bool,
    min_length_px: f64,
    join_gap_widths: f64,
) -> Result<FoundPaths, VisionError> {
    let Skeleton {
        grid,
        pixels,
        width_px,
    } = thin::skeleton(mask)?;
    let mut graph = Graph::build(grid, &pixels);
    let spur_px = SPUR_WIDTHS * width_px + SPUR_EXTRA_PX;
    graph.prune_spurs(spur_px, &graph.unmerged(), width_px);
    let root = graph.merge_junctions(width_px);
    graph.prune_spurs(spur_px, &root, width_px);
    let root = pairing::merge_cheaper_crossings(&mut graph, root, width_px);
    let junctions = pairing::junction_branches(&graph, &root).len();
    let shared = pairing::share_runs(&mut graph, &root, mask, width_px)?;
    // Branches per merged junction, and their least-cost pairing (bending,
    // and colour when the image is given).
    let partner = pairing::pair_branches(&graph, &root, image, painted, width_px, &shared)?;
    let paths = walk::walk_paths(&graph, &partner, mask, width_px);
    // Superpixel walks have their own limit on turning, and their coarse
    // node-to-node polylines would read as corners here.
    let span_px = tangent_span_px(width_px);
    let paths = paths
        .into_iter()
        .flat_map(|path| cut_at_corners(path, span_px))
        .collect();
    let found = finish_paths(paths, mask, image, width_px, min_length_px, join_gap_widths)?;
    Ok(FoundPaths {
        junctions: Some(junctions),
        ..found
    })
}
