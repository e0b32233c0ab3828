"""Raw scans bake: a raw-scan-like mesh (tests/support/raw_scans.py: the shared dragon_vrip_res2
midpoint-subdivided once, about 405k vertices, with every kind of scan damage) baked at the
paper's 67 dimensions (20 modes + 47 derivatives, 1k ghost), each seed in a fresh process: wall
time, peak resident memory, what the bake found. Targets (issue 15): at most 60 s within 4 GB.
"""

import json
import textwrap

from common import ROOT, json_from_fresh_process

SEEDS = (0, 1)
TARGET_SECONDS, TARGET_GB = 60.0, 4.0

_CHILD = textwrap.dedent("""
    import json, resource, sys, time, warnings
    sys.path.insert(0, {bench!r})
    import numpy as np
    import modal_deform.core as mdc
    import common  # puts the test-support package on sys.path
    from support import raw_scans
    V, F = raw_scans.raw_scan({name!r}, levels={levels}, seed={seed})
    report = mdc.check(V, F)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        try:
            basis = mdc.bake(V, F, modes=20, derivatives=47, ghost=1000)
            outcome = dict(ok=True, dimension=basis.dimension, floppy=basis.num_floppy,
                           timings={{k: round(v, 2) for k, v in basis.timings.items()}})
        except Exception as error:
            outcome = dict(ok=False, error=f"{{type(error).__name__}}: {{error}}")
    outcome.update(seconds=time.perf_counter() - start, vertices=len(V), faces=len(F),
                   components=report["components"],
                   damage={{k: report[k]["count"] for k in ("nonmanifold_edges", "boundary_edges",
                                                            "degenerate_faces", "duplicate_faces")}},
                   peak_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20, before_gb=before)
    print(json.dumps(outcome))
""")


def bake_in_fresh_process(name, levels, seed):
    code = _CHILD.format(bench=str(ROOT / "bench"), name=name, levels=levels, seed=seed)
    return json_from_fresh_process(code)


def run(quick=False):
    name, levels = ("dragon_res4", 0) if quick else ("dragon_res2", 1)
    bakes = []
    for seed in SEEDS[:1] if quick else SEEDS:
        outcome = bake_in_fresh_process(name, levels, seed)
        outcome["seed"] = seed
        bakes.append(outcome)
        print(
            f"   raw scan ({name}, {levels} subdivision, seed {seed}): {json.dumps(outcome)}",
            flush=True,
        )
        if outcome["ok"]:
            print(
                f"   bake {outcome['seconds']:.1f} s (target {TARGET_SECONDS:.0f} s), peak "
                f"{outcome['peak_gb']:.2f} GB (target {TARGET_GB:.0f} GB)",
                flush=True,
            )
    parameters = {
        "mesh": name,
        "subdivisions": levels,
        "seeds": list(SEEDS),
        "modes": 20,
        "derivatives": 47,
        "ghost": 1000,
        "targets": {"seconds": TARGET_SECONDS, "peak_gb": TARGET_GB},
    }
    return parameters, {"bakes": bakes}
