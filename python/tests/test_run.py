"""ilopt.run against `ilopt run`: the same summary, the same checkpoints, the same files."""

import csv
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import ilopt

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    tomllib = pytest.importorskip("tomli")

# The obstacle example (examples/run/obstacle-adam.toml) at a budget the suite can afford.
OBSTACLE = """
[task]
name = "obstacle"
horizon = "fixed"
steps = 200
after_end = "absorb"

[policy]
sigma = 0.1
features = { kind = "rbf", per_axis = 9, width = 0.2, x_range = [-0.5, 2.0], y_range = [-1.0, 1.0] }

[algorithm]
algorithm = "adam"
form = "causal"
alpha = 0.005
beta1 = 0.9
beta2 = 0.999
epsilon = 1e-8

[run]
budget_calls = 12_000
trajectories_per_gradient = 4
baseline = { kind = "leave-one-out" }
seeds = [1, 2]

[evaluation]
every_calls = 4_000
episodes = 3
"""


def read_csv(path: Path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def assert_columns_match_csv(columns, rows):
    assert list(columns) == list(rows[0]) if rows else True
    for name, values in columns.items():
        assert len(values) == len(rows)
        for v, row in zip(values, rows):
            cell = row[name]
            if cell == "":
                assert math.isnan(v), (name, v)
            else:
                # Shortest round-trip text: parsing it gives the very double.
                assert v == (int(cell) if values.dtype.kind == "i" else float(cell)), (name, v, cell)


def same_files(a: Path, b: Path):
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    for name in names:
        if name != "timings.json":  # the only file with wall times
            assert (a / name).read_bytes() == (b / name).read_bytes(), name


def check_against_cli(cli, config_path: Path, python_config, tmp_path: Path):
    cli_out = tmp_path / "cli"
    summary = cli("run", "--config", config_path, "--out", cli_out)
    py_out = tmp_path / "py"
    result = ilopt.run(python_config, out=py_out, threads=1)
    assert result.summary == summary
    assert sorted(result.checkpoints) == summary["seeds"]
    for seed, columns in result.checkpoints.items():
        assert_columns_match_csv(columns, read_csv(cli_out / f"seed-{seed}.csv"))
        assert columns["at_calls"].dtype == np.int64
    same_files(cli_out, py_out)
    # In memory only: the same numbers, nothing written.
    again = ilopt.run(python_config)
    assert again.summary == summary
    for seed in summary["seeds"]:
        for name, values in again.checkpoints[seed].items():
            np.testing.assert_array_equal(values, result.checkpoints[seed][name])
        np.testing.assert_array_equal(again.theta[seed], result.theta[seed])
    return result


def test_toy_run_from_a_path_matches_the_cli(cli, repo, tmp_path):
    path = repo / "examples/run/toy-sgd.toml"
    check_against_cli(cli, path, path, tmp_path)


def test_obstacle_run_from_a_dict_matches_the_cli(cli, tmp_path):
    path = tmp_path / "obstacle.toml"
    path.write_text(OBSTACLE)
    result = check_against_cli(cli, path, tomllib.loads(OBSTACLE), tmp_path)
    assert result.summary["task"] == "obstacle"
    assert all(len(t) == result.summary["dim"] for t in result.theta.values())


def test_a_dicts_relative_paths_resolve_against_the_current_directory(cli, repo, monkeypatch):
    config = tomllib.loads((repo / "examples/run/toy-sgd.toml").read_text())
    monkeypatch.chdir(repo / "examples/run")
    from_dict = ilopt.run(config, threads=2)
    assert from_dict.summary == ilopt.run(repo / "examples/run/toy-sgd.toml").summary


def test_to_pandas_is_the_csv_files_with_a_seed_column(cli, repo, tmp_path):
    pd = pytest.importorskip("pandas")
    result = ilopt.run(repo / "examples/run/toy-sgd.toml", out=tmp_path)
    frame = result.to_pandas()
    expected = pd.concat(
        [
            pd.read_csv(tmp_path / f"seed-{s}.csv").assign(seed=s)[
                ["seed", *pd.read_csv(tmp_path / f"seed-{s}.csv").columns]
            ]
            for s in result.summary["seeds"]
        ],
        ignore_index=True,
    )
    pd.testing.assert_frame_equal(frame, expected, check_dtype=False)
    assert frame.groupby("at_calls")["objective"].mean().is_monotonic_decreasing
