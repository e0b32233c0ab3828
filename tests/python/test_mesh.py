import re

import numpy as np
import pytest

import modal_deform.core as mdc


def test_check_reports_the_dragon_defects(shared_mesh):
    V, F = shared_mesh("dragon_vrip_res4.ply.gz")
    report = mdc.check(V, F)
    assert report["vertices"] == 5205 and report["faces"] == 11102
    assert report["nonmanifold_edges"]["count"] == 803
    assert report["unreferenced_vertices"]["count"] == 2
    assert len(report["unreferenced_vertices"]["first"]) == 2
    assert sum(report["component_sizes"]) == 5205 - 2
    labels = report["vertex_component"]
    assert labels.shape == (5205,) and np.count_nonzero(labels == -1) == 2
    assert sorted(np.bincount(labels[labels >= 0]), reverse=True) == report["component_sizes"]


def test_mass_sums_to_area(shared_mesh):
    V, F = shared_mesh("bunny.obj.gz")
    m = mdc.mass(V, F)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    assert m.shape == (len(V),)
    assert m.sum() == pytest.approx(area, rel=1e-12)


def test_generated_shapes_are_closed_or_open_as_promised():
    V, F = mdc.testing.bar(2, 2, 6)
    assert mdc.check(V, F)["boundary_edges"]["count"] == 0
    V, F = mdc.testing.cylinder(12, 4)
    assert mdc.check(V, F)["boundary_edges"]["count"] == 24
    V, F = mdc.testing.bumpy_plane(20, bumps=5)
    assert V.shape == (21 * 21, 3) and np.ptp(V[:, 2]) > 0.1


@pytest.mark.parametrize(
    "V, F, needle",
    [
        (np.zeros((3, 2)), [[0, 1, 2]], "V: expected an (n, 3)"),
        (np.eye(3), [[0, 1]], "F: expected an (m, 3)"),
        (np.eye(3), [[0.0, 1.0, 2.0]], "F: expected integer"),
        (np.eye(3), [[0, 1, 7]], "F[0]"),
        ([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], [[0, 1, 2]], "V[2]"),
        (np.zeros((0, 3)), np.zeros((0, 3), int), "V: the mesh has no vertices"),
    ],
)
def test_bad_input_raises_value_error_naming_it(V, F, needle):
    with pytest.raises(ValueError, match=re.escape(needle)):
        mdc.check(V, F)


def test_read_mesh_names_missing_files(tmp_path):
    with pytest.raises(ValueError, match="cannot open"):
        mdc.read_mesh(tmp_path / "missing.obj")
