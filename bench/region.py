"""A region bake against the whole mesh's (issue 24): dragon_vrip_res2 (100k vertices) baked at the
paper's 67 dimensions (15 modes + 52 derivatives, 1k ghost) as a whole and with only its head as the
region (the 20% of its length at the low-x end, which rises to the head), the two bakes in turn in
one process; medians of the wall time, the stages, and what each basis spends its dimensions on.
The region's pose is checked for the vertices outside: they must not move at all.
"""
import statistics
import time

import numpy as np

import modal_deform.core as mdc
from common import ROOT

RUNS = 3
SIZES = {"modes": 15, "derivatives": 52, "ghost": 1000}
HEAD = 0.2  # the region: x within this fraction of the extent from the minimum


def bake(V, F, region):
    start = time.perf_counter()
    basis = mdc.bake(V, F, **SIZES, region=region)
    return basis, time.perf_counter() - start


def pose_outside_moves(basis, V, region):
    """The largest displacement of a vertex outside the region when the head's top is lifted."""
    top = region[V[region, 1] > np.quantile(V[region, 1], 0.95)]
    T = np.eye(4)
    T[1, 3] = 0.05 * np.ptp(V, axis=0).max()
    solver = mdc.ReducedSolver(basis, [top])
    solver.set_transforms([T])
    solver.solve(max_iterations=50)
    outside = np.setdiff1d(np.arange(len(V)), region)
    return float(np.abs(solver.positions()[outside] - V[outside].astype(np.float32)).max())


def run(quick=False):
    name = "dragon_vrip_res4" if quick else "dragon_vrip_res2"
    V, F = mdc.read_mesh(ROOT.parent / "shared" / "meshes" / f"{name}.ply.gz")
    x = (V[:, 0] - V[:, 0].min()) / np.ptp(V[:, 0])
    region = np.flatnonzero(x < HEAD).astype(np.int32)
    runs = {"whole": [], "region": []}
    for index in range(1 if quick else RUNS):
        for kind in runs:
            basis, seconds = bake(V, F, region if kind == "region" else None)
            runs[kind].append({"seconds": seconds, "stages": basis.timings, "dimension": basis.dimension,
                               "num_rigid": basis.num_rigid, "num_floppy": basis.num_floppy,
                               "ghost_vertices": len(basis.ghost_vertices)})
            print(f"   run {index + 1}, {kind}: {seconds:.1f} s, {basis.dimension} dimensions", flush=True)
    still = pose_outside_moves(basis, V, region)
    summary = {kind: {"seconds": statistics.median(r["seconds"] for r in rs),
                      "stages": {k: statistics.median(r["stages"].get(k, 0.0) for r in rs) for k in rs[0]["stages"]},
                      **{k: rs[0][k] for k in ("dimension", "num_rigid", "num_floppy", "ghost_vertices")}}
               for kind, rs in runs.items()}
    parameters = {"mesh": name, "vertices": len(V), "region_vertices": len(region), "head_fraction": HEAD,
                  "runs": len(runs["whole"]), **SIZES}
    return parameters, {"runs": runs, "summary": summary, "outside_max_displacement": still}
