"""The exceptions freefloat raises: one root, :class:`FreeFloatError`, and subclasses with data.

Every message is a single line that names the problem and says what would be valid, so that
the command line can print it as it is (exit code 2) and a caller can test it.
"""

from __future__ import annotations

import math
import unicodedata
from collections.abc import Iterable, Sequence
from typing import Any

from ..excerpts import excerpt


class FreeFloatError(Exception):
    """Root of every error freefloat raises on purpose."""

    def naming(self, path: object) -> FreeFloatError:
        """This error with the file ``path`` named first, unless its message names it already.

        Changed in place (its data kept) and returned, to be raised again.
        """
        if str(path) not in str(self):
            self.args = (f"{path}: {self}",)
        return self


class FileError(FreeFloatError):
    """A file or folder that cannot be read or written; carries the path.

    Missing, not a regular file (a directory, a FIFO, a device such as ``/dev/zero``), larger
    than freefloat's limit for its kind, a symbolic-link loop, a NUL byte in the path, no
    permission, a file where a folder should be.
    """

    def __init__(self, message: str, path: str | None = None) -> None:
        self.path = path
        super().__init__(message)


class ModelError(FreeFloatError):
    """A URDF that cannot describe a free-floating space manipulator."""

    def __init__(self, message: str, urdf: str | None = None) -> None:
        self.urdf = urdf
        super().__init__(message if urdf is None else f"{urdf}: {message}")


class UnknownNameError(FreeFloatError):
    """A joint, frame, robot or key name that does not exist; carries the valid names."""

    def __init__(
        self, kind: str, name: str, valid: Iterable[str], why: str = "", where: str = ""
    ) -> None:
        self.kind = kind
        self.name = name
        self.valid = tuple(valid)
        shown = ", ".join(self.valid) if self.valid else "(none)"
        twin = _look_alike(name, self.valid) if isinstance(name, str) else None
        if twin is not None and not why:
            why = f"looks like {twin!r} but its code points differ: {name!a}, {twin!a}"
        because = f" ({why})" if why else ""
        prefix = f"{where}: " if where else ""
        super().__init__(f"{prefix}unknown {kind} {excerpt(name)}{because}; valid: {shown}")


#: Letters of other scripts drawn like Latin ones (Cyrillic, Greek): a name typed with one
#: looks like the Latin name it is not.
_HOMOGLYPHS = str.maketrans(
    "\u0430\u0435\u043e\u0440\u0441\u0443\u0445\u0456\u0458\u0455\u0410\u0412\u0415"
    "\u041a\u041c\u041d\u041e\u0420\u0421\u0422\u0425\u03bf\u0391\u0392\u0395\u0396"
    "\u0397\u0399\u039a\u039c\u039d\u039f\u03a1\u03a4\u03a5\u03a7\u03b1\u03b9\u03ba\u03bd"
    "\u03c1\u03c5",
    "aeopcyxijsABEKMHOPCTXoABEZHIKMNOPTYXaikvpu",
)


def _look_alike(name: str, valid: Sequence[str]) -> str | None:
    """A valid name ``name`` could be mistaken for, or None.

    The same text in another Unicode form (NFC against NFD, fullwidth letters), or with
    letters of another script drawn like Latin ones (a Cyrillic a for a Latin a:
    :data:`_HOMOGLYPHS`).
    """

    def skeleton(text: str) -> str:
        return unicodedata.normalize("NFKC", text).translate(_HOMOGLYPHS)

    drawn = skeleton(name)
    return next((v for v in valid if v != name and skeleton(v) == drawn), None)


class ScenarioError(FreeFloatError):
    """A scenario file that cannot be read or holds a bad value."""


class InputError(FreeFloatError):
    """A numerical input that is not usable (NaN, infinite, non-positive duration...)."""


class InputLimitError(InputError):
    """A value beyond one of freefloat's stated limits (docs/limits.md).

    Attributes:
        name: what the value is (``"duration"``, ``"--samples"``, ``"[path] extra for 'q2'"``).
        value: the value given (quoted in the message as a short excerpt).
        low: the smallest accepted value, or None.
        high: the largest accepted value, or None.
        unit: the unit of the value and the limits (``"s"``, ``"deg"``, ``""``).
    """

    def __init__(
        self,
        name: str,
        value: Any,
        low: float | None = None,
        high: float | None = None,
        unit: str = "",
        why: str = "",
    ) -> None:
        self.name = name
        self.value = value
        self.low = low
        self.high = high
        self.unit = unit
        u = f" {unit}" if unit else ""
        low = None if low is None or low == -float("inf") else low
        high = None if high is None or high == float("inf") else high
        if low is not None and high is not None:
            limit = f"outside the supported range [{low:g}, {high:g}]{u}"
        elif high is not None:
            limit = f"above the supported maximum {high:g}{u}"
        else:
            limit = f"below the supported minimum {low:g}{u}"
        shown = _number(value) if isinstance(value, float) else excerpt(value)
        super().__init__(f"{name} = {shown}{u} is {limit}" + (f"; {why}" if why else ""))


def _number(value: float) -> str:
    """A number shortly (``2e+09``), in full where that would hide it (180.0001, not 180)."""
    short = f"{value:g}"
    return short if not math.isfinite(value) or float(short) == value else repr(value)


class InfeasibleError(FreeFloatError):
    """A requested attitude change outside the reachable interval (planar bounds).

    Attributes:
        requested_deg: the yaw change asked (deg), or with ``off_axis`` the turn asked about
            the other axes (deg).
        bounds_deg: the reachable interval (deg).
        off_axis: the goal turns a planar base about an axis it cannot turn about (no joint
            motion reaches it, whichever way round a joint goes).
    """

    def __init__(
        self,
        requested_deg: float,
        bounds_deg: Sequence[float],
        message: str | None = None,
        off_axis: bool = False,
    ) -> None:
        self.requested_deg = float(requested_deg)
        self.bounds_deg = (float(bounds_deg[0]), float(bounds_deg[1]))
        self.off_axis = off_axis
        lo, hi = self.bounds_deg
        super().__init__(
            message
            or f"requested yaw change {round(self.requested_deg, 3) + 0.0:.3f} deg is outside the "
            "reachable "
            f"interval ({lo:.3f}, {hi:.3f}) deg for this joint motion (planar bounds); no "
            "point-to-point path exists"
        )


class SolverError(FreeFloatError):
    """No path reaches the goal attitude; carries the best residual and what was tried.

    Attributes:
        best_residual: the smallest attitude residual norm reached (rad).
        tried: every attempt, in order.
        per_axis: the residual vector at the best point (rad), when known.
        stopped_by: why the search stopped short (a joint's limit, a singular map, freedom
            exhausted, the evaluation budget), when known.
        reached_fraction: how far along the way from the quintic attitude to the goal the
            planner got (0-1; continuation only, else 0).
        last_beta: the free coefficients where continuation stopped (rad or m), if it did.
        hint: what to try instead ("" when none).
        blocked_by: the names of the constraints that stood in the way: one a continuation
            stopped at or could not bring its start within, one a root found broke, one no
            start within could be found for (empty when none did). A constraint the quintic
            path breaks but a start was found within did not stand in the way.
    """

    def __init__(
        self,
        message: str,
        best_residual: float,
        tried: Sequence[str] = (),
        per_axis: Sequence[float] | None = None,
        hint: str = "",
        stopped_by: str = "",
        reached_fraction: float = 0.0,
        last_beta: Sequence[float] | None = None,
        blocked_by: Sequence[str] = (),
    ) -> None:
        self.headline = message
        self.blocked_by = tuple(blocked_by)
        self.hint = hint
        self.stopped_by = stopped_by
        self.last_beta = None if last_beta is None else tuple(float(b) for b in last_beta)
        self.reached_fraction = float(reached_fraction)
        self.best_residual = float(best_residual)
        self.tried = tuple(tried)
        self.per_axis = None if per_axis is None else tuple(float(x) for x in per_axis)
        axes = ""
        if self.per_axis is not None and len(self.per_axis) == 3:
            axes = "; per axis x, y, z: " + ", ".join(f"{x:.3g}" for x in self.per_axis)
        detail = f"; tried: {'; '.join(self.tried)}" if self.tried else ""
        hint = f"; {hint}" if hint else ""
        if self.last_beta is not None:  # the residual of the path where the search stopped
            figure = (
                f"the path it stopped on misses the goal by {self.best_residual:.3g} rad = "
                f"{math.degrees(self.best_residual):.3g} deg{axes}"
            )
        else:
            figure = f"best residual {self.best_residual:.3g} rad{axes}"
        super().__init__(f"{message} ({figure}){detail}{hint}")

    def with_hint(self, more: str) -> SolverError:
        """The same refusal with ``more`` added to its hint: every figure kept."""
        return SolverError(
            self.headline,
            self.best_residual,
            self.tried,
            self.per_axis,
            hint=f"{self.hint}; {more}" if self.hint else more,
            stopped_by=self.stopped_by,
            reached_fraction=self.reached_fraction,
            last_beta=self.last_beta,
            blocked_by=self.blocked_by,
        )


class PlanFileError(FreeFloatError):
    """A plan file that is unreadable, corrupt or of another format version."""


class PlanMismatchError(PlanFileError):
    """A plan file whose stored number disagrees with its recomputation; names the field.

    Attributes:
        field: the field's path in the file (``samples.tau``, ``free_parameters.q2``...).
        difference: the largest disagreement found (in ``unit``; inf for a non-numeric field).
        tolerance: the disagreement allowed (in ``unit``).
        unit: unit of ``difference`` and ``tolerance``.
        where: where the largest disagreement is (an instant, a joint), for the reader.
    """

    def __init__(
        self,
        field: str,
        difference: float,
        tolerance: float,
        unit: str = "",
        where: str = "",
        message: str | None = None,
    ) -> None:
        self.field = field
        self.difference = float(difference)
        self.tolerance = float(tolerance)
        self.unit = unit
        self.where = where
        units = f" {unit}" if unit else ""
        at = f" {where}" if where else ""
        super().__init__(
            f"plan field {field!r} disagrees with the recomputation: {message}"
            if message is not None
            else f"plan field {field!r} disagrees with the recomputation by "
            f"{self.difference:.3g}{units}{at} (tolerance {self.tolerance:.3g}{units})"
        )


class VerificationError(FreeFloatError):
    """A plan that fails its independent verification; carries the failed checks.

    Attributes:
        failures: the names of the checks that failed.
        details: per failed check, what it found (its figure against its tolerance, and
            where), or "" when not known; the message gives them after the names.
    """

    def __init__(self, failures: Sequence[str], details: Sequence[str] = ()) -> None:
        self.failures = tuple(failures)
        if len(details) > len(self.failures):
            raise ValueError(f"{len(details)} details for {len(self.failures)} failed checks")
        self.details = tuple(details) + ("",) * (len(self.failures) - len(details))
        said = [f"{n}: {d}" if d else n for n, d in zip(self.failures, self.details, strict=False)]
        super().__init__(
            "the plan fails verification (" + "; ".join(said) + "); it is not returned or written"
        )


class ViewerError(FreeFloatError):
    """The 3D viewer or the plotting stack is missing, broken, or cannot draw the robot."""


class AmbiguousEndEffectorError(ModelError):
    """No single default end effector: several chains end equally deep; carries the tips.

    Attributes:
        candidates: the frame at the tip of each longest chain (none of them a gripper finger).
    """

    def __init__(self, candidates: Sequence[str], urdf: str | None = None) -> None:
        self.candidates = tuple(candidates)
        super().__init__(
            f"the end effector is ambiguous: {len(self.candidates)} chains are longest "
            f"({', '.join(self.candidates)}); name one in the scenario "
            '(end_effector = "..." or end_effectors = [...])',
            urdf,
        )


class PluginError(FreeFloatError):
    """An installed plug-in (a package's entry point) that cannot be loaded or registered.

    Carries the entry point's group (``freefloat.constraints``...), its name and its
    distribution; the message says what went wrong in one line.
    """

    def __init__(self, group: str, name: str, distribution: str, reason: str) -> None:
        self.group, self.name, self.distribution = group, name, distribution
        where = f"plug-in {name!r} of package {distribution!r} (entry point group {group!r})"
        super().__init__(f"{where}: {reason}")


class UnitsWarning(UserWarning):
    """A value that is accepted but looks like it was written in the wrong unit.

    Issued through :mod:`warnings` (the command line prints it as one line
    ``freefloat: warning: ...``): scenario joint values that look like radians, where scenario
    files are in degrees; a base quaternion written ``w`` first, or far from unit length.
    """
