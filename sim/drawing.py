"""What the views draw of the bodies: one shape for every view (recordings, console).

Drawing choices change no number of the simulation. The ROV has no hull in the parameter set
(appendix B gives its mass and added mass, not its outline), so its box is derived from its
mass; the tree's box is its documented size (``ps.tree.dimensions_m``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sim.gnc import Rzyx
from sim.params import ParameterSet
from sim.wire import RHO_WATER

FloatArray = NDArray[np.float64]

ROV_BOX_ASPECT = (1.6, 1.0, 0.9)
"""Length : width : height of the box drawn for the ROV (work-class ROVs are about this shape)."""
ROV_SOLIDITY = 0.5
"""Fraction of the ROV's box that is solid (an open frame): the box holds twice the water its
mass displaces."""


def rov_drawing_box_m(ps: ParameterSet) -> FloatArray:
    """[length, width, height] of the box drawn for the ROV [m]: volume m / (rho_water
    ROV_SOLIDITY), shape ROV_BOX_ASPECT. For Minerva (460 kg, appendix B.4) it is
    1.37 x 0.85 x 0.77 m; the real vehicle is 1.44 x 0.82 x 0.8 m."""
    volume = float(ps.rov.M_rb[0, 0]) / RHO_WATER / ROV_SOLIDITY
    aspect = np.array(ROV_BOX_ASPECT)
    return aspect * (volume / float(np.prod(aspect))) ** (1.0 / 3.0)


def attachment_point_n(tree_eta_n: FloatArray, attachment_height_m: float) -> FloatArray:
    """Where the wire holds the tree, in NED [m]: the centre of gravity plus R_nb [0, 0, -z_a]
    (z_a above it in the tree's axes, eq. 2.22)."""
    eta = np.asarray(tree_eta_n, dtype=float)
    r_nb = Rzyx(float(eta[3]), float(eta[4]), float(eta[5]))
    return eta[0:3] + r_nb @ np.array([0.0, 0.0, -attachment_height_m])
