"""Scenario: shipped names, files, overrides, and the CLI's errors as
ValueError."""

import subprocess

import pytest

import slipfront
from conftest import REPO


def test_shipped_names_files_and_the_default_scene():
    names = slipfront.scenarios()
    assert "triggered_front" in names and "tromborg2014_stick_slip" in names
    by_name = slipfront.Scenario.load("triggered_front")
    by_file = slipfront.Scenario.load(str(REPO / "scenarios" / "triggered_front.toml"))
    assert by_name == by_file
    assert slipfront.Scenario.load(REPO / "scenarios" / "triggered_front.toml") == by_file
    assert by_name.shape == (57, 31)
    default = slipfront.Scenario.load()
    assert default == slipfront.Scenario.load("tromborg2014_stick_slip")
    assert default != by_name


def test_overrides_take_python_values_and_round_trip_through_toml():
    sc = slipfront.Scenario.load("small_stick_slip",
                                 set={"loading.drive.velocity": 4e-4, "time.seed": 7})
    assert sc.get("loading.drive.velocity") == 4e-4
    assert sc.get("time.seed") == 7
    again = slipfront.Scenario.from_toml(sc.to_toml())
    assert again == sc
    assert sc.with_set({"time.seed": 8}).get("time.seed") == 8
    assert sc.model()["dt"] > 0
    with pytest.raises(KeyError):
        sc.get("no.such.key")


def _cli_error(cli, *args):
    done = subprocess.run([cli, "check", *args], capture_output=True, text=True)
    assert done.returncode != 0
    return done.stderr


@pytest.mark.parametrize("key,value,shown", [
    ("material.density", -5.0, "-5"),
    ("geometry.nx", 0, "0"),
    ("friction.no_such_key", 1.0, "no_such_key"),
])
def test_bad_input_raises_the_clis_message(cli, key, value, shown):
    with pytest.raises(ValueError) as err:
        slipfront.Scenario.load("small_stick_slip", set={key: value})
    message = str(err.value)
    assert key.split(".")[-1] in message and shown in message
    # The same problem lines as `slipfront check --set` prints.
    cli_text = _cli_error(cli, str(REPO / "scenarios" / "small_stick_slip.toml"),
                          "--set", f"{key}={value}")
    problems = [line.strip() for line in message.splitlines() if line.strip().startswith("- ")]
    assert problems, message
    for line in problems:
        assert line in cli_text, (line, cli_text)


def test_a_time_step_above_the_stability_limit_is_refused_as_the_cli_refuses_it(cli):
    scene = str(REPO / "scenarios" / "small_stick_slip.toml")
    with pytest.raises(ValueError) as err:
        slipfront.run(scene, set={"time.dt": 1e-5}, progress=False)
    done = subprocess.run([cli, "run", scene, "--set", "time.dt=1e-5"], capture_output=True,
                          text=True)
    assert done.returncode != 0
    assert "above the stability limit 2.4808e-6 s" in str(err.value)
    assert str(err.value) in done.stderr
    # allow_unstable lets it start (and the blow-up is reported as BlowUp).
    with pytest.raises(slipfront.BlowUp, match=r"blew up at step \d+ .*block"):
        slipfront.run(scene, set={"time.dt": 1e-5}, t_end=0.01, allow_unstable=True,
                      progress=False)


def test_a_missing_file_or_name():
    with pytest.raises(FileNotFoundError, match="no_such_scene"):
        slipfront.Scenario.load("no_such_scene")
    with pytest.raises(ValueError, match="expected a bool, int, float"):
        slipfront.Scenario.load("small_stick_slip", set={"time.seed": object()})
