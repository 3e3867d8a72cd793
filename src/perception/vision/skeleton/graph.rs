//! The skeleton as a graph: end points and junctions are its nodes, the
//! pixel runs between them its edges. Spurs are pruned, junctions that
//! are one crossing merged, and runs that two cables share split in two.

use std::collections::HashSet;

use opencv::core::Mat;

use super::direction::{bend_rad, direction_leaving};
use super::thin::Grid;
use crate::perception::vision::mask::half_width_at;
use crate::perception::vision::paths::{polyline_length, unit};

/// Junctions joined by an edge shorter than this many cable widths are one
/// crossing: two cables crossing at 25° overlap for about 2.4 widths.
const MERGE_WIDTHS: f64 = 2.5;

/// Junctions up to this many cable widths apart may still be one crossing
/// (two cables crossing at 10° overlap for about six widths; 10 px cables
/// bending opposite ways through 29° left junctions 8.6 widths apart), when
/// their shape says so (see `Graph::merge_junctions`) or their pairing
/// does (see `pairing::merge_cheaper_crossings`).
pub(super) const SPLIT_CROSSING_WIDTHS: f64 = 10.0;

/// How straight both outer branches of a split crossing's junction must run
/// on into the edge between the junctions. That edge runs between the two
/// cables, so a cable that bends through the crossing leaves it at up to
/// 45° (0.6 rad split 3 crossings of the training photographs wrongly).
const SPLIT_CONTINUE_RAD: f64 = 0.9;

/// A spur that runs on into another branch of its 3-way junction within
/// this, and is at least [`CABLE_END_MIN_WIDTHS`] long, is a cable's end
/// that another cable's end touches, not a spur of the thinning (which
/// leaves its junction at a slant): pruned, the cable that touches it would
/// run on into it as one path, and the cable would lose its end.
const CABLE_END_STRAIGHT_RAD: f64 = 0.5;

/// Thinning a blunt end or a ragged edge leaves spurs of up to about this
/// many cable widths.
const CABLE_END_MIN_WIDTHS: f64 = 1.0;

/// A run of skeleton that leaves a crossing and returns to it is a loop of
/// one cable, not the lens between two cables crossing twice, when it is
/// this many times longer than the run the two strands share.
const LOOP_TO_OVERLAP: f64 = 3.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum NodeKind {
    End,
    Junction,
}

pub(super) struct Node {
    pub kind: NodeKind,
    pub centre_px: [f64; 2],
}

pub(super) struct Edge {
    /// Node at each end.
    pub ends: [usize; 2],
    /// From the pixel of `ends[0]` it leaves to the pixel of `ends[1]`.
    pub pixels: Vec<usize>,
    /// Where two cables share the run, its cable's points beside the
    /// skeleton (see [`Graph::split_shared`]); its pixels otherwise.
    pub points_px: Option<Vec<[f64; 2]>>,
    pub length_px: f64,
    pub alive: bool,
    /// Inside a merged junction: not a branch of it.
    pub internal: bool,
}

/// A branch of a junction: an edge and which of its ends is at the
/// junction.
pub(super) type Branch = (usize, usize);

const NONE: usize = usize::MAX;

pub(super) struct Graph {
    pub grid: Grid,
    pub nodes: Vec<Node>,
    pub edges: Vec<Edge>,
    /// Paths that are closed loops of skeleton with no node on them.
    pub loops: Vec<Vec<usize>>,
}

impl Graph {
    pub(super) fn build(grid: Grid, skeleton: &[usize]) -> Graph {
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
                                points_px: None,
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
                        points_px: None,
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

    /// Each merged junction's branches (by its root in `root`), counted at
    /// the root.
    fn degrees(&self, root: &[usize]) -> Vec<usize> {
        let mut degree = vec![0; self.nodes.len()];
        for e in self.edges.iter().filter(|e| e.alive && !e.internal) {
            degree[root[e.ends[0]]] += 1;
            degree[root[e.ends[1]]] += 1;
        }
        degree
    }

    /// Each node as its own junction: the roots before any merge.
    pub(super) fn unmerged(&self) -> Vec<usize> {
        (0..self.nodes.len()).collect()
    }

    /// Drops spurs (end-to-junction edges shorter than `spur_px`), shortest
    /// first, as long as their junction, merged as `root` says, keeps at
    /// least two other branches, but not a cable's end at a 3-way junction
    /// (see [`CABLE_END_STRAIGHT_RAD`]). Pruned again once junctions are
    /// merged, a spur left at one of a crossing's junctions (whose only
    /// other branch ran into the crossing) goes too, and is not paired with
    /// a cable.
    pub(super) fn prune_spurs(&mut self, spur_px: f64, root: &[usize], width_px: f64) {
        let mut degree = self.degrees(root);
        let mut spurs: Vec<usize> = (0..self.edges.len())
            .filter(|&e| {
                let edge = &self.edges[e];
                let kinds = edge.ends.map(|n| self.nodes[n].kind);
                edge.alive
                    && edge.length_px < spur_px
                    && kinds.contains(&NodeKind::End)
                    && kinds.contains(&NodeKind::Junction)
            })
            .collect();
        spurs.sort_by(|&a, &b| self.edges[a].length_px.total_cmp(&self.edges[b].length_px));
        for e in spurs {
            let ends = self.edges[e].ends;
            let side = usize::from(self.nodes[ends[0]].kind != NodeKind::Junction);
            let junction = root[ends[side]];
            let cable_end = degree[junction] == 3 && self.is_cable_end((e, side), root, width_px);
            if degree[junction] >= 3 && !cable_end {
                self.edges[e].alive = false;
                degree[junction] -= 1;
            }
        }
    }

    /// Whether the spur `spur` (its edge, and its end at the junction) is a
    /// cable's end (see [`CABLE_END_STRAIGHT_RAD`]), its junction merged as
    /// `root` says.
    fn is_cable_end(&self, spur: Branch, root: &[usize], width_px: f64) -> bool {
        let (e, side) = spur;
        if self.edges[e].length_px < CABLE_END_MIN_WIDTHS * width_px {
            return false;
        }
        let at = self.edges[e].ends[side];
        let centre = self.nodes[at].centre_px;
        let spur_dir = self.branch_direction(spur, centre, width_px);
        self.edges.iter().enumerate().any(|(o, edge)| {
            o != e
                && edge.alive
                && !edge.internal
                && (0..2).any(|k| {
                    root[edge.ends[k]] == root[at]
                        && bend_rad(spur_dir, self.branch_direction((o, k), centre, width_px))
                            < CABLE_END_STRAIGHT_RAD
                })
        })
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
    pub(super) fn merge_junctions(&mut self, width_px: f64) -> Vec<usize> {
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
                    self.all_run_on_into((e, side), branches, self.nodes[n].centre_px, width_px)
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

    /// Whether every branch but `into` of a junction at `centre` runs on
    /// into `into` (within [`SPLIT_CONTINUE_RAD`]): where two cables meet
    /// to run on together, or to cross at a shallow angle.
    pub(super) fn all_run_on_into(
        &self,
        into: Branch,
        branches: &[Branch],
        centre: [f64; 2],
        width_px: f64,
    ) -> bool {
        let into_dir = self.branch_direction(into, centre, width_px);
        branches.iter().filter(|&&br| br != into).all(|&br| {
            bend_rad(self.branch_direction(br, centre, width_px), into_dir) < SPLIT_CONTINUE_RAD
        })
    }

    /// Splits the run `e` that two cables share into two: where they lie
    /// together, the skeleton runs down the middle of the pair. The run is
    /// moved to the left (as it goes from its first end to its second) and
    /// a twin, which it returns, to the right, to where each cable's centre
    /// line lies given their half widths (`half_width_px`: left, right) and
    /// the pair's (`half_widths`, the mask's distance transform): a cable's
    /// half width in from the pair's edge where they lie side by side, on
    /// the skeleton where one lies on the other.
    pub(super) fn split_shared(
        &mut self,
        e: usize,
        half_widths: &Mat,
        half_width_px: [f64; 2],
    ) -> usize {
        let pts: Vec<[f64; 2]> = self.outward((e, 0));
        let k = ((half_width_px[0] + half_width_px[1]).round() as usize).max(2);
        let last = pts.len() - 1;
        let (mut left, mut right) = (Vec::new(), Vec::new());
        for (i, &p) in pts.iter().enumerate() {
            let Some(t) = unit(pts[i.saturating_sub(k)], pts[(i + k).min(last)]) else {
                left.push(p);
                right.push(p);
                continue;
            };
            let pair_px = half_width_at(half_widths, p);
            let normal = [-t[1], t[0]];
            let [l, r] = half_width_px.map(|own| (pair_px - own).max(0.0));
            left.push([p[0] + l * normal[0], p[1] + l * normal[1]]);
            right.push([p[0] - r * normal[0], p[1] - r * normal[1]]);
        }
        let edge = &mut self.edges[e];
        edge.points_px = Some(left);
        let twin = Edge {
            ends: edge.ends,
            pixels: edge.pixels.clone(),
            points_px: Some(right),
            length_px: edge.length_px,
            alive: edge.alive,
            internal: edge.internal,
        };
        self.edges.push(twin);
        self.edges.len() - 1
    }

    /// Makes the run `e` between two junctions part of one crossing: the
    /// merged junctions at its ends become one (`root` gives each node's).
    pub(super) fn merge_across(&mut self, e: usize, root: &mut [usize]) {
        let [a, b] = self.edges[e].ends;
        let (ra, rb) = (root[a], root[b]);
        for r in root.iter_mut() {
            if *r == ra {
                *r = rb;
            }
        }
        self.edges[e].internal = true;
    }

    /// Points of a branch going out of its junction.
    pub(super) fn outward(&self, (e, side): Branch) -> Vec<[f64; 2]> {
        let edge = &self.edges[e];
        let mut pts: Vec<[f64; 2]> = match &edge.points_px {
            Some(points) => points.clone(),
            None => edge.pixels.iter().map(|&i| self.grid.xy(i)).collect(),
        };
        if side == 1 {
            pts.reverse();
        }
        pts
    }

    /// The branch's direction leaving the junction (see
    /// [`direction_stretch`]).
    pub(super) fn branch_direction(
        &self,
        branch: Branch,
        centre: [f64; 2],
        width_px: f64,
    ) -> [f64; 2] {
        direction_leaving(&self.outward(branch), centre, width_px)
    }
}

#[cfg(test)]
mod tests {
    use opencv::core::{Point, Scalar};
    use opencv::imgproc;

    use super::super::pairing::{junction_branches, merge_cheaper_crossings, pair_branches};
    use super::super::thin::skeleton;
    use super::*;
    use crate::perception::vision::mask::zeros_u8;

    /// A one-pixel skeleton of `lines`, each from its first to its last
    /// point, in a 200 × 200 mask.
    fn graph_of(lines: &[[[i32; 2]; 2]]) -> Graph {
        let mut mask = zeros_u8(200, 200).unwrap();
        for [a, b] in lines {
            let (a, b) = (Point::new(a[0], a[1]), Point::new(b[0], b[1]));
            imgproc::line(&mut mask, a, b, Scalar::all(255.0), 1, imgproc::LINE_8, 0).unwrap();
        }
        let thinned = skeleton(&mask).unwrap();
        Graph::build(thinned.grid, &thinned.pixels)
    }

    /// How many branches meet at each merged junction.
    fn branch_counts(graph: &Graph, root: &[usize]) -> Vec<usize> {
        junction_branches(graph, root)
            .values()
            .map(Vec::len)
            .collect()
    }

    #[test]
    fn a_spur_at_a_crossings_second_junction_goes_once_they_are_merged() {
        // A cable down x = 50, a side run of 8 px at y = 60 that forks into
        // two spurs: its fork keeps one spur (it needs two branches beside
        // it), until it is merged with the cable's junction.
        let mut graph = graph_of(&[
            [[50, 0], [50, 150]],
            [[51, 60], [58, 60]],
            [[59, 59], [62, 56]],
            [[59, 61], [62, 64]],
        ]);
        let (width_px, spur_px) = (6.0, 13.0);
        graph.prune_spurs(spur_px, &graph.unmerged(), width_px);
        let spurs_alive = |graph: &Graph| {
            graph
                .edges
                .iter()
                .filter(|e| e.alive && e.length_px < spur_px)
                .filter(|e| e.ends.iter().any(|&n| graph.nodes[n].kind == NodeKind::End))
                .count()
        };
        assert_eq!(spurs_alive(&graph), 1);
        let root = graph.merge_junctions(width_px);
        graph.prune_spurs(spur_px, &root, width_px);
        assert_eq!(spurs_alive(&graph), 0);
        // The merged junction is left with the cable's two branches.
        assert_eq!(branch_counts(&graph, &root), vec![2]);
    }

    #[test]
    fn junctions_that_pair_more_cheaply_as_one_crossing_are_merged() {
        // Two cables 6 px wide run together for 40 px and part again; one
        // comes in steeply, 1.1 rad off the run they share, so the shapes
        // `merge_junctions` looks for keep the two junctions apart, and
        // each, paired alone, ends a cable.
        let mut graph = graph_of(&[
            [[60, 40], [80, 80]],
            [[40, 110], [80, 80]],
            [[80, 80], [120, 80]],
            [[120, 80], [160, 110]],
            [[120, 80], [160, 50]],
        ]);
        let width_px = 6.0;
        let root = graph.merge_junctions(width_px);
        assert_eq!(branch_counts(&graph, &root), vec![3, 3]);
        let root = merge_cheaper_crossings(&mut graph, root, width_px);
        assert_eq!(branch_counts(&graph, &root), vec![4]);
        // Each cable goes on through the crossing.
        let partner = pair_branches(&graph, &root, None, false, width_px, &[]).unwrap();
        let far_end = |branch: Branch| *graph.outward(branch).last().unwrap();
        let near = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) < 4.0;
        for (from, to) in [
            ([60.0, 40.0], [160.0, 110.0]),
            ([40.0, 110.0], [160.0, 50.0]),
        ] {
            let branch = partner.keys().find(|&&b| near(far_end(b), from)).unwrap();
            assert!(
                near(far_end(partner[branch]), to),
                "{:?}",
                far_end(partner[branch])
            );
        }
    }

    #[test]
    fn off_paint_a_branch_is_never_paired_with_one_of_another_hue() {
        // A black cable comes in from the left and turns down by 1.35 rad
        // at (100, 100); a red one ends there, straight on from the black
        // one's first leg. By shape, and with unlike colours costing at
        // most 1 rad more, the black one would run on into the red one.
        let (left, right, down) = (
            [[0, 100], [100, 100]],
            [[100, 100], [199, 100]],
            [[100, 100], [120, 190]],
        );
        let mut graph = graph_of(&[left, right, down]);
        let mut image =
            Mat::new_rows_cols_with_default(200, 200, opencv::core::CV_8UC3, Scalar::all(200.0))
                .unwrap();
        for ([a, b], bgr) in [
            (right, (40.0, 40.0, 210.0)),
            (left, (30.0, 30.0, 30.0)),
            (down, (30.0, 30.0, 30.0)),
        ] {
            let (a, b) = (Point::new(a[0], a[1]), Point::new(b[0], b[1]));
            let colour = Scalar::new(bgr.0, bgr.1, bgr.2, 0.0);
            imgproc::line(&mut image, a, b, colour, 7, imgproc::LINE_8, 0).unwrap();
        }
        let width_px = 6.0;
        let root = graph.merge_junctions(width_px);
        assert_eq!(branch_counts(&graph, &root), vec![3]);
        // The far end of the branch paired with the one from the left.
        let partner_of_left = |painted: bool| {
            let partner =
                pair_branches(&graph, &root, Some(&image), painted, width_px, &[]).unwrap();
            let from_left = partner
                .keys()
                .find(|&&b| graph.outward(b).last().unwrap()[0] < 5.0)
                .copied()
                .expect("the branch from the left is paired");
            *graph.outward(partner[&from_left]).last().unwrap()
        };
        let off_paint = partner_of_left(false);
        assert!(off_paint[1] > 180.0, "{off_paint:?}");
        // On paint, where one cable's branches can read as far apart in
        // hue, shape and the bounded colour cost decide.
        let on_paint = partner_of_left(true);
        assert!(on_paint[0] > 190.0, "{on_paint:?}");
    }
}
