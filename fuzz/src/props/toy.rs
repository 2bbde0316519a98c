//! The toy-MDP parser's property and the random MDPs and trajectories the oracle properties draw.

use ilopt::scalar::BigRational;
use ilopt::toy::{
    MAX_ACTIONS, MAX_HORIZON, MAX_STATES, PolicyKind, Termination, ToyMdp, ToyTrajectory,
};
use num_traits::{One, Signed, Zero};

/// Arbitrary bytes → [`ToyMdp::from_json_str`]: never a panic; an error has a message; an accepted
/// MDP satisfies every invariant of `docs/formats/toy-mdp.md`.
pub fn check_toy_parser(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match ToyMdp::from_json_str(text) {
        Ok(mdp) => check_mdp_invariants(&mdp),
        Err(e) => assert!(!e.to_string().is_empty(), "empty error message"),
    }
}

/// The invariants of an accepted toy MDP (exact: rows sum to exactly 1).
pub fn check_mdp_invariants(m: &ToyMdp) {
    let (s, a) = (m.states, m.actions);
    assert!((1..=MAX_STATES).contains(&s), "states = {s}");
    assert!((2..=MAX_ACTIONS).contains(&a), "actions = {a}");
    assert!(
        (2..=MAX_HORIZON).contains(&m.horizon),
        "horizon = {}",
        m.horizon
    );
    let dist = |row: &[BigRational], what: &str| {
        assert_eq!(row.len(), s, "{what}: length");
        assert!(
            row.iter().all(|p| !p.is_negative()),
            "{what}: negative entry"
        );
        let sum = row
            .iter()
            .fold(<BigRational as Zero>::zero(), |acc, p| acc + p);
        assert!(sum.is_one(), "{what} sums to {sum}");
    };
    dist(&m.initial, "initial");
    assert_eq!(m.transition.len(), s);
    for (i, row) in m.transition.iter().enumerate() {
        assert_eq!(row.len(), a, "transition[{i}]: length");
        for (j, d) in row.iter().enumerate() {
            dist(d, &format!("transition[{i}][{j}]"));
        }
    }
    assert_eq!(m.expert.len(), s);
    assert!(
        m.expert.iter().all(|&e| e < a),
        "expert action out of range"
    );
    let p = &m.policy;
    assert_eq!(p.actions(), a);
    assert_eq!(p.groups.len(), s);
    let g = p.group_count();
    assert!(g >= 1 && g <= s, "group count {g}");
    assert!((0..g).all(|o| p.groups.contains(&o)), "a group is unused");
    assert!(p.groups.iter().all(|&o| o < g));
    match p.kind {
        PolicyKind::Direct => assert!(p.c.is_none(), "direct with c"),
        PolicyKind::RationalSoftmax | PolicyKind::TiedSoftmax => {
            assert!(p.c.as_ref().is_some_and(Signed::is_positive), "c not > 0")
        }
    }
    if p.kind == PolicyKind::TiedSoftmax {
        assert_eq!(a, 2, "tied-softmax with {a} actions");
    }
    assert_eq!(p.dim(), g * p.block());
    match &m.termination {
        Termination::Reset { terminal, law } => {
            assert_eq!(terminal.len(), s, "terminal: length");
            dist(law, "on_terminal.law");
            for (z, _) in terminal.iter().enumerate().filter(|(_, t)| **t) {
                assert!(law[z].is_zero(), "reset law has mass on terminal state {z}");
                assert!(
                    m.initial[z].is_zero(),
                    "initial law has mass on terminal state {z}"
                );
            }
        }
        Termination::Absorb { loss } => {
            assert_eq!(loss.len(), s, "on_terminal.loss: length");
            assert!(
                loss.iter().flatten().all(|c| !c.is_negative()),
                "negative absorbing loss"
            );
        }
        _ => {}
    }
    // The augmented chain (math.md §8) is a Markov kernel.
    for (i, row) in m.chain_transition().iter().enumerate() {
        for (j, d) in row.iter().enumerate() {
            dist(d, &format!("chain_transition[{i}][{j}]"));
        }
    }
}

// 2./3. The oracle on small MDPs, and the differential check f64 / Interval / BigRational.

/// A fraction of small integers (`den = 0` is written as such and must be rejected).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frac {
    /// Numerator.
    pub num: i16,
    /// Denominator.
    pub den: u8,
}

/// A small MDP described loosely; [`MdpSpec::to_json`] writes it in the toy-MDP format, where it
/// is either valid or rejected by the parser.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MdpSpec {
    /// S = `states % 4` (0 is rejected).
    pub states: u8,
    /// A = `actions % 4` (0 and 1 are rejected).
    pub actions: u8,
    /// T = `horizon % 5` (0 and 1 are rejected).
    pub horizon: u8,
    /// Entries of μ and P, used cyclically.
    pub probs: Vec<Frac>,
    /// Write every distribution as weights `|num| % 4` normalised to sum 1 (else raw `num/den`).
    pub normalize: bool,
    /// π*(s) = `expert[s] % (A + 1)` (A is rejected), cyclically.
    pub expert: Vec<u8>,
    /// 0 rational-softmax, 1 direct, 2 tied-softmax, 3 an unknown kind.
    pub kind: u8,
    /// The policy parameter c.
    pub c: Frac,
    /// Optional observation map (`groups[s] % (S + 1)`).
    pub groups: Option<Vec<u8>>,
}

impl MdpSpec {
    /// S, A, T as written to the file.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (
            usize::from(self.states % 4),
            usize::from(self.actions % 4),
            usize::from(self.horizon % 5),
        )
    }

    /// The toy-MDP JSON text.
    pub fn to_json(&self) -> String {
        let (s, a, t) = self.sizes();
        let fallback = [Frac { num: 1, den: 1 }];
        let probs: &[Frac] = if self.probs.is_empty() {
            &fallback
        } else {
            &self.probs
        };
        let mut next = 0usize;
        let mut row = |len: usize| -> serde_json::Value {
            let fr: Vec<Frac> = (0..len)
                .map(|_| {
                    let f = probs[next % probs.len()];
                    next += 1;
                    f
                })
                .collect();
            if self.normalize {
                let mut w: Vec<u32> = fr
                    .iter()
                    .map(|f| u32::from(f.num.unsigned_abs() % 4))
                    .collect();
                if w.iter().all(|&x| x == 0)
                    && let Some(first) = w.first_mut()
                {
                    *first = 1;
                }
                let sum: u32 = w.iter().sum();
                serde_json::Value::Array(w.iter().map(|x| format!("{x}/{sum}").into()).collect())
            } else {
                serde_json::Value::Array(
                    fr.iter()
                        .map(|f| format!("{}/{}", f.num, f.den).into())
                        .collect(),
                )
            }
        };
        let initial = row(s);
        let transition: Vec<serde_json::Value> = (0..s)
            .map(|_| serde_json::Value::Array((0..a).map(|_| row(s)).collect()))
            .collect();
        let expert: Vec<u64> = (0..s)
            .map(|i| {
                let e = self
                    .expert
                    .get(i % self.expert.len().max(1))
                    .copied()
                    .unwrap_or(0);
                u64::from(e) % (a as u64 + 1)
            })
            .collect();
        let mut policy = serde_json::json!({
            "kind": match self.kind % 4 {
                0 => "rational-softmax",
                1 => "direct",
                2 => "tied-softmax",
                _ => "softmax",
            }
        });
        if self.kind % 4 != 1 {
            policy["c"] = format!("{}/{}", self.c.num, self.c.den).into();
        }
        if let Some(g) = &self.groups {
            let g: Vec<u64> = (0..s)
                .map(|i| u64::from(g.get(i).copied().unwrap_or(0)) % (s as u64 + 1))
                .collect();
            policy["groups"] = g.into();
        }
        serde_json::json!({
            "states": s,
            "actions": a,
            "horizon": t,
            "initial": initial,
            "transition": transition,
            "expert": expert,
            "policy": policy,
        })
        .to_string()
    }
}

/// A trajectory given loosely: `conform` fits it to the MDP (lengths and ranges), otherwise it is
/// used as given (and should be rejected as foreign when it does not fit).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TrajSpec {
    /// States.
    pub states: Vec<u8>,
    /// Actions.
    pub actions: Vec<u8>,
    /// Expert labels.
    pub labels: Vec<u8>,
    /// Fit to the MDP.
    pub conform: bool,
}

impl TrajSpec {
    /// The trajectory for an MDP of S states, A actions, horizon T.
    pub fn build(&self, s: usize, a: usize, t: usize) -> ToyTrajectory {
        let cyc = |v: &[u8], i: usize| v.get(i % v.len().max(1)).copied().unwrap_or(0) as usize;
        if self.conform {
            ToyTrajectory {
                states: (0..t).map(|i| cyc(&self.states, i) % s).collect(),
                actions: (0..t - 1).map(|i| cyc(&self.actions, i) % a).collect(),
                labels: (0..t - 1).map(|i| cyc(&self.labels, i) % a).collect(),
            }
        } else {
            let raw = |v: &[u8]| v.iter().take(8).map(|&x| usize::from(x)).collect();
            ToyTrajectory {
                states: raw(&self.states),
                actions: raw(&self.actions),
                labels: raw(&self.labels),
            }
        }
    }
}
