"""One checked signed-distance query between two coal shapes (the solvers' and verification's).

coal's GJK/EPA answers to :data:`GJK_TOLERANCE`; an impossible answer (non-finite, or outside
what the bounding spheres allow: EPA can return -DBL_MAX for some penetrating pairs at tight
tolerances) is asked again at looser EPA tolerances (:data:`RETRY_TOLERANCES`); a sphere
against a sphere, box or capsule still impossible is measured in closed form
(:mod:`.sphere_distance`), as is every sphere-cylinder pair (coal's routine takes the radial
way out of an overlap even when a cap's is shorter), and any other still impossible raises
:class:`~freefloat.errors.ModelError`. Every request starts from coal's
default guesses (:func:`configure`), never from the last query's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from ..errors import ModelError
from .sphere_distance import SphereWitness, closed_form_first, sphere_distance

__all__ = [
    "DEFAULT_GUESS",
    "DEFAULT_SUPPORT_GUESS",
    "GJK_TOLERANCE",
    "RETRY_TOLERANCES",
    "CheckedDistance",
    "Closest",
    "Distances",
    "checked_distance",
    "coal_placement",
    "configure",
    "possible_distances",
]

#: Convergence tolerance of coal's GJK and EPA distance queries (m).
GJK_TOLERANCE = 1e-9
#: EPA tolerances (m) a query is asked again at when its answer is impossible.
RETRY_TOLERANCES = (1e-6, 1e-4)


@dataclass(frozen=True)
class CheckedDistance:
    """A signed distance that passed its plausibility check.

    Attributes:
        value: signed distance (m), negative when the shapes overlap.
        result: coal's result (witness points, normal), or the closed form's.
        retries: queries asked again (at a looser EPA tolerance, or in closed form) to get it.
    """

    value: float
    result: coal.DistanceResult | SphereWitness
    retries: int


@dataclass(frozen=True)
class Closest:
    """The smallest signed distance over the pairs at each of B joint vectors.

    Attributes:
        values: (B,) smallest signed distances (m; inf when there are no pairs).
        pairs: (B,) their pair indices (-1 when there are no pairs).
        gradients: (B, N) their derivatives with respect to the joints (m per rad or m per
            m), when asked for.
        lower: (B, P) a lower bound of every pair's distance at each row (m): its measured
            value, or the bound that spared its query.
    """

    values: np.ndarray
    pairs: np.ndarray
    gradients: np.ndarray | None = None
    lower: np.ndarray | None = None


@dataclass(frozen=True)
class Distances:
    """Signed distances of every checked pair at one configuration.

    Attributes:
        values: (P,) signed distances (m), negative when the shapes overlap.
        gradients: (P, N) derivatives with respect to the N joints (m per rad or m per m),
            when asked for.
    """

    values: np.ndarray
    gradients: np.ndarray | None = None


#: A request as coal makes it: its guesses are where every query starts.
_DEFAULT_REQUEST = coal.DistanceRequest()
#: coal's starting guesses, written into a request before every query.
DEFAULT_GUESS = np.array(_DEFAULT_REQUEST.cached_gjk_guess)
DEFAULT_SUPPORT_GUESS = np.array(_DEFAULT_REQUEST.cached_support_func_guess)


#: Requests at the first tolerance and at every retry tolerance, built once.
_REQUESTS: list[coal.DistanceRequest] = []


def checked_distance(
    shape_a: coal.CollisionGeometry,
    place_a: coal.Transform3s,
    shape_b: coal.CollisionGeometry,
    place_b: coal.Transform3s,
    spheres: tuple[float, float],
    name: str,
) -> CheckedDistance:
    """Signed distance (m) of two shapes, asked again at looser tolerances when impossible.

    Impossible: not finite, or outside what the bounding spheres allow (``spheres``: their
    lower and upper bounds of the distance, m; a translation separating the spheres separates
    the shapes, so a depth never exceeds theirs). A sphere and a cylinder are measured in
    closed form (:func:`sphere_distance`: coal's depths for them are wrong within those
    bounds), as is a sphere against a sphere, box or capsule that no tolerance answers.

    Raises:
        ModelError: no tolerance of :data:`RETRY_TOLERANCES` gives a possible value, and
            no closed form applies.
    """
    if closed_form_first(shape_a, shape_b):
        exact = sphere_distance(shape_a, place_a, shape_b, place_b)
        assert exact is not None  # a sphere and a cylinder have a closed form
        return CheckedDistance(exact.min_distance, exact, 0)
    if not _REQUESTS:
        _REQUESTS.extend(_distance_request(t) for t in (GJK_TOLERANCE, *RETRY_TOLERANCES))
    least, most = spheres
    value = math.nan
    for retries, request in enumerate(_REQUESTS):
        result = coal.DistanceResult()
        value = float(coal.distance(shape_a, place_a, shape_b, place_b, request, result))
        if math.isfinite(value) and least - 1e-9 <= value <= most + 1e-9:
            return CheckedDistance(value, result, retries)
    exact = sphere_distance(shape_a, place_a, shape_b, place_b)
    if exact is not None:
        return CheckedDistance(exact.min_distance, exact, len(_REQUESTS))
    raise ModelError(
        f"coal returned an impossible distance {value:.6g} m for {name} at every EPA "
        "tolerance tried ("
        + ", ".join(f"{t:g}" for t in (GJK_TOLERANCE, *RETRY_TOLERANCES))
        + " m)"
    )


def coal_placement(placement: pin.SE3) -> coal.Transform3s:
    """The coal transform of a Pinocchio placement."""
    return coal.Transform3s(placement.rotation, placement.translation)


def possible_distances(values: np.ndarray, gaps: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Which distances (m) bounding spheres allow: within ``gaps +- reach`` (m).

    As :func:`checked_distance` requires one; NaN and infinite values are not.
    """
    with np.errstate(invalid="ignore"):
        inside = (values >= gaps - reach - 1e-9) & (values <= gaps + reach + 1e-9)
    return np.isfinite(values) & inside


def _distance_request(epa_tolerance: float) -> coal.DistanceRequest:
    """A signed-distance request: GJK to :data:`GJK_TOLERANCE`, EPA to ``epa_tolerance`` (m)."""
    return configure(coal.DistanceRequest(), epa_tolerance)


def configure(request: coal.DistanceRequest, epa_tolerance: float) -> coal.DistanceRequest:
    """Set ``request`` up for signed distances from coal's default guess (never the last one's).

    GJK to :data:`GJK_TOLERANCE` (coal's default 1e-6 m is too coarse), EPA to
    ``epa_tolerance`` (m).
    """
    request.gjk_tolerance = GJK_TOLERANCE
    request.epa_tolerance = epa_tolerance
    request.gjk_max_iterations = 1000
    request.enable_signed_distance = True
    request.gjk_initial_guess = coal.GJKInitialGuess.DefaultGuess
    return request
