//! The paper's instance method (ARIADNE: De Gregorio et al., "Let's take a
//! Walk on Superpixels Graphs: Deformable Linear Objects Segmentation and
//! Model Estimation", ACCV 2018, arXiv 1810.04461): SLIC superpixels on
//! the masked image, their region adjacency graph, and walks from each end
//! node that always step to the neighbour continuing the walk's direction
//! best, so that a walk goes straight through a crossing.
//!
//! cablecell's simplification: a walk's step is chosen by direction alone
//! (ARIADNE also weighs colour similarity and a learnt prior).

use std::collections::HashSet;

use opencv::core::{self, Mat, Rect};
use opencv::imgproc;
use opencv::prelude::*;
use opencv::ximgproc::{self, SuperpixelSLICTrait, SuperpixelSLICTraitConst};

use super::error::{VisionError, cv};
use super::mask::continuous;
use super::paths::{FoundPaths, finish_paths, unit};

/// Superpixel side, in cable widths, unless set otherwise: about two, so
/// that a cable is one superpixel across and each node has a clear
/// direction to its next. Smaller gives more superpixels.
pub const DEFAULT_REGION_WIDTHS: f64 = 2.0;
/// SLIC iterations: the centres settle within a few.
const SLIC_ITERATIONS: i32 = 4;
/// SLIC's compactness: high, so superpixels stay blob-shaped along the
/// cable instead of following colour noise.
const SLIC_RULER: f32 = 20.0;
/// A walk covering more than this fraction of nodes that earlier walks
/// took is the same cable again (walked from a stray node beside it).
const MAX_SHARED_FRACTION: f64 = 0.5;
/// A walk stops rather than turn by more than this at one step.
const MAX_TURN_RAD: f64 = 1.0;
/// A walk's heading is the direction over this many past nodes: longer
/// than one step so a crossing's irregular nodes do not divert it.
const HEADING_NODES: usize = 3;

struct Nodes {
    centres_px: Vec<[f64; 2]>,
    neighbours: Vec<Vec<usize>>,
}

/// Superpixel nodes within the mask and their adjacency, in the crop's
/// coordinates.
fn graph(image: &Mat, mask: &Mat, region_px: i32) -> Result<Nodes, VisionError> {
    let mut masked = Mat::default();
    image
        .copy_to_masked(&mut masked, mask)
        .map_err(cv("mask image for superpixels"))?;
    let mut slic =
        ximgproc::create_superpixel_slic(&masked, ximgproc::SLICO, region_px, SLIC_RULER)
            .map_err(cv("create SLIC"))?;
    slic.iterate(SLIC_ITERATIONS).map_err(cv("iterate SLIC"))?;
    let mut labels = Mat::default();
    slic.get_labels(&mut labels)
        .map_err(cv("superpixel labels"))?;
    let labels = continuous(&labels)?;
    let label = labels
        .data_typed::<i32>()
        .map_err(cv("read superpixel labels"))?;
    let mask = continuous(mask)?;
    let on = mask.data_bytes().map_err(cv("read mask"))?;
    let cols = usize::try_from(mask.cols()).unwrap_or(0);

    // Pieces: the connected parts of each superpixel within the mask (a
    // superpixel may reach over the background to a second cable).
    let n = label.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let neighbours_of = |i: usize| {
        let right = (i % cols + 1 < cols).then_some(i + 1);
        let down = Some(i + cols).filter(|&j| j < n);
        [right, down].into_iter().flatten()
    };
    for i in 0..n {
        if on[i] == 0 {
            continue;
        }
        for j in neighbours_of(i) {
            if on[j] != 0 && label[j] == label[i] {
                let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                parent[ri] = rj;
            }
        }
    }
    let mut piece_of_root = vec![usize::MAX; n];
    let mut piece_at = vec![usize::MAX; n];
    let mut sums: Vec<[f64; 3]> = Vec::new();
    for i in 0..n {
        if on[i] == 0 {
            continue;
        }
        let r = root(&mut parent, i);
        if piece_of_root[r] == usize::MAX {
            piece_of_root[r] = sums.len();
            sums.push([0.0; 3]);
        }
        let id = piece_of_root[r];
        piece_at[i] = id;
        sums[id][0] += (i % cols) as f64;
        sums[id][1] += (i / cols) as f64;
        sums[id][2] += 1.0;
    }
    let mut pairs = HashSet::new();
    for i in 0..n {
        let a = piece_at[i];
        if a == usize::MAX {
            continue;
        }
        for j in neighbours_of(i) {
            let b = piece_at[j];
            if b != usize::MAX && b != a {
                pairs.insert((a.min(b), a.max(b)));
            }
        }
    }
    let mut pieces_next_to = vec![Vec::new(); sums.len()];
    let mut pairs: Vec<(usize, usize)> = pairs.into_iter().collect();
    pairs.sort_unstable();
    for (a, b) in pairs {
        pieces_next_to[a].push(b);
        pieces_next_to[b].push(a);
    }

    // Slivers of mask in a superpixel mostly over the background (or the
    // other side of a cable) would be nodes off the centre line that a walk
    // zigzags through: they are no nodes, but still join their neighbours.
    let min_node_px = f64::from(region_px * region_px) / 8.0;
    let mut node_of_piece: Vec<Option<usize>> = vec![None; sums.len()];
    let mut centres_px: Vec<[f64; 2]> = Vec::new();
    for (piece, s) in sums.iter().enumerate() {
        if s[2] >= min_node_px {
            node_of_piece[piece] = Some(centres_px.len());
            centres_px.push([s[0] / s[2], s[1] / s[2]]);
        }
    }
    let mut neighbours = vec![Vec::new(); centres_px.len()];
    for (piece, next) in pieces_next_to.iter().enumerate() {
        let linked: Vec<usize> = next.iter().filter_map(|&p| node_of_piece[p]).collect();
        match node_of_piece[piece] {
            Some(node) => neighbours[node].extend(linked),
            None => {
                for &a in &linked {
                    neighbours[a].extend(linked.iter().copied().filter(|&b| b != a));
                }
            }
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
    }
    Ok(Nodes {
        centres_px,
        neighbours,
    })
}

/// The walk from end node `start`: each step to the unvisited neighbour
/// whose direction turns least from the heading, stopping at a turn above
/// [`MAX_TURN_RAD`].
fn walk(nodes: &Nodes, start: usize) -> Vec<usize> {
    let mut path = vec![start];
    let mut on_path = HashSet::from([start]);
    let mut cur = start;
    loop {
        let here = nodes.centres_px[cur];
        let back = path[path.len().saturating_sub(HEADING_NODES + 1)];
        let heading = unit(nodes.centres_px[back], here);
        let next = nodes.neighbours[cur]
            .iter()
            .filter(|n| !on_path.contains(*n))
            .filter_map(|&n| {
                let dir = unit(here, nodes.centres_px[n])?;
                let turn = match heading {
                    Some(h) => (h[0] * dir[0] + h[1] * dir[1]).clamp(-1.0, 1.0).acos(),
                    None => 0.0,
                };
                Some((turn, n))
            })
            .filter(|&(turn, _)| turn <= MAX_TURN_RAD)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match next {
            Some((_, n)) => {
                path.push(n);
                on_path.insert(n);
                cur = n;
            }
            None => break,
        }
    }
    path
}

/// The cables' typical width from the mask's distance transform: across a
/// strip of width w the distance to the edge runs from about 1 to w/2, so
/// its mean is about (w/2 + 1)/2. The mask is framed by a pixel of
/// background first: one that fills its image (a region of interest inside
/// a cable) has no edge of its own, and its distances would be OpenCV's
/// stand-in for infinity.
fn width_px(mask: &Mat) -> Result<f64, VisionError> {
    let mut framed = Mat::default();
    core::copy_make_border(
        mask,
        &mut framed,
        1,
        1,
        1,
        1,
        core::BORDER_CONSTANT,
        core::Scalar::all(0.0),
    )
    .map_err(cv("frame mask"))?;
    let mut distance = Mat::default();
    imgproc::distance_transform(&framed, &mut distance, imgproc::DIST_L2, 3, core::CV_32F)
        .map_err(cv("distance transform"))?;
    let mean = core::mean(&distance, &framed).map_err(cv("mean distance"))?;
    Ok((4.0 * mean[0] - 2.0).max(1.0))
}

/// Finds the cables in `mask` (CV_8U, non-zero = cable) over `image` (same
/// size, any channels) by walks on the superpixel graph, with superpixels
/// `region_widths` cable widths across; pieces are joined across gaps of
/// up to `join_gap_widths` cable widths (see [`JOIN_GAP_WIDTHS`]).
///
/// [`JOIN_GAP_WIDTHS`]: super::paths::JOIN_GAP_WIDTHS
pub fn paths_from_mask(
    image: &Mat,
    mask: &Mat,
    min_length_px: f64,
    region_widths: f64,
    join_gap_widths: f64,
) -> Result<FoundPaths, VisionError> {
    let width_px = width_px(mask)?;
    let empty = FoundPaths {
        paths: Vec::new(),
        width_px,
        junctions: None,
    };
    let bbox = imgproc::bounding_rect(mask).map_err(cv("mask extent"))?;
    if bbox.width <= 0 || bbox.height <= 0 || width_px.is_nan() || width_px <= 0.0 {
        return Ok(empty);
    }
    let region_px = (region_widths * width_px).round().max(4.0) as i32;
    let pad = region_px;
    let crop = Rect::new(
        bbox.x - pad,
        bbox.y - pad,
        bbox.width + 2 * pad,
        bbox.height + 2 * pad,
    ) & Rect::new(0, 0, mask.cols(), mask.rows());
    // SLIC needs room for a superpixel (it crashes on strips a few pixels
    // across), and a cable needs several along it.
    if crop.width < region_px || crop.height < region_px {
        return Ok(empty);
    }
    let image_crop = Mat::roi(image, crop)
        .and_then(|m| m.try_clone())
        .map_err(cv("crop image for superpixels"))?;
    let mask_crop = Mat::roi(mask, crop)
        .and_then(|m| m.try_clone())
        .map_err(cv("crop mask for superpixels"))?;
    let nodes = graph(&image_crop, &mask_crop, region_px)?;

    // Walk from every end node, then keep the walks longest first, each
    // only if most of its nodes are new: a walk stopped short at a crossing,
    // or one from a stray node beside a cable, repeats a longer one.
    let mut walks: Vec<Vec<usize>> = (0..nodes.centres_px.len())
        .filter(|&n| nodes.neighbours[n].len() == 1)
        .map(|start| walk(&nodes, start))
        .collect();
    walks.sort_by_key(|w| std::cmp::Reverse(w.len()));
    let mut taken = vec![false; nodes.centres_px.len()];
    let mut paths = Vec::new();
    let offset = [f64::from(crop.x), f64::from(crop.y)];
    for path in walks {
        let shared = path.iter().filter(|&&n| taken[n]).count();
        if shared as f64 > MAX_SHARED_FRACTION * path.len() as f64 {
            continue;
        }
        for &n in &path {
            taken[n] = true;
        }
        paths.push(
            path.iter()
                .map(|&n| {
                    let c = nodes.centres_px[n];
                    [c[0] + offset[0], c[1] + offset[1]]
                })
                .collect(),
        );
    }
    finish_paths(
        paths,
        mask,
        Some(image),
        width_px,
        min_length_px,
        join_gap_widths,
    )
}
