"""ilopt from Python: the kit's runs, oracle estimates and exact toy evaluations.

Each function goes through the same Rust route as the ``ilopt`` command line, so a seed gives
the same numbers as the CLI and bad input raises :class:`IloptError` with the CLI's message.

- :func:`run` — ``ilopt run``: train on a config (a dict of the TOML schema, or a path).
- :func:`oracle_estimate` — ``ilopt estimate``: one draw of the eq. 3.15 gradient estimate.
- :func:`toy_eval` — ``ilopt toy eval``: F, ∇F, E[g], E‖g‖² exactly, as ``Fraction``s.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import IloptError

__all__ = ["IloptError", "RunResult", "run", "oracle_estimate", "toy_eval"]

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


def run(
    config: Union[Mapping[str, Any], PathLike],
    task: Any = None,
    out: Optional[PathLike] = None,
    threads: Optional[int] = None,
) -> RunResult:
    """Train as ``ilopt run`` does and return the results in memory.

    ``config`` is a dict with the schema of an ``ilopt run`` TOML file (``{"task": {...},
    "algorithm": {...}, "run": {...}}``; relative paths in it are relative to the current
    directory) or the path of such a file (relative to the file's directory). With ``out``, the
    directory receives the files ``ilopt run --out`` writes; without, nothing is written.
    ``threads`` runs seeds in parallel (default: all cores; the numbers do not depend on it).
    The GIL is released while Rust runs.
    """
    if task is not None:
        raise IloptError(
            "task: only the config's built-in tasks (cartpole, obstacle, toy) are available in "
            "this version; leave task=None"
        )
    kind, text = _source(config, "config")
    out_path = None if out is None else os.fspath(out)
    summary, checkpoints, theta = _native.run(kind, text, out_path, threads)
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
