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
//! thin into two 3-way junctions rather than one 4-way one. At each
//! (merged) junction the branches are paired so that the total bending is
//! least, each branch's direction followed back along its curve into the
//! junction, and, given the image, pairing branches of unlike colour costs
//! more: a cable goes on through a crossing as it bends and keeps its
//! colour, and its path is bridged across the crossing by a cubic Hermite
//! curve; a loop's two ends are not paired with each other, since a cable
//! that loops across itself goes on through the crossing. Walking edges
//! and pairings from end to end gives one pixel path
//! per cable; a path that turns sharply is two cables and is cut there.
//! `paths.rs` then finishes the paths as it does the superpixel method's.

use std::collections::{HashMap, HashSet};

use opencv::core::Mat;
use opencv::prelude::*;

use super::error::{VisionError, cv};
use super::mask::continuous;
use super::paths::{
    FoundPaths, angle_rad, delta_e, finish_paths, median_colour_lab, polyline_length,
    tangent_span_px, unit,
};
use super::spline::arc_lengths_px;

/// Spurs shorter than this many cable widths (plus [`SPUR_EXTRA_PX`]) are
/// pruned: thinning a blunt end or a ragged edge leaves spurs of about one
/// half to one width.
const SPUR_WIDTHS: f64 = 1.5;
/// Added to the spur length so that thin cables still lose their spurs.
const SPUR_EXTRA_PX: f64 = 4.0;
/// Junctions joined by an edge shorter than this many cable widths are one
/// crossing: two cables crossing at 25° overlap for about 2.4 widths.
const MERGE_WIDTHS: f64 = 2.5;
/// Skeleton pixels this many widths either side of a crossing are left out
/// of the paths through it.
const JUNCTION_TRIM_WIDTHS: f64 = 1.0;
/// Junctions up to this many cable widths apart may still be one crossing
/// (two cables crossing at 10° overlap for about six widths; 10 px cables
/// bending opposite ways through 29° left junctions 8.6 widths apart), when
/// their shape says so (see `Graph::merge_junctions`).
const SPLIT_CROSSING_WIDTHS: f64 = 10.0;
/// How straight both outer branches of a split crossing's junction must run
/// on into the edge between the junctions. That edge runs between the two
/// cables, so a cable that bends through the crossing leaves it at up to
/// 45° (0.6 rad split 3 crossings of the training photographs wrongly).
const SPLIT_CONTINUE_RAD: f64 = 0.9;
/// A run of skeleton that leaves a crossing and returns to it is a loop of
/// one cable, not the lens between two cables crossing twice, when it is
/// this many times longer than the run the two strands share.
const LOOP_TO_OVERLAP: f64 = 3.0;
/// Cost, in radians of bending, of leaving a branch unpaired at a junction
/// (the cable ends there). Two branches are joined rather than both left
/// unpaired when their bend is under twice this (about 140°).
const UNPAIRED_COST_RAD: f64 = 1.2;
/// A path that turns by more than this over two cable widths either side
/// of a point (`paths::tangent_span_px`) is two cables meeting there (or a
/// hook at its end). In the 45 photographs of cables-dev, the paths found
/// along single wires turn by at most 0.73 rad so; where two wires were
/// found as one, by 1.03 rad or more.
const CORNER_TURN_RAD: f64 = 0.9;
/// Cost, in radians of bending, of pairing two branches at a crossing
/// whose colours differ by [`COLOUR_FULL_DELTA_E`] or more (less in
/// proportion): where two cables of different colours cross at a shallow
/// angle or bend through the crossing, their shapes alone can pair the
/// wrong branches. Less than [`UNPAIRED_COST_RAD`], so that shading and
/// highlights, which change a cable's colour along it, do not cut it.
const COLOUR_COST_RAD: f64 = 1.0;
/// Colour differences (CIE76 ΔE, in OpenCV's 8-bit Lab) up to this cost
/// nothing: a cable's own colour varies so much along it with shading and
/// noise, and a branch too short to show its colour must not be preferred
/// to one of nearly the same colour.
const COLOUR_SAME_DELTA_E: f64 = 10.0;
/// A colour difference that costs the whole of [`COLOUR_COST_RAD`] (red
/// against orange is about 40); between this and [`COLOUR_SAME_DELTA_E`]
/// the cost grows in proportion.
const COLOUR_FULL_DELTA_E: f64 = 40.0;
/// Above this many branches at one junction the exact least-cost pairing
/// is too costly and pairs are taken greedily, cheapest first.
const MAX_EXACT_BRANCHES: usize = 8;

/// Thinning and graph on a grid padded by one pixel, so that neighbour
/// look-ups never leave it.
struct Grid {
    stride: usize,
    on: Vec<u8>,
    offsets: [isize; 8],
}

impl Grid {
    /// Pads a CV_8U mask (non-zero = cable).
    fn from_mask(mask: &Mat) -> Result<Grid, VisionError> {
        let mask = continuous(mask)?;
        let bytes = mask.data_bytes().map_err(cv("read mask"))?;
        let rows = usize::try_from(mask.rows()).unwrap_or(0);
        let cols = usize::try_from(mask.cols()).unwrap_or(0);
        let stride = cols + 2;
        let mut on = vec![0u8; stride * (rows + 2)];
        for (y, row) in bytes.chunks_exact(cols.max(1)).take(rows).enumerate() {
            let base = (y + 1) * stride + 1;
            for (x, &v) in row.iter().enumerate() {
                on[base + x] = u8::from(v != 0);
            }
        }
        let s = stride as isize;
        Ok(Grid {
            stride,
            on,
            // N, NE, E, SE, S, SW, W, NW: clockwise from north.
            offsets: [-s, -s + 1, 1, s + 1, s, s - 1, -1, -s - 1],
        })
    }

    fn xy(&self, i: usize) -> [f64; 2] {
        [
            (i % self.stride) as f64 - 1.0,
            (i / self.stride) as f64 - 1.0,
        ]
    }

    /// The 8 neighbours' states, clockwise from north.
    fn ring(&self, i: usize) -> [u8; 8] {
        let mut r = [0u8; 8];
        for (k, off) in self.offsets.iter().enumerate() {
            r[k] = self.on[i.wrapping_add_signed(*off)];
        }
        r
    }

    fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.offsets
            .iter()
            .map(move |off| i.wrapping_add_signed(*off))
            .filter(|&j| self.on[j] != 0)
    }

    fn degree(&self, i: usize) -> usize {
        self.neighbours(i).count()
    }

    /// Zhang–Suen thinning of the pixels in `fg`, which is left holding the
    /// skeleton.
    fn thin(&mut self, fg: &mut Vec<usize>) {
        let mut marked = Vec::new();
        loop {
            let mut changed = false;
            for pass in 0..2 {
                marked.clear();
                for &i in fg.iter() {
                    let p = self.ring(i);
                    let b: u8 = p.iter().sum();
                    if !(2..=6).contains(&b) {
                        continue;
                    }
                    let a = (0..8).filter(|&k| p[k] == 0 && p[(k + 1) % 8] == 1).count();
                    if a != 1 {
                        continue;
                    }
                    let (n, e, s, w) = (p[0], p[2], p[4], p[6]);
                    let keep = if pass == 0 {
                        n * e * s != 0 || e * s * w != 0
                    } else {
                        n * e * w != 0 || n * s * w != 0
                    };
                    if !keep {
                        marked.push(i);
                    }
                }
                for &i in &marked {
                    self.on[i] = 0;
                }
                changed |= !marked.is_empty();
                fg.retain(|&i| self.on[i] != 0);
            }
            if !changed {
                break;
            }
        }
    }

    /// Removes skeleton pixels whose removal keeps their neighbours
    /// connected (Yokoi's 8-connectivity number is 1) and that are not end
    /// points: Zhang–Suen leaves staircases and corner pixels that would
    /// otherwise read as junctions.
    fn remove_redundant(&mut self, fg: &mut Vec<usize>) {
        loop {
            let mut changed = false;
            for &i in fg.iter() {
                let p = self.ring(i);
                let count: u8 = p.iter().sum();
                if count < 2 {
                    continue;
                }
                // Yokoi's order: x1 = E, x2 = NE, x3 = N, x4 = NW, x5 = W,
                // x6 = SW, x7 = S, x8 = SE; complements.
                let x = [p[2], p[1], p[0], p[7], p[6], p[5], p[4], p[3]].map(|v| 1 - v);
                let n8: i32 = [0usize, 2, 4, 6]
                    .iter()
                    .map(|&k| i32::from(x[k]) - i32::from(x[k] * x[(k + 1) % 8] * x[(k + 2) % 8]))
                    .sum();
                if n8 == 1 {
                    self.on[i] = 0;
                    changed = true;
                }
            }
            fg.retain(|&i| self.on[i] != 0);
            if !changed {
                break;
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum NodeKind {
    End,
    Junction,
}

struct Node {
    kind: NodeKind,
    centre_px: [f64; 2],
}

struct Edge {
    /// Node at each end.
    ends: [usize; 2],
    /// From the pixel of `ends[0]` it leaves to the pixel of `ends[1]`.
    pixels: Vec<usize>,
    length_px: f64,
    alive: bool,
    /// Inside a merged junction: not a branch of it.
    internal: bool,
}

/// A branch of a junction: an edge and which of its ends is at the
/// junction.
type Branch = (usize, usize);

const NONE: usize = usize::MAX;

struct Graph {
    grid: Grid,
    nodes: Vec<Node>,
    edges: Vec<Edge>,
    /// Paths that are closed loops of skeleton with no node on them.
    loops: Vec<Vec<usize>>,
}

impl Graph {
    fn build(grid: Grid, skeleton: &[usize]) -> Graph {
        let mut node_of = vec![NONE; grid.on.len()];
        let mut nodes = Vec::new();
        let mut node_pixels: Vec<Vec<usize>> = Vec::new();
        for &i in skeleton {
            if node_of[i] != NONE {
                continue;
            }
            let degree = grid.degree(i);
            if degree == 1 {
                node_of[i] = nodes.len();
                nodes.push(Node {
                    kind: NodeKind::End,
                    centre_px: grid.xy(i),
                });
                node_pixels.push(vec![i]);
            } else if degree >= 3 {
                // A junction: all 8-adjacent junction pixels together.
                let id = nodes.len();
                let mut cluster = vec![i];
                node_of[i] = id;
                let mut k = 0;
                while k < cluster.len() {
                    let c = cluster[k];
                    k += 1;
                    for j in grid.neighbours(c) {
                        if node_of[j] == NONE && grid.degree(j) >= 3 {
                            node_of[j] = id;
                            cluster.push(j);
                        }
                    }
                }
                let n = cluster.len() as f64;
                let sum = cluster.iter().fold([0.0, 0.0], |acc, &c| {
                    let p = grid.xy(c);
                    [acc[0] + p[0], acc[1] + p[1]]
                });
                nodes.push(Node {
                    kind: NodeKind::Junction,
                    centre_px: [sum[0] / n, sum[1] / n],
                });
                node_pixels.push(cluster);
            }
        }

        let mut visited = vec![false; grid.on.len()];
        let mut edges = Vec::new();
        let mut direct: std::collections::HashSet<(usize, usize)> =
            std::collections::HashSet::new();
        for (n, pixels) in node_pixels.iter().enumerate() {
            for &p in pixels {
                for q in grid.neighbours(p) {
                    let m = node_of[q];
                    if m != NONE {
                        if m != n && direct.insert((n.min(m), n.max(m))) {
                            edges.push(Edge {
                                ends: [n, m],
                                pixels: vec![p, q],
                                length_px: 1.0,
                                alive: true,
                                internal: false,
                            });
                        }
                        continue;
                    }
                    if visited[q] {
                        continue;
                    }
                    let mut pixels = vec![p, q];
                    visited[q] = true;
                    let (mut prev, mut cur) = (p, q);
                    let end = loop {
                        let next = grid.neighbours(cur).find(|&r| {
                            r != prev
                                && (node_of[r] != NONE || !visited[r])
                                && !(r == p && pixels.len() == 2)
                        });
                        match next {
                            Some(r) if node_of[r] != NONE => {
                                pixels.push(r);
                                break node_of[r];
                            }
                            Some(r) => {
                                visited[r] = true;
                                pixels.push(r);
                                prev = cur;
                                cur = r;
                            }
                            None => {
                                // A dead end no node marks (cannot happen on a
                                // clean skeleton): make it an end.
                                nodes.push(Node {
                                    kind: NodeKind::End,
                                    centre_px: grid.xy(cur),
                                });
                                break nodes.len() - 1;
                            }
                        }
                    };
                    let pts: Vec<[f64; 2]> = pixels.iter().map(|&i| grid.xy(i)).collect();
                    edges.push(Edge {
                        ends: [n, end],
                        pixels,
                        length_px: polyline_length(&pts),
                        alive: true,
                        internal: false,
                    });
                }
            }
        }

        // Closed loops of skeleton with no node: trace each once.
        let mut loops = Vec::new();
        for &i in skeleton {
            if node_of[i] != NONE || visited[i] {
                continue;
            }
            let mut pixels = vec![i];
            visited[i] = true;
            let mut cur = i;
            while let Some(r) = grid
                .neighbours(cur)
                .find(|&r| !visited[r] && node_of[r] == NONE)
            {
                visited[r] = true;
                pixels.push(r);
                cur = r;
            }
            loops.push(pixels);
        }
        Graph {
            grid,
            nodes,
            edges,
            loops,
        }
    }

    fn degrees(&self) -> Vec<usize> {
        let mut degree = vec![0; self.nodes.len()];
        for e in self.edges.iter().filter(|e| e.alive && !e.internal) {
            degree[e.ends[0]] += 1;
            degree[e.ends[1]] += 1;
        }
        degree
    }

    /// Drops spurs (end-to-junction edges shorter than `spur_px`), shortest
    /// first, as long as their junction keeps at least two other branches.
    fn prune_spurs(&mut self, spur_px: f64) {
        let mut degree = self.degrees();
        let mut spurs: Vec<usize> = (0..self.edges.len())
            .filter(|&e| {
                let edge = &self.edges[e];
                let kinds = edge.ends.map(|n| self.nodes[n].kind);
                edge.length_px < spur_px
                    && kinds.contains(&NodeKind::End)
                    && kinds.contains(&NodeKind::Junction)
            })
            .collect();
        spurs.sort_by(|&a, &b| self.edges[a].length_px.total_cmp(&self.edges[b].length_px));
        for e in spurs {
            let ends = self.edges[e].ends;
            let junction = if self.nodes[ends[0]].kind == NodeKind::Junction {
                ends[0]
            } else {
                ends[1]
            };
            if degree[junction] >= 3 {
                self.edges[e].alive = false;
                degree[junction] -= 1;
            }
        }
    }

    /// Merges junctions that are one crossing; returns each node's merged
    /// junction (its root). Two junctions are one crossing when the edge
    /// joining them is shorter than [`MERGE_WIDTHS`] cable widths, or when
    /// it is shorter than [`SPLIT_CROSSING_WIDTHS`] and both are 3-way
    /// junctions whose two other branches both run on into it (within
    /// [`SPLIT_CONTINUE_RAD`]): the shape of two cables crossing at a
    /// shallow angle (or running together for a while), unlike a cable end
    /// touching another's side. So are two 3-way junctions joined by that
    /// short edge and a run [`LOOP_TO_OVERLAP`] times longer: a cable
    /// looping across itself.
    fn merge_junctions(&mut self, width_px: f64) -> Vec<usize> {
        let mut parent: Vec<usize> = (0..self.nodes.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut incident: Vec<Vec<Branch>> = vec![Vec::new(); self.nodes.len()];
        for (e, edge) in self.edges.iter().enumerate() {
            if edge.alive {
                incident[edge.ends[0]].push((e, 0));
                incident[edge.ends[1]].push((e, 1));
            }
        }
        let is_junction = |n: usize| self.nodes[n].kind == NodeKind::Junction;
        // The lengths of the runs of skeleton from junction `a` to `b`.
        let runs_between = |a: usize, b: usize| -> Vec<f64> {
            incident[a]
                .iter()
                .filter(|&&(e, side)| self.edges[e].ends[1 - side] == b)
                .map(|&(e, _)| self.edges[e].length_px)
                .collect()
        };
        let mut merge = Vec::new();
        let mut loop_overlaps = Vec::new();
        for (e, edge) in self.edges.iter().enumerate() {
            let [a, b] = edge.ends;
            if !edge.alive || !is_junction(a) || !is_junction(b) {
                continue;
            }
            let short = edge.length_px < MERGE_WIDTHS * width_px;
            let split_crossing = a != b
                && edge.length_px < SPLIT_CROSSING_WIDTHS * width_px
                && [(a, 0), (b, 1)].iter().all(|&(n, side)| {
                    let branches = &incident[n];
                    if branches.len() != 3 {
                        return false;
                    }
                    let centre = self.nodes[n].centre_px;
                    let into = self.branch_direction((e, side), centre, width_px);
                    branches.iter().filter(|&&br| br != (e, side)).all(|&br| {
                        bend_rad(self.branch_direction(br, centre, width_px), into)
                            < SPLIT_CONTINUE_RAD
                    })
                });
            // Joined by this run and a far longer one: a cable that loops
            // back across itself at a shallow angle, this run where its two
            // strands overlap. (Two cables crossing twice join their
            // crossings by runs of like length.)
            let loop_overlap = a != b
                && edge.length_px < SPLIT_CROSSING_WIDTHS * width_px
                && incident[a].len() == 3
                && incident[b].len() == 3
                && match runs_between(a, b)[..] {
                    [r, s] => r.max(s) > LOOP_TO_OVERLAP * r.min(s),
                    _ => false,
                };
            if short || split_crossing {
                merge.push(e);
            } else if loop_overlap {
                loop_overlaps.push(e);
            }
        }
        // A loop's overlap is one crossing only between junctions that are
        // no part of another: when the loop passes through a crossing with
        // another cable, the far longer run may be the rest of the loop
        // beyond it.
        let merged: HashSet<usize> = merge.iter().flat_map(|&e| self.edges[e].ends).collect();
        merge.extend(loop_overlaps.into_iter().filter(|&e| {
            let [a, b] = self.edges[e].ends;
            !merged.contains(&a) && !merged.contains(&b)
        }));
        for e in merge {
            let [a, b] = self.edges[e].ends;
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra] = rb;
            self.edges[e].internal = true;
        }
        (0..self.nodes.len())
            .map(|i| root(&mut parent, i))
            .collect()
    }

    /// Pixels of a branch going out of its junction.
    fn outward(&self, (e, side): Branch) -> Vec<[f64; 2]> {
        let px = &self.edges[e].pixels;
        let mut pts: Vec<[f64; 2]> = px.iter().map(|&i| self.grid.xy(i)).collect();
        if side == 1 {
            pts.reverse();
        }
        pts
    }

    /// The branch's direction leaving the junction (see
    /// [`direction_stretch`]).
    fn branch_direction(&self, branch: Branch, centre: [f64; 2], width_px: f64) -> [f64; 2] {
        direction_leaving(&self.outward(branch), centre, width_px)
    }
}

/// The bend of joining each two branches at a junction at `centre`, given
/// each branch's pixels going out of it.
fn bend_costs(outward: &[Vec<[f64; 2]>], centre: [f64; 2], width_px: f64) -> Vec<Vec<f64>> {
    let dirs: Vec<[f64; 2]> = outward
        .iter()
        .map(|pts| tangent_at_centre(pts, centre, width_px))
        .collect();
    dirs.iter()
        .map(|&a| dirs.iter().map(|&b| bend_rad(a, b)).collect())
        .collect()
}

/// Each branch's colour in Lab past the crossing, given its pixels going
/// out of it, where the other cable neither covers nor shades it: under
/// its skeleton from 2.75 to 4.75 cable widths out (the stretch that
/// [`tangent_at_centre`] follows), or over the last width of a shorter
/// branch (see [`median_colour_lab`]). `None` for a branch that ends
/// inside the crossing.
fn branch_colours_lab(
    outward: &[Vec<[f64; 2]>],
    image: &Mat,
    width_px: f64,
) -> Result<Vec<Option<[f64; 3]>>, VisionError> {
    let (skip, span) = direction_stretch(width_px);
    outward
        .iter()
        .map(|pts| {
            let to = pts.len().min(skip + 2 * span);
            let from = (skip + span).min(to.saturating_sub(span / 2)).max(skip);
            match pts.get(from..to) {
                Some(stretch) => median_colour_lab(image, stretch),
                None => Ok(None),
            }
        })
        .collect()
}

/// A branch's direction at the junction's centre, given its pixels `pts`
/// going out of it: its direction past the junction's distortion, turned
/// on towards the centre by as much as it turns over the next two widths,
/// so that a cable bending through a crossing is judged by its curve
/// rather than its chord, and branches leaving a shallow crossing's two
/// junctions, far apart, are compared at one point.
fn tangent_at_centre(pts: &[[f64; 2]], centre: [f64; 2], width_px: f64) -> [f64; 2] {
    let near = direction_leaving(pts, centre, width_px);
    let (skip, span) = direction_stretch(width_px);
    let (i1, i2) = (skip + span, skip + 2 * span);
    if i2 >= pts.len() {
        return near;
    }
    let far = [pts[i2][0] - pts[i1][0], pts[i2][1] - pts[i1][1]];
    let near_rad = near[1].atan2(near[0]);
    let turn_rad = near_rad - far[1].atan2(far[0]);
    let turn_rad = turn_rad.sin().atan2(turn_rad.cos());
    // From the middle of the far stretch to the middle of the near one
    // is one span; from there to the branch's start, skip + span / 2,
    // and on to the junction's centre.
    let to_centre_px = (pts[0][0] - centre[0]).hypot(pts[0][1] - centre[1]);
    let back_px = skip as f64 + 0.5 * span as f64 + to_centre_px;
    let back_rad = near_rad + turn_rad * back_px / span as f64;
    [back_rad.cos(), back_rad.sin()]
}

/// The direction of a branch's pixels `pts` (going out of a junction at
/// `centre`) over the stretch of [`direction_stretch`], or from the centre
/// to its last pixel when it is shorter.
fn direction_leaving(pts: &[[f64; 2]], centre: [f64; 2], width_px: f64) -> [f64; 2] {
    let Some(last) = pts.len().checked_sub(1) else {
        return [0.0, 0.0];
    };
    let (skip, span) = direction_stretch(width_px);
    let i0 = skip.min(last);
    let i1 = (skip + span).min(last);
    let (from, to) = if i1 > i0 {
        (pts[i0], pts[i1])
    } else {
        (centre, pts[last])
    };
    unit(from, to).unwrap_or([0.0, 0.0])
}

/// Where a branch's direction is measured, in pixels along it from its
/// junction: past the junction's distortion (about one width out), over two
/// widths.
fn direction_stretch(width_px: f64) -> (usize, usize) {
    let skip = (0.75 * width_px).round() as usize;
    let span = (2.0 * width_px).max(8.0).round() as usize;
    (skip, span)
}

/// Points about a pixel apart across the gap from the end of `before` to
/// the start of `after`, on the cubic Hermite curve that leaves `before`
/// and enters `after` along their directions over their last and first
/// `span` points: a cable bends through a crossing, where the skeleton
/// says nothing of it. Empty when either run is too short to have a
/// direction.
fn bridge(before: &[[f64; 2]], after: &[[f64; 2]], span: usize) -> Vec<[f64; 2]> {
    let (Some(&p0), Some(&p1)) = (before.last(), after.first()) else {
        return Vec::new();
    };
    let back = before[before.len().saturating_sub(span + 1)];
    let ahead = after[span.min(after.len() - 1)];
    let (Some(m0), Some(m1)) = (unit(back, p0), unit(p1, ahead)) else {
        return Vec::new();
    };
    let gap_px = (p1[0] - p0[0]).hypot(p1[1] - p0[1]);
    let n = gap_px.ceil() as usize;
    (1..n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let (t2, t3) = (t * t, t * t * t);
            let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
            let h10 = t3 - 2.0 * t2 + t;
            let h01 = -2.0 * t3 + 3.0 * t2;
            let h11 = t3 - t2;
            std::array::from_fn(|k| {
                h00 * p0[k] + h10 * gap_px * m0[k] + h01 * p1[k] + h11 * gap_px * m1[k]
            })
        })
        .collect()
}

/// Whether the pixel nearest `p` is in `mask` (CV_8U) and set.
fn on_mask(mask: &Mat, p: [f64; 2]) -> bool {
    let (x, y) = (p[0].round(), p[1].round());
    (0.0..f64::from(mask.cols())).contains(&x)
        && (0.0..f64::from(mask.rows())).contains(&y)
        && mask.at_2d::<u8>(y as i32, x as i32).is_ok_and(|&v| v != 0)
}

/// Bending, in radians, of going in along `a` (pointing out of the
/// junction) and out along `b`: 0 for a straight continuation.
fn bend_rad(a: [f64; 2], b: [f64; 2]) -> f64 {
    let cos = -(a[0] * b[0] + a[1] * b[1]);
    cos.clamp(-1.0, 1.0).acos()
}

/// Adds to each pairing's bend the cost of the two branches' colour
/// difference (see [`COLOUR_COST_RAD`]); branches of unknown colour cost
/// nothing more.
fn add_colour_costs(cost: &mut [Vec<f64>], colours_lab: &[Option<[f64; 3]>]) {
    for (row, a) in cost.iter_mut().zip(colours_lab) {
        for (c, b) in row.iter_mut().zip(colours_lab) {
            if let (Some(a), Some(b)) = (a, b) {
                let over = (delta_e(*a, *b) - COLOUR_SAME_DELTA_E)
                    / (COLOUR_FULL_DELTA_E - COLOUR_SAME_DELTA_E);
                *c += COLOUR_COST_RAD * over.clamp(0.0, 1.0);
            }
        }
    }
}

/// Forbids pairing a crossing's two branches that are the ends of one edge,
/// when the crossing has four branches: a cable that loops back across
/// itself leaves the crossing along the loop and returns along it, so
/// joining the loop's two ends would close it into a ring with no ends,
/// which no cable is, and leave the rest of the cable as another. Where
/// more cables' crossings are merged into one junction, such an edge may
/// run between two of them, and the bends measured at one centre decide.
fn forbid_closing_loops(cost: &mut [Vec<f64>], branches: &[Branch]) {
    if branches.len() != 4 {
        return;
    }
    for (i, a) in branches.iter().enumerate() {
        for (j, b) in branches.iter().enumerate() {
            if i != j && a.0 == b.0 {
                cost[i][j] = f64::INFINITY;
            }
        }
    }
}

/// Least total cost pairing of `k` branches where `cost[i][j]` is the cost
/// of joining i and j (their bend, plus any colour difference's cost) and
/// leaving one unpaired costs [`UNPAIRED_COST_RAD`].
fn best_pairing(cost: &[Vec<f64>]) -> Vec<(usize, usize)> {
    let k = cost.len();
    if k > MAX_EXACT_BRANCHES {
        let mut candidates: Vec<(f64, usize, usize)> = (0..k)
            .flat_map(|i| (i + 1..k).map(move |j| (i, j)))
            .map(|(i, j)| (cost[i][j], i, j))
            .filter(|c| c.0 < 2.0 * UNPAIRED_COST_RAD)
            .collect();
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut used = vec![false; k];
        let mut pairs = Vec::new();
        for (_, i, j) in candidates {
            if !used[i] && !used[j] {
                used[i] = true;
                used[j] = true;
                pairs.push((i, j));
            }
        }
        return pairs;
    }
    fn search(
        cost: &[Vec<f64>],
        free: u32,
        acc: f64,
        pairs: &mut Vec<(usize, usize)>,
        best: &mut (f64, Vec<(usize, usize)>),
    ) {
        if acc >= best.0 {
            return;
        }
        if free == 0 {
            *best = (acc, pairs.clone());
            return;
        }
        let i = free.trailing_zeros() as usize;
        let rest = free & !(1 << i);
        search(cost, rest, acc + UNPAIRED_COST_RAD, pairs, best);
        let mut others = rest;
        while others != 0 {
            let j = others.trailing_zeros() as usize;
            others &= !(1 << j);
            pairs.push((i, j));
            search(cost, rest & !(1 << j), acc + cost[i][j], pairs, best);
            pairs.pop();
        }
    }
    let mut best = (f64::INFINITY, Vec::new());
    search(cost, (1u32 << k) - 1, 0.0, &mut Vec::new(), &mut best);
    best.1
}

/// `path` cut at each corner sharper than [`CORNER_TURN_RAD`]: where its
/// direction over `span_px` before a point and over `span_px` after it
/// differ by more, two cables meet there (touching end to end, or leaving
/// the view at one place with the mask joined between them). Points within
/// `span_px` of an end are not looked at: ends are ragged.
fn cut_at_corners(path: Vec<[f64; 2]>, span_px: f64) -> Vec<Vec<[f64; 2]>> {
    let along_px = arc_lengths_px(&path);
    let total_px = along_px.last().copied().unwrap_or(0.0);
    let turn_rad = |i: usize| {
        let back = along_px.partition_point(|&s| s <= along_px[i] - span_px) - 1;
        let ahead = along_px.partition_point(|&s| s < along_px[i] + span_px);
        let (a, b, c) = (path[back], path[i], path[ahead]);
        angle_rad([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]])
    };
    let mut cuts = Vec::new();
    let mut sharpest: Option<(usize, f64)> = None;
    for (i, &at_px) in along_px.iter().enumerate() {
        let inside = at_px >= span_px && total_px - at_px >= span_px;
        let turn = if inside { turn_rad(i) } else { 0.0 };
        if turn > CORNER_TURN_RAD {
            if sharpest.is_none_or(|(_, t)| turn > t) {
                sharpest = Some((i, turn));
            }
        } else if let Some((at, _)) = sharpest.take() {
            cuts.push(at);
        }
    }
    if cuts.is_empty() {
        return vec![path];
    }
    let mut pieces = Vec::with_capacity(cuts.len() + 1);
    let mut from = 0;
    for at in cuts {
        pieces.push(path[from..=at].to_vec());
        from = at;
    }
    pieces.push(path[from..].to_vec());
    pieces
}

/// Finds the cables in a CV_8U mask (non-zero = cable): one path each, from
/// end to end, of at least `min_length_px`. With the BGR `image` the mask
/// was found in (of its size), crossings also pair branches by colour.
pub fn paths_from_mask(
    mask: &Mat,
    image: Option<&Mat>,
    min_length_px: f64,
) -> Result<FoundPaths, VisionError> {
    let mut grid = Grid::from_mask(mask)?;
    let mut fg: Vec<usize> = (0..grid.on.len()).filter(|&i| grid.on[i] != 0).collect();
    let area = fg.len() as f64;
    grid.thin(&mut fg);
    grid.remove_redundant(&mut fg);
    let width_px = if fg.is_empty() {
        0.0
    } else {
        area / fg.len() as f64
    };
    let mut graph = Graph::build(grid, &fg);
    graph.prune_spurs(SPUR_WIDTHS * width_px + SPUR_EXTRA_PX);
    let root = graph.merge_junctions(width_px);

    // Branches per merged junction, and their least-cost pairing (bending,
    // and colour when the image is given).
    let mut branches: HashMap<usize, Vec<Branch>> = HashMap::new();
    for (e, edge) in graph.edges.iter().enumerate() {
        if !edge.alive || edge.internal {
            continue;
        }
        for side in 0..2 {
            let n = edge.ends[side];
            if graph.nodes[n].kind == NodeKind::Junction {
                branches.entry(root[n]).or_default().push((e, side));
            }
        }
    }
    let mut partner: HashMap<Branch, Branch> = HashMap::new();
    let mut junctions: Vec<usize> = branches.keys().copied().collect();
    junctions.sort_unstable();
    for j in &junctions {
        let list = &branches[j];
        let centre = graph.nodes[*j].centre_px;
        let pairs = if list.len() == 2 {
            vec![(0, 1)]
        } else {
            let outward: Vec<_> = list.iter().map(|&b| graph.outward(b)).collect();
            let mut cost = bend_costs(&outward, centre, width_px);
            if let Some(image) = image {
                let colours = branch_colours_lab(&outward, image, width_px)?;
                add_colour_costs(&mut cost, &colours);
            }
            forbid_closing_loops(&mut cost, list);
            best_pairing(&cost)
        };
        for (a, b) in pairs {
            partner.insert(list[a], list[b]);
            partner.insert(list[b], list[a]);
        }
    }

    // Walk from every terminal branch end (an end point, or a junction
    // branch left unpaired) through the pairings.
    let mut used = vec![false; graph.edges.len()];
    let mut paths = Vec::new();
    // Skeleton pixels within about a width of a crossing lean towards the
    // other cable: a path through a crossing leaves them out, and out the
    // skeleton between a split crossing's junctions, and bridges the gap
    // with a curve that keeps to the cable's direction either side.
    let trim = (JUNCTION_TRIM_WIDTHS * width_px).round() as usize;
    let span = direction_stretch(width_px).1;
    let walk = |start: Branch, used: &mut Vec<bool>| -> Vec<[f64; 2]> {
        let mut pts = Vec::new();
        let mut cur = start;
        let mut entered_crossing = false;
        loop {
            used[cur.0] = true;
            let edge_pts = graph.outward(cur);
            let far = (cur.0, 1 - cur.1);
            let next = partner.get(&far).copied().filter(|next| !used[next.0]);
            let head = if entered_crossing { trim } else { 0 };
            let tail = if next.is_some() { trim } else { 0 };
            let own = if edge_pts.len() > 2 * (head + tail) {
                &edge_pts[head..edge_pts.len() - tail]
            } else {
                &edge_pts[..]
            };
            if entered_crossing {
                let across = bridge(&pts, own, span);
                // One that leaves the mask joins what are no one cable.
                if across.iter().all(|&p| on_mask(mask, p)) {
                    pts.extend(across);
                }
            }
            pts.extend_from_slice(own);
            match next {
                Some(next) => {
                    cur = next;
                    entered_crossing = true;
                }
                None => break,
            }
        }
        pts
    };
    let mut starts: Vec<Branch> = Vec::new();
    for (e, edge) in graph.edges.iter().enumerate() {
        if !edge.alive || edge.internal {
            continue;
        }
        for side in 0..2 {
            let terminal = match graph.nodes[edge.ends[side]].kind {
                NodeKind::End => true,
                NodeKind::Junction => !partner.contains_key(&(e, side)),
            };
            if terminal {
                starts.push((e, side));
            }
        }
    }
    for start in starts {
        if !used[start.0] {
            paths.push(walk(start, &mut used));
        }
    }
    // What is left are cables closed through junctions: open them anywhere.
    for e in 0..graph.edges.len() {
        let edge = &graph.edges[e];
        if edge.alive && !edge.internal && !used[e] {
            paths.push(walk((e, 0), &mut used));
        }
    }
    for lp in &graph.loops {
        paths.push(lp.iter().map(|&i| graph.grid.xy(i)).collect());
    }
    // Superpixel walks have their own limit on turning, and their coarse
    // node-to-node polylines would read as corners here.
    let span_px = tangent_span_px(width_px);
    let paths = paths
        .into_iter()
        .flat_map(|path| cut_at_corners(path, span_px))
        .collect();
    finish_paths(paths, mask, image, width_px, min_length_px)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::test_curves::segment_px;

    #[test]
    fn a_bridge_across_a_gap_keeps_to_the_arc_either_side() {
        // Two runs of a circle of 100 px radius, a pixel apart, with 0.4 rad
        // (40 px) of it missing between them.
        let arc = |from_rad: f64, to_rad: f64| -> Vec<[f64; 2]> {
            let n = ((to_rad - from_rad) * 100.0).round() as usize;
            (0..=n)
                .map(|i| {
                    let a = from_rad + (to_rad - from_rad) * i as f64 / n as f64;
                    [300.0 + 100.0 * a.cos(), 200.0 + 100.0 * a.sin()]
                })
                .collect()
        };
        let (before, after) = (arc(0.0, 0.3), arc(0.7, 1.0));
        let across = bridge(&before, &after, 16);
        assert_eq!(across.len(), 39);
        // Each run's direction is its chord over 16 px, 0.08 rad off the
        // tangent at its end: the bridge swings out by about half a pixel.
        for p in &across {
            let off_px = ((p[0] - 300.0).hypot(p[1] - 200.0) - 100.0).abs();
            assert!(off_px < 1.0, "{p:?} is {off_px:.2} px off the arc");
        }
        // The points go from one run to the other, a pixel apart.
        let mut all = before.clone();
        all.extend(&across);
        all.extend(&after);
        assert!(
            all.windows(2)
                .all(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) < 1.1)
        );
    }

    #[test]
    fn colour_costs_pair_like_colours_and_let_shading_pass() {
        // Three branches: 0 and 1 continue each other a little better than
        // 0 and 2, by shape.
        let pi = std::f64::consts::PI;
        let bends = || {
            vec![
                vec![pi, 0.30, 0.35],
                vec![0.30, pi, 2.5],
                vec![0.35, 2.5, pi],
            ]
        };
        let black = Some([10.0, 128.0, 128.0]);
        let shaded_black = Some([18.0, 127.0, 129.0]);
        let red = Some([130.0, 190.0, 170.0]);
        // Branch 1 red, 0 and 2 black: colour pairs 0 with 2.
        let mut cost = bends();
        add_colour_costs(&mut cost, &[black, red, black]);
        assert_eq!(best_pairing(&cost), vec![(0, 2)]);
        assert!((cost[0][1] - (0.30 + COLOUR_COST_RAD)).abs() < 1e-9);
        // A shading difference, or a branch of unknown colour, costs
        // nothing: shape decides.
        for colours in [[black, shaded_black, black], [black, None, black]] {
            let mut cost = bends();
            add_colour_costs(&mut cost, &colours);
            assert_eq!(cost, bends());
            assert_eq!(best_pairing(&cost), vec![(0, 1)]);
        }
    }

    #[test]
    fn two_cables_meeting_at_a_corner_are_cut_apart() {
        // Down to (200, 200), then up: a 90° corner.
        let mut path = segment_px([100.0, 100.0], [200.0, 200.0]);
        path.extend(segment_px([201.0, 199.0], [300.0, 100.0]));
        let pieces = cut_at_corners(path, 16.0);
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        assert_eq!(*pieces[0].last().unwrap(), [200.0, 200.0]);
        assert_eq!(pieces[1][0], [200.0, 200.0]);
        assert!(pieces.iter().all(|p| polyline_length(p) > 135.0));
    }

    #[test]
    fn a_tight_bend_is_no_corner_but_a_hooked_end_is_cut_off() {
        // A U of 20 px radius: its chords over 16 px either side of a
        // point meet at 0.8 rad.
        let u: Vec<[f64; 2]> = (0..=63)
            .map(|i| {
                let a = std::f64::consts::PI * f64::from(i) / 63.0;
                [300.0 + 20.0 * a.cos(), 200.0 + 20.0 * a.sin()]
            })
            .collect();
        assert_eq!(cut_at_corners(u.clone(), 16.0), vec![u]);
        // A right-angled hook of 12 px at an end (a blunt end's thinning):
        // cut off with a few pixels of the line, left to the length filter.
        let mut hooked = segment_px([100.0, 100.0], [300.0, 100.0]);
        hooked.extend(segment_px([300.0, 101.0], [300.0, 112.0]));
        let pieces = cut_at_corners(hooked, 16.0);
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        assert!(pieces[0].iter().all(|p| p[1] == 100.0));
        assert!(polyline_length(&pieces[0]) > 184.0);
        assert!(polyline_length(&pieces[1]) < 28.0);
    }
}
