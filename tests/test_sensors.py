"""Sensor model: rates, zero-order hold, noise level, dropouts."""

import numpy as np
import pytest

from control.simulation import Simulation
from sim import params, sensors

MODEL = params.load("model-scale")


def test_rate_must_divide_the_plant_rate():
    spec = MODEL.spec.sensors.model_copy(
        update=dict(position=MODEL.spec.sensors.position.model_copy(update=dict(rate_hz=3.0)))
    )
    with pytest.raises(ValueError, match=r"sensors.position.rate_hz = 3.0 Hz must divide"):
        sensors.sensor_config(spec, 0.01)


def test_hold_noise_and_dropouts_over_a_run():
    sim = Simulation(MODEL, tree_depth_m=100.0, seed=11, control=False)
    rows = sim.run_for(400.0)
    y = rows["y"]
    truth = np.array([sensors.true_outputs(x) for x in rows.plant_state()])
    # position is held between fixes: it only changes on whole seconds (1 Hz), never between
    changes = np.flatnonzero(np.any(np.diff(y[:, 0:3], axis=0) != 0, axis=1)) + 1
    # (row k holds the sample taken on plant step k, which is due when k is a multiple of 100)
    assert np.all(changes % 100 == 0)
    # 5 % of fixes are lost: ~400 fixes expected, binomial std ~4.4 -> 4 sigma band
    n_fixes = len(changes)
    assert 400 * 0.95 - 18 <= n_fixes <= 400 * 0.95 + 18
    # gyro at 100 Hz: the noise is the configured 0.0017 rad/s (400 s x 100 Hz samples ->
    # 0.5 % standard error on a std; 3 % tolerance)
    # (the gyro is sampled every step, from the state at the end of that step: the same row)
    gyro_err = y[:, 8:11] - truth[:, 8:11]
    assert gyro_err.std() == pytest.approx(MODEL.spec.sensors.gyro.noise_std, rel=0.03)
    # compass is wrapped into [-pi, pi)
    assert np.all(y[:, 4] >= -np.pi) and np.all(y[:, 4] < np.pi)
