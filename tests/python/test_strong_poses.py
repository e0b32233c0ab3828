"""Strong poses (issue 22): turns of 90 and 170 degrees about the long axis and bends of 90 and 180
degrees converge, never stall, on the bar, the 23k dragon, a proxy bake and a raw-scan-like mesh;
along every solve path the objective is continuous with the gradient the solver follows (centred
differences along a random direction). The 100k and 1.6M dragons are in make bench
(bench/strong_poses.py); Suzanne is in the Blender tests (scripts/strong_pose.py)."""

import warnings

import pytest
from support import (  # the poses and the difference check, shared with make bench
    raw_scans,
    strong_poses,
)
from support.meshes import read_shared

import modal_deform.core as mdc


def _bake(V, F, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the scans are floppy
        return mdc.bake(V, F, modes=20, **options)


def _mesh(name):
    if name == "bar":
        V, F = mdc.testing.bar(12, 12, 120, 1.0, 1.0, 10.0)
        return V, F, _bake(V, F, derivatives=47, ghost=1000)
    if name == "dragon_23k":
        V, F = read_shared("dragon_vrip_res3.ply.gz")
        return V, F, _bake(V, F, derivatives=47, ghost=1000)
    if name == "dragon_on_proxy":
        V, F = read_shared("dragon_vrip_res4.ply.gz")
        V, F = raw_scans.midpoint_subdivide(V, F)  # 21k vertices on a proxy of 3k
        return V, F, _bake(V, F, derivatives=47, ghost=1000, proxy=3000, proxy_above=10000)
    V, F = raw_scans.raw_scan("dragon_res4", levels=0, seed=0)
    return V, F, _bake(V, F, derivatives=20, ghost=300)


@pytest.fixture(scope="module", params=["bar", "dragon_23k", "dragon_on_proxy", "raw_scan"])
def baked(request):
    return (request.param, *_mesh(request.param))


@pytest.mark.parametrize("pose", strong_poses.POSES)
def test_strong_pose_converges_with_a_continuous_objective(baked, pose):
    name, V, F, basis = baked
    path = strong_poses.follow(mdc, basis, V, pose, check_differences=True)
    assert not any(step["stalled"] for step in path), f"{name}, {pose}: stalled at step {path}"
    final = path[-1]
    assert final["converged"], f"{name}, {pose}: not converged: {final}"
    worst = max(step["difference_error"] for step in path)
    assert worst < 1e-4, (
        f"{name}, {pose}: the objective's centred differences disagree with its gradient by {worst}"
    )
