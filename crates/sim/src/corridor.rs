//! The 1-D corridor of Schaefer (2020), chapter 8 ("localization in simulation", Sec. 8.5.1):
//! N = 100 voxels with hidden ground-truth map values, a mapping phase that visits every voxel
//! `n` times, and a localization phase with one observation per iteration along the corridor.
//!
//! # Models
//!
//! * **Reflection model (REF)**, eq. (8.3): voxel `i` reflects a ray with probability
//!   `μ_i ~ U(0, 1)`. One measurement of a voxel is one Bernoulli draw `δ ~ Bern(μ_i)`.
//! * **Decay-rate model (DEC)**, eq. (8.4): voxel `i` has the decay rate `λ_i ~ Gamma(1, 1)`
//!   (shape 1, rate 1, i.e. Exp(1)), per metre. One measurement is one ray segment through
//!   the voxel: `t ~ Exp(λ_i)`; `t < 1` is a hit at depth `r = t`, otherwise a miss that
//!   travels `r = 1`.
//!
//! # Decisions the thesis leaves open (recorded here)
//!
//! 1. **Voxel length** 1 m, so a miss travels 1 m and depths are in metres.
//! 2. **A measurement** of a voxel is the draw above. The mapping statistics per voxel are `H_i`
//!    (hits), `M_i` (misses) and `R_i` (total in-voxel distance: `Σ r`). Under REF the in-voxel
//!    distance carries no information; it is recorded as 1 m for a miss and 0.5 m for a hit (the
//!    reflection at the voxel centre) so that `R_i` is defined for both models.
//! 3. **Mapping order**: `n` passes along the corridor, one measurement of every voxel per
//!    pass (pass-major), all from one random stream.
//! 4. **Localization**: the robot starts before voxel 0 and iteration `t = 0 … N − 1` moves it into
//!    voxel `t` and fires once: the observation of iteration `t` is one measurement of voxel `t`;
//!    there are N = 100 iterations. The motion is known (deterministic shift by one voxel);
//!    evaluating pose hypotheses is left to the sensor-model evaluation.
//! 5. **Random streams** (so evaluations can regenerate a run): run `r` of a data set with
//!    seed `S` uses the world seed `w = stream(S, RUN, r)`'s first `u64`;
//!    [`CorridorWorld::sample`]`(w, model)` draws the map from `stream(w, MAP, model)`; the
//!    mapping statistics for `n` visits use `stream(w, MAPPING, n)`, the localization run
//!    `stream(w, LOCALIZATION, 0)` (constants of this module, see [`streams`]).
//!
//! The generated set (`corridor/`) holds a few seeded runs per model for inspection: a JSON
//! file per model with the ground truth, the mapping statistics for several `n` and the
//! localization observations, and one point CSV per run (`x,y,…` with x the voxel centre in
//! metres, y = 0) that `raypath info` reads.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::Rng;
use rand_distr::{Distribution, Exp, Gamma};
use serde::Serialize;

use crate::dataset::{GeneratedSet, Progress};
use crate::error::{Result, SimError};
use crate::out2d;
use crate::rng::stream;

/// Number of voxels of the thesis corridor.
pub const CORRIDOR_VOXELS: usize = 100;

/// Length of a voxel in metres (decision 1).
pub const VOXEL_LENGTH_M: f64 = 1.0;

/// In-voxel distance recorded for a reflection-model hit (decision 2).
pub const REFLECTION_HIT_DEPTH_M: f64 = 0.5;

/// The random-stream domains of the corridor (decision 5).
pub mod streams {
    /// Derives the world seed of run `r` from the data-set seed.
    pub const RUN: u64 = 0x636f_7272_0000_0001;
    /// Draws the ground-truth map from the world seed (index: 0 = REF, 1 = DEC).
    pub const MAP: u64 = 0x636f_7272_0000_0002;
    /// Mapping statistics (index: the number of visits `n`).
    pub const MAPPING: u64 = 0x636f_7272_0000_0003;
    /// Localization observations (index 0).
    pub const LOCALIZATION: u64 = 0x636f_7272_0000_0004;
}

/// The forward sensor model of the corridor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CorridorModel {
    /// Reflection model: map values are reflection probabilities `μ_i ~ U(0, 1)`.
    Reflection,
    /// Decay-rate model: map values are decay rates `λ_i ~ Gamma(1, 1)` per metre.
    DecayRate,
}

impl CorridorModel {
    /// Both models.
    pub const ALL: [CorridorModel; 2] = [CorridorModel::Reflection, CorridorModel::DecayRate];

    /// `reflection` or `decay-rate`.
    pub fn name(self) -> &'static str {
        match self {
            CorridorModel::Reflection => "reflection",
            CorridorModel::DecayRate => "decay-rate",
        }
    }

    fn index(self) -> u64 {
        match self {
            CorridorModel::Reflection => 0,
            CorridorModel::DecayRate => 1,
        }
    }
}

/// One measurement of one voxel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct VoxelObservation {
    /// Whether the voxel reflected the ray (δ = 1).
    pub hit: bool,
    /// Distance the ray travelled inside the voxel in metres (decision 2).
    pub distance_m: f64,
}

/// The mapping statistics of all voxels after `n_visits` measurements of each.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapStatistics {
    /// Measurements per voxel.
    pub n_visits: u32,
    /// `H_i`: hits per voxel.
    pub hits: Vec<u32>,
    /// `M_i`: misses per voxel.
    pub misses: Vec<u32>,
    /// `R_i`: total in-voxel distance per voxel in metres.
    pub distance_m: Vec<f64>,
}

/// A corridor with its hidden ground-truth map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CorridorWorld {
    /// The model the map values belong to.
    pub model: CorridorModel,
    /// Ground truth per voxel: `μ_i` (REF) or `λ_i` in 1/m (DEC).
    pub values: Vec<f64>,
}

impl CorridorWorld {
    /// The thesis corridor (100 voxels) of `model` drawn from the world seed `seed`
    /// (decision 5).
    pub fn sample(seed: u64, model: CorridorModel) -> Self {
        let mut rng = stream(seed, streams::MAP, model.index());
        Self::sample_from(&mut rng, model, CORRIDOR_VOXELS)
    }

    /// A corridor of `voxels` voxels whose values are drawn from `rng`.
    pub fn sample_from<R: Rng + ?Sized>(rng: &mut R, model: CorridorModel, voxels: usize) -> Self {
        let values = match model {
            CorridorModel::Reflection => (0..voxels).map(|_| rng.random::<f64>()).collect(),
            CorridorModel::DecayRate => {
                // Gamma(shape 1, scale 1) = Gamma(1, rate 1); the parameters are valid.
                let gamma = Gamma::new(1.0, 1.0).ok();
                (0..voxels)
                    .map(|_| gamma.map_or(1.0, |g| g.sample(rng)))
                    .collect()
            }
        };
        Self { model, values }
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True for a corridor without voxels.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// One measurement of `voxel` (`None` past the end of the corridor).
    pub fn observation<R: Rng + ?Sized>(
        &self,
        voxel: usize,
        rng: &mut R,
    ) -> Option<VoxelObservation> {
        let value = *self.values.get(voxel)?;
        Some(measure(self.model, value, rng))
    }

    /// The mapping phase: `n_visits` passes along the corridor, one measurement of every voxel
    /// per pass (decision 3).
    pub fn map_statistics<R: Rng + ?Sized>(&self, n_visits: u32, rng: &mut R) -> MapStatistics {
        let n = self.len();
        let mut stats = MapStatistics {
            n_visits,
            hits: vec![0; n],
            misses: vec![0; n],
            distance_m: vec![0.0; n],
        };
        for _ in 0..n_visits {
            for (i, &value) in self.values.iter().enumerate() {
                let obs = measure(self.model, value, rng);
                if let (Some(h), Some(m), Some(r)) = (
                    stats.hits.get_mut(i),
                    stats.misses.get_mut(i),
                    stats.distance_m.get_mut(i),
                ) {
                    if obs.hit {
                        *h += 1;
                    } else {
                        *m += 1;
                    }
                    *r += obs.distance_m;
                }
            }
        }
        stats
    }

    /// The localization phase: the observation of iteration `t` is one measurement of voxel
    /// `t`, for every voxel in order (decision 4).
    pub fn localization_observations<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<VoxelObservation> {
        self.values
            .iter()
            .map(|&value| measure(self.model, value, rng))
            .collect()
    }
}

fn measure<R: Rng + ?Sized>(model: CorridorModel, value: f64, rng: &mut R) -> VoxelObservation {
    match model {
        CorridorModel::Reflection => {
            let hit = rng.random::<f64>() < value;
            VoxelObservation {
                hit,
                distance_m: if hit {
                    REFLECTION_HIT_DEPTH_M
                } else {
                    VOXEL_LENGTH_M
                },
            }
        }
        CorridorModel::DecayRate => {
            let t = Exp::new(value).map_or(f64::INFINITY, |e| e.sample(rng));
            if t < VOXEL_LENGTH_M {
                VoxelObservation {
                    hit: true,
                    distance_m: t,
                }
            } else {
                VoxelObservation {
                    hit: false,
                    distance_m: VOXEL_LENGTH_M,
                }
            }
        }
    }
}

/// Configuration of the generated corridor set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CorridorConfig {
    /// Seeded runs per model.
    pub runs: usize,
    /// The numbers of visits `n` whose mapping statistics are written (thesis: 1, 2, 3, 4,
    /// 5, 10, 20, 50, 100, 200; the set keeps a few for inspection).
    pub n_visits: Vec<u32>,
    /// Voxels per corridor (thesis: 100).
    pub voxels: usize,
}

impl Default for CorridorConfig {
    fn default() -> Self {
        Self {
            runs: 4,
            n_visits: vec![1, 10, 100],
            voxels: CORRIDOR_VOXELS,
        }
    }
}

impl CorridorConfig {
    /// The quick set: the same few runs (they are tiny).
    pub fn quick() -> Self {
        Self::default()
    }
}

/// The world seed of run `run` of a data set generated with `seed` (decision 5).
pub fn run_seed(seed: u64, run: usize) -> u64 {
    stream(seed, streams::RUN, run as u64).random()
}

/// One run as written to JSON.
#[derive(Serialize)]
struct Run {
    run: usize,
    world_seed: u64,
    truth: Vec<f64>,
    mapping: Vec<MapStatistics>,
    localization: Vec<VoxelObservation>,
}

#[derive(Serialize)]
struct RunsFile<'a> {
    generator: &'static str,
    seed: u64,
    model: CorridorModel,
    voxel_length_m: f64,
    config: &'a CorridorConfig,
    runs: Vec<Run>,
}

/// Generates the inspection set: `corridor-<model>.json` and
/// `corridor-<model>-run<r>.csv` for both models.
pub fn generate(
    config: &CorridorConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    if config.runs == 0 || config.voxels == 0 || config.n_visits.is_empty() {
        return Err(SimError::InvalidParameter {
            name: "runs",
            reason: "need at least one run, one voxel and one number of visits".into(),
        });
    }
    out2d::create_dir(out_dir)?;
    let counter = out2d::Counter::new((2 * config.runs) as u64, progress);
    let mut files = Vec::new();
    let mut stats = serde_json::Map::new();
    for model in CorridorModel::ALL {
        let mut runs = Vec::new();
        for r in 0..config.runs {
            let world_seed = run_seed(seed, r);
            let mut map_rng = stream(world_seed, streams::MAP, model.index());
            let world = CorridorWorld::sample_from(&mut map_rng, model, config.voxels);
            let mapping: Vec<MapStatistics> = config
                .n_visits
                .iter()
                .map(|&n| {
                    world.map_statistics(n, &mut stream(world_seed, streams::MAPPING, u64::from(n)))
                })
                .collect();
            let localization =
                world.localization_observations(&mut stream(world_seed, streams::LOCALIZATION, 0));
            let csv_name = format!("corridor-{}-run{r}.csv", model.name());
            out2d::write_file(
                &out_dir.join(&csv_name),
                csv(&world, &mapping, &localization).as_bytes(),
            )?;
            files.push(PathBuf::from(csv_name));
            runs.push(Run {
                run: r,
                world_seed,
                truth: world.values,
                mapping,
                localization,
            });
            counter.tick();
        }
        stats.insert(model.name().into(), model_stats(&runs));
        let json_name = format!("corridor-{}.json", model.name());
        out2d::write_json(
            &out_dir.join(&json_name),
            &RunsFile {
                generator: "raypath-sim corridor",
                seed,
                model,
                voxel_length_m: VOXEL_LENGTH_M,
                config,
                runs,
            },
        )?;
        files.push(PathBuf::from(json_name));
    }
    Ok(GeneratedSet {
        name: "corridor".into(),
        description: "The 1-D corridor of Schaefer 2020 ch. 8 (100 voxels, reflection and \
                      decay-rate ground truth, mapping statistics, localization observations), \
                      a few seeded runs as JSON and point CSV"
            .into(),
        files: out2d::sorted(files),
        stats: serde_json::Value::Object(stats),
    })
}

fn csv(
    world: &CorridorWorld,
    mapping: &[MapStatistics],
    localization: &[VoxelObservation],
) -> String {
    let mut out = String::from("x,y,truth");
    for m in mapping {
        let n = m.n_visits;
        let _ = write!(out, ",hits_n{n},misses_n{n},distance_m_n{n}");
    }
    out.push_str(",obs_hit,obs_distance_m\n");
    for (i, value) in world.values.iter().enumerate() {
        let _ = write!(out, "{},0,{value}", (i as f64 + 0.5) * VOXEL_LENGTH_M);
        for m in mapping {
            let (h, mi, r) = (
                m.hits.get(i).copied().unwrap_or(0),
                m.misses.get(i).copied().unwrap_or(0),
                m.distance_m.get(i).copied().unwrap_or(0.0),
            );
            let _ = write!(out, ",{h},{mi},{r}");
        }
        let obs = localization.get(i);
        let _ = writeln!(
            out,
            ",{},{}",
            u8::from(obs.is_some_and(|o| o.hit)),
            obs.map_or(0.0, |o| o.distance_m)
        );
    }
    out
}

fn model_stats(runs: &[Run]) -> serde_json::Value {
    let values: Vec<f64> = runs.iter().flat_map(|r| r.truth.iter().copied()).collect();
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    let hit_fraction: Vec<serde_json::Value> = runs
        .first()
        .map(|r| {
            r.mapping
                .iter()
                .map(|m| {
                    let h: u64 = runs
                        .iter()
                        .filter_map(|r| r.mapping.iter().find(|x| x.n_visits == m.n_visits))
                        .flat_map(|x| x.hits.iter().map(|&h| u64::from(h)))
                        .sum();
                    let total = (m.n_visits as usize * values.len()).max(1) as f64;
                    serde_json::json!({ "n_visits": m.n_visits, "hit_fraction": h as f64 / total })
                })
                .collect()
        })
        .unwrap_or_default();
    serde_json::json!({
        "runs": runs.len(),
        "voxels_per_run": runs.first().map_or(0, |r| r.truth.len()),
        "truth_mean": mean,
        "truth_variance": var,
        "mapping": hit_fraction,
    })
}
