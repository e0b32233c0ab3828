"""The bake beside a busy core (issue 25, "Busy-proof"): the dragon at 23k (dragon_vrip_res3) and
100k vertices (dragon_vrip_res2) baked at 15 modes + 52 derivatives with a 1k ghost by
bench/bake_once.py, each bake in a fresh process, quiet and with one `yes` process beside it: in plain
Python as the add-on ships (OpenMP's passive wait, OpenBLAS under CHOLMOD on the usable cores less
one) and, at 23k, with GCC OpenMP's default spinning wait (GOMP_SPINCOUNT=300000, which the core's
import then leaves alone); and inside bpy 4.5 and 5.3 on the installed extension, beside Blender's
own NumPy and its OpenBLAS. `yes` runs in a session of its own, as another application does: Linux
shares the cores between sessions first (autogroups), so a `yes` in the bake's session would take half
of what the session gets, which on a machine loaded by other sessions is far less than the core it
leaves free on an idle one (the 23k bake then took 1.9 to 2.7 times as long at load 10 to 11, against
1.09 on an idle machine). The machine is shared, so "quiet" means nothing of ours beside the bake:
each bake runs quiet and busy back to back (which comes first alternates by round), the ratio is
taken pair by pair and the load average before each pair is kept; medians over the rounds.

Inside each Python, one bake of the 5k dragon first checks the threads: the OpenMP settings the
core's runtime reports (OMP_DISPLAY_ENV) and the thread counts of every OpenBLAS in the process
during the bake (bake_once.py --threads).
"""
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

import common
from common import ROOT

MESHES = {"23k": "dragon_vrip_res3.ply.gz", "100k": "dragon_vrip_res2.ply.gz"}
#: The 5k dragon: the thread checks, and the smoke test's only bake.
CHECK_MESH = "dragon_vrip_res4.ply.gz"
ROUNDS = 3
#: The Pythons the bake runs in: this one (the source tree's core) and each bpy.
PYTHONS = ("python",) + tuple(f"bpy {version}" for version in common.BPY_VERSIONS)
#: The bake's environment on top of this process's, by variant.
VARIANTS = {"shipped": {}, "spinning_openmp": {"GOMP_SPINCOUNT": "300000"}}
CONDITIONS = ("quiet", "busy")
SCRIPT = ROOT / "bench" / "bake_once.py"


def bakes_of(meshes):
    """(python, mesh size, variant) of each bake: every Python as shipped at every size, and plain Python
    with OpenMP spinning at the first size."""
    first = next(iter(meshes))
    return tuple((python, size, variant) for python in PYTHONS for size in meshes for variant in VARIANTS
                 if variant == "shipped" or (python == "python" and size == first))


def name(bake):
    return " ".join(bake)


def in_fresh_process(python, arguments, environment, folder):
    """bake_once.py's JSON and its standard error, in plain Python or in bpy `python`."""
    if python == "python":
        run = subprocess.run([sys.executable, "-W", "ignore", str(SCRIPT), *arguments], cwd=ROOT, capture_output=True,
                             text=True, check=True, env={k: v for k, v in os.environ.items()
                                                         if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")} | environment)
    else:
        run = common.in_bpy(python.split()[1], SCRIPT, arguments, folder, env=environment, capture_output=True,
                            text=True)
    return json.loads(run.stdout.strip().splitlines()[-1]), run.stderr


def thread_check(python, folder):
    """What the core's OpenMP runtime reports of its wait, and the OpenBLAS thread counts seen."""
    result, stderr = in_fresh_process(python, [CHECK_MESH, "--threads"], {"OMP_DISPLAY_ENV": "verbose"}, folder)
    return {"omp_wait_policy": re.findall(r"OMP_WAIT_POLICY = '(\w+)'", stderr),
            "gomp_spincount": re.findall(r"GOMP_SPINCOUNT = '(\d+)'", stderr),
            "openblas_threads_seen": result["openblas_threads_seen"]}


def bake_pair(bake, mesh, busy_first, folder):
    """{condition: seconds, "stages": {condition: {stage: seconds}}} of the bake quiet and beside one
    `yes`, back to back."""
    python, _, variant = bake
    pair = {"stages": {}}
    for condition in (CONDITIONS[::-1] if busy_first else CONDITIONS):
        busy = subprocess.Popen(["yes"], stdout=subprocess.DEVNULL, start_new_session=True) \
            if condition == "busy" else None
        try:
            result = in_fresh_process(python, [mesh], VARIANTS[variant], folder)[0]
        finally:
            if busy is not None:
                busy.kill()
                busy.wait()
        pair[condition] = result["seconds"]
        pair["stages"][condition] = result["stages"]
    return pair


def summary(bakes, rounds):
    """Medians over the rounds per bake: seconds, busy / quiet pair by pair, also per stage; shipped /
    spinning."""
    def median(values):
        return statistics.median(list(values))
    out = {}
    for bake in bakes:
        pairs = [r[name(bake)] for r in rounds]
        out[name(bake)] = {"quiet": median(p["quiet"] for p in pairs), "busy": median(p["busy"] for p in pairs),
                           "busy_over_quiet": median(p["busy"] / p["quiet"] for p in pairs),
                           "stages_busy_over_quiet": {
                               stage: median(p["stages"]["busy"][stage] / p["stages"]["quiet"][stage] for p in pairs)
                               for stage in pairs[0]["stages"]["quiet"] if pairs[0]["stages"]["quiet"][stage] > 0},
                           "load_before": [min(p["load_before"] for p in pairs), max(p["load_before"] for p in pairs)]}
    shipped, spinning = (name(b) for b in bakes if b[0] == "python" and b[1] == bakes[0][1])
    out["shipped_over_spinning"] = {c: median(r[shipped][c] / r[spinning][c] for r in rounds) for c in CONDITIONS}
    return out


def run(quick=False):
    meshes = {"5k": CHECK_MESH} if quick else MESHES
    bakes = bakes_of(meshes)
    rounds = []
    with tempfile.TemporaryDirectory() as folder:
        checks = {python: thread_check(python, folder) for python in PYTHONS}
        for python, check in checks.items():
            print(f"   {python}: OpenMP wait {check['omp_wait_policy']}, spin count {check['gomp_spincount']}; "
                  f"OpenBLAS threads seen {check['openblas_threads_seen']}", flush=True)
        for index in range(1 if quick else ROUNDS):
            pairs = {}
            for bake in bakes:
                load = os.getloadavg()[0]
                pairs[name(bake)] = bake_pair(bake, meshes[bake[1]], index % 2 == 1, folder) | {"load_before": load}
                p = pairs[name(bake)]
                print(f"   round {index + 1}, {name(bake)}: quiet {p['quiet']:.1f} s, busy {p['busy']:.1f} s, "
                      f"{p['busy'] / p['quiet']:.2f} (load {load:.1f})", flush=True)
            rounds.append(pairs)
    result = summary(bakes, rounds)
    parameters = {"meshes": meshes, "check_mesh": CHECK_MESH, "modes": 15, "derivatives": 52, "ghost": 1000,
                  "rounds": len(rounds), "bakes": [list(b) for b in bakes], "variants": VARIANTS,
                  "busy": "one `yes` process beside the bake", "load_before": os.getloadavg()}
    return parameters, {"checks": checks, "rounds": rounds, "summary": result}
