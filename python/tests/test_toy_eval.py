"""ilopt.toy_eval against `ilopt toy eval`: the same exact values, as Fractions."""

import json
from fractions import Fraction

import pytest

import ilopt


def as_fractions(value):
    if isinstance(value, str):
        return Fraction(value)
    if isinstance(value, list):
        return [as_fractions(v) for v in value]
    if isinstance(value, dict):
        return {k: as_fractions(v) for k, v in value.items()}
    return value


@pytest.mark.parametrize(
    "mdp, theta, python_theta",
    [
        ("m1-tied.json", "0", [0]),
        ("m1-tied.json", "1/2", [Fraction(1, 2)]),
        ("terminal-absorb.json", "1/3", ["1/3"]),
        ("three-state.json", "1,-2,1/3,0.25,3,1", [1, -2, Fraction(1, 3), "0.25", 3, "1"]),
    ],
)
def test_exact_values_equal_the_clis(cli, repo, mdp, theta, python_theta):
    path = repo / "examples/toy" / mdp
    expected = as_fractions(cli("toy", "eval", "--mdp", path, "--theta", theta))
    got = ilopt.toy_eval(path, python_theta)
    assert got == expected
    assert isinstance(got["objective"], Fraction)
    # The MDP as a dict gives the same.
    assert ilopt.toy_eval(json.loads(path.read_text()), python_theta) == expected


def test_baselines_and_the_optimal_baseline_equal_the_clis(cli, repo):
    path = repo / "examples/toy/three-state.json"
    theta = "1,-2,1/3,0.25,3,1"
    expected = as_fractions(
        cli("toy", "eval", "--mdp", path, "--theta", theta, "--baseline", "1/2",
            "--optimal-baseline")
    )
    got = ilopt.toy_eval(path, theta.split(","), baseline=[Fraction(1, 2)], optimal_baseline=True)
    assert got == expected
    assert "state" in got["optimal_baseline"]


def test_a_float_is_taken_at_its_exact_value(repo):
    path = repo / "examples/toy/m1-tied.json"
    assert ilopt.toy_eval(path, [0.5]) == ilopt.toy_eval(path, ["1/2"])
