//! The record of one roll-out on a task: per decision the learner's features, the action taken
//! and the expert's label, and how the stream ended.

use crate::oracle::Decisions;
use crate::problem::OracleError;
use smallvec::SmallVec;

/// Features a [`TaskExample`] keeps inside itself (more go to the heap).
pub const INLINE_FEATURES: usize = 8;

/// A trajectory on a task: per decision, the features, the action taken and the expert's label.
///
/// The features are stored flat, row after row (`feature_dim` entries per decision), so that a
/// roll-out fills one buffer instead of allocating a vector per step; [`TaskTrajectory::feature`]
/// and [`TaskTrajectory::feature_rows`] read them, [`TaskTrajectory::features`] returns one
/// vector per decision (a copy).
#[derive(Debug, Clone)]
pub struct TaskTrajectory<S, L, A> {
    /// φ(s_1), …, φ(s_n) concatenated.
    pub(super) feature_data: Vec<S>,
    /// Entries of one φ(s_t).
    pub(super) feature_dim: usize,
    /// Number of feature rows stored.
    pub(super) rows: usize,
    /// `true` when every feature entry is known to be finite: a learner's roll-out, where every φ
    /// went through [`EstimatorKernel::sample_validated`], which checks φ. The estimators then skip their own
    /// pass over the features. `false`: unknown (checked when needed).
    pub(super) features_finite: bool,
    /// a_t.
    pub actions: Vec<A>,
    /// π*(s_t).
    pub labels: Vec<L>,
    /// The absorbing losses after the last decision, `Σ_{t>n} l_t` (a [`Horizon::Fixed`](super::Horizon::Fixed) stream
    /// with [`AfterEnd::Absorb`](super::AfterEnd::Absorb) whose episode ended at decision n before the horizon; zero for
    /// an end with zero loss). `None`: the trajectory did not absorb.
    pub absorbed: Option<S>,
    /// Episodes that ended inside the stream and were followed by a reset
    /// ([`AfterEnd::Reset`](super::AfterEnd::Reset); 0 otherwise).
    pub resets: usize,
    /// What the learner's policy noted per decision when it sampled
    /// ([`EstimatorKernel::sample_noting`](crate::oracle::EstimatorKernel::sample_noting)), with
    /// the θ it sampled at: the causal estimate at that same θ reads them instead of
    /// recomputing them. Empty for other roll-outs and policies that note nothing.
    pub(super) notes: Notes<S>,
}

/// The notes of a learner's roll-out and the θ they were taken at (both empty: none).
#[derive(Debug, Clone)]
pub(super) struct Notes<S> {
    /// `note_len` entries per decision.
    pub(super) values: Vec<S>,
    /// The θ of the roll-out.
    pub(super) theta: Vec<S>,
}

impl<S> Default for Notes<S> {
    fn default() -> Self {
        Self {
            values: Vec::new(),
            theta: Vec::new(),
        }
    }
}

/// Equal data (features, actions, labels); how the features came to be known finite and the
/// policy's notes are not part of it.
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
            notes: Notes::default(),
        })
    }

    /// φ(s_1), …, φ(s_n) as one vector per decision (a copy).
    pub fn features(&self) -> Vec<Vec<S>> {
        self.feature_rows().map(<[S]>::to_vec).collect()
    }
}

/// A labelled state: features and the expert's label.
///
/// Up to [`INLINE_FEATURES`] features are kept inside the example: a dataset learner that draws
/// minibatches from a large aggregated dataset then reads one place in memory per example, not
/// two (the example, then its features on the heap).
#[derive(Debug, Clone, PartialEq)]
pub struct TaskExample<S, L> {
    /// φ(s).
    pub features: SmallVec<[S; INLINE_FEATURES]>,
    /// π*(s).
    pub label: L,
}

impl<S, L, A> TaskTrajectory<S, L, A> {
    /// The trajectory as the estimator passes of [`crate::oracle`] read it.
    pub(crate) fn decisions(&self) -> Decisions<'_, S, L, A> {
        Decisions {
            feature_data: &self.feature_data,
            feature_dim: self.feature_dim,
            rows: self.rows,
            features_finite: self.features_finite,
            actions: &self.actions,
            labels: &self.labels,
            absorbed: self.absorbed.as_ref(),
            notes: (!self.notes.theta.is_empty())
                .then_some((self.notes.values.as_slice(), self.notes.theta.as_slice())),
        }
    }
}
