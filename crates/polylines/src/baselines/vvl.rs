//! VVL: Visvalingam–Whyatt line simplification of the Algorithm 1 polylines.
//!
//! Each polyline is simplified on its own by repeatedly removing the interior vertex with the
//! smallest effective area — the triangle it forms with its two neighbours, raised to at least
//! the largest area removed before (Visvalingam & Whyatt 1993), so that the sequence of costs
//! never decreases — until two vertices remain; then the polyline vanishes at the last cost
//! (a lone segment vanishes at cost 0: "solitary segments are removed at zero cost"). Polygons
//! keep at least three vertices. Like the reference implementation, the removals of all
//! polylines are then ordered globally by cost and applied until `J ≤ J_max`, so the run time
//! does not depend on `J`.

use crate::initial::initial_chains;
use crate::rays::ScanRays;
use crate::{Polyline, PolylineConfig, Polylines};

/// One removal event: its cost, the polyline, and the step within that polyline.
#[derive(Clone, Copy, Debug)]
struct Event {
    cost: f64,
    line: usize,
    step: usize,
}

/// Runs VVL.
pub fn vvl(rays: &ScanRays, config: &PolylineConfig) -> Polylines {
    let chains = initial_chains(rays, config.max_edge_m);
    let points: Vec<Vec<nalgebra::Point2<f64>>> = chains
        .iter()
        .map(|c| c.rays.iter().filter_map(|&k| rays.endpoint(k)).collect())
        .collect();
    // Per polyline: the removal order (vertex positions) and the cost of each removal.
    let mut orders: Vec<Vec<usize>> = Vec::with_capacity(chains.len());
    let mut events = Vec::new();
    for (line, (chain, pts)) in chains.iter().zip(&points).enumerate() {
        let (order, costs) = removal_sequence(pts, chain.closed);
        for (step, cost) in costs.into_iter().enumerate() {
            events.push(Event { cost, line, step });
        }
        orders.push(order);
    }
    events.sort_by(|a, b| {
        a.cost
            .total_cmp(&b.cost)
            .then(a.line.cmp(&b.line))
            .then(a.step.cmp(&b.step))
    });
    let mut count: usize = points.iter().map(Vec::len).sum();
    let mut steps = vec![0usize; chains.len()];
    for e in &events {
        if count <= config.max_vertices {
            break;
        }
        let n = points[e.line].len();
        let done = steps[e.line];
        // Vertices removed by this event: one, or the last two when the polyline vanishes.
        let removed = if !chains[e.line].closed && n - done == 2 {
            2
        } else {
            1
        };
        steps[e.line] += removed;
        count -= removed;
    }
    let mut lines = Vec::new();
    for (line, chain) in chains.iter().enumerate() {
        let n = points[line].len();
        if n - steps[line] < 2 {
            continue;
        }
        let mut keep = vec![true; n];
        for &i in orders[line].iter().take(steps[line]) {
            keep[i] = false;
        }
        let vertices = (0..n)
            .filter(|&i| keep[i])
            .map(|i| points[line][i])
            .collect();
        let beams = (0..n).filter(|&i| keep[i]).map(|i| chain.rays[i]).collect();
        lines.push(Polyline {
            vertices,
            rays: beams,
            closed: chain.closed,
        });
    }
    Polylines { lines }
}

/// Visvalingam's removal order of one polyline: positions in order, and one cost per event
/// (the final event of an open polyline removes its last two vertices).
fn removal_sequence(pts: &[nalgebra::Point2<f64>], closed: bool) -> (Vec<usize>, Vec<f64>) {
    let n = pts.len();
    let mut prev: Vec<usize> = (0..n).map(|i| if i == 0 { n - 1 } else { i - 1 }).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut alive = vec![true; n];
    let is_end = |i: usize| !closed && (i == 0 || i == n - 1);
    let area = |prev: &[usize], next: &[usize], i: usize| -> f64 {
        let (a, b, c) = (pts[prev[i]], pts[i], pts[next[i]]);
        0.5 * ((b - a).perp(&(c - a))).abs()
    };
    let mut areas: Vec<f64> = (0..n)
        .map(|i| {
            if is_end(i) || n < 3 {
                f64::INFINITY
            } else {
                area(&prev, &next, i)
            }
        })
        .collect();
    let floor_count = if closed { 3 } else { 2 };
    let (mut order, mut costs) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut largest = 0.0f64;
    let mut remaining = n;
    while remaining > floor_count {
        let Some(i) = (0..n)
            .filter(|&i| alive[i])
            .min_by(|&a, &b| areas[a].total_cmp(&areas[b]))
        else {
            break;
        };
        if !areas[i].is_finite() {
            break;
        }
        largest = largest.max(areas[i]);
        alive[i] = false;
        remaining -= 1;
        order.push(i);
        costs.push(largest);
        let (p, q) = (prev[i], next[i]);
        next[p] = q;
        prev[q] = p;
        for v in [p, q] {
            if !is_end(v) {
                areas[v] = area(&prev, &next, v);
            }
        }
    }
    if !closed && remaining == 2 {
        order.extend((0..n).filter(|&i| alive[i]));
        costs.push(largest);
    }
    (order, costs)
}
