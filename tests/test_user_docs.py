"""What a new user reads: docs/config.md's hardware defaults are sim.HardwareConfig()'s, docs/scenes.md
lists every named scene with its signature, docs/extending.md cites only files that exist, and
`rast5d list` shows the registries."""
from __future__ import annotations

import dataclasses
import inspect
import re
from pathlib import Path

import pytest

import models
import sim
from models import registry

pytestmark = pytest.mark.smoke

REPO = Path(__file__).resolve().parents[1]


def _sections(markdown: str) -> dict[str, dict[str, str]]:
    """{section title: {key: default column text}} of a generated reference page."""
    out, title = {}, None
    for line in markdown.splitlines():
        m = re.match(r"^## `([^`]+)`", line)
        if m:
            title = m.group(1)
            out[title] = {}
            continue
        m = re.match(r"^\| `([^`]+)` \| [^|]* \| `([^`]*)` \|", line)
        if m and title:
            out[title][m.group(1)] = m.group(2)
    return out


def test_config_md_hardware_defaults_are_the_real_defaults():
    sections = _sections((REPO / "docs" / "config.md").read_text())
    hardware = sim.HardwareConfig()
    checked = 0
    for f in dataclasses.fields(hardware):
        value = getattr(hardware, f.name)
        if dataclasses.is_dataclass(value):
            rows = sections[f"hardware.{f.name}"]
            for sub in dataclasses.fields(value):
                assert rows[sub.name] == repr(getattr(value, sub.name)), (f.name, sub.name, rows[sub.name])
                checked += 1
        else:
            assert sections["hardware"][f.name] == repr(value), f.name
            checked += 1
    # units differ from each other (the shared UnitConfig class defaults are not what a unit gets)
    assert hardware.setup.latency_cycles != hardware.shader.latency_cycles and checked > 20


def test_scenes_md_lists_every_named_scene_with_its_parameters():
    text = (REPO / "docs" / "scenes.md").read_text()
    for name in models.scene_names():
        row = next((line for line in text.splitlines() if line.startswith(f"| `{name}` |")), None)
        assert row is not None, name
        for param in inspect.signature(registry._REGISTRY[name]).parameters.values():
            assert f"`{param.name}` ({param.default!r})" in row, (name, param.name)
    for key in ("objects", "mesh", "transform", "motion", "color", "camera_hint"):
        assert f"`{key}`" in text, key


def test_extending_md_cites_files_that_exist():
    text = (REPO / "docs" / "extending.md").read_text()
    cited = set(re.findall(r"`((?:sim|models|experiments|configs|tests|docs)/[\w./-]+)`", text))
    cited |= {f"docs/{m}" for m in re.findall(r"\]\((\w+\.md)\)", text)}
    assert len(cited) > 10
    for path in sorted(cited):
        if "<" in path or "my_study" in path:
            continue
        assert (REPO / path).exists(), path
    for kind in ("A traversal algorithm", "A scene", "A counter", "A report page"):
        assert f"## {kind}" in text


@pytest.mark.parametrize("what", ["algorithms", "scenes", "counters", "configs"])
def test_rast5d_list(what, capsys, monkeypatch):
    from experiments.cli import main

    monkeypatch.chdir(REPO)
    assert main(["list", what]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    expected = {"algorithms": sim.algorithm_names(), "scenes": models.scene_names(),
                "counters": list(sim.counter_docs()),
                "configs": [str(p.relative_to(REPO)) for p in (REPO / "configs").rglob("*.yaml")
                            if "scenes" not in p.parts]}[what]
    assert sorted(names) == sorted(expected)


def test_committed_report_pages_carry_no_volatile_provenance(tmp_path, monkeypatch):
    """`make run` rewrites reports/quickstart/quickstart.md: two runs that differ only in wall time, engine
    build and revision must write the same text (the volatile facts go to results/provenance/)."""
    import pandas as pd

    from experiments.config import validate
    from experiments.report.pages import section_markdown

    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path / "results"))
    config = validate({"name": "tiny", "scene": {"name": "quad"}, "outputs": {"page": "tiny", "title": "Tiny"}})
    cfg_path = tmp_path / "tiny.yaml"
    cfg_path.write_text("scene: {name: quad}\n")
    texts = []
    for wall, engine, rev, elapsed in ((0.5, "aaaa", "1234567", 3.0), (7.25, "bbbb", "89abcde-dirty", 41.0)):
        df = pd.DataFrame({"status": ["ok"], "time.wall_s": [wall], "engine.version": [engine],
                           "engine.git_rev": [rev]})
        texts.append("\n".join(section_markdown(config, cfg_path, df, tmp_path, "rast5d report --only tiny",
                                                elapsed=elapsed, volatile=False)))
    assert texts[0] == texts[1] and "1 points (0 failed)" in texts[0]
    record = (tmp_path / "results" / "provenance" / "tiny.txt").read_text()
    assert "bbbb" in record and "89abcde-dirty" in record and "41 s this run" in record
    assert "s of render time" not in (REPO / "reports" / "quickstart" / "quickstart.md").read_text()
