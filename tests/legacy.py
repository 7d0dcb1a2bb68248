"""Genuine plan files of the formats before 4 (monomials in seconds), made from a current plan.

Written here from the old format's definition, not by freefloat: ``path.coefficients`` are the
ascending monomial coefficients in t of each joint's path, ``free_parameters`` (and each root's)
their coefficients of t^6 and up, and a ``min_norm`` value the squared norm of those
coefficients in normalised time, ``sum_j (b_j T^j)^2``.
"""

from __future__ import annotations

import copy
import math

import numpy as np
from scipy.special import eval_jacobi


def _monomials_in_s(start: float, goal: float, beta: list[float]) -> np.ndarray:
    """Ascending coefficients in s of a joint's path of the format-4 definition."""
    poly = np.polynomial.Polynomial
    s = poly([0.0, 1.0])
    out = start + (goal - start) * (10 * s**3 - 15 * s**4 + 6 * s**5)
    for n, b in enumerate(beta):
        factorial = math.factorial
        scale = math.sqrt((2 * n + 13) * factorial(n + 12) * factorial(n)) / factorial(n + 6)
        # P_n^(6,6) from its values at n + 1 Chebyshev points (exact for degree n), in s
        x = np.cos(np.pi * (np.arange(n + 1) + 0.5) / (n + 1))
        jacobi = poly.fit(x, eval_jacobi(n, 6, 6, x), n, domain=[-1, 1], window=[-1, 1])
        in_s = jacobi(2 * s - 1)
        out = out + b * scale * s**3 * (1 - s) ** 3 * in_s
    coef = np.zeros(6 + len(beta))
    coef[: len(out.coef)] = out.coef
    return coef


def _sample_monomials(old: dict, names: list[str]) -> None:
    """The joint samples as a format-3 planner took them: from its monomials in t (s).

    A format-3 file's samples agree with its own paths to the rounding of their monomials,
    not with the format-4 series they were converted from.
    """
    t = np.asarray(old["samples"]["t"], dtype=float)
    polynomial = np.polynomial.polynomial
    for key, order in (("q", 0), ("qd", 1), ("qdd", 2)):
        columns = [
            polynomial.polyval(t, polynomial.polyder(old["path"]["coefficients"][n], order))
            for n in names
        ]
        old["samples"][key] = np.column_stack(columns).tolist()


def as_format_3(doc: dict) -> dict:
    """A format-4 plan dictionary as the same plan in format 3."""
    old = copy.deepcopy(doc)
    T = float(doc["duration"])
    names = doc["robot"]["joints"]
    start = dict(zip(names, doc["request"]["start_joints"], strict=True))
    goal = dict(zip(names, doc["request"]["goal_joints"], strict=True))

    def in_t(name: str, beta: list[float]) -> list[float]:
        c = _monomials_in_s(start[name], goal[name], beta)
        return (c / T ** np.arange(len(c))).tolist()

    old["format"] = "freefloat.plan/3"
    old["path"] = {
        "family": "polynomial",
        "coefficients": {n: in_t(n, doc["path"]["coefficients"][n]) for n in names},
    }
    old["free_parameters"] = {n: old["path"]["coefficients"][n][6:] for n in names}
    _sample_monomials(old, names)
    for root in old["solver"]["solutions"]:
        root["free_parameters"] = {n: in_t(n, root["free_parameters"][n])[6:] for n in names}
    old.pop("path_quality", None)
    if old.get("objective", {}).get("name") == "min_norm":
        norm = sum(
            (b * T ** (6 + k)) ** 2
            for values in old["free_parameters"].values()
            for k, b in enumerate(values)
        )
        old["objective"]["value"] = old["objective"]["start_value"] = norm
    # and without the other records of format 4
    for key in ("urdf_text", "urdf_sha256", "end_effectors"):
        old["robot"].pop(key, None)
    old["samples"].pop("end_effector_paths", None)
    for key in ("constraints", "robustness"):
        old.pop(key, None)
    old.get("safety", {}).pop("note", None)
    old.get("objective", {}).pop("parameters", None)
    return old
