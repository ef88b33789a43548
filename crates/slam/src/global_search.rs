//! Global loop search: a wide branch-and-bound window for when the local search has found no
//! loop closure over a long stretch of path (Hess et al. 2016, §V: the multi-resolution
//! search makes windows of many metres affordable).
//!
//! The local search (`loops.rs`) looks around the node's estimate within a window of a
//! few metres (at most [`LoopSearchConfig::max_linear_window_m`]). After a long path without a
//! loop closure the estimate may be off by more than that: on the raw `ual-2014-05-23` log the
//! end of the 524 m loop lies about 22 m (and 11°) from its start, and the local window (5 m) never
//! reaches it. The global search then takes the finished submaps within the window's reach of
//! the estimate (nearest first) and searches each with a translation window that grows with
//! the path since the last loop closure ([`GlobalSearchConfig::window_per_travel`]), up to
//! [`GlobalSearchConfig::max_linear_window_m`]. Matches pass the same tests as local ones
//! (minimum score, rotation and translation ambiguity, refinement), since a wider window
//! admits more wrong poses.
//!
//! [`LoopSearchConfig::max_linear_window_m`]: crate::LoopSearchConfig::max_linear_window_m

use crate::error::{Result, SlamError, require_positive};

/// Settings of the global loop search (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalSearchConfig {
    /// The global search runs only after this much path since the last accepted loop closure
    /// (or the start), metres. Default 50 m (ours): below it the local window, which grows
    /// with 2 % of the path, already covers the front-end's drift on the benchmark logs.
    pub min_travel_m: f64,
    /// … from every n-th node (a multiple of [`crate::LoopSearchConfig::every_nodes`] keeps it
    /// on nodes that also search locally). Default 30 (ours: every 10th local search; the
    /// window is wide, so a nearby node finds the same loop, and one wide search costs up to a
    /// few seconds in the cluttered outdoor `ual` submaps).
    pub every_nodes: usize,
    /// Half width of the translation window as a fraction of the path since the last loop
    /// closure. Default 0.06 (ours: on the raw `ual` log the front-end's estimate of the loop's
    /// end is 22 m and 11° off its start after about 500 m, 4–5 % of the path).
    pub window_per_travel: f64,
    /// Upper bound of that half width, metres. Default 30 m (ours: the `ual` offset with
    /// margin; Cartographer's global localisation searches ±50 m, our submaps are smaller).
    pub max_linear_window_m: f64,
    /// At most this many finished submaps (the nearest to the estimate) per global search.
    /// Default 2 (ours: the cost is linear in it).
    pub max_candidates: usize,
}

impl Default for GlobalSearchConfig {
    fn default() -> Self {
        Self {
            min_travel_m: 50.0,
            every_nodes: 30,
            window_per_travel: 0.06,
            max_linear_window_m: 30.0,
            max_candidates: 2,
        }
    }
}

impl GlobalSearchConfig {
    /// Checks the parameters (errors name the field).
    pub fn validate(&self) -> Result<()> {
        require_positive("global.min_travel_m", self.min_travel_m)?;
        require_positive("global.window_per_travel", self.window_per_travel)?;
        require_positive("global.max_linear_window_m", self.max_linear_window_m)?;
        for (name, v) in [
            ("global.every_nodes", self.every_nodes),
            ("global.max_candidates", self.max_candidates),
        ] {
            if v == 0 {
                return Err(SlamError::InvalidParameter {
                    name,
                    reason: "at least 1".into(),
                });
            }
        }
        Ok(())
    }

    /// Whether node `node` runs a global search after `travel_m` of path without a loop
    /// closure.
    pub(crate) fn due(&self, node: usize, travel_m: f64) -> bool {
        travel_m >= self.min_travel_m && node % self.every_nodes == 0
    }

    /// The translation half width after `travel_m` of path without a loop closure.
    pub(crate) fn linear_window_m(&self, travel_m: f64) -> f64 {
        (self.window_per_travel * travel_m).min(self.max_linear_window_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_settings_are_errors_naming_the_field() {
        assert!(GlobalSearchConfig::default().validate().is_ok());
        let bad = [
            GlobalSearchConfig {
                min_travel_m: 0.0,
                ..GlobalSearchConfig::default()
            },
            GlobalSearchConfig {
                window_per_travel: f64::NAN,
                ..GlobalSearchConfig::default()
            },
            GlobalSearchConfig {
                max_candidates: 0,
                ..GlobalSearchConfig::default()
            },
            GlobalSearchConfig {
                every_nodes: 0,
                ..GlobalSearchConfig::default()
            },
        ];
        for b in bad {
            let e = b.validate().unwrap_err().to_string();
            assert!(e.contains("global."), "{e}");
        }
    }

    #[test]
    fn the_window_grows_with_the_path_up_to_its_bound() {
        let c = GlobalSearchConfig::default();
        assert!(!c.due(30, 49.0) && c.due(30, 51.0) && !c.due(31, 100.0));
        assert!((c.linear_window_m(100.0) - 6.0).abs() < 1e-12);
        assert!((c.linear_window_m(1e4) - 30.0).abs() < 1e-12);
    }
}
