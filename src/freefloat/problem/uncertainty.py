"""What an uncertainty of the mass properties does to a plan's final attitude (first order).

An :class:`Uncertainty` gives each body parameter a size ``u``: the mass a fraction of itself,
each centre-of-mass coordinate a length, each inertia component a fraction of its scale (its
own value for a moment, ``sqrt(I_aa I_bb)`` for a product ``I_ab``). With the exact
sensitivity ``S`` (:mod:`freefloat.problem.inertial_sensitivity`), the error is ``e = S d`` to first
order and

- **RMS**: the parameters independent with standard deviations ``u``: covariance
  ``C = sum_k u_k^2 S_k S_k^T`` and RMS error ``sqrt(trace C)``;
- **worst case**: every parameter anywhere in ``[-u_k, u_k]``: the largest ``|S d|`` over that
  box, found at a vertex (exactly, by enumeration, up to 12 parameters; over more, the best
  vertex of 4096 directions, each improved by the ascent ``d <- S v / |S v|``,
  ``v <- sign(S^T d) u`` until it stops growing).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..robot.payload import PAYLOAD_LINK
from .inertial_sensitivity import Sensitivity

__all__ = ["DEFAULT_UNCERTAINTY", "AttitudeSpread", "BodyEffect", "Uncertainty", "spread"]

_GROUPS = {"mass": slice(0, 1), "com": slice(1, 4), "inertia": slice(4, 10)}
_DIRECTIONS = 4096
_ENUMERATE = 12


@dataclass(frozen=True)
class Uncertainty:
    """Sizes of the uncertainty of every body's parameters.

    Attributes:
        mass_fraction: of each body's mass (0.05 = 5 %).
        com_m: of each centre-of-mass coordinate (m).
        inertia_fraction: of each inertia component's scale.
        payload: a captured payload's own sizes (a client's mass properties are the least
            known); None: the same as every body's.
    """

    mass_fraction: float = 0.05
    com_m: float = 0.01
    inertia_fraction: float = 0.10
    payload: Uncertainty | None = None

    def __post_init__(self) -> None:
        for name, value in (
            ("mass fraction", self.mass_fraction),
            ("centre-of-mass uncertainty", self.com_m),
            ("inertia fraction", self.inertia_fraction),
        ):
            if not (math.isfinite(value) and 0.0 <= value <= 10.0):
                raise InputError(
                    f"{name} must be a number from 0 to 10 (m or fraction), got {value}"
                )

    def sizes(self, nominal: np.ndarray, bodies: tuple[str, ...] = ()) -> np.ndarray:
        """(B, 10) the size ``u`` of each parameter (kg, m, kg m^2) for nominal values (B, 10).

        ``bodies``: the rows' names; a captured payload's row takes :attr:`payload`'s sizes.
        """
        u = self._sizes(nominal)
        if self.payload is not None and PAYLOAD_LINK in bodies:
            row = bodies.index(PAYLOAD_LINK)
            u[row] = self.payload._sizes(nominal[row : row + 1])[0]
        return u

    def _sizes(self, nominal: np.ndarray) -> np.ndarray:
        """:meth:`sizes` with this uncertainty's own sizes for every row."""
        u = np.empty_like(nominal)
        u[:, 0] = self.mass_fraction * np.abs(nominal[:, 0])
        u[:, 1:4] = self.com_m
        moments = np.abs(nominal[:, 4:7])
        u[:, 4:7] = self.inertia_fraction * moments
        pairs = ((0, 1), (0, 2), (1, 2))  # ixy, ixz, iyz
        for column, (a, b) in enumerate(pairs):
            u[:, 7 + column] = self.inertia_fraction * np.sqrt(moments[:, a] * moments[:, b])
        return u

    def describe(self) -> str:
        """The uncertainty in words, e.g. ``mass 5 %, centre of mass 10 mm, inertia 10 %``."""
        said = (
            f"mass {100 * self.mass_fraction:g} %, centre of mass {1000 * self.com_m:g} mm, "
            f"inertia {100 * self.inertia_fraction:g} %"
        )
        if self.payload is not None:
            said += f"; the captured payload {self.payload.describe()}"
        return said


#: The uncertainty of the plan summary's one-line figure.
DEFAULT_UNCERTAINTY = Uncertainty()


@dataclass(frozen=True)
class BodyEffect:
    """The attitude error one body's uncertainty causes (rad, first order).

    Attributes:
        body: the body (URDF link).
        mass: worst case of its mass alone.
        com: worst case of its centre of mass alone.
        inertia: worst case of its six inertia components alone.
        rms: RMS of all ten together.
    """

    body: str
    mass: float
    com: float
    inertia: float
    rms: float


@dataclass(frozen=True)
class AttitudeSpread:
    """First-order final attitude error of a plan under an uncertainty (rad).

    Attributes:
        uncertainty: the sizes used.
        bodies: one effect per body.
        covariance: 3 x 3 covariance of the error rotation vector (rad^2).
        rms: sqrt(trace(covariance)).
        worst: largest error over every parameter within its size.
    """

    uncertainty: Uncertainty
    bodies: tuple[BodyEffect, ...]
    covariance: np.ndarray
    rms: float
    worst: float


def worst_case(columns: np.ndarray, sizes: np.ndarray) -> float:
    """Largest ``|S d|`` with ``|d_k| <= sizes_k`` (rad), ``columns`` = S (3, n)."""
    keep = sizes > 0.0
    s = columns[:, keep] * sizes[keep]
    n = s.shape[1]
    if n == 0:
        return 0.0
    if n <= _ENUMERATE:  # every vertex (up to sign)
        signs = np.array(list(itertools.product((1.0, -1.0), repeat=n - 1)))
        signs = np.hstack([np.ones((len(signs), 1)), signs])
        return float(np.linalg.norm(signs @ s.T, axis=1).max())
    k = np.arange(_DIRECTIONS) + 0.5
    polar = np.arccos(1.0 - 2.0 * k / _DIRECTIONS)
    azimuth = math.pi * (1.0 + math.sqrt(5.0)) * k
    d = np.stack(
        [np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)], axis=1
    )
    best = 0.0
    for _ in range(50):
        vectors = np.sign(d @ s) @ s.T  # (directions, 3)
        norms = np.linalg.norm(vectors, axis=1)
        if norms.max() <= best * (1.0 + 1e-15):
            break
        best = float(norms.max())
        d = vectors / np.maximum(norms, 1e-300)[:, None]
    return best


def spread(
    sensitivity: Sensitivity, uncertainty: Uncertainty = DEFAULT_UNCERTAINTY
) -> AttitudeSpread:
    """The first-order attitude error of a plan under ``uncertainty`` (see the module doc)."""
    sizes = uncertainty.sizes(sensitivity.nominal, sensitivity.bodies)
    jac = sensitivity.jacobian  # (3, B, 10)
    effects = []
    for b, body in enumerate(sensitivity.bodies):
        group = {
            name: worst_case(jac[:, b, part], sizes[b, part]) for name, part in _GROUPS.items()
        }
        scaled = jac[:, b, :] * sizes[b]
        effects.append(
            BodyEffect(
                body,
                group["mass"],
                group["com"],
                group["inertia"],
                float(math.sqrt(np.sum(scaled**2))),
            )
        )
    scaled = (jac * sizes[None]).reshape(3, -1)
    covariance = scaled @ scaled.T
    return AttitudeSpread(
        uncertainty=uncertainty,
        bodies=tuple(effects),
        covariance=covariance,
        rms=float(math.sqrt(np.trace(covariance))),
        worst=worst_case(jac.reshape(3, -1), sizes.reshape(-1)),
    )
