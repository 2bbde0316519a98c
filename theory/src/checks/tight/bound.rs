//! What the tight rows do alike for every bound: search ([`super::search`]), certify the best
//! candidates in order until one passes, then state the bound's row and its B ÷ 2 control at
//! that candidate. Each bound's module says how a candidate is certified and how its row reads
//! ([`Bound`]: [`super::sgd::Sgd`] for eq. 3.27, [`super::storm::Storm`] for eq. (3.60\*)).

use super::search::{Algorithm, Estimate, Noise, search};
use super::{Prepared, Sizes};
use crate::inputs::TableInputs;
use crate::record::check::{Check, Method, Role};

/// One bound's tight rows: how a candidate is certified and how its rows read.
pub trait Bound {
    /// A candidate certified for the bound: its exact or enclosed X̄ and its constants.
    type Certified;
    /// The bound, as a row that could not be computed names it ("eq. 3.27").
    const EQUATION: &'static str;
    /// How the rows are decided (exactly in ℚ, or rigorously in intervals).
    const METHOD: Method;

    /// Certify one candidate under `inputs`' oracle for `algorithm`'s estimator and family.
    ///
    /// # Errors
    /// A message saying why the candidate was passed over.
    fn certify(
        e: &Estimate,
        inputs: &TableInputs,
        s: &Sizes,
        algorithm: Algorithm,
    ) -> Result<Self::Certified, String>;

    /// The row for `X̄ ≤ scale · B` at a certified candidate (scale 1: the theorem's row; ½: its
    /// negative control), B read through `inputs`.
    fn row(c: &Self::Certified, inputs: &TableInputs, scale: f64, s: &Sizes, noise: Noise)
    -> Check;

    /// The id's stem, the result and the role of `algorithm`'s main row.
    fn names(algorithm: Algorithm) -> (&'static str, &'static str, Role);
}

/// The seeded search's candidates ([`search`]) for `algorithm`; it reads no input of the table.
pub fn candidates(s: &Sizes, noise: Noise, algorithm: Algorithm) -> Vec<Estimate> {
    search(algorithm, noise, s.budget(algorithm))
}

/// Certify the best of the [`candidates`] in order until one passes, under `inputs`' oracle.
pub fn prepare_from<B: Bound>(
    found: &[Estimate],
    inputs: &TableInputs,
    s: &Sizes,
    algorithm: Algorithm,
) -> Prepared<B::Certified> {
    super::first_certified(found, s.tries, |e| B::certify(e, inputs, s, algorithm))
}

/// Search (seeded, [`search`]) and certify the best candidates in order until one passes.
pub fn prepare<B: Bound>(
    inputs: &TableInputs,
    s: &Sizes,
    noise: Noise,
    algorithm: Algorithm,
) -> Prepared<B::Certified> {
    prepare_from::<B>(&candidates(s, noise, algorithm), inputs, s, algorithm)
}

/// The bound's row and its B ÷ 2 control (stated where X̄/B ≥ ½ was reached, or always for the
/// one-parameter searches over every instance) from [`prepare`]d candidates (made
/// with the same oracle, sizes, noise and algorithm), or one inconclusive row saying why no
/// candidate could be certified.
pub fn rows_from<B: Bound>(
    inputs: &TableInputs,
    s: &Sizes,
    noise: Noise,
    algorithm: Algorithm,
    p: &Prepared<B::Certified>,
) -> Vec<Check> {
    let (stem, result, role) = B::names(algorithm);
    match &p.certified {
        Some(c) => super::with_control(
            |scale| B::row(c, inputs, scale, s, noise),
            super::control_always(noise, algorithm),
            &p.passed_over,
        ),
        None => vec![p.none_certified(
            Check::builder(
                format!("{stem}.tight{}", noise.suffix()),
                result,
                format!("a tight instance of {}", B::EQUATION),
                role,
            ),
            &s.budget(algorithm),
            B::METHOD,
        )],
    }
}

/// [`prepare`], then [`rows_from`].
pub fn rows<B: Bound>(
    inputs: &TableInputs,
    s: &Sizes,
    noise: Noise,
    algorithm: Algorithm,
) -> Vec<Check> {
    rows_from::<B>(
        inputs,
        s,
        noise,
        algorithm,
        &prepare::<B>(inputs, s, noise, algorithm),
    )
}
