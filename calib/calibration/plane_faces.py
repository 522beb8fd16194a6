"""The tilt-plane part of a six-face log: θ of the holds on faces in the tilt plane, the others
set aside — so that the tilt-plane commands (``gap``) take a six-face log without hand cutting.

A six-face test of a 3-axis sensor (:mod:`calib.calibration.sixface`) holds the case on its
faces. In the tilt plane's axes (x, y after ``--axes``, n = x × y) four of the faces lie in
the plane: the reference reading of a hold on face ``u`` (a unit case axis, the one pointing
up) is ``A_r = g·u``, and with the course signs ``A_rx = −g sin θ``, ``A_ry = −g cos θ``
(DESIGN.md) the face's table angle is::

    θ = atan2(−u_x, −u_y)        (rad):   +x up → −π/2,   −x up → +π/2,   −y up → 0,
                                          +y up → π

The faces ±n (the normal axis up or down) are outside the plane: their samples are dropped
and the provenance says which holds went where. A face is the case axis nearest the hold's
mean reading, within 20° (:data:`calib.calibration.sixface.FACE_COS`, the same rule as the
six-face fit); a log with a hold off every face is not a six-face log and is left alone.
The angles are the nominal ones of the faces (a face that is not flat, or a sensor misaligned
in its case, shows as lack of fit in ``gap``, which is what it is for).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from calib.calibration.sixface import face_name, faces_of
from calib.input_rules import DataError
from calib.logs.reader import ImuLog

PLANE_FACES_NEEDED = 2
"""In-plane faces needed for the subset to calibrate anything (two distinct θ)."""


def face_angle(u: np.ndarray) -> float:
    """θ (rad) of a hold on the in-plane face ``u`` (unit vector in x, y, n with u_n = 0):
    ``atan2(−u_x, −u_y)`` from the course signs (module docstring)."""
    return float(np.arctan2(-u[0], -u[1]))


def tilt_plane_faces(log: ImuLog) -> ImuLog | None:
    """The held samples of ``log`` on faces in the tilt plane, with θ from each face; None
    when ``log`` is not a six-face log with θ unknown (θ known, no third axis, fewer than two
    held poses, or a hold off every face).

    Returns
    -------
    ImuLog with ``theta`` (rad) per sample, ``pose`` re-labelled 0, 1, … over the in-plane
    holds in their order, every array cut alike; the provenance's ``plane_faces`` lists
    each hold's face and where it went (``theta_rad`` or ``"out of the tilt plane"``).

    Raises
    ------
    DataError : a six-face log with fewer than :data:`PLANE_FACES_NEEDED` distinct in-plane
        faces (nothing to calibrate in the plane), naming the faces it has.
    """
    if log.theta is not None or log.acc_normal is None or log.pose is None:
        return None
    labels = np.unique(log.pose[log.pose >= 0])
    if labels.size < 2:  # one hold (a still log) is no six-face log: θ is simply unknown
        return None
    acc3 = np.column_stack([log.acc, log.acc_normal])
    means = np.array([acc3[log.pose == k].mean(axis=0) for k in labels])
    try:
        u = faces_of(means, log.source)
    except DataError:
        return None
    names = [face_name(v).replace("z", "n") for v in u]  # the third axis is the normal n
    in_plane = np.abs(u[:, 2]) < 0.5
    distinct = sorted({names[i] for i in np.flatnonzero(in_plane)})
    if len(distinct) < PLANE_FACES_NEEDED:
        raise DataError(f"{log.source}: a six-face log with {len(distinct)} face(s) in the "
                        f"tilt plane ({', '.join(distinct) or 'none'}; faces held: "
                        f"{', '.join(sorted(set(names)))}); the tilt plane needs at least "
                        f"{PLANE_FACES_NEEDED} of ±x, ±y (n is the normal to --axes): choose "
                        "the plane with --axes")
    new_label = {int(k): j for j, k in enumerate(labels[in_plane])}
    angle = {int(k): face_angle(u[i]) for i, k in enumerate(labels) if in_plane[i]}
    keep = np.isin(log.pose, labels[in_plane])
    pose = np.array([new_label[int(k)] for k in log.pose[keep]], dtype=int)
    theta = np.array([angle[int(k)] for k in log.pose[keep]])
    record = [{"hold": int(k), "face": names[i],
               "theta_rad": angle[int(k)] if in_plane[i] else "out of the tilt plane"}
              for i, k in enumerate(labels)]
    prov = dict(log.provenance)
    prov["plane_faces"] = record
    prov["samples"] = dict(prov.get("samples", {}), kept=int(keep.sum()))
    dropped = [r["face"] for r in record if r["theta_rad"] == "out of the tilt plane"]
    prov["held_samples_only"] = (
        f"six-face log: the {int(in_plane.sum())} holds on faces in the tilt plane kept with θ "
        f"from the face ({int(keep.sum())} of {log.n} samples); "
        f"{len(dropped)} hold(s) on {', '.join(sorted(set(dropped))) or 'no'} face(s) "
        "out of the plane set aside")

    def cut(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else a[keep]

    return replace(log, acc=log.acc[keep], t=cut(log.t), theta=theta, pose=pose,
                   gyro=cut(log.gyro), acc_normal=cut(log.acc_normal), acc_s=cut(log.acc_s),
                   gyro_s=cut(log.gyro_s), provenance=prov)


__all__ = ["PLANE_FACES_NEEDED", "face_angle", "tilt_plane_faces"]
