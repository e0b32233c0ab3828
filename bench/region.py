"""A region bake against the whole mesh's (issue 24), at two sizes: dragon_vrip_res2 (100k
vertices), where both bakes are dense, and the same dragon midpoint-subdivided twice (1.6M
vertices), where both are on a proxy of the default size (the whole mesh's proxy against the
proxy of the region's own faces). Each at the paper's 67 dimensions (15 modes + 52 derivatives,
1k ghost), as a whole and with only its head as the region (the 20% of its length at the low-x
end, which rises to the head); the two bakes in turn in one process; medians of the wall time,
the stages, and what each basis spends its dimensions on. Each region's pose is checked for the
vertices outside: they must not move at all.
"""

import statistics
import time

import common  # noqa: F401 (puts the test-support package on sys.path)
import numpy as np
from support import SHARED_MESHES
from support.subdivision import midpoint_subdivide

import modal_deform.core as mdc

RUNS = {"dense": 3, "proxy": 2}
SIZES = {"modes": 15, "derivatives": 52, "ghost": 1000}
HEAD = 0.2  # the region: x within this fraction of the extent from the minimum


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


def whole_and_region(V, F, runs, proxy):
    """The whole mesh and its head region baked in turn `runs` times: per-run figures, medians, and
    the region pose's largest move outside the region."""
    x = (V[:, 0] - V[:, 0].min()) / np.ptp(V[:, 0])
    region = np.flatnonzero(x < HEAD).astype(np.int32)
    done = {"whole": [], "region": []}
    for index in range(runs):
        for kind in done:
            start = time.perf_counter()
            basis = mdc.bake(V, F, **SIZES, **proxy, region=region if kind == "region" else None)
            seconds = time.perf_counter() - start
            done[kind].append(
                {
                    "seconds": seconds,
                    "stages": basis.timings,
                    "dimension": basis.dimension,
                    "num_rigid": basis.num_rigid,
                    "num_floppy": basis.num_floppy,
                    "ghost_vertices": len(basis.ghost_vertices),
                    "proxy_vertices": basis.num_basis_vertices if basis.on_proxy else 0,
                }
            )
            print(
                f"   {len(V)} vertices, run {index + 1}, {kind}: {seconds:.1f} s, {basis.dimension} dimensions",
                flush=True,
            )
    summary = {
        kind: {
            "seconds": statistics.median(r["seconds"] for r in rs),
            "stages": {
                k: statistics.median(r["stages"].get(k, 0.0) for r in rs) for k in rs[0]["stages"]
            },
            **{
                k: rs[0][k]
                for k in (
                    "dimension",
                    "num_rigid",
                    "num_floppy",
                    "ghost_vertices",
                    "proxy_vertices",
                )
            },
        }
        for kind, rs in done.items()
    }
    return {
        "vertices": len(V),
        "region_vertices": len(region),
        "runs": done,
        "summary": summary,
        "outside_max_displacement": pose_outside_moves(basis, V, region),
    }


def run(quick=False):
    name = "dragon_vrip_res4" if quick else "dragon_vrip_res2"
    V, F = mdc.read_mesh(SHARED_MESHES / f"{name}.ply.gz")
    dense = whole_and_region(V, F, 1 if quick else RUNS["dense"], {"proxy": None})
    for _ in range(2):
        V, F = midpoint_subdivide(V, F)
    # The quick run's proxies are scaled down with its mesh (5k vertices subdivided: 80k).
    proxy = (
        {"proxy": 5000, "proxy_above": 10000}
        if quick
        else {
            "proxy": mdc.BAKE_OPTIONS["proxy"].default,
            "proxy_above": mdc.BAKE_OPTIONS["proxy_above"].default,
        }
    )
    on_proxy = whole_and_region(V, F, 1 if quick else RUNS["proxy"], proxy)
    parameters = {"mesh": name, "head_fraction": HEAD, **SIZES, **proxy}
    return parameters, {"dense": dense, "on_proxy": on_proxy}
