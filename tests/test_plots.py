"""The figures of `run --plots`: each quantity on an axis with its unit, errors shown, the
docking frame on the track, and scales not wrecked by a one-second transient."""

from __future__ import annotations

import matplotlib.figure
import numpy as np

from app.plots import mission_figures
from missions import schema
from missions.runner import run_mission
from missions.setup import charted_frame
from sim import params


def test_figures_name_units_show_errors_and_the_docking_frame(tmp_path, monkeypatch):
    figures: dict[str, matplotlib.figure.Figure] = {}
    real_savefig = matplotlib.figure.Figure.savefig

    def keep(self, path, *args, **kwargs):
        figures[str(path).rsplit("-", 1)[-1]] = self
        return real_savefig(self, path, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    mission = schema.load_mission("full-docking-current-0.3")
    short = mission.model_copy(update={"legs": mission.legs[:2]})
    result = run_mission(short)
    layout = params.load(mission.setup.params).spec.docking.to_numeric()
    paths = mission_figures(
        result, tmp_path, np.array([0.0, 0.0, 0.0]), (charted_frame(mission), layout)
    )
    assert [p.name.rsplit("-", 1)[-1] for p in paths] == ["pose.png", "track.png", "forces.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)
    pose = [ax.get_ylabel() for ax in figures["pose.png"].axes]
    assert pose == [
        "north [m]",
        "error [m]",
        "east [m]",
        "error [m]",
        "heading [deg]",
        "error [deg]",
    ]
    track = [line.get_label() for line in figures["track.png"].axes[0].get_lines()]
    assert "docking frame" in track and "guideposts" in track
    forces = [ax.get_ylabel() for ax in figures["forces.png"].axes]
    assert forces[0].startswith("ROV force [N]") and forces[1].startswith("ROV moment [N m]")
    assert all("[" in label for label in forces), "every axis says its unit"


def test_a_one_second_transient_does_not_set_the_scale(tmp_path, monkeypatch):
    """The sea trial's hook-up throws the estimate metres away for a second; the pose axes
    are scaled to the run, not to that spike."""
    import matplotlib.pyplot as plt

    from app.plots import _robust_limits

    t = np.arange(0.0, 600.0, 0.1)
    steady = 1.0 + 0.01 * np.sin(t)
    spike = steady.copy()
    spike[470:480] = 40.0
    fig, ax = plt.subplots()
    _robust_limits(ax, steady, spike)
    lo, hi = ax.get_ylim()
    plt.close(fig)
    # the steady signal spans 0.99..1.01; a scale set by the 40 m spike would reach past 40,
    # so 2.0 and 0.9 separate the two cases by more than an order of magnitude
    assert hi < 2.0 and lo > 0.9
