"""What the kit adds to a Gymnasium environment's own cost: environment steps per second of
training through `ilopt.GymTask` against plain Python loops over the same environment.

    python python/bench/gym_overhead.py [ENV_ID] [--steps N] [--repeats R]

Three loops over N environment steps, each R times alternately, medians of CPU time per step
(user + system of this process):

- `env.step` with a constant action (the environment's own cost);
- `env.step` with the expert's action (`expert(obs)` every step: what a Python imitation loop pays
  at least, since every visited state needs its label);
- `ilopt.run` with SGD on the causal eq. 3.15 estimate (one trajectory of 200 decisions per
  gradient, checkpoints only at 0 and the end, one evaluation episode each), per training step
  (the run's `env_steps`).

The kit's share is its time per step over the plain loop's, minus one. The expert is CartPole's
balancing rule (`obs[2] + 0.5 obs[3] > 0`), so the default environment is CartPole-v1.
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


def kit(env_id, n):
    task = ilopt.GymTask(env_id, expert=expert, steps=200)
    config = {
        "algorithm": {"algorithm": "sgd", "form": "causal", "step": {"kind": "constant", "eta": 1e-3}},
        "run": {"budget_calls": n, "seeds": [1]},
        "evaluation": {"every_calls": n, "episodes": 1},
    }
    start = cpu()
    r = ilopt.run(config, task=task, quiet=True)
    elapsed = cpu() - start
    steps = int(r.checkpoints[1]["env_steps"][-1])
    return elapsed / steps


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("env", nargs="?", default="CartPole-v1")
    p.add_argument("--steps", type=int, default=100_000)
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()
    env = gymnasium.make(a.env)
    constant = env.action_space.sample() * 0
    times = {"constant": [], "expert": [], "kit": []}
    for _ in range(a.repeats):
        times["constant"].append(plain(env, a.steps, lambda obs: constant))
        times["expert"].append(plain(env, a.steps, expert))
        times["kit"].append(kit(a.env, a.steps))
    med = {k: statistics.median(v) for k, v in times.items()}
    for k, v in med.items():
        print(f"{k:>8}: {v * 1e6:8.2f} µs CPU per step ({1 / v:,.0f} steps/s)")
    print(f"kit over env.step alone: +{(med['kit'] / med['constant'] - 1) * 100:.0f} %")
    print(f"kit over env.step + expert: +{(med['kit'] / med['expert'] - 1) * 100:.0f} %")


if __name__ == "__main__":
    main()
