//! The serialisable record of a run: [`AlgorithmConfig`] (every algorithm with its
//! hyper-parameters) and [`RunConfig`] (+ initial θ, seed, stopping rule). JSON via serde;
//! [`crate::algo::replay`] rebuilds the algorithm from it and reproduces the run bit for bit.

use super::adam::{Adam, AdamOptimizerConfig};
use super::as_printed::{PrintedAlgorithm4Config, printed_algorithm_4, printed_algorithm_5};
use super::bc::{Bc, BcConfig};
use super::dagger::{Dagger, DaggerConfig};
use super::forward_training::{ForwardTraining, ForwardTrainingConfig};
use super::o2nc::{O2nc, O2ncConfig};
use super::rmsprop::{RmsProp, RmsPropOptimizerConfig};
use super::rrm::{Rrm, RrmConfig};
use super::sgd::{Sgd, SgdConfig};
use super::smile::{Smile, SmileConfig};
use super::storm::{Storm, StormConfig};
use super::storm_plus::{StormPlus, StormPlusConfig};
use super::{AlgoError, Algorithm, ConfigNumber, StoppingRule};
use crate::problem::IlProblem;
use crate::scalar::Scalar;
use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// Every algorithm of the kit with its hyper-parameters (JSON: `{"algorithm": "storm", …}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "algorithm", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum AlgorithmConfig {
    /// SGD, Algorithm 3.
    Sgd(SgdConfig),
    /// STORM (eq. 3.40) or IS-STORM (math.md §4), by `correction`.
    Storm(StormConfig),
    /// STORM+ (Levy, Kavis, Cevher 2021).
    StormPlus(StormPlusConfig),
    /// Adam.
    Adam(AdamOptimizerConfig),
    /// RMSProp, eqs. 2.14–2.15.
    RmsProp(RmsPropOptimizerConfig),
    /// Online-to-non-convex conversion with OGD (Algorithm 5, IL-correct).
    O2nc(O2ncConfig),
    /// Negative control: Algorithm 4 as printed (E9).
    PrintedAlgorithm4(PrintedAlgorithm4Config),
    /// Negative control: Algorithm 5 as printed (E11).
    PrintedAlgorithm5(O2ncConfig),
    /// Behavioural cloning.
    Bc(BcConfig),
    /// DAgger, Algorithm 2.
    Dagger(DaggerConfig),
    /// Sampled repeated risk minimisation, eq. 3.29.
    Rrm(RrmConfig),
    /// SMILe, Algorithm 1.
    Smile(SmileConfig),
    /// Forward training.
    ForwardTraining(ForwardTrainingConfig),
}

/// A boxed algorithm for scalar `S` on problem `P`.
pub type BoxedAlgorithm<'a, S, P> = Box<dyn Algorithm<S, P> + 'a>;

impl AlgorithmConfig {
    /// Build the algorithm in the scalar `S`. In a scalar without roots (exact rationals) this
    /// builds SGD with constant or inverse-time steps, STORM / IS-STORM / the printed
    /// Algorithm 4 with `constant` or `explicit` schedules, and the dataset learners with an SGD
    /// inner optimiser; everything else is rejected here, before the run starts.
    ///
    /// # Errors
    /// The algorithm's constructor errors: invalid hyper-parameters, and
    /// [`AlgoError::NeedsRoots`] for a configuration that needs roots `S` lacks.
    pub fn build<'a, S: Scalar, P: IlProblem<S> + ?Sized + 'a>(
        &self,
    ) -> Result<BoxedAlgorithm<'a, S, P>, AlgoError> {
        Ok(match self {
            AlgorithmConfig::Sgd(c) => Box::new(Sgd::new(c)?),
            AlgorithmConfig::Storm(c) => Box::new(Storm::new(c)?),
            AlgorithmConfig::StormPlus(c) => Box::new(StormPlus::new(c)?),
            AlgorithmConfig::Adam(c) => Box::new(Adam::new(c)?),
            AlgorithmConfig::RmsProp(c) => Box::new(RmsProp::new(c)?),
            AlgorithmConfig::O2nc(c) => Box::new(O2nc::new(c)?),
            AlgorithmConfig::PrintedAlgorithm4(c) => Box::new(printed_algorithm_4(c)?),
            AlgorithmConfig::PrintedAlgorithm5(c) => Box::new(printed_algorithm_5(c)?),
            AlgorithmConfig::Bc(c) => Box::new(Bc::<S, P>::new(c)?),
            AlgorithmConfig::Dagger(c) => Box::new(Dagger::<S, P>::new(c)?),
            AlgorithmConfig::Rrm(c) => Box::new(Rrm::<S, P>::new(c)?),
            AlgorithmConfig::Smile(c) => Box::new(Smile::<S, P>::new(c)?),
            AlgorithmConfig::ForwardTraining(c) => Box::new(ForwardTraining::<S, P>::new(c)?),
        })
    }
}

/// Everything needed to reproduce a run: algorithm, initial θ, seed, stopping rule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunConfig {
    /// The algorithm and its hyper-parameters.
    pub algorithm: AlgorithmConfig,
    /// The initial parameter θ₀ (exact values; see [`ConfigNumber`]).
    pub theta0: Vec<ConfigNumber>,
    /// The seed of the run's ChaCha8 RNG.
    pub seed: u64,
    /// When to stop.
    pub stop: StoppingRule,
}

impl RunConfig {
    /// θ₀ in the scalar `S`.
    ///
    /// # Errors
    /// [`AlgoError::InvalidParameter`] for a non-finite entry.
    pub fn theta0<S: Scalar>(&self) -> Result<DVector<S>, AlgoError> {
        let v = self
            .theta0
            .iter()
            .map(|x| x.to::<S>("theta0"))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(DVector::from_vec(v))
    }

    /// The JSON text of this config.
    ///
    /// # Errors
    /// Serialisation failures (none for well-formed configs).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// Parse a config from JSON.
    ///
    /// # Errors
    /// Malformed JSON or unknown fields/values.
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(text)
    }
}
