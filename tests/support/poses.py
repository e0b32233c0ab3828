"""Rigid transforms and poses of handles, as the benchmarks and tests move them, and smooth shape
keys of a mesh (NumPy only).

handles, poses = poses.end_pull(V)
for frame in range(1, poses[0].frames + 1):
    transforms = poses[0].at(frame / poses[0].frames)   # one 4x4 per handle
"""

import dataclasses
from typing import Callable

import numpy as np


@dataclasses.dataclass(frozen=True)
class Pose:
    """A motion of the handles: ``at(t)`` the transforms (one 4x4 per handle, mesh units) a
    fraction t in [0, 1] of the way from rest; reached in ``frames`` steps, as an animation."""

    name: str
    description: str
    at: Callable[[float], list]
    frames: int


def rigid_transform(axis, angle, centre, t=(0.0, 0.0, 0.0)):
    """The 4x4 transform x -> R (x - centre) + centre + t, R the rotation by ``angle`` (radians)
    about ``axis``."""
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K  # Rodrigues
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(centre) + np.asarray(t) - R @ np.asarray(centre)
    return T


def translation(t):
    T = np.eye(4)
    T[:3, 3] = t
    return T


def end_handles(V, fraction):
    """Handles on the `fraction` of a scan's length at each end of its longest bounding-box axis
    (low end first); with the (long, side, up) axes as unit vectors, the length and the high end's
    centre."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    a = int(np.argmax(hi - lo))
    length = hi[a] - lo[a]
    handles = [
        np.flatnonzero(V[:, a] < lo[a] + fraction * length),
        np.flatnonzero(V[:, a] > hi[a] - fraction * length),
    ]
    axes = np.eye(3)[[a, (a + 1) % 3, (a + 2) % 3]]
    return handles, axes, length, V[handles[1]].mean(axis=0)


def end_pull(V):
    """Handles of a scan along its longest bounding-box axis: the 10% at its low end held, the
    10% at its high end; the pose turns that end by 0.6 rad about the up axis and moves it by a
    quarter of the length sideways (as bench/bench_solve.cpp poses the dragon)."""
    handles, (_, side, up), length, centre = end_handles(V, 0.1)
    axis, shift = up, 0.25 * length * side

    def at(t):
        return [np.eye(4), rigid_transform(axis, 0.6 * t, centre, t * shift)]

    return handles, (
        Pose("pull", "far 10% turned by 0.6 rad and moved by a quarter of the length", at, 6),
    )


def smooth_keys(V, count, seed=1):
    """`count` smooth deformations of V (n, 3), float64, as shape keys for the shape blending
    benchmarks: each swings the part beyond a plane across the longest axis about an axis through
    the centre, by an angle that rises smoothly across the plane (a random plane, axis and angle
    of 0.6 to 1.2 radians per key, from `seed`)."""
    rng = np.random.default_rng(seed)
    centre = V.mean(0)
    extent = V.max(0) - V.min(0)
    long = int(np.argmax(extent))
    t = (V[:, long] - V[:, long].min()) / extent[long]
    keys = []
    for j in range(count):
        cut = 0.3 + 0.4 * rng.random()
        side = 1 if j % 2 else -1
        s = np.clip((side * (t - cut)) / 0.2 + 0.5, 0, 1)
        s = s * s * (3 - 2 * s)
        axis = rng.normal(size=3)
        angle = (0.6 + 0.6 * rng.random()) * (1 if rng.random() < 0.5 else -1)
        pivot = centre.copy()
        pivot[long] = V[:, long].min() + cut * extent[long]
        # each vertex turned by its own fraction s of the angle about the pivot (Rodrigues)
        angles = angle * s
        a = axis / np.linalg.norm(axis)
        P = V - pivot
        cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
        X = P * cos + np.cross(a, P) * sin + a * (P @ a)[:, None] * (1 - cos) + pivot
        keys.append(X)
    return keys
