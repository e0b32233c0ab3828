"""Physics in-betweens (issue 51): mdc.Inbetween's solve and per-frame cost on the dragon, how the
solve grows with frames and dimensions, and the reproduction of a free motion from its keys.

    PYTHONPATH=python_addon /usr/bin/python3 bench/run.py --only inbetween [--quick]

- cost: the 100k dragon baked with the paper's 67 dimensions (15 modes, rigid motions among them,
  and 52 derivatives), the tail held (keyed at rest) and the head keyed at 5 poses over 120 frames
  (turns of up to 30° about the vertical and a sideways shift, back to rest at the end): the solve's
  wall time, iterations and ghost gradient evaluations, and a frame's positions (positions(frame)
  inside the keys, the map of a solved state) against the issue's 1 s and 2 ms.
- frames: the same keys spread over 30, 60, 120 and 240 frames (the solve's unknowns grow with
  them); dimensions: the 120 frames at 30, 67 and 100 dimensions (the 23k dragon: the bake of a
  larger basis of the 100k one alone takes minutes).
- reproduction: the dragon released at rest from posing's minimum with the head turned 10° and
  moving freely for 48 frames (Simulation, no handle acting); keys every 12 frames, each handle's
  rigid fit there: the largest distance between the in-betweens' and Simulation's vertices over
  the frames, relative to the mesh's diagonal, and each key's fit error against posing's at the
  same transforms.
"""

import time

import numpy as np
from dynamics import tail_and_head
from shapes import rigid_transform as rigid
from support import SHARED_MESHES as MESHES
from support.inbetween import free_motion_keys

import modal_deform.core as mdc

PAPER = dict(modes=15, derivatives=52)
DIMENSIONS = [dict(modes=10, derivatives=20), PAPER, dict(modes=20, derivatives=80)]
FRAMES = [30, 60, 120, 240]
KEYS = 5


def keys_over(V, handles, frames):
    """KEYS keys spread over `frames`: the tail at rest, the head turned about the vertical (0°,
    30°, −20°, 15°, 0°) and shifted sideways by up to 10% of the length."""
    centre = V[handles[1]].mean(axis=0)
    length = np.ptp(V[:, 0])
    turns = np.radians([0, 30, -20, 15, 0])
    shifts = [0, 0.1, -0.05, 0.05, 0]
    return [
        (
            round(k * frames / (KEYS - 1)),
            [np.eye(4), rigid([0, 0, 1], turns[k], centre, [0, shifts[k] * length, 0])],
        )
        for k in range(KEYS)
    ]


def solve_cost(basis, V, handles, frames):
    ib = mdc.Inbetween(basis, handles, keys_over(V, handles, frames))
    stats = ib.solve()
    out = np.empty((len(V), 3), np.float32)
    times = []
    for frame in range(ib.first_frame, ib.last_frame):
        start = time.perf_counter()
        ib.positions(frame, out)
        times.append(1e3 * (time.perf_counter() - start))
    return {
        "frames": frames,
        "dimension": basis.dimension,
        "solve_s": stats["ms"] / 1e3,
        "converged": stats["converged"],
        "iterations": stats["iterations"],
        "evaluations": stats["evaluations"],
        "nodes": stats["nodes"],
        "control": stats["control"],
        "initial_control": stats["initial_control"],
        "positions_ms": {"median": float(np.median(times)), "max": float(max(times))},
    }


def key_error(V, handle, X, T):
    fit = mdc.rigid_fit(V[handle], X[handle])
    return float(np.linalg.norm(V[handle] @ (fit - T)[:3, :3].T + (fit - T)[:3, 3], axis=1).max())


def reproduction(basis, V, handles, frames=48, every=12):
    diagonal = float(np.linalg.norm(np.ptp(V, axis=0)))
    centre = V[handles[1]].mean(axis=0)
    start = [np.eye(4), rigid([0, 0, 1], np.radians(10), centre)]
    positions, keys = free_motion_keys(basis, handles, start, frames, range(0, frames + 1, every))
    ib = mdc.Inbetween(basis, handles, keys)
    stats = ib.solve()
    error = [float(np.abs(ib.positions(f) - positions[f]).max()) for f in range(frames + 1)]
    keys_vs_posing = []
    for frame, transforms in keys:
        pose = mdc.ReducedSolver(basis, handles)
        pose.set_transforms(transforms)
        pose.solve(max_iterations=1000, tolerance=1e-8)
        for h, T in zip(handles, transforms):
            keys_vs_posing.append(
                {
                    "frame": frame,
                    "inbetween": key_error(V, h, ib.positions(frame), T) / diagonal,
                    "posing": key_error(V, h, pose.positions(), T) / diagonal,
                }
            )
    return {
        "frames": frames,
        "key_every": every,
        "excursion": float(np.abs(positions - V).max()) / diagonal,
        "error": max(error) / diagonal,
        "error_first_frame": error[0] / diagonal,
        "converged": stats["converged"],
        "iterations": stats["iterations"],
        "solve_s": stats["ms"] / 1e3,
        "key_errors": keys_vs_posing,
    }


def run(quick=False):
    big, small = (
        ("dragon_vrip_res4", "dragon_vrip_res4")
        if quick
        else ("dragon_vrip_res2", "dragon_vrip_res3")
    )
    V, F = mdc.read_mesh(MESHES / f"{big}.ply.gz")
    handles = tail_and_head(V)
    start = time.perf_counter()
    basis = mdc.bake(V, F, **PAPER)
    bake_s = time.perf_counter() - start
    figures = {"mesh": big, "vertices": len(V), "bake_s": bake_s}
    figures["cost"] = solve_cost(basis, V, handles, 120)
    print(
        f"   cost: solve {figures['cost']['solve_s']:.2f} s, positions "
        f"{figures['cost']['positions_ms']['median']:.2f} ms",
        flush=True,
    )
    figures["frames"] = [
        solve_cost(basis, V, handles, f) for f in (FRAMES[:2] if quick else FRAMES)
    ]
    figures["reproduction"] = reproduction(basis, V, handles)
    print(f"   reproduction: {figures['reproduction']['error']:.2e} of the diagonal", flush=True)
    Vs, Fs = mdc.read_mesh(MESHES / f"{small}.ply.gz")
    small_handles = tail_and_head(Vs)
    figures["dimensions"] = {"mesh": small, "vertices": len(Vs), "runs": []}
    for sizes in DIMENSIONS[:2] if quick else DIMENSIONS:
        b = mdc.bake(Vs, Fs, **sizes)
        figures["dimensions"]["runs"].append({**sizes, **solve_cost(b, Vs, small_handles, 120)})
    parameters = {
        "defaults": {name: o.default for name, o in mdc.INBETWEEN_OPTIONS.items()},
        "paper_bake": PAPER,
        "keys": KEYS,
        "dimension_bakes": DIMENSIONS,
        "frames": FRAMES,
    }
    return parameters, figures
