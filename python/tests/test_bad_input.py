"""Bad input from Python raises ilopt.IloptError (a ValueError) with the CLI's message."""

import sys

import pytest

import ilopt

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    tomllib = pytest.importorskip("tomli")

GOOD = """
[task]
name = "toy"
mdp = "MDP"

[algorithm]
algorithm = "sgd"
form = "causal"
step = { kind = "constant", eta = 0.2 }

[run]
budget_calls = 300
seeds = [1]
"""


def configs(repo, tmp_path, text):
    """The same config as a file (for the CLI and Python) and as a dict."""
    text = text.replace("MDP", str(repo / "examples/toy/three-state.json"))
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path, tomllib.loads(text)


@pytest.mark.parametrize(
    "edit, words",
    [
        (lambda t: t.replace("[run]\nbudget_calls = 300\nseeds = [1]\n", ""), "missing field `run`"),
        (lambda t: t.replace("budget_calls = 300", "budget_calls = -5"), "-5"),
        (lambda t: t.replace("budget_calls = 300", "budget_calls = 0"), "must be an integer ≥ 1, got 0"),
        (lambda t: t.replace("seeds = [1]", "seeds = [1, 1]"), "seed 1 is repeated"),
        (lambda t: t.replace("eta = 0.2", "eta = 0.2, etta = 1"), "unknown key"),
        (lambda t: t + "theta0 = [1, 2]\n", "has 2 entries"),
    ],
)
def test_run_raises_the_clis_message(cli, repo, tmp_path, edit, words):
    path, as_dict = configs(repo, tmp_path, edit(GOOD))
    expected = cli("run", "--config", path, "--out", tmp_path / "out", ok=False)
    assert words in expected
    with pytest.raises(ilopt.IloptError) as from_path:
        ilopt.run(path)
    assert str(from_path.value) == expected
    assert isinstance(from_path.value, ValueError)
    # A dict names itself instead of the file; TOML parse errors quote their own lines, so the
    # message's last line is compared.
    with pytest.raises(ilopt.IloptError) as from_dict:
        ilopt.run(as_dict)
    message = str(from_dict.value)
    assert message.startswith("<config dict>: ")
    assert message.splitlines()[-1] == expected.replace(str(path), "<config dict>").splitlines()[-1]


def test_oracle_estimate_raises_the_clis_messages(cli, repo):
    path = repo / "examples/run/toy-sgd.toml"
    expected = cli("estimate", "--config", path, "--theta", "[1, 2]", ok=False)
    assert expected == "theta: has 2 entries, the toy policy has 6 parameters"
    with pytest.raises(ilopt.IloptError, match="^theta: has 2 entries, the toy policy has 6 parameters$"):
        ilopt.oracle_estimate(path, [1, 2], 1, 0)
    expected = cli("estimate", "--config", path, "--theta", "[1,1,1,1,1,1]", "--trajectories", 0, ok=False)
    with pytest.raises(ilopt.IloptError) as e:
        ilopt.oracle_estimate(path, [1] * 6, 0, 0)
    assert str(e.value) == expected == "trajectories must lie in 1..=100000, got 0"


@pytest.mark.parametrize(
    "theta, python_theta, words",
    [
        ("1/0", ["1/0"], "zero denominator"),
        ("x", ["x"], "is not an exact number"),
        ("1,1/0", [1, "1/0"], "--theta entry 1 (0-based)"),
        ("1,2", [1, 2], "θ"),
    ],
)
def test_toy_eval_raises_the_clis_message(cli, repo, theta, python_theta, words):
    path = repo / "examples/toy/m1-tied.json"
    expected = cli("toy", "eval", "--mdp", path, "--theta", theta, ok=False)
    assert words in expected
    with pytest.raises(ilopt.IloptError) as e:
        ilopt.toy_eval(path, python_theta)
    assert str(e.value) == expected


def test_wrong_python_types_are_type_errors(repo):
    path = repo / "examples/toy/m1-tied.json"
    with pytest.raises(TypeError, match=r"--theta entry 0 \(0-based\): expected an int"):
        ilopt.toy_eval(path, [[1]])
    with pytest.raises(TypeError, match="config must be a dict or a path"):
        ilopt.run(3)


def test_a_missing_mdp_file_names_it(cli, repo, tmp_path):
    missing = tmp_path / "nope.json"
    expected = cli("toy", "eval", "--mdp", missing, "--theta", "0", ok=False)
    with pytest.raises(ilopt.IloptError) as e:
        ilopt.toy_eval(missing, [0])
    assert str(e.value) == expected and str(missing) in expected


def test_a_task_that_is_not_a_gym_task_is_refused_with_a_clear_message(repo):
    with pytest.raises(TypeError, match="task must be an ilopt.GymTask or None, got object"):
        ilopt.run(repo / "examples/run/toy-sgd.toml", task=object())
