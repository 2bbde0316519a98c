#!/usr/bin/env python3
"""Reference trajectories of Gymnasium's CartPole-v1, for the bit-for-bit test `tests/cartpole.rs`.

Usage:  pip install gymnasium numpy && python3 scripts/cartpole_reference.py [OUT]
        (OUT defaults to tests/data/cartpole_reference.json)

For each case, Gymnasium's own `CartPoleEnv` (through `gym.make("CartPole-v1").unwrapped`, so that
neither the time limit nor the order checks interfere) is put in a chosen float64 initial state by
assigning `env.unwrapped.state`, then stepped with a fixed action sequence of 200 actions. After each
step the float64 state `env.unwrapped.state` and the `terminated` flag are recorded (and, for the first
10 steps, the float32 observation that `step` returns). Stepping goes on
after termination (Gymnasium only warns), so the dynamics are compared there too.

Cases (all seeded, so the file is reproducible):
  * 12 initial states drawn like `reset()` (uniform in [-0.05, 0.05)^4), with action sequences that are
    either i.i.d. fair coin flips, constant, alternating, or recorded from a simple balancing rule
    (long, non-terminating trajectories);
  * 4 wider initial states (|theta_dot| up to 2, |x_dot| up to 2) that terminate within a few steps;
  * 8 states exactly on or one float above/below a termination threshold with zero velocity, so that
    the first step keeps x (resp. theta) unchanged: they pin down the strict inequalities and the exact
    float64 thresholds 2.4 and 12 * 2 * math.pi / 360.

Every float is written as the string of its `repr`, which round-trips exactly; strings (not JSON
numbers) so that any JSON reader can parse them exactly with a correctly rounded decimal parser.
"""

import json
import math
import sys
import warnings

import gymnasium as gym
import numpy as np

STEPS = 200
OBSERVED_STEPS = 10  # Gymnasium's float32 observations are recorded for the first steps only


def f(x):
    """A float64 as its exact round-trip text."""
    return repr(float(x))


def balancing_actions(env, init, rng, steps):
    """Actions of a noisy balancing rule, recorded while stepping a copy of the environment."""
    env.unwrapped.state = np.array(init, dtype=np.float64)
    env.unwrapped.steps_beyond_terminated = None
    actions = []
    for _ in range(steps):
        x, x_dot, theta, theta_dot = env.unwrapped.state
        u = theta + 0.5 * theta_dot + 0.01 * x + 0.05 * x_dot
        a = 1 if u > 0 else 0
        if rng.random() < 0.1:
            a = 1 - a
        actions.append(a)
        env.unwrapped.step(a)
    return actions


def run_case(env, init, actions):
    env.unwrapped.state = np.array(init, dtype=np.float64)
    env.unwrapped.steps_beyond_terminated = None
    states, terminated, observations = [], [], []
    for t, a in enumerate(actions):
        obs, _, term, _, _ = env.unwrapped.step(a)
        s = env.unwrapped.state
        assert s.dtype == np.float64 and obs.dtype == np.float32
        states.append([f(v) for v in s])
        terminated.append(bool(term))
        if t < OBSERVED_STEPS:
            observations.append([f(v) for v in obs])
    return states, terminated, observations


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "tests/data/cartpole_reference.json"
    warnings.filterwarnings("ignore")
    gym.logger.min_level = 40  # no "step() after terminated" warnings
    env = gym.make("CartPole-v1")
    env.reset(seed=0)
    u = env.unwrapped
    rng = np.random.default_rng(20251122)

    cases = []

    def add(name, init, actions):
        states, terminated, observations = run_case(env, init, actions)
        cases.append(
            {
                "name": name,
                "init": [f(v) for v in init],
                "actions": [int(a) for a in actions],
                "states": states,
                "terminated": terminated,
                "observations_float32": observations,
            }
        )

    kinds = ["random", "random", "balance", "balance", "balance", "balance",
             "ones", "zeros", "alternate", "random", "balance", "random"]
    for i, kind in enumerate(kinds):
        init = rng.uniform(-0.05, 0.05, size=4)
        if kind == "random":
            actions = [int(a) for a in rng.integers(0, 2, size=STEPS)]
        elif kind == "ones":
            actions = [1] * STEPS
        elif kind == "zeros":
            actions = [0] * STEPS
        elif kind == "alternate":
            actions = [i % 2 for i in range(STEPS)]
        else:
            actions = balancing_actions(env, init, rng, STEPS)
        add(f"reset-range-{i}-{kind}", init, actions)

    for i in range(4):
        init = rng.uniform(-1.0, 1.0, size=4) * np.array([1.0, 2.0, 0.2, 2.0])
        actions = [int(a) for a in rng.integers(0, 2, size=STEPS)]
        add(f"wide-{i}", init, actions)

    xt = u.x_threshold
    tt = u.theta_threshold_radians
    edge = [
        ("x-at-threshold", [xt, 0.0, 0.0, 0.0]),
        ("x-one-ulp-beyond", [math.nextafter(xt, math.inf), 0.0, 0.0, 0.0]),
        ("minus-x-at-threshold", [-xt, 0.0, 0.0, 0.0]),
        ("minus-x-one-ulp-beyond", [math.nextafter(-xt, -math.inf), 0.0, 0.0, 0.0]),
        ("theta-at-threshold", [0.0, 0.0, tt, 0.0]),
        ("theta-one-ulp-beyond", [0.0, 0.0, math.nextafter(tt, math.inf), 0.0]),
        ("minus-theta-at-threshold", [0.0, 0.0, -tt, 0.0]),
        ("minus-theta-one-ulp-beyond", [0.0, 0.0, math.nextafter(-tt, -math.inf), 0.0]),
    ]
    for name, init in edge:
        actions = [int(a) for a in rng.integers(0, 2, size=STEPS)]
        add(name, init, actions)

    doc = {
        "source": "scripts/cartpole_reference.py",
        "gymnasium_version": gym.__version__,
        "numpy_version": np.__version__,
        "x_threshold": f(xt),
        "theta_threshold_radians": f(tt),
        "cases": cases,
    }
    with open(out, "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")
    n_steps = sum(len(c["actions"]) for c in cases)
    n_term = sum(any(c["terminated"]) for c in cases)
    print(f"wrote {out}: {len(cases)} cases, {n_steps} steps, {n_term} cases terminate")


if __name__ == "__main__":
    main()
