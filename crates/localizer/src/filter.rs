//! The particle filter (Monte-Carlo localization, Thrun et al. 2005, Table 8.2).
//!
//! One cycle is
//!
//! 1. **predict** — every particle moves by a sample of the motion model,
//!    xᵢ ← x'ᵢ ~ p(x' | xᵢ, u) (in parallel, one random stream per particle);
//! 2. **update** — every log-weight grows by the measurement log-likelihood,
//!    lᵢ ← lᵢ + ln p(z | xᵢ) (in parallel), then log-sum-exp normalization
//!    ([`crate::weights`]);
//! 3. **resample** when the effective sample size falls below a fraction of the particle count,
//!    ESS / N < [`FilterConfig::resample_ess_ratio`] (default 0.5 as in the polex implementation of
//!    Schaefer 2020, ch. 12; the thesis's `ESS < 0.5` never holds for normalized weights, ESS ≥ 1,
//!    and is read as ESS / N), by low-variance resampling ([`crate::resample`]) or, with
//!    [`FilterConfig::kld`], by KLD-sampling ([`crate::kld`]), which also adapts N.
//!
//! ## Determinism
//!
//! Every random operation takes the next number of an operation counter; particle `i` of
//! operation `k` draws from [`ParticleRng::stream`]`(seed, k, i)`. Weighting is a pure
//! function per particle; normalization, resampling and estimation run sequentially. So the
//! same seed and the same sequence of calls give bit-identical particles on any number of
//! threads (run the filter inside a `rayon::ThreadPool::install` to choose the threads).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{LocalizerError, require_open_interval};
use crate::estimate::{Estimator, estimate};
use crate::init::Initializer;
use crate::kld::{KldConfig, KldReport, KldScratch, kld_resample};
use crate::models::{MeasurementModel, MotionModel};
use crate::resample::systematic_resample;
use crate::rng::{Domain, ParticleRng};
use crate::state::FilterState;
use crate::weights::{effective_sample_size, normalize_log_weights};
use rand::Rng;

/// Filter parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterConfig {
    /// Resample when ESS / N falls below this ratio, in (0, 1]. Default 0.5 (Schaefer 2020,
    /// ch. 12). 1.0 resamples after every update that leaves the weights non-uniform.
    pub resample_ess_ratio: f64,
    /// KLD-sampling; `None` (default) keeps the particle count fixed. It acts whenever the
    /// filter resamples; set `resample_ess_ratio` to 1 to resample (and so adapt N) after
    /// every update, as AMCL does.
    pub kld: Option<KldConfig>,
    /// Fewest particles per rayon task (amortizes scheduling for cheap models). Default 64.
    pub min_particles_per_task: usize,
}

impl Default for FilterConfig {
    fn default() -> Self {
        Self {
            resample_ess_ratio: 0.5,
            kld: None,
            min_particles_per_task: 64,
        }
    }
}

impl FilterConfig {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), LocalizerError> {
        require_open_interval(
            "resample_ess_ratio",
            self.resample_ess_ratio,
            0.0,
            1.0 + 1e-12,
        )?;
        if let Some(kld) = &self.kld {
            kld.validate()?;
        }
        Ok(())
    }
}

/// What one measurement update did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UpdateReport {
    /// ln Σᵢ wᵢ p(z | xᵢ): the log of the filter's estimate of the observation's marginal
    /// likelihood (useful to detect divergence: it drops when no particle explains z).
    pub log_normalizer: f64,
    /// The largest log-likelihood over the particles.
    pub max_log_likelihood: f64,
    /// Particles with log-likelihood −∞.
    pub impossible_particles: usize,
    /// The effective sample size after the update.
    pub ess: f64,
}

/// What one resampling did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResampleReport {
    /// The effective sample size before resampling.
    pub ess_before: f64,
    /// The particle count before resampling.
    pub particles_before: usize,
    /// The particle count after resampling.
    pub particles_after: usize,
    /// KLD-sampling details, when enabled.
    pub kld: Option<KldReport>,
}

/// What one [`ParticleFilter::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// The measurement update.
    pub update: UpdateReport,
    /// The resampling, if the ESS threshold triggered one.
    pub resample: Option<ResampleReport>,
}

/// A particle filter over states `S` ([`raypath_geometry::Pose2`] or
/// [`raypath_geometry::Pose3`]); see the module docs.
#[derive(Clone, Debug)]
pub struct ParticleFilter<S> {
    config: FilterConfig,
    seed: u64,
    operation: u64,
    states: Vec<S>,
    /// Normalized: Σ e^{lᵢ} = 1.
    log_weights: Vec<f64>,
    scratch_log: Vec<f64>,
    scratch_weights: Vec<f64>,
    scratch_states: Vec<S>,
    scratch_indices: Vec<usize>,
    kld_scratch: KldScratch,
}

impl<S: FilterState> ParticleFilter<S> {
    /// A filter over the given particles with uniform weights.
    pub fn new(states: Vec<S>, config: FilterConfig, seed: u64) -> Result<Self, LocalizerError> {
        config.validate()?;
        if states.is_empty() {
            return Err(LocalizerError::Empty {
                what: "particle set",
            });
        }
        if let Some(index) = states.iter().position(|s| !s.is_finite()) {
            return Err(LocalizerError::NonFinite {
                what: "particle",
                index,
            });
        }
        let n = states.len();
        let mut filter = Self::empty(config, seed);
        filter.states = states;
        filter.log_weights = vec![-(n as f64).ln(); n];
        Ok(filter)
    }

    fn empty(config: FilterConfig, seed: u64) -> Self {
        Self {
            config,
            seed,
            operation: 0,
            states: Vec::new(),
            log_weights: Vec::new(),
            scratch_log: Vec::new(),
            scratch_weights: Vec::new(),
            scratch_states: Vec::new(),
            scratch_indices: Vec::new(),
            kld_scratch: KldScratch::default(),
        }
    }

    /// A filter with `particles` particles drawn from `initializer` (per-particle streams,
    /// so the draw does not depend on the thread count).
    pub fn from_initializer<I: Initializer<S>>(
        initializer: &I,
        particles: usize,
        config: FilterConfig,
        seed: u64,
    ) -> Result<Self, LocalizerError> {
        config.validate()?;
        let mut filter = Self::empty(config, seed);
        filter.reinitialize(initializer, particles)?;
        Ok(filter)
    }

    /// Replaces the particles by `particles` fresh draws from `initializer` with uniform
    /// weights (e.g. after divergence).
    pub fn reinitialize<I: Initializer<S>>(
        &mut self,
        initializer: &I,
        particles: usize,
    ) -> Result<(), LocalizerError> {
        initializer.validate()?;
        if particles == 0 {
            return Err(LocalizerError::Empty {
                what: "particle set",
            });
        }
        let (seed, op) = (self.seed, self.next_operation());
        let mut states = Vec::with_capacity(particles);
        (0..particles)
            .into_par_iter()
            .with_min_len(self.config.min_particles_per_task.max(1))
            .map(|i| {
                let mut rng = ParticleRng::for_item(seed, Domain::Init, op, i as u64);
                initializer.sample(&mut rng)
            })
            .collect_into_vec(&mut states);
        if let Some(index) = states.iter().position(|s| !s.is_finite()) {
            return Err(LocalizerError::NonFinite {
                what: "initial particle",
                index,
            });
        }
        self.states = states;
        self.log_weights = vec![-(particles as f64).ln(); particles];
        Ok(())
    }

    fn next_operation(&mut self) -> u64 {
        self.operation += 1;
        self.operation
    }

    fn min_len(&self) -> usize {
        self.config.min_particles_per_task.max(1)
    }

    /// The prediction step: every particle moves by a sample of `model` given `control`.
    pub fn predict<M>(&mut self, model: &M, control: &M::Control)
    where
        M: MotionModel<S>,
        M::Control: Sync,
    {
        let (seed, op, min_len) = (self.seed, self.next_operation(), self.min_len());
        self.states
            .par_iter_mut()
            .with_min_len(min_len)
            .enumerate()
            .for_each(|(i, state)| {
                let mut rng = ParticleRng::for_item(seed, Domain::Predict, op, i as u64);
                *state = model.sample(state, control, &mut rng);
            });
    }

    /// The measurement update: multiplies every weight by p(z | xᵢ) (adds the
    /// log-likelihood) and normalizes.
    ///
    /// Errors (weights left as they were): [`LocalizerError::NanLikelihood`] when the model
    /// returns NaN, [`LocalizerError::AllParticlesImpossible`] when every particle gets −∞,
    /// [`LocalizerError::NonFinite`] for +∞.
    pub fn update<M>(
        &mut self,
        model: &M,
        observation: &M::Observation,
    ) -> Result<UpdateReport, LocalizerError>
    where
        M: MeasurementModel<S>,
        M::Observation: Sync,
    {
        let min_len = self.min_len();
        self.states
            .par_iter()
            .with_min_len(min_len)
            .map(|state| model.log_likelihood(state, observation))
            .collect_into_vec(&mut self.scratch_log);
        if let Some(particle) = self.scratch_log.iter().position(|l| l.is_nan()) {
            return Err(LocalizerError::NanLikelihood { particle });
        }
        let max_log_likelihood = self
            .scratch_log
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let impossible_particles = self
            .scratch_log
            .iter()
            .filter(|&&l| l == f64::NEG_INFINITY)
            .count();
        for (l, w) in self.scratch_log.iter_mut().zip(&self.log_weights) {
            *l += *w;
        }
        let log_normalizer = normalize_log_weights(&mut self.scratch_log)?;
        std::mem::swap(&mut self.log_weights, &mut self.scratch_log);
        Ok(UpdateReport {
            log_normalizer,
            max_log_likelihood,
            impossible_particles,
            ess: self.ess(),
        })
    }

    /// Resamples now (systematic, or KLD-sampling when configured); weights become uniform.
    pub fn resample(&mut self) -> ResampleReport {
        let ess_before = self.ess();
        let particles_before = self.states.len();
        let op = self.next_operation();
        let mut rng = ParticleRng::for_item(self.seed, Domain::Resample, op, 0);
        self.scratch_weights.clear();
        self.scratch_weights
            .extend(self.log_weights.iter().map(|l| l.exp()));
        let kld = match &self.config.kld {
            Some(kld) => Some(kld_resample(
                &self.states,
                &self.scratch_weights,
                kld,
                &mut rng,
                &mut self.scratch_states,
                &mut self.kld_scratch,
            )),
            None => {
                systematic_resample(
                    &self.scratch_weights,
                    particles_before,
                    rng.random(),
                    &mut self.scratch_indices,
                );
                self.scratch_states.clear();
                self.scratch_states.extend(
                    self.scratch_indices
                        .iter()
                        .filter_map(|&i| self.states.get(i).copied()),
                );
                None
            }
        };
        // Normalized weights always have a positive sum, so the output is never empty; guard
        // anyway rather than lose the particle set.
        if !self.scratch_states.is_empty() {
            std::mem::swap(&mut self.states, &mut self.scratch_states);
            let n = self.states.len();
            self.log_weights.clear();
            self.log_weights.resize(n, -(n as f64).ln());
        }
        ResampleReport {
            ess_before,
            particles_before,
            particles_after: self.states.len(),
            kld,
        }
    }

    /// Resamples when ESS / N < [`FilterConfig::resample_ess_ratio`].
    pub fn resample_if_needed(&mut self) -> Option<ResampleReport> {
        (self.ess_ratio() < self.config.resample_ess_ratio).then(|| self.resample())
    }

    /// One full cycle: predict, update, resample if needed.
    pub fn step<Mo, Me>(
        &mut self,
        motion: &Mo,
        control: &Mo::Control,
        measurement: &Me,
        observation: &Me::Observation,
    ) -> Result<StepReport, LocalizerError>
    where
        Mo: MotionModel<S>,
        Mo::Control: Sync,
        Me: MeasurementModel<S>,
        Me::Observation: Sync,
    {
        self.predict(motion, control);
        let update = self.update(measurement, observation)?;
        let resample = self.resample_if_needed();
        Ok(StepReport { update, resample })
    }

    /// The point estimate (see [`Estimator`]).
    pub fn estimate(&self, estimator: Estimator) -> S {
        let mut order = Vec::new();
        estimate(&self.states, &self.log_weights, estimator, &mut order)
            // The set is never empty (constructors reject it, resampling keeps the old set
            // rather than an empty one); identity only satisfies the types.
            .unwrap_or_else(S::identity)
    }

    /// The particles' states.
    pub fn states(&self) -> &[S] {
        &self.states
    }

    /// The normalized log-weights (Σ e^{lᵢ} = 1).
    pub fn log_weights(&self) -> &[f64] {
        &self.log_weights
    }

    /// The normalized weights wᵢ = e^{lᵢ}.
    pub fn weights(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        self.log_weights.iter().map(|l| l.exp())
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Always false: a filter holds at least one particle.
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// The effective sample size 1 / Σ wᵢ².
    pub fn ess(&self) -> f64 {
        effective_sample_size(&self.log_weights)
    }

    /// ESS / N in (0, 1].
    pub fn ess_ratio(&self) -> f64 {
        self.ess() / self.states.len().max(1) as f64
    }

    /// The configuration.
    pub fn config(&self) -> &FilterConfig {
        &self.config
    }

    /// Replaces the configuration (validated first).
    pub fn set_config(&mut self, config: FilterConfig) -> Result<(), LocalizerError> {
        config.validate()?;
        self.config = config;
        Ok(())
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The number of random operations so far (predictions, resamplings, initializations).
    pub fn operations(&self) -> u64 {
        self.operation
    }
}
