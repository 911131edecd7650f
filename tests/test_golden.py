"""Golden operation counts (tests/golden/ops.csv): key sets first, then values; `make golden` regenerates."""
import pytest

from tests.golden import golden

pytestmark = pytest.mark.golden


@pytest.fixture(scope="module")
def recomputed():
    return golden.compute_all(progress=False)


@pytest.fixture(scope="module")
def stored():
    assert golden.GOLDEN.exists(), "tests/golden/ops.csv is missing: run `make golden`"
    return golden.read()


def test_same_keys(stored, recomputed):
    removed, added, _ = golden.diff(stored, recomputed)
    assert not removed, f"cases/counters no longer produced (first 5): {sorted(removed)[:5]}; run `make golden`"
    assert not added, f"cases/counters not in the golden file (first 5): {sorted(added)[:5]}; run `make golden`"


def test_same_values(stored, recomputed):
    _, _, changed = golden.diff(stored, recomputed)
    lines = [f"{k}: {a} -> {b}" for k, a, b in changed[:20]]
    assert not changed, (f"{len(changed)} golden counts changed (first 20):\n" + "\n".join(lines)
                         + "\nIf intended, run `make golden` and explain the change in the commit.")


def test_golden_file_is_sorted_text(stored):
    """The file stays reviewable: plain CSV, one counter per line, sorted keys."""
    text = golden.GOLDEN.read_text().splitlines()
    assert text[0] == ",".join(golden.KEY + ("counter", "value"))
    assert text[1:] == sorted(text[1:], key=lambda line: tuple(line.split(",")[:-1]))
