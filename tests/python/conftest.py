"""Shared fixtures: the scanned meshes from ../shared/meshes, read once a session."""

import pytest
from support.meshes import read_shared


@pytest.fixture(scope="session")
def shared_mesh():
    """shared_mesh("bunny.obj.gz") -> (V, F), read once per session."""
    cache = {}

    def read(name):
        if name not in cache:
            cache[name] = read_shared(name)
        return cache[name]

    return read
