"""What a cheaper map of a rig's displacement U q could read (issue 50): the bytes of U that a choice
of precision per block and column would read for the motion of a rig, against the 16-bit map's
(cpp/solve/quantized_vectors.h), with the same guarantee (every coordinate within the map's
tolerance of the float32 map). In each block of 192 rows, column j contributes at most
c_bj = s_bj |q_j| (s_bj its largest |U_kj|); left out, it errs by c_bj, read in 8 bits by c_bj / 254,
in 16 bits by c_bj / 65534. Per block, the smallest contributions are left out while their sum stays
within half the tolerance left after the 16-bit error of all, then the next smallest are read in 8
bits while the error stays within the tolerance; the rest in 16 bits. "skip only" leaves out columns
and reads the rest in 16 bits. Also the blocks whose 16-bit bound exceeds the tolerance (mapped from
float32 today).

The motion: the dragon (100k) skinned to a chain of 3 bones along its long axis (weights linear
between the bones' centres), attached within a tenth of its length of the chain, the armature
jumping by a fifth of its length (frames 1 to 9) while turning by 30 degrees, then the bones bending
by 20 degrees each about the vertical through their joints and back (9 to 17), still after: as
bench/playback.py's rig case, in the core.

    PYTHONPATH=python_addon /usr/bin/python3 bench/rig_map_bytes.py
"""

import json
import os
import pathlib

import numpy as np

import modal_deform.core as mdc

ROOT = pathlib.Path(__file__).resolve().parents[1]
BONES, FRAMES, ROWS_PER_BLOCK = 3, 41, 192
TOLERANCE = 3e-5  # of the bounding-box diagonal: FinePositions::kTolerance


def smooth(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def rotation_z(angle, centre=np.zeros(3)):
    c, s = np.cos(angle), np.sin(angle)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:3, 3] = centre - T[:3, :3] @ centre
    return T


def chain(V):
    """The weights (n, BONES) and the Attach vertices of a chain along V's long axis."""
    axis = int(np.argmax(np.ptp(V, axis=0)))
    low, high = V[:, axis].min(), V[:, axis].max()
    t = (V[:, axis] - low) / (high - low)
    centres = (np.arange(BONES) + 0.5) / BONES
    k = np.clip(np.searchsorted(centres, t) - 1, 0, BONES - 2)
    s = np.clip((t - centres[k]) / (centres[k + 1] - centres[k]), 0.0, 1.0)
    W = np.zeros((len(V), BONES))
    W[np.arange(len(V)), k] = 1 - s
    W[np.arange(len(V)), k + 1] += s
    centre = (V.min(axis=0) + V.max(axis=0)) / 2
    off_axis = np.delete(V - centre, axis, axis=1)
    attach = np.flatnonzero(np.linalg.norm(off_axis, axis=1) <= 0.1 * (high - low))
    joints = [centre.copy() for _ in range(BONES)]
    for b in range(BONES):
        joints[b][axis] = low + (high - low) * b / BONES
    return W, attach, joints, high - low


def bones_at(frame, joints, length):
    """The chain's world skinning matrices at `frame` (bench/playback.py's animate_rig)."""
    up = 0.2 * length * (smooth((frame - 1) / 4) if frame <= 5 else 1 - smooth((frame - 5) / 4))
    world = rotation_z(np.radians(30) * smooth((frame - 5) / 4))
    world[2, 3] += up
    bend = np.radians(60 / BONES) * (
        smooth((frame - 9) / 4) if frame <= 13 else 1 - smooth((frame - 13) / 4)
    )
    B, parent = [], world
    for joint in joints:
        parent = parent @ rotation_z(bend, joint)
        B.append(parent)
    return np.array(B)


def bytes_read(S, q, tolerance):
    """(tiered, skip only) bytes of U read over all blocks, and the blocks over tolerance in 16 bits."""
    c = np.sort(S * np.abs(q)[None], axis=1)  # per block, contributions ascending
    r = c.shape[1]
    tiered = skip_only = over = 0
    for cb in c:
        e16 = cb.sum() / 65534
        over += e16 > tolerance
        budget = tolerance - e16
        sums = np.cumsum(cb)
        skipped = int(np.searchsorted(sums, 0.5 * budget, side="right"))
        left = budget - (sums[skipped - 1] if skipped else 0.0)
        eight = int(np.searchsorted(np.cumsum(cb[skipped:] * (1 / 254 - 1 / 65534)), left, "right"))
        tiered += ROWS_PER_BLOCK * (eight + 2 * (r - skipped - eight))
        skipped_alone = int(np.searchsorted(sums, budget, side="right"))
        skip_only += ROWS_PER_BLOCK * 2 * (r - skipped_alone)
    return tiered, skip_only, over


def main():
    V, F = mdc.read_mesh(str(ROOT.parent / "shared" / "meshes" / "dragon_vrip_res2.ply.gz"))
    basis = mdc.bake(V, F, modes=15, derivatives=52, ghost=1000)
    W, attach, joints, length = chain(V)
    simulation = mdc.Simulation(basis, [attach], rig=W)
    U = basis.vectors
    blocks = -(-U.shape[0] // ROWS_PER_BLOCK)
    padded = np.zeros((blocks * ROWS_PER_BLOCK, U.shape[1]), np.float32)
    padded[: U.shape[0]] = U
    S = np.abs(padded.reshape(blocks, ROWS_PER_BLOCK, -1)).max(axis=1).astype(np.float64)
    diagonal = float(np.linalg.norm(np.ptp(V, axis=0)))
    full = 2 * U.size
    frames = []
    for frame in range(1, FRAMES + 1):
        simulation.step([np.eye(4)], bones=bones_at(frame, joints, length))
        q = simulation.state[0]
        tiered, skip_only, over = bytes_read(S, q, TOLERANCE * diagonal)
        frames.append(
            {
                "frame": frame,
                "displacement_of_diagonal": float(
                    np.abs(basis.fine_vectors() @ q).max() / diagonal
                ),
                "tiered_of_16_bit": tiered / full,
                "skip_only_of_16_bit": skip_only / full,
                "blocks_over_tolerance": int(over),
            }
        )
    moving = [f for f in frames if f["frame"] > 1]
    result = {
        "command": __doc__.split("\n\n")[-1].strip(),
        "vertices": len(V),
        "dimension": basis.dimension,
        "blocks": blocks,
        "attached": len(attach),
        "tiered_of_16_bit": [
            min(f["tiered_of_16_bit"] for f in moving),
            max(f["tiered_of_16_bit"] for f in moving),
        ],
        "skip_only_of_16_bit": [
            min(f["skip_only_of_16_bit"] for f in moving),
            max(f["skip_only_of_16_bit"] for f in moving),
        ],
        "blocks_over_tolerance_most": max(f["blocks_over_tolerance"] for f in frames),
        "frames": frames,
        "load_average": os.getloadavg(),
    }
    (ROOT / "bench" / "results" / "rig_map_bytes.json").write_text(
        json.dumps(result, indent=1) + "\n"
    )
    print(json.dumps({k: v for k, v in result.items() if k != "frames"}, indent=1))


main()
