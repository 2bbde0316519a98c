//! CartPole-v1, faithful to Gymnasium's `CartPoleEnv` (thesis §4.2.1).
//!
//! Source: `gymnasium/envs/classic_control/cartpole.py` (Gymnasium 1.x; checked against 1.4.0), the
//! cart-pole of Barto, Sutton & Anderson (1983) with the equations of Florian (2005), "Correct
//! equations for the dynamics of the cart-pole system". State `s = (x, ẋ, θ, θ̇)`: cart position (m),
//! cart velocity (m/s), pole angle from upright (rad, positive clockwise), pole angular velocity.
//! Action `0` pushes the cart left with 10 N, action `1` right.
//!
//! One step (the "euler" integrator, `τ = 0.02` s), in exactly Gymnasium's order of operations, so
//! that in `f64` every state is bit-for-bit Gymnasium's float64 state (`tests/environments/cartpole.rs` checks
//! 4 800 steps against data written by Gymnasium itself, `scripts/cartpole_reference.py`):
//!
//! ```text
//! F        = ±force_mag
//! temp     = (F + polemass_length · θ̇² · sin θ) / total_mass
//! θ̈        = (g · sin θ − cos θ · temp) / (length · (4/3 − masspole · cos²θ / total_mass))
//! ẍ        = temp − polemass_length · θ̈ · cos θ / total_mass
//! x' = x + τ·ẋ,   ẋ' = ẋ + τ·ẍ,   θ' = θ + τ·θ̇,   θ̇' = θ̇ + τ·θ̈
//! terminated = x' < −2.4 ∨ x' > 2.4 ∨ θ' < −θ_max ∨ θ' > θ_max
//! ```
//!
//! (each product and quotient associates left to right, as Python evaluates it; `θ̇²` is
//! `np.square`, a single multiplication). The reward is 1 for every step, the terminating one
//! included; `gym.make("CartPole-v1")` adds a time limit of 500 steps (`truncated`).
//!
//! # Scalars
//! Generic over [`Real`]. Constants are built from integer ratios ([`CartPoleParams::gymnasium`]),
//! which in `f64` are exactly Python's float literals (both are correctly rounded), and derived
//! constants (`total_mass`, `polemass_length`) are computed with the same operation as Gymnasium.
//! The two thresholds are Gymnasium's *float64 values* (`2.4` and `12 * 2 * math.pi / 360`), taken
//! exactly as rationals: they define the environment.
//!
//! With the `mpfr` feature, [`inari::Interval`] is [`Real`] and the interval run encloses, at every
//! step, (a) the exact-real trajectory of the equations above with exact constants (`g = 49/5`, `4/3`,
//! …) and exact sine and cosine, and (b) the `f64` run from the same (float) initial state: every
//! interval operation returns `[RD(lo), RU(hi)]` of the exact range, which contains the
//! round-to-nearest result of the same operation on contained floats, and every `f64` constant is
//! the rounding of the exact one. For `sin`/`cos`, (b) also needs the libm that `f64` calls (glibc,
//! which numpy calls too) to be faithfully rounded; glibc documents errors of at most 1 ulp, and the
//! enclosure test in `tests/environments/cartpole.rs` found the `f64` run inside on every step it checks (2 400
//! steps of 24 trajectories; widths about 1e-11 after 100 steps, 2e-8 after 200 balanced steps).
//! A termination test an interval cannot decide is [`EnvError::Undecidable`].
//!
//! # Differences from Gymnasium
//! * The observation is the full-precision state `[S; 4]`; Gymnasium returns it cast to float32
//!   (see [`gymnasium_observation`] for that cast).
//! * The reset draws from the kit's ChaCha8 [`KitRng`], not numpy's PCG64, so seeds do not carry
//!   over; the distribution is the same (uniform on `[−0.05, 0.05]` per component, drawn as numpy
//!   does, `low + (high − low)·u`).
//! * Stepping after the episode ended is [`EnvError::EpisodeOver`] (Gymnasium warns and returns
//!   reward 0); a non-finite state is [`EnvError::NonFinite`].

use super::{Env, EnvError, Step};
use crate::problem::KitRng;
use crate::scalar::{BigRational, Real, Scalar, Undecidable};
use rand::Rng;
use std::cmp::Ordering;
use std::marker::PhantomData;

/// Episode length of CartPole-v1: `gym.make("CartPole-v1")` wraps the environment in
/// `TimeLimit(max_episode_steps=500)` (Gymnasium's registration), so step 500 is `truncated`.
pub const MAX_EPISODE_STEPS: usize = 500;

/// Names of the state components, in order, for error messages and reports.
pub const STATE_NAMES: [&str; 4] = ["x", "x_dot", "theta", "theta_dot"];

/// Gymnasium's `x_threshold = 2.4` (m): the episode terminates when `|x| > 2.4` (strictly). This is
/// the float64 value of the literal `2.4` (Gymnasium compares floats), taken exactly as a rational.
pub fn x_threshold_rational() -> BigRational {
    BigRational::from_float(X_THRESHOLD).expect("2.4 is finite")
}

/// Gymnasium's `x_threshold` as the float64 it is: the nearest to 12/5, i.e. Python's literal
/// `2.4` (Rust's literal is correctly rounded too).
const X_THRESHOLD: f64 = 2.4;

/// Gymnasium's `theta_threshold_radians` as the float64 Python computes: `24·π` then `/ 360`, each
/// correctly rounded (Rust evaluates the same IEEE operations at compile time).
const THETA_THRESHOLD: f64 = 12.0 * 2.0 * std::f64::consts::PI / 360.0;

/// Gymnasium's `theta_threshold_radians = 12 * 2 * math.pi / 360` (12°): the episode terminates
/// when `|θ| > θ_max` (strictly). This is the float64 value Python computes (`math.pi` is
/// [`std::f64::consts::PI`]; `24 * pi` then `/ 360`, each correctly rounded,
/// `0.20943951023931953`), taken exactly as a rational.
pub fn theta_threshold_rational() -> BigRational {
    BigRational::from_float(THETA_THRESHOLD).expect("finite")
}

/// The constants of Gymnasium's `CartPoleEnv.__init__`, in the scalar `S`.
///
/// Base constants are integer ratios (exact for rationals, enclosed for intervals, correctly
/// rounded — i.e. Python's float literal — for `f64`); derived ones are computed as Gymnasium
/// computes them.
#[derive(Debug, Clone, PartialEq)]
pub struct CartPoleParams<S> {
    /// `gravity = 9.8` (m/s²).
    pub gravity: S,
    /// `masscart = 1.0` (kg).
    pub masscart: S,
    /// `masspole = 0.1` (kg).
    pub masspole: S,
    /// `total_mass = masspole + masscart` (kg).
    pub total_mass: S,
    /// `length = 0.5` (m): *half* the pole's length (distance from the pivot to its centre of mass).
    pub length: S,
    /// `polemass_length = masspole * length` (kg·m).
    pub polemass_length: S,
    /// `force_mag = 10.0` (N): the magnitude of the push of either action.
    pub force_mag: S,
    /// `tau = 0.02` (s): the time step of the euler integrator.
    pub tau: S,
    /// The literal `4.0 / 3.0` of the pole's moment of inertia about its end (`(4/3)·m·l²`).
    pub four_thirds: S,
    /// `x_threshold`, see [`x_threshold_rational`].
    pub x_threshold: S,
    /// `theta_threshold_radians`, see [`theta_threshold_rational`].
    pub theta_threshold: S,
}

impl<S: Scalar> CartPoleParams<S> {
    /// The constants of CartPole-v1. Every one is built by [`Scalar::from_ratio`] or (the two
    /// thresholds, float64 values) [`Scalar::from_binary64`], which in `f64` fold to compile-time
    /// constants when inlined.
    #[inline]
    pub fn gymnasium() -> Self {
        let masscart = S::from_ratio(1, 1);
        let masspole = S::from_ratio(1, 10);
        let length = S::from_ratio(1, 2);
        let total_mass = masspole.clone() + &masscart;
        let polemass_length = masspole.clone() * &length;
        CartPoleParams {
            gravity: S::from_ratio(49, 5),
            masscart,
            masspole,
            total_mass,
            length,
            polemass_length,
            force_mag: S::from_ratio(10, 1),
            tau: S::from_ratio(1, 50),
            four_thirds: S::from_ratio(4, 3),
            // Exact in every scalar (a finite float64; rounded in f32): the values of
            // `x_threshold_rational` and `theta_threshold_rational`.
            x_threshold: S::from_binary64(X_THRESHOLD).expect("finite"),
            theta_threshold: S::from_binary64(THETA_THRESHOLD).expect("finite"),
        }
    }
}

/// The CartPole transition `s ↦ s'` and termination test.
///
/// The constants ([`CartPoleParams::gymnasium`]) are built at every step rather than stored: in
/// `f64` they are then compile-time constants, cheaper in the roll-out's hot loop than loads from
/// a stored struct, and in the other scalars building them costs little next to the step's sine
/// and cosine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CartPoleDynamics<S> {
    scalar: PhantomData<fn() -> S>,
}

impl<S: Real> Default for CartPoleDynamics<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Real> CartPoleDynamics<S> {
    /// The dynamics of CartPole-v1 ([`CartPoleParams::gymnasium`]).
    pub fn new() -> Self {
        CartPoleDynamics {
            scalar: PhantomData,
        }
    }

    /// The constants.
    pub fn params(&self) -> CartPoleParams<S> {
        CartPoleParams::gymnasium()
    }

    /// One euler step of Gymnasium's `CartPoleEnv.step` (module docs) from `state` under `action`
    /// (0: push left, 1: push right); returns the next state and whether it is terminal.
    ///
    /// # Errors
    /// * [`EnvError::InvalidAction`] if `action ∉ {0, 1}`;
    /// * [`EnvError::NonFinite`] if a component of the next state is not finite;
    /// * [`EnvError::Undecidable`] if the termination test cannot be decided (intervals).
    #[inline]
    pub fn step(&self, state: &[S; 4], action: usize) -> Result<([S; 4], bool), EnvError> {
        let mut next = state.clone();
        let terminated = self.step_in_place(&mut next, action)?;
        Ok((next, terminated))
    }

    /// [`CartPoleDynamics::step`] that overwrites `state` with the next state (only on success;
    /// on error `state` is unchanged) and returns whether it is terminal.
    ///
    /// The same numbers as [`CartPoleDynamics::step`] (which calls it); it exists for the
    /// roll-out's hot loop, where returning the state inside a `Result` made it travel through
    /// stack copies whose loads could not be forwarded from the stores (a stall on the
    /// step-to-step dependency chain).
    ///
    /// # Errors
    /// As [`CartPoleDynamics::step`].
    #[inline(always)]
    pub fn step_in_place(&self, state: &mut [S; 4], action: usize) -> Result<bool, EnvError> {
        let p = &CartPoleParams::<S>::gymnasium();
        if action > 1 {
            return Err(invalid_action(action));
        }
        let [x, x_dot, theta, theta_dot] = &*state;
        let costheta = theta.cos();
        let sintheta = theta.sin();
        let push = p.polemass_length.clone() * theta_dot.square() * &sintheta;
        let denominator = p.length.clone()
            * (p.four_thirds.clone() - p.masspole.clone() * costheta.square() / &p.total_mass);
        // The accelerations under both pushes, then the action's: the action picks between
        // finished values instead of entering the arithmetic as the force, so that the step's
        // floating-point chain does not wait for the sampler that chose it (the compiler makes the
        // choice a branch, which the core predicts; a force picked first becomes a table load on
        // the step-to-step dependency chain). The kept values are the same numbers as from the
        // chosen force alone. In `f64` only the kept pair is computed (the branch precedes the
        // division that differs); other scalar types may compute both, a few operations wasted.
        let accelerations = |force: S| {
            // temp = (force + polemass_length * np.square(theta_dot) * sintheta) / total_mass
            let temp = (force + &push) / &p.total_mass;
            // thetaacc = (gravity * sintheta - costheta * temp)
            //            / (length * (4.0 / 3.0 - masspole * np.square(costheta) / total_mass))
            let thetaacc =
                (p.gravity.clone() * &sintheta - costheta.clone() * &temp) / &denominator;
            // xacc = temp - polemass_length * thetaacc * costheta / total_mass
            let xacc = temp - p.polemass_length.clone() * &thetaacc * &costheta / &p.total_mass;
            (xacc, thetaacc)
        };
        let right = accelerations(p.force_mag.clone());
        let left = accelerations(-p.force_mag.clone());
        let (xacc, thetaacc) = if action == 1 { right } else { left };
        // euler
        let next = [
            x.clone() + p.tau.clone() * x_dot,
            x_dot.clone() + p.tau.clone() * &xacc,
            theta.clone() + p.tau.clone() * theta_dot,
            theta_dot.clone() + p.tau.clone() * &thetaacc,
        ];
        // One branch for the four tests (`&`, not `&&`); which component failed is found out of line.
        if !next.iter().fold(true, |ok, v| ok & v.is_finite()) {
            return Err(non_finite(&next));
        }
        let terminated = terminal(p, &next)?;
        *state = next;
        Ok(terminated)
    }

    /// Gymnasium's termination test `x < −x_max ∨ x > x_max ∨ θ < −θ_max ∨ θ > θ_max` (strict).
    ///
    /// Decided in Kleene's three-valued logic: true if some comparison is certainly true, false if
    /// all are certainly false.
    ///
    /// # Errors
    /// [`Undecidable`] otherwise (an interval straddles a threshold, or a NaN).
    #[inline]
    pub fn is_terminal(&self, state: &[S; 4]) -> Result<bool, Undecidable> {
        terminal(&CartPoleParams::gymnasium(), state)
    }
}

/// [`CartPoleDynamics::is_terminal`] with the constants `p`.
#[inline]
fn terminal<S: Scalar>(p: &CartPoleParams<S>, state: &[S; 4]) -> Result<bool, Undecidable> {
    let tests = [
        (&state[0], -p.x_threshold.clone(), Ordering::Less),
        (&state[0], p.x_threshold.clone(), Ordering::Greater),
        (&state[2], -p.theta_threshold.clone(), Ordering::Less),
        (&state[2], p.theta_threshold.clone(), Ordering::Greater),
    ]
    .map(|(v, bound, side)| v.certain_cmp(&bound).map(|o| o == side));
    // `|`, not `||`: the four tests without a branch each.
    if tests.iter().fold(false, |any, t| any | (*t == Some(true))) {
        Ok(true)
    } else if tests.iter().fold(false, |any, t| any | t.is_none()) {
        Err(undecidable_termination())
    } else {
        Ok(false)
    }
}

/// The first non-finite component of `state`, as an error (the cold path of
/// [`CartPoleDynamics::step_in_place`]).
#[cold]
#[inline(never)]
fn non_finite<S: Scalar>(state: &[S; 4]) -> EnvError {
    let what = STATE_NAMES
        .into_iter()
        .zip(state)
        .find_map(|(what, v)| (!v.is_finite()).then_some(what))
        .unwrap_or(STATE_NAMES[0]);
    EnvError::NonFinite { what }
}

#[cold]
#[inline(never)]
fn undecidable_termination() -> Undecidable {
    Undecidable {
        what: "CartPole termination test (|x| > 2.4 or |theta| > 12 degrees)",
    }
}

#[cold]
#[inline(never)]
fn invalid_action(action: usize) -> EnvError {
    EnvError::InvalidAction {
        action: action.to_string(),
        expected: "0 (push left) or 1 (push right)",
    }
}

/// One step of CartPole-v1's dynamics from `state` under `action`: the next state and whether it is
/// terminal (the pure function behind `ilopt replay cartpole`). See [`CartPoleDynamics::step`],
/// which avoids rebuilding the constants on every call.
///
/// # Errors
/// As [`CartPoleDynamics::step`].
pub fn cartpole_step<S: Real>(state: &[S; 4], action: usize) -> Result<([S; 4], bool), EnvError> {
    CartPoleDynamics::new().step(state, action)
}

/// A reset state: each component uniform on `[−0.05, 0.05]`, drawn as numpy's
/// `Generator.uniform(low, high)` does, `low + (high − low)·u` with `u` uniform on `[0, 1)` (53 random
/// bits), in `f64` (the rounding can reach `high`).
pub fn sample_reset_state(rng: &mut KitRng) -> [f64; 4] {
    let low = f64::from_ratio(-1, 20);
    let high = f64::from_ratio(1, 20);
    std::array::from_fn(|_| {
        let u: f64 = rng.random();
        low + (high - low) * u
    })
}

/// Gymnasium's observation: the state cast to float32 (`np.array(self.state, dtype=np.float32)`,
/// round to nearest). For intervals this is the midpoint's cast.
pub fn gymnasium_observation<S: Scalar>(state: &[S; 4]) -> [f32; 4] {
    // `as` rounds to nearest, ties to even, as numpy's cast does.
    std::array::from_fn(|i| state[i].to_f64() as f32)
}

/// One CartPole episode's mechanics, shared by the Gymnasium environment [`CartPole`] and the
/// imitation-learning task (`task::cartpole`): the state, the steps taken, and one step of the
/// dynamics under a time limit.
#[derive(Debug, Clone, PartialEq)]
pub struct CartPoleEpisode<S> {
    /// [x, ẋ, θ, θ̇].
    pub state: [S; 4],
    /// Steps taken so far.
    pub steps: usize,
}

/// How a CartPole step ended the episode, in Gymnasium's two flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepEnd {
    /// The next state is terminal (the pole fell or the cart left the track).
    pub terminated: bool,
    /// The step reached the time limit.
    pub truncated: bool,
}

impl<S: Real> CartPoleEpisode<S> {
    /// An episode at `state`, no step taken.
    pub fn at(state: [S; 4]) -> Self {
        Self { state, steps: 0 }
    }

    /// A new episode from Gymnasium's reset law ([`sample_reset_state`]), its `f64` draws
    /// converted exactly into `S` (a float, a rational, or a point interval).
    #[inline]
    pub fn reset(rng: &mut KitRng) -> Self {
        let s = sample_reset_state(rng);
        Self::at(std::array::from_fn(|i| {
            S::from_binary64(s[i]).expect("the reset law draws finite values")
        }))
    }

    /// One step under `action` ([`CartPoleDynamics::step_in_place`]) with the time limit
    /// `max_steps`: the step that brings the episode to `max_steps` steps is truncated
    /// (Gymnasium's `TimeLimit`).
    ///
    /// # Errors
    /// As [`CartPoleDynamics::step`]; the episode is then unchanged.
    #[inline(always)]
    pub fn advance(
        &mut self,
        dynamics: &CartPoleDynamics<S>,
        action: usize,
        max_steps: usize,
    ) -> Result<StepEnd, EnvError> {
        let terminated = dynamics.step_in_place(&mut self.state, action)?;
        self.steps += 1;
        Ok(StepEnd {
            terminated,
            truncated: self.steps >= max_steps,
        })
    }
}

/// The CartPole-v1 environment: [`CartPoleDynamics`] with a reset distribution, a reward of 1 per
/// step (the terminating step included) and a time limit ([`MAX_EPISODE_STEPS`] by default).
#[derive(Debug, Clone)]
pub struct CartPole<S> {
    dynamics: CartPoleDynamics<S>,
    episode: Option<CartPoleEpisode<S>>,
    over: bool,
    max_episode_steps: usize,
}

impl<S: Real> Default for CartPole<S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<S: Real> CartPole<S> {
    /// `gym.make("CartPole-v1")`: time limit [`MAX_EPISODE_STEPS`].
    pub fn new() -> Self {
        Self::with_max_episode_steps(MAX_EPISODE_STEPS)
    }

    /// CartPole with another time limit: the step that brings the episode to `max_episode_steps`
    /// steps is `truncated` (Gymnasium's `TimeLimit`).
    pub fn with_max_episode_steps(max_episode_steps: usize) -> Self {
        CartPole {
            dynamics: CartPoleDynamics::new(),
            episode: None,
            over: false,
            max_episode_steps,
        }
    }

    /// The current state (Gymnasium's `env.unwrapped.state`), `None` before the first reset.
    pub fn state(&self) -> Option<&[S; 4]> {
        self.episode.as_ref().map(|e| &e.state)
    }

    /// Steps taken in the current episode.
    pub fn elapsed_steps(&self) -> usize {
        self.episode.as_ref().map_or(0, |e| e.steps)
    }

    /// The dynamics.
    pub fn dynamics(&self) -> &CartPoleDynamics<S> {
        &self.dynamics
    }

    /// Starts a new episode from a given state (as assigning `env.unwrapped.state` right after a
    /// reset) and returns its observation.
    pub fn reset_to(&mut self, state: [S; 4]) -> [S; 4] {
        self.episode = Some(CartPoleEpisode::at(state.clone()));
        self.over = false;
        state
    }
}

impl<S: Real> Env<S> for CartPole<S> {
    type Obs = [S; 4];
    type Action = usize;

    /// The initial state of [`CartPoleEpisode::reset`].
    fn reset(&mut self, rng: &mut KitRng) -> [S; 4] {
        self.reset_to(CartPoleEpisode::reset(rng).state)
    }

    fn step(&mut self, action: usize) -> Result<Step<S, [S; 4]>, EnvError> {
        let episode = self.episode.as_mut().ok_or(EnvError::NotReset)?;
        if self.over {
            return Err(EnvError::EpisodeOver);
        }
        if action > 1 {
            // Invalid input does not end the episode.
            return Err(invalid_action(action));
        }
        let end = match episode.advance(&self.dynamics, action, self.max_episode_steps) {
            Ok(end) => end,
            Err(e) => {
                self.over = true;
                return Err(e);
            }
        };
        let StepEnd {
            terminated,
            truncated,
        } = end;
        self.over = terminated || truncated;
        let next = episode.state.clone();
        Ok(Step {
            observation: next,
            reward: S::one(),
            terminated,
            truncated,
        })
    }
}
