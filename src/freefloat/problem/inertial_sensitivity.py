"""Attitude sensitivity of a path to the bodies' inertial parameters (docs/robustness.md).

Along fixed joint paths (a plan's) the final base attitude depends on every body's mass
``m`` (kg), centre of mass ``c`` (m, body frame) and inertia about it ``I_c`` (kg m^2, body
frame): the momentum map ``omega = F1(q; pi) q'`` does. This module differentiates the final
attitude error (rotation vector of ``q_goal^* q_reached``, rad, goal frame) with respect to
those ten numbers per body, exactly:

- zero momentum, ``A(q; pi) v = 0``, is linear in Pinocchio's dynamic parameters ``pi`` of
  each body, and the momentum of body ``i`` is ``X_i^* Phi(v_i) pi_i`` (``Phi``: Pinocchio's
  body regressor at zero acceleration). At fixed ``q, q'`` the base twist then changes by
  ``d v_b = -A_b^-1 (dh/dpi) d pi``;
- ``pi = (m, m c, I_c + m (|c|^2 1 - c c^T))`` is differentiated by hand to ``(m, c, I_c)``;
- the change of the node rates is carried through the planner's discrete sixth-order Magnus
  scheme and the final logarithm exactly as the residual's Jacobian is (docs/method.md
  section 5).

Pinocchio merges links joined by fixed joints into one body; a body is named by the URDF link
its joint moves (the spacecraft's link for the base), and its parameters are those of the
merged body in that link's frame. A captured payload, merged into the end effector's body, is
the exception: it has its own row (its mass, centre of mass and inertia in its link's frame),
since its mass properties are the least known of all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..physics.attitude import (
    magnus_increment_jacobian,
    magnus_increments,
    propagate,
    quat_log,
    quat_to_matrix,
    relative_quat,
    rotation_matrices,
    so3_right_jacobian,
    step_nodes,
)
from ..robot.model import Robot
from ..robot.payload import PAYLOAD_LINK, held_payload
from .residual import Problem

__all__ = [
    "BODY_PARAMETERS",
    "Sensitivity",
    "attitude_sensitivity",
    "body_names",
    "body_parameters",
]

#: The ten parameters of a body, in order: mass (kg), centre of mass (m, body frame) and the
#: inertia about it (kg m^2, body frame).
BODY_PARAMETERS = (
    "mass",
    "com.0",
    "com.1",
    "com.2",
    "inertia.ixx",
    "inertia.iyy",
    "inertia.izz",
    "inertia.ixy",
    "inertia.ixz",
    "inertia.iyz",
)

#: Positions of (ixx, iyy, izz, ixy, ixz, iyz) in Pinocchio's dynamic parameters.
_PIN_INERTIA = (4, 6, 9, 5, 7, 8)


@dataclass(frozen=True)
class Sensitivity:
    """Derivative of a plan's final attitude error with respect to every body's parameters.

    Attributes:
        bodies: the body names (URDF links), base first; a captured payload is a row of its
            own (``captured_payload``, in its link's frame) after the body holding it, whose
            row then has that body's parameters without it.
        nominal: (B, 10) the parameters of :data:`BODY_PARAMETERS` per body (kg, m, kg m^2).
        jacobian: (3, B, 10) d(error rotation vector) / d(parameter): rad per kg, per m, per
            kg m^2.
        error: the nominal final error rotation vector (rad, goal frame).
        steps: Magnus steps of the integration grid (the plan's).
    """

    bodies: tuple[str, ...]
    nominal: np.ndarray
    jacobian: np.ndarray
    error: np.ndarray
    steps: int

    def first_order(self, delta: np.ndarray) -> np.ndarray:
        """Predicted error rotation vector (rad) for parameter changes ``delta`` (B, 10)."""
        return np.asarray(self.error + np.einsum("ibp,bp->i", self.jacobian, delta))


def body_names(robot: Robot) -> tuple[str, ...]:
    """Name of each moving body (Pinocchio joint 1 on): the URDF link its joint moves."""
    model = robot.model
    names = []
    for joint in range(1, model.njoints):
        if joint == 1:
            names.append(robot.base_link)
            continue
        link = next(
            f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint == joint
        )
        names.append(link)
    return tuple(names)


def _parameters(inertia: pin.Inertia) -> np.ndarray:
    """(10,) the parameters of :data:`BODY_PARAMETERS` of one inertia (kg, m, kg m^2)."""
    ic = np.asarray(inertia.inertia)
    return np.array([inertia.mass, *np.asarray(inertia.lever), *(ic[i, j] for i, j in _COMPONENTS)])


def body_parameters(robot: Robot) -> np.ndarray:
    """(B, 10) parameters of :data:`BODY_PARAMETERS` of each body (kg, m, kg m^2)."""
    return np.array([_parameters(inertia) for inertia in list(robot.model.inertias)[1:]])


#: (row, column) of ixx, iyy, izz, ixy, ixz, iyz in a 3 x 3 inertia.
_COMPONENTS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


@dataclass(frozen=True)
class _Row:
    """One row of the sensitivity: a body, or a link merged into one (the payload).

    ``joint``: the Pinocchio joint whose body holds it; ``nominal``: its ten parameters (kg,
    m, kg m^2) in its own frame; ``chain``: (10, 10) d(that body's dynamic parameters) /
    d(these parameters).
    """

    name: str
    joint: int
    nominal: np.ndarray
    chain: np.ndarray


def _rows(robot: Robot, payload_apart: bool) -> list[_Row]:
    """Every body's row; with ``payload_apart``, a captured payload apart from its holder.

    The payload (:func:`~freefloat.robot.payload.held_payload`, in its link's frame) is
    merged into its holder's body at its frame's placement ``(R, p)``: there its centre of
    mass is ``R c + p`` and its inertia ``R I R^T``, and the holder's own parameters are the
    body's dynamic parameters less the payload's. A holder with no mass of its own keeps no
    row.
    """
    rows = [
        _Row(name, b + 1, params, _dynamic_jacobian(params))
        for b, (name, params) in enumerate(
            zip(body_names(robot), body_parameters(robot), strict=True)
        )
    ]
    held = held_payload(robot) if payload_apart else None
    if held is None:
        return rows
    model = robot.model
    frame = model.frames[model.getFrameId(PAYLOAD_LINK, pin.FrameType.BODY)]
    placed = frame.placement.act(held)
    own = model.inertias[frame.parentJoint].toDynamicParameters() - placed.toDynamicParameters()
    rotation = np.asarray(frame.placement.rotation)
    turn = np.zeros((10, 10))  # d(parameters in the body frame) / d(in the payload's frame)
    turn[0, 0], turn[1:4, 1:4], turn[4:, 4:] = 1.0, rotation, _turned_components(rotation)
    payload = _Row(
        PAYLOAD_LINK,
        frame.parentJoint,
        _parameters(held),
        _dynamic_jacobian(_parameters(placed)) @ turn,
    )
    at = frame.parentJoint - 1
    kept = [payload]
    if own[0] > 0.0:
        holder = _parameters(pin.Inertia.FromDynamicParameters(own))
        kept.insert(0, _Row(rows[at].name, frame.parentJoint, holder, _dynamic_jacobian(holder)))
    return rows[:at] + kept + rows[at + 1 :]


def _turned_components(rotation: np.ndarray) -> np.ndarray:
    """(6, 6) the map of (ixx, iyy, izz, ixy, ixz, iyz) under ``I -> R I R^T``."""
    out = np.zeros((6, 6))
    for column, (i, j) in enumerate(_COMPONENTS):
        unit = np.zeros((3, 3))
        unit[i, j] = unit[j, i] = 1.0
        turned = rotation @ unit @ rotation.T
        out[:, column] = [turned[a, b] for a, b in _COMPONENTS]
    return out


def _dynamic_jacobian(params: np.ndarray) -> np.ndarray:
    """(10, 10) d(Pinocchio dynamic parameters) / d(mass, com, inertia about the com)."""
    m, c = params[0], params[1:4]
    cx, cy, cz = c
    # S = |c|^2 1 - c c^T in Pinocchio's order xx, xy, yy, xz, yz, zz (positions 4..9).
    s = np.array(
        [cy * cy + cz * cz, -cx * cy, cx * cx + cz * cz, -cx * cz, -cy * cz, cx * cx + cy * cy]
    )
    ds = np.array(  # d S / d (cx, cy, cz), rows in the order of s
        [
            [0.0, 2 * cy, 2 * cz],
            [-cy, -cx, 0.0],
            [2 * cx, 0.0, 2 * cz],
            [-cz, 0.0, -cx],
            [0.0, -cz, -cy],
            [2 * cx, 2 * cy, 0.0],
        ]
    )
    out = np.zeros((10, 10))
    out[0, 0] = 1.0
    out[1:4, 0] = c
    out[4:10, 0] = s
    out[1:4, 1:4] = m * np.eye(3)
    out[4:10, 1:4] = m * ds
    for column, row in enumerate(_PIN_INERTIA):
        out[row, 4 + column] = 1.0
    return out


def _node_sensitivities(
    robot: Robot, rows: list[_Row], q: np.ndarray, qs: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Base angular velocity (K, 3) and its derivative (K, 3, len(rows), 10) at K nodes.

    ``q`` (K, N) joint values, ``qs`` (K, N) their rates (any time unit; the result is in
    rad per that unit).
    """
    model, data = robot.model, robot.model.createData()
    config = robot.configuration(np.zeros(robot.n))
    omega = np.empty((len(q), 3))
    domega = np.empty((len(q), 3, len(rows), 10))
    dh = np.empty((6, len(rows), 10))
    for k in range(len(q)):
        robot.write_joints(config, q[k])
        ag = pin.computeCentroidalMap(model, data, config)
        com = np.asarray(data.com[0])
        v_base = -np.linalg.solve(ag[:, :6], ag[:, 6:] @ qs[k])
        omega[k] = v_base[3:]
        pin.forwardKinematics(model, data, config, np.concatenate([v_base, qs[k]]))
        for r, row in enumerate(rows):
            regressor = pin.bodyRegressor(pin.Motion.Zero(), data.v[row.joint])
            dh[:, r] = data.oMi[row.joint].toDualActionMatrix() @ regressor @ row.chain
        # momentum about the system CM: the angular part loses c x (linear part)
        dh_g = dh.copy()
        dh_g[3:] -= np.cross(com, dh[:3], axisa=0, axisb=0, axisc=0)
        dv = -np.linalg.solve(ag[:, :6], dh_g.reshape(6, -1))
        domega[k] = dv[3:].reshape(3, len(rows), 10)
    return omega, domega


def attitude_sensitivity(
    problem: Problem, beta: np.ndarray, steps: int | None = None, payload_apart: bool = True
) -> Sensitivity:
    """The exact sensitivity of the final attitude error along a path to every body's parameters.

    Args:
        problem: the problem (its robot is the nominal model; start and goal attitudes).
        beta: the path's free coefficients (rad or m).
        steps: Magnus steps on [0, 1]; default the problem's integration grid.
        payload_apart: a captured payload is a row of its own, apart from the body holding
            it (False: within that body, as format-4 plan files recorded it).
    """
    robot = problem.robot
    steps = problem.steps if steps is None else int(steps)
    nodes, h = step_nodes(np.linspace(0.0, 1.0, steps + 1))
    path = problem.family.evaluate(beta, nodes)
    rows = _rows(robot, payload_apart)
    omega, domega = _node_sensitivities(robot, rows, path.q, path.qd)
    bodies, count = domega.shape[2], domega.shape[2] * 10
    omega = omega.reshape(steps, 3, 3)
    domega = domega.reshape(steps, 9, count)
    increments = magnus_increments(omega, h)
    dw = np.einsum("mck,mkf->mcf", magnus_increment_jacobian(omega, h), domega)
    rotations = rotation_matrices(increments)
    after = np.empty_like(rotations)
    after[-1] = np.eye(3)
    for m in range(steps - 1, 0, -1):
        after[m - 1] = rotations[m] @ after[m]
    dtheta = np.einsum("mji,mjk,mkf->if", after, so3_right_jacobian(increments), dw)
    reached = propagate(problem.start_quaternion, increments)[-1]
    relative = relative_quat(problem.goal_quaternion, reached)
    jacobian = np.asarray(pin.Jlog3(quat_to_matrix(relative))) @ dtheta
    return Sensitivity(
        bodies=tuple(row.name for row in rows),
        nominal=np.array([row.nominal for row in rows]),
        jacobian=jacobian.reshape(3, bodies, 10),
        error=quat_log(relative),
        steps=steps,
    )
