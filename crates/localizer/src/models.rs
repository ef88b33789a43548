//! The two model traits the filter is generic over.
//!
//! ## Design
//!
//! Both traits are **generic** (statically dispatched), not object-safe: the motion model
//! takes `&mut impl Rng`, and [`crate::ParticleFilter::predict`] and
//! [`crate::ParticleFilter::update`] are monomorphized for the concrete model, so the
//! per-particle call inlines into the rayon loop. A caller that needs run-time selection
//! (the CLI's `--model` switch) wraps the models in an enum and implements the trait for the
//! enum; one `match` per particle is far cheaper than the likelihood of a scan.
//!
//! Both traits require `Sync` because the filter shares the model between rayon threads;
//! the filter additionally needs the observation and control types to be `Sync`.
//!
//! The crate implements [`MotionModel`] in [`crate::motion`]; measurement models come from
//! elsewhere (raypath-sensor-models' scan likelihoods, pole landmarks) or from the user, as
//! in the example on the crate's front page.

use rand::Rng;

/// A measurement model p(z | x): the log-likelihood of an observation given a particle's
/// state `S` ([`raypath_geometry::Pose2`] or [`raypath_geometry::Pose3`]).
pub trait MeasurementModel<S>: Sync {
    /// What is observed (a scan, a set of landmarks, …).
    type Observation: ?Sized;

    /// ln p(z | x) in natural-log space. `−∞` is allowed (impossible observation); NaN never
    /// (the filter reports it as [`crate::LocalizerError::NanLikelihood`]). Only differences
    /// between particles matter, so any constant offset may be dropped.
    fn log_likelihood(&self, state: &S, observation: &Self::Observation) -> f64;
}

/// A motion model p(x' | x, u) that can be sampled: the prediction step of the filter.
pub trait MotionModel<S>: Sync {
    /// The control or odometry input u.
    type Control;

    /// Draws x' ~ p(x' | x = `state`, u = `control`) using `rng`.
    fn sample(&self, state: &S, control: &Self::Control, rng: &mut impl Rng) -> S;
}

impl<S, M: MeasurementModel<S> + ?Sized> MeasurementModel<S> for &M {
    type Observation = M::Observation;

    fn log_likelihood(&self, state: &S, observation: &Self::Observation) -> f64 {
        (**self).log_likelihood(state, observation)
    }
}

impl<S, M: MotionModel<S>> MotionModel<S> for &M {
    type Control = M::Control;

    fn sample(&self, state: &S, control: &Self::Control, rng: &mut impl Rng) -> S {
        (**self).sample(state, control, rng)
    }
}
