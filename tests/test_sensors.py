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


@pytest.mark.parametrize("first_step", [0, 7, 12_345])
def test_drawn_noise_is_the_numpy_forms_bit_for_bit(first_step: int) -> None:
    """``draw_noise`` scales the normals and masks the samples in one compiled call; the
    numbers are those of the numpy forms it replaced (the same draws, in the same order)."""
    spec = params.load("full-scale").sensors
    cfg = sensors.sensor_config(spec, 0.01)
    cfg = sensors.SensorConfig(cfg.decimation, cfg.noise_std, np.linspace(0.0, 0.4, 5))
    got = sensors.draw_noise(
        cfg, np.random.default_rng(3), np.random.default_rng(4), first_step, 100
    )
    due = (first_step + np.arange(100))[:, None] % cfg.decimation[None, :] == 0
    uniforms = np.random.default_rng(3).random((100, sensors.N_SENSORS))
    kept = uniforms >= cfg.dropout_probability[None, :]
    noise = np.random.default_rng(4).standard_normal((100, sensors.N_Y)) * cfg.noise_std[None, :]
    assert np.array_equal(got.noise.view(np.int64), noise.view(np.int64))
    assert np.array_equal(got.fresh, due & kept)
    assert 0 < got.fresh.sum() < got.fresh.size, "some samples dropped, some kept"


def test_drawn_noise_in_pieces_is_the_noise_drawn_at_once() -> None:
    """Each generator is read in step order: 100 steps drawn as 1 + 36 + 63 are the 100 drawn
    at once, number for number (the simulator cuts a run into chunks wherever its requests
    end, and the draws must not depend on where)."""
    cfg = sensors.sensor_config(params.load("full-scale").sensors, 0.01)
    cfg = sensors.SensorConfig(cfg.decimation, cfg.noise_std, np.linspace(0.1, 0.4, 5))
    whole = sensors.draw_noise(cfg, np.random.default_rng(5), np.random.default_rng(6), 0, 100)
    d, g = np.random.default_rng(5), np.random.default_rng(6)
    parts = []
    first = 0
    for n in (1, 36, 63):
        parts.append(sensors.draw_noise(cfg, d, g, first, n))
        first += n
    assert np.array_equal(whole.noise, np.vstack([p.noise for p in parts]))
    assert np.array_equal(whole.fresh, np.vstack([p.fresh for p in parts]))


@pytest.mark.parametrize("block_steps", [7, 100, 2048])
def test_the_noise_stream_gives_draw_noises_numbers_in_any_pieces(block_steps: int) -> None:
    """``NoiseStream`` draws ahead in blocks (compiled) and hands them out a chunk at a time:
    pieces of 1, 36, 63, 250 and 13 steps, across block edges (blocks of 7 and 100 steps)
    and with the sensors' settings changed between two pieces, are bit for bit what
    ``draw_noise`` gives for the same pieces from generators of the same seeds."""
    spec = params.load("full-scale").sensors
    cfg = sensors.sensor_config(spec, 0.01)
    cfg_a = sensors.SensorConfig(cfg.decimation, cfg.noise_std, np.linspace(0.1, 0.4, 5))
    cfg_b = sensors.SensorConfig(cfg.decimation, 3.0 * cfg.noise_std, np.full(5, 0.2))
    stream = sensors.NoiseStream(np.random.default_rng(5), np.random.default_rng(6))
    stream.BLOCK_STEPS = block_steps
    d, g = np.random.default_rng(5), np.random.default_rng(6)
    first = 0
    for n, cfg_k in ((1, cfg_a), (36, cfg_a), (63, cfg_b), (250, cfg_a), (13, cfg_b)):
        got = stream.take(cfg_k, first, n)
        expected = sensors.draw_noise(cfg_k, d, g, first, n)
        assert np.array_equal(got.noise.view(np.int64), expected.noise.view(np.int64))
        assert np.array_equal(got.fresh, expected.fresh)
        first += n
    assert 0 < expected.fresh.sum() < expected.fresh.size
