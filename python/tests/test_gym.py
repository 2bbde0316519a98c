"""Gymnasium environments as tasks (ilopt.GymTask): the kit's algorithms, estimators and
checkpoints on an environment that steps in Python, with an expert written in Python."""

import math
import threading

import gymnasium
import numpy as np
import pytest

import ilopt


def balance(obs):
    """A CartPole expert: push towards where the pole falls (balances 500 steps)."""
    return int(obs[2] + 0.5 * obs[3] + 0.01 * obs[0] + 0.1 * obs[1] > 0)


def pendulum_pd(obs):
    """A Pendulum expert: a PD controller on the angle, clipped to the torque limit."""
    angle = math.atan2(obs[1], obs[0])
    return np.clip([-10.0 * angle - 2.0 * obs[2]], -2.0, 2.0)


DAGGER = {
    "algorithm": "dagger",
    "trajectories_per_iteration": 1,
    "aggregate": True,
    "retrain": "warm-start",
    "beta": {"kind": "exponential", "p": 0.5},
    "inner": {
        "iterations": 50,
        "rule": {"rule": "adam", "alpha": 0.05, "beta1": 0.9, "beta2": 0.999, "epsilon": 1e-8},
    },
}

ADAM = {
    "algorithm": "adam",
    "form": "causal",
    "alpha": 0.05,
    "beta1": 0.9,
    "beta2": 0.999,
    "epsilon": 1e-8,
}


def config(algorithm, budget, seeds=(1,), every=None, episodes=5):
    evaluation = {"episodes": episodes}
    if every is not None:
        evaluation["every_calls"] = every
    return {
        "algorithm": algorithm,
        "run": {"budget_calls": budget, "seeds": list(seeds)},
        "evaluation": evaluation,
    }


def final(result, seed, column):
    return result.checkpoints[seed][column][-1]


def test_dagger_learns_to_balance_gymnasium_cartpole():
    task = ilopt.GymTask("CartPole-v1", expert=balance, steps=200)
    r = ilopt.run(config(DAGGER, 40_000, every=10_000), task=task)
    assert r.summary["task"] == "gym-cartpole-v1"
    assert r.summary["policy"] == "softmax"
    assert r.summary["dim"] == 2 * 5
    scores = r.checkpoints[1]["score"]
    assert scores[0] < 100, scores  # θ = 0 acts with one action: the pole falls
    assert scores[-1] == 500.0, scores  # every evaluation episode balanced to the time limit
    assert final(r, 1, "eval_loss") < r.checkpoints[1]["eval_loss"][0]


def test_adam_with_a_baseline_learns_to_balance_gymnasium_cartpole():
    """Adam on the oracle's eq. 3.15 estimate, 8 trajectories per estimate with the
    leave-one-out baseline."""
    task = ilopt.GymTask(gymnasium.make("CartPole-v1"), expert=balance, steps=200)
    c = config(ADAM, 160_000, every=40_000)
    c["run"]["trajectories_per_gradient"] = 8
    c["run"]["baseline"] = {"kind": "leave-one-out"}
    r = ilopt.run(c, task=task)
    scores = r.checkpoints[1]["score"]
    assert scores[0] < 100 and scores[-1] >= 475.0, scores
    assert r.summary["runs"][0]["termination"] == "gradient-budget"


def test_a_box_action_space_trains_the_linear_gaussian_learner():
    task = ilopt.GymTask("Pendulum-v1", expert=pendulum_pd, steps=100, sigma=0.5)
    r = ilopt.run(config(DAGGER, 20_000, every=5000), task=task)
    assert r.summary["policy"] == "linear-gaussian"
    assert r.summary["dim"] == 1 * 4
    loss = r.checkpoints[1]["eval_loss"]
    assert np.all(np.isfinite(loss))
    assert loss[-1] < 0.5 * loss[0], loss


def test_runs_are_reproduced_by_their_seeds_and_write_the_files_of_ilopt_run(tmp_path):
    task = ilopt.GymTask("CartPole-v1", expert=balance, steps=50, features=lambda o: [o[2], o[3], 1.0])
    c = config(ADAM, 3000, seeds=(2, 1), every=1000, episodes=2)
    a = ilopt.run(c, task=task, out=tmp_path / "a")
    b = ilopt.run(c, task=task)
    assert a.summary == b.summary
    for seed in (1, 2):
        for column, values in a.checkpoints[seed].items():
            np.testing.assert_array_equal(values, b.checkpoints[seed][column], err_msg=column)
    assert a.summary["dim"] == 2 * 3
    for name in ["config.toml", "summary.json", "seed-1.csv", "seed-2.json", "theta-seed-1.json"]:
        assert (tmp_path / "a" / name).is_file(), name
    assert 'name = "custom"' in (tmp_path / "a" / "config.toml").read_text()


class SeedLog(gymnasium.Wrapper):
    """Records the seed of every reset (None for an unseeded one)."""

    def __init__(self, env):
        super().__init__(env)
        self.seeds = []

    def reset(self, *, seed=None, options=None):
        self.seeds.append(seed)
        return self.env.reset(seed=seed, options=options)


def test_a_seed_is_passed_at_each_seeds_first_training_episode_and_every_evaluation_episode():
    env, eval_env = SeedLog(gymnasium.make("CartPole-v1")), SeedLog(gymnasium.make("CartPole-v1"))
    task = ilopt.GymTask(env, expert=balance, steps=50, eval_env=eval_env)
    env.seeds.clear()
    eval_env.seeds.clear()
    r = ilopt.run(config(ADAM, 3000, seeds=(1, 2), every=1000, episodes=2), task=task)
    seeded = [i for i, s in enumerate(env.seeds) if s is not None]
    assert len(env.seeds) > 10 and len(seeded) == 2, env.seeds
    assert seeded[0] == 0 and env.seeds[seeded[0]] != env.seeds[seeded[1]]
    assert all(s is not None for s in eval_env.seeds) and len(eval_env.seeds) == 2 * 4 * 2
    # every checkpoint meets the same evaluation episodes
    assert eval_env.seeds[:2] == eval_env.seeds[2:4]


def test_training_depends_neither_on_the_seeds_before_nor_on_the_checkpoint_schedule():
    task = ilopt.GymTask("CartPole-v1", expert=balance, steps=50)
    both = ilopt.run(config(ADAM, 3000, seeds=(2, 1), every=1000, episodes=2), task=task)
    alone = ilopt.run(config(ADAM, 3000, seeds=(1,), every=3000, episodes=1), task=task)
    np.testing.assert_array_equal(both.theta[1], alone.theta[1])
    assert final(both, 1, "env_steps") == final(alone, 1, "env_steps")
    assert not np.array_equal(both.theta[1], both.theta[2])


def test_an_environment_that_cannot_be_copied_needs_an_eval_env():
    class Uncopyable(gymnasium.Wrapper):
        def __deepcopy__(self, memo):
            raise TypeError("holds a simulator handle")

    env = Uncopyable(gymnasium.make("CartPole-v1"))
    with pytest.raises(ilopt.IloptError, match="eval_env: .*could not be deep-copied .*holds a simulator handle"):
        ilopt.GymTask(env, expert=balance)
    task = ilopt.GymTask(env, expert=balance, eval_env="CartPole-v1")
    assert task.eval_env is not env
    with pytest.raises(ilopt.IloptError, match="eval_env: its action space"):
        ilopt.GymTask(env, expert=balance, eval_env="Pendulum-v1")
    with pytest.raises(ilopt.IloptError, match="eval_env must be a gymnasium.Env or an id .* got int"):
        ilopt.GymTask(env, expert=balance, eval_env=42)


def test_bad_gym_tasks_raise_with_a_message():
    with pytest.raises(ilopt.IloptError, match="Discrete\\(2\\)"):
        ilopt.run(config(DAGGER, 30_000), task=ilopt.GymTask("CartPole-v1", expert=lambda o: 7))
    with pytest.raises(ilopt.IloptError, match="expert\\(observation\\)"):
        ilopt.run(
            config(DAGGER, 30_000),
            task=ilopt.GymTask("CartPole-v1", expert=lambda o: 1 / 0 if o[0] > -10 else 0),
        )
    with pytest.raises(ilopt.IloptError, match="Box action space 1"):
        ilopt.run(config(DAGGER, 30_000), task=ilopt.GymTask("Pendulum-v1", expert=lambda o: [0.0, 0.0]))
    with pytest.raises(ilopt.IloptError, match="features\\(observation\\) has 2 entries"):
        counter = iter(range(10**9))
        ilopt.run(
            config(DAGGER, 30_000),
            task=ilopt.GymTask(
                "CartPole-v1", expert=balance, features=lambda o: [1.0] * (3 if next(counter) == 0 else 2)
            ),
        )
    with pytest.raises(ilopt.IloptError, match="Discrete or Box"):
        ilopt.GymTask(
            gymnasium.wrappers.TimeLimit(MultiDiscreteEnv(), 10), expert=lambda o: [0, 0]
        )
    with pytest.raises(ilopt.IloptError, match="after_end"):
        ilopt.run(config(DAGGER, 30_000), task=ilopt.GymTask("CartPole-v1", expert=balance, after_end="absorb"))
    with pytest.raises(ilopt.IloptError, match="leaves out \\[task\\]"):
        c = config(DAGGER, 30_000)
        c["task"] = {"name": "cartpole"}
        ilopt.run(c, task=ilopt.GymTask("CartPole-v1", expert=balance))
    with pytest.raises(ilopt.IloptError, match="steps"):
        ilopt.GymTask("CartPole-v1", expert=balance, steps=0)
    with pytest.raises(ilopt.IloptError, match="the first step alone costs at least"):
        ilopt.run(config(DAGGER, 500), task=ilopt.GymTask("CartPole-v1", expert=balance))
    with pytest.raises(TypeError, match="GymTask"):
        ilopt.run(config(DAGGER, 30_000), task="CartPole-v1")


class MultiDiscreteEnv(gymnasium.Env):
    """An environment whose actions are neither Discrete nor Box."""

    observation_space = gymnasium.spaces.Box(-1.0, 1.0, shape=(2,))
    action_space = gymnasium.spaces.MultiDiscrete([2, 2])

    def reset(self, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(2, dtype=np.float32), {}

    def step(self, action):
        return np.zeros(2, dtype=np.float32), 0.0, False, False, {}


class ScriptedCartPole(gymnasium.Wrapper):
    """CartPole-v1 whose step or reset misbehaves after a number of calls, and which records the
    thread of every call."""

    def __init__(self, bad_step=None, bad_reset=None, after=50):
        super().__init__(gymnasium.make("CartPole-v1"))
        self.bad_step, self.bad_reset, self.after = bad_step, bad_reset, after
        self.steps, self.resets, self.threads = 0, 0, set()

    def reset(self, *, seed=None, options=None):
        self.threads.add(threading.get_ident())
        self.resets += 1
        if self.bad_reset is not None and self.resets > 1:
            return self.bad_reset()
        return self.env.reset(seed=seed, options=options)

    def step(self, action):
        self.threads.add(threading.get_ident())
        self.steps += 1
        if self.bad_step is not None and self.steps > self.after:
            return self.bad_step()
        return self.env.step(action)


def raise_value_error():
    raise ValueError("the simulator diverged")


def test_a_gym_run_calls_python_on_the_calling_thread_once_per_decision():
    env = ScriptedCartPole()
    calls = []

    def expert(obs):
        calls.append(threading.get_ident())
        return balance(obs)

    task = ilopt.GymTask(env, expert=expert, steps=50)
    calls.clear()
    r = ilopt.run(config(ADAM, 2000, every=1000, episodes=2), task=task)
    assert env.threads == task.eval_env.threads == {threading.get_ident()}
    assert set(calls) == {threading.get_ident()}
    # one expert call per training decision and per evaluation decision; the evaluation episodes
    # step the second environment (a deep copy of env)
    eval_steps = len(calls) - int(final(r, 1, "expert_queries"))
    assert final(r, 1, "env_steps") == 2000 and final(r, 1, "expert_queries") == 2000
    assert env.steps == 2000 and task.eval_env.steps == eval_steps > 0


def test_a_failing_environment_raises_with_its_message():
    """Failures at the first checkpoint's evaluation raise; a failure during training ends the seed's
    run with the message as its termination."""
    with pytest.raises(ilopt.IloptError, match="env.step\\(.*the simulator diverged"):
        task = ilopt.GymTask(ScriptedCartPole(bad_step=raise_value_error, after=0), expert=balance)
        ilopt.run(config(DAGGER, 30_000), task=task)
    with pytest.raises(ilopt.IloptError, match="env.reset\\(seed=\\d+\\): .*the simulator diverged"):
        task = ilopt.GymTask(ScriptedCartPole(bad_reset=raise_value_error), expert=balance)
        ilopt.run(config(DAGGER, 30_000), task=task)
    with pytest.raises(ilopt.IloptError, match="not \\(observation, reward, terminated, truncated, info\\)"):
        task = ilopt.GymTask(ScriptedCartPole(bad_step=lambda: None, after=0), expert=balance)
        ilopt.run(config(DAGGER, 30_000), task=task)
    with pytest.raises(ilopt.IloptError, match="returned the reward NaN"):
        nan = (np.zeros(4, dtype=np.float32), float("nan"), False, False, {})
        task = ilopt.GymTask(ScriptedCartPole(bad_step=lambda: nan, after=0), expert=balance)
        ilopt.run(config(DAGGER, 30_000), task=task)
    env = ScriptedCartPole(bad_step=raise_value_error, after=1000)
    r = ilopt.run(config(ADAM, 3000, episodes=1), task=ilopt.GymTask(env, expert=balance, steps=100))
    termination = r.summary["runs"][0]["termination"]
    assert "env.step(" in termination and "the simulator diverged" in termination, termination
