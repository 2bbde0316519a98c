"""ilopt.oracle_estimate against `ilopt estimate`: bit for bit, for the same seed."""

import json
import re

import numpy as np
import pytest

import ilopt


def dimension(config):
    """The policy's dimension, from the error an empty θ gets."""
    with pytest.raises(ilopt.IloptError) as e:
        ilopt.oracle_estimate(config, [], 1, 0)
    return int(re.search(r"has (\d+) parameters", str(e.value)).group(1))


@pytest.mark.parametrize(
    "config, m, seed",
    [
        ("toy-sgd.toml", 1, 0),
        ("toy-sgd.toml", 3, 7),
        ("cartpole-sgd-baseline.toml", 4, 11),  # leave-one-out baseline
        ("cartpole-dagger.toml", 2, 5),
        ("obstacle-adam.toml", 2, 3),
    ],
)
def test_bit_equal_to_the_clis(cli, repo, config, m, seed):
    path = repo / "examples/run" / config
    d = dimension(path)
    theta = (0.05 * np.random.default_rng(seed).standard_normal(d)).tolist()
    if config.startswith("toy"):
        theta = [1.0 + t for t in theta]  # the rational softmax is stationary at θ = 0
    got = ilopt.oracle_estimate(path, theta, m, seed)
    out = cli("estimate", "--config", path, "--theta", json.dumps(theta),
              "--trajectories", m, "--seed", seed)
    expected = np.array(out["estimate"], dtype=np.float64)
    assert got.dtype == np.float64 and got.shape == (d,)
    assert got.tobytes() == expected.tobytes()
    assert np.any(got != 0)
    # Another seed draws other trajectories.
    assert not np.array_equal(got, ilopt.oracle_estimate(path, theta, m, seed + 1))
