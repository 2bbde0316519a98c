"""ilopt from Python: the kit's runs, oracle estimates and exact toy evaluations.

Each function goes through the same Rust route as the ``ilopt`` command line, so a seed gives
the same numbers as the CLI and bad input raises :class:`IloptError` with the CLI's message.

- :func:`run` — ``ilopt run``: train on a config (a dict of the TOML schema, or a path), on a
  built-in task or on any Gymnasium environment (:class:`GymTask`).
- :func:`oracle_estimate` — ``ilopt estimate``: one draw of the eq. 3.15 gradient estimate.
- :func:`toy_eval` — ``ilopt toy eval``: F, ∇F, E[g], E‖g‖² exactly, as ``Fraction``s.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import IloptError

__all__ = ["GymTask", "IloptError", "RunResult", "run", "oracle_estimate", "toy_eval"]

PathLike = Union[str, "os.PathLike[str]"]


def _json_default(value: Any) -> Any:
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, Fraction):
        return str(value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not a config value")


def _source(value: Any, what: str) -> Tuple[str, str]:
    """A config or MDP as (kind, text): a path, or a mapping as JSON text."""
    if isinstance(value, (str, os.PathLike)):
        return "path", os.fspath(value)
    if isinstance(value, Mapping):
        try:
            return "json", json.dumps(value, default=_json_default, allow_nan=True)
        except (TypeError, ValueError) as e:
            raise IloptError(f"<{what} dict>: {e}") from None
    raise TypeError(f"{what} must be a dict or a path, got {type(value).__name__}")


@dataclass
class RunResult:
    """What :func:`run` returns.

    ``summary`` is the dict ``summary.json`` holds. ``checkpoints`` maps each seed to its
    checkpoints as columns, ``{column: numpy array}``, the columns of ``seed-<n>.csv`` in order:
    the counts (``at_calls``, ``iteration``, ``gradient_evaluations``, ``trajectories``,
    ``env_steps``, ``expert_queries``) as int64, the others as float64 with NaN where the CSV
    cell is empty. ``theta`` maps each seed to its final θ.
    """

    summary: Dict[str, Any]
    checkpoints: Dict[int, Dict[str, np.ndarray]]
    theta: Dict[int, np.ndarray] = field(default_factory=dict)

    def to_pandas(self):
        """The checkpoints as one long DataFrame: a ``seed`` column, then the CSV's columns."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "RunResult.to_pandas needs pandas: pip install pandas "
                "(the checkpoints are also in .checkpoints as numpy arrays)"
            ) from None
        frames = []
        for seed, columns in self.checkpoints.items():
            n = len(next(iter(columns.values()))) if columns else 0
            frame = pd.DataFrame({"seed": np.full(n, seed, dtype=np.int64), **columns})
            frames.append(frame)
        if not frames:
            return pd.DataFrame()
        return pd.concat(frames, ignore_index=True)


def _evaluation_env(gymnasium: Any, env: Any, env_id: Optional[str], eval_env: Any) -> Any:
    """The environment of a GymTask's evaluation episodes: ``eval_env`` (an env or an id), else a
    second ``gymnasium.make(env_id)``, else a deep copy of ``env``; its action space must be
    ``env``'s."""
    import copy

    if isinstance(eval_env, str):
        eval_env = gymnasium.make(eval_env)
    elif eval_env is not None and not all(
        hasattr(eval_env, a) for a in ("reset", "step", "action_space")
    ):
        raise IloptError(
            f"eval_env must be a gymnasium.Env or an id for gymnasium.make, got "
            f"{type(eval_env).__name__}"
        )
    elif eval_env is None and env_id is not None:
        eval_env = gymnasium.make(env_id)
    elif eval_env is None:
        try:
            eval_env = copy.deepcopy(env)
        except Exception as e:
            raise IloptError(
                f"eval_env: the evaluation episodes need a second instance of the environment, "
                f"and env could not be deep-copied ({type(e).__name__}: {e}); pass eval_env= "
                f"(another instance, or the id for gymnasium.make)"
            ) from None
    space = getattr(eval_env, "action_space", None)
    if space != env.action_space:
        raise IloptError(
            f"eval_env: its action space {space} is not env's {env.action_space}"
        )
    return eval_env


class GymTask:
    """Any Gymnasium environment as a task of :func:`run`.

    ``env`` is a ``gymnasium.Env`` or an id for ``gymnasium.make``. Its action space is
    ``Discrete(n)`` (the learner is the softmax policy over the features) or a ``Box`` (the
    linear-Gaussian policy with standard deviation ``sigma``, acting on the flattened action).
    ``expert`` maps an observation to the expert's action, which is also the learner's label.
    ``features`` maps an observation to a feature vector (default: the observation flattened to
    float64, then a 1). ``steps`` is the thesis's fixed horizon: each trajectory is a stream of
    ``steps`` decisions, a fresh episode after one ends (``after_end="reset"``); ``steps=None``
    takes one episode per trajectory. Checkpoints evaluate the learner's deterministic action on
    episodes of at most ``eval_steps`` decisions (default: the environment's time limit, else
    ``steps``); their score is the mean episode return.

    The environment steps in Python (one seed at a time); everything else — the algorithms, the
    eq. 3.15 estimators and baselines, the checkpoints — is the kit's. Each seed's run resets
    ``env`` with a seed drawn from the run's seeded RNG at its first training episode and without
    one after that (Gymnasium's own advice: a seeded reset builds a new generator). The
    evaluation episodes run on ``eval_env``, each reset with a seed drawn from the checkpoint's
    RNG, so every checkpoint meets the same episodes and evaluating does not move the training's
    generator; ``eval_env`` defaults to a second ``gymnasium.make`` of the id, or a deep copy of
    ``env``. A run is reproduced by its seed.
    """

    def __init__(
        self,
        env: Any,
        expert: Any,
        features: Any = None,
        steps: Optional[int] = 500,
        after_end: str = "reset",
        sigma: float = 0.1,
        eval_steps: Optional[int] = None,
        name: Optional[str] = None,
        eval_env: Any = None,
    ):
        try:
            import gymnasium
        except ImportError as e:  # pragma: no cover - depends on the installation
            raise ImportError("ilopt.GymTask needs gymnasium: pip install gymnasium") from e
        env_id = env if isinstance(env, str) else None
        if env_id is not None:
            env = gymnasium.make(env_id)
        eval_env = _evaluation_env(gymnasium, env, env_id, eval_env)
        if name is None:
            spec_id = getattr(getattr(env, "spec", None), "id", None) or type(env).__name__
            name = "gym-" + re.sub(r"[^a-z0-9_-]+", "-", str(spec_id).lower()).strip("-")
        if not callable(expert):
            raise IloptError(f"expert must be callable (observation -> action), got {expert!r}")
        if features is not None and not callable(features):
            raise IloptError(f"features must be callable or None, got {features!r}")
        space = env.action_space
        if isinstance(space, gymnasium.spaces.Discrete):
            if int(space.start) != 0:
                raise IloptError(f"a Discrete action space must start at 0, got {space}")
            self.space, self.size = "discrete", int(space.n)
        elif isinstance(space, gymnasium.spaces.Box):
            self.space, self.size = "box", int(np.prod(space.shape))
        else:
            raise IloptError(
                f"the action space must be Discrete or Box, got {type(space).__name__}"
            )
        if steps is not None and (not isinstance(steps, (int, np.integer)) or steps < 1):
            raise IloptError(f"steps must be an integer >= 1 or None, got {steps!r}")
        if eval_steps is None:
            spec = getattr(env, "spec", None)
            eval_steps = getattr(spec, "max_episode_steps", None) or steps
        if eval_steps is None or int(eval_steps) < 1:
            raise IloptError(
                "eval_steps: give the evaluation episodes' length (the environment has no "
                "time limit and steps is None)"
            )
        obs, _ = env.reset(seed=0)
        phi = features(obs) if features is not None else np.append(
            np.asarray(obs, dtype=np.float64).ravel(), 1.0
        )
        self.feature_dim = int(np.asarray(phi, dtype=np.float64).size)
        if self.feature_dim < 1:
            raise IloptError("features(observation) is empty")
        self.env, self.eval_env = env, eval_env
        self.expert, self.features = expert, features
        self.steps, self.after_end, self.sigma = steps, after_end, float(sigma)
        self.eval_steps = int(eval_steps)
        self.name = name


def run(
    config: Union[Mapping[str, Any], PathLike],
    task: Any = None,
    out: Optional[PathLike] = None,
    threads: Optional[int] = None,
    overwrite: bool = False,
    quiet: bool = False,
) -> RunResult:
    """Train as ``ilopt run`` does and return the results in memory.

    ``config`` is a dict with the schema of an ``ilopt run`` TOML file (``{"task": {...},
    "algorithm": {...}, "run": {...}}``; relative paths in it are relative to the current
    directory) or the path of such a file (relative to the file's directory). With ``out``, the
    directory receives the files ``ilopt run --out`` writes; without, nothing is written.
    ``threads`` runs seeds in parallel (default: all cores; the numbers do not depend on it).
    A non-empty ``out`` is refused unless ``overwrite``, which first removes the kit's own files
    there. Unless ``quiet``, a line per checkpoint and the closing table go to stderr, as
    ``ilopt run`` writes them. With ``task`` (a :class:`GymTask`), the config leaves out ``task`` and ``policy``, which the
    task brings, and the seeds run one at a time on this thread, which keeps the GIL; without it
    the GIL is released while Rust runs.
    """
    kind, text = _source(config, "config")
    out_path = None if out is None else os.fspath(out)
    if task is None:
        summary, checkpoints, theta = _native.run(
            kind, text, out_path, threads, bool(overwrite), bool(quiet)
        )
    elif isinstance(task, GymTask):
        summary, checkpoints, theta = _native.run_gym(
            kind,
            text,
            out_path,
            bool(overwrite),
            bool(quiet),
            task.env,
            task.eval_env,
            task.expert,
            task.features,
            task.feature_dim,
            task.space,
            task.size,
            task.steps,
            task.after_end,
            task.sigma,
            task.eval_steps,
            task.name,
        )
    else:
        raise TypeError(f"task must be an ilopt.GymTask or None, got {type(task).__name__}")
    return RunResult(json.loads(summary), dict(checkpoints), dict(theta))


def oracle_estimate(
    config: Union[Mapping[str, Any], PathLike],
    theta: Sequence[float],
    trajectories: int = 1,
    seed: int = 0,
) -> np.ndarray:
    """The oracle's estimate of ∇F(θ) (eq. 3.15, causal form) on the config's task, policy and
    ``run.baseline``: the mean over ``trajectories`` roll-outs of π_θ from one RNG seeded with
    ``seed``. Bit for bit what ``ilopt estimate`` prints for the same arguments."""
    kind, text = _source(config, "config")
    values = [float(x) for x in np.asarray(theta, dtype=np.float64).ravel()]
    return _native.oracle_estimate(kind, text, values, int(trajectories), int(seed))


def _exact_text(x: Any, index: int, what: str) -> str:
    if isinstance(x, bool):
        raise TypeError(f"{what} entry {index} (0-based): a bool is not a number")
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, Fraction):
        return f"{x.numerator}/{x.denominator}"
    if isinstance(x, (float, np.floating)):
        f = Fraction(float(x))  # the float's exact value
        return f"{f.numerator}/{f.denominator}"
    if isinstance(x, str):
        return x
    raise TypeError(
        f"{what} entry {index} (0-based): expected an int, a str such as \"1/3\" or a "
        f"fractions.Fraction, got {type(x).__name__}"
    )


def _fractions(value: Any) -> Any:
    if isinstance(value, str):
        return Fraction(value)
    if isinstance(value, list):
        return [_fractions(v) for v in value]
    if isinstance(value, dict):
        return {k: _fractions(v) for k, v in value.items()}
    return value


def toy_eval(
    mdp: Union[Mapping[str, Any], PathLike],
    theta: Sequence[Any],
    baseline: Optional[Sequence[Any]] = None,
    optimal_baseline: bool = False,
) -> Dict[str, Any]:
    """What ``ilopt toy eval`` prints, exactly: ``objective`` F(θ), ``gradient`` ∇F(θ),
    ``expected_estimate`` E[g(θ, τ)] (eq. 3.15 by enumeration) and ``second_moment`` E‖g‖², as
    ``fractions.Fraction``s (lists of them for vectors); with ``baseline`` or
    ``optimal_baseline`` the CLI's further fields.

    ``mdp`` is a dict in the toy-MDP format (docs/formats/toy-mdp.md) or a file's path. ``theta``
    entries are ints, strings such as ``"1/3"`` or ``"0.25"``, ``Fraction``s, or floats (taken
    at their exact binary value)."""
    kind, text = _source(mdp, "mdp")
    if isinstance(theta, (str, bytes)):
        raise TypeError("theta must be a list of numbers, not a string")
    entries = [_exact_text(x, i, "--theta") for i, x in enumerate(theta)]
    b = None
    if baseline is not None:
        b = [_exact_text(x, i, "--baseline") for i, x in enumerate(baseline)]
    return _fractions(json.loads(_native.toy_eval(kind, text, entries, b, optimal_baseline)))
