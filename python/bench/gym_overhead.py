"""What the kit adds to a Gymnasium environment's own cost: environment steps per second of
training through `ilopt.GymTask` against plain Python loops over the same environment.

    python python/bench/gym_overhead.py [ENV_ID] [--steps N] [--repeats R]

Four loops over about N environment steps, each R times alternately, medians of CPU time per
step (user + system of this process):

- `env.step` with a constant action (the environment's own cost);
- `env.step` with the expert's action (`expert(obs)` every step: what a Python imitation loop pays
  at least, since every visited state needs its label);
- `ilopt.run` with SGD on the causal eq. 3.15 estimate (one trajectory of 200 decisions per
  gradient, checkpoints only at 0 and the end, one evaluation episode each), per training step
  (the run's `env_steps`);
- the same run's calls replayed in plain Python: every `env.reset(seed=...)` (the seed's first
  episode) or `env.reset()` (the others) and every `env.step(action)` the run made on its
  training environment (recorded once by a wrapper, untimed), with `expert(obs)` at every step.
  This is the environment's and the expert's own cost along the run's trajectory: the learner's
  episodes end sooner than the expert's, so it resets more often.

The kit's share is its time per step over a plain loop's, minus one: over the replay it is what the
kit itself adds. The expert is CartPole's balancing rule (`obs[2] + 0.5 obs[3] > 0`), so the
default environment is CartPole-v1.
"""

import argparse
import resource
import statistics
import time

import gymnasium

import ilopt


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def expert(obs):
    return int(obs[2] + 0.5 * obs[3] > 0)


def plain(env, n, act):
    obs, _ = env.reset(seed=0)
    start = cpu()
    for _ in range(n):
        obs, _, terminated, truncated, _ = env.step(act(obs))
        if terminated or truncated:
            obs, _ = env.reset()
    return (cpu() - start) / n


def kit_config(n):
    return {
        "algorithm": {"algorithm": "sgd", "form": "causal", "step": {"kind": "constant", "eta": 1e-3}},
        "run": {"budget_calls": n, "seeds": [1]},
        "evaluation": {"every_calls": n, "episodes": 1},
    }


def kit(env_id, n):
    task = ilopt.GymTask(env_id, expert=expert, steps=200)
    start = cpu()
    r = ilopt.run(kit_config(n), task=task, quiet=True)
    elapsed = cpu() - start
    steps = int(r.checkpoints[1]["env_steps"][-1])
    return elapsed / steps


class Recorder(gymnasium.Wrapper):
    """Logs every reset's seed (as a 1-tuple, None for an unseeded reset) and every step's
    action."""

    def __init__(self, env):
        super().__init__(env)
        self.log = []

    def reset(self, *, seed=None, options=None):
        self.log.append((seed,))
        return self.env.reset(seed=seed, options=options)

    def step(self, action):
        self.log.append(action)
        return self.env.step(action)


def record(env_id, n):
    """The calls a kit run makes on its training environment, without GymTask's own first reset
    (it reads the features' length); the evaluation episodes step a copy of the environment."""
    recorder = Recorder(gymnasium.make(env_id))
    task = ilopt.GymTask(recorder, expert=expert, steps=200)
    del recorder.log[:]
    ilopt.run(kit_config(n), task=task, quiet=True)
    return recorder.log


def replay(env, log):
    steps = sum(not isinstance(e, tuple) for e in log)
    start = cpu()
    for e in log:
        if isinstance(e, tuple):
            obs, _ = env.reset(seed=e[0])
        else:
            expert(obs)
            obs, _, _, _, _ = env.step(e)
    return (cpu() - start) / steps


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("env", nargs="?", default="CartPole-v1")
    p.add_argument("--steps", type=int, default=100_000)
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()
    env = gymnasium.make(a.env)
    constant = env.action_space.sample() * 0
    log = record(a.env, a.steps)
    times = {"constant": [], "expert": [], "kit": [], "replay": []}
    for _ in range(a.repeats):
        times["constant"].append(plain(env, a.steps, lambda obs: constant))
        times["expert"].append(plain(env, a.steps, expert))
        times["kit"].append(kit(a.env, a.steps))
        times["replay"].append(replay(env, log))
    med = {k: statistics.median(v) for k, v in times.items()}
    for k, v in med.items():
        print(f"{k:>8}: {v * 1e6:8.2f} µs CPU per step ({1 / v:,.0f} steps/s)")
    print(f"kit over env.step alone: +{(med['kit'] / med['constant'] - 1) * 100:.0f} %")
    print(f"kit over env.step + expert: +{(med['kit'] / med['expert'] - 1) * 100:.0f} %")
    print(f"kit over its own steps replayed: +{(med['kit'] / med['replay'] - 1) * 100:.0f} %")


if __name__ == "__main__":
    main()
