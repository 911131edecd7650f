"""`make run`: the default experiment (configs/quickstart.yaml). Runs a small CoC x spp x algorithm
sweep on spot_wall through the result store (cached), and writes reports/quickstart/: README.md with
the plots (PNG + PDF), the tables, the speed-vs-error chart and an image grid."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .config import REPO, load_dict, validate
from .report import section_markdown
from .runner import results_dir, run_sweep

CONFIG = REPO / "configs" / "quickstart.yaml"


def image_grid(df, images: Path, out: Path, algorithm: str = "tile") -> Path:
    """Rows: spp; columns: CoC; one algorithm (every exact algorithm renders the same image)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    from .plots import STYLE

    d = df[(df["pipeline.algorithm"] == algorithm) & (df["status"] == "ok")]
    spps, cocs = sorted(d["samples.spp"].unique()), sorted(d["camera.coc_px"].unique())
    with matplotlib.rc_context(STYLE):
        fig, axes = plt.subplots(len(spps), len(cocs), figsize=(1.9 * len(cocs), 1.9 * len(spps)), squeeze=False)
        for i, spp in enumerate(spps):
            for j, coc in enumerate(cocs):
                ax = axes[i][j]
                row = d[(d["samples.spp"] == spp) & (d["camera.coc_px"] == coc)]
                if len(row):
                    ax.imshow(Image.open(images / f"{row['config_hash'].iloc[0]}.png"))
                    rmse = row["metric.rmse"].iloc[0] if "metric.rmse" in row else float("nan")
                    ax.set_title(f"CoC {coc:g}, {spp} spp\nRMSE {rmse:.3f}", fontsize=7)
                ax.set_axis_off()
        fig.savefig(out, dpi=150)
        plt.close(fig)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default=str(REPO / "reports" / "quickstart"))
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a config key")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    data, lines = load_dict(CONFIG, args.set)
    config = validate(data, str(CONFIG), lines)
    images = results_dir() / "images" / config.name
    df = run_sweep(config, source="configs/quickstart.yaml", workers=args.workers, images_dir=images, lines=lines)
    elapsed = time.perf_counter() - t0
    cmd = "make run" + ("" if not args.set else " (python -m experiments.quickstart "
                        + " ".join(f"--set {s}" for s in args.set) + ")")
    md = [f"# {config.outputs.page}", ""]
    md += section_markdown(config, CONFIG, df, out, cmd, args.set, elapsed)
    grid = image_grid(df, images, out / "image_grid.png")
    md += ["## Images (tile; every exact algorithm renders the same image)", "", f"![image grid]({grid.name})", "",
           f"`make run` took {time.perf_counter() - t0:.0f} s on this run ({df.attrs['summary']['rendered']} points "
           f"rendered, {df.attrs['summary']['cached']} from the cache in results/).", ""]
    (out / "README.md").write_text("\n".join(md) + "\n")
    ok = df[df["status"] == "ok"]
    for _, r in ok[ok["samples.spp"] == 16].iterrows():
        print(f"  CoC {r['camera.coc_px']:>4g} px, 16 spp, {r['pipeline.algorithm']:<10}: tested "
              f"{r['raster.samples_tested']:>10,.0f}  STE {r['raster.ste']:.3f}  ops/pixel {r['ops.per_pixel']:>8,.0f}  "
              f"RMSE {r['metric.rmse']:.4f}")
    print(f"wrote {out}/README.md ({len(df)} points) in {time.perf_counter() - t0:.1f} s")
    return 0 if (df["status"] == "ok").all() else 1


if __name__ == "__main__":
    sys.exit(main())
