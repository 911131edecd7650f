"""The engine's stage folders include each other in one direction only (docs/architecture.md): a
folder includes only the folders before it in LAYERS, so the stages form no include loops. The check
reads every #include of sim/engine/ as text; it fails on a tree with a loop (shown below)."""
from __future__ import annotations

import re
from pathlib import Path

ENGINE = Path(__file__).resolve().parents[1] / "sim" / "engine"
LAYERS = ("core", "tiletest", "sampletest", "setup", "intervals", "memory", "backend", "lines", "gpu", "timing",
          "traversal", "sampled", "conservative", "frame", "selftest")
INCLUDE = re.compile(r'#include "([^"/]+)/[^"]+"')


def backward_includes(root: Path) -> list[str]:
    """'file -> include' for every include of a later folder (or of a folder not in LAYERS)."""
    bad = []
    for f in sorted(root.rglob("*")):
        if f.suffix not in (".h", ".cpp", ".def"):
            continue
        src = f.relative_to(root).parts[0]
        for m in INCLUDE.finditer(f.read_text()):
            dst = m.group(1)
            if dst == src:
                continue
            if src not in LAYERS or dst not in LAYERS or LAYERS.index(dst) > LAYERS.index(src):
                bad.append(f"{f.relative_to(root)} -> {m.group(0)}")
    return bad


def test_stage_folders_include_only_earlier_stages():
    assert {p.name for p in ENGINE.iterdir() if p.is_dir()} == set(LAYERS)
    assert backward_includes(ENGINE) == []


def test_a_loop_is_caught(tmp_path):
    (tmp_path / "setup").mkdir()
    (tmp_path / "sampletest").mkdir()
    (tmp_path / "setup" / "setup.h").write_text('#include "sampletest/kernels.h"\n')
    (tmp_path / "sampletest" / "kernels.h").write_text('#include "setup/setup.h"\n')  # sampletest before setup
    assert backward_includes(tmp_path) == ['sampletest/kernels.h -> #include "setup/setup.h"']


def test_production_kernels_are_not_named_like_tests():
    """Files named *_test.* read as unit tests to a newcomer; the engine's kernels are not tests
    (selftest/ is the test-only C++)."""
    named = [str(f.relative_to(ENGINE)) for f in ENGINE.rglob("*") if re.search(r"(^|_)test\.(h|cpp)$", f.name)]
    assert named == []
