"""Rocker kinematics for many chains at once [R1]–[R6] (physics §3): the batch drivers of
:mod:`engine_kernels.valvetrain.rocker`, one case per prange row."""

from __future__ import annotations

from engine_kernels._jit import batch, prange
from engine_kernels.valvetrain.rocker import rocker_valve_lift, tappet_lift_for_valve_lift


@batch
def rocker_valve_lift_batch(
    phi, lift, lift_velocity, lift_acceleration, geometry, side, theta, out, status
):
    """:func:`rocker_valve_lift` for many rocker geometries on one cam (one per prange row).

    phi, lift, lift_velocity, lift_acceleration : 1-D arrays  The shared tappet table
                                                  ([rad], [m], [m/rad], [m/rad²]).
    geometry : 2-D array  (n_cases, 8) rows indexed by the ``G_*`` constants [m].
    side     : int        ``PAD_AHEAD`` or ``PAD_BEHIND``.
    theta    : 1-D array  Output cam rotation angles [rad].
    out      : 3-D array  (n_cases, 6, len(theta)) curves, ``ROW_*`` order.
    status   : 1-D int array  (n_cases,) status flags.
    """
    for i in prange(geometry.shape[0]):
        status[i] = rocker_valve_lift(
            phi, lift, lift_velocity, lift_acceleration, geometry[i], side, theta, out[i]
        )


@batch
def tappet_lift_for_valve_lift_batch(valve_lift, geometry, out):
    """:func:`tappet_lift_for_valve_lift` for many chains (one per prange row) [R3], [R6].

    valve_lift : 1-D array  (n_cases,) theoretical valve lift Y [m].
    geometry   : 2-D array  (n_cases, 8) rows indexed by the ``G_*`` constants [m].
    out        : 1-D array  (n_cases,) tappet lift at the nose [m] (written; NaN where the
                            valve arm cannot reach Y).
    """
    for i in prange(geometry.shape[0]):
        out[i] = tappet_lift_for_valve_lift(valve_lift[i], geometry[i])
