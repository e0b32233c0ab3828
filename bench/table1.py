"""Table 1 analogue: time per BFGS iteration, to map q to the fine mesh, for a full 10-iteration
update, and the bake by stage, per model, dimension and ghost size (paper section 7, Table 1).

Each model is baked once per dimension (ghost 1000, the bake's timings are those of that run);
the other ghost sizes reuse the basis with a ghost rebuilt by mdc.ghost_mesh and
mdc.restrict_to_ghost (the bake's own steps; restricted from the stored float32 vectors).
The pose is the scan's end pull (bench/shapes.py): 60 frames of up to 10 iterations each.
"""

import time

import numpy as np
import shapes
from common import median_ms

import modal_deform.core as mdc

#: Dimension = modes (the 6 rigid motions included) + modal derivatives: the paper's 67 = 20 + 47
#: and 130 = 20 + 110 (here 25 + 105: 14 non-rigid modes have only 105 pairs). A floppy mesh's
#: extra zero modes (dragon_vrip_res2: 6) come on top.
DIMENSIONS = {67: (20, 47), 130: (25, 105)}
GHOSTS = (500, 1000, 2500, 5000)
MODELS = ("bunny", "dragon_res3", "dragon_res2")
FRAMES = 60

#: The paper's Table 1 row we can compare with (DESIGN.md): dragon, 130k vertices, 67 dimensions,
#: 1k ghost, a 2.66 GHz laptop of 2010.
PAPER = {
    "model": "dragon_res2",
    "vertices": 130000,
    "dimension": 67,
    "ghost": 1000,
    "ms_per_iteration": 5.0,
    "ms_map": 8.0,
    "ms_update": 58.0,
    "bake_s": 1067.0,
}


def with_ghost(basis, F, target):
    """The basis of the mesh (basis.rest, F) with a ghost of about `target` vertices instead."""
    Vg, Fg, ghost_map = mdc.ghost_mesh(basis.rest, F, target)
    arrays = basis.to_arrays()
    arrays.update(
        ghost_vertices=Vg,
        ghost_faces=Fg,
        ghost_map=ghost_map,
        ghost_vectors=mdc.restrict_to_ghost(ghost_map, basis.mass, basis.vectors),
    )
    return mdc.Basis.from_arrays(arrays)


def time_posing(basis, shape):
    """ms per BFGS iteration over an animated pose, ms to map, ms per 10-iteration update."""
    pose = shape.poses[0]
    solver = mdc.ReducedSolver(basis, shape.handles)
    iterations, solve_ms = 0, 0.0
    for frame in range(1, FRAMES + 1):
        solver.set_transforms(pose.at(frame / FRAMES))
        stats = solver.solve(max_iterations=10, tolerance=1e-6)
        iterations += stats["iterations"]
        solve_ms += stats["ms"]
    out = np.empty((basis.num_vertices, 3), np.float32)
    map_ms = median_ms(lambda: solver.positions(out), 20)
    # A full update as the add-on does per tick: new transforms, 10 iterations, map. The handle
    # keeps moving (back towards rest) so that every update has work to do.
    update_ms, update_iterations = [], []
    for frame in range(20):
        start = time.perf_counter()
        solver.set_transforms(pose.at(1 - 0.02 * (frame + 1)))
        update_iterations.append(solver.solve(max_iterations=10, tolerance=1e-12)["iterations"])
        solver.positions(out)
        update_ms.append(1e3 * (time.perf_counter() - start))
    return {
        "ms_per_iteration": solve_ms / max(iterations, 1),
        "iterations_per_frame": iterations / FRAMES,
        "ms_map": map_ms,
        "ms_update": float(np.median(update_ms)),
        "update_iterations": float(np.median(update_iterations)),
    }


def run(quick=False):
    models = ("bar",) if quick else MODELS
    ghosts = (100, 300) if quick else GHOSTS
    rows = []
    for name in models:
        shape = shapes.make(name, nx=4, nz=30) if quick else shapes.make(name)
        for target, (modes, derivatives) in DIMENSIONS.items():
            start = time.perf_counter()
            basis = mdc.bake(shape.V, shape.F, modes, derivatives, ghost=1000)
            bake_s = time.perf_counter() - start
            for ghost in ghosts:
                if ghost > len(shape.V):  # the ghost would be the mesh itself, as for the last size
                    continue
                start = time.perf_counter()
                posed = basis if ghost == 1000 else with_ghost(basis, shape.F, ghost)
                ghost_s = time.perf_counter() - start
                row = {
                    "model": name,
                    "vertices": len(shape.V),
                    "faces": len(shape.F),
                    "modes": modes,
                    "derivatives": derivatives,
                    "dimension": basis.dimension,
                    "floppy": basis.num_floppy,
                    "ghost_target": ghost,
                    "ghost": len(posed.ghost_vertices),
                    "bake_s": bake_s,
                    "bake_stages_s": basis.timings,
                    "ghost_rebuild_s": None if posed is basis else ghost_s,
                }
                row.update(time_posing(posed, shape))
                rows.append(row)
                print(
                    f"  {name} {basis.dimension} dims, ghost {row['ghost']}: {row['ms_per_iteration']:.2f} ms/iter, "
                    f"map {row['ms_map']:.1f} ms, update {row['ms_update']:.1f} ms, bake {bake_s:.1f} s",
                    flush=True,
                )
    parameters = {
        "models": models,
        "dimensions": DIMENSIONS,
        "ghosts": ghosts,
        "frames": FRAMES,
        "stiffness": mdc.solve.STIFFNESS,
        "pose": "end pull (bench/shapes.py end_pull)",
        "paper": PAPER,
    }
    return parameters, {"rows": rows}
