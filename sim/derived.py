"""Derived figures: a name, a unit, a one-line description and a formula over a flat dict of raw
figures, evaluated at export and never stored. sim.stats declares the counter figures and
sim.timing the timing figures with this one type."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np


def ratio(a, b):
    """a / b, nan when b is zero (a rate over no events is undefined, not zero). Elementwise on numpy
    arrays (sim.sampling evaluates the formulas for every sampled bin at once)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.broadcast_arrays(np.asarray(a, np.float64), np.asarray(b, np.float64))
        out = np.full(a.shape, math.nan)
        return np.divide(a, b, out=out, where=b != 0)
    return a / b if b else math.nan


@dataclass(frozen=True)
class Derived:
    name: str
    unit: str
    description: str
    formula: Callable[[dict], float]


def evaluate(derived: Iterable[Derived], flat: dict) -> dict:
    """flat with every derived figure added, in declaration order (a formula may use earlier ones)."""
    for d in derived:
        flat[d.name] = d.formula(flat)
    return flat


def docs(derived: Iterable[Derived]) -> dict[str, tuple[str, str]]:
    """{name: (unit, description)} of the derived figures."""
    return {d.name: (d.unit, d.description) for d in derived}


def nest(flat: dict) -> dict:
    """{"a.b": v} -> {"a": {"b": v}} (names have the form stage.thing)."""
    out: dict = {}
    for key, value in flat.items():
        node = out
        parts = key.split(".")
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        node[parts[-1]] = value
    return out
