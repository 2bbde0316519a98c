//! Environments as imitation-learning problems: the eq. 3.15 oracle on the real tasks.
//!
//! A [`Task`] is an episodic simulator with an expert (CartPole with the LQR expert, the obstacle
//! task with the velocity-obstacle expert); a [`crate::policy::Policy`] is the learner over the
//! task's features. [`TaskProblem`] joins them into an [`IlProblem`]: roll-outs with seeded RNGs,
//! expert labels at every visited state, and on a trajectory with decisions t = 1..n
//!
//! * the causal estimator of eq. 3.15, `g = Σ_t ∇l_t + Σ_{i<n} ψ_i Σ_{t>i} l_t`;
//! * the full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i`;
//! * the importance-weighted old-point estimates of math.md §4, with per-decision ratios
//!   `π_old(a_i|s_i)/π_new(a_i|s_i) = exp(log π_old − log π_new)` ([`LikelihoodRatio`]).
//!
//! What one trajectory is, and so which objective the estimators are unbiased for, is the
//! problem's [`Horizon`]:
//!
//! * [`Horizon::Fixed`] (the thesis's F, eqs. 3.1–3.16): a stream of exactly `steps` decisions.
//!   When an episode ends early the stream either **resets** (a fresh start from the task's reset
//!   law; the thesis's CartPole protocol) and goes on, with eq. 3.15 unchanged and its score sum
//!   running across resets (the reset time depends on earlier actions), or **absorbs**: the
//!   remaining steps take no decision and each costs the task's [`Task::absorbing_loss`] of the
//!   end state (obstacle task: 0 after reaching the goal, the loss's supremum after a crash).
//!   The absorbing losses enter the loss-to-go of every decision before them, the last one
//!   included (its action caused the end); absorbing steps cost no gradient evaluation. Both are
//!   the thesis's setting on an augmented MDP.
//! * [`Horizon::Episodic`]: one episode, ending when the task says so; F(θ) = E Σ_{t=1}^{n} l(s_t, θ)
//!   with the random episode length n. Eq. 3.15 is unbiased for it too, but a short episode is
//!   cheap, so its minimisers include policies that end the episode at once (a labelled control,
//!   not the thesis's objective).

pub mod cartpole;
mod horizon;
pub mod obstacle;

pub use horizon::{AfterEnd, Horizon};

use crate::baseline::{DecisionTerms, Given};
use crate::oracle::EstimatorKernel;
use crate::oracle::kernel::accumulate;
use crate::policy::{LikelihoodRatio, Policy, PolicyError};
use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use crate::scalar::{Real, Scalar};
use nalgebra::DVector;
use rand::Rng;
use std::borrow::Borrow;

/// An episodic environment with an expert, over the scalar `S`.
pub trait Task<S: Scalar> {
    /// The per-episode simulator state.
    type Episode: Clone;
    /// The expert's label at a state (what the loss compares the policy's output with).
    type Label: Clone + std::fmt::Debug;
    /// An action in the environment.
    type Action: Clone + std::fmt::Debug;

    /// Start an episode (seeded reset).
    ///
    /// # Errors
    /// [`OracleError::Environment`] if the environment cannot start.
    fn start(&self, rng: &mut KitRng) -> Result<Self::Episode, OracleError>;
    /// The learner's features φ(s) of the current state.
    fn features(&self, episode: &Self::Episode) -> Vec<S>;
    /// Append φ(s) of the current state to `out` (the same values as [`Task::features`]).
    ///
    /// The roll-out stores the features of a trajectory in one flat buffer through this method;
    /// the default calls [`Task::features`] (one allocation), the kit's tasks override it with a
    /// version that writes in place (with the capacity reserved from
    /// [`Task::max_episode_steps`], a step then allocates nothing).
    fn push_features(&self, episode: &Self::Episode, out: &mut Vec<S>) {
        out.extend(self.features(episode));
    }
    /// Append φ(s) to `out` as [`Task::push_features`] does, and hand the same values to `f`
    /// (the roll-out's learner acts on them).
    ///
    /// The default hands `f` the entries just appended. A task whose φ has a length known at
    /// compile time should override it to build φ in a local array, append a copy and hand `f`
    /// the array (see [`cartpole::CartPoleTask`]): inlined into the roll-out, the policy's `θ·φ`
    /// then reads φ from registers instead of loading back what was just stored, a store-to-load
    /// round trip on the roll-out's critical path (issue 8: about 8 % of the CartPole roll-out).
    fn push_features_then<R>(
        &self,
        episode: &Self::Episode,
        out: &mut Vec<S>,
        f: impl FnOnce(&[S]) -> R,
    ) -> R {
        let start = out.len();
        self.push_features(episode, out);
        f(&out[start..])
    }
    /// An upper bound on the number of decisions of an episode, if the task has one (a time
    /// limit). The roll-out reserves the trajectory's storage for that many steps up front, so
    /// that the per-step loop never grows a buffer. `None` (the default): buffers grow
    /// geometrically as usual.
    fn max_episode_steps(&self) -> Option<usize> {
        None
    }
    /// The expert's label and the action the expert would take at the current state.
    ///
    /// # Errors
    /// [`OracleError`] if the expert cannot decide (undecidable comparison, no solution).
    fn expert(&self, episode: &Self::Episode) -> Result<(Self::Label, Self::Action), OracleError>;
    /// The loss per remaining step when a [`Horizon::Fixed`] stream with [`AfterEnd::Absorb`]
    /// ends in this state (called after [`Task::advance`] returned `true`): 0 for an end that
    /// is a success, the per-step loss's supremum for a failure. `None` (the default): the task
    /// defines no absorbing loss, and an absorbing roll-out is an error.
    fn absorbing_loss(&self, episode: &Self::Episode) -> Option<S> {
        let _ = episode;
        None
    }
    /// Apply an action; `Ok(true)` when the episode is over (terminated or truncated).
    ///
    /// # Errors
    /// [`OracleError::Environment`] for an invalid action or a failed step.
    fn advance(
        &self,
        episode: &mut Self::Episode,
        action: &Self::Action,
    ) -> Result<bool, OracleError>;
}

/// A trajectory on a task: per decision, the features, the action taken and the expert's label.
///
/// The features are stored flat, row after row (`feature_dim` entries per decision), so that a
/// roll-out fills one buffer instead of allocating a vector per step; [`TaskTrajectory::feature`]
/// and [`TaskTrajectory::feature_rows`] read them, [`TaskTrajectory::features`] returns the old
/// `Vec<Vec<S>>` form (a copy).
#[derive(Debug, Clone)]
pub struct TaskTrajectory<S, L, A> {
    /// φ(s_1), …, φ(s_n) concatenated.
    feature_data: Vec<S>,
    /// Entries of one φ(s_t).
    feature_dim: usize,
    /// Number of feature rows stored.
    rows: usize,
    /// `true` when every feature entry is known to be finite: a learner's roll-out, where every φ
    /// went through [`EstimatorKernel::sample_trusted`], which checks φ. The estimators then skip their own
    /// pass over the features. `false`: unknown (checked when needed).
    features_finite: bool,
    /// a_t.
    pub actions: Vec<A>,
    /// π*(s_t).
    pub labels: Vec<L>,
    /// The absorbing losses after the last decision, `Σ_{t>n} l_t` (a [`Horizon::Fixed`] stream
    /// with [`AfterEnd::Absorb`] whose episode ended at decision n before the horizon; zero for
    /// an end with zero loss). `None`: the trajectory did not absorb.
    pub absorbed: Option<S>,
    /// Episodes that ended inside the stream and were followed by a reset
    /// ([`AfterEnd::Reset`]; 0 otherwise).
    pub resets: usize,
}

/// Equal data (features, actions, labels); how the features came to be known finite is not part
/// of it.
impl<S: PartialEq, L: PartialEq, A: PartialEq> PartialEq for TaskTrajectory<S, L, A> {
    fn eq(&self, other: &Self) -> bool {
        self.feature_data == other.feature_data
            && self.feature_dim == other.feature_dim
            && self.rows == other.rows
            && self.actions == other.actions
            && self.labels == other.labels
            && self.absorbed == other.absorbed
            && self.resets == other.resets
    }
}

impl<S, L, A> TaskTrajectory<S, L, A> {
    /// Number of decisions n.
    pub fn len(&self) -> usize {
        self.actions.len()
    }
    /// `true` for an empty trajectory.
    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }
    /// Entries of one feature vector φ(s_t) (0 for an empty trajectory built without features).
    pub fn feature_dim(&self) -> usize {
        self.feature_dim
    }
    /// φ(s_t) (0-based `t`).
    ///
    /// # Panics
    /// If `t` is not below the number of stored feature rows.
    pub fn feature(&self, t: usize) -> &[S] {
        assert!(t < self.rows, "feature row {t} of {}", self.rows);
        &self.feature_data[t * self.feature_dim..(t + 1) * self.feature_dim]
    }
    /// φ(s_1), …, φ(s_n) in order.
    pub fn feature_rows(&self) -> impl ExactSizeIterator<Item = &[S]> + '_ {
        (0..self.rows).map(|t| self.feature(t))
    }
    /// All features, concatenated (`feature_dim` entries per decision).
    pub fn feature_data(&self) -> &[S] {
        &self.feature_data
    }
}

impl<S: Clone, L, A> TaskTrajectory<S, L, A> {
    /// A trajectory from its per-decision parts (features, actions, labels), e.g. one read back
    /// from a file. The three lists may differ in length (the oracle rejects such a trajectory).
    ///
    /// # Errors
    /// [`OracleError::Trajectory`] if the feature vectors do not all have the same length.
    pub fn from_parts(
        features: Vec<Vec<S>>,
        actions: Vec<A>,
        labels: Vec<L>,
    ) -> Result<Self, OracleError> {
        let feature_dim = features.first().map_or(0, Vec::len);
        if features.iter().any(|f| f.len() != feature_dim) {
            return Err(OracleError::Trajectory(
                "feature vectors of different lengths".into(),
            ));
        }
        Ok(Self {
            rows: features.len(),
            feature_data: features.into_iter().flatten().collect(),
            feature_dim,
            features_finite: false,
            actions,
            labels,
            absorbed: None,
            resets: 0,
        })
    }

    /// φ(s_1), …, φ(s_n) as one vector per decision (a copy; the form of the field this struct had
    /// before the features were stored flat).
    pub fn features(&self) -> Vec<Vec<S>> {
        self.feature_rows().map(<[S]>::to_vec).collect()
    }
}

/// A labelled state: features and the expert's label.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskExample<S, L> {
    /// φ(s).
    pub features: Vec<S>,
    /// π*(s).
    pub label: L,
}

/// A task with a learner policy: an [`IlProblem`].
#[derive(Debug, Clone)]
pub struct TaskProblem<T, P> {
    /// The environment with its expert.
    pub task: T,
    /// The learner's policy class.
    pub policy: P,
    /// What one trajectory is (the objective).
    pub horizon: Horizon,
}

impl<T, P> TaskProblem<T, P> {
    /// The task and policy with one episode per trajectory ([`Horizon::Episodic`]).
    pub fn episodic(task: T, policy: P) -> Self {
        Self {
            task,
            policy,
            horizon: Horizon::Episodic,
        }
    }

    /// The task and policy under the thesis's fixed-horizon objective.
    ///
    /// # Errors
    /// [`OracleError::Environment`] if `steps` is 0.
    pub fn fixed(
        task: T,
        policy: P,
        steps: usize,
        after_end: AfterEnd,
    ) -> Result<Self, OracleError> {
        if steps == 0 {
            return Err(OracleError::Environment(
                "a fixed horizon needs at least 1 decision, got 0".into(),
            ));
        }
        Ok(Self {
            task,
            policy,
            horizon: Horizon::fixed(steps, after_end),
        })
    }
}

/// A policy's error as an oracle error (out of line: the hot loops only branch to it).
#[cold]
#[inline(never)]
fn policy_error(e: PolicyError) -> OracleError {
    match e {
        PolicyError::Undecidable(u) => OracleError::Undecidable(u),
        other => OracleError::Domain(other.to_string()),
    }
}

fn check_theta<S: Scalar>(theta: &DVector<S>, dim: usize) -> Result<(), OracleError> {
    if theta.len() != dim {
        return Err(OracleError::Dimension {
            expected: dim,
            got: theta.len(),
        });
    }
    if !theta.iter().all(Scalar::is_finite) {
        return Err(OracleError::NonFinite("θ"));
    }
    Ok(())
}

fn check_trajectory<S, L, A>(t: &TaskTrajectory<S, L, A>) -> Result<(), OracleError> {
    if t.rows != t.len() || t.labels.len() != t.len() || t.is_empty() {
        return Err(OracleError::Trajectory(format!(
            "{} features, {} actions, {} labels",
            t.rows,
            t.len(),
            t.labels.len()
        )));
    }
    Ok(())
}

/// Working storage of one estimate: the per-decision ∇l_t and ψ_t and the running `Σ_{i<t} ψ_i`,
/// allocated once per call (one allocation), never per decision.
struct Scratch<S> {
    buf: Vec<S>,
    d: usize,
}

impl<S: Scalar> Scratch<S> {
    fn new(d: usize) -> Self {
        Self {
            buf: vec![S::zero(); 3 * d],
            d,
        }
    }
    /// `(∇l_t, ψ_t, Σ_{i<t} ψ_i)`.
    fn parts(&mut self) -> (&mut [S], &mut [S], &mut [S]) {
        let (grad, rest) = self.buf.split_at_mut(self.d);
        let (score, score_sum) = rest.split_at_mut(self.d);
        (grad, score, score_sum)
    }
}

/// The causal estimator `Σ_t [w_{1:t−1} ∇l_t + w_{1:t−1} l_t Σ_{i<t} ψ_i]` in one pass over the
/// trajectory (math.md §4 for the weights): with `ratio = None` every weight is 1 (eq. 3.15);
/// with `Some(θ_new)` the per-decision prefix weights `w_{1:t−1} = exp(Σ_{i<t} log π_θ(a_i|s_i) −
/// log π_θnew(a_i|s_i))` are accumulated along the way. Returns `g` and the log of the whole
/// trajectory's weight: the sum of the log-ratios of every decision that weighs a loss
/// (decisions 1..n−1; 1..n when the trajectory absorbed), zero without `ratio`.
///
/// An absorbed trajectory adds its absorbing losses `L_abs = Σ_{t>n} l_t` to the loss-to-go of
/// every decision: `+ w_{1:n} L_abs Σ_{i≤n} ψ_i` (they carry no `∇l`: they do not depend on θ
/// but through the law of the end state).
///
/// Per decision: one [`Policy::loss_score_into`] into preallocated buffers and O(d) field
/// operations, no allocation. The operations and their order are those of the former
/// two-stage computation (terms, then sums), so `f64` results are bit-for-bit unchanged. (Only
/// which error is reported can differ: when the loss fails at one decision and the likelihood
/// ratio at an earlier one, the ratio's error now comes first.)
fn causal_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    ratio: Option<&[S]>,
    per_decision: bool,
    t: &TaskTrajectory<S, L, A>,
) -> Result<(Vec<S>, S), OracleError>
where
    S: Real,
    P: LikelihoodRatio<S, Action = A> + EstimatorKernel<S>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let n = t.len();
    let mut g = vec![S::zero(); d];
    let mut log_w = S::zero();
    // θ has been checked by the caller; with every φ checked here once, the per-decision calls can
    // skip the policy's own checks (`causal_step_trusted`). Otherwise the checked calls below
    // report the first failure exactly as before.
    let trusted = !per_decision && features_valid(policy, t);
    let tail = t.absorbed.as_ref();
    if trusted && ratio.is_none() && tail.is_none() {
        // The plain causal estimator: the whole pass in the policy (one loop it may specialise).
        let (rows, actions, labels) = (&t.feature_data, &t.actions, &t.labels);
        // Scratch only if the policy's pass asks for it (the logistic policy's does not).
        let mut scratch = Vec::new();
        policy
            .causal_sum_trusted(theta, rows, labels, actions, None, &mut g, &mut scratch)
            .map_err(policy_error)?;
        return Ok((g, log_w));
    }
    let mut scratch = Scratch::new(d);
    let (grad, score, score_sum) = scratch.parts();
    for (step, ((phi, a), y)) in t.feature_rows().zip(&t.actions).zip(&t.labels).enumerate() {
        if trusted {
            policy
                .causal_step_trusted(theta, phi, y.borrow(), a, grad, score, &mut g, score_sum)
                .map_err(policy_error)?;
        } else {
            let l = policy
                .loss_score_into(theta, phi, y.borrow(), a, grad, score)
                .map_err(policy_error)?;
            if per_decision {
                let w = log_w.exp();
                accumulate(&mut g, Some(&w), &l, grad, score, score_sum);
            } else {
                accumulate(&mut g, None, &l, grad, score, score_sum);
            }
        }
        if let Some(theta_new) = ratio
            && (step + 1 < n || tail.is_some())
        {
            log_w += policy
                .log_likelihood_ratio(theta, theta_new, phi, a)
                .map_err(policy_error)?;
        }
    }
    if let Some(tail) = tail {
        // `score_sum` now holds Σ_{i≤n} ψ_i.
        let wl = if per_decision {
            log_w.exp() * tail
        } else {
            tail.clone()
        };
        for (gj, sj) in g.iter_mut().zip(score_sum.iter()) {
            *gj += wl.clone() * sj;
        }
    }
    Ok((g, log_w))
}

/// The causal estimator's [`DecisionTerms`] on a task trajectory with decisions t = 1..n, for
/// the baselined estimator of [`crate::baseline`]: direct part `Σ_t w_{1:t−1} ∇l_t`, per step
/// the loss `w_{1:t−1} l_t` (then the absorbing tail's `w_{1:n} L_abs`, with no decision), per
/// scored decision (1..n−1; 1..n when the trajectory absorbed, as in [`causal_pass`]) its score
/// ψ_i with the prefix weight `w_{1:i}` (per-decision weighting) — or the whole weight as the
/// estimate's scale (trajectory weighting). Same per-decision calls as [`causal_pass`], into the
/// reused buffers of `out`: no allocation per step.
fn terms_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    ratio: Option<(&[S], Weighting)>,
    t: &TaskTrajectory<S, L, A>,
    out: &mut DecisionTerms<S>,
) -> Result<(), OracleError>
where
    S: Real,
    P: LikelihoodRatio<S, Action = A>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let n = t.len();
    let tail = t.absorbed.as_ref();
    let scored = if tail.is_some() { n } else { n - 1 };
    let per_decision = matches!(ratio, Some((_, Weighting::PerDecision)));
    out.begin(d, n);
    let mut scratch = Scratch::new(d);
    let (grad, score, _) = scratch.parts();
    let mut log_w = S::zero();
    for (step, ((phi, a), y)) in t.feature_rows().zip(&t.actions).zip(&t.labels).enumerate() {
        let l = policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
        if per_decision {
            let w = log_w.exp();
            for (o, g) in out.direct_mut().iter_mut().zip(grad.iter()) {
                *o += w.clone() * g;
            }
            out.push_loss(w * l);
        } else {
            for (o, g) in out.direct_mut().iter_mut().zip(grad.iter()) {
                *o += g;
            }
            out.push_loss(l);
        }
        if step < scored {
            if let Some((theta_new, _)) = ratio {
                log_w += policy
                    .log_likelihood_ratio(theta, theta_new, phi, a)
                    .map_err(policy_error)?;
            }
            let row = out.push_score(per_decision.then(|| log_w.exp()));
            row.clone_from_slice(score);
        }
    }
    if let Some(tail) = tail {
        out.push_loss(if per_decision {
            log_w.exp() * tail
        } else {
            tail.clone()
        });
    }
    if matches!(ratio, Some((_, Weighting::Trajectory))) {
        out.set_scale(log_w.exp());
    }
    Ok(())
}

/// Whether every feature vector of `t` has the policy's length and only finite entries (the
/// per-call φ check of the policies, done once for the whole trajectory).
fn features_valid<S, P, L, A>(policy: &P, t: &TaskTrajectory<S, L, A>) -> bool
where
    S: Scalar,
    P: Policy<S>,
{
    t.feature_dim == policy.feature_dim()
        && (t.features_finite
            || t.feature_data
                .iter()
                .fold(true, |ok, x| ok & Scalar::is_finite(x)))
}

/// The full form `Σ_t ∇l_t + (Σ_t l_t) Σ_{i<n} ψ_i`, in two passes (the total loss first), each
/// without per-decision allocation. An absorbed trajectory adds its absorbing losses to the total
/// and its last decision's score to the sum (`Σ_{i≤n} ψ_i`: that action caused the end).
fn full_pass<S, P, L, A>(
    policy: &P,
    theta: &[S],
    t: &TaskTrajectory<S, L, A>,
) -> Result<Vec<S>, OracleError>
where
    S: Scalar,
    P: Policy<S, Action = A>,
    L: Borrow<P::Label>,
{
    let d = policy.param_dim();
    let n = t.len();
    let mut scratch = Scratch::new(d);
    let (grad, score, _) = scratch.parts();
    let mut total = t.absorbed.clone().unwrap_or_else(S::zero);
    for ((phi, a), y) in t.feature_rows().zip(&t.actions).zip(&t.labels) {
        total += policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
    }
    let scored = if t.absorbed.is_some() { n } else { n - 1 };
    let mut g = vec![S::zero(); d];
    for (step, ((phi, a), y)) in t.feature_rows().zip(&t.actions).zip(&t.labels).enumerate() {
        policy
            .loss_score_into(theta, phi, y.borrow(), a, grad, score)
            .map_err(policy_error)?;
        for ((gj, dj), sj) in g.iter_mut().zip(grad.iter()).zip(score.iter()) {
            *gj += dj;
            if step < scored {
                *gj += total.clone() * sj;
            }
        }
    }
    Ok(g)
}

/// The learner θ's action at φ (θ checked by the caller), inlined into each roll-out loop.
#[inline(always)]
fn sample_learner<S: Scalar, P: EstimatorKernel<S>>(
    policy: &P,
    theta: &[S],
    phi: &[S],
    rng: &mut KitRng,
) -> Result<P::Action, OracleError> {
    policy.sample_trusted(theta, phi, rng).map_err(policy_error)
}

/// The error of a task whose feature vectors changed length during an episode.
#[cold]
#[inline(never)]
fn features_changed_length(before: usize, now: usize) -> OracleError {
    OracleError::Environment(format!(
        "the task's features changed length from {before} to {now}"
    ))
}

/// The error of an absorbing roll-out on a task without an absorbing loss.
#[cold]
#[inline(never)]
fn no_absorbing_loss() -> OracleError {
    OracleError::Environment(
        "the horizon absorbs at the end of an episode, but the task defines no absorbing loss"
            .into(),
    )
}

impl<T, P> TaskProblem<T, P> {
    /// One episode of the task from a fresh start, acting with `choose(step, φ(s), a*(s), rng)` at
    /// every decision, recording features, actions and the expert's labels.
    ///
    /// The storage for the whole episode is reserved once: with the task's time limit known, the
    /// per-step loop allocates nothing (for tasks and policies whose features, labels and actions
    /// are written in place).
    fn rollout_with<S, F>(
        &self,
        rng: &mut KitRng,
        choose: F,
    ) -> Result<TaskTrajectory<S, T::Label, T::Action>, OracleError>
    where
        S: Scalar,
        T: Task<S>,
        P: EstimatorKernel<S>,
        F: FnMut(usize, &[S], T::Action, &mut KitRng) -> Result<T::Action, OracleError>,
    {
        let steps = match self.horizon {
            Horizon::Episodic => self.task.max_episode_steps().unwrap_or(0),
            Horizon::Fixed { steps, .. } => steps,
        };
        let mut t = TaskTrajectory {
            feature_data: Vec::with_capacity(steps * self.policy.feature_dim()),
            feature_dim: 0,
            rows: 0,
            features_finite: false,
            actions: Vec::with_capacity(steps),
            labels: Vec::with_capacity(steps),
            absorbed: None,
            resets: 0,
        };
        self.rollout_into(rng, &mut t, choose)?;
        Ok(t)
    }

    /// The loop of [`TaskProblem::rollout_with`], into the empty trajectory `t`: one episode, or
    /// a stream of the fixed horizon's decisions with resets or an absorbing end. A function of
    /// its own, not inlined: writing through `&mut t` measured a few per cent faster than into a
    /// local that is then returned. Each behaviour of [`IlProblem::rollout`] gets its own copy,
    /// with its action choice compiled in.
    #[inline(never)]
    fn rollout_into<S, F>(
        &self,
        rng: &mut KitRng,
        t: &mut TaskTrajectory<S, T::Label, T::Action>,
        mut choose: F,
    ) -> Result<(), OracleError>
    where
        S: Scalar,
        T: Task<S>,
        P: EstimatorKernel<S>,
        F: FnMut(usize, &[S], T::Action, &mut KitRng) -> Result<T::Action, OracleError>,
    {
        let (limit, after_end) = match self.horizon {
            Horizon::Episodic => (usize::MAX, None),
            Horizon::Fixed { steps, after_end } => (steps, Some(after_end)),
        };
        let mut ep = self.task.start(rng)?;
        loop {
            let step = t.actions.len();
            let (rows, feature_dim) = (&mut t.rows, &mut t.feature_dim);
            // φ is stored and handed on by the task (by value where it can): its length is
            // checked, then the expert labels the state and `choose` acts on φ.
            let (label, action) =
                self.task
                    .push_features_then(&ep, &mut t.feature_data, |phi| {
                        if *rows == 0 {
                            *feature_dim = phi.len();
                        } else if phi.len() != *feature_dim {
                            return Err(features_changed_length(*feature_dim, phi.len()));
                        }
                        *rows += 1;
                        let (label, expert_action) = self.task.expert(&ep)?;
                        Ok((label, choose(step, phi, expert_action, rng)?))
                    })?;
            let done = self.task.advance(&mut ep, &action)?;
            t.actions.push(action);
            t.labels.push(label);
            let n = t.actions.len();
            if n >= limit {
                return Ok(());
            }
            if done {
                match after_end {
                    None => return Ok(()),
                    Some(AfterEnd::Reset) => {
                        t.resets += 1;
                        ep = self.task.start(rng)?;
                    }
                    Some(AfterEnd::Absorb) => {
                        let c = self
                            .task
                            .absorbing_loss(&ep)
                            .ok_or_else(no_absorbing_loss)?;
                        t.absorbed = Some(S::from_i64((limit - n) as i64) * c);
                        return Ok(());
                    }
                }
            }
        }
    }
}

impl<S, T, P> IlProblem<S> for TaskProblem<T, P>
where
    S: Real,
    T: Task<S>,
    P: LikelihoodRatio<S, Action = T::Action> + EstimatorKernel<S>,
    T::Label: Borrow<P::Label>,
{
    type Trajectory = TaskTrajectory<S, T::Label, T::Action>;
    type Labelled = TaskExample<S, T::Label>;

    fn dim(&self) -> usize {
        self.policy.param_dim()
    }

    fn rollout(
        &self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<Self::Trajectory, OracleError> {
        let d = self.dim();
        match behaviour {
            Behaviour::Learner(th) => check_theta(th, d)?,
            Behaviour::Mixture {
                expert_weight,
                learners,
            } => {
                let all = std::iter::once(*expert_weight).chain(learners.iter().map(|l| l.0));
                if all.clone().any(|w| !(0.0..=1.0).contains(&w))
                    || (all.sum::<f64>() - 1.0).abs() > 1e-9
                {
                    return Err(OracleError::Behaviour(
                        "mixture weights must lie in [0, 1] and sum to 1".into(),
                    ));
                }
                for (_, th) in learners {
                    check_theta(th, d)?;
                }
            }
            Behaviour::NonStationary(steps) => {
                for th in steps.iter().flatten() {
                    check_theta(th, d)?;
                }
            }
            _ => {}
        }
        // One loop per kind of behaviour, each with its action choice compiled in: the learner's
        // roll-out (the oracle's hot loop) carries no mixture or schedule code. Every learner θ
        // of `behaviour` was checked above.
        let act = |learner: Option<&DVector<S>>, phi: &[S], expert, rng: &mut KitRng| match learner
        {
            Some(th) => sample_learner(&self.policy, th.as_slice(), phi, rng),
            None => Ok(expert),
        };
        let t = match behaviour {
            Behaviour::Learner(th) => {
                // θ's slice taken once: the loop then holds its address and length in registers.
                let th = th.as_slice();
                let mut t = self.rollout_with(rng, |_, phi, _, rng| {
                    sample_learner(&self.policy, th, phi, rng)
                })?;
                // Every φ was checked by `sample_trusted`.
                t.features_finite = true;
                t
            }
            Behaviour::Expert => self.rollout_with(rng, |_, _, expert, _| Ok(expert))?,
            Behaviour::Mixture {
                expert_weight,
                learners,
            } => self.rollout_with(rng, |_, phi, expert, rng| {
                let x: f64 = rng.random();
                let learner = if x < *expert_weight {
                    None
                } else {
                    let mut acc = *expert_weight;
                    let mut pick = learners.last().map(|l| l.1);
                    for (w, th) in learners {
                        acc += w;
                        if x < acc {
                            pick = Some(*th);
                            break;
                        }
                    }
                    pick
                };
                act(learner, phi, expert, rng)
            })?,
            Behaviour::NonStationary(steps) => self
                .rollout_with(rng, |step, phi, expert, rng| {
                    act(steps.get(step).copied().flatten(), phi, expert, rng)
                })?,
        };
        cost.trajectories += 1;
        cost.env_steps += t.len() as u64;
        cost.expert_queries += t.len() as u64;
        Ok(t)
    }

    fn estimate(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        check_theta(theta, self.dim())?;
        check_trajectory(trajectory)?;
        let th = theta.as_slice();
        let g = match form {
            EstimatorForm::Causal => causal_pass(&self.policy, th, None, false, trajectory)?.0,
            EstimatorForm::Full => full_pass(&self.policy, th, trajectory)?,
        };
        cost.gradient_evaluations += trajectory.len() as u64;
        if !g.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("the gradient estimate"));
        }
        Ok(DVector::from_vec(g))
    }

    fn weighted_estimate(
        &self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &Self::Trajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        check_theta(theta_old, self.dim())?;
        check_theta(theta_new, self.dim())?;
        check_trajectory(trajectory)?;
        // Term t carries w_{1:t−1} = Π_{i<t} π_old(a_i|s_i)/π_new(a_i|s_i); the last decision
        // never weighs a loss.
        let (old, new) = (theta_old.as_slice(), theta_new.as_slice());
        let g = match weighting {
            Weighting::PerDecision => {
                causal_pass(&self.policy, old, Some(new), true, trajectory)?.0
            }
            Weighting::Trajectory => {
                let (g, log_w) = causal_pass(&self.policy, old, Some(new), false, trajectory)?;
                let w = log_w.exp();
                g.into_iter().map(|x| x * &w).collect()
            }
        };
        cost.gradient_evaluations += trajectory.len() as u64;
        if !g.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("the weighted gradient estimate"));
        }
        Ok(DVector::from_vec(g))
    }

    /// Without an absorbing tail, on a trajectory whose features are known valid, the baseline
    /// is folded into the plain estimator's loop as per-decision loss shifts
    /// `δ_t = b_t − b_{t−1}` ([`EstimatorKernel::causal_sum_trusted`]); otherwise assembled from
    /// the [`DecisionTerms`].
    fn baselined_estimate(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        baseline: Given<'_, S>,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        check_theta(theta, self.dim())?;
        check_trajectory(trajectory)?;
        let t = trajectory;
        let n = t.len();
        let scored = if t.absorbed.is_some() { n } else { n - 1 };
        if !baseline.covers(scored) {
            return Err(crate::problem::too_few_baselines(scored));
        }
        let mut g = vec![S::zero(); self.dim()];
        if t.absorbed.is_none() && features_valid(&self.policy, t) {
            // δ_t = b_t − b_{t−1} with b_0 = 0 and b_t = 0 after the last scored decision: for
            // one constant only the first and the first unscored decision shift.
            let mut shifts = vec![S::zero(); n];
            match baseline {
                Given::Constant(b) => {
                    if scored > 0 {
                        shifts[0] = b.clone();
                        shifts[scored] = -b.clone();
                    }
                }
                Given::TimeIndexed(bs) => {
                    let mut previous = S::zero();
                    for (shift, b) in shifts.iter_mut().zip(&bs[..scored]) {
                        *shift = b.clone() - &previous;
                        previous = b.clone();
                    }
                    shifts[scored] = -previous;
                }
            }
            let mut scratch = Vec::new();
            self.policy
                .causal_sum_trusted(
                    theta.as_slice(),
                    &t.feature_data,
                    &t.labels,
                    &t.actions,
                    Some(&shifts),
                    &mut g,
                    &mut scratch,
                )
                .map_err(policy_error)?;
        } else {
            let mut terms = DecisionTerms::new();
            terms_pass(&self.policy, theta.as_slice(), None, t, &mut terms)?;
            terms.finish();
            terms.estimate_into(|i| baseline.at(i).cloned(), &mut g);
        }
        cost.gradient_evaluations += n as u64;
        if !g.iter().all(Scalar::is_finite) {
            return Err(OracleError::NonFinite("the baselined gradient estimate"));
        }
        Ok(DVector::from_vec(g))
    }

    fn decision_terms(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
        weights: Option<(&DVector<S>, Weighting)>,
        out: &mut DecisionTerms<S>,
        cost: &mut Cost,
    ) -> Result<(), OracleError> {
        check_theta(theta, self.dim())?;
        if let Some((theta_new, _)) = weights {
            check_theta(theta_new, self.dim())?;
        }
        check_trajectory(trajectory)?;
        let ratio = weights.map(|(new, w)| (new.as_slice(), w));
        terms_pass(&self.policy, theta.as_slice(), ratio, trajectory, out)?;
        cost.gradient_evaluations += trajectory.len() as u64;
        Ok(())
    }

    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &Self::Trajectory,
    ) -> Result<S, OracleError> {
        check_theta(theta, self.dim())?;
        check_trajectory(trajectory)?;
        let mut total = trajectory.absorbed.clone().unwrap_or_else(S::zero);
        let mut grad = vec![S::zero(); self.dim()];
        // θ is checked above; with every φ checked once, the loss alone is computed per decision
        // (the same values as `loss_into`'s, without its gradient).
        let trusted = features_valid(&self.policy, trajectory);
        for (phi, y) in trajectory.feature_rows().zip(&trajectory.labels) {
            let th = theta.as_slice();
            total += if trusted {
                self.policy.loss_trusted(th, phi, y.borrow(), &mut grad)
            } else {
                self.policy.loss_into(th, phi, y.borrow(), &mut grad)
            }
            .map_err(policy_error)?;
        }
        Ok(total)
    }

    fn labelled_states(&self, trajectory: &Self::Trajectory) -> Vec<Self::Labelled> {
        trajectory
            .feature_rows()
            .zip(&trajectory.labels)
            .map(|(f, l)| TaskExample {
                features: f.to_vec(),
                label: l.clone(),
            })
            .collect()
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &Self::Labelled,
        cost: &mut Cost,
    ) -> Result<(S, DVector<S>), OracleError> {
        check_theta(theta, self.dim())?;
        let (l, g) = self
            .policy
            .loss(theta.as_slice(), &example.features, example.label.borrow())
            .map_err(policy_error)?;
        cost.gradient_evaluations += 1;
        Ok((l, DVector::from_vec(g)))
    }
}
