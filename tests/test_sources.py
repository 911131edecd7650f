"""Sources: every paper is cited through the bibliography (docs/references.md, sim/references.py) by its
short key, and no project file points to a file outside the project (the shared style and architecture
notes, or a paper's text file by its name)."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from sim import references

ROOT = Path(__file__).resolve().parents[1]
# What points outside the project, spelled in parts so that this file does not match itself: the
# proposal notes beside the project, the shared folder of papers and data, a paper's text file by name.
_NOTES = ("STYLE", "ARCHITECTURE")
_SHARED = ("/".join(("..", "shared")), "/".join(("shared", "data")))
_PAPER_FILE = "_".join((r"\b00[0-4]", "[0-9a-f]{16}"))
OUTSIDE = re.compile("|".join([rf"\b(?:{'|'.join(_NOTES)})\.md", *map(re.escape, _SHARED), _PAPER_FILE]))
# A paper cited by its number (as the engine's declarations name them) in user-facing text.
BY_NUMBER = re.compile(r"(?<![\w.,\-/])00[0-4](?![\w.]|-\d)")
# Files still to change (strict: a listed prefix that passes fails
# test_pending_files_still_need_their_change); none.
PENDING: tuple[str, ...] = ()


def _files():
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True).stdout.split()
    return [f for f in out if f.endswith((".py", ".md", ".yaml", ".yml", ".toml", ".cff", ".h", ".cpp", ".def", ".pyi",
                                          ".ipynb", ".txt", ".cfg", ".ini"))
            and not f.startswith("models/assets/") and f != "tests/test_sources.py"]


def _offenders(pattern, files):
    bad = {}
    for f in files:
        try:
            text = (ROOT / f).read_text()
        except (OSError, UnicodeDecodeError):
            continue
        hits = [f"{i}: {line.strip()[:100]}" for i, line in enumerate(text.splitlines(), 1) if pattern.search(line)]
        if hits:
            bad[f] = hits
    return bad


def test_no_file_points_outside_the_project():
    bad = _offenders(OUTSIDE, _files())
    pending = {f for f in bad if f.startswith(PENDING)}
    assert set(bad) == pending, {f: h for f, h in bad.items() if f not in pending}


USER_FACING = ("README.md", "CHANGELOG.md", "docs/", "configs/", "reports/", "experiments/", "models/", "rast5d/",
               "sim/")


def test_user_facing_text_cites_papers_by_key():
    """Docs, pages, configs and the package's docstrings and messages cite [Akenine-Möller 2012], never
    '001' (sim/references.py itself maps the numbers to the keys)."""
    files = [f for f in _files() if f.startswith(USER_FACING) and f not in ("sim/references.py",)]
    bad = _offenders(BY_NUMBER, files)
    pending = {f for f in bad if f.startswith(PENDING)}
    assert set(bad) == pending, {f: h for f, h in bad.items() if f not in pending}


@pytest.mark.parametrize("prefix", PENDING)
def test_pending_files_still_need_their_change(prefix):
    """A pending prefix that no longer has an offender leaves PENDING (so the list cannot outlive the change)."""
    files = [f for f in _files() if f.startswith(prefix)]
    assert _offenders(OUTSIDE, files) or _offenders(BY_NUMBER, files), f"{prefix} is clean: remove it from PENDING"


def test_every_implemented_paper_has_a_full_citation_and_key():
    keys = [r.key for r in references.REFERENCES]
    assert len(set(keys)) == len(keys)
    assert sorted(r.number for r in references.REFERENCES if r.number) == ["000", "001", "002", "003", "004"]
    text = (ROOT / "docs" / "references.md").read_text()
    for r in references.REFERENCES:
        assert f"## [{r.key}]" in text and r.citation in text
    paper_file = "_".join(("004", "0123456789abcdef")) + ".txt"
    assert references.cite(f"001 §6.2 and {paper_file} Table 1") == \
        "[Akenine-Möller 2012] §6.2 and [Tzeng 2012] Table 1"


def test_every_cited_key_is_in_the_bibliography():
    """A key cited in the docs, pages or configs ([Name Year]) is an entry of docs/references.md."""
    keys = {r.key for r in references.REFERENCES}
    cited = set()
    for f in _files():
        if f.startswith(("docs/", "configs/", "reports/", "README.md")) and f.endswith((".md", ".yaml")):
            cited |= set(re.findall(r"\[([A-Z][A-Za-zé&\-ö ]+ (?:19|20)\d\d)\]", (ROOT / f).read_text()))
    assert cited <= keys, cited - keys
