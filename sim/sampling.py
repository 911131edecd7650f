"""Sampled simulation: render a stratified random subset of the screen bins and estimate the frame.

``PipelineConfig(sample_fraction=f, sample_seed=s)`` with f < 1: the engine sorts the K screen bins that
hold triangles by their brute-force work (the pixels of their triangles' bounds in the bin times spp),
cuts them into H = round(f * K) // 2 strata of similar work and draws 2 bins per stratum
(sampled/bin_sample.h, seeded with s). Only those bins are traversed; bins without triangles do no
traversal work (their counters are exactly 0). Bins heavier than a stratum's share of the work form a
take-all stratum (all traversed, no variance).

Per-triangle work runs only where it is needed (sampled/sampled_setup.h): a bounds pre-pass over
every triangle (setup's own screen bounds, nothing charged) gives each bin's work and the frame totals
of the auxiliaries below; full triangle setup and binning run only for the triangles whose bounds
reach a drawn bin. setup.triangles and the setup of the triangles culled behind the near plane or off
screen are the frame's exactly; every other triangle's setup counters belong to its home bin (the bin
of the top-left corner of its bounds, where traversals charge their per-triangle setup too) and are
estimated with that bin's counters.

Every counter a bin owns is estimated by the stratified regression (GREG) estimator on four auxiliary
variables whose frame totals the engine knows before traversing any bin (sampled/bin_covariates.h):
brute-force work x1, the triangles' lens-centre coverage x2, their lens-swept footprint x3 and their
lens-centre perimeter x4 spread over their bounds (edge) (the bins' own x2 ... x4 are computed for the
drawn bins only):

    T = T_y + (X - T_x) b,    Var(T) = sum_h N_h^2 (1 - n_h / N_h) s_h^2(g e) / n_h

T_y, T_x the stratified expansion estimates (T = sum_h N_h * mean_h), X the frame's known totals of
the auxiliaries, b the design-weighted least-squares fit of y on x over the drawn bins, and s_h^2(g e)
the within-stratum variance of the residuals e = y - x b weighted by the g-weights
g = 1 + (X - T_x)' A^-1 x (A the weighted cross-product of x; N_h bins in stratum h, n_h = 2 drawn).
The residual variance is scaled by n / (n - p) for the fit's p coefficients (p = 4; n bins drawn from
sampled strata), and the 95% half-width is t_{0.975, H - (p - 1)} * sqrt(Var) (H sampled strata less
the coefficients the fit adds to a ratio estimator's one as degrees of freedom). An auxiliary whose
frame total is 0 is left out of the fit and of p. A counter that
follows the auxiliaries (tile tests with the footprint, hits with the coverage) is estimated far more
tightly than by expansion alone; one that does not is no worse than the stratified estimator, and the
interval comes from the residuals either way. Derived figures (ratios, sums) are evaluated on the
estimated totals; their half-widths come from the same formula applied to each bin's linearised
contribution (the derivative of the figure along that bin's counter vector).

The intervals assume no sampled stratum is dominated by a few of its bins. With very few strata on a
frame whose work sits in a few very dense bins that stay below the take-all threshold, they can cover
far below 95% (modern_hall at 512 x 288, 8-px bins, f = 0.01, 11 strata: 0.41 over 100 draws; at
1024 x 576 and every fraction from 0.01: >= 0.90): prefer fractions giving a few tens of strata
(``sample.strata``). ``estimate`` warns (``sim.errors.FewStrataWarning``) below FEW_STRATA sampled strata.

Not estimable under sampling (reported as NaN with a NaN half-width, never scaled):

- the texture cache (``tex.cache.*``): it is replayed after the render in bin order, and a bin's
  misses depend on the lines the bins before it left in the cache;
- the timing model (``timing.*``): its FIFOs and unit overlap couple the work of consecutive bins, so
  a frame's cycles are not a sum of per-bin terms.

Units smaller than a bin (``PipelineConfig(sample_split=s)``, s in (0, 1]; sampled/dense_units.h): a bin
whose work exceeds s times a stratum's share (W / H) is cut into ceil(work / (s W / H)) units of its
triangles, dealt in serpentine order of their work in the bin, and the units replace the bin in the
population the strata are drawn from (``sample.candidates`` counts units). A drawn unit is traversed as
its bin holding only its triangles, so the dense bins are no longer a take-all floor. The estimator is
the same; it is unbiased for the counters that are sums over (triangle, bin) visits that read no depth
buffer (VISIT_SUMS: setup, raster, tile and interval tests, ops.total's parts). Counters that depend on
the triangles drawn before in the bin (depth passes, ops.interp, HiZ and z-culling, shading, texture fetches) would
be biased (a unit's triangles see fewer occluders) and are NaN under units; the draw refuses
configurations where the traversal itself reads depth (HiZ), line samples and the GPU pipeline. At
sample_fraction 1, or when no bin exceeds the cap, nothing is cut and the render is as with s = 0.

HiZ and z-culling, the shading cache and shading visits restart in every bin (backend/hiz.h,
backend/shading.h), so their counters are per-bin sums and are estimated like the others. Occlusion
queries stop at the first visible sample of the frame and cannot be sampled (an error).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ConfigError

# Figures that need the whole frame (prefixes of counter and figure names).
NOT_ESTIMABLE = ("tex.cache.", "timing.")
# Under units of the dense bins' triangles (pipeline.sample_split > 0): the counters that are sums over
# (triangle, bin) visits independent of the triangles drawn before in the bin (no depth buffer read).
# Every other counter (depth passes and writes, ops.interp, whose colour interpolation follows the depth
# test, HiZ and z-culling, shading, texture fetches, line segments, the GPU pipeline's and the
# conservative records) is not estimated: NaN, with a NaN half-width. tests/test_sampling.py checks the
# mean of each over many draws against the whole frame. The frame's facts (frame.*) are exact.
VISIT_SUMS = ("frame.", "setup.", "raster.", "precision.", "interval.", "tile.", "trav.", "alpha.", "ops.setup",
              "ops.tile", "ops.sample_region", "ops.sample_inside", "ops.ps_setup", "depth.tests",
              "conservative.pixels_tested")
MIN_STRATA = 2  # two strata of two bins: the fewest that give a variance estimate
FEW_STRATA = 20  # below this many sampled strata the intervals can cover well under 95% (a warning)

DOCS = {
    "sample.fraction": ("ratio", "Sampled simulation: sample.bins / sample.candidates"),
    "sample.bins": ("bins", "Sampled simulation: screen bins traversed (2 per stratum; with sample_split, units of "
                    "the dense bins' triangles count as bins)"),
    "sample.strata": ("strata", "Sampled simulation: strata the bins were drawn from (0: every bin with triangles, exact)"),
    "sample.candidates": ("bins", "Sampled simulation: screen bins that hold triangles (the others do no traversal "
                          "work; with sample_split, a dense bin counts as its units)"),
}


def docs() -> dict[str, tuple[str, str]]:
    return dict(DOCS)


def t_quantile_975(df: int) -> float:
    """The 0.975 quantile of Student's t with df degrees of freedom (closed form for df 1, 2; the
    Cornish-Fisher expansion around the normal quantile above, accurate to 1e-3 for df >= 3)."""
    if df < 1:
        raise ValueError(f"df: expected >= 1, got {df}")
    if df == 1:
        return math.tan(math.pi * 0.475)
    if df == 2:
        q = 0.975
        return (2 * q - 1) / math.sqrt(2 * q * (1 - q))
    z = 1.959963984540054
    g1 = (z ** 3 + z) / 4
    g2 = (5 * z ** 5 + 16 * z ** 3 + 3 * z) / 96
    g3 = (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / 384
    g4 = (79 * z ** 9 + 776 * z ** 7 + 1482 * z ** 5 - 1920 * z ** 3 - 945 * z) / 92160
    return z + g1 / df + g2 / df ** 2 + g3 / df ** 3 + g4 / df ** 4


@dataclass(frozen=True)
class BinSample:
    """The traversed bins: ``bins`` (row-major indices), ``stratum`` (the stratum of each), ``sizes``
    (bins per stratum), ``candidates`` (bins that hold triangles; the others do no traversal work)."""

    bins: np.ndarray
    stratum: np.ndarray
    sizes: np.ndarray
    candidates: int
    work: np.ndarray | None = None  # brute-force work of every bin of the frame (the first auxiliary)
    aux: np.ndarray | None = None   # (bins of the frame, k) further auxiliaries (the engine's bin_aux;
                                    # only the drawn bins' rows are read)
    aux_total: np.ndarray | None = None  # (k,) their frame totals (None: the sums of ``aux``)
    units: bool = False  # some dense bins were cut into units of their triangles (pipeline.sample_split)

    @property
    def fraction(self) -> float:
        return len(self.bins) / self.candidates if self.candidates else 1.0

    @property
    def exact(self) -> bool:
        """Every bin with triangles was traversed: the figures are exact."""
        return len(self.sizes) == 0


def check_fraction(fraction, owner: str = "PipelineConfig") -> None:
    if isinstance(fraction, bool) or not isinstance(fraction, (int, float)) or not 0 < fraction <= 1:
        raise ConfigError(f"{owner}.sample_fraction: expected a number in (0, 1], got {fraction!r}")


def check_split(config) -> None:
    """ConfigError when units of the dense bins' triangles (config.sample_split > 0) would change what the
    estimated counters count: the traversal reads the depth buffer (HiZ z-culling), a unit's line samples
    merge and occlude within the bin, the GPU pipeline's early depth test, or shading (its texture-line
    stream is per bin and its visits depend on depth)."""
    from .pipeline import algorithm_info

    info = algorithm_info(config.algorithm)
    why = None
    if info.samples == "lines":
        why = f"algorithm {config.algorithm!r} tests line samples, whose segment buffers merge and occlude across a bin's triangles"
    elif info.pipeline == "gpu":
        why = f"algorithm {config.algorithm!r} runs the GPU pipeline, whose fragments pass a depth test in bin order"
    elif info.depth_cull and config.hiz["enabled"]:
        why = "hiz.enabled: z-culling skips tile and sample tests by the depths the bin's earlier triangles left"
    elif config.shading != "none":
        why = f"shading {config.shading!r}: shading visits depend on depth order and share the bin's texture-line stream"
    if why:
        raise ConfigError(f"PipelineConfig.sample_split: {config.sample_split!r} cuts dense bins into units of their "
                          f"triangles, but {why}; use sample_split=0")


def choose_bins(work, fraction: float, seed: int, aux=None) -> BinSample:
    """The engine's draw (sampled/bin_sample.h) for per-bin brute-force work ``work``: the bins
    with work sorted by it, cut into round(fraction * K) // 2 strata, 2 bins drawn per stratum.
    ConfigError when fewer than 2 strata remain (no interval can be given)."""
    check_fraction(fraction)
    from . import _core

    work = np.asarray(work, dtype=np.int64)
    try:
        bins, stratum, sizes = _core.stratify_bins(work.tolist(), float(fraction), int(seed))
    except ValueError as e:
        raise ConfigError(f"PipelineConfig.{e}") from None
    return BinSample(np.asarray(bins, np.int64), np.asarray(stratum, np.int64), np.asarray(sizes, np.int64),
                     int((work > 0).sum()), work, None if aux is None else np.asarray(aux, np.float64))


def from_engine(out: dict) -> BinSample:
    """The BinSample of a sampled engine render (sim._core.render's output)."""
    work = np.asarray(out["bin_work"])
    aux, total = out.get("bin_aux"), out.get("bin_aux_total")
    # With units of the dense bins the per-unit vectors extend past the screen bins (sampled/dense_units.h).
    units = len(work) > int(out["counters"]["frame.bins"])
    return BinSample(np.asarray(out["bins"], np.int64), np.asarray(out["bin_stratum"], np.int64),
                     np.asarray(out["strata_sizes"], np.int64), int((work > 0).sum()), work,
                     None if aux is None else np.asarray(aux, np.float64),
                     None if total is None else np.asarray(total, np.float64), units)


def _design(sample: BinSample) -> tuple[np.ndarray, np.ndarray]:
    """(N_h, n_h) per stratum: bins in the stratum, bins drawn from it."""
    H = len(sample.sizes)
    return sample.sizes.astype(np.float64), np.bincount(sample.stratum, minlength=H).astype(np.float64)


def stratified_total(sample: BinSample, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(estimated frame totals, variances) of per-bin values y (rows: the sampled bins; columns:
    figures), by the stratified expansion estimator with 2 bins per stratum."""
    y = np.asarray(y, dtype=np.float64)
    if y.ndim == 1:
        y = y[:, None]
    Nh, nh = _design(sample)
    # Per-stratum sums in draw order (every stratum has drawn bins): reduceat over the bins sorted by stratum.
    order = np.argsort(sample.stratum, kind="stable")
    starts = np.searchsorted(sample.stratum[order], np.arange(len(Nh)))
    means = np.add.reduceat(y[order], starts, axis=0) / nh[:, None]
    dev = y - means[sample.stratum]
    ss = np.add.reduceat((dev * dev)[order], starts, axis=0)
    full = nh >= Nh  # a take-all stratum: every bin traversed, no sampling variance
    s2 = np.where(full[:, None], 0.0, ss / np.maximum(nh - 1, 1)[:, None])
    total = (Nh[:, None] * means).sum(axis=0)
    var = (Nh ** 2 * (1 - nh / Nh) / nh)[:, None] * s2
    return total, var.sum(axis=0)


class Estimator:
    """The estimator of one draw, fitted once and applied to any per-bin values (the counters, and the
    derived figures' linearised contributions):

    - with brute-force work and the auxiliaries ``aux``: the stratified regression (GREG) estimator,
      T = T_y + (X - T_x) b, b the least-squares fit of y on x weighted by the design weights
      N_h / n_h, and the variance of the stratified estimator applied to the residuals y - x b
      weighted by the g-weights, scaled by n / (n - p) for the p coefficients of the fit;
    - with work only: the combined ratio estimator T = X T_y / T_x;
    - with neither: the stratified expansion estimator.

    An auxiliary whose frame total is 0 (no bin has any) is left out of the fit, and ``coefficients``
    counts the auxiliaries the fit uses (the degrees of freedom of the interval lose all but one)."""

    def __init__(self, sample: BinSample):
        self.sample = sample
        self.coefficients = 0
        if sample.work is None:
            return
        work = np.asarray(sample.work, np.float64)
        if sample.aux is None:
            self._x = work[sample.bins][:, None]
            self._X = np.array([work.sum()])
            self._tx = stratified_total(sample, self._x)[0]
            self.coefficients = 1
            self._ratio = True
            return
        self._ratio = False
        aux = np.asarray(sample.aux, np.float64)
        total = np.nansum(aux, axis=0) if sample.aux_total is None else np.asarray(sample.aux_total, np.float64)
        X = np.concatenate([[work.sum()], total])  # the frame's totals
        x = np.column_stack([work[sample.bins], aux[sample.bins]])
        keep = X > 0
        x = x[:, keep] / X[keep]  # columns whose totals are 1: a well-conditioned fit
        self._x, self._X = x, np.ones(x.shape[1])
        self.coefficients = x.shape[1]
        Nh, nh = _design(sample)
        w = (Nh / nh)[sample.stratum]
        self._xw = x * w[:, None]
        self._A = x.T @ self._xw
        self._tx = stratified_total(sample, x)[0]
        # The residuals weighted by the g-weights (the estimator is sum_i w_i g_i y_i with
        # g_i = 1 + (X - T_x)' A^-1 x_i): a draw far from the known totals gets the wider interval it needs.
        self._g = 1.0 + x @ np.linalg.lstsq(self._A, self._X - self._tx, rcond=1e-10)[0]
        # Residuals of a fit understate the errors by the coefficients it spent: n / (n - p) over the n
        # bins drawn from sampled strata (the take-all stratum has no variance).
        n = int(nh[nh < Nh].sum())
        p = self.coefficients
        self._scale = n / (n - p) if n > p else float("inf")

    @property
    def extra_coefficients(self) -> int:
        """Coefficients beyond a ratio estimator's one: the degrees of freedom the fit takes."""
        return max(0, self.coefficients - 1)

    def total(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(estimated frame totals, variances) of per-bin values y (rows: the drawn bins; columns: figures)."""
        y = np.asarray(y, dtype=np.float64)
        y = y[:, None] if y.ndim == 1 else y
        if self.sample.work is None:
            return stratified_total(self.sample, y)
        ty, _ = stratified_total(self.sample, y)
        x = self._x
        if self._ratio:
            r = ty / self._tx[0]
            _, var = stratified_total(self.sample, y - x * r[None, :])
            return self._X[0] * r, var
        b = np.linalg.lstsq(self._A, self._xw.T @ y, rcond=1e-10)[0]
        _, var = stratified_total(self.sample, (y - x @ b) * self._g[:, None])
        return ty + (self._X - self._tx) @ b, var * self._scale


def sampled_strata(sample: BinSample) -> int:
    """Strata whose bins were drawn (not the take-all stratum): the degrees of freedom."""
    nh = np.bincount(sample.stratum, minlength=len(sample.sizes))
    return int((nh < sample.sizes).sum())


def estimate(sample: BinSample, counters: dict, bin_counters: np.ndarray, derived, names: list[str]
             ) -> tuple[dict, dict]:
    """(flat figures, 95% half-widths) of the frame from a sampled render.

    counters: the engine's totals (setup of every triangle + the rendered bins + frame facts);
    bin_counters: (len(bins), len(names)) the rendered bins' own counters; derived: sim.stats.DERIVED."""
    from .derived import evaluate

    bc = np.asarray(bin_counters, dtype=np.float64)
    totals = np.array([float(counters[n]) for n in names])
    exact_part = totals - bc.sum(axis=0)  # setup (every triangle) and the frame facts
    if sample.exact:  # every bin with triangles traversed: the totals are the frame's
        est, var, tq = bc.sum(axis=0), np.zeros(len(names)), 0.0
    else:
        fit = Estimator(sample)
        est, var = fit.total(bc)
        # degrees of freedom: the sampled strata less the regression's coefficients beyond the first
        tq = t_quantile_975(max(1, sampled_strata(sample) - fit.extra_coefficients))
    raw = exact_part + est
    half = tq * np.sqrt(var)
    flat, ci = {}, {}
    for i, n in enumerate(names):
        if n.startswith(NOT_ESTIMABLE) or (sample.units and not n.startswith(VISIT_SUMS)):
            flat[n], ci[n] = math.nan, math.nan
        else:
            flat[n], ci[n] = float(raw[i]), float(half[i])
    # Derived figures: evaluated on the estimates; half-widths by linearisation per bin (central
    # differences, every bin at once: the formulas are arithmetic and sim.derived.ratio, which
    # take arrays).
    base = evaluate(derived, dict(flat))
    dnames = [d.name for d in derived]
    step = 1e-6  # a bin's counters are at most the frame's: a relative perturbation <= 1e-6
    with np.errstate(divide="ignore", invalid="ignore"):
        plus = evaluate(derived, {n: flat[n] + step * bc[:, i] for i, n in enumerate(names)})
        minus = evaluate(derived, {n: flat[n] - step * bc[:, i] for i, n in enumerate(names)})
        z = np.column_stack([np.broadcast_to((np.asarray(plus[d], np.float64) - np.asarray(minus[d], np.float64))
                                             / (2 * step), (len(bc),)) for d in dnames]) if dnames else np.zeros((len(bc), 0))
    dvar = np.zeros(len(dnames)) if sample.exact else fit.total(np.nan_to_num(z, nan=0.0))[1]
    for j, d in enumerate(dnames):
        flat[d] = base[d]
        bad = not np.isfinite(base[d]) or not np.all(np.isfinite(z[:, j]))
        ci[d] = math.nan if bad else float(tq * math.sqrt(dvar[j]))
    flat.update({"sample.fraction": sample.fraction, "sample.bins": len(sample.bins),
                 "sample.strata": len(sample.sizes), "sample.candidates": sample.candidates})
    if not sample.exact and sampled_strata(sample) < FEW_STRATA:
        import warnings

        from .errors import FewStrataWarning

        warnings.warn(f"sample_fraction: drawing {len(sample.bins)} of {sample.candidates} bins gives "
                      f"{sampled_strata(sample)} sampled strata (fewer than {FEW_STRATA}): the 95% intervals "
                      "can cover far below 95%; raise sample_fraction or use smaller bins (pipeline.bin_size)",
                      FewStrataWarning, stacklevel=3)
    return flat, ci
