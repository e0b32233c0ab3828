"""One bake and an animated pose of a shared model, on whichever core this Python imports: the
Linux build natively, or the Windows wheel in Windows CPython under Wine (windows/windows.mk,
`make bench-windows`). Prints one JSON line (platform, bake seconds, ms per BFGS iteration and per
10-iteration update, table1.time_posing) and, with --save, writes the basis (eigenvalues and
vectors) to an .npz file, so that two platforms' bakes can be compared (--compare A.npz B.npz).

    PYTHONPATH=python_addon python3 bench/platforms.py --model dragon_res3 --save linux.npz
    python bench/platforms.py --compare linux.npz windows.npz [--append bench/results/windows.jsonl]
"""

import argparse
import json
import pathlib
import sys
import time

import numpy as np

sys.path.insert(
    0, str(pathlib.Path(__file__).resolve().parent)
)  # shapes, table1 (the embeddable CPython adds no script folder)


def bake_and_pose(model, save):
    import shapes
    import table1

    import modal_deform.core as mdc

    shape = shapes.make(model)
    start = time.perf_counter()
    basis = mdc.bake(shape.V, shape.F, modes=20, derivatives=47, ghost=1000)
    bake_s = time.perf_counter() - start
    posing = table1.time_posing(basis, shape)
    if save:
        np.savez(save, eigenvalues=basis.eigenvalues, vectors=basis.vectors)
    return {
        "model": model,
        "platform": sys.platform,
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "vertices": int(basis.num_vertices),
        "bake_s": round(bake_s, 2),
        "stages": basis.timings,
        "ms_per_iteration": round(posing["ms_per_iteration"], 3),
        "ms_update": round(posing["ms_update"], 2),
    }


def compare(first, second):
    """How far two bakes of one mesh are apart: eigenvalues relative, vectors per column up to sign
    (each basis vector is determined up to sign; eigenvectors of close eigenvalues only as a space)."""
    a, b = np.load(first), np.load(second)
    same = bool(
        np.array_equal(a["vectors"], b["vectors"])
        and np.array_equal(a["eigenvalues"], b["eigenvalues"])
    )
    nonzero = np.abs(a["eigenvalues"]) > 1e-9
    eigen = float(
        np.max(
            np.abs(a["eigenvalues"] - b["eigenvalues"])[nonzero] / np.abs(a["eigenvalues"])[nonzero]
        )
    )
    U, W = a["vectors"].astype(np.float64), b["vectors"].astype(np.float64)
    sign = np.sign(np.sum(U * W, axis=0))
    column = np.max(np.abs(U - sign * W), axis=0) / np.max(np.abs(U), axis=0)
    return {
        "identical": same,
        "eigenvalues_max_relative": eigen,
        "columns": int(U.shape[1]),
        "columns_identical": int(np.sum(column == 0)),
        "column_max_relative": float(column.max()),
        "column_median_relative": float(np.median(column)),
    }


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--model", default="dragon_res3")
    parser.add_argument("--save", help="write the basis to this .npz")
    parser.add_argument("--compare", nargs=2, metavar="NPZ", help="compare two saved bases instead")
    parser.add_argument("--append", help="also append the JSON line to this file")
    arguments = parser.parse_args()
    result = (
        compare(*arguments.compare)
        if arguments.compare
        else bake_and_pose(arguments.model, arguments.save)
    )
    line = json.dumps(result)
    print(line, flush=True)
    if arguments.append:
        with open(arguments.append, "a") as results:
            results.write(line + "\n")


if __name__ == "__main__":
    main()
