//! Pairing a junction's branches: a cable goes on through a crossing as
//! it bends and keeps its colour, so the branches are paired at least
//! total cost of bending and colour difference; a loop's two ends are not
//! paired with each other. Two junctions whose branches pair far more
//! cheaply as one crossing than apart are first merged into one. A run
//! that two cables share, forked at both ends, carries both: its forks'
//! branches are paired through it and a twin, side by side.

use std::collections::{HashMap, HashSet};

use opencv::core::Mat;
use opencv::prelude::*;

use super::direction::{bend_rad, direction_stretch, tangent_at_centre};
use super::graph::{Branch, Graph, NodeKind, SPLIT_CROSSING_WIDTHS};
use crate::perception::vision::error::VisionError;
use crate::perception::vision::mask::{half_width_at, half_widths};
use crate::perception::vision::paths::{delta_e, median, median_colour_lab, near_border};

/// Cost, in radians of bending, of leaving a branch unpaired at a junction
/// (the cable ends there). Two branches are joined rather than both left
/// unpaired when their bend is under twice this (about 140°).
pub(super) const UNPAIRED_COST_RAD: f64 = 1.2;

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

/// Chroma difference (the distance between two colours' a and b, in
/// OpenCV's 8-bit Lab) from which two branches are never paired, off
/// paint: a cable keeps its hue through a crossing whatever the light
/// does to its lightness, and a tube that ends against another's side, or
/// crosses it bending alike, would otherwise run on into it. Over paint
/// one cable's branches can read that far apart, even given its labelled
/// mask, so there unlike colours only cost [`COLOUR_COST_RAD`]
/// (docs/vision-record.md, "Hues that part cables").
const HUES_APART_CHROMA: f64 = 40.0;

/// Cost, in radians, of two cables crossing over along a run they share
/// (see [`pair_along_shared`]): less than a full colour difference, so
/// that where the colours say the cables crossed, they did.
const SIDE_SWAP_COST_RAD: f64 = 0.5;

/// How many times as wide as one of its cables a run to the border must
/// be to be shared by two (see [`share_runs`]): two side by side are
/// twice as wide.
const PAIR_WIDTHS: f64 = 1.5;

/// Above this many branches at one junction the exact least-cost pairing
/// is too costly and pairs are taken greedily, cheapest first.
const MAX_EXACT_BRANCHES: usize = 8;

/// The branches that meet at each merged junction (by its root): what
/// [`pair_branches`] pairs; none when the mask holds no crossing.
pub(super) fn junction_branches(graph: &Graph, root: &[usize]) -> HashMap<usize, Vec<Branch>> {
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
    branches
}

/// Merges two 3-way junctions that one run of skeleton, shorter than
/// [`SPLIT_CROSSING_WIDTHS`], joins into one crossing where pairing their
/// four other branches there costs, by bending, at least
/// [`UNPAIRED_COST_RAD`] less than pairing each junction's three alone:
/// two cables crossing at a shallow angle, one of them bending through
/// the crossing, leave two junctions that the shapes `Graph::
/// merge_junctions` looks for keep apart, and each junction, paired
/// alone, ends a cable there. Asking for that much less merges only
/// where the crossing goes on with a cable the two junctions would end;
/// the runs that save most are merged first, each junction once.
/// Returns each node's merged junction, as `root` gives it.
pub(super) fn merge_cheaper_crossings(
    graph: &mut Graph,
    mut root: Vec<usize>,
    width_px: f64,
) -> Vec<usize> {
    let branches = junction_branches(graph, &root);
    let least_cost = |list: &[Branch], centre: [f64; 2]| {
        let outward: Vec<_> = list.iter().map(|&b| graph.outward(b)).collect();
        let mut cost = bend_costs(&outward, centre, width_px);
        forbid_closing_loops(&mut cost, list);
        pairing_cost(&cost, &best_pairing(&cost))
    };
    let mut savings: Vec<(f64, usize)> = Vec::new();
    for (e, edge) in graph.edges.iter().enumerate() {
        let (ra, rb) = (root[edge.ends[0]], root[edge.ends[1]]);
        // A run inside a merged junction has both ends at its root.
        if !edge.alive || ra == rb || edge.length_px >= SPLIT_CROSSING_WIDTHS * width_px {
            continue;
        }
        let (Some(at_a), Some(at_b)) = (branches.get(&ra), branches.get(&rb)) else {
            continue;
        };
        let runs_between = at_a.iter().filter(|x| at_b.iter().any(|y| y.0 == x.0));
        if at_a.len() != 3 || at_b.len() != 3 || runs_between.count() != 1 {
            continue;
        }
        let outer: Vec<Branch> = at_a
            .iter()
            .chain(at_b)
            .filter(|b| b.0 != e)
            .copied()
            .collect();
        // The merged junction is centred where `rb` is (see
        // `Graph::merge_across`), and paired there.
        let centre = graph.nodes[rb].centre_px;
        let apart = least_cost(at_a, graph.nodes[ra].centre_px) + least_cost(at_b, centre);
        let saving = apart - least_cost(&outer, centre);
        if saving >= UNPAIRED_COST_RAD {
            savings.push((saving, e));
        }
    }
    savings.sort_by(|x, y| y.0.total_cmp(&x.0));
    let mut merged = HashSet::new();
    for (_, e) in savings {
        let (ra, rb) = (root[graph.edges[e].ends[0]], root[graph.edges[e].ends[1]]);
        if merged.contains(&ra) || merged.contains(&rb) {
            continue;
        }
        merged.extend([ra, rb]);
        graph.merge_across(e, &mut root);
    }
    root
}

/// A run of skeleton that two cables share, split in two (see
/// [`share_runs`]): the run, moved to the left cable, and its twin, to the
/// right one, and at each end's fork the branches on the left and on the
/// right (as the run goes from its first end to its second); no fork
/// where the two leave the view together.
pub(super) struct SharedRun {
    run: usize,
    twin: usize,
    forks: [Option<[Branch; 2]>; 2],
}

/// Finds the runs that two cables share and splits each in two
/// (`Graph::split_shared`): a run from a 3-way junction whose other two
/// branches both run on into it, to another such junction (the only run
/// between them) or to the image's border. Two cables that lie together
/// for a stretch (or cross at so shallow an angle that they overlap for
/// longer than [`SPLIT_CROSSING_WIDTHS`]) thin into one run down the
/// middle of the pair with such a fork where they part; paired as a
/// junction, one cable would go on along the run and the other end at the
/// fork. A run to the border must also be [`PAIR_WIDTHS`] times as wide as the
/// cables past its fork: a cable at the border with paint forked off it
/// has the fork, not the width.
pub(super) fn share_runs(
    graph: &mut Graph,
    root: &[usize],
    mask: &Mat,
    width_px: f64,
) -> Result<Vec<SharedRun>, VisionError> {
    let branches = junction_branches(graph, root);
    let size_px = [f64::from(mask.cols()), f64::from(mask.rows())];
    let mut found: Vec<(usize, [Option<[Branch; 2]>; 2])> = Vec::new();
    let mut taken = HashSet::new();
    for (e, edge) in graph.edges.iter().enumerate() {
        let roots = [root[edge.ends[0]], root[edge.ends[1]]];
        if !edge.alive || edge.internal || roots[0] == roots[1] {
            continue;
        }
        // The fork at one end of the run: its other two branches, on the
        // left of the run and on the right.
        let fork = |side: usize| -> Option<[Branch; 2]> {
            let r = roots[side];
            let at = branches.get(&r)?;
            let centre = graph.nodes[r].centre_px;
            if at.len() != 3
                || taken.contains(&r)
                || !graph.all_run_on_into((e, side), at, centre, width_px)
            {
                return None;
            }
            let along = graph.branch_direction((e, side), centre, width_px);
            // The run leaves its second end back towards the first.
            let ahead = if side == 0 { along } else { along.map(|c| -c) };
            let left_of_run = |b: Branch| {
                let d = graph.branch_direction(b, centre, width_px);
                ahead[0] * d[1] - ahead[1] * d[0]
            };
            let mut outer: Vec<Branch> = at.iter().copied().filter(|b| b.0 != e).collect();
            outer.sort_by(|x, y| left_of_run(*y).total_cmp(&left_of_run(*x)));
            Some([outer[0], outer[1]])
        };
        let at_border = |side: usize| {
            let node = &graph.nodes[edge.ends[side]];
            node.kind == NodeKind::End && near_border(node.centre_px, size_px, width_px + 2.0)
        };
        let forks = [fork(0), fork(1)];
        let shared = match forks {
            [Some(_), Some(_)] => {
                let at_1 = &branches[&roots[1]];
                branches[&roots[0]]
                    .iter()
                    .filter(|x| at_1.iter().any(|y| y.0 == x.0))
                    .count()
                    == 1
            }
            [Some(_), None] => at_border(1),
            [None, Some(_)] => at_border(0),
            [None, None] => false,
        };
        if shared {
            taken.extend(roots);
            found.push((e, forks));
        }
    }
    if found.is_empty() {
        return Ok(Vec::new());
    }
    let half_widths = half_widths(mask)?;
    let mut shared = Vec::new();
    for (run, forks) in found {
        // Each side's cable's half width, where it runs apart from the
        // other past the forks.
        let own_px = [0, 1].map(|side| {
            let mut halves: Vec<f64> = forks
                .iter()
                .flatten()
                .flat_map(|fork| graph.outward(fork[side]))
                .map(|p| half_width_at(&half_widths, p))
                .filter(|&h| h > 0.0)
                .collect();
            median(&mut halves).unwrap_or(0.5 * width_px)
        });
        if forks.contains(&None) {
            let mut pair: Vec<f64> = graph
                .outward((run, 0))
                .into_iter()
                .map(|p| half_width_at(&half_widths, p))
                .collect();
            let pair_px = median(&mut pair).unwrap_or(0.0);
            if pair_px < 0.5 * PAIR_WIDTHS * (own_px[0] + own_px[1]) {
                continue;
            }
        }
        shared.push(SharedRun {
            run,
            twin: graph.split_shared(run, &half_widths, own_px),
            forks,
        });
    }
    Ok(shared)
}

/// The pairings at the forks of a shared run: at the first fork, the
/// branch on the left joined to the run and the one on the right to its
/// twin; at the second, the same, so that two cables lying together do
/// not cross; or the other way, where colours say so. Given the image,
/// branches of unlike colour cost more to join, as at a crossing, and
/// [`SIDE_SWAP_COST_RAD`] is what crossing over costs against them: two
/// cables crossing at a shallow angle do cross.
fn pair_along_shared(
    graph: &Graph,
    shared: &SharedRun,
    image: Option<&Mat>,
    width_px: f64,
) -> Result<Vec<(Branch, Branch)>, VisionError> {
    let (run, twin) = (shared.run, shared.twin);
    let [[a_left, a_right], [b_left, b_right]] = match shared.forks {
        [Some(a), Some(b)] => [a, b],
        [Some([left, right]), None] => return Ok(vec![(left, (run, 0)), (right, (twin, 0))]),
        [None, Some([left, right])] => return Ok(vec![(left, (run, 1)), (right, (twin, 1))]),
        [None, None] => return Ok(Vec::new()),
    };
    let colours = match image {
        Some(image) => {
            let outer = [a_left, a_right, b_left, b_right];
            let outward: Vec<_> = outer.iter().map(|&b| graph.outward(b)).collect();
            branch_colours_lab(&outward, image, width_px)?
        }
        None => vec![None; 4],
    };
    let join = |a: usize, b: usize| colour_cost(colours[a], colours[b]);
    let alongside = join(0, 2) + join(1, 3);
    let crossed = join(0, 3) + join(1, 2) + 2.0 * SIDE_SWAP_COST_RAD;
    let (b_run, b_twin) = if alongside <= crossed {
        (b_left, b_right)
    } else {
        (b_right, b_left)
    };
    Ok(vec![
        (a_left, (run, 0)),
        ((run, 1), b_run),
        (a_right, (twin, 0)),
        ((twin, 1), b_twin),
    ])
}

/// What the pairing `pairs` of branches whose pairings cost `cost` costs,
/// each branch it leaves unpaired [`UNPAIRED_COST_RAD`].
fn pairing_cost(cost: &[Vec<f64>], pairs: &[(usize, usize)]) -> f64 {
    let paired: f64 = pairs.iter().map(|&(i, j)| cost[i][j]).sum();
    paired + UNPAIRED_COST_RAD * (cost.len() - 2 * pairs.len()) as f64
}

/// Each junction branch's partner: at every merged junction (`root`
/// gives each node's), its branches paired at least cost, by bending and,
/// given the BGR `image` the mask was found in, by colour, never across
/// unlike hues unless the background is `painted` (see
/// [`HUES_APART_CHROMA`]). Branches left unpaired have none: the cable
/// ends there.
pub(super) fn pair_branches(
    graph: &Graph,
    root: &[usize],
    image: Option<&Mat>,
    painted: bool,
    width_px: f64,
    shared_runs: &[SharedRun],
) -> Result<HashMap<Branch, Branch>, VisionError> {
    let branches = junction_branches(graph, root);
    let mut partner: HashMap<Branch, Branch> = HashMap::new();
    let mut forks = HashSet::new();
    for shared in shared_runs {
        let ends = graph.edges[shared.run].ends;
        for (end, fork) in ends.iter().zip(shared.forks) {
            if fork.is_some() {
                forks.insert(root[*end]);
            }
        }
        for (x, y) in pair_along_shared(graph, shared, image, width_px)? {
            partner.insert(x, y);
            partner.insert(y, x);
        }
    }
    let mut junctions: Vec<usize> = branches
        .keys()
        .copied()
        .filter(|j| !forks.contains(j))
        .collect();
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
                if !painted {
                    forbid_unlike_hues(&mut cost, &colours);
                }
            }
            forbid_closing_loops(&mut cost, list);
            best_pairing(&cost)
        };
        for (a, b) in pairs {
            partner.insert(list[a], list[b]);
            partner.insert(list[b], list[a]);
        }
    }
    Ok(partner)
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

/// Adds to each pairing's bend the cost of the two branches' colour
/// difference (see [`COLOUR_COST_RAD`]); branches of unknown colour cost
/// nothing more.
fn add_colour_costs(cost: &mut [Vec<f64>], colours_lab: &[Option<[f64; 3]>]) {
    for (row, a) in cost.iter_mut().zip(colours_lab) {
        for (c, b) in row.iter_mut().zip(colours_lab) {
            *c += colour_cost(*a, *b);
        }
    }
}

/// The cost of joining two branches of these colours (see
/// [`COLOUR_COST_RAD`]); nothing where either colour is unknown.
fn colour_cost(a: Option<[f64; 3]>, b: Option<[f64; 3]>) -> f64 {
    let (Some(a), Some(b)) = (a, b) else {
        return 0.0;
    };
    let over = (delta_e(a, b) - COLOUR_SAME_DELTA_E) / (COLOUR_FULL_DELTA_E - COLOUR_SAME_DELTA_E);
    COLOUR_COST_RAD * over.clamp(0.0, 1.0)
}

/// Forbids pairing two branches whose hues differ (see
/// [`HUES_APART_CHROMA`]); branches of unknown colour stay free.
fn forbid_unlike_hues(cost: &mut [Vec<f64>], colours_lab: &[Option<[f64; 3]>]) {
    for (row, a) in cost.iter_mut().zip(colours_lab) {
        for (c, b) in row.iter_mut().zip(colours_lab) {
            if let (Some(a), Some(b)) = (a, b)
                && (a[1] - b[1]).hypot(a[2] - b[2]) >= HUES_APART_CHROMA
            {
                *c = f64::INFINITY;
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

#[cfg(test)]
mod tests {
    use opencv::core::{Point, Scalar, Vector};
    use opencv::imgproc;

    use super::super::paths_from_mask;
    use super::*;
    use crate::perception::vision::mask::zeros_u8;
    use crate::perception::vision::paths::{JOIN_GAP_WIDTHS, polyline_length};

    /// The paths found in a 220 × 400 mask of `lines`, each a polyline
    /// through its points, with its width in pixels.
    fn paths_of(lines: &[(&[(i32, i32)], i32)]) -> Vec<Vec<[f64; 2]>> {
        let mut mask = zeros_u8(220, 400).unwrap();
        for &(points, width) in lines {
            let line: Vector<Point> = points.iter().map(|&(x, y)| Point::new(x, y)).collect();
            let lines = Vector::<Vector<Point>>::from_iter([line]);
            imgproc::polylines(
                &mut mask,
                &lines,
                false,
                Scalar::all(255.0),
                width,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
        }
        let found = paths_from_mask(&mask, None, false, 20.0, JOIN_GAP_WIDTHS).unwrap();
        found.paths.into_iter().map(|path| path.points_px).collect()
    }

    /// Asserts that `paths` are two, one along each of two cables whose
    /// centre lines run at y = 100 and 110 from x = 140 to 260, where the
    /// skeleton of the pair runs down their middle.
    fn assert_two_on_their_own_lines(paths: &[Vec<[f64; 2]>]) {
        assert_eq!(paths.len(), 2, "{paths:?}");
        let mut middles: Vec<f64> = paths
            .iter()
            .map(|path| {
                let along: Vec<f64> = path
                    .iter()
                    .filter(|p| (140.0..260.0).contains(&p[0]))
                    .map(|p| p[1])
                    .collect();
                assert!(!along.is_empty());
                along.iter().sum::<f64>() / along.len() as f64
            })
            .collect();
        middles.sort_by(f64::total_cmp);
        assert!((middles[0] - 100.0).abs() < 1.5, "{middles:?}");
        assert!((middles[1] - 110.0).abs() < 1.5, "{middles:?}");
    }

    #[test]
    fn two_cables_lying_together_for_a_stretch_are_two_paths_along_their_own_lines() {
        // Two 10 px cables that come together from above and below, lie
        // side by side (centre lines at y = 100 and 110) from x = 80 to
        // 320, and part again: one run of skeleton down y = 105 between
        // two forks, too far apart to be one crossing.
        let paths = paths_of(&[
            (&[(20, 40), (80, 100), (320, 100), (380, 40)], 10),
            (&[(20, 170), (80, 110), (320, 110), (380, 170)], 10),
        ]);
        assert_two_on_their_own_lines(&paths);
        // Each runs from its cable's one end to its other: from top left
        // to top right, or bottom left to bottom right.
        for path in &paths {
            let (first, last) = (path[0], path[path.len() - 1]);
            assert!(
                (first[1] < 105.0) == (last[1] < 105.0),
                "{first:?} {last:?}"
            );
            assert!(polyline_length(path) > 380.0, "{}", polyline_length(path));
        }
    }

    #[test]
    fn two_cables_leaving_the_view_together_are_two_paths_to_the_border() {
        let paths = paths_of(&[
            (&[(20, 40), (80, 100), (399, 100)], 10),
            (&[(20, 170), (80, 110), (399, 110)], 10),
        ]);
        assert_two_on_their_own_lines(&paths);
        for path in &paths {
            assert!(path.iter().any(|p| p[0] > 385.0), "{path:?}");
        }
    }

    #[test]
    fn a_cable_at_the_border_with_a_thin_stroke_forked_off_it_is_not_split() {
        // A 10 px cable to the border, and a 3 px stroke that meets it at
        // a shallow angle: a fork at the run to the border, but the run is
        // one cable wide.
        let paths = paths_of(&[(&[(20, 105), (399, 105)], 10), (&[(20, 70), (150, 103)], 3)]);
        let to_border = paths
            .iter()
            .filter(|path| path.iter().any(|p| p[0] > 385.0))
            .count();
        assert_eq!(to_border, 1, "{paths:?}");
    }

    #[test]
    fn a_cable_ending_against_another_near_its_end_leaves_it_whole() {
        // A 20 px cable along y = 100, and another whose end comes down at
        // 45° onto its side 35 px from its end: the first cable's end is a
        // short straight run past the junction, as long as a thinning spur.
        let paths = paths_of(&[(&[(60, 100), (360, 100)], 20), (&[(10, 20), (95, 95)], 20)]);
        assert_eq!(paths.len(), 2, "{paths:?}");
        let along = paths
            .iter()
            .find(|path| path.iter().all(|p| (p[1] - 100.0).abs() < 5.0))
            .expect("one path along the first cable");
        let xs = along.iter().map(|p| p[0]);
        let (from, to) = (xs.clone().fold(f64::MAX, f64::min), xs.fold(0.0, f64::max));
        assert!(from < 75.0 && to > 345.0, "{from} to {to}");
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
        // Unlike hues are forbidden off paint; lightness alone is not a
        // hue (a lit and a shaded stretch of one red cable).
        let shaded_red = Some([60.0, 180.0, 160.0]);
        let mut cost = bends();
        forbid_unlike_hues(&mut cost, &[red, black, shaded_red]);
        assert_eq!(cost[0][1], f64::INFINITY);
        assert_eq!(cost[0][2], 0.35);
        assert_eq!(cost[1][2], f64::INFINITY);
        // A shading difference, or a branch of unknown colour, costs
        // nothing: shape decides.
        for colours in [[black, shaded_black, black], [black, None, black]] {
            let mut cost = bends();
            add_colour_costs(&mut cost, &colours);
            assert_eq!(cost, bends());
            assert_eq!(best_pairing(&cost), vec![(0, 1)]);
        }
    }
}
