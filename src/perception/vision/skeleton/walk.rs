//! Walking the graph from end to end through the pairings, one path per
//! cable, bridging each crossing with a curve that keeps to the cable's
//! direction either side; and cutting a path where it turns so sharply
//! that it is two cables.

use std::collections::HashMap;

use opencv::core::Mat;
use opencv::prelude::*;

use super::direction::direction_stretch;
use super::graph::{Branch, Graph, NodeKind};
use crate::perception::vision::paths::{angle_rad, pixel_in, unit};
use crate::perception::vision::spline::arc_lengths_px;

/// Skeleton pixels this many widths either side of a crossing are left out
/// of the paths through it.
const JUNCTION_TRIM_WIDTHS: f64 = 1.0;

/// A path that turns by more than this over two cable widths either side
/// of a point (`paths::tangent_span_px`) is two cables meeting there (or a
/// hook at its end). In the 45 photographs of cables-dev, the paths found
/// along single wires turn by at most 0.73 rad so; where two wires were
/// found as one, by 1.03 rad or more.
const CORNER_TURN_RAD: f64 = 0.9;

/// One path per cable: walked from every terminal branch end (an end
/// point, or a junction branch left unpaired) through the pairings in
/// `partner`, bridged across each crossing where the bridge keeps to
/// `mask`; then what is left, cables closed through junctions, opened
/// anywhere; then the skeleton's loops with no node.
pub(super) fn walk_paths(
    graph: &Graph,
    partner: &HashMap<Branch, Branch>,
    mask: &Mat,
    width_px: f64,
) -> Vec<Vec<[f64; 2]>> {
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
    paths
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
    pixel_in(mask, p).is_some_and(|(row, col)| mask.at_2d::<u8>(row, col).is_ok_and(|&v| v != 0))
}

/// `path` cut at each corner sharper than [`CORNER_TURN_RAD`]: where its
/// direction over `span_px` before a point and over `span_px` after it
/// differ by more, two cables meet there (touching end to end, or leaving
/// the view at one place with the mask joined between them). Points within
/// `span_px` of an end are not looked at: ends are ragged.
pub(super) fn cut_at_corners(path: Vec<[f64; 2]>, span_px: f64) -> Vec<Vec<[f64; 2]>> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::vision::curves::segment_px;
    use crate::perception::vision::paths::polyline_length;

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
