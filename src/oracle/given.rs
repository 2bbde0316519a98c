//! [`Given`]: baselines known before an estimate is formed.

/// Baselines fixed before the pass over a trajectory: one constant for every scored decision, or
/// one per decision index (0-based here: entry i is b_{i+1}).
#[derive(Debug, PartialEq)]
pub enum Given<'a, S> {
    /// b for every decision.
    Constant(&'a S),
    /// b_1, b_2, … (a decision beyond the list is an error of the estimate).
    TimeIndexed(&'a [S]),
}

// By hand: the references are `Copy` whatever `S` is.
impl<S> Clone for Given<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S> Copy for Given<'_, S> {}

impl<'a, S> Given<'a, S> {
    /// The baseline of the 0-based decision `i`; `None` beyond a list.
    pub fn at(&self, i: usize) -> Option<&'a S> {
        match *self {
            Given::Constant(b) => Some(b),
            Given::TimeIndexed(bs) => bs.get(i),
        }
    }

    /// Whether `decisions` scored decisions all have a baseline.
    pub fn covers(&self, decisions: usize) -> bool {
        match self {
            Given::Constant(_) => true,
            Given::TimeIndexed(bs) => bs.len() >= decisions,
        }
    }
}
