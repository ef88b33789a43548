//! A small tf tree: frames with one parent each, static and timestamped transforms, lookups
//! of `target_from_source` at a time (linear in position, slerp in rotation).

use std::collections::HashMap;

use raypath_geometry::Pose3;

use super::msgs::Transform;
use crate::sequence::interpolate;

/// A pose track may be held this many seconds beyond its first or last sample.
pub const HOLD_S: f64 = 0.1;

/// Timestamped poses (seconds, strictly increasing once [`Track::finish`]ed).
#[derive(Clone, Debug, Default)]
pub struct Track {
    /// Times in seconds.
    pub times: Vec<f64>,
    /// Poses at the times.
    pub poses: Vec<Pose3>,
}

impl Track {
    /// Adds a sample (any order).
    pub fn push(&mut self, t: f64, pose: Pose3) {
        self.times.push(t);
        self.poses.push(pose);
    }

    /// Sorts by time; of samples with equal times the last one added is kept.
    pub fn finish(&mut self) {
        let mut pairs: Vec<(f64, Pose3)> = self
            .times
            .drain(..)
            .zip(self.poses.drain(..))
            .filter(|(t, _)| t.is_finite())
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (t, p) in pairs {
            if self.times.last() == Some(&t) {
                if let Some(last) = self.poses.last_mut() {
                    *last = p;
                }
            } else {
                self.times.push(t);
                self.poses.push(p);
            }
        }
    }

    /// The pose at `t`: interpolated inside the track, the end pose within [`HOLD_S`] beyond
    /// it (or at any time for a single sample); an error naming the span otherwise.
    pub fn at(&self, t: f64) -> Result<Pose3, String> {
        let (Some(&first), Some(&last)) = (self.times.first(), self.times.last()) else {
            return Err("no samples".into());
        };
        if self.times.len() == 1 {
            return Ok(self.poses[0]);
        }
        if let Some(p) = interpolate(&self.times, &self.poses, t) {
            return Ok(p);
        }
        if t < first && first - t <= HOLD_S {
            return Ok(self.poses[0]);
        }
        if t > last && t - last <= HOLD_S {
            return Ok(self.poses[self.poses.len() - 1]);
        }
        Err(format!(
            "time {t:.6} s is outside the samples from {first:.6} s to {last:.6} s"
        ))
    }
}

#[derive(Clone, Debug)]
struct Edge {
    parent: usize,
    is_static: bool,
    /// `parent_from_child`.
    track: Track,
}

/// Frames and the transforms between them.
#[derive(Clone, Debug, Default)]
pub struct TfTree {
    index: HashMap<String, usize>,
    names: Vec<String>,
    edges: Vec<Option<Edge>>,
    /// Conflicts found while adding transforms (second parents, cycles).
    pub warnings: Vec<String>,
}

impl TfTree {
    fn frame(&mut self, name: &str) -> usize {
        if let Some(&i) = self.index.get(name) {
            return i;
        }
        let i = self.names.len();
        self.index.insert(name.to_string(), i);
        self.names.push(name.to_string());
        self.edges.push(None);
        i
    }

    /// True when the tree knows `frame`.
    pub fn contains(&self, frame: &str) -> bool {
        self.index.contains_key(frame)
    }

    /// True when the tree has no transforms.
    pub fn is_empty(&self) -> bool {
        self.edges.iter().all(Option::is_none)
    }

    /// Adds a transform (from `/tf_static` when `is_static`).
    pub fn add(&mut self, t: &Transform, is_static: bool) {
        if t.parent == t.child {
            return;
        }
        let parent = self.frame(&t.parent);
        let child = self.frame(&t.child);
        let time = t.stamp.secs();
        match &mut self.edges[child] {
            Some(edge) if edge.parent == parent => {
                if is_static {
                    edge.is_static = true;
                    edge.track = Track::default();
                }
                if !edge.is_static || is_static {
                    edge.track.push(time, t.parent_from_child);
                }
            }
            Some(edge) => {
                let msg = format!(
                    "tf: frame {:?} has parents {:?} and {:?}; the transforms from {:?} are \
                     ignored",
                    t.child, self.names[edge.parent], t.parent, t.parent
                );
                if !self.warnings.contains(&msg) {
                    self.warnings.push(msg);
                }
            }
            None => {
                // Refuse an edge that would close a cycle.
                let mut up = Some(parent);
                while let Some(f) = up {
                    if f == child {
                        self.warnings.push(format!(
                            "tf: {:?} → {:?} would close a cycle; ignored",
                            t.parent, t.child
                        ));
                        return;
                    }
                    up = self.edges[f].as_ref().map(|e| e.parent);
                }
                let mut track = Track::default();
                track.push(time, t.parent_from_child);
                self.edges[child] = Some(Edge {
                    parent,
                    is_static,
                    track,
                });
            }
        }
    }

    /// Sorts the transforms in time; call after the last [`TfTree::add`].
    pub fn finish(&mut self) {
        for edge in self.edges.iter_mut().flatten() {
            edge.track.finish();
        }
    }

    fn chain(&self, frame: usize) -> Vec<usize> {
        let mut out = vec![frame];
        let mut f = frame;
        while let Some(edge) = &self.edges[f] {
            f = edge.parent;
            out.push(f);
        }
        out
    }

    /// The root of the tree holding `frame`.
    pub fn root_of(&self, frame: &str) -> Option<&str> {
        let &i = self.index.get(frame)?;
        self.chain(i).last().map(|&r| self.names[r].as_str())
    }

    /// `ancestor_from_frame` along the chain from `chain[0]` up to `chain[upto]`.
    fn up(&self, chain: &[usize], upto: usize, t: f64) -> Result<Pose3, String> {
        let mut pose = Pose3::identity();
        for &f in &chain[..upto] {
            let Some(edge) = &self.edges[f] else {
                return Err(format!("frame {:?} has no parent", self.names[f]));
            };
            let step = if edge.is_static {
                edge.track
                    .poses
                    .last()
                    .copied()
                    .unwrap_or_else(Pose3::identity)
            } else {
                edge.track.at(t).map_err(|e| {
                    format!("tf {} → {}: {e}", self.names[edge.parent], self.names[f])
                })?
            };
            pose = step * pose;
        }
        Ok(pose)
    }

    /// True when both frames are in the tree and connected.
    pub fn connected(&self, a: &str, b: &str) -> bool {
        match (self.index.get(a), self.index.get(b)) {
            (Some(&a), Some(&b)) => self.chain(a).last() == self.chain(b).last(),
            _ => false,
        }
    }

    /// The chains of both frames up to their common ancestor: `(chain_a, steps_a, chain_b,
    /// steps_b)`.
    fn paths(&self, a: usize, b: usize) -> Option<(Vec<usize>, usize, Vec<usize>, usize)> {
        let ca = self.chain(a);
        let cb = self.chain(b);
        let (ia, ib) = ca
            .iter()
            .enumerate()
            .find_map(|(i, f)| cb.iter().position(|g| g == f).map(|j| (i, j)))?;
        Some((ca, ia, cb, ib))
    }

    /// True when the path between the frames has only static transforms.
    pub fn is_static_between(&self, target: &str, source: &str) -> bool {
        let (Some(&a), Some(&b)) = (self.index.get(target), self.index.get(source)) else {
            return false;
        };
        let Some((ca, ia, cb, ib)) = self.paths(a, b) else {
            return false;
        };
        ca[..ia]
            .iter()
            .chain(&cb[..ib])
            .filter_map(|&f| self.edges[f].as_ref())
            .all(|e| e.is_static)
    }

    /// `target_from_source` at time `t`; an error naming the frames when they are not
    /// connected or a transform on the way does not cover `t`.
    pub fn lookup(&self, target: &str, source: &str, t: f64) -> Result<Pose3, String> {
        let known = |f: &str| {
            self.index.get(f).copied().ok_or_else(|| {
                let mut frames = self.names.clone();
                frames.sort();
                format!("tf has no frame {f:?} (frames: {})", frames.join(", "))
            })
        };
        let (a, b) = (known(target)?, known(source)?);
        let Some((ca, ia, cb, ib)) = self.paths(a, b) else {
            let (ca, cb) = (self.chain(a), self.chain(b));
            return Err(format!(
                "tf has no path between {target:?} (tree root {:?}) and {source:?} (tree root \
                 {:?})",
                self.names[ca[ca.len() - 1]],
                self.names[cb[cb.len() - 1]]
            ));
        };
        let ancestor_from_target = self.up(&ca, ia, t)?;
        let ancestor_from_source = self.up(&cb, ib, t)?;
        Ok(ancestor_from_target.inverse() * ancestor_from_source)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::rosbag::msgs::Stamp;

    fn tf(parent: &str, child: &str, t: f64, pose: Pose3) -> Transform {
        Transform {
            stamp: Stamp::from_secs(t).unwrap(),
            parent: parent.into(),
            child: child.into(),
            parent_from_child: pose,
        }
    }

    fn close(a: &Pose3, b: &Pose3) -> bool {
        (a.translation() - b.translation()).norm() < 1e-9
            && a.rotation().angle_to(&b.rotation()) < 1e-9
    }

    #[test]
    fn lookups_compose_and_interpolate() {
        let mut tree = TfTree::default();
        let laser = Pose3::from_xyz_rpy(0.2, 0.0, 0.3, 0.0, 0.0, 0.1);
        tree.add(&tf("base_link", "laser", 0.0, laser), true);
        tree.add(
            &tf(
                "odom",
                "base_link",
                10.0,
                Pose3::from_xyz_rpy(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            ),
            false,
        );
        tree.add(
            &tf(
                "odom",
                "base_link",
                12.0,
                Pose3::from_xyz_rpy(2.0, 0.0, 0.0, 0.0, 0.0, 1.0),
            ),
            false,
        );
        tree.add(
            &tf(
                "map",
                "odom",
                5.0,
                Pose3::from_xyz_rpy(1.0, 1.0, 0.0, 0.0, 0.0, 0.0),
            ),
            false,
        );
        tree.add(
            &tf(
                "base_link",
                "camera",
                0.0,
                Pose3::from_xyz_rpy(0.0, 0.5, 0.0, 0.0, 0.0, 0.0),
            ),
            true,
        );
        tree.finish();
        let odom_from_base = Pose3::from_xyz_rpy(1.0, 0.0, 0.0, 0.0, 0.0, 0.5);
        let got = tree.lookup("odom", "laser", 11.0).unwrap();
        assert!(close(&got, &(odom_from_base * laser)));
        let map = tree.lookup("map", "laser", 11.0).unwrap();
        let map_from_odom = Pose3::from_xyz_rpy(1.0, 1.0, 0.0, 0.0, 0.0, 0.0);
        assert!(close(&map, &(map_from_odom * odom_from_base * laser)));
        // Sibling frames through their common parent; the inverse direction.
        let cam_from_laser = tree.lookup("camera", "laser", 3.0).unwrap();
        assert!(close(
            &cam_from_laser,
            &(Pose3::from_xyz_rpy(0.0, -0.5, 0.0, 0.0, 0.0, 0.0) * laser)
        ));
        let laser_from_odom = tree.lookup("laser", "odom", 11.0).unwrap();
        assert!(close(&laser_from_odom, &got.inverse()));
        assert!(tree.is_static_between("base_link", "laser"));
        assert!(!tree.is_static_between("odom", "laser"));
        assert_eq!(tree.root_of("laser"), Some("map"));
        // Held briefly beyond the samples, an error further out.
        assert!(tree.lookup("odom", "laser", 12.05).is_ok());
        let e = tree.lookup("odom", "laser", 13.0).unwrap_err();
        assert!(
            e.contains("odom → base_link") && e.contains("outside"),
            "{e}"
        );
        let e = tree.lookup("odom", "nowhere", 11.0).unwrap_err();
        assert!(e.contains("no frame \"nowhere\""), "{e}");
    }

    #[test]
    fn disconnected_and_conflicting() {
        let mut tree = TfTree::default();
        tree.add(&tf("a", "b", 0.0, Pose3::identity()), true);
        tree.add(&tf("c", "d", 0.0, Pose3::identity()), true);
        tree.add(&tf("c", "b", 0.0, Pose3::identity()), true);
        tree.add(&tf("b", "a", 0.0, Pose3::identity()), true);
        tree.finish();
        assert_eq!(tree.warnings.len(), 2, "{:?}", tree.warnings);
        let e = tree.lookup("b", "d", 0.0).unwrap_err();
        assert!(e.contains("no path between \"b\""), "{e}");
    }
}
