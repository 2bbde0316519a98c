//! The stored form of a trained expert: the JSON file format of `experts/cartpole-ppo.json`.

use super::*;

/// The stored form of a trained expert (`experts/cartpole-ppo.json`): everything needed to use
/// it and to retrain it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PpoExpertFile {
    /// Always [`FILE_FORMAT`].
    pub format: String,
    /// Always [`FILE_VERSION`].
    pub version: u32,
    /// The command that wrote the file.
    pub command: String,
    /// The training seed.
    pub seed: u64,
    /// The training configuration.
    pub config: PpoConfig,
    /// What the training run did.
    pub training: TrainingSummary,
    /// The greedy actor's evaluation on the standard seeds.
    pub evaluation: Evaluation,
    /// Actor weights (layout of [`Mlp`]: 4 inputs, `config.hidden` units, 2 outputs).
    pub actor: Vec<f64>,
    /// Critic weights (layout of [`Mlp`]: 4 inputs, `config.hidden` units, 1 output).
    pub critic: Vec<f64>,
}

/// The raw shape of the file, with the weights kept as JSON values so that a `null` or a string
/// is reported with its field and index.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFile {
    pub(super) format: String,
    pub(super) version: u32,
    pub(super) command: String,
    pub(super) seed: u64,
    pub(super) config: PpoConfig,
    pub(super) training: TrainingSummary,
    pub(super) evaluation: Evaluation,
    pub(super) actor: Vec<serde_json::Value>,
    pub(super) critic: Vec<serde_json::Value>,
}

/// The committed CartPole expert (`experts/cartpole-ppo.json`, written by the `train_ppo`
/// example), embedded when the kit is built so that a binary runs from any directory.
pub const COMMITTED_CARTPOLE_EXPERT: &str = include_str!("../../../experts/cartpole-ppo.json");

/// The path [`COMMITTED_CARTPOLE_EXPERT`] was read from, relative to the repository (for messages).
pub const COMMITTED_CARTPOLE_EXPERT_PATH: &str = "experts/cartpole-ppo.json";

impl PpoExpertFile {
    /// The committed CartPole expert ([`COMMITTED_CARTPOLE_EXPERT`]), validated.
    ///
    /// # Errors
    /// As [`PpoExpertFile::parse`] (the kit's tests check that the committed file validates).
    pub fn committed_cartpole() -> Result<Self, PpoError> {
        Self::parse(COMMITTED_CARTPOLE_EXPERT, COMMITTED_CARTPOLE_EXPERT_PATH)
    }

    /// The file record of a trained expert.
    pub fn new(
        command: String,
        seed: u64,
        config: PpoConfig,
        training: TrainingSummary,
        evaluation: Evaluation,
        expert: &PpoExpert,
    ) -> Self {
        PpoExpertFile {
            format: FILE_FORMAT.into(),
            version: FILE_VERSION,
            command,
            seed,
            config,
            training,
            evaluation,
            actor: expert.actor.clone(),
            critic: expert.critic.clone(),
        }
    }

    /// The expert the file holds.
    ///
    /// # Errors
    /// As [`PpoExpert::new`] (a record built in memory is not validated until here).
    pub fn expert(&self) -> Result<PpoExpert, PpoError> {
        PpoExpert::new(self.config.hidden, self.actor.clone(), self.critic.clone())
    }

    /// Reads and validates a stored expert: JSON shape, [`FILE_FORMAT`] and [`FILE_VERSION`],
    /// [`PpoConfig::validate`], each network's number of weights for `config.hidden`, and finite
    /// weights.
    ///
    /// # Errors
    /// [`PpoError::Io`], [`PpoError::Json`], or [`PpoError::InvalidFile`] naming the field (e.g.
    /// `actor[17]`, `config.gamma`).
    pub fn read(path: impl AsRef<Path>) -> Result<Self, PpoError> {
        let path = path.as_ref();
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| PpoError::Io {
            path: shown.clone(),
            source,
        })?;
        Self::parse(&text, &shown)
    }

    /// [`PpoExpertFile::read`] on text; `origin` names it in errors.
    ///
    /// # Errors
    /// As [`PpoExpertFile::read`], without [`PpoError::Io`].
    pub fn parse(text: &str, origin: &str) -> Result<Self, PpoError> {
        let bad = |field: String, reason: String| PpoError::InvalidFile {
            path: origin.into(),
            field,
            reason,
        };
        let raw: RawFile = serde_json::from_str(text).map_err(|source| PpoError::Json {
            path: origin.into(),
            source,
        })?;
        if raw.format != FILE_FORMAT {
            return Err(bad(
                "format".into(),
                format!("expected \"{FILE_FORMAT}\", got {:?}", raw.format),
            ));
        }
        if raw.version != FILE_VERSION {
            return Err(bad(
                "version".into(),
                format!("expected {FILE_VERSION}, got {}", raw.version),
            ));
        }
        if let Err(e) = raw.config.validate() {
            let PpoError::InvalidConfig { field, reason } = e else {
                return Err(bad("config".into(), e.to_string()));
            };
            return Err(bad(format!("config.{field}"), reason));
        }
        let hidden = raw.config.hidden;
        let (actor_net, critic_net) =
            networks(hidden).map_err(|e| bad("config.hidden".into(), e.to_string()))?;
        let weights = |name: &str, values: Vec<serde_json::Value>, expected: usize| {
            if values.len() != expected {
                return Err(bad(
                    name.into(),
                    format!(
                        "expected {expected} weights for config.hidden = {hidden}, got {}",
                        values.len()
                    ),
                ));
            }
            values
                .iter()
                .enumerate()
                .map(|(i, v)| match v.as_f64() {
                    Some(x) if x.is_finite() => Ok(x),
                    _ => Err(bad(
                        format!("{name}[{i}]"),
                        format!("expected a finite number, got {v}"),
                    )),
                })
                .collect::<Result<Vec<f64>, _>>()
        };
        let actor = weights("actor", raw.actor, actor_net.net().param_dim())?;
        let critic = weights("critic", raw.critic, critic_net.param_dim())?;
        Ok(PpoExpertFile {
            format: raw.format,
            version: raw.version,
            command: raw.command,
            seed: raw.seed,
            config: raw.config,
            training: raw.training,
            evaluation: raw.evaluation,
            actor,
            critic,
        })
    }

    /// Writes the record as pretty JSON (weights round-trip exactly: serde_json's
    /// `float_roundtrip`).
    ///
    /// # Errors
    /// [`PpoError::Io`]; [`PpoError::Json`] if serialisation fails (a non-finite number).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), PpoError> {
        let path = path.as_ref();
        let shown = path.display().to_string();
        let mut text = serde_json::to_string_pretty(self).map_err(|source| PpoError::Json {
            path: shown.clone(),
            source,
        })?;
        text.push('\n');
        std::fs::write(path, text).map_err(|source| PpoError::Io {
            path: shown,
            source,
        })
    }
}
