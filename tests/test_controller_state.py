"""The controller's state vector by name (control.controller_state)."""

import numpy as np
import pytest

from control import loop
from control.controller_state import ControllerState

PARTS = (
    "tree_integral",
    "tree_error",
    "tree_error_rate",
    "reference",
    "last_wrench_rov",
    "free_integral",
    "free_setpoint_n",
    "allocated_force_newton",
    "pilot_demand",
    "hand_over_wrench",
    "pilot_flown",
)


def test_named_parts_tile_the_vector():
    """Each entry of cs belongs to one named part (the two modes, the two holds and the grip
    now and at the last step are scalars): writing every part's position into it gives back
    0..N_CS-1, once each."""
    state = ControllerState(np.full(loop.N_CS, -1.0))
    for name in PARTS:
        view = getattr(state, name)
        assert np.all(view == -1.0), f"{name} overlaps another part"
        view[:] = np.flatnonzero(state.vector == -1.0)[: view.shape[0]]
    scalars = [loop.CS_MODE, loop.CS_LAST_MODE, loop.CS_HOLD, loop.CS_HOLD + 1]
    scalars += [loop.CS_GRIP, loop.CS_LAST_GRIP]
    assert np.array_equal(np.flatnonzero(state.vector == -1.0), sorted(scalars))


def test_start_and_scalars():
    state = ControllerState.start(loop.MODE_FREE)
    assert state.mode == loop.MODE_FREE and state.last_mode == -1 and not state.stepped
    assert state.heading_hold and state.depth_hold
    state.depth_hold = False
    state.mode, state.last_mode = loop.MODE_TREE, loop.MODE_FREE
    assert not state.depth_hold and state.heading_hold
    assert state.tree_mode_pending and state.stepped
    with pytest.raises(ValueError, match="entries"):
        ControllerState(np.zeros(3))


def test_retune_keeps_the_pd_terms_plus_integral():
    """-Kp e - Kd de + i is the same before and after a retune."""
    state = ControllerState.start(loop.MODE_TREE)
    state.tree_integral[:] = [10.0, -4.0, 2.0]
    state.tree_error[:] = [0.3, -0.2, 0.05]
    state.tree_error_rate[:] = [0.01, 0.02, -0.03]
    kp, kd = np.array([100.0, 120.0, 300.0]), np.array([400.0, 500.0, 900.0])
    e, de = state.tree_error.copy(), state.tree_error_rate.copy()
    before = -kp * e - kd * de + state.tree_integral
    state.retune_tree(kp, kd, 2 * kp, 3 * kd)
    after = -2 * kp * e - 3 * kd * de + state.tree_integral
    np.testing.assert_allclose(after, before, rtol=0, atol=1e-12)
