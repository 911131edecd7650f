"""The traversal registry's facts (sample kind, sample-table kinds, depth-cull stage, pipeline) and the
parameters a render does not read: refused by nothing, but warned about by name, and left out of a sweep
point's hash so the same result is not computed twice."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

import sim
from experiments import config as xc
from experiments.config import config_hash, expand_sweep

ROOT = Path(__file__).resolve().parents[1]


def test_every_registered_algorithm_has_its_facts():
    info = sim.algorithm_info()
    assert set(info) == set(sim.algorithm_names()) == {name for name, _d, _i in sim._core.algorithms()}
    assert "lines" in sim.algorithm_names()  # the listing is the registry's, line samples included
    assert sim.algorithm_names("lines") == ["lines"] == sim.line_algorithms()
    assert set(sim.algorithm_names("points")) == set(info) - {"lines"}
    for name, facts in info.items():
        assert facts.samples in ("points", "lines") and facts.pipeline in ("sample", "gpu")
        assert facts.tables and set(facts.tables) <= set(sim.SampleTable.kinds())
        assert facts.discrete_lens == (name in sim.interleaved_algorithms())


def test_the_facts_match_what_the_engine_accepts():
    """Independent of the facts: the engine renders (or refuses) each algorithm with each table kind, and
    answers (or refuses) an occlusion query; the facts must say the same."""
    import numpy as np

    from models import Scene

    def quad(z, half):
        a, b, c, d = (-half, -half, z), (half, -half, z), (half, half, z), (-half, half, z)
        return Scene.from_arrays(np.array([[a, b, c], [a, c, d]], dtype=np.float64))

    scene, query = quad(-4.0, 2.0), quad(-6.0, 0.5)  # a static wall and a small quad behind it
    cam = sim.Camera(width=16, height=16, focus_distance=4.0, coc_px=4.0)
    tables = {"stratified": sim.SampleTable.stratified(spp=4, seed=1, time=False),
              "interleaved": sim.SampleTable.interleaved(spp=4, seed=1, n_lens=4, time=False),
              "lines": sim.SampleTable.lines(n_lines=4, seed=1)}
    for name, facts in sim.algorithm_info().items():
        for kind, table in tables.items():
            try:
                sim.render(scene, cam, table, sim.PipelineConfig(algorithm=name, threads=1), timing=False)
                accepted = True
            except sim.ConfigError:
                accepted = False
            assert accepted == (kind in facts.tables), (name, kind, facts.tables)
        table = tables["lines" if facts.samples == "lines" else
                       "interleaved" if facts.discrete_lens else "stratified"]
        try:
            sim.occlusion_query(scene, query, cam, table, sim.PipelineConfig(algorithm=name, threads=1))
            answers = True
        except sim.ConfigError:
            answers = False
        assert answers == facts.depth_cull, name


@pytest.mark.parametrize("algorithm, kwargs, field", [
    ("bruteforce", {"hiz": {"enabled": True, "tile_size": 8}}, "hiz.enabled"),
    ("interval", {"hiz": {"enabled": False, "tile_size": 4}}, "hiz.tile_size"),
    ("tile", {"lines": {**sim.PipelineConfig().lines, "tile_clip": True}}, "lines.tile_clip"),
    ("tile", {"gpu_constants": "strip"}, "gpu_constants"),
    ("tile", {"sample_seed": 7}, "sample_seed"),
    ("tile", {"shading": "msaa", "shading_grid": 2}, "shading_grid"),
])
def test_a_parameter_the_render_does_not_read_is_warned_about_by_name(algorithm, kwargs, field):
    with pytest.warns(sim.UnreadParameterWarning, match=re.escape(f"PipelineConfig.{field} = ")) as got:
        config = sim.PipelineConfig(algorithm=algorithm, **kwargs)
    assert algorithm in str(got[0].message) or "sample_fraction" in str(got[0].message) or "shading" in str(
        got[0].message)
    assert got[0].filename == __file__  # the warning points at the caller's line
    assert field in sim.pipeline.unread_parameters(config)


@pytest.mark.parametrize("algorithm, kwargs", [
    ("tile", {"hiz": {"enabled": True, "tile_size": 8}}),
    ("gpu_wedge", {"hiz": {"enabled": True, "tile_size": 8}, "gpu_constants": "strip"}),
    ("lines", {"lines": {**sim.PipelineConfig().lines, "tile_clip": True}}),
    ("tile", {"sample_fraction": 0.5, "sample_seed": 7}),
    ("tile", {"shading": "cache", "shading_grid": 2}),
])
def test_a_parameter_the_render_reads_is_not_warned_about(algorithm, kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("error", sim.UnreadParameterWarning)
        assert sim.pipeline.unread_parameters(sim.PipelineConfig(algorithm=algorithm, **kwargs)) == {}


def test_unread_hiz_changes_neither_the_image_nor_the_counters():
    """What the warning claims: bruteforce renders the same with and without HiZ enabled."""
    import numpy as np

    import models

    scene = models.named("spot_wall", width=24, height=24)
    cam = sim.Camera.for_scene(scene, width=24, height=24, coc_px=4)
    table = sim.SampleTable.stratified(spp=4, seed=1)
    with pytest.warns(sim.UnreadParameterWarning):
        on = sim.PipelineConfig(algorithm="bruteforce", threads=1, hiz={"enabled": True, "tile_size": 8})
    a = sim.render(scene, cam, table, on, timing=False)
    b = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1), timing=False)
    assert np.array_equal(a.image, b.image) and a.flat_stats == {**b.flat_stats, "time.wall_s": a.flat_stats["time.wall_s"]}


def _config(tmp_path, text: str):
    """(config, source, lines) of a config file, as `rast5d run` expands it."""
    p = tmp_path / "c.yaml"
    p.write_text(text)
    data, lines = xc.load_dict(p)
    return xc.validate(data, str(p), lines), str(p), lines


BASE = """name: unread
scene: {name: spot_wall, params: {width: 16, height: 16}}
camera: {width: 16, height: 16, coc_px: 4}
samples: {kind: stratified, spp: 4, seed: 1}
"""


def test_a_sweep_point_with_an_unread_parameter_hashes_as_without_it(tmp_path):
    plain = expand_sweep(*_config(tmp_path, BASE + "pipeline: {algorithm: bruteforce}\n"))[0][1]
    with pytest.warns(sim.UnreadParameterWarning, match=r"c\.yaml:\d+: pipeline\.hiz\.enabled is set but not read"):
        (_, cfg), = expand_sweep(*_config(tmp_path, BASE + "pipeline: {algorithm: bruteforce, hiz: {enabled: true}}\n"))
    assert cfg.pipeline.hiz["enabled"] is False  # stored as the render sees it
    assert config_hash(cfg) == config_hash(plain)


def test_a_swept_parameter_that_some_points_do_not_read_is_warned_about_once(tmp_path):
    text = BASE + ("pipeline: {algorithm: tile}\nsweep:\n  pipeline.algorithm: [tile, bruteforce]\n"
                   "  pipeline.hiz.enabled: [false, true]\n")
    with pytest.warns(sim.UnreadParameterWarning) as got:
        points = expand_sweep(*_config(tmp_path, text))
    unread = [str(w.message) for w in got if issubclass(w.category, sim.UnreadParameterWarning)]
    assert len(unread) == 1 and "1 of 4 sweep points" in unread[0], unread
    hashes = {(p["pipeline.algorithm"], p["pipeline.hiz.enabled"]): config_hash(c) for p, c in points}
    assert hashes["bruteforce", True] == hashes["bruteforce", False]  # one render serves both
    assert hashes["tile", True] != hashes["tile", False]  # tile reads it


# ---- no code decides by an algorithm's name ---------------------------------------------------------

_NAME_TEST = re.compile(r"""(algorithm|\balg\w*|\ba\b)\s*(==|!=)\s*["'](lines|gpu_\w*)["']|"""
                        r"""\.startswith\(\s*["'](gpu_|lines)""")
_PENDING: dict[str, str] = {}


def _sources():
    for folder in ("sim", "experiments", "models", "rast5d"):
        yield from sorted((ROOT / folder).rglob("*.py"))


@pytest.mark.parametrize("path", [p.relative_to(ROOT).as_posix() for p in _sources()])
def test_no_code_compares_an_algorithm_name_to_decide(path, request):
    if path in _PENDING:
        request.applymarker(pytest.mark.xfail(strict=True, reason=_PENDING[path]))
    hits = [f"{path}:{i}: {line.strip()}" for i, line in enumerate((ROOT / path).read_text().splitlines(), 1)
            if _NAME_TEST.search(line)]
    assert not hits, "decide by sim.algorithm_info(name) facts, not the name:\n" + "\n".join(hits)
