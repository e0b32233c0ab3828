"""Shape blending (issue 52): per-blend time and the space's bake time per key count on the dragon.

    PYTHONPATH=python_addon /usr/bin/python3 bench/run.py --only shape_space [--quick]

Keys are smooth deformations of the rest mesh (a part beyond a plane across the longest axis swung
about an axis through the centre, by an angle that rises smoothly across the plane). Per mesh:
the basis bake's seconds, the space's bake seconds per key count, and the median blend
milliseconds (map included) over fixed random weights, with BFGS iterations.
"""

import time

import numpy as np
from support import SHARED_MESHES
from support.poses import smooth_keys

import modal_deform.core as mdc

KEYS = 8
BLENDS = 30


def measure(name):
    V, F = mdc.read_mesh(SHARED_MESHES / f"dragon_vrip_{name}.ply.gz")
    t = time.perf_counter()
    basis = mdc.bake(V, F)
    bake_s = time.perf_counter() - t
    keys = smooth_keys(V, KEYS)
    result = {"mesh": name, "vertices": len(V), "basis_bake_s": bake_s, "space_bake_s": {}}
    for k in (1, 2, 4, 8):
        t = time.perf_counter()
        space = mdc.ShapeSpace(V, F, keys[:k], basis=basis)
        result["space_bake_s"][k] = time.perf_counter() - t
    rng = np.random.default_rng(2)
    out = np.empty((len(V), 3), np.float32)
    ms, solve_ms, iterations, converged = [], [], [], 0
    for _ in range(BLENDS):
        w = rng.random(KEYS) * (rng.random(KEYS) < 0.5)
        t = time.perf_counter()
        space.blend(w, out=out)
        ms.append(1e3 * (time.perf_counter() - t))
        st = space.stats
        solve_ms.append(st["solve_ms"])
        iterations.append(st["iterations"])
        converged += st["converged"]
    result.update(
        dimension=space.dimension,
        blend_ms_median=float(np.median(ms)),
        blend_ms_min=float(np.min(ms)),
        solve_ms_median=float(np.median(solve_ms)),
        iterations_median=float(np.median(iterations)),
        iterations_max=int(np.max(iterations)),
        converged=converged,
    )
    return result


def run(quick=False):
    names = ["res4"] if quick else ["res3", "res2"]
    return {"keys": KEYS, "blends": BLENDS}, {name: measure(name) for name in names}
