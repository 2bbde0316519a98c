//! [`ToyProblem`]: a toy MDP as an [`IlProblem`] — sampling, expert labels, and the eq. 3.15
//! oracle, generic over the scalar.
//!
//! Sampling draws a dyadic uniform u = k/2⁵³ from the RNG (the same bits for every scalar type) and
//! picks the first category whose cumulative probability certainly exceeds u. In `f64` and in
//! rationals this always decides; in intervals it decides unless u falls inside the enclosure of a
//! cumulative probability, which is reported as [`OracleError::Undecidable`] — never guessed. So
//! runs with the same seed in `f64`, rationals and intervals follow the same trajectories.
//!
//! Termination (math.md §8, [`Termination`]): under a reset, a transition drawn into a terminal
//! state is followed by a second draw from the reset law, and the stream of decisions goes on;
//! under absorption, a terminal state repeats for the remaining steps, with no decision, no draw
//! and no expert query there (the recorded action is the placeholder 0). The estimators take the
//! scores of the decisions only (see [`estimator`]); the absorbing losses enter the loss-to-go of
//! every earlier decision, and absorbing steps cost no gradient evaluation. An MDP without
//! terminal states makes one draw per transition and none from a reset law.

use super::estimator;
use super::table::PolicyTable;
use super::{Termination, ToyMdp, estimator::prefix_loss};
use crate::baseline::PerDecisionTerms;
use crate::oracle::DecisionTerms;
use crate::problem::{Behaviour, Cost, EstimatorForm, IlProblem, KitRng, OracleError, Weighting};
use crate::sampling::{dyadic_uniform, sample_categorical};
use crate::scalar::Scalar;
use nalgebra::DVector;
use rand::Rng;
use std::sync::{Arc, Mutex, PoisonError};

/// A sampled trajectory τ = (s_1, a_1, …, a_{T−1}, s_T) with expert labels π*(s_t), t = 1..T−1.
/// At an absorbing step (math.md §8) no decision is taken: the action recorded there is the
/// placeholder 0 and the state repeats.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ToyTrajectory {
    /// s_1..s_T (length T).
    pub states: Vec<usize>,
    /// a_1..a_{T−1} (length T − 1).
    pub actions: Vec<usize>,
    /// π*(s_1)..π*(s_{T−1}) (length T − 1).
    pub labels: Vec<usize>,
}

/// One supervised example: a state and its expert label.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ToyExample {
    /// The state.
    pub state: usize,
    /// The expert's action there.
    pub label: usize,
}

/// A toy MDP instantiated in scalar `S` (its exact data enclosed/rounded once).
#[derive(Debug, Clone)]
pub struct ToyProblem<S> {
    mdp: ToyMdp,
    initial: Vec<S>,
    /// The environment's kernel P, as the file gives it (what the sampler draws from).
    transition: Vec<Vec<Vec<S>>>,
    /// The augmented chain's kernel P′ ([`ToyMdp::chain_transition`]) when it differs from P.
    chain: Option<Vec<Vec<Vec<S>>>>,
    /// The reset law (empty unless the MDP resets).
    reset_law: Vec<S>,
    c: S,
    /// The tables of the last few points in `f64` ([`ToyProblem::shared_table`]).
    recent: TableMemo<S>,
}

/// How many of the most recent `f64` tables [`ToyProblem::shared_table`] keeps: a STORM step asks
/// for the tables at θ_k and θ_{k−1} four times between them, an SGD step for θ_k twice.
const RECENT_TABLES: usize = 4;

/// A table with the bits of the θ it is at.
type KeyedTable<S> = (Vec<u64>, Arc<PolicyTable<S>>);

/// The most recent tables in a float type, keyed by the bits of θ ([`Scalar::bit_key`]). A clone
/// starts empty.
#[derive(Debug)]
struct TableMemo<S>(Mutex<Vec<KeyedTable<S>>>);

impl<S> Clone for TableMemo<S> {
    fn clone(&self) -> Self {
        Self(Mutex::new(Vec::new()))
    }
}

/// Whether `key` holds θ's bit keys (compared in place: a look-up allocates no key).
fn same_bits<S: Scalar>(key: &[u64], theta: &[S]) -> bool {
    key.len() == theta.len() && key.iter().zip(theta).all(|(k, x)| x.bit_key() == Some(*k))
}

impl<S: Scalar> ToyProblem<S> {
    /// Instantiate `mdp` in scalar `S`.
    pub fn new(mdp: &ToyMdp) -> Self {
        let cast = |v: &Vec<_>| v.iter().map(S::from_rational).collect::<Vec<S>>();
        let kernel = |p: &Vec<Vec<Vec<_>>>| {
            p.iter()
                .map(|row| row.iter().map(cast).collect())
                .collect::<Vec<_>>()
        };
        Self {
            initial: cast(&mdp.initial),
            transition: kernel(&mdp.transition),
            chain: match mdp.termination {
                Termination::None => None,
                _ => Some(kernel(&mdp.chain_transition())),
            },
            reset_law: match &mdp.termination {
                Termination::Reset { law, .. } => cast(law),
                _ => Vec::new(),
            },
            c: mdp.policy.c.as_ref().map_or_else(S::zero, S::from_rational),
            mdp: mdp.clone(),
            recent: TableMemo(Mutex::new(Vec::new())),
        }
    }
    /// The exact MDP.
    pub fn mdp(&self) -> &ToyMdp {
        &self.mdp
    }
    /// μ in `S`.
    pub fn initial(&self) -> &[S] {
        &self.initial
    }
    /// The chain's kernel P′(·|s, a) in `S` ([`ToyMdp::chain_transition`]: P itself without
    /// termination), on which the exact routes run.
    pub fn transition(&self, s: usize, a: usize) -> &[S] {
        match &self.chain {
            Some(chain) => &chain[s][a],
            None => &self.transition[s][a],
        }
    }
    /// Whether `s` is an absorbing state (terminal under [`Termination::Absorb`]): no decision is
    /// taken there.
    #[inline]
    pub fn is_absorbing(&self, s: usize) -> bool {
        self.mdp.termination.absorbing_loss(s).is_some()
    }
    /// The number of decisions along `states`: the states before the first absorbing one (all of
    /// them if none absorbs).
    pub fn decision_count(&self, states: &[usize]) -> usize {
        match self.mdp.termination {
            Termination::Absorb { .. } => states
                .iter()
                .position(|&s| self.is_absorbing(s))
                .unwrap_or(states.len()),
            _ => states.len(),
        }
    }
    /// The actions of a prefix (s_1..s_{T−1}, a_1..a_{T−2}) whose scores enter eq. 3.15: all of
    /// them without absorption, otherwise the decisions before the first absorbing state,
    /// including the one that led into it (see [`estimator`]).
    pub fn scored_actions<'t>(&self, states: &[usize], actions: &'t [usize]) -> &'t [usize] {
        &actions[..self.decision_count(states).min(actions.len())]
    }
    /// The policy/loss table at θ.
    ///
    /// # Errors
    /// As [`PolicyTable::new`].
    pub fn table(&self, theta: &[S]) -> Result<PolicyTable<S>, OracleError> {
        PolicyTable::new(&self.mdp, &self.c, theta)
    }
    /// The table at θ as [`ToyProblem::table`], shared: in `f64` and `f32` the tables of the last
    /// four points are kept and one at the same θ (bit for bit) is reused, since an
    /// algorithm's step asks for the table at the same iterate several times (roll-out, estimate,
    /// importance weights). A table is a function of θ alone, so every value is the same. The
    /// table pushed out for a new θ is rebuilt in place ([`PolicyTable::rebuild`]) when nothing
    /// else holds it, so that an algorithm stepping through new iterates does not allocate a
    /// table's storage at each.
    ///
    /// # Errors
    /// As [`PolicyTable::new`] (an error is not kept).
    pub fn shared_table(&self, theta: &[S]) -> Result<Arc<PolicyTable<S>>, OracleError> {
        if theta.first().is_some_and(|x| x.bit_key().is_none()) {
            return self.table(theta).map(Arc::new);
        }
        let lock = || self.recent.0.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((_, t)) = lock().iter().find(|(k, _)| same_bits(k, theta)) {
            return Ok(Arc::clone(t));
        }
        // The oldest table makes room, and its storage is reused when nothing else holds it.
        let oldest = {
            let mut recent = lock();
            (recent.len() >= RECENT_TABLES).then(|| recent.remove(0))
        };
        let (mut key, table) = match oldest {
            Some((key, t)) => (key, Some(t)),
            None => (Vec::with_capacity(theta.len()), None),
        };
        // A type has bit keys for every value or for none (checked on θ's first entry above).
        key.clear();
        key.extend(theta.iter().filter_map(Scalar::bit_key));
        // Built without the lock held, so that threads sharing the problem do not wait on it.
        let t = match table {
            Some(mut t) => match Arc::get_mut(&mut t) {
                Some(unique) => {
                    unique.rebuild(&self.mdp, &self.c, theta)?;
                    t
                }
                None => Arc::new(self.table(theta)?),
            },
            None => Arc::new(self.table(theta)?),
        };
        let mut recent = lock();
        if recent.len() >= RECENT_TABLES {
            recent.remove(0);
        }
        recent.push((key, Arc::clone(&t)));
        Ok(t)
    }
    /// The policy parameter c in `S` (zero for the direct parameterisation).
    pub fn c(&self) -> &S {
        &self.c
    }

    fn check(&self, t: &ToyTrajectory) -> Result<(), OracleError> {
        let m = &self.mdp;
        let bad = |msg: String| Err(OracleError::Trajectory(msg));
        if t.states.len() != m.horizon || t.actions.len() + 1 != m.horizon {
            return bad(format!(
                "{} states and {} actions for horizon {}",
                t.states.len(),
                t.actions.len(),
                m.horizon
            ));
        }
        if t.labels.len() + 1 != m.horizon {
            return bad(format!(
                "{} labels for horizon {}",
                t.labels.len(),
                m.horizon
            ));
        }
        if let Some(i) = t.states.iter().position(|&s| s >= m.states) {
            return bad(format!("states[{i}] = {} ≥ {}", t.states[i], m.states));
        }
        if let Some(i) = t.actions.iter().position(|&a| a >= m.actions) {
            return bad(format!("actions[{i}] = {} ≥ {}", t.actions[i], m.actions));
        }
        if let Some(i) = t.labels.iter().position(|&a| a >= m.actions) {
            return bad(format!("labels[{i}] = {} ≥ {}", t.labels[i], m.actions));
        }
        match &m.termination {
            Termination::None => {}
            Termination::Reset { terminal, .. } => {
                if let Some(i) = t.states.iter().position(|&s| terminal[s]) {
                    return bad(format!(
                        "states[{i}] = {} is terminal; under a reset the chain never occupies a terminal state",
                        t.states[i]
                    ));
                }
            }
            Termination::Absorb { .. } => {
                let n = self.decision_count(&t.states);
                if let Some(i) = (n..t.states.len()).find(|&i| t.states[i] != t.states[n]) {
                    return bad(format!(
                        "states[{i}] = {} follows the absorbing state {} at states[{n}]",
                        t.states[i], t.states[n]
                    ));
                }
            }
        }
        Ok(())
    }

    /// The prefix's states s_1..s_{T−1} and the actions whose scores count.
    fn prefix<'t>(&self, t: &'t ToyTrajectory) -> (&'t [usize], &'t [usize]) {
        let h = self.mdp.horizon;
        let states = &t.states[..h - 1];
        (states, self.scored_actions(states, &t.actions[..h - 2]))
    }
}

/// Who acts at one step.
enum Actor<'a, S> {
    Expert,
    Learner(&'a PolicyTable<S>),
}

/// The policies of a [`Behaviour`], tabulated once per roll-out, and the rule that picks one per step.
struct Actors<S> {
    tables: Vec<Arc<PolicyTable<S>>>,
    /// Mixture: probability of the expert, and of each learner table.
    expert_weight: f64,
    weights: Vec<f64>,
    /// Non-stationary: the table index acting at each step (`None` = expert).
    per_step: Option<Vec<Option<usize>>>,
}

impl<S: Scalar> Actors<S> {
    fn new(problem: &ToyProblem<S>, behaviour: &Behaviour<'_, S>) -> Result<Self, OracleError> {
        let table = |th: &DVector<S>| problem.shared_table(th.as_slice());
        Ok(match behaviour {
            Behaviour::Learner(theta) => Self {
                tables: vec![table(theta)?],
                expert_weight: 0.0,
                weights: vec![1.0],
                per_step: None,
            },
            Behaviour::Expert => Self {
                tables: vec![],
                expert_weight: 1.0,
                weights: vec![],
                per_step: None,
            },
            Behaviour::Mixture {
                expert_weight,
                learners,
            } => {
                let weights: Vec<f64> = learners.iter().map(|(w, _)| *w).collect();
                validate_weights(*expert_weight, &weights)?;
                Self {
                    tables: learners
                        .iter()
                        .map(|(_, th)| table(th))
                        .collect::<Result<_, _>>()?,
                    expert_weight: *expert_weight,
                    weights,
                    per_step: None,
                }
            }
            Behaviour::NonStationary(steps) => {
                let mut tables = Vec::new();
                let mut idx = Vec::new();
                for th in steps {
                    idx.push(match th {
                        Some(th) => {
                            tables.push(table(th)?);
                            Some(tables.len() - 1)
                        }
                        None => None,
                    });
                }
                Self {
                    tables,
                    expert_weight: 0.0,
                    weights: vec![],
                    per_step: Some(idx),
                }
            }
            #[allow(unreachable_patterns)]
            _ => return Err(OracleError::Behaviour("unsupported behaviour".into())),
        })
    }

    /// The actor at step `t`; a mixture draws one f64 uniform (the same for every scalar type).
    fn pick(&self, t: usize, rng: &mut KitRng) -> Actor<'_, S> {
        if let Some(steps) = &self.per_step {
            return match steps.get(t).copied().flatten() {
                Some(i) => Actor::Learner(&self.tables[i]),
                None => Actor::Expert,
            };
        }
        if self.weights.is_empty() {
            return Actor::Expert;
        }
        if self.expert_weight == 0.0 && self.weights.len() == 1 {
            return Actor::Learner(&self.tables[0]);
        }
        let x: f64 = rng.random();
        if x < self.expert_weight {
            return Actor::Expert;
        }
        let mut acc = self.expert_weight;
        for (j, w) in self.weights.iter().enumerate() {
            acc += w;
            if x < acc {
                return Actor::Learner(&self.tables[j]);
            }
        }
        Actor::Learner(&self.tables[self.weights.len() - 1])
    }
}

fn validate_weights(expert: f64, learners: &[f64]) -> Result<(), OracleError> {
    let all = std::iter::once(expert).chain(learners.iter().copied());
    if let Some(w) = all.clone().find(|w| !(0.0..=1.0).contains(w)) {
        return Err(OracleError::Behaviour(format!(
            "mixture weight {w} is not in [0, 1]"
        )));
    }
    let total: f64 = all.sum();
    if (total - 1.0).abs() > 1e-9 {
        return Err(OracleError::Behaviour(format!(
            "mixture weights sum to {total}, not 1"
        )));
    }
    Ok(())
}

impl<S: Scalar> IlProblem<S> for ToyProblem<S> {
    type Trajectory = ToyTrajectory;
    type Labelled = ToyExample;

    fn dim(&self) -> usize {
        self.mdp.policy.dim()
    }

    fn rollout(
        &mut self,
        behaviour: &Behaviour<'_, S>,
        rng: &mut KitRng,
        cost: &mut Cost,
    ) -> Result<ToyTrajectory, OracleError> {
        let h = self.mdp.horizon;
        let actors = Actors::new(self, behaviour)?;
        let mut states = Vec::with_capacity(h);
        let mut actions = Vec::with_capacity(h - 1);
        let mut labels = Vec::with_capacity(h - 1);
        let u: S = dyadic_uniform(rng);
        states.push(sample_categorical(&self.initial, &u)?);
        let mut decisions = 0u64;
        for t in 0..h - 1 {
            let s = states[t];
            let label = self.mdp.expert[s];
            if self.is_absorbing(s) {
                // No decision: the state absorbs whatever the action, and nothing is drawn.
                actions.push(0);
                labels.push(label);
                states.push(s);
                continue;
            }
            decisions += 1;
            let actor = actors.pick(t, rng);
            let a = match actor {
                Actor::Expert => label,
                Actor::Learner(table) => {
                    let u: S = dyadic_uniform(rng);
                    sample_categorical(&table.probs[table.groups[s]], &u)?
                }
            };
            let u: S = dyadic_uniform(rng);
            let mut next = sample_categorical(&self.transition[s][a], &u)?;
            if !self.reset_law.is_empty() && self.mdp.termination.is_terminal(next) {
                // A reset: the stream continues from a draw of the reset law.
                let u: S = dyadic_uniform(rng);
                next = sample_categorical(&self.reset_law, &u)?;
            }
            actions.push(a);
            labels.push(label);
            states.push(next);
        }
        cost.trajectories += 1;
        cost.env_steps += decisions;
        cost.expert_queries += decisions;
        Ok(ToyTrajectory {
            states,
            actions,
            labels,
        })
    }

    fn estimate(
        &mut self,
        theta: &DVector<S>,
        trajectory: &ToyTrajectory,
        form: EstimatorForm,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        self.check(trajectory)?;
        let table = self.shared_table(theta.as_slice())?;
        let (states, actions) = self.prefix(trajectory);
        let g = match form {
            EstimatorForm::Causal => estimator::causal(&table, states, actions),
            EstimatorForm::Full => estimator::full(&table, states, actions),
        };
        cost.gradient_evaluations += self.decision_count(states) as u64;
        Ok(DVector::from_vec(g))
    }

    fn weighted_estimate(
        &mut self,
        theta_old: &DVector<S>,
        theta_new: &DVector<S>,
        trajectory: &ToyTrajectory,
        weighting: Weighting,
        cost: &mut Cost,
    ) -> Result<DVector<S>, OracleError> {
        self.check(trajectory)?;
        let old = self.shared_table(theta_old.as_slice())?;
        let new = self.shared_table(theta_new.as_slice())?;
        let (states, actions) = self.prefix(trajectory);
        let g = estimator::weighted(&old, &new, states, actions, weighting);
        cost.gradient_evaluations += self.decision_count(states) as u64;
        Ok(DVector::from_vec(g))
    }

    fn trajectory_loss(
        &self,
        theta: &DVector<S>,
        trajectory: &ToyTrajectory,
    ) -> Result<S, OracleError> {
        self.check(trajectory)?;
        let table = self.shared_table(theta.as_slice())?;
        Ok(prefix_loss(&table, self.prefix(trajectory).0))
    }

    /// The states s_1..s_{T−1} with their labels, absorbing states left out (no decision is
    /// taken there, so they are no supervised example).
    fn labelled_states(&self, trajectory: &ToyTrajectory) -> Vec<ToyExample> {
        trajectory
            .states
            .iter()
            .zip(&trajectory.labels)
            .filter(|(s, _)| !self.is_absorbing(**s))
            .map(|(&state, &label)| ToyExample { state, label })
            .collect()
    }

    fn supervised(
        &self,
        theta: &DVector<S>,
        example: &ToyExample,
        grad: &mut [S],
        cost: &mut Cost,
    ) -> Result<S, OracleError> {
        if example.state >= self.mdp.states || example.label >= self.mdp.actions {
            return Err(OracleError::Trajectory(format!(
                "example (state {}, label {}) outside the MDP",
                example.state, example.label
            )));
        }
        let table = self.shared_table(theta.as_slice())?;
        let o = table.groups[example.state];
        let (l, local) = super::policy::brier(&table.probs[o], &table.jacobian[o], example.label);
        if grad.len() != table.dim {
            return Err(OracleError::Dimension {
                expected: table.dim,
                got: grad.len(),
            });
        }
        grad.fill(S::zero());
        table.add_block_unscaled(grad, example.state, &local);
        cost.gradient_evaluations += 1;
        Ok(l)
    }
}

// A baseline's state lives in plain fields behind `&mut self`: a baselined oracle can be sent to
// and shared between threads like the problem it wraps.
const _: () = {
    const fn send_and_sync<T: Send + Sync>() {}
    send_and_sync::<crate::baseline::Baselined<ToyProblem<f64>, f64>>();
};

impl<S: Scalar> PerDecisionTerms<S> for ToyProblem<S> {
    fn decision_terms(
        &self,
        theta: &DVector<S>,
        trajectory: &ToyTrajectory,
        weights: Option<(&DVector<S>, Weighting)>,
        out: &mut DecisionTerms<S>,
        cost: &mut Cost,
    ) -> Result<(), OracleError> {
        self.check(trajectory)?;
        let table = self.shared_table(theta.as_slice())?;
        let (states, actions) = self.prefix(trajectory);
        match weights {
            None => estimator::decision_terms(&table, states, actions, None, false, out),
            Some((theta_new, weighting)) => {
                let new = self.shared_table(theta_new.as_slice())?;
                let ratios: Vec<S> = states
                    .iter()
                    .zip(actions)
                    .map(|(&s, &a)| table.prob(s, a).clone() / new.prob(s, a))
                    .collect();
                let per_decision = weighting == Weighting::PerDecision;
                estimator::decision_terms(
                    &table,
                    states,
                    actions,
                    Some(&ratios),
                    per_decision,
                    out,
                );
            }
        }
        cost.gradient_evaluations += self.decision_count(states) as u64;
        Ok(())
    }

    /// The one-hot vector of decision i's state s_i (|S| entries), so that `b_i = w_{s_i}`: one
    /// baseline per state. Built in `scratch`, one row per decision (at most the trajectory's
    /// decisions).
    fn state_features<'a>(
        &self,
        trajectory: &'a ToyTrajectory,
        decisions: usize,
        scratch: &'a mut Vec<S>,
    ) -> Result<(&'a [S], usize), OracleError> {
        self.check(trajectory)?;
        let k = self.mdp.states;
        let (states, _) = self.prefix(trajectory);
        scratch.clear();
        for &s in &states[..decisions.min(states.len())] {
            scratch.extend((0..k).map(|j| if j == s { S::one() } else { S::zero() }));
        }
        Ok((scratch, k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::BigRational;

    fn m2() -> ToyMdp {
        ToyMdp::from_json_str(include_str!("../../examples/toy/m2-tied-two-groups.json"))
            .expect("valid toy file")
    }

    /// In a float type a table at the same θ, bit for bit, is the one kept; 0 and −0 are
    /// different keys; a table pushed out of the last four is rebuilt.
    fn floats_reuse_tables_by_the_bits_of_theta<S: Scalar>() {
        let p = ToyProblem::<S>::new(&m2());
        let x = |v: f64| S::from_binary64(v).expect("finite");
        let a = p.shared_table(&[x(0.5), x(0.0)]).unwrap();
        assert!(Arc::ptr_eq(&a, &p.shared_table(&[x(0.5), x(0.0)]).unwrap()));
        let b = p.shared_table(&[x(0.5), x(-0.0)]).unwrap();
        assert!(!Arc::ptr_eq(&a, &b));
        assert!(Arc::ptr_eq(
            &b,
            &p.shared_table(&[x(0.5), x(-0.0)]).unwrap()
        ));
        for k in 1..=RECENT_TABLES {
            p.shared_table(&[x(k as f64), x(1.0)]).unwrap();
        }
        let again = p.shared_table(&[x(0.5), x(0.0)]).unwrap();
        assert!(!Arc::ptr_eq(&a, &again));
        assert_eq!(a.probs, again.probs);
        // Tables pushed out while nothing else holds them are rebuilt in place, with a fresh
        // table's values.
        drop((a, b, again));
        let show = |t: &PolicyTable<S>| {
            format!(
                "{:?} {:?} {:?} {:?} {:?}",
                t.probs, t.jacobian, t.score, t.loss, t.loss_grad
            )
        };
        let mut kept = Vec::new();
        for k in 0..3 * RECENT_TABLES {
            let theta = [x(k as f64 / 8.0), x(-1.0)];
            let t = p.shared_table(&theta).unwrap();
            assert_eq!(show(&t), show(&p.table(&theta).unwrap()), "θ #{k}");
            // From the fifth on, the table pushed out is the one of four iterates before, held
            // by nothing else: its `Arc` comes back (a fresh table would be allocated while the
            // pushed-out one still lives, at another address).
            if k >= RECENT_TABLES {
                assert_eq!(
                    Arc::as_ptr(&t),
                    kept[k - RECENT_TABLES],
                    "θ #{k} not in place"
                );
            }
            kept.push(Arc::as_ptr(&t));
        }
    }

    /// Types without bit keys build a table at every call.
    fn other_scalars_build_a_table_every_time<S: Scalar>() {
        let p = ToyProblem::<S>::new(&m2());
        let theta = [S::from_ratio(1, 2), S::zero()];
        let t = p.shared_table(&theta).unwrap();
        assert!(!Arc::ptr_eq(&t, &p.shared_table(&theta).unwrap()));
    }

    #[test]
    fn shared_tables_are_kept_for_floats_only() {
        floats_reuse_tables_by_the_bits_of_theta::<f64>();
        floats_reuse_tables_by_the_bits_of_theta::<f32>();
        other_scalars_build_a_table_every_time::<BigRational>();
        other_scalars_build_a_table_every_time::<crate::scalar::Interval>();
        other_scalars_build_a_table_every_time::<crate::scalar::Dual<f64>>();
    }
}
