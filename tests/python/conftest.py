"""Shared fixtures: the scanned meshes from ../shared/meshes and generated shapes."""
import pathlib

import pytest

import modal_deform.core as mdc

SHARED_MESHES = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "meshes"


@pytest.fixture(scope="session")
def shared_mesh():
    """shared_mesh("bunny.obj.gz") -> (V, F), read once per session."""
    cache = {}

    def read(name):
        if name not in cache:
            cache[name] = mdc.read_mesh(SHARED_MESHES / name)
        return cache[name]

    return read
