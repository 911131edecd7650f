"""`rast5d report`: run every report config (configs/paper/*.yaml, and each configs/*.yaml that names
an `outputs.page`; the configs folder is --configs DIR, else ./configs, else the shipped configs:
experiments/paths.py) through the result store's cache and write one Markdown page per `outputs.page`
into reports/<outputs.folder>/ under the working directory (--reports DIR) (figures as PNG + PDF, our numbers, the paper's published numbers
beside them, the exact command and config), plus the index reports/README.md. `--quick` renders a
small-resolution variant into reports/quick/ with its own result store (results/quick/), so it never
clobbers the full report.

Configs whose file name starts with `_` are bases for `extends:` and are not run.
"""
from __future__ import annotations

import functools
import json
import os
import shlex
import sys
import time
from collections import defaultdict
from pathlib import Path

from .. import paths
from ..config import ConfigError, RenderConfig, load_dict, validate
from ..run import images_dir, results_dir, run_sweep
from .figures import render_plot
from .frames import PROSE_DATA, PlotError, apply_derived, ok_rows
from . import hardware as _hardware  # noqa: F401  (registers the hardware page's named tables)
from .tables import TABLES, VALUES, md_table

# --quick: every point at most QUICK_SIZE pixels on a side (aspect kept when the config gives both),
# the same samples per pixel, sweeps and pages.
QUICK_SIZE = 64


# --quick also samples (pipeline.sample_fraction, sim/sampling.py) the render points whose outputs
# need no whole-frame figure and whose quick frame has at least 8 x 8 bins: QUICK_FRACTION of the
# 8-px bins that hold triangles. Configs that read image metrics, the
# timing model, the texture cache or bin sizes, and other point kinds, render whole frames.
QUICK_FRACTION, QUICK_BIN = 0.5, 8
_WHOLE_FRAME = ("timing", "tex.cache", "metrics", "bin_size", "sample_fraction", "hinterleave_tile")


def quick_overrides(data: dict) -> list[str]:
    cam = data.get("camera") or {}
    w, h = cam.get("width"), cam.get("height")
    if w and h:
        s = min(1.0, QUICK_SIZE / max(w, h))
        out = [f"camera.width={max(8, round(w * s))}", f"camera.height={max(8, round(h * s))}"]
    else:
        out = [f"camera.width={QUICK_SIZE}", f"camera.height={QUICK_SIZE}"]
    text = json.dumps(data, default=str)
    size = [int(o.split("=")[1]) for o in out]
    # Sample only frames of at least 8 x 8 bins: fewer bins with triangles leave no interval.
    if (data.get("point") or {}).get("kind", "render") == "render" and not any(k in text for k in _WHOLE_FRAME) \
            and min(size) >= 8 * QUICK_BIN:
        out += [f"pipeline.bin_size={QUICK_BIN}", f"pipeline.sample_fraction={QUICK_FRACTION}"]
    return out


def _command(name: str, quick: bool) -> str:
    return f"rast5d report --only {name}" + (" --quick" if quick else "")


def section_markdown(config: RenderConfig, config_path: Path, df, out_dir: Path, command: str,
                     overrides: list[str] = (), elapsed: float | None = None, volatile: bool = True,
                     echo: bool = True) -> list[str]:
    """The Markdown of one config's section: title, text, figures, tables, provenance (with the run's
    times, engine and revision only when volatile)."""
    o = config.outputs
    lines = [f"## {o.title or config.name}", ""]
    try:
        dfd = apply_derived(df, o.derived)
    except PlotError as e:
        return lines + [f"**Error:** {e}", ""]
    # The summary and the text are templates over the page's data (experiments/report/prose.py), filled
    # when the page is assembled (fill_prose), once every section of the page has its rows.
    if o.summary:
        lines += [SUMMARY_BEGIN.format(name=config.name), prose_token(config.name, "summary"), SUMMARY_END, ""]
    if o.text:
        lines += [prose_token(config.name, "text"), ""]
    PROSE_DATA[config.name] = (config, df, dfd)
    if o.images and "config_hash" in dfd.columns:  # the points' images, for image_grid plots
        dfd = dfd.assign(**{"image.path": [str(images_dir(config.name) / f"{h}.png") for h in dfd["config_hash"]]})
    shown: list = []  # data tables already on the page, by figure
    # Scatter plots of the same rows that differ only in x share one data table (under the first,
    # with every x as a column): one data table per figure, never the same rows twice.
    first_of: dict[int, int] = {}
    extra_cols: dict[int, list] = {}
    groups: dict[tuple, int] = {}
    for i, spec in enumerate(o.plots):
        if spec.kind != "scatter":
            continue
        key = (spec.facet, str(spec.hue), spec.style, tuple(spec.columns), tuple(spec.ys),
               json.dumps(spec.where, sort_keys=True, default=str))
        if key in groups and spec.x in dfd.columns:
            first_of[i] = groups[key]
            extra_cols.setdefault(groups[key], []).append(spec.x)
        else:
            groups.setdefault(key, i)
    figure_no: dict[int, int] = {}
    for i, spec in enumerate(o.plots):
        if i in extra_cols:
            spec = spec.model_copy(update={"columns": [*spec.columns, *[c for c in extra_cols[i] if c != spec.x]]})
        base = out_dir / f"{config.name}_{i + 1}" if len(o.plots) > 1 else out_dir / config.name
        try:
            if spec.kind == "image" or spec.map is not None:  # pictures of single points
                from .heatmaps import point_pictures
                from .frames import apply_where, same

                dd = ok_rows(dfd)
                for col, names in spec.labels.items():  # display names first, as in render_plot
                    if col in dd.columns:
                        dd = dd.assign(**{col: [next((n for k, n in names.items() if same(v, k)), v) for v in dd[col]]})
                from .figures import column_labels

                with column_labels(o.column_labels):
                    res = point_pictures(spec, config, apply_where(dd, spec.where), base)
            else:
                res = render_plot(spec, dfd, base, derived=o.derived, names=o.column_labels)
        except PlotError as e:
            lines += [f"**Plot error:** {e}", ""]
            continue
        if res.get("skipped"):
            continue
        if spec.title and spec.kind == "table":
            lines += [f"**{spec.title}**", ""]
        if spec.echo and echo:
            print("\n".join(([spec.title, ""] if spec.title else []) + res["markdown"]))
        if res["files"]:
            png = res["files"][0]
            lines += [f"![{spec.title or config.name}]({png.name})", "",
                      f"[PDF]({png.with_suffix('.pdf').name})", ""]
            figure_no[i] = len(shown) + 1
            if i in first_of and first_of[i] in figure_no:
                lines += [f"Data: the table under figure {figure_no[first_of[i]]} of this section "
                          f"(column `{spec.x}`).", ""]
            elif res["markdown"] in shown:  # the same table is not repeated
                lines += [f"Data: the table under figure {shown.index(res['markdown']) + 1} of this section.", ""]
            else:
                lines += ["<details><summary>data</summary>", ""] + res["markdown"] + ["", "</details>", ""]
            shown.append(res["markdown"])
        else:
            lines += res["markdown"] + [""]
    ok = ok_rows(df)
    bad = df[df["status"] != "ok"] if "status" in df.columns else df.iloc[0:0]
    if len(bad):
        lines += ["**Failed points** (kept out of the figures and tables):", ""]
        for _, r in bad.iterrows():
            lines.append(f"- {r.get('scene.name')} {r.get('pipeline.algorithm')} CoC {r.get('camera.coc_px')} "
                         f"spp {r.get('samples.spp')}: {r.get('error')}")
        lines.append("")
    wall = float(ok["time.wall_s"].sum()) if "time.wall_s" in ok.columns and len(ok) else 0.0
    shown, target = config_link(config_path, out_dir)
    engine = ok["engine.version"].iloc[0] if "engine.version" in ok.columns and len(ok) else "n/a"
    rev = ok["engine.git_rev"].iloc[0] if "engine.git_rev" in ok.columns and len(ok) else "n/a"
    # Times, engine and revision change on every run: a committed page (volatile=False) keeps them out,
    # so regenerating it leaves git clean; they are printed and kept in results/provenance/ instead.
    run_facts = (f"{wall:.0f} s of render time" + (f", {elapsed:.0f} s this run" if elapsed is not None else "")
                 + f"; engine {engine}, revision {rev}")
    lines += [f"Made by `{command}` from [`{shown}`]({target})"
              + (f" with `{' '.join('--set ' + shlex.quote(s) for s in overrides)}`" if overrides else "")
              + f": {len(df)} points ({len(bad)} failed)" + (f", {run_facts}" if volatile else "")
              + f". Results: `experiments.load({config.name!r})`.", ""]
    if not volatile:
        print(f"{config.name}: {len(df)} points ({len(bad)} failed), {run_facts}")
        record = results_dir() / "provenance" / f"{config.name}.txt"
        record.parent.mkdir(parents=True, exist_ok=True)
        record.write_text(f"{command}: {len(df)} points ({len(bad)} failed), {run_facts}\n")
    try:
        lines += ["<details><summary>config</summary>", "", "```yaml", config_path.read_text().rstrip(), "```", "",
                  "</details>", ""]
    except OSError:
        pass
    return lines


# ---- prose: the templates of a section's summary and text (experiments/report/prose.py) --------------

SUMMARY_BEGIN, SUMMARY_END = "<!-- summary:{name} -->", "<!-- /summary -->"
_TOKEN = "\x00prose:{name}:{part}\x00"


def prose_token(name: str, part: str) -> str:
    return _TOKEN.format(name=name, part=part)


def _with_keys(df, config):
    """df with attrs["keys"]: its columns that a sweep key of config sets (what tells its rows apart), by
    which the prose pairs the rows of two references."""
    swept = [k for k in config.sweep if k != "zip"]
    df = df.copy()
    df.attrs["keys"] = [str(c) for c in df.columns if any(str(c) == k or str(c).startswith(k + ".") for k in swept)]
    return df


def fill_prose(lines: list[str], names: list[str]) -> tuple[list[str], int]:
    """The page's lines with each section's summary and text filled from the page's data: a section's own
    rows (derived columns included), the other sections of the page by config name, the section's named
    value tables (tables.VALUES) by table name, and its named tables ({{table:NAME}}) placed. Returns
    (lines, number of prose errors); an error is printed on the page in place of the paragraph."""
    from .prose import ProseError, Sources, fill

    frames = {n: _with_keys(ok_rows(PROSE_DATA[n][2]), PROSE_DATA[n][0]) for n in names if n in PROSE_DATA}
    section_values: dict = {}  # a named value table is computed once per section, however often it is quoted
    out, errors = [], 0
    for line in lines:
        if not line.startswith("\x00prose:"):
            out.append(line)
            continue
        name, part = line.strip("\x00").split(":")[1:3]
        config, df, dfd = PROSE_DATA[name]
        template = (config.outputs.summary if part == "summary" else config.outputs.text or "").strip()
        if name not in section_values:
            section_values[name] = {k: functools.cache(lambda fn=fn, dfd=dfd, config=config: fn(ok_rows(dfd), config))
                                    for k, fn in VALUES.items()}
        values = section_values[name]
        sources = Sources(frames.get(name, _with_keys(ok_rows(dfd), config)), {n: f for n, f in frames.items() if n != name},
                          values)
        try:
            text = fill(template, sources)
            if part == "summary":  # one paragraph, as the README quotes it
                text = " ".join(text.split())
        except ProseError as e:
            errors += 1
            print(f"{name}: prose error: {e}", file=sys.stderr)
            out.append(f"**Prose error:** {e}")
            continue
        for key, fn in TABLES.items():
            marker = "{{table:" + key + "}}"
            if marker in text:
                text = text.replace(marker, "\n".join(fn(df, config)))
        out.append(text)
    return out, errors


def _configs_root(config_path: Path) -> Path | None:
    """The configs folder a config file belongs to (the nearest parent named configs), or None."""
    for parent in Path(config_path).resolve().parents:
        if parent.name == "configs":
            return parent
    return None


def config_link(config_path: Path, out_dir: Path) -> tuple[str, str]:
    """(the config's name as shown, a relative link from out_dir to it) for a page's provenance line.
    A config inside the installed package (a shipped config) is copied, with the bases it extends,
    to <out_dir's report root>/configs/ first, so the link works wherever the pages are moved."""
    config_path = Path(config_path).resolve()
    root = _configs_root(config_path)
    shown = f"configs/{config_path.relative_to(root).as_posix()}" if root is not None else config_path.name
    target = config_path
    if paths.inside_installed_package(config_path) and root is not None:
        report_root = Path(out_dir).resolve()
        while report_root.parent != report_root and report_root.name != "reports" and report_root != Path.cwd():
            report_root = report_root.parent
        target = report_root / shown
        for src in [config_path, *_config_bases(config_path)]:
            dst = report_root / "configs" / src.relative_to(root)
            dst.parent.mkdir(parents=True, exist_ok=True)
            if not dst.exists() or dst.read_bytes() != src.read_bytes():
                dst.write_bytes(src.read_bytes())
    return shown, Path(os.path.relpath(target, Path(out_dir).resolve())).as_posix()


def _config_bases(path: Path) -> list[Path]:
    """The files a config extends, recursively."""
    import yaml

    try:
        bases = (yaml.safe_load(path.read_text()) or {}).get("extends") or []
    except (OSError, yaml.YAMLError):
        return []
    out = []
    for b in [bases] if isinstance(bases, str) else bases:
        bp = (path.parent / b).resolve()
        if bp.exists() and bp not in out:
            out += [bp, *_config_bases(bp)]
    return out


def write_config_page(config: RenderConfig, config_path, df, overrides=(), echo: bool = True) -> Path:
    """`rast5d run`: the config's own page, results/pages/<name>/<name>.md (not committed)."""
    out_dir = results_dir() / "pages" / config.name
    out_dir.mkdir(parents=True, exist_ok=True)
    cmd = "rast5d run " + str(config_path) + "".join(f" --set {shlex.quote(s)}" for s in overrides)
    lines = [f"# {config.outputs.page or config.name}", ""]
    lines += section_markdown(config, Path(config_path), df, out_dir, cmd, overrides, echo=echo)
    lines, _ = fill_prose(lines, [config.name])
    page = out_dir / f"{config.name}.md"
    page.write_text("\n".join(lines) + "\n")
    return page


def report_configs(configs_dir: Path | None = None) -> list[Path]:
    """The report configs of a configs folder (default: experiments.paths.configs_dir()): its
    ``paper/*.yaml`` and each top-level ``*.yaml`` that names an outputs.page; a folder without paper/ gives
    every config in it (files starting with _ are bases for `extends:`)."""
    def run(found):
        return [p for p in sorted(found) if not p.name.startswith("_")]

    root = Path(configs_dir) if configs_dir is not None else paths.configs_dir()
    if not (root / "paper").is_dir():
        return run(root.glob("*.yaml"))
    top = [p for p in run(root.glob("*.yaml")) if (load_dict(p)[0].get("outputs") or {}).get("page")]
    return run((root / "paper").glob("*.yaml")) + top


def _retimed_renders(loaded) -> set[str]:
    """Hashes of the renders that the report's retime points re-time: those render points keep their
    timing records in the store, so a page's retime sections re-time them instead of rendering again."""
    from ..run.runner import hashed_sweep, render_hash

    keep = set()
    for p, config, _, lines in loaded:
        if config.point.kind == "retime":
            keep.update(render_hash(cfg) for _, cfg, _ in hashed_sweep(config, _source(p), lines))
    return keep


def _pictured(loaded) -> dict[str, set[str]]:
    """{config hash: picture names} of the points the pages picture (heatmaps.pictured_points): their
    sweep renders keep the image and maps in the store, so the page does not render them again."""
    from ..run.runner import hashed_sweep
    from .heatmaps import pictured_points

    out: dict[str, set[str]] = {}
    for p, config, _, lines in loaded:
        if any(sp.kind == "image" or sp.map is not None for sp in config.outputs.plots):
            for h, names in pictured_points(config, [(h, cfg) for _, cfg, h in
                                                     hashed_sweep(config, _source(p), lines)]).items():
                out.setdefault(h, set()).update(names)
    return out


def _source(p: Path) -> str:
    """A config file as its errors name it: configs/<path> (or the path as given)."""
    root = _configs_root(p)
    return f"configs/{Path(p).resolve().relative_to(root).as_posix()}" if root is not None else str(p)


def main(only=None, workers=None, scheduler=None, force=False, quick=False, configs_dir: Path | None = None,
         reports_dir: Path | None = None, retry_failed: bool = False) -> int:
    from ..run.runner import sweeps_once

    with sweeps_once():  # each sweep expanded and hashed once for the pool, the sweep and its pictures
        return _main(only, workers, scheduler, force, quick, configs_dir, reports_dir, retry_failed)


def _main(only, workers, scheduler, force, quick, configs_dir, reports_dir, retry_failed) -> int:
    reports_root = paths.check_output_dir(paths.reports_dir(reports_dir), "reports directory", "--reports DIR")
    paths.check_results_dir()
    out_root = reports_root / ("quick" if quick else "")
    if quick:
        os.environ["RAST5D_RESULTS"] = str(results_dir() / "quick")
    found = report_configs(configs_dir)
    if not found:
        print(f"report: no report configs in {paths.display(Path(configs_dir or paths.configs_dir()))} "
              "(`rast5d init DIR` copies the shipped ones)", file=sys.stderr)
        return 2
    loaded = []
    for p in found:
        data, lines = load_dict(p)
        overrides = quick_overrides(data) if quick else []
        if overrides:
            data, lines = load_dict(p, overrides)
        config = validate(data, str(p), lines)
        loaded.append((p, config, overrides, lines))
    if only:
        known = {c.name for _, c, _, _ in loaded} | {c.outputs.page for _, c, _, _ in loaded if c.outputs.page}
        unknown = [n for n in only if n not in known]
        if unknown:
            print(f"report: unknown {unknown} (configs and pages: {', '.join(sorted(known))})", file=sys.stderr)
            return 2
        chosen = {c.name for _, c, _, _ in loaded if c.name in only or c.outputs.page in only}
        # A page is written whole: the other configs on a chosen config's page come along (from the
        # result store; --force re-renders only the chosen ones).
        pages = {c.outputs.page or c.name for _, c, _, _ in loaded if c.name in chosen}
        loaded = [x for x in loaded if (x[1].outputs.page or x[1].name) in pages]
    else:
        chosen = {c.name for _, c, _, _ in loaded}
    keep_records = _retimed_renders(loaded)
    pictures = _pictured(loaded)
    sections: dict[tuple[str, str], list] = defaultdict(list)
    counts = {"rendered": 0, "cached": 0, "failures": 0, "rows": 0}
    t_all = time.perf_counter()

    source = _source
    # One pool over every config's missing points, costliest config first (experiments/run/schedule.py), in a
    # thread: the sweeps below wait for their points' rows (the pool holds their store locks) and each
    # page section is written as soon as its rows are in, while the pool works on. Dask-run configs and
    # workers=0 (in-process) skip it.
    pool = None
    if scheduler is None and (workers is None or workers > 0):
        from ..run.schedule import run_all

        pool = run_all([(c, source(p), lines) for p, c, _, lines in loaded if c.executor.kind != "dask"],
                       workers=workers or os.cpu_count() or 1, keep_records=keep_records,
                       force=chosen if force else frozenset(), retry_failed=retry_failed, background=True,
                       pictures=pictures)
    try:
        _sweeps_and_sections(loaded, pool, chosen, sections, counts, out_root, quick, workers, scheduler, force,
                             retry_failed, keep_records, source, pictures)
    except BaseException:
        if pool is not None:
            pool.stop()
        raise
    if pool is not None:
        pool.join()
        counts["rendered"] += pool.computed
    # every row not computed in this run came from the store (a point shared by two configs counts once)
    counts["cached"] = max(0, counts.pop("rows") - counts["rendered"])
    failures = counts.pop("failures")
    for (folder, page), parts in sections.items():
        page_dir = out_root / folder
        parts.sort(key=lambda t: (t[0], t[1]))
        text = [f"# {page}", "", f"Regenerate with `{_command(page, quick)}` (this page) or "
                f"`rast5d report{' --quick' if quick else ''}` (all pages)."
                + (f" **Quick variant**: at most {QUICK_SIZE} px on a side; numbers are not comparable to the "
                   "paper's." if quick else ""), ""]
        for _, _, md, _ in parts:
            text += md
        text, prose_errors = fill_prose(text, [name for _, name, _, _ in parts])
        failures += prose_errors
        (page_dir / f"{page}.md").write_text("\n".join(text) + "\n")
        print(f"wrote {paths.display(page_dir / f'{page}.md')}")
    # The index lists the pages on disk, so a partial run that wrote a paper page refreshes it too.
    if not only or any(folder == "paper" for folder, _ in sections):
        write_index(out_root, out_root / "paper", quick, time.perf_counter() - t_all, counts, reports_root)
    if not quick:  # the README's Results section, from the summaries of the pages on disk
        from .readme import write_results

        write_results(reports_root)
    return 1 if failures else 0


def _sweeps_and_sections(loaded, pool, chosen, sections, counts, out_root, quick, workers, scheduler, force,
                         retry_failed, keep_records, source, pictures=None):
    """Each config's sweep (from the store, or waiting for the pool's rows) and its page section, in the
    order the pool completes the configs (PoolRun.wait_ready): a section written as soon as its rows
    are in keeps this process busy while the pool works on, instead of leaving every section to the
    end. Sections are placed on their pages by outputs.order."""
    remaining = list(loaded)
    while remaining:
        i = pool.wait_ready([c.name for _, c, _, _ in remaining]) if pool is not None else 0
        p, config, overrides, lines = remaining.pop(i)
        t0 = time.perf_counter()
        pooled = pool is not None and config.executor.kind != "dask"
        df = run_sweep(config, source=source(p), workers=workers, scheduler=scheduler,
                       force=force and config.name in chosen and not pooled, lines=lines,
                       retry_failed=retry_failed, keep_records=keep_records, pictures=pictures,
                       pooled=pool.hashes if pooled else frozenset())
        counts["failures"] += int((df["status"] != "ok").sum()) if "status" in df.columns else 0
        summary = df.attrs.get("summary", {})
        counts["rendered"] += summary.get("rendered", 0) - summary.get("pooled", 0)  # the pool counts its own
        counts["rows"] += len(df)
        page = config.outputs.page or config.name
        page_dir = out_root / config.outputs.folder
        page_dir.mkdir(parents=True, exist_ok=True)
        md = section_markdown(config, p, df, page_dir, _command(config.name, quick), overrides,
                              time.perf_counter() - t0, volatile=False)
        sections[config.outputs.folder, page].append((config.outputs.order, config.name, md, config))


def write_index(out_root: Path, page_dir: Path, quick: bool, elapsed: float, counts: dict,
                reports_root: Path | None = None):
    """reports/README.md (or reports/quick/README.md): every page, with the title of its sections."""
    import re

    rows = []
    for md in sorted(page_dir.glob("*.md")):
        if md.name == "README.md":
            continue
        titles = re.findall(r"^## (.+)$", md.read_text(), flags=re.M)
        rows.append([f"[{md.stem}]({md.relative_to(out_root)})", "; ".join(titles)])
    lines = ["# Reports" + (" (quick variant)" if quick else ""), "",
             f"Generated by `rast5d report{' --quick' if quick else ''}` from the report configs in `configs/` "
             "(`configs/paper/` and `configs/quickstart.yaml`; results cached in `results/`, or `results/quick/` for "
             "--quick; `--force` re-renders). Each page shows our numbers beside the paper's published numbers where "
             "they exist, and the command and config that made it.", ""]
    print(f"report: {elapsed:.0f} s ({counts['rendered']} points rendered, {counts['cached']} from the result store)")
    lines += md_table(["page", "sections"], rows) + [""]
    root = reports_root or out_root
    other = [p for p in (root / "quickstart" / "quickstart.md", root / "bench" / "bench_core.md",
                         root / "ccd" / "README.md") if p.exists()]
    if other and not quick:
        lines += ["Other reports: " + ", ".join(f"[{p.relative_to(root)}]({p.relative_to(root)})"
                                                 for p in other), ""]
    (out_root / "README.md").write_text("\n".join(lines) + "\n")


__all__ = ["main", "write_config_page", "section_markdown", "report_configs", "ConfigError"]
