//! Loop closure: find finished submaps a new node may see, verify each candidate by a
//! correlative branch-and-bound search (Olson 2009; Hess et al. 2016, §V) and refine it by the
//! Gauss–Newton matcher on the submap's grids.
//!
//! Candidates come from two sources:
//!
//! * **nearby submaps**: finished submaps whose centre lies within a search radius of the
//!   node's current estimate; radius and window grow with the path since the last accepted loop
//!   closure, since the estimate's uncertainty grows with it;
//! * **place recognition** (`raypath-place-recognition`): the node scan's planar polar context
//!   (a Scan-Context-like descriptor) against the nodes of finished submaps, wherever the
//!   estimate puts them; a candidate is searched over the full rotation around the matched
//!   node.
//!
//! A candidate becomes a loop constraint when the best pose of the search reaches the minimum
//! score, no heading at least [`LoopSearchConfig::ambiguity_min_angle_rad`] away scores
//! nearly as well ([`LoopSearchConfig::ambiguity_ratio`]; ours: a corridor or a symmetric room
//! fits a scan at several headings, and the loop closures that passed every other test and
//! still disagreed with the corrected logs were rotations), and the Gauss–Newton refinement
//! stays within [`LoopSearchConfig::max_refinement_m`] of it. Wrong constraints that pass all
//! three are left to the robust pose graph (see [`crate::graph`]).

use raypath_geometry::{Pose2, Scan2};
use raypath_place_recognition::{PolarConfig, PolarContext, PolarDescription};
use raypath_reflectivity::{MatcherConfig, ScanPoints, match_levels};

use crate::config::LoopSearchConfig;
use crate::correlative::{SearchWindow, match_scan};
use crate::error::Result;
use crate::global_search::GlobalSearchConfig;
use crate::submap::Submap;

/// Where a loop candidate came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LoopSource {
    /// A finished submap near the node's current estimate.
    Nearby,
    /// Place recognition (planar polar context).
    PlaceRecognition,
    /// The global search's wide window ([`crate::global_search`]).
    Global,
}

/// An accepted loop constraint: node `node` seen in submap `submap` at `submap_from_sensor`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopClosure {
    /// The node (scan) that closes the loop.
    pub node: usize,
    /// The finished submap it was matched against (index into [`crate::SlamOutput::submaps`]).
    pub submap: usize,
    /// The submap's anchor node (the other end of the pose-graph edge).
    pub anchor: usize,
    /// The node's pose in the submap frame.
    pub submap_from_sensor: Pose2,
    /// Branch-and-bound score (mean probability of the points).
    pub score: f64,
    /// Where the candidate came from.
    pub source: LoopSource,
    /// The index of the pose-graph edge.
    pub edge: usize,
}

/// A candidate pair to verify.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    submap: usize,
    initial: Pose2,
    window: SearchWindow,
    source: LoopSource,
}

/// Counters of the loop search.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LoopStats {
    /// Node–submap pairs searched.
    pub candidates: usize,
    /// Of which from place recognition.
    pub place_recognition_candidates: usize,
    /// Pairs whose best pose reached the minimum score.
    pub matched: usize,
    /// Matches refused because the refinement moved too far.
    pub refinement_rejected: usize,
    /// Matches refused as ambiguous in rotation.
    pub ambiguous_rejected: usize,
    /// Node–submap pairs searched by the global search (also counted in `candidates`).
    pub global_candidates: usize,
}

/// The loop closer's state: polar-context descriptions of the nodes.
#[derive(Debug)]
pub(crate) struct LoopCloser {
    config: LoopSearchConfig,
    polar: Option<PolarContext>,
    descriptions: Vec<Option<PolarDescription>>,
    thinned: Vec<[f64; 2]>,
    pub stats: LoopStats,
}

impl LoopCloser {
    pub fn new(config: LoopSearchConfig, max_range_m: f64) -> Result<Self> {
        let polar = if config.place_recognition {
            Some(PolarContext::new(PolarConfig {
                max_range_m: max_range_m.min(20.0),
                ..PolarConfig::default()
            })?)
        } else {
            None
        };
        Ok(Self {
            config,
            polar,
            descriptions: Vec::new(),
            thinned: Vec::new(),
            stats: LoopStats::default(),
        })
    }

    /// Describes node `node`'s scan for place recognition (call for every node, in order).
    pub fn describe(&mut self, node: usize, scan: &Scan2) {
        let d = self.polar.as_ref().and_then(|p| p.describe_scan(scan).ok());
        if self.descriptions.len() <= node {
            self.descriptions.resize(node + 1, None);
        }
        self.descriptions[node] = d;
    }

    /// Searches the finished `submaps` for loops of node `node` at world pose `world_from_node`
    /// (`nodes`: current world poses of all nodes; `node_submap`: the finished submap each node
    /// belongs to, if any; `travel_m`: path since the last accepted loop).
    #[allow(clippy::too_many_arguments)]
    pub fn search(
        &mut self,
        node: usize,
        points: &ScanPoints,
        nodes: &[Pose2],
        node_submap: &[Option<usize>],
        submaps: &[Submap],
        matcher: &MatcherConfig,
        travel_m: f64,
    ) -> Vec<(usize, Pose2, f64, LoopSource)> {
        let Some(&world_from_node) = nodes.get(node) else {
            return Vec::new();
        };
        let candidates =
            self.candidates(node, world_from_node, nodes, node_submap, submaps, travel_m);
        let global = self.config.global.filter(|g| g.due(node, travel_m));
        if candidates.is_empty() && global.is_none() {
            return Vec::new();
        }
        thin(points.points(), self.config.thinning_m, &mut self.thinned);
        let mut out: Vec<_> = candidates
            .into_iter()
            .filter_map(|c| self.verify(&c, points, submaps, matcher))
            .collect();
        if let Some(global) = global.filter(|_| out.is_empty()) {
            let wide =
                self.global_candidates(&global, node, world_from_node, nodes, submaps, travel_m);
            self.stats.global_candidates += wide.len();
            out.extend(
                wide.iter()
                    .filter_map(|c| self.verify(c, points, submaps, matcher)),
            );
        }
        out
    }

    /// Branch and bound over the candidate's window, the ambiguity tests and the Gauss–Newton
    /// refinement: the loop constraint `(submap, submap_from_sensor, score, source)` or `None`.
    fn verify(
        &mut self,
        c: &Candidate,
        points: &ScanPoints,
        submaps: &[Submap],
        matcher: &MatcherConfig,
    ) -> Option<(usize, Pose2, f64, LoopSource)> {
        self.stats.candidates += 1;
        if c.source == LoopSource::PlaceRecognition {
            self.stats.place_recognition_candidates += 1;
        }
        let submap = submaps.get(c.submap)?;
        let m = match_scan(
            submap.precomputed(),
            &self.thinned,
            c.initial,
            &c.window,
            &self.config.correlative,
        )?;
        self.stats.matched += 1;
        if self.rotation_ambiguous(submap, c, &m) || self.translation_ambiguous(submap, &m) {
            self.stats.ambiguous_rejected += 1;
            return None;
        }
        let (refined, _) =
            match_levels(submap.levels(), matcher, points, m.submap_from_sensor, None);
        let jump = (m.submap_from_sensor.inverse() * refined)
            .translation()
            .norm();
        if !refined.is_finite() || jump > self.config.max_refinement_m {
            self.stats.refinement_rejected += 1;
            return None;
        }
        Some((c.submap, refined, m.score, c.source))
    }

    /// The global search's candidates ([`crate::global_search`]): the nearest finished
    /// submaps within the wide window's reach of the node's estimate, each with that window.
    fn global_candidates(
        &self,
        global: &GlobalSearchConfig,
        node: usize,
        world_from_node: Pose2,
        nodes: &[Pose2],
        submaps: &[Submap],
        travel_m: f64,
    ) -> Vec<Candidate> {
        let window = SearchWindow {
            linear_m: global.linear_window_m(travel_m),
            angular_rad: self.config.angular_window_rad,
        };
        let reach = self.config.search_radius_m + window.linear_m;
        let mut out: Vec<(f64, Candidate)> = submaps
            .iter()
            .enumerate()
            .filter(|(_, s)| {
                s.nodes()
                    .last()
                    .is_some_and(|&last| last + self.config.min_node_gap <= node)
            })
            .filter_map(|(k, s)| {
                let world_from_submap = *nodes.get(s.anchor())?;
                let centre =
                    world_from_submap * nalgebra::Point2::new(s.centre()[0], s.centre()[1]);
                let d = (centre.coords - world_from_node.translation()).norm();
                (d <= reach).then_some((
                    d,
                    Candidate {
                        submap: k,
                        initial: world_from_submap.inverse() * world_from_node,
                        window,
                        source: LoopSource::Global,
                    },
                ))
            })
            .collect();
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.into_iter()
            .take(global.max_candidates)
            .map(|(_, c)| c)
            .collect()
    }

    /// Whether a pose at least `ambiguity_min_angle_rad` away in rotation scores nearly as
    /// well as the match `m` (`ambiguity_ratio` of its score): two more branch-and-bound
    /// searches, over the headings above and below the match out to the window's width, with
    /// that share of the score as their minimum (so they prune early when nothing comes close).
    fn rotation_ambiguous(
        &self,
        submap: &Submap,
        c: &Candidate,
        m: &crate::correlative::CorrelativeMatch,
    ) -> bool {
        let Some(ratio) = self.config.ambiguity_ratio else {
            return false;
        };
        let band = self.config.ambiguity_min_angle_rad;
        let half = (c.window.angular_rad - band) / 2.0;
        if half <= 0.0 {
            return false;
        }
        let theta = m.submap_from_sensor.theta();
        [1.0, -1.0].into_iter().any(|sign| {
            let initial = Pose2::new(c.initial.x(), c.initial.y(), theta + sign * (band + half));
            let window = SearchWindow {
                linear_m: c.window.linear_m,
                angular_rad: half,
            };
            self.matches(submap, initial, &window, ratio * m.score)
        })
    }

    /// Whether branch and bound finds a pose within `window` around `initial` that scores at
    /// least `min_score`.
    fn matches(
        &self,
        submap: &Submap,
        initial: Pose2,
        window: &SearchWindow,
        min_score: f64,
    ) -> bool {
        let config = crate::correlative::CorrelativeConfig {
            min_score,
            ..self.config.correlative
        };
        match_scan(
            submap.precomputed(),
            &self.thinned,
            initial,
            window,
            &config,
        )
        .is_some()
    }

    /// Whether a pose at least `ambiguity_min_shift_m` away from the match `m` (at its
    /// heading, ± the rotation band) scores nearly as well: eight more branch-and-bound
    /// searches over squares of that half-width around the match's, with `ambiguity_ratio` of
    /// its score as their minimum. A corridor without features along it is such a place.
    fn translation_ambiguous(
        &self,
        submap: &Submap,
        m: &crate::correlative::CorrelativeMatch,
    ) -> bool {
        let (Some(ratio), Some(shift)) = (
            self.config.ambiguity_ratio,
            self.config.ambiguity_min_shift_m,
        ) else {
            return false;
        };
        let window = SearchWindow {
            linear_m: shift,
            angular_rad: self.config.ambiguity_min_angle_rad,
        };
        let at = m.submap_from_sensor;
        (-1..=1)
            .flat_map(|i| (-1..=1).map(move |j| (i, j)))
            .filter(|&ij| ij != (0, 0))
            .any(|(i, j)| {
                let offset = 2.0 * shift;
                let initial = Pose2::new(
                    at.x() + f64::from(i) * offset,
                    at.y() + f64::from(j) * offset,
                    at.theta(),
                );
                self.matches(submap, initial, &window, ratio * m.score)
            })
    }

    fn candidates(
        &self,
        node: usize,
        world_from_node: Pose2,
        nodes: &[Pose2],
        node_submap: &[Option<usize>],
        submaps: &[Submap],
        travel_m: f64,
    ) -> Vec<Candidate> {
        let c = &self.config;
        let growth = c.radius_growth * travel_m;
        let radius = c.search_radius_m + growth;
        let window = SearchWindow {
            linear_m: (c.linear_window_m + growth).min(c.max_linear_window_m),
            angular_rad: c.angular_window_rad,
        };
        let recent = |s: &Submap| {
            s.nodes()
                .last()
                .is_none_or(|&last| last + c.min_node_gap > node)
        };
        let mut out = Vec::new();
        for (k, s) in submaps.iter().enumerate() {
            let Some(&world_from_submap) = nodes.get(s.anchor()) else {
                continue;
            };
            if recent(s) {
                continue;
            }
            let centre = world_from_submap * nalgebra::Point2::new(s.centre()[0], s.centre()[1]);
            let d = (centre.coords - world_from_node.translation()).norm();
            if d <= radius {
                out.push((
                    d,
                    Candidate {
                        submap: k,
                        initial: world_from_submap.inverse() * world_from_node,
                        window,
                        source: LoopSource::Nearby,
                    },
                ));
            }
        }
        // The nearest submaps first, at most `max_candidates` of them.
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut out: Vec<Candidate> = out
            .into_iter()
            .take(c.max_candidates)
            .map(|(_, candidate)| candidate)
            .collect();
        if let Some(pr) = self.place_recognition(node, nodes, node_submap, submaps) {
            if !out.iter().any(|o| o.submap == pr.submap) {
                out.push(pr);
            }
        }
        out
    }

    /// The best place-recognition match among nodes of finished submaps, if close enough.
    fn place_recognition(
        &self,
        node: usize,
        nodes: &[Pose2],
        node_submap: &[Option<usize>],
        submaps: &[Submap],
    ) -> Option<Candidate> {
        let c = &self.config;
        let query = self.descriptions.get(node)?.as_ref()?;
        let limit = node.checked_sub(c.min_node_gap)?;
        // Ring keys first (cheap, heading-free), then the exact distance of the 5 nearest.
        let mut best: Vec<(f64, usize)> = Vec::with_capacity(6);
        for (j, d) in self.descriptions.iter().enumerate().take(limit + 1) {
            let (Some(d), Some(Some(_))) = (d, node_submap.get(j)) else {
                continue;
            };
            let k: f64 = query
                .ring_key()
                .iter()
                .zip(d.ring_key())
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            if best.len() < 5 || k < best[best.len() - 1].0 {
                let at = best.partition_point(|b| b.0 <= k);
                best.insert(at, (k, j));
                best.truncate(5);
            }
        }
        let (distance, j) = best
            .iter()
            .filter_map(|&(_, j)| Some((query.distance(self.descriptions[j].as_ref()?).0, j)))
            .min_by(|a, b| a.0.total_cmp(&b.0))?;
        if distance > c.place_recognition_max_distance {
            return None;
        }
        let submap = (*node_submap.get(j)?)?;
        let world_from_submap = *nodes.get(submaps.get(submap)?.anchor())?;
        Some(Candidate {
            submap,
            initial: world_from_submap.inverse() * *nodes.get(j)?,
            window: SearchWindow {
                linear_m: c.place_recognition_window_m,
                angular_rad: std::f64::consts::PI,
            },
            source: LoopSource::PlaceRecognition,
        })
    }
}

/// Keeps one point per `spacing` metres along the scan (points in scan order).
fn thin(points: &[[f64; 2]], spacing: f64, out: &mut Vec<[f64; 2]>) {
    out.clear();
    let s2 = spacing * spacing;
    for p in points {
        match out.last() {
            Some(q) if (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) < s2 => {}
            _ => out.push(*p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::submap::ActiveSubmap;
    use raypath_reflectivity::MapConfig;

    /// A frozen submap of one scan at the origin of a room whose walls are `walls` (end
    /// points every 2 cm).
    fn room_submap(walls: &[([f64; 2], [f64; 2])]) -> (Submap, Vec<[f64; 2]>) {
        let mut points = ScanPoints::new();
        let mut raw = Vec::new();
        for (p, q) in walls {
            let n = ((q[0] - p[0]).hypot(q[1] - p[1]) / 0.02) as usize;
            for k in 0..=n {
                let t = k as f64 / n as f64;
                let v = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
                points.push(v, f64::NAN);
                raw.push(v);
            }
        }
        let config = MapConfig {
            size_m: 20.0,
            ..MapConfig::default()
        };
        let mut active = ActiveSubmap::new(&config, 0, Pose2::identity(), 0.0).unwrap();
        for _ in 0..5 {
            active.map.update(&Pose2::identity(), &points);
        }
        (active.freeze(7).unwrap(), raw)
    }

    /// Whether the loop closer calls the match of the room's own scan ambiguous: (in
    /// rotation, in translation).
    fn ambiguous(walls: &[([f64; 2], [f64; 2])]) -> (bool, bool) {
        let (submap, raw) = room_submap(walls);
        let config = LoopSearchConfig::default();
        let mut closer = LoopCloser::new(config, 30.0).unwrap();
        thin(&raw, config.thinning_m, &mut closer.thinned);
        let candidate = Candidate {
            submap: 0,
            initial: Pose2::new(0.1, -0.1, 0.05),
            window: SearchWindow {
                linear_m: 0.5,
                angular_rad: config.angular_window_rad,
            },
            source: LoopSource::Nearby,
        };
        let m = match_scan(
            submap.precomputed(),
            &closer.thinned,
            candidate.initial,
            &candidate.window,
            &config.correlative,
        )
        .expect("the room's own scan matches");
        assert!(m.submap_from_sensor.translation().norm() < 0.06);
        (
            closer.rotation_ambiguous(&submap, &candidate, &m),
            closer.translation_ambiguous(&submap, &m),
        )
    }

    #[test]
    fn a_round_room_is_ambiguous_in_rotation_a_corridor_in_translation_a_room_with_a_pillar_in_neither()
     {
        let polygon = |n: usize, r: f64| -> Vec<([f64; 2], [f64; 2])> {
            (0..n)
                .map(|k| {
                    let a = |k: usize| k as f64 * std::f64::consts::TAU / n as f64;
                    (
                        [r * a(k).cos(), r * a(k).sin()],
                        [r * a(k + 1).cos(), r * a(k + 1).sin()],
                    )
                })
                .collect()
        };
        // A 90-gon of radius 4 m looks the same every 4°.
        assert_eq!(ambiguous(&polygon(90, 4.0)), (true, false));
        // A featureless corridor, 16 m long and 2 m wide, looks the same along its length.
        let corridor = [([-8.0, -1.0], [8.0, -1.0]), ([-8.0, 1.0], [8.0, 1.0])];
        assert!(ambiguous(&corridor).1);
        // A 6 m × 4 m room with a pillar off the centre.
        let mut room = vec![
            ([-3.0, -2.0], [3.0, -2.0]),
            ([3.0, -2.0], [3.0, 2.0]),
            ([3.0, 2.0], [-3.0, 2.0]),
            ([-3.0, 2.0], [-3.0, -2.0]),
        ];
        room.extend([
            ([1.0, 0.5], [1.6, 0.5]),
            ([1.6, 0.5], [1.6, 1.0]),
            ([1.6, 1.0], [1.0, 1.0]),
            ([1.0, 1.0], [1.0, 0.5]),
        ]);
        assert_eq!(ambiguous(&room), (false, false));
    }

    /// A 6 m × 4 m room with a pillar off the centre.
    fn room_with_pillar() -> Vec<([f64; 2], [f64; 2])> {
        vec![
            ([-3.0, -2.0], [3.0, -2.0]),
            ([3.0, -2.0], [3.0, 2.0]),
            ([3.0, 2.0], [-3.0, 2.0]),
            ([-3.0, 2.0], [-3.0, -2.0]),
            ([1.0, 0.5], [1.6, 0.5]),
            ([1.6, 0.5], [1.6, 1.0]),
            ([1.6, 1.0], [1.0, 1.0]),
            ([1.0, 1.0], [1.0, 0.5]),
        ]
    }

    /// Searches the room's submap (anchor node 0 at the origin, finished long ago) for node
    /// 200, whose estimate is `estimate`, after `travel_m` without a loop closure; the scan is
    /// `walls` seen from the origin.
    fn search_room(
        config: LoopSearchConfig,
        walls: &[([f64; 2], [f64; 2])],
        estimate: Pose2,
        travel_m: f64,
    ) -> Vec<(usize, Pose2, f64, LoopSource)> {
        let (mut submap, _) = room_submap(&room_with_pillar());
        submap.set_nodes_for_test(vec![0, 1]);
        let (_, raw) = room_submap(walls);
        let mut points = ScanPoints::new();
        for p in &raw {
            points.push(*p, f64::NAN);
        }
        let node = 210;
        let mut nodes = vec![Pose2::identity(); node + 1];
        nodes[node] = estimate;
        let mut closer = LoopCloser::new(config, 30.0).unwrap();
        closer.search(
            node,
            &points,
            &nodes,
            &[Some(0), Some(0)],
            &[submap],
            &MatcherConfig::default(),
            travel_m,
        )
    }

    #[test]
    fn the_global_search_closes_a_loop_beyond_the_local_window_and_no_wrong_one() {
        let config = LoopSearchConfig {
            place_recognition: false,
            global: Some(GlobalSearchConfig::default()),
            ..LoopSearchConfig::default()
        };
        // The node sees the room from its origin, but its estimate drifted 8 m and 6°: beyond
        // the local window (5 m at most), within the global one (0.06 × 200 m = 12 m).
        let estimate = Pose2::new(6.0, -5.3, 0.1);
        let local_only = LoopSearchConfig {
            global: None,
            ..config
        };
        assert!(search_room(local_only, &room_with_pillar(), estimate, 200.0).is_empty());
        let found = search_room(config, &room_with_pillar(), estimate, 200.0);
        assert_eq!(found.len(), 1, "{found:?}");
        let (submap, pose, score, source) = found[0];
        assert_eq!((submap, source), (0, LoopSource::Global));
        assert!(score >= config.correlative.min_score);
        assert!(
            pose.translation().norm() < 0.05 && pose.theta().abs() < 0.01,
            "{pose:?}"
        );
        // Too little path since the last loop: no global search.
        assert!(search_room(config, &room_with_pillar(), estimate, 20.0).is_empty());
        // Another place (a featureless corridor) is not matched into the room.
        let corridor = [([-8.0, -1.0], [8.0, -1.0]), ([-8.0, 1.0], [8.0, 1.0])];
        assert!(search_room(config, &corridor, estimate, 200.0).is_empty());
    }

    #[test]
    fn thinning_keeps_one_point_per_spacing() {
        let pts: Vec<[f64; 2]> = (0..100).map(|i| [i as f64 * 0.01, 0.0]).collect();
        let mut out = Vec::new();
        thin(&pts, 0.1, &mut out);
        assert_eq!(out.len(), 10);
        assert!(out.windows(2).all(|w| (w[1][0] - w[0][0]) >= 0.1 - 1e-12));
    }
}
