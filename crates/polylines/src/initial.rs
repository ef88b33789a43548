//! Algorithm 1, lines 1–10: the initial polylines through all scan endpoints.
//!
//! Neighbouring endpoints `b_k, b_{k+1}` are connected when both beams returned and they are at
//! most `l_max` apart; the connections are merged into polylines. A full-revolution scan whose
//! connections all pass is one closed polygon (the last beam connects to the first). Single
//! endpoints without a connection form no polyline.

use crate::rays::ScanRays;

/// A chain of beams whose endpoints form an initial polyline.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chain {
    /// Beam indices in order.
    pub rays: Vec<usize>,
    /// True for a closed polygon.
    pub closed: bool,
}

/// The initial polylines of Algorithm 1 (lines 1–10).
pub fn initial_chains(rays: &ScanRays, max_edge_m: f64) -> Vec<Chain> {
    let n = rays.len();
    if n < 2 {
        return Vec::new();
    }
    let connected = |k: usize| -> bool {
        let next = (k + 1) % n;
        match (rays.endpoint(k), rays.endpoint(next)) {
            (Some(a), Some(b)) => (b - a).norm() <= max_edge_m,
            _ => false,
        }
    };
    // Edges k → k+1; the closing edge n−1 → 0 only for a full revolution.
    let edges = if rays.is_closed() { n } else { n - 1 };
    let links: Vec<bool> = (0..edges).map(connected).collect();
    if rays.is_closed() && links.iter().all(|&l| l) {
        return vec![Chain {
            rays: (0..n).collect(),
            closed: true,
        }];
    }
    // Start after a broken link (or at beam 0 of an open fan) and walk once around.
    let start = if rays.is_closed() {
        links.iter().position(|&l| !l).map_or(0, |i| (i + 1) % n)
    } else {
        0
    };
    let mut chains = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for step in 0..n {
        let k = (start + step) % n;
        if current.is_empty() {
            if rays.radius(k).is_none() {
                continue;
            }
            current.push(k);
        }
        let linked = links.get(k).copied().unwrap_or(false) && step + 1 < n;
        if linked {
            current.push((k + 1) % n);
        } else {
            if current.len() >= 2 {
                chains.push(Chain {
                    rays: std::mem::take(&mut current),
                    closed: false,
                });
            }
            current.clear();
        }
    }
    if current.len() >= 2 {
        chains.push(Chain {
            rays: current,
            closed: false,
        });
    }
    chains
}

#[cfg(test)]
mod tests {
    use super::*;
    use raypath_geometry::Scan2;
    use std::f64::consts::{PI, TAU};

    fn rays(angle_min: f64, inc: f64, ranges: Vec<f64>) -> ScanRays {
        ScanRays::new(&Scan2 {
            angle_min_rad: angle_min,
            angle_increment_rad: inc,
            max_range_m: 50.0,
            ranges,
            intensities: None,
        })
        .expect("valid")
    }

    #[test]
    fn full_circle_is_one_polygon() {
        let r = rays(-PI, TAU / 100.0, vec![2.0; 100]);
        let chains = initial_chains(&r, 1.0);
        assert_eq!(chains.len(), 1);
        assert!(chains[0].closed);
        assert_eq!(chains[0].rays.len(), 100);
    }

    #[test]
    fn breaks_at_no_returns_and_long_edges() {
        let mut ranges = vec![2.0; 100];
        ranges[10] = 60.0; // no-return
        ranges[50] = 8.0; // isolated far point: both its edges are too long
        let r = rays(-PI, TAU / 100.0, ranges);
        let chains = initial_chains(&r, 1.0);
        assert_eq!(chains.len(), 2);
        assert!(chains.iter().all(|c| !c.closed));
        let total: usize = chains.iter().map(|c| c.rays.len()).sum();
        assert_eq!(total, 98);
        // The chain that wraps around starts right after the gap at beam 50.
        assert!(
            chains
                .iter()
                .any(|c| c.rays[0] == 51 && c.rays.last() == Some(&9))
        );
    }

    #[test]
    fn open_fan() {
        let r = rays(-PI / 2.0, PI / 179.0, vec![3.0; 180]);
        let chains = initial_chains(&r, 1.0);
        assert_eq!(chains.len(), 1);
        assert!(!chains[0].closed);
        assert_eq!(chains[0].rays, (0..180).collect::<Vec<_>>());
    }
}
