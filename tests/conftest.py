"""Shared fixtures: seeded random generators, and a fresh memo of built scenes and tables per test.

``rng`` is a numpy Generator seeded from the test's node id (file, name and parameters), so every
test draws its own reproducible stream: a failure replays with the same inputs, alone or in the
suite, whatever ran before it, and adding a test changes no other test's inputs.
"""
from __future__ import annotations

import hashlib

import numpy as np
import pytest


def node_seed(nodeid: str) -> int:
    """A stable 64-bit seed from a pytest node id (Python's hash() is salted per process)."""
    return int.from_bytes(hashlib.sha256(nodeid.encode()).digest()[:8], "little")


@pytest.fixture
def rng(request) -> np.random.Generator:
    """numpy Generator seeded from the requesting test's node id."""
    return np.random.default_rng(node_seed(request.node.nodeid))


@pytest.fixture(autouse=True)
def fresh_build_memo():
    """Each test builds its scenes and sample tables anew: a test that patches a builder (to read a
    file, to fail) must not be served what an earlier test built."""
    import importlib

    importlib.import_module("experiments.config.build").forget()  # the module (the package exports build())
    yield
