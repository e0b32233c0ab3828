"""Secondary motion on a rig (issue 50, item 2): the cost of a frame against the number of bones.

The 100k dragon (dragon_vrip_res2, the default bake) on a chain of 3, 30 and 100 bones along its
length, weighted linearly between the bones' centres (two bones a vertex at most), its tail (10% of
the length) attached; the rig jumps as a whole and bends along the chain. Per bone count: the
constructor's time beside the one without a rig (the rig's projection on the basis, once), the
step's median time per frame on the moving rig, and on the rig held still (the force computed, the
solve at rest) beside the same still frame without a rig: the rig's own share; and the map.

    PYTHONPATH=python_addon /usr/bin/python3 bench/run.py --only rig [--quick]
"""

import time

import numpy as np
import scipy.sparse
from support import SHARED_MESHES as MESHES

import modal_deform.core as mdc

FRAMES = 60


def chain_weights(t, bones):
    """Sparse (n, bones): a partition of unity along t in [0, 1], linear between the bones'
    centres."""
    centres = (np.arange(bones) + 0.5) / bones
    k = np.clip(np.searchsorted(centres, t) - 1, 0, max(bones - 2, 0))
    if bones == 1:
        return scipy.sparse.csr_matrix(np.ones((len(t), 1)))
    s = np.clip((t - centres[k]) / (centres[k + 1] - centres[k]), 0, 1)
    rows = np.repeat(np.arange(len(t)), 2)
    cols = np.column_stack([k, k + 1]).ravel()
    values = np.column_stack([1 - s, s]).ravel()
    return scipy.sparse.csr_matrix((values, (rows, cols)), shape=(len(t), bones))


def rotation(axis, angle, centre):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    T = np.eye(4)
    T[:3, :3] = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
    T[:3, 3] = centre - T[:3, :3] @ centre
    return T


def motion(V, bones, frames):
    """Per frame, the bones' matrices: a jump of a fifth of the length along z in 8 frames and
    back, and every joint bending by up to 40/bones degrees about the vertical."""
    lo, hi = V[:, 0].min(), V[:, 0].max()
    joints = lo + (hi - lo) * np.arange(bones) / bones
    result = []
    for f in range(frames):
        jump = np.eye(4)
        jump[2, 3] = 0.2 * (hi - lo) * np.sin(np.pi * min(f, 16) / 16)
        bend = np.radians(40 / bones) * np.sin(2 * np.pi * f / 24)
        B, chain = [], jump
        for b in range(bones):
            chain = chain @ rotation([0, 0, 1], bend, np.array([joints[b], 0, 0]))
            B.append(chain)
        result.append(np.array(B))
    return result


def run(quick=False):
    name = "dragon_vrip_res4" if quick else "dragon_vrip_res2"
    V, F = mdc.read_mesh(MESHES / f"{name}.ply.gz")
    basis = mdc.bake(V, F)
    t = (V[:, 0] - V[:, 0].min()) / np.ptp(V[:, 0])
    attach = [np.flatnonzero(t < 0.1)]
    frames = 20 if quick else FRAMES
    out = np.empty((len(V), 3), np.float32)

    start = time.perf_counter()
    plain = mdc.Simulation(basis, attach)
    plain_construct_s = time.perf_counter() - start
    plain_ms = []
    for _ in range(frames):
        plain.step([np.eye(4)])
        plain_ms.append(plain.stats["ms"])
    runs = {}
    for bones in (3, 30, 100):
        W = chain_weights(t, bones)
        start = time.perf_counter()
        sim = mdc.Simulation(basis, attach, rig=W)
        construct_s = time.perf_counter() - start
        step_ms, map_ms = [], []
        for B in motion(V, bones, frames):
            sim.advance([np.eye(4)], bones=B)
            step_ms.append(sim.stats["ms"])
            start = time.perf_counter()
            sim.positions(out)
            map_ms.append(1e3 * (time.perf_counter() - start))
        # The rig still: the force computed every frame, zero, the solve at rest (beside the
        # plain simulation's still frame): the rig's own share of a frame.
        still = motion(V, bones, 1)[0]
        still_ms = []
        for _ in range(frames):
            sim.advance([np.eye(4)], bones=still)
        for _ in range(frames):
            sim.advance([np.eye(4)], bones=still)
            still_ms.append(sim.stats["ms"])
        runs[bones] = {
            "construct_s": construct_s,
            "still_step_ms": float(np.median(still_ms)),
            "step_ms": float(np.median(step_ms)),
            "step_ms_p95": float(np.percentile(step_ms, 95)),
            "map_ms": float(np.median(map_ms)),
        }
        print(f"   {bones} bones: {runs[bones]}", flush=True)
    figures = {
        "mesh": name,
        "vertices": len(V),
        "dimension": basis.dimension,
        "without_rig": {
            "construct_s": plain_construct_s,
            "step_ms": float(np.median(plain_ms)),
        },
        "bones": runs,
    }
    return {"frames": frames}, figures
