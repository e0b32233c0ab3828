"""The benchmark's test shapes and poses, in one place for the benchmarks.

Generated shapes in the style of Botsch & Sorkine's linear-deformation benchmarks ("On Linear
Variational Surface Deformation Methods", 2008), scaled so that the longest bounding-box edge is
10 (the paper's normalised frame), each with one handle set and five poses (the bar six): the three
classic motions (lift, bend, twist) and larger ones. The shared scans (bunny, dragons) are read in
place with a generic pose: one end held, the other pulled and turned.

The meshes are the core's test shapes (mdc.testing, the C++ tests' own primitives); the first
poses follow tests/cpp/test_posing_accuracy.cpp, the reference (bumpy plane lifted in the middle,
rods bent and twisted by their ends). The shared meshes, rigid transforms and the scans' end-pull
pose come from the test-support package (tests/support), which this module puts on sys.path.

    shape = shapes.make("bar")
    for pose in shape.poses:
        for frame in range(1, pose.frames + 1):
            transforms = pose.at(frame / pose.frames)   # one 4x4 per handle in shape.handles
"""

import dataclasses
import pathlib
import sys

import numpy as np

import modal_deform.core as mdc

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from support import SCAN_FILES as _SCAN_FILES  # noqa: E402,F401
from support import SHARED_MESHES
from support.poses import Pose, end_handles, end_pull, rigid_transform, translation  # noqa: E402,F401

#: Generated shapes and the shared scans, in the order tables list them.
GENERATED = ("bumpy_plane", "cylinder", "bar")
SCANS = ("bunny", "dragon_res4", "dragon_res3", "dragon_res2")


@dataclasses.dataclass(frozen=True)
class Shape:
    """A mesh (V (n, 3), F (m, 3)), its handles (list of vertex index arrays), its poses, and the
    direction renders look from (towards the shape)."""

    name: str
    V: np.ndarray
    F: np.ndarray
    handles: list
    poses: tuple
    view: tuple

    def pose(self, name):
        return next(p for p in self.poses if p.name == name)


def rod_end(length, axis, bend, twist):
    """The far end of a rod along z (from 0 to ``length``, its axis through the point ``axis`` at
    z = 0) after bending it by ``bend`` into a circular arc in the y-z plane and twisting it by
    ``twist`` about its own axis (radians)."""
    axis = np.array([axis[0], axis[1], 0.0])
    turn = rigid_transform((0, 0, 1), twist, axis)
    if bend == 0:
        return turn
    arc = rigid_transform((-1, 0, 0), bend, axis + np.array([0, length / bend, 0]))
    return arc @ translation((0, 0, -length)) @ turn


def _rod_poses(length, axis, poses):
    """Rod poses: the near end held, the far end bent/twisted/shifted per (name, description,
    bend, twist, shift, frames)."""

    def motion(bend, twist, shift):
        return lambda t: [
            np.eye(4),
            translation((0, t * shift, 0)) @ rod_end(length, axis, t * bend, t * twist),
        ]

    return tuple(Pose(name, text, motion(b, w, s), frames) for name, text, b, w, s, frames in poses)


def bumpy_plane(n=199):
    """Bumpy plane, 10 by 10 with 12 bumps ((n+1)² vertices, 40k by default): the border held,
    a disc of radius 1 in the middle moved."""
    V, F = mdc.testing.bumpy_plane(n, 10.0, 12, 1.0)
    r = np.hypot(V[:, 0], V[:, 1])
    handles = [np.flatnonzero(np.abs(V[:, :2]).max(axis=1) > 5 - 1e-9), np.flatnonzero(r < 1)]
    centre = V[handles[1]].mean(axis=0)

    def lift(height, tilt=0.0, turn=0.0):
        def at(t):
            T = translation((0, 0, t * height)) @ rigid_transform((0, 1, 0), t * tilt, centre)
            return [np.eye(4), T @ rigid_transform((0, 0, 1), t * turn, centre)]

        return at

    deg = np.pi / 180
    poses = (
        Pose("lift", "middle lifted by 3 (30% of the width)", lift(3), 3),
        Pose("bend", "middle lifted by 3 and tilted by 30 deg", lift(3, tilt=30 * deg), 3),
        Pose("twist", "middle lifted by 3 and turned by 90 deg", lift(3, turn=90 * deg), 3),
        Pose("lift_large", "middle lifted by 5 (50% of the width)", lift(5), 5),
        Pose("bend_large", "middle lifted by 5 and tilted by 60 deg", lift(5, tilt=60 * deg), 5),
    )
    return Shape("bumpy_plane", V, F, handles, poses, view=(-1.0, -1.6, -0.9))


def _rod_handles(V, length):
    return [np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > length - 1e-9)]


def cylinder(around=64, along=80):
    """Open tube of radius 1.25 and length 10 (around x (along+1) vertices, 5k by default), its
    end rings as handles."""
    V, F = mdc.testing.cylinder(around, along, 1.25, 10.0)
    deg = np.pi / 180
    poses = _rod_poses(
        10.0,
        (0, 0),
        (
            ("lift", "far ring shifted sideways by 2.5", 0, 0, 2.5, 3),
            ("bend", "bent by 60 deg", 60 * deg, 0, 0, 2),
            ("twist", "twisted by 90 deg", 0, 90 * deg, 0, 3),
            ("bend_twist", "bent by 60 and twisted by 90 deg", 60 * deg, 90 * deg, 0, 6),
            ("bend_large", "bent by 120 deg", 120 * deg, 0, 0, 6),
        ),
    )
    return Shape("cylinder", V, F, _rod_handles(V, 10.0), poses, view=(1.0, -0.4, -0.35))


def bar(nx=12, nz=120):
    """Closed 1 x 1 x 10 box (about 6k vertices by default), its end faces as handles."""
    V, F = mdc.testing.bar(nx, nx, nz, 1.0, 1.0, 10.0)
    deg = np.pi / 180
    poses = _rod_poses(
        10.0,
        (0.5, 0.5),
        (
            ("lift", "far end shifted sideways by 2", 0, 0, 2.0, 3),
            ("bend", "bent by 90 deg", 90 * deg, 0, 0, 6),
            ("bend_60", "bent by 60 deg", 60 * deg, 0, 0, 4),
            ("twist", "twisted by 90 deg", 0, 90 * deg, 0, 6),
            ("bend_large", "bent by 180 deg", 180 * deg, 0, 0, 6),
            ("twist_large", "twisted by 180 deg (the reference buckles)", 0, 180 * deg, 0, 6),
        ),
    )
    return Shape("bar", V, F, _rod_handles(V, 10.0), poses, view=(1.0, -0.35, -0.3))


def end_turns(V, turns=(30, 90, 170), bend=90):
    """Handles of a scan along its longest bounding-box axis, the 15% at each end, and poses of its
    high end (Refine's, bench/refine.py): "turn_<d>" turns it by d degrees about the long axis and
    moves it by 9% of the length sideways and 4.5% up; "bend_<bend>" turns it about the up axis."""
    handles, (along, side, up_axis), length, centre = end_handles(V, 0.15)
    shift = 0.09 * length * side + 0.045 * length * up_axis

    def motion(axis, degrees, moved):
        return lambda t: [
            np.eye(4),
            rigid_transform(axis, t * np.radians(degrees), centre, t * moved),
        ]

    poses = tuple(
        Pose(
            f"turn_{d}",
            f"far end turned by {d} deg about the long axis and moved",
            motion(along, d, shift),
            max(2, round(d / 15)),
        )
        for d in turns
    )
    if bend:
        poses += (
            Pose(
                f"bend_{bend}",
                f"far end turned by {bend} deg about the up axis",
                motion(up_axis, bend, np.zeros(3)),
                max(2, round(bend / 15)),
            ),
        )
    return handles, poses


def turned_scan(name, turns):
    """A shared scan in the normalised frame (scaled so that its longest bounding-box edge is 10)
    with Refine's handles and turns (end_turns, no bend)."""
    V, F = mdc.read_mesh(SHARED_MESHES / _SCAN_FILES[name])
    V = (V - V.min(axis=0)) * (10.0 / np.ptp(V, axis=0).max())
    handles, poses = end_turns(V, turns, bend=None)
    return Shape(name, V, F, handles, poses, (0.3, -1.0, -0.3))


def scan(name):
    """A shared scan (read in place, in its own units) with the end_pull handles and pose."""
    V, F = mdc.read_mesh(SHARED_MESHES / _SCAN_FILES[name])
    handles, poses = end_pull(V)
    view = (0.0, -1.0, -0.25) if name == "bunny" else (0.3, -1.0, -0.3)
    return Shape(name, V, F, handles, poses, view)


def make(name, **sizes):
    """The shape called ``name`` (GENERATED or SCANS); ``sizes`` override a generated shape's
    resolution (the smoke test's small meshes)."""
    if name in _SCAN_FILES:
        return scan(name)
    return {"bumpy_plane": bumpy_plane, "cylinder": cylinder, "bar": bar}[name](**sizes)
