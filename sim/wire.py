"""Closed forms for a load hanging in a long, heavy lifting wire (thesis section 2.3.3, after
Nielsen 2007 ch. 5.3), with the corrections of MODEL_NOTES.md.

Symbols (SI): w submerged wire weight per metre [N/m], W0 submerged weight of the load [N],
L unstretched wire length [m], q current drag on the wire per metre [N/m], F0 horizontal force
on the load [N], EA axial stiffness [N].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from sim.gnc import JIT_NOALLOC

RHO_WATER = 1025.0  # kg/m^3 (MODEL_NOTES conventions)
GRAVITY = 9.81  # m/s^2 (MODEL_NOTES conventions)
RHO_STEEL = 7850.0  # kg/m^3 (MODEL_NOTES conventions)

# Gauss-Legendre nodes for the geometric-compliance integral: the integrand is smooth and
# positive on [0, L]; 24 nodes integrate it to better than 1e-10 relative (checked in tests
# against scipy.integrate.quad).
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(24)


@dataclass(frozen=True)
class WireProperties:
    """A lifting wire rope."""

    mass_per_length_kg_m: float
    """Mass in air per metre [kg/m] (MODEL_NOTES: 25 kg/m for the 76 mm full-scale wire)."""
    diameter_m: float
    """Hydrodynamic diameter [m], used for buoyancy and drag (eq. 2.26)."""
    axial_stiffness_newton: float
    """EA [N] (eq. 2.23)."""
    drag_coefficient: float
    """Normal drag coefficient C_D [-] (eq. 2.26)."""

    def submerged_weight_per_length(self) -> float:
        """w = m g - rho_w g pi d^2 / 4 [N/m] (MODEL_NOTES: 199.6 N/m for the default wire)."""
        area = np.pi * self.diameter_m**2 / 4.0
        return self.mass_per_length_kg_m * GRAVITY - RHO_WATER * GRAVITY * area

    def drag_per_length(self, current_speed_mps: float) -> float:
        """Morison drag on the wire per metre, q = 1/2 rho d C_D |V| V [N/m] (eq. 2.26)."""
        v = current_speed_mps
        return 0.5 * RHO_WATER * self.diameter_m * self.drag_coefficient * abs(v) * v


def submerged_weight(mass_kg: float, density_kg_m3: float = RHO_STEEL) -> float:
    """W0 = m g (1 - rho_w / rho_body) [N]; 307.0 kN for 36 t of steel (MODEL_NOTES)."""
    return mass_kg * GRAVITY * (1.0 - RHO_WATER / density_kg_m3)


def horizontal_stiffness(w: float, W0: float, L: float) -> float:
    """Horizontal stiffness at the load, k = w / ln((W0 + w L) / W0) [N/m].

    Thesis eq. 2.30 prints the reciprocal with the logarithm upside down (negative); this is the
    corrected form (MODEL_NOTES). Tends to the simple pendulum W0 / L as w -> 0."""
    if L <= 0.0:
        raise ValueError(f"wire length L must be > 0 m, got {L}")
    return float(horizontal_stiffness_c(w, W0, L))


@njit(**JIT_NOALLOC)
def horizontal_stiffness_c(w: float, W0: float, L: float) -> float:
    """``horizontal_stiffness`` compiled (no check of L), for the environment rows of every
    chunk (``sim.site.wire_entries_into``): the logarithm is libm's, as everywhere in the
    compiled step, not numpy's (which takes an AVX-512 implementation on machines that have
    one, and rounds differently there)."""
    if w <= 0.0:
        return W0 / L
    return w / math.log((W0 + w * L) / W0)


def horizontal_offset(q: float, w: float, W0: float, L: float, F0: float = 0.0) -> float:
    """Offset of the load below a line of length L, downstream of the top [m].

    x(L) = (q W0 / w^2 - F0 / w) ln(W0 / (W0 + w L)) + q L / w  (MODEL_NOTES form of eq. 2.29,
    positive in the direction of the drag q and the force F0)."""
    if w <= 0.0:
        raise ValueError(f"submerged wire weight w must be > 0 N/m, got {w}")
    return float(horizontal_offset_c(q, w, W0, L, F0))


@njit(**JIT_NOALLOC)
def horizontal_offset_c(q: float, w: float, W0: float, L: float, F0: float) -> float:
    """``horizontal_offset`` compiled (w > 0 not checked; see ``horizontal_stiffness_c``)."""
    log_term = math.log(W0 / (W0 + w * L))
    return (q * W0 / (w * w) - F0 / w) * log_term + q * L / w


def geometric_compliance(q: float, w: float, W0: float, L: float, F0: float) -> float:
    """Vertical compliance from the change of the wire's shape [m/N].

    1/k_geo = integral_0^L (F0 + q s)^2 / (W0 + w s)^3 ds (MODEL_NOTES; thesis eq. 2.24 is
    garbled), s measured from the load upwards; 24-point Gauss-Legendre."""
    return float(_gauss_compliance(q, w, W0, L, F0, _GL_NODES, _GL_WEIGHTS))


@njit(**JIT_NOALLOC)
def _gauss_compliance(
    q: float, w: float, W0: float, L: float, F0: float, nodes: np.ndarray, weights: np.ndarray
) -> float:
    """``geometric_compliance``'s quadrature, compiled: the simulator asks for it every chunk
    (the current's speed moves q and F0), and the numpy form's small-array operations cost
    5 us a call. Its powers are products and its sum runs left to right, so the result no
    longer depends on the CPU (numpy's ``** 3`` takes an AVX-512 ``pow`` on machines that
    have it, ``np.dot`` OpenBLAS's kernels); the last bits differ from the numpy form's."""
    half = 0.5 * L
    total = 0.0
    for i in range(nodes.shape[0]):
        s = half * (nodes[i] + 1.0)
        a = F0 + q * s
        b = W0 + w * s
        total += weights[i] * ((a * a) / (b * b * b))
    return half * total


def elastic_compliance(axial_stiffness_newton: float, L: float) -> float:
    """1/k_E = L / EA [m/N] (eq. 2.23)."""
    return L / axial_stiffness_newton


def vertical_stiffness(
    wire: WireProperties, W0: float, L: float, current_speed_mps: float, F0: float
) -> float:
    """Total vertical stiffness, elastic and geometric in series (eq. 2.25) [N/m]."""
    w = wire.submerged_weight_per_length()
    q = abs(wire.drag_per_length(current_speed_mps))
    compliance = elastic_compliance(wire.axial_stiffness_newton, L)
    compliance += geometric_compliance(q, w, W0, L, abs(F0))
    return 1.0 / compliance
