"""The bake beside a busy core (issue 25, "Busy-proof"): dragon_vrip_res3 (23k vertices) baked at
15 modes + 52 derivatives with a 1k ghost, each bake in a fresh process, quiet and with one `yes`
process beside it, as the add-on ships it (OpenMP's passive wait, OpenBLAS under CHOLMOD on the
usable cores less one) and with GCC OpenMP's default spinning wait (GOMP_SPINCOUNT=300000, libgomp's
default, which the core's import then leaves alone). The four variants run in turn within each
round, so that a round's figures saw the same load; ratios are taken round by round, medians over
the rounds. Before and after the OpenBLAS limit: run this experiment on each commit.
"""
import json
import os
import statistics
import subprocess
import sys

from common import ROOT

MESH = "dragon_vrip_res3.ply.gz"
ROUNDS = 3
#: The bake's environment on top of this process's, by variant.
VARIANTS = {"shipped": {}, "spinning_openmp": {"GOMP_SPINCOUNT": "300000"}}
CONDITIONS = ("quiet", "busy")
BAKE = f"""
import json, sys, time
sys.path.insert(0, {str(ROOT / 'python_addon')!r})
import modal_deform.core as mdc
V, F = mdc.read_mesh({str(ROOT.parent / 'shared' / 'meshes')!r} + '/' + sys.argv[1])
start = time.perf_counter()
mdc.bake(V, F, modes=15, derivatives=52, ghost=1000)
print(json.dumps({{"seconds": time.perf_counter() - start}}))
"""


def bake_in_fresh_process(mesh, variant):
    environment = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    environment.update(VARIANTS[variant])
    result = subprocess.run([sys.executable, "-W", "ignore", "-c", BAKE, mesh], env=environment, cwd=ROOT,
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout.strip().splitlines()[-1])["seconds"]


def bake_round(mesh):
    """{condition: {variant: seconds}} for one round."""
    seconds = {}
    for condition in CONDITIONS:
        busy = subprocess.Popen(["yes"], stdout=subprocess.DEVNULL) if condition == "busy" else None
        try:
            seconds[condition] = {variant: bake_in_fresh_process(mesh, variant) for variant in VARIANTS}
        finally:
            if busy is not None:
                busy.kill()
                busy.wait()
    return seconds


def summary(rounds):
    """Medians over the rounds: seconds, busy / quiet per variant, shipped / spinning per condition."""
    def median(values):
        return statistics.median(list(values))
    return {
        "seconds": {c: {v: median(r[c][v] for r in rounds) for v in VARIANTS} for c in CONDITIONS},
        "busy_over_quiet": {v: median(r["busy"][v] / r["quiet"][v] for r in rounds) for v in VARIANTS},
        "shipped_over_spinning": {c: median(r[c]["shipped"] / r[c]["spinning_openmp"] for r in rounds)
                                  for c in CONDITIONS},
    }


def run(quick=False):
    mesh = "dragon_vrip_res4.ply.gz" if quick else MESH
    rounds = []
    for index in range(1 if quick else ROUNDS):
        rounds.append(bake_round(mesh))
        print(f"   round {index + 1}: " + "; ".join(
            f"{c} " + ", ".join(f"{v} {s:.1f} s" for v, s in rounds[-1][c].items()) for c in CONDITIONS), flush=True)
    result = summary(rounds)
    print("   busy / quiet: " + ", ".join(f"{v} {x:.2f}" for v, x in result["busy_over_quiet"].items())
          + "; shipped / spinning: " + ", ".join(f"{c} {x:.2f}" for c, x in result["shipped_over_spinning"].items()),
          flush=True)
    parameters = {"mesh": mesh, "modes": 15, "derivatives": 52, "ghost": 1000, "rounds": len(rounds),
                  "variants": VARIANTS, "busy": "one `yes` process beside the bake", "load_before": os.getloadavg()}
    return parameters, {"rounds": rounds, "summary": result}
