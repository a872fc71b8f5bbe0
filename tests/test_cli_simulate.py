"""`rov-console simulate` end to end, through the command line."""

import json

import pytest

from tests.cli import cli


def run_cli(*args, check=True):
    proc = cli(*args)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_simulate_prints_the_documented_json():
    out = json.loads(
        run_cli(
            "simulate",
            "--params",
            "model-scale",
            "--depth",
            "100",
            "--duration",
            "90",
            "--push",
            "20@90",
            "--current",
            "0@0",
            "--seed",
            "4",
        ).stdout
    )
    for key in (
        "tree_eta_n",
        "rov_eta_n",
        "crane_tip_n",
        "horizontal_offset_m",
        "heading_deg",
        "wire_tension_newton",
        "settled",
        "real_time_factor",
    ):
        assert key in out
    assert len(out["tree_eta_n"]) == 6 and len(out["rov_eta_n"]) == 6
    assert out["crane_tip_n"] == [1.0, 1.0, 0.0]
    assert out["tree_eta_n"][2] == pytest.approx(100.0, abs=0.1)
    # pushed east (90 deg): the tree went east of the crane tip
    assert out["tree_eta_n"][1] > 1.0
    assert out["settled"] is False  # 90 s of a 20 s-period swing with little damping
    assert out["real_time_factor"] > 0


def test_simulate_tree_alone_has_no_rov():
    out = json.loads(run_cli("simulate", "--no-rov", "--duration", "10").stdout)
    assert out["rov_eta_n"] is None
    assert out["wire_tension_newton"] == pytest.approx(307047, rel=0.01)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--current", "0.1@south"], "--current must look like VALUE@DIR_DEG"),
        (["--params", "nowhere"], "unknown parameter set 'nowhere'"),
        (["--depth", "1"], "depth must put the tree"),
        (["--push", "nan@0"], "--push must be finite"),
        (["--duration", "0.015"], "duration 0.015 s is not a whole number of 0.01 s steps"),
    ],
)
def test_bad_input_gets_a_clear_error(args, message):
    proc = run_cli("simulate", "--duration", "1", *args, check=False)
    assert proc.returncode == 2
    assert message in proc.stderr.replace("\n", " ").replace("│", " ").replace("  ", " ")
