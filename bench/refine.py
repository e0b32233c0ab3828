"""Refine and the full solve on real scans (issue 26): Newton on the full mesh from rest, and
Refine from the reduced pose.

Meshes: the shared dragons at 23k (dragon_res3) and 100k (dragon_res2) vertices, and a
raw-scan-like 23k dragon (tests/support/raw_scans.damaged, seed 0: slivers, needles, fins, debris).
Handles: the last 15% of the length at each end (1.5 units once scaled to a length of 10);
stiffness 100. Poses: the far end turned about the long axis by 30, 90 and 170 degrees and moved
by 9% of the length sideways and 4.5% up ("turn"), and bent about the up axis by 90 degrees
("bend"). From rest (the 23k dragon only: at 100k it takes most of an hour a pose): mdc.solve_full
with its load steps. Refine: the paper's basis (15 modes + 52
derivatives, 1k ghost), the reduced pose converged (at most 2000 BFGS iterations), then
ReducedSolver.refine from it; the table reports the reduced pose's objective gap and vertex RMS
(relative to the bounding-box diagonal) against the refined minimum. Crushed: faces with less than
5% of their rest area where the solve starts and where it ends; Newton keeps every face from
turning over, so each one the minimum crushes cuts steps on the way. Targets: from rest the 23k
dragon converges at 30 and 90 degrees; Refine converges at 23k within 15 s and at 100k within 60 s.

    PYTHONPATH=python_addon /usr/bin/python3 bench/run.py --only refine
    PYTHONPATH=python_addon:bench /usr/bin/python3 bench/refine.py [--quick] [--meshes dragon_res3 ...]
        [--poses "dragon_res2=turn 30" ...] [--record]
"""

import argparse
import json
import os
import shlex
import sys
import time

import common
import numpy as np
import shapes
from support import raw_scans

import modal_deform.core as mdc

STIFFNESS = 100.0
TURNS = (30, 90, 170)
BEND = 90
TARGETS = {
    "refine_seconds": {"dragon_res3": 15.0, "dragon_res2": 60.0},
    "from_rest_converges": {"dragon_res3": (30, 90)},
}
MESHES = ("dragon_res3", "raw_dragon_res3", "dragon_res2")
CRUSHED_BELOW = 0.05  # of a face's rest area


def mesh(name):
    """(V, F) of a shared dragon, or of the raw-scan-like 23k dragon ("raw_" prefix)."""
    if name.startswith("raw_"):
        V, F = mdc.read_mesh(shapes.SHARED_MESHES / shapes._SCAN_FILES[name[4:]])
        return raw_scans.damaged(V, F, seed=0)
    return mdc.read_mesh(shapes.SHARED_MESHES / shapes._SCAN_FILES[name])


def poses(V):
    """Handles (both ends, 15% of the length each) and {pose name: transforms} of a mesh."""
    handles, named = shapes.end_turns(V, TURNS, BEND)
    return handles, {pose.name.replace("_", " "): pose.at(1.0) for pose in named}


def face_areas(X, F):
    return 0.5 * np.linalg.norm(np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]), axis=1)


def crushed_faces(rest_areas, X, F):
    """Faces of X with less than CRUSHED_BELOW of their rest area (faces of no area at rest left out)."""
    return int(np.sum((rest_areas > 0) & (face_areas(X, F) < CRUSHED_BELOW * rest_areas)))


def from_rest(V, F, rest_areas, handles, transforms):
    start = time.perf_counter()
    X, stats = mdc.solve_full(V, F, handles, transforms, pull=STIFFNESS)
    stats["wall_seconds"] = time.perf_counter() - start
    stats.update(crushed_at_start=0, crushed_at_end=crushed_faces(rest_areas, X, F))
    return stats


def refine(basis, F, rest_areas, handles, transforms):
    solver = mdc.ReducedSolver(basis, handles, pull=STIFFNESS)
    solver.set_transforms(transforms)
    start = time.perf_counter()
    reduced = solver.solve(max_iterations=2000, tolerance=1e-6)
    reduced_seconds = time.perf_counter() - start
    reduced_X = solver.positions().astype(np.float64)
    start = time.perf_counter()
    X, stats = solver.refine(F)
    stats["wall_seconds"] = time.perf_counter() - start
    stats.update(
        reduced_seconds=reduced_seconds,
        reduced_iterations=reduced["iterations"],
        reduced_converged=reduced["converged"],
        reduced_ghost_objective=reduced["energy"],
        gap=stats["initial_energy"] - stats["energy"],
        rms=common.rms_error(reduced_X, X),
        crushed_at_start=crushed_faces(rest_areas, reduced_X, F),
        crushed_at_end=crushed_faces(rest_areas, X, F),
    )
    return stats


def row(stats):
    keys = (
        "steps",
        "iterations",
        "factorizations",
        "seconds",
        "wall_seconds",
        "energy",
        "initial_energy",
        "converged",
        "stalled",
        "gradient_norm",
        "gradient_scale",
        "gap",
        "rms",
        "reduced_seconds",
        "reduced_iterations",
        "reduced_converged",
        "relaxed_vertices",
        "crushed_at_start",
        "crushed_at_end",
    )
    history = stats["history"]
    return {k: stats[k] for k in keys if k in stats} | {
        "exact_iterations": sum(it["model"] == "exact" for it in history),
        "guarded_steps": sum(it["guarded"] for it in history),
        "line_search_failures": sum(it["step"] == 0 for it in history),
        "load_average": os.getloadavg()[0],
    }


def run(quick=False, meshes=MESHES, poses_of=None):
    """poses_of: {mesh: pose names} to run only those poses of a mesh (all of the others')."""
    meshes = ("dragon_res4",) if quick else meshes
    figures = {}
    for name in meshes:
        V, F = mesh(name)
        handles, named_poses = poses(V)
        rest_areas = face_areas(V, F)
        if poses_of and name in poses_of:
            named_poses = {pose: t for pose, t in named_poses.items() if pose in poses_of[name]}
        entry = {
            "vertices": len(V),
            "faces": len(F),
            "handle_vertices": [len(h) for h in handles],
            "from_rest": {},
            "refine": {},
        }
        start = time.perf_counter()
        basis = mdc.bake(V, F, modes=15, derivatives=52, ghost=1000)
        entry["bake_seconds"] = time.perf_counter() - start
        for pose, transforms in named_poses.items():
            entry["refine"][pose] = row(refine(basis, F, rest_areas, handles, transforms))
            print(name, "refine", pose, json.dumps(entry["refine"][pose]), flush=True)
        if name not in TARGETS["from_rest_converges"]:
            figures[name] = entry
            continue  # from rest at 100k takes most of an hour a pose
        for pose, transforms in named_poses.items():
            entry["from_rest"][pose] = row(from_rest(V, F, rest_areas, handles, transforms))
            print(name, "from rest", pose, json.dumps(entry["from_rest"][pose]), flush=True)
        figures[name] = entry
    parameters = {
        "stiffness": STIFFNESS,
        "turns": TURNS,
        "bend": BEND,
        "basis": "15 modes + 52 derivatives, 1k ghost",
        "tolerance": 1e-8,
        "targets": TARGETS,
        "meshes": list(meshes),
    }
    return parameters, figures


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--quick", action="store_true", help="the 5k dragon only")
    parser.add_argument("--meshes", nargs="+", default=MESHES, choices=MESHES + ("dragon_res4",))
    parser.add_argument(
        "--poses",
        nargs="+",
        metavar="MESH=POSE",
        default=[],
        help='only these poses of a mesh, e.g. "dragon_res2=turn 30" (a mesh not named runs all)',
    )
    parser.add_argument(
        "--record",
        action="store_true",
        help="write bench/results/refine.json (as make bench does) instead of printing the figures",
    )
    args = parser.parse_args()
    poses_of = {}
    for item in args.poses:
        name, pose = item.split("=", 1)
        poses_of.setdefault(name, []).append(pose)
    start = time.perf_counter()
    parameters, figures = run(args.quick, tuple(args.meshes), poses_of)
    if args.record:
        command = "PYTHONPATH=python_addon:bench /usr/bin/python3 " + shlex.join(
            ["bench/refine.py"] + sys.argv[1:]
        )
        print(
            f"wrote {common.write('refine', command, parameters, figures, time.perf_counter() - start)}"
        )
    else:
        json.dump({"parameters": parameters, "figures": figures}, sys.stdout, indent=1)


if __name__ == "__main__":
    main()
