"""Fig. 5/12 analogue: how close reduced poses come to the full nonlinear solve as the basis grows,
with modal derivatives and with linear modes only (paper Figs. 5 and 12).

For each shape, basis size (modes, derivatives) and pose: the reduced solver run to convergence
through the pose's frames, against mdc.solve_full (Newton on the fine mesh, same objective).
The ghost is the mesh itself, so that the error is the basis's. (The bumpy plane is left out: its
full solves and 300-dimensional bases on 40k vertices take longer than the suite's budget.) A linear-only basis has modes + derivatives vibration modes and no derivatives.
Reported: vertex RMS error relative to the bounding-box diagonal, and the relative gap of the
shells energy, (E(reduced) - E(full)) / E(full), in the normalised frame.
"""
import numpy as np

import modal_deform.core as mdc
import shapes
from common import MESHES, rms_error

#: The paper's (vibration modes, modal derivatives); the bake's modes count the 6 rigid motions on top.
SIZES = ((8, 6), (10, 20), (15, 52), (20, 110), (30, 270))
RIGID = 6
TOLERANCE = 1e-8
#: Poses kept as meshes (bench/results/tmp/meshes/, not committed) for the side-by-side renders,
#: with the basis of RENDERED_SIZE.
RENDERED = {"bar": ("bend_large", "twist"), "cylinder": ("bend_large", "bend_twist")}
RENDERED_SIZE = (15, 52)
LAPLACIAN_FRAMES = 20
SHAPES = ("bar", "cylinder")
QUICK_SIZES = {"bar": dict(nx=4, nz=30), "cylinder": dict(around=16, along=20)}


def pose_reduced(basis, shape, pose):
    """Positions (n, 3) of the reduced solve converged at every frame of the pose."""
    solver = mdc.ReducedSolver(basis, shape.handles)
    for frame in range(1, pose.frames + 1):
        solver.set_transforms(pose.at(frame / pose.frames))
        for _ in range(50):
            if solver.solve(20, TOLERANCE)["converged"]:
                break
    return solver.positions().astype(np.float64)


def meshes_for_renders(shape, pose, reference):
    """What render_figures.py and the Laplacian Deform comparison (blender_pose.py) read: the mesh,
    the camera's view direction, the handles and the pose's transforms in LAPLACIAN_FRAMES steps."""
    steps = [pose.at(k / LAPLACIAN_FRAMES) for k in range(1, LAPLACIAN_FRAMES + 1)]
    return {"shape": shape.name, "pose": pose.name, "F": shape.F, "rest": shape.V, "full": reference,
            "view": shape.view, "handle0": shape.handles[0], "handle1": shape.handles[1], "transforms": steps}


def run(quick=False):
    names = SHAPES
    sizes = SIZES[:3] if quick else SIZES
    rows, poses, rendered = [], {}, {}
    for name in names:
        shape = shapes.make(name, **QUICK_SIZES[name]) if quick else shapes.make(name)
        poses[name] = [(p.name, p.description) for p in shape.poses]
        energy = mdc.DiscreteShells(shape.V, shape.F)  # the shapes are normalised already
        full = {pose.name: mdc.solve_full(shape.V, shape.F, shape.handles, pose.at(1.0)) for pose in shape.poses}
        ghost = len(shape.V)
        for modes, derivatives in sizes:
            bases = {"modal derivatives": mdc.bake(shape.V, shape.F, RIGID + modes, derivatives, ghost=ghost),
                     "linear modes": mdc.bake(shape.V, shape.F, RIGID + modes + derivatives, 0, ghost=ghost)}
            for kind, basis in bases.items():
                errors = []
                for pose in shape.poses:
                    X, reference = pose_reduced(basis, shape, pose), full[pose.name]
                    E, E_full = energy.value(X), energy.value(reference)
                    rows.append({"shape": name, "vertices": len(shape.V), "basis": kind, "modes": modes,
                                 "derivatives": derivatives, "dimension": basis.dimension,
                                 "ghost": len(basis.ghost_vertices), "pose": pose.name,
                                 "rms_error": rms_error(X, reference), "energy": E, "energy_full": E_full,
                                 "energy_gap": (E - E_full) / E_full})
                    errors.append(rows[-1]["rms_error"])
                    if (modes, derivatives) == RENDERED_SIZE and pose.name in RENDERED.get(name, ()):
                        arrays = rendered.setdefault((name, pose.name), meshes_for_renders(shape, pose, reference))
                        arrays["derivatives" if kind == "modal derivatives" else "linear"] = X
                print(f"  {name} ({modes}, {derivatives}) {kind}: mean RMS error {np.mean(errors):.2e}", flush=True)
    MESHES.mkdir(parents=True, exist_ok=True)
    for (name, pose), arrays in rendered.items():
        np.savez(MESHES / f"{name}_{pose}.npz", **arrays)
    parameters = {"shapes": names, "sizes": sizes, "stiffness": mdc.solve.STIFFNESS, "tolerance": TOLERANCE,
                  "poses": poses, "rendered": {"size": RENDERED_SIZE, "poses": RENDERED}}
    return parameters, {"rows": rows}
