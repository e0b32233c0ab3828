"""Strong poses (issue 22), shared by tests/python/test_strong_poses.py, the Blender test
scripts/strong_pose.py and bench/strong_poses.py: handles on the last 15% of the longest
bounding-box axis at each end (1.5 units of the normalised 10-unit model); the high end turned
about the long axis by 90 or 170 degrees, or the model bent by 90 or 180 degrees into a circular
arc (bench/shapes.rod_end's motion, for any axis). A pose is reached in steps of at most 30
degrees, each solved to convergence as a script would (follow), with a centred-difference check
of the objective at the end of each step. NumPy only: `follow` takes the modal_deform.core to use.
"""

import numpy as np

from .poses import end_handles

POSES = ("turn_90", "turn_170", "bend_90", "bend_180")
STEP_DEGREES = 30.0
STIFFNESS = 100.0


def _rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _about(axis, angle, point):
    """4x4: rotation by angle about the line through point along axis."""
    T = np.eye(4)
    T[:3, :3] = _rotation(axis, angle)
    T[:3, 3] = point - T[:3, :3] @ point
    return T


def ends(V, fraction=0.15):
    """(handles, long axis index, the two ends' centres, the length along the axis)."""
    handles, axes, length, high = end_handles(V, fraction)
    return handles, int(np.argmax(axes[0])), V[handles[0]].mean(axis=0), high, length


def transforms(V, pose, degrees, shift=(0.0, 0.0)):
    """The handles' transforms (low end held) for `pose` ("turn_*" or "bend_*") at `degrees`;
    `shift` moves the turned end along the other two axes too (in tenths of the length)."""
    handles, a, low, high, length = ends(V)
    e_a, e_side, e_up = np.eye(3)[a], np.eye(3)[(a + 1) % 3], np.eye(3)[(a + 2) % 3]
    angle = np.radians(degrees)
    if pose.startswith("turn"):
        T = _about(e_a, angle, high)
        T[:3, 3] += 0.1 * length * (shift[0] * e_side + shift[1] * e_up)
    elif angle == 0:
        T = np.eye(4)
    else:  # a circular arc in the long-up plane: the end back onto the low centre, then about the arc's centre
        span = high[a] - low[a]
        back = np.eye(4)
        back[:3, 3] = -span * e_a
        T = _about(np.cross(e_a, e_up), angle, low + span / angle * e_up) @ back
    return handles, [np.eye(4), T]


def difference_error(solver, seed=0):
    """The least error, over steps 1e-4 .. 1e-8, of the objective's centred difference along a
    random unit direction against its gradient, relative to 1 + |f|: small where f is smooth
    (its third derivatives along q are large: on the 23k dragon bent by 90 degrees the error falls
    from 31 at 1e-4 to 2.5e-3 at 1e-6), about jump / step where it jumps."""
    q = solver.q
    value, gradient = solver.objective(q)
    u = np.random.default_rng(seed).standard_normal(len(q))
    u /= np.linalg.norm(u)
    errors = []
    for h in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        plus, _ = solver.objective(q + h * u)
        minus, _ = solver.objective(q - h * u)
        errors.append(abs((plus - minus) / (2 * h) - gradient @ u))
    return min(errors) / (1 + abs(value))


def follow(mdc, basis, V, pose, check_differences=False, pull=STIFFNESS, final_iterations=3000):
    """Reaches `pose` in steps of at most STEP_DEGREES, each solved to convergence (tolerance
    1e-6); returns one dict of solve stats per step (with "difference_error" when asked). `mdc`:
    the modal_deform.core the basis came from (inside Blender, the installed add-on's)."""
    degrees = float(pose.split("_")[1])
    steps = int(np.ceil(degrees / STEP_DEGREES))
    handles, _ = transforms(V, pose, 0)
    solver = mdc.ReducedSolver(basis, handles, pull=pull)
    path = []
    for k in range(1, steps + 1):
        solver.set_transforms(transforms(V, pose, degrees * k / steps)[1])
        stats = solver.solve(max_iterations=final_iterations if k == steps else 500, tolerance=1e-6)
        if check_differences:
            stats["difference_error"] = difference_error(solver, seed=k)
        path.append(stats)
    return path
