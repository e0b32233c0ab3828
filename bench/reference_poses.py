"""Bases and poses of the bench meshes, saved or compared bit for bit: the check that a change
which should not change behaviour (a refactoring) does not.

Cases: the default bake (modes, derivatives, ghost) of the bunny and of the 5k and 23k dragons,
and on the 5k dragon a painted-stiffness bake, a region bake and a proxy bake; a reduced pose of
each default bake (end_turns' "turn_90", 50 BFGS iterations); solve_full from rest and Refine from
the reduced pose on the 5k dragon ("turn_30"). Each case is one .npz of every array the result
holds (the stored basis fields, q and positions, the full solve's positions and scalar stats).

    PYTHONPATH=python_addon:bench /usr/bin/python3 bench/reference_poses.py save DIR
    PYTHONPATH=python_addon:bench /usr/bin/python3 bench/reference_poses.py compare DIR

`compare` prints each array that differs in any bit and exits 1 if one does; timings (seconds,
ms) are not compared.
"""

import argparse
import pathlib
import sys

import numpy as np
import shapes

import modal_deform.core as mdc

# Stats that measure time, not behaviour.
_TIMES = {"seconds", "ms"}


def _mesh(name):
    return mdc.read_mesh(shapes.SHARED_MESHES / shapes._SCAN_FILES[name])


def _basis_arrays(basis):
    return {f"basis.{k}": v for k, v in basis.to_arrays().items()}


def _stats_arrays(prefix, stats):
    arrays = {}
    for key, value in stats.items():
        if key in _TIMES:
            continue
        if key == "history":
            for field in ("shift", "step", "ratio", "energy", "gradient_norm", "cg_iterations"):
                arrays[f"{prefix}.history.{field}"] = np.array([it[field] for it in value])
            continue
        arrays[f"{prefix}.{key}"] = np.array(value)
    return arrays


def _reduced_pose(basis, V):
    handles, poses = shapes.end_turns(V, turns=(90,), bend=None)
    solver = mdc.ReducedSolver(basis, handles)
    solver.set_transforms(poses[0].at(1.0))
    stats = solver.solve(max_iterations=50)
    arrays = {"pose.q": solver.q, "pose.positions": solver.positions()}
    arrays.update(_stats_arrays("pose", stats))
    return arrays


def cases():
    """{case name: function returning {array name: array}}."""

    def default_bake(name):
        def run():
            V, F = _mesh(name)
            basis = mdc.bake(V, F)
            return {**_basis_arrays(basis), **_reduced_pose(basis, V)}

        return run

    def painted():
        V, F = _mesh("dragon_res4")
        weights = np.clip((V[:, 0] - V[:, 0].min()) / np.ptp(V[:, 0]), 0, 1)
        return _basis_arrays(mdc.bake(V, F, stiffness_weights=weights, max_stiffness=50.0))

    def region():
        V, F = _mesh("dragon_res4")
        return _basis_arrays(mdc.bake(V, F, region=np.flatnonzero(V[:, 0] > np.median(V[:, 0]))))

    def proxy():
        V, F = _mesh("dragon_res4")
        return _basis_arrays(mdc.bake(V, F, proxy=1500, proxy_above=2000))

    def full_and_refine():
        V, F = _mesh("dragon_res4")
        handles, poses = shapes.end_turns(V, turns=(30,), bend=None)
        transforms = poses[0].at(1.0)
        X, stats = mdc.solve_full(V, F, handles, transforms, pull=100.0)
        arrays = {"full.positions": X, **_stats_arrays("full", stats)}
        solver = mdc.ReducedSolver(mdc.bake(V, F, modes=15), handles, pull=100.0)
        solver.set_transforms(transforms)
        solver.solve(max_iterations=200)
        X, stats = solver.refine(F)
        arrays.update({"refine.positions": X, **_stats_arrays("refine", stats)})
        return arrays

    return {
        "bunny": default_bake("bunny"),
        "dragon_res4": default_bake("dragon_res4"),
        "dragon_res3": default_bake("dragon_res3"),
        "dragon_res4_painted": painted,
        "dragon_res4_region": region,
        "dragon_res4_proxy": proxy,
        "dragon_res4_full_refine": full_and_refine,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("action", choices=("save", "compare"))
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("--only", nargs="*", help="case names (default: all)")
    args = parser.parse_args()
    args.folder.mkdir(parents=True, exist_ok=True)
    differ = False
    for name, run in cases().items():
        if args.only and name not in args.only:
            continue
        arrays = run()
        path = args.folder / f"{name}.npz"
        if args.action == "save":
            np.savez(path, **arrays)
            print(f"{name}: saved {len(arrays)} arrays to {path}")
            continue
        stored = dict(np.load(path))
        changed = sorted(set(stored) ^ set(arrays))
        changed += [
            key
            for key in sorted(set(stored) & set(arrays))
            if stored[key].dtype != arrays[key].dtype
            or stored[key].shape != np.shape(arrays[key])
            or stored[key].tobytes() != np.asarray(arrays[key], stored[key].dtype).tobytes()
        ]
        differ = differ or bool(changed)
        print(
            f"{name}: {'identical' if not changed else 'DIFFERS in ' + ', '.join(changed)} ({len(stored)} arrays)"
        )
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
