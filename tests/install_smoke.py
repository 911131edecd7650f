"""Smoke test of an installed wheel (run by `make test-install` in a fresh venv, outside the checkout):
the package imports from the environment, not the checkout; the version matches pyproject.toml; a
named scene renders with honest counters; a Mitsuba XML and a mesh load; the command line renders a
config. Plain asserts, no pytest (the fresh environment has only the package's own dependencies)."""
from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from pathlib import Path

CHECKOUT = Path(__file__).resolve().parents[1]


def main() -> int:
    import experiments
    import models
    import sim

    for module in (sim, models, experiments) if "--editable" not in sys.argv else ():
        where = Path(module.__file__).resolve()
        assert CHECKOUT not in where.parents or "site-packages" in where.parts, f"{module.__name__} from {where}"
    expected = re.search(r'^version = "([^"]+)"', (CHECKOUT / "pyproject.toml").read_text(), re.M).group(1)
    assert experiments.__version__ == expected, (experiments.__version__, expected)
    bin_dir = Path(sys.executable).parent
    out = subprocess.run([bin_dir / "rast5d", "--version"], capture_output=True, text=True, check=True).stdout
    assert out.startswith(f"rast5d {expected}"), out
    for what, needle in (("algorithms", "tile"), ("scenes", "spot_wall"), ("counters", "raster.samples_tested")):
        out = subprocess.run([bin_dir / "rast5d", "list", what], capture_output=True, text=True, check=True).stdout
        assert needle in out, (what, out)

    scene = models.named("quad")
    camera = sim.Camera(width=32, height=32, coc_px=4, **{k: v for k, v in scene.camera_hint.items()
                                                          if k not in ("width", "height")})
    result = sim.render(scene, camera, sim.SampleTable.stratified(spp=4, seed=1), sim.PipelineConfig(algorithm="tile"))
    stats = result.flat_stats
    assert stats["raster.samples_tested"] >= stats["raster.samples_hit"] > 0, stats["raster.samples_hit"]

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        (tmp / "scene.xml").write_text(
            '<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="40"/>'
            '<transform name="to_world"><lookat origin="0.3, 0.3, 3" target="0.3, 0.3, 0" up="0, 1, 0"/>'
            '</transform><film type="hdrfilm"><integer name="width" value="48"/><integer name="height" '
            'value="32"/></film></sensor><shape type="obj"><string name="filename" value="tri.obj"/>'
            '<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf></shape></scene>')
        loaded = models.load(tmp / "scene.xml")
        assert loaded.n_triangles == 1 and loaded.camera_hint["width"] == 48, loaded
        (tmp / "c.yaml").write_text(f"scene: {{path: {tmp / 'scene.xml'}}}\nsamples: {{spp: 4}}\n")
        out = subprocess.run([bin_dir / "rast5d", "render", str(tmp / "c.yaml"), "-o", str(tmp / "c.png")],
                             capture_output=True, text=True, cwd=tmp)
        assert out.returncode == 0, out.stderr
        assert (tmp / "c.png").stat().st_size > 0 and "samples tested" in out.stdout, out.stdout
    print(f"install smoke: rast5d {expected} on Python {sys.version.split()[0]} from "
          f"{Path(sim.__file__).resolve().parent.parent}: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
