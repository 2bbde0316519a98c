//! A Gymnasium environment as a task of `ilopt run` (Python's `ilopt.GymTask`): [`PyEnv`] is an
//! [`Env`] whose reset and step call the Python environment's bound methods (looked up once); the
//! features φ(o) are computed as the observation arrives (a Python callable, or the observation
//! flattened to float64 with a trailing 1), and the expert is a Python callable from the
//! observation to the action, which is also the label. [`EnvRun`] makes it a task of
//! [`execute_task`](ilopt_cli::run::execute_task): a softmax learner for a `Discrete` action
//! space, a linear-Gaussian learner for a `Box` one. The environment lives in one interpreter, so
//! the seeds run one at a time, on the calling thread, which holds the GIL for the whole run:
//! each call into Python re-enters the lock this thread already has.
//!
//! **Seeding.** Every reset draws a seed from the run's RNG (63 bits). The training environment
//! is reset with it at the first episode of each seed's run ([`EnvRun::on_each_seed`] marks the
//! start) and without a seed after that, so its own generator runs on from there, as Gymnasium
//! recommends (a seeded reset builds a new generator, about five unseeded resets' cost on
//! CartPole-v1). Evaluation episodes run on a second environment
//! ([`EnvRun::with_evaluation_env`]), each reset with its draw, so that every checkpoint meets
//! the same episodes and evaluating does not move the training's generator. A run is thus
//! reproduced by its seed, whatever ran before it and whatever the checkpoint schedule.

use ilopt::env::{Env, EnvError, Step};
use ilopt::policy::{LinearGaussian, Softmax};
use ilopt::problem::KitRng;
use ilopt::task::{AfterEnd, EnvTask, Horizon};
use ilopt_cli::run::{EnvRun, LoadedConfig, RunOptions, RunOutcome, execute_task};
use pyo3::prelude::*;
use rand::RngCore;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// An observation: the Python object (for the expert), its features φ, or why it could not be
/// had (a failed reset, reported by the expert's next call).
#[derive(Debug)]
pub struct PyObs {
    raw: Option<Py<PyAny>>,
    phi: Vec<f64>,
    error: Option<String>,
}

impl Clone for PyObs {
    fn clone(&self) -> Self {
        PyObs {
            raw: self
                .raw
                .as_ref()
                .map(|o| Python::with_gil(|py| o.clone_ref(py))),
            phi: self.phi.clone(),
            error: self.error.clone(),
        }
    }
}

/// An action as Python takes it.
pub trait PyAction: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// The Python object `env.step` receives.
    fn to_py<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>>;
    /// The expert's answer as an action, checked against the space (`size`: the number of
    /// discrete actions, or the Box's dimension).
    fn from_py(value: &Bound<'_, PyAny>, size: usize) -> Result<Self, String>;
}

impl PyAction for usize {
    fn to_py<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(self.into_pyobject(py)?.into_any())
    }
    fn from_py(value: &Bound<'_, PyAny>, size: usize) -> Result<Self, String> {
        let a: i64 = match value.downcast::<pyo3::types::PyInt>() {
            Ok(int) => int.extract(),
            Err(_) => value
                .call_method0(pyo3::intern!(value.py(), "__index__"))
                .and_then(|i| i.extract()),
        }
        .map_err(|e| format!("the expert's action {value}: not an integer ({e})"))?;
        usize::try_from(a)
            .ok()
            .filter(|a| *a < size)
            .ok_or_else(|| format!("the expert's action {a} is not in Discrete({size})"))
    }
}

impl PyAction for Vec<f64> {
    fn to_py<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        use numpy::IntoPyArray;
        Ok(self.clone().into_pyarray(py).into_any())
    }
    fn from_py(value: &Bound<'_, PyAny>, size: usize) -> Result<Self, String> {
        let mut v = Vec::with_capacity(size);
        flatten_into(value, &mut v).map_err(|e| format!("the expert's action: {e}"))?;
        if v.len() != size {
            return Err(format!(
                "the expert's action has {} entries, the Box action space {size}",
                v.len()
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(format!("entry {i} of the expert's action is not finite"));
        }
        Ok(v)
    }
}

/// `numpy.asarray(value, dtype=float64).ravel()` appended to `out`; a float32 or float64 numpy
/// array (what Gymnasium's Box spaces hold) is copied from its buffer without a call into Python.
fn flatten_into(value: &Bound<'_, PyAny>, out: &mut Vec<f64>) -> PyResult<()> {
    use numpy::{PyArrayDyn, PyArrayMethods};
    if let Ok(a) = value.downcast::<PyArrayDyn<f32>>() {
        out.extend(a.to_owned_array().iter().map(|&x| f64::from(x)));
        return Ok(());
    }
    if let Ok(a) = value.downcast::<PyArrayDyn<f64>>() {
        out.extend(a.to_owned_array().iter());
        return Ok(());
    }
    let np = value.py().import("numpy")?;
    let kwargs = pyo3::types::PyDict::new(value.py());
    kwargs.set_item("dtype", "float64")?;
    let v: Vec<f64> = np
        .call_method("asarray", (value,), Some(&kwargs))?
        .call_method0("ravel")?
        .call_method0("tolist")?
        .extract()?;
    out.extend(v);
    Ok(())
}

/// The Python side of a Gymnasium task that both its environments share: the expert and the
/// feature map.
struct PySide {
    expert: Py<PyAny>,
    features: Option<Py<PyAny>>,
    feature_dim: usize,
    size: usize,
}

impl PySide {
    /// φ(o), checked: the feature callable's output (or o flattened, then 1) of `feature_dim`
    /// finite entries.
    fn features(&self, py: Python<'_>, obs: &Bound<'_, PyAny>) -> Result<Vec<f64>, String> {
        let mut phi = Vec::with_capacity(self.feature_dim);
        match &self.features {
            Some(f) => f
                .bind(py)
                .call1((obs,))
                .and_then(|v| flatten_into(&v, &mut phi))
                .map_err(|e| format!("features(observation): {e}"))?,
            None => {
                flatten_into(obs, &mut phi).map_err(|e| format!("the observation: {e}"))?;
                phi.push(1.0);
            }
        }
        if phi.len() != self.feature_dim {
            return Err(format!(
                "features(observation) has {} entries, the first observation's had {}",
                phi.len(),
                self.feature_dim
            ));
        }
        if let Some(i) = phi.iter().position(|x| !x.is_finite()) {
            return Err(format!("entry {i} of features(observation) is not finite"));
        }
        Ok(phi)
    }

    fn observe(&self, py: Python<'_>, obs: Bound<'_, PyAny>) -> Result<PyObs, String> {
        let phi = self.features(py, &obs)?;
        Ok(PyObs {
            raw: Some(obs.unbind()),
            phi,
            error: None,
        })
    }
}

/// A Gymnasium environment as an [`Env`] (module docs); `A` its action type (`usize` for
/// `Discrete`, `Vec<f64>` for `Box`). Its copies are the one Python environment.
pub struct PyEnv<A> {
    env: Arc<PyEnvMethods>,
    side: Arc<PySide>,
    action: std::marker::PhantomData<A>,
}

/// One Python environment's bound `reset` and `step`, and when it is reset with a seed.
struct PyEnvMethods {
    /// `"env"` or `"eval_env"`, as errors name it.
    name: &'static str,
    reset: Py<PyAny>,
    step: Py<PyAny>,
    /// `None`: every reset passes its seed (evaluation episodes). `Some(flag)`: only the first
    /// reset after the flag is raised (at each seed's start) does.
    reseed: Option<AtomicBool>,
}

impl<A> PyEnv<A> {
    /// The environment `env`, named `name` in errors (its `reset` and `step` looked up once);
    /// `every_episode` seeds every reset, else only the first after [`PyEnv::reseed`].
    fn new(
        name: &'static str,
        env: &Bound<'_, PyAny>,
        side: Arc<PySide>,
        every_episode: bool,
    ) -> Result<Self, String> {
        let method = |m: &str| {
            env.getattr(m)
                .map(Bound::unbind)
                .map_err(|e| format!("{name}.{m}: {e}"))
        };
        Ok(PyEnv {
            env: Arc::new(PyEnvMethods {
                name,
                reset: method("reset")?,
                step: method("step")?,
                reseed: (!every_episode).then(|| AtomicBool::new(true)),
            }),
            side,
            action: std::marker::PhantomData,
        })
    }

    /// Seed the next reset (a seed's run starts).
    fn reseed(&self) {
        if let Some(flag) = &self.env.reseed {
            flag.store(true, Ordering::SeqCst);
        }
    }
}

impl<A> Clone for PyEnv<A> {
    fn clone(&self) -> Self {
        PyEnv {
            env: self.env.clone(),
            side: self.side.clone(),
            action: std::marker::PhantomData,
        }
    }
}

impl<A: PyAction> Env<f64> for PyEnv<A> {
    type Obs = PyObs;
    type Action = A;

    fn reset(&mut self, rng: &mut KitRng) -> PyObs {
        let seed = rng.next_u64() >> 1;
        let seeded = self
            .env
            .reseed
            .as_ref()
            .is_none_or(|flag| flag.swap(false, Ordering::SeqCst));
        let (side, name) = (&self.side, self.env.name);
        Python::with_gil(|py| {
            let reset = self.env.reset.bind(py);
            let obs = if seeded {
                let kwargs = pyo3::types::PyDict::new(py);
                kwargs
                    .set_item("seed", seed)
                    .and_then(|()| reset.call((), Some(&kwargs)))
                    .and_then(|r| r.get_item(0))
                    .map_err(|e| format!("{name}.reset(seed={seed}): {e}"))?
            } else {
                reset
                    .call0()
                    .and_then(|r| r.get_item(0))
                    .map_err(|e| format!("{name}.reset(): {e}"))?
            };
            side.observe(py, obs)
        })
        .unwrap_or_else(|error| PyObs {
            raw: None,
            phi: vec![0.0; side.feature_dim],
            error: Some(error),
        })
    }

    fn step(&mut self, action: A) -> Result<Step<f64, PyObs>, EnvError> {
        let (side, name) = (&self.side, self.env.name);
        Python::with_gil(|py| {
            let a = action
                .to_py(py)
                .map_err(|e| format!("the action {action:?}: {e}"))?;
            let out = self
                .env
                .step
                .bind(py)
                .call1((a,))
                .map_err(|e| format!("{name}.step({action:?}): {e}"))?;
            let parsed = || -> PyResult<(Bound<'_, PyAny>, f64, bool, bool)> {
                use pyo3::types::{PySequence, PySequenceMethods};
                let out = out.downcast::<PySequence>()?;
                Ok((
                    out.get_item(0)?,
                    out.get_item(1)?.extract()?,
                    out.get_item(2)?.is_truthy()?,
                    out.get_item(3)?.is_truthy()?,
                ))
            };
            let (obs, reward, terminated, truncated) = parsed().map_err(|e| {
                format!("{name}.step returned {out}, not (observation, reward, terminated, truncated, info): {e}")
            })?;
            if !reward.is_finite() {
                return Err(format!("{name}.step({action:?}) returned the reward {reward}"));
            }
            let obs = side.observe(py, obs)?;
            Ok(Step::new(obs, reward, terminated, truncated))
        })
        .map_err(EnvError::External)
    }
}

/// The feature map of a [`PyEnv`] task: φ as the observation brought it.
pub type Features = fn(&PyObs) -> Vec<f64>;

fn stored_features(o: &PyObs) -> Vec<f64> {
    o.phi.clone()
}

/// The expert of a [`PyEnv`] task: the Python callable at the observation (a failed reset's
/// error is reported here, at the episode's first decision).
fn expert<A: PyAction>(
    side: Arc<PySide>,
) -> impl Fn(&PyObs) -> Result<A, String> + Clone + Send + Sync {
    move |o: &PyObs| {
        if let Some(e) = &o.error {
            return Err(e.clone());
        }
        let Some(raw) = &o.raw else {
            return Err("an observation without its Python object".into());
        };
        Python::with_gil(|py| {
            let a = side
                .expert
                .bind(py)
                .call1((raw.bind(py),))
                .map_err(|e| format!("expert(observation): {e}"))?;
            A::from_py(&a, side.size)
        })
    }
}

/// What `ilopt.GymTask` passes to Rust.
pub struct GymSpec {
    /// The `gymnasium.Env` of the training episodes.
    pub env: Py<PyAny>,
    /// The `gymnasium.Env` of the checkpoints' evaluation episodes (another instance).
    pub eval_env: Py<PyAny>,
    /// observation ↦ action.
    pub expert: Py<PyAny>,
    /// observation ↦ features, or none for (o, 1).
    pub features: Option<Py<PyAny>>,
    /// The length of φ (from the first observation).
    pub feature_dim: usize,
    /// `"discrete"` or `"box"`.
    pub space: String,
    /// n for `Discrete(n)`, m for a `Box` of m entries.
    pub size: usize,
    /// Decisions per trajectory of the fixed horizon (or none: one episode per trajectory).
    pub steps: Option<usize>,
    /// `"reset"` (the only end a GymTask's fixed horizon takes).
    pub after_end: String,
    /// σ of the linear-Gaussian learner.
    pub sigma: f64,
    /// Decisions of an evaluation episode at most.
    pub eval_steps: usize,
    /// The task's name in the records.
    pub name: String,
}

/// The training environment (seeded at each seed's start) and the evaluation one (seeded at
/// every episode), as [`PyEnv`]s.
fn envs<A>(
    env: &Py<PyAny>,
    eval_env: &Py<PyAny>,
    side: &Arc<PySide>,
) -> Result<(PyEnv<A>, PyEnv<A>), String> {
    Python::with_gil(|py| {
        Ok((
            PyEnv::new("env", env.bind(py), side.clone(), false)?,
            PyEnv::new("eval_env", eval_env.bind(py), side.clone(), true)?,
        ))
    })
}

/// Run `config` on the Gymnasium task of `spec` ([`execute_task`], one seed at a time), writing
/// to `out` if given: a softmax learner for `Discrete(n)`, a linear-Gaussian one for a `Box`.
///
/// # Errors
/// A message naming the argument at fault, or the run's error as the CLI words it.
pub fn run_gym(
    spec: GymSpec,
    config: &LoadedConfig,
    out: Option<&Path>,
    options: RunOptions,
) -> Result<RunOutcome, String> {
    let horizon = match (spec.steps, spec.after_end.as_str()) {
        (None, _) => Horizon::Episodic,
        (Some(0), _) => return Err("steps must be at least 1".into()),
        (Some(t), "reset") => Horizon::fixed(t, AfterEnd::Reset),
        (Some(_), other) => {
            return Err(format!(
                "after_end must be \"reset\" (a GymTask has no absorbing loss), got {other:?}"
            ));
        }
    };
    let side = Arc::new(PySide {
        expert: spec.expert,
        features: spec.features,
        feature_dim: spec.feature_dim,
        size: spec.size,
    });
    let features: Features = stored_features;
    match spec.space.as_str() {
        "discrete" => {
            let policy = Softmax::new(spec.size, spec.feature_dim).map_err(|e| e.to_string())?;
            let (env, eval_env) = envs::<usize>(&spec.env, &spec.eval_env, &side)?;
            let reseed = env.clone();
            let task = EnvRun::new(
                &spec.name,
                "softmax",
                EnvTask::new(env, features, expert::<usize>(side)),
                policy,
                horizon,
                spec.eval_steps,
            )
            .map_err(|e| e.to_string())?
            .with_evaluation_env(eval_env)
            .on_each_seed(move |_| reseed.reseed())
            .one_seed_at_a_time();
            execute_task(&task, config, out, Some(1), options).map_err(|e| e.to_string())
        }
        "box" => {
            let policy = LinearGaussian::new(spec.size, spec.feature_dim, spec.sigma)
                .map_err(|e| format!("sigma: {e}"))?;
            let (env, eval_env) = envs::<Vec<f64>>(&spec.env, &spec.eval_env, &side)?;
            let reseed = env.clone();
            let task = EnvRun::new(
                &spec.name,
                "linear-gaussian",
                EnvTask::new(env, features, expert::<Vec<f64>>(side)),
                policy,
                horizon,
                spec.eval_steps,
            )
            .map_err(|e| e.to_string())?
            .with_evaluation_env(eval_env)
            .on_each_seed(move |_| reseed.reseed())
            .one_seed_at_a_time();
            execute_task(&task, config, out, Some(1), options).map_err(|e| e.to_string())
        }
        other => Err(format!(
            "the action space must be Discrete or Box, got {other:?}"
        )),
    }
}
