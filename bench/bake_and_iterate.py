"""One bake and the BFGS iterations of an animated pose on one model, in a fresh process: the
figures to compare two builds of the core by (e.g. the in-tree build against the wheel of
`make wheel`, whichever modal_deform is first on PYTHONPATH).

    PYTHONPATH=python_addon:bench /usr/bin/python3 bench/bake_and_iterate.py [--model dragon_res2]

Prints one line: model, where the compiled core was loaded from, bake seconds, ms per BFGS
iteration (table1.time_posing: 60 frames of up to 10 iterations), ms per 10-iteration update.
"""
import argparse
import sys
import time

import modal_deform.core as mdc
import shapes
import table1


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="dragon_res2", choices=table1.MODELS)
    parser.add_argument("--modes", type=int, default=20)
    parser.add_argument("--derivatives", type=int, default=47)
    arguments = parser.parse_args()
    shape = shapes.make(arguments.model)
    start = time.perf_counter()
    basis = mdc.bake(shape.V, shape.F, arguments.modes, arguments.derivatives, ghost=1000)
    bake_s = time.perf_counter() - start
    posing = table1.time_posing(basis, shape)
    native = sys.modules[mdc.__name__.rpartition(".")[0] + "._native"].__file__
    print(f"{arguments.model} core={native} bake_s={bake_s:.2f} ms_per_iteration={posing['ms_per_iteration']:.3f} "
          f"ms_update={posing['ms_update']:.2f}", flush=True)


if __name__ == "__main__":
    main()
