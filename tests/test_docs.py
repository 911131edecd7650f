"""Generated reference docs (docs/config.md, docs/counters.md) match their declarations; CLI smoke."""
import json
import subprocess
import sys

import pytest

from experiments.config import docs

pytestmark = pytest.mark.smoke


@pytest.mark.parametrize("path", list(docs.targets()), ids=lambda p: p.name)
def test_generated_docs_are_current(path):
    expected = docs.targets()[path]
    assert path.exists() and path.read_text() == expected, f"{path} is stale: run `python -m experiments.config.docs`"


def test_every_counter_is_documented_once():
    import sim

    names = list(sim.counter_docs())
    assert len(names) == len(set(names))
    import re

    for name, (unit, desc) in sim.counter_docs().items():
        assert unit and desc, name
        # stage.thing; capital H only where the paper's H_j lines (or H5, their extension to time) are meant
        # (one more level for grouped figures: timing.<unit>.busy_cycles)
        assert re.fullmatch(r"[a-z]+\.([a-z][a-z0-9_]*\.)?[a-z0-9_]*(H5?_[a-z_]+|_H5?)?[a-z0-9_]*", name), name
