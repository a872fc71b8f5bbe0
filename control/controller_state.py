"""The controller's state by name: the flat vector ``cs`` that the compiled step
(``control.loop``) carries from step to step, laid out by ``loop``'s ``CS_*`` offsets, with
each part named for Python.

The kernels take ``vector`` and give a new one back; Python reads and writes its parts only
through ``ControllerState`` (the tree controller's law and its bumpless transfers are in
``control.pid``). The array properties are views: writing into them writes the vector.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from control import loop, pid

FloatArray = NDArray[np.float64]


class ControllerState:
    """The controller's state vector ``cs`` (``loop.N_CS``,) with its parts named."""

    def __init__(self, vector: FloatArray) -> None:
        if vector.shape != (loop.N_CS,):
            raise ValueError(f"controller state must have {loop.N_CS} entries, got {vector.shape}")
        self.vector = vector
        """The vector the kernels take and give back."""

    @classmethod
    def start(cls, mode: int) -> ControllerState:
        """A controller that has not stepped yet in supervisor ``mode`` (``loop.MODE_*``): its
        first step initialises the reference bumplessly; the pilot's holds are on."""
        state = cls(np.zeros(loop.N_CS))
        state.mode = mode
        state.last_mode = -1
        state.heading_hold = True
        state.depth_hold = True
        return state

    def _part(self, offset: int, length: int) -> FloatArray:
        return self.vector[offset : offset + length]

    @property
    def tree_integral(self) -> FloatArray:
        """The tree controller's integral i_n (3,): NED forces [N] and yaw moment [N m]."""
        return self._part(loop.CS_I, 3)

    @property
    def tree_error(self) -> FloatArray:
        """The tree controller's last pose error e (3,) [m, m, rad]."""
        return self._part(loop.CS_E, 3)

    @property
    def tree_error_rate(self) -> FloatArray:
        """The tree controller's last error rate de/dt (3,) [m/s, m/s, rad/s]."""
        return self._part(loop.CS_DE, 3)

    @property
    def reference(self) -> FloatArray:
        """The reference model's state (9,): pose, rate, acceleration [NED, m, rad]."""
        return self._part(loop.CS_REF, 9)

    @property
    def last_wrench_rov(self) -> FloatArray:
        """The last commanded ROV wrench (6,), ROV axes [N, N m]."""
        return self._part(loop.CS_TAU, 6)

    @property
    def free_integral(self) -> FloatArray:
        """The free-ROV station keeping's integral (4,)."""
        return self._part(loop.CS_FI, 4)

    @property
    def free_setpoint_n(self) -> FloatArray:
        """The free-flying ROV's set point (4,): [north, east, down, psi] [m, rad]."""
        return self._part(loop.CS_FSP, 4)

    @property
    def allocated_force_newton(self) -> FloatArray:
        """Thruster forces allocated outside the kernel (``loop.ALLOC_EXTERNAL``) [N]."""
        return self._part(loop.CS_ALLOC_F, loop.M_MAX)

    @property
    def pilot_demand(self) -> FloatArray:
        """The pilot's demand (4,) in the ROV's axes [X, Y, Z, N] [N, N m]."""
        return self._part(loop.CS_PILOT, 4)

    @property
    def hand_over_wrench(self) -> FloatArray:
        """The fading wrench (3,) of a hand-over between the tree controller and the pilot's
        hold of the gripped tree, tree axes [N, N, N m] (``loop._hand_over_into``)."""
        return self._part(loop.CS_HANDOVER, 3)

    @property
    def pilot_flown(self) -> FloatArray:
        """Where the pilot flew the gripped tree at the last step (2,): 1.0 for the
        horizontal position, then the heading; the hand-over to the tree controller carries
        no old thrust on those (``loop._hand_over_into``)."""
        return self._part(loop.CS_FLOWN, 2)

    @property
    def gripping(self) -> bool:
        """The ROV gripped the tree at the last step (the kernel copies it from the step's
        environment row)."""
        return bool(self.vector[loop.CS_GRIP] > 0.5)

    @property
    def mode(self) -> int:
        """The supervisor's mode (``loop.MODE_*``)."""
        return int(self.vector[loop.CS_MODE])

    @mode.setter
    def mode(self, mode: int) -> None:
        self.vector[loop.CS_MODE] = mode

    @property
    def last_mode(self) -> int:
        """The mode of the last step; -1 before the first."""
        return int(self.vector[loop.CS_LAST_MODE])

    @last_mode.setter
    def last_mode(self, mode: int) -> None:
        self.vector[loop.CS_LAST_MODE] = mode

    @property
    def stepped(self) -> bool:
        """The controller has taken a step (its reference is initialised)."""
        return bool(self.vector[loop.CS_LAST_MODE] >= 0)

    @property
    def tree_mode_pending(self) -> bool:
        """Switched into tree mode, and the step that takes the switch (resetting the
        reference to the estimate) has not run yet."""
        return self.mode == loop.MODE_TREE and self.last_mode != loop.MODE_TREE

    @property
    def heading_hold(self) -> bool:
        """Flown by hand, a released yaw stick holds the heading."""
        return bool(self.vector[loop.CS_HOLD] > 0.5)

    @heading_hold.setter
    def heading_hold(self, on: bool) -> None:
        self.vector[loop.CS_HOLD] = 1.0 if on else 0.0

    @property
    def depth_hold(self) -> bool:
        """Flown by hand, a released heave stick holds the depth."""
        return bool(self.vector[loop.CS_HOLD + 1] > 0.5)

    @depth_hold.setter
    def depth_hold(self, on: bool) -> None:
        self.vector[loop.CS_HOLD + 1] = 1.0 if on else 0.0

    def retune_tree(
        self, kp_old: FloatArray, kd_old: FloatArray, kp_new: FloatArray, kd_new: FloatArray
    ) -> None:
        """The tree controller's K_p and K_d change, bumpless: the jump of the P and D terms
        at this instant moves into the integral (``pid.retuned_tree_integral``)."""
        self.tree_integral[:] = pid.retuned_tree_integral(
            self.tree_integral,
            self.tree_error,
            self.tree_error_rate,
            kp_old,
            kd_old,
            kp_new,
            kd_new,
        )
