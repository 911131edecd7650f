"""The programmable sample table (docs/architecture.md; docs/conventions.md).

A P×P block of pixels repeats over the screen; pixel (px, py) uses the spp samples of table entry
[py mod P, px mod P]. Each sample is (x, y, u, v, t): x, y ∈ [0, 1) inside the pixel, (u, v) in the
lens shape Ω ⊆ [-1, 1]², t ∈ [0, 1). A sample's canonical index s (its position in the table) names
its depth-buffer slot, whatever order an algorithm visits samples in.

Generated tables are lens-agnostic: they store canonical unit-cube values (x, y, a, b, t) in
[0, 1)⁵ and map (a, b) onto a lens shape only when asked (`sim.lens.map_to_lens`). Every canonical
value is float32-representable, so `samples()` reproduces x, y and t exactly and any stratum or
elementary-interval property of the canonical values holds for the float32 samples too.

Seeding (documented contract): a generator draws every random number from
``np.random.default_rng(np.random.SeedSequence(entropy=seed,
spawn_key=(zlib.crc32(name.encode()), period)))``, so a table is a pure function of
(generator, params) and different generators or periods never share a stream. All dimensions are
always drawn, even when `lens` or `time` is off, so switching a dimension off leaves the others
unchanged.

Generators are registered by name with `@_generator(name)` (one implementation,
registered by name: docs/architecture.md §Where to add a thing) and appear as classmethods: ``SampleTable.stratified(spp=16, seed=1)`` is
``SampleTable.create("stratified", spp=16, seed=1)``. User tables come from
``SampleTable.from_array``.
"""

from __future__ import annotations

import math
import zlib
from typing import Callable

import numpy as np

from .errors import ConfigError

from .lens import LENS_SHAPES, check_shape, inside_lens, map_to_lens

MAX_SPP = 4096
# Lines per wagon wheel of SampleTable.lines: chosen by the wheel sweep of the methods page (the lowest mean
# RMSE excess at equal operations over its scenes; reports/paper/methods.md).
LINE_WHEEL = 2
MAX_PERIOD = 256
LENS_GRID_SIZES = (1, 2, 4, 8, 16)

# name -> (implementation, extra parameter defaults)
_GENERATORS: dict[str, tuple[Callable[..., "_Draw"], dict[str, object]]] = {}
# generators fit to render reference images (image-error metrics): no parameter of their own
_REFERENCE_GENERATORS: list[str] = []
# generators whose tables have discrete lens coordinates (n_lens > 0): the interleaved algorithms' tables
_DISCRETE_LENS_GENERATORS: list[str] = []
_COMMON_DEFAULTS: dict[str, object] = {"seed": 0, "period": 32, "lens": True, "time": True}


class SampleTable:
    """A P×P-periodic table of spp 5D samples per pixel. Build it with a generator classmethod
    (``random``, ``stratified``, ``stratified_permuted``, ``sobol``, ``interleaved``) or with
    ``from_array``; see the module docstring."""

    def __init__(
        self,
        *,
        generator: str,
        period: int,
        spp: int,
        seed: int | None,
        params: dict,
        has_lens: bool,
        has_time: bool,
        unit: np.ndarray | None = None,
        lens_unit: np.ndarray | None = None,
        lens_index: np.ndarray | None = None,
        final: np.ndarray | None = None,
        final_lens_positions: np.ndarray | None = None,
        declared_lens: str = "any",
    ):
        # Use the classmethods; this constructor trusts its (already validated) arguments.
        self.generator = generator
        self.period = period
        self.spp = spp
        self.seed = seed
        self.params = dict(params)
        self.has_lens = bool(has_lens)
        self.has_time = bool(has_time)
        self.unit = _readonly(unit)
        self.lens_unit = _readonly(lens_unit)
        self.lens_index = _readonly(lens_index)
        if lens_index is not None:
            self.n_lens = int(final_lens_positions.shape[0] if lens_unit is None else lens_unit.shape[0])
        else:
            self.n_lens = 0
        self._final = _readonly(final)  # from_array: the user's float32 samples
        self._final_lens_positions = _readonly(final_lens_positions)
        self._declared_lens = declared_lens
        self._samples_cache: dict[str, np.ndarray] = {}
        self._positions_cache: dict[str, np.ndarray] = {}
        self._grid_cache: dict[tuple[int, str], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._index_cache: dict[tuple[str, int, int], object] = {}
        self._dims_cache: dict[str, tuple[bool, bool]] = {}

    # ---------------------------------------------------------------- registry

    @classmethod
    def generators(cls, reference: bool = False, discrete_lens: bool | None = None) -> list[str]:
        """Names accepted by `create` (procedural generators; `from_array` is separate), in
        registration order; ``reference=True``: only those registered as reference generators (the
        metrics' reference images); ``discrete_lens``: only those whose tables have (True) or lack
        (False) discrete lens coordinates (what the interleaved algorithms need)."""
        names = list(_REFERENCE_GENERATORS) if reference else list(_GENERATORS)
        if discrete_lens is not None:
            names = [n for n in names if (n in _DISCRETE_LENS_GENERATORS) == discrete_lens]
        return names

    @classmethod
    def kinds(cls) -> list[str]:
        """Every table kind a config may name: the generators, then 'lines' (SampleTable.lines)."""
        return cls.generators() + ["lines"]

    @classmethod
    def create(cls, name: str, **params) -> "SampleTable":
        """Build a table with generator `name`. Common params: spp (required, 1..4096), seed=0,
        period=32 (1..256), lens=True, time=True; some generators take more (see their docs)."""
        if name not in _GENERATORS:
            raise ConfigError(
                f"generator: unknown sample-table generator {name!r} "
                f"(known: {', '.join(_GENERATORS)}; line samples are SampleTable.lines (samples.kind lines), "
                "user arrays go through SampleTable.from_array)"
            )
        impl, extra_defaults = _GENERATORS[name]
        known = ["spp", *_COMMON_DEFAULTS, *extra_defaults]
        for key in params:
            if key not in known:
                import difflib

                close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise ConfigError(f"{name}: unknown parameter {key!r}{hint} (known: {', '.join(known)})")
        if "spp" not in params:
            raise ConfigError(f"spp: required by the {name} generator")
        full = {**_COMMON_DEFAULTS, **extra_defaults, **params}
        spp = _check_int("spp", full["spp"], 1, MAX_SPP)
        period = _check_int("period", full["period"], 1, MAX_PERIOD)
        seed = _check_int("seed", full["seed"], 0, 2**63 - 1)
        lens = _check_bool("lens", full["lens"])
        time = _check_bool("time", full["time"])
        extras = {k: full[k] for k in extra_defaults}
        rng = np.random.default_rng(
            np.random.SeedSequence(entropy=seed, spawn_key=(zlib.crc32(name.encode()), period))
        )
        spec = _Spec(name=name, spp=spp, period=period, lens=lens, time=time)
        draw = impl(spec, rng, **extras)
        unit = draw.unit
        if not lens:
            unit[..., 2:4] = 0.5
        if not time:
            unit[..., 4] = 0.0
        params_out = {"spp": spp, "seed": seed, "period": period, "lens": lens, "time": time, **draw.params}
        return cls(
            generator=name,
            period=period,
            spp=spp,
            seed=seed,
            params=params_out,
            has_lens=lens,
            has_time=time,
            unit=unit,
            lens_unit=draw.lens_unit,
            lens_index=draw.lens_index,
        )

    # ---------------------------------------------------------------- user arrays

    @classmethod
    def from_array(cls, samples, *, lens_index=None, lens_positions=None, lens: str = "any") -> "SampleTable":
        """A user table in *final* coordinates: shape (spp, 5) (the same samples in every pixel,
        period 1) or (P, P, spp, 5) indexed [py, px, s]; columns x, y ∈ [0, 1), u, v ∈ [-1, 1],
        t ∈ [0, 1], checked after conversion to float32 (what the engine sees).

        `lens` declares the aperture the (u, v) were made for: "any" (default) means no shape
        check at all, and `samples(shape)` returns the values as given for every shape; a shape
        name means every (u, v) must lie inside it, and `samples(shape)` / `lens_positions`
        raise ValueError for a requested shape that some (u, v) lies outside of.

        Interleaved user tables give both `lens_positions` (N, 2) and `lens_index` (same leading
        shape as samples, values in 0..N-1); each sample's (u, v) must then equal
        lens_positions[lens_index] bitwise in float32.

        has_lens is False when every u = v = 0; has_time is False when every t is equal (the
        values are still returned as given). `unit`, `lens_unit` and `seed` are None."""
        if lens != "any" and lens not in LENS_SHAPES:
            raise ConfigError(f"lens: unknown shape {lens!r} (known: any, {', '.join(LENS_SHAPES)})")
        arr = np.asarray(samples)
        if arr.dtype.kind not in "fiu":
            raise ConfigError(f"samples: expected a real numeric array, got dtype {arr.dtype}")
        if arr.ndim == 2 and arr.shape[1] == 5:
            broadcast = True  # one pixel's samples, repeated with period 1
            arr4 = arr[None, None]
        elif arr.ndim == 4 and arr.shape[3] == 5 and arr.shape[0] == arr.shape[1]:
            broadcast = False
            arr4 = arr
        else:
            raise ConfigError(f"samples: expected shape (spp, 5) or (P, P, spp, 5), got {arr.shape}")
        period, spp = arr4.shape[0], arr4.shape[2]
        if not 1 <= spp <= MAX_SPP:
            raise ConfigError(f"samples: spp (axis -2) must be in 1..{MAX_SPP}, got {spp}")
        if not 1 <= period <= MAX_PERIOD:
            raise ConfigError(f"samples: period (axes 0, 1) must be in 1..{MAX_PERIOD}, got {period}")

        def where(mask4: np.ndarray) -> tuple[int, ...]:
            """First True index of a (P, P, spp[, ...]) mask, in the user's array shape."""
            idx = tuple(int(i) for i in np.argwhere(mask4)[0])
            return idx[2:] if broadcast else idx

        def full_index(i: tuple[int, ...]) -> tuple[int, ...]:
            return (0, 0) + i if broadcast else i

        as64 = arr4.astype(np.float64)
        bad = ~np.isfinite(as64)
        if bad.any():
            i = where(bad)
            raise ConfigError(f"samples: non-finite value at index {i}: {arr[i]}")
        final = np.ascontiguousarray(arr4, dtype=np.float32)
        names = ("x", "y", "u", "v", "t")
        bounds = ((0.0, 1.0, True), (0.0, 1.0, True), (-1.0, 1.0, False), (-1.0, 1.0, False), (0.0, 1.0, False))
        for c, (name, (lo, hi, open_hi)) in enumerate(zip(names, bounds)):
            col = final[..., c]
            bad = (col < lo) | ((col >= hi) if open_hi else (col > hi))
            if bad.any():
                i = where(bad)
                rng_txt = f"[{lo:g}, {hi:g})" if open_hi else f"[{lo:g}, {hi:g}]"
                raise ConfigError(
                    f"samples: {name} must be in {rng_txt}; first offending sample at index {i} has "
                    f"{name} = {float(col[full_index(i)])!r} (as float32)"
                )
        if lens != "any":
            bad = ~inside_lens(final[..., 2], final[..., 3], lens)
            if bad.any():
                i = where(bad)
                k = full_index(i)
                raise ConfigError(
                    f"samples: (u, v) at index {i} = ({float(final[k][2])!r}, {float(final[k][3])!r}) "
                    f"is outside the declared {lens!r} lens"
                )

        positions = index = None
        if (lens_index is None) != (lens_positions is None):
            raise ConfigError("lens_index: lens_index and lens_positions must be given together")
        if lens_positions is not None:
            pos = np.asarray(lens_positions)
            if pos.dtype.kind not in "fiu" or pos.ndim != 2 or pos.shape[1] != 2 or pos.shape[0] < 1:
                raise ConfigError(
                    f"lens_positions: expected a real (N, 2) array with N >= 1, got shape {pos.shape} "
                    f"dtype {pos.dtype}"
                )
            positions = np.ascontiguousarray(pos, dtype=np.float32)
            bad = ~np.isfinite(positions).all(axis=1) | (np.abs(positions) > 1.0).any(axis=1)
            if lens != "any":
                bad |= ~inside_lens(positions[:, 0], positions[:, 1], lens)
            if bad.any():
                i = int(np.argmax(bad))
                where_txt = "[-1, 1]^2" if lens == "any" else f"the declared {lens!r} lens"
                raise ConfigError(
                    f"lens_positions: position {i} = {positions[i].tolist()} is not finite or not in "
                    f"{where_txt}"
                )
            idx = np.asarray(lens_index)
            expected = arr.shape[:-1]
            if idx.dtype.kind not in "iu" or idx.shape != expected:
                raise ConfigError(
                    f"lens_index: expected an integer array of shape {expected}, got shape {idx.shape} "
                    f"dtype {idx.dtype}"
                )
            idx4 = idx.reshape(period, period, spp).astype(np.int64)
            bad = (idx4 < 0) | (idx4 >= positions.shape[0])
            if bad.any():
                i = where(bad)
                raise ConfigError(
                    f"lens_index: value at index {i} = {int(idx[i])} is not in 0..{positions.shape[0] - 1}"
                )
            index = idx4.astype(np.int32)
            want = positions[index]
            bad = (want.view(np.uint32) != final[..., 2:4].view(np.uint32)).any(axis=-1)
            if bad.any():
                i = where(bad)
                k = full_index(i)
                raise ConfigError(
                    f"samples: (u, v) at index {i} = {final[k][2:4].tolist()} is not bitwise equal to "
                    f"lens_positions[{int(index[k])}] = {positions[index[k]].tolist()}"
                )
        has_lens = bool((final[..., 2:4] != 0.0).any())
        has_time = bool((final[..., 4] != final.reshape(-1, 5)[0, 4]).any())
        return cls(
            generator="from_array",
            period=period,
            spp=spp,
            seed=None,
            params={"lens": lens},
            has_lens=has_lens,
            has_time=has_time,
            lens_index=index,
            final=final,
            final_lens_positions=positions,
            declared_lens=lens,
        )

    # ---------------------------------------------------------------- line samples

    @classmethod
    def lines(cls, n_lines: int = 16, seed: int = 0, period: int = 32, wheel: int = LINE_WHEEL) -> "SampleTable":
        """A line-sample table for ``PipelineConfig(algorithm="lines")`` ([Tzeng 2012]
        §3): per pixel ``n_lines`` lines through the centre of the disk lens, as wagon wheels of
        ``wheel`` lines sharing one screen point. The n_lines angles are stratified over [0, π)
        with a random rotation per pixel (θ_k = π(k + ξ)/n_lines); line k belongs to wheel
        k mod (n_lines / wheel), so every wheel's spokes are spread evenly; the wheels' screen
        points are jittered on a stratified grid of the pixel. Sample s holds (x, y, cos θ, sin θ,
        0): (u, v) is the line's direction, and the line covers the lens points p (u, v), p in
        [-1, 1]. Static scenes only (no time); the disk lens only. The default wheel, LINE_WHEEL lines, is
        the size with the lowest RMSE at equal operations over the wheel sweep of the methods page
        (reports/paper/methods.md, configs/paper/methods_wheel.yaml): smaller wheels place more screen
        points per pixel (sharper in-focus edges), larger ones more lens directions per point."""
        n_lines = _check_int("n_lines", n_lines, 1, MAX_SPP)
        seed = _check_int("seed", seed, 0, 2**63 - 1)
        period = _check_int("period", period, 1, MAX_PERIOD)
        wheel = _check_int("wheel", wheel, 1, MAX_SPP)
        wheel = min(wheel, n_lines)
        if n_lines % wheel:
            raise ConfigError(f"n_lines: expected a multiple of wheel ({wheel}), got {n_lines}")
        n_points = n_lines // wheel
        rng = np.random.default_rng(
            np.random.SeedSequence(entropy=seed, spawn_key=(zlib.crc32(b"lines"), period)))
        P = period
        nx, ny = _grid_shape(n_points)
        cell = rng.permuted(np.tile(np.arange(n_points), (P, P, 1)), axis=2)
        jit = rng.random((P, P, n_points, 2))
        px = ((cell % nx) + jit[..., 0]) / nx
        py = ((cell // nx) + jit[..., 1]) / ny
        xi = rng.random((P, P, 1))
        out = np.zeros((P, P, n_lines, 5), dtype=np.float32)
        for m in range(n_points):
            for j in range(wheel):
                k = m + j * n_points
                s = m * wheel + j
                theta = np.pi * (k + xi[..., 0]) / n_lines
                out[:, :, s, 0] = _round_down_f32(px[:, :, m])
                out[:, :, s, 1] = _round_down_f32(py[:, :, m])
                out[:, :, s, 2] = np.cos(theta)
                out[:, :, s, 3] = np.sin(theta)
        table = cls(generator="lines", period=P, spp=n_lines, seed=seed,
                    params={"n_lines": n_lines, "seed": seed, "period": P, "wheel": wheel},
                    has_lens=True, has_time=False, final=out, declared_lens="any")
        table.kind = "lines"
        table.n_lines = n_lines
        return table

    # ---------------------------------------------------------------- views

    def samples(self, lens: str = "disk") -> np.ndarray:
        """(P, P, spp, 5) float32 [py, px, s, (x, y, u, v, t)] for lens shape `lens` (read-only,
        cached per shape). Interleaved tables: (u, v) == lens_positions(lens)[lens_index] bitwise."""
        check_shape(lens)
        cached = self._samples_cache.get(lens)
        if cached is not None:
            return cached
        if self._final is not None:
            self._check_declared(self._final[..., 2], self._final[..., 3], lens, "samples")
            out = self._final
        else:
            out = np.empty(self.unit.shape, dtype=np.float32)
            out[..., 0] = self.unit[..., 0]  # exact: canonical values are float32-representable
            out[..., 1] = self.unit[..., 1]
            out[..., 4] = self.unit[..., 4]
            if not self.has_lens:
                out[..., 2:4] = 0.0
            elif self.lens_index is not None:
                out[..., 2:4] = self.lens_positions(lens)[self.lens_index]
            else:
                u, v = map_to_lens(self.unit[..., 2], self.unit[..., 3], lens)
                out[..., 2] = u
                out[..., 3] = v
            out = _readonly(out)
        self._samples_cache[lens] = out
        return out

    def dimensions(self, lens: str = "disk") -> tuple[bool, bool]:
        """(any sample has a lens position other than (0, 0), any has a time other than 0) for lens
        shape ``lens``: where the engine may skip a dimension exactly (cached per shape)."""
        dims = self._dims_cache.get(lens)
        if dims is None:
            s = self.samples(lens)
            dims = self._dims_cache[lens] = (bool(np.any(s[..., 2:4] != 0)), bool(np.any(s[..., 4] != 0)))
        return dims

    def lens_positions(self, lens: str = "disk") -> np.ndarray:
        """(N, 2) float32 discrete lens positions of an interleaved table (read-only)."""
        check_shape(lens)
        if self.n_lens == 0:
            raise ConfigError(
                f"lens_positions: the {self.generator} table has no discrete lens positions "
                f"(only interleaved tables do)"
            )
        cached = self._positions_cache.get(lens)
        if cached is not None:
            return cached
        if self._final_lens_positions is not None:
            p = self._final_lens_positions
            self._check_declared(p[:, 0], p[:, 1], lens, "lens_positions")
        else:
            u, v = map_to_lens(self.lens_unit[:, 0], self.lens_unit[:, 1], lens)
            p = _readonly(np.stack([u, v], axis=1).astype(np.float32))
        self._positions_cache[lens] = p
        return p

    def lens_grid(self, grid: int, lens: str = "disk") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lens-grid buckets ([Akenine-Möller 2012] §5.1, Fig. 10) from the engine:
        (order (P,P,spp), counts (P,P,G*G), offsets (P,P,G*G)), int32; cell = j*G + i."""
        if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)) or int(grid) not in LENS_GRID_SIZES:
            raise ConfigError(
                f"lens_grid: grid must be one of {', '.join(map(str, LENS_GRID_SIZES))}, got {grid!r}"
            )
        grid = int(grid)
        key = (grid, check_shape(lens))
        if key not in self._grid_cache:
            from . import _core

            order, counts, offsets = _core.lens_grid_buckets(self.samples(lens), grid)
            self._grid_cache[key] = (_readonly(order), _readonly(counts), _readonly(offsets))
        return self._grid_cache[key]

    def __getstate__(self) -> dict:
        """Pickling and copying leave out the engine indexes (engine objects); engine_index rebuilds them."""
        state = dict(self.__dict__)
        state["_index_cache"] = {}
        return state

    def engine_index(self, lens: str, grid: int, time_strata: int):
        """The engine's copy of samples(lens) with its (lens cell, time stratum) index for lens grid
        ``grid`` and ``time_strata`` strata (sim._core.SampleTableIndex), built once per key and cached:
        sim.render passes it instead of the samples array. The engine object holds its own copy of
        the samples and has no mutator; the table's arrays are read-only, so the two cannot diverge."""
        key = (check_shape(lens), int(grid), int(time_strata))
        index = self._index_cache.get(key)
        if index is None:
            from . import _core

            if self.n_lens:
                lens_index = np.ascontiguousarray(self.lens_index, dtype=np.int32)
                lens_uv = np.ascontiguousarray(self.lens_positions(lens), dtype=np.float32)
            else:
                lens_index, lens_uv = np.zeros((0,), np.int32), np.zeros((0, 2), np.float32)
            index = _core.SampleTableIndex(self.samples(lens), key[1], key[2], lens_index, lens_uv)
            self._index_cache[key] = index
        return index

    def pixel_samples(self, px: int, py: int, lens: str = "disk") -> np.ndarray:
        """The (spp, 5) samples of screen pixel (px, py): samples(lens)[py mod P, px mod P]."""
        return self.samples(lens)[py % self.period, px % self.period]

    def describe(self) -> dict:
        """A flat dict for stats tables."""
        return {
            "generator": self.generator,
            "spp": self.spp,
            "period": self.period,
            "seed": self.seed,
            "n_lens": self.n_lens,
            "has_lens": self.has_lens,
            "has_time": self.has_time,
        }

    def __repr__(self) -> str:
        dims = "xy" + ("+uv" if self.has_lens else "") + ("+t" if self.has_time else "")
        extra = f", n_lens={self.n_lens}" if self.n_lens else ""
        seed = "" if self.seed is None else f", seed={self.seed}"
        return f"SampleTable({self.generator}, spp={self.spp}, period={self.period}{seed}{extra}, dims={dims})"

    def _check_declared(self, u: np.ndarray, v: np.ndarray, lens: str, field: str) -> None:
        if self._declared_lens == "any" or not self.has_lens:
            return
        bad = ~inside_lens(u, v, lens)
        if bad.any():
            i = tuple(int(k) for k in np.argwhere(bad)[0])
            raise ConfigError(
                f"{field}: (u, v) at index {i} = ({float(u[i])!r}, {float(v[i])!r}) is outside the "
                f"requested {lens!r} lens (the table was declared for {self._declared_lens!r})"
            )


# ==================================================================== generators


class _Spec:
    __slots__ = ("name", "spp", "period", "lens", "time")

    def __init__(self, *, name: str, spp: int, period: int, lens: bool, time: bool):
        self.name, self.spp, self.period, self.lens, self.time = name, spp, period, lens, time


class _Draw:
    """What a generator returns: canonical (P, P, spp, 5) values, plus the interleaved extras."""

    def __init__(self, unit, lens_unit=None, lens_index=None, params=None):
        self.unit = unit
        self.lens_unit = lens_unit
        self.lens_index = lens_index
        self.params = params or {}


def _generator(name: str, reference: bool = False, discrete_lens: bool = False, **extra_defaults):
    """Register a generator `impl(spec, rng, **extras) -> _Draw` under `name`, and expose it as
    the classmethod ``SampleTable.<name>(**params)``; ``reference``: it may render the reference
    images of the image-error metrics; ``discrete_lens``: its tables have discrete lens coordinates."""

    def register(impl):
        _GENERATORS[name] = (impl, extra_defaults)
        if reference:
            _REFERENCE_GENERATORS.append(name)
        if discrete_lens:
            _DISCRETE_LENS_GENERATORS.append(name)

        def factory(cls, **params):
            return cls.create(name, **params)

        factory.__name__ = factory.__qualname__ = name
        factory.__doc__ = impl.__doc__
        setattr(SampleTable, name, classmethod(factory))
        return impl

    return register


@_generator("random", reference=True)
def _random(spec: _Spec, rng: np.random.Generator) -> _Draw:
    """Independent uniform values in all five dimensions."""
    P, S = spec.period, spec.spp
    return _Draw(_round_down_f32(rng.random((P, P, S, 5))))


@_generator("stratified", reference=True)
def _stratified(spec: _Spec, rng: np.random.Generator) -> _Draw:
    """Per pixel: jittered (x, y) on an nx×ny grid (nx·ny = spp, closest to square, nx ≥ ny);
    (a, b) jittered on its own nx×ny grid and randomly permuted across the samples; t in spp
    jittered 1D strata, permuted independently (pbrt-style padding)."""
    P, S = spec.period, spec.spp
    nx, ny = _grid_shape(S)
    unit = np.empty((P, P, S, 5))
    _fill_xy_strata(unit, rng, nx, ny)
    lens_strata = rng.permuted(np.broadcast_to(np.arange(S), (P, P, S)), axis=-1)
    unit[..., 2] = _stratum_values(lens_strata % nx, nx, rng.random((P, P, S)))
    unit[..., 3] = _stratum_values(lens_strata // nx, ny, rng.random((P, P, S)))
    time_strata = rng.permuted(np.broadcast_to(np.arange(S), (P, P, S)), axis=-1)
    unit[..., 4] = _stratum_values(time_strata, S, rng.random((P, P, S)))
    return _Draw(unit, params={"grid_xy": (nx, ny), "grid_lens": (nx, ny)})


@_generator("stratified_permuted")
def _stratified_permuted(spec: _Spec, rng: np.random.Generator) -> _Draw:
    """[Akenine-Möller 2012] §6, Fig. 13: "permuted (x,y) sample positions for each block of
    2×2 pixels". (x, y) are jittered strata per pixel (as `stratified`); the lens (a, b) are
    jittered on an mx×my grid with mx·my = 4·spp over each 2×2 block, and t on 4·spp 1D strata
    over the block; both are randomly (and independently) assigned to the block's 4·spp
    (pixel, x/y-stratum) slots. Needs an even period."""
    P, S = spec.period, spec.spp
    if P % 2:
        raise ConfigError(f"period: the stratified_permuted generator uses 2x2-pixel blocks; expected an even period, got {P}")
    nx, ny = _grid_shape(S)
    mx, my = _grid_shape(4 * S)
    unit = np.empty((P, P, S, 5))
    _fill_xy_strata(unit, rng, nx, ny)
    Q = P // 2
    block = np.empty((Q, Q, 4 * S, 3))
    lens_strata = rng.permuted(np.broadcast_to(np.arange(4 * S), (Q, Q, 4 * S)), axis=-1)
    block[..., 0] = _stratum_values(lens_strata % mx, mx, rng.random((Q, Q, 4 * S)))
    block[..., 1] = _stratum_values(lens_strata // mx, my, rng.random((Q, Q, 4 * S)))
    time_strata = rng.permuted(np.broadcast_to(np.arange(4 * S), (Q, Q, 4 * S)), axis=-1)
    block[..., 2] = _stratum_values(time_strata, 4 * S, rng.random((Q, Q, 4 * S)))
    unit[..., 2:5] = _blocks_to_pixels(block, 2, S)
    return _Draw(unit, params={"grid_xy": (nx, ny), "grid_lens_block": (mx, my)})


@_generator("sobol", reference=True)
def _sobol(spec: _Spec, rng: np.random.Generator) -> _Draw:
    """Scrambled Sobol (0,2)-nets. The first spp points of the 2D Sobol sequence (dim 1: van der
    Corput = bit reversal; dim 2: the Pascal-matrix generator) give (x, y), and again (a, b);
    t is the 1D van der Corput sequence. Every dimension gets its own Owen-style nested uniform
    scramble per pixel, by hashing (Burley 2020, "Practical Hash-based Owen Scrambling": reverse
    bits, Laine–Karras permutation with a random 32-bit seed, reverse back), which keeps the
    (0,m,2)-net property when spp = 2^m. The (a, b) pairs and the t values are then randomly
    permuted across the pixel's samples, independently, to decorrelate them from (x, y)."""
    P, S = spec.period, spec.spp
    d1, d2 = _sobol_02(S)
    seeds = rng.integers(0, 2**32, size=(P, P, 1, 5), dtype=np.uint32)
    unit = np.empty((P, P, S, 5))
    for c, base in enumerate((d1, d2, d1, d2, d1)):
        scrambled = _owen_scramble(np.broadcast_to(base, (P, P, S)), seeds[..., c])
        unit[..., c] = _u32_to_unit(scrambled)
    lens_perm = rng.permuted(np.broadcast_to(np.arange(S), (P, P, S)), axis=-1)
    unit[..., 2:4] = np.take_along_axis(unit[..., 2:4], lens_perm[..., None], axis=2)
    time_perm = rng.permuted(np.broadcast_to(np.arange(S), (P, P, S)), axis=-1)
    unit[..., 4] = np.take_along_axis(unit[..., 4], time_perm, axis=2)
    return _Draw(unit, params={"scramble": "owen_hash"})


@_generator("interleaved", discrete_lens=True, n_lens=256)
def _interleaved(spec: _Spec, rng: np.random.Generator, n_lens) -> _Draw:
    """Interleaved sampling with N = n_lens discrete lens positions (any perfect square >= 1),
    jittered on a √N×√N grid of [0, 1)². Blocks of B×B pixels, B the smallest power of two with
    B²·spp >= N; each block's B²·spp samples take every position floor(B²·spp / N) times plus
    (B²·spp mod N) distinct extra positions chosen at random, in a random order per block, so
    per block every position occurs equally often whenever N divides B²·spp ([Akenine-Möller 2012]: N = 256,
    spp = 64 gives one sample per position per 2×2 block). spp >= N needs N | spp (then each
    pixel holds each position spp/N times). Needs period divisible by B. (x, y) are jittered
    strata per pixel; t is stratified per pixel and permuted."""
    P, S = spec.period, spec.spp
    if isinstance(n_lens, bool) or not isinstance(n_lens, (int, np.integer)) or n_lens < 1 or math.isqrt(int(n_lens)) ** 2 != n_lens:
        raise ConfigError(f"n_lens: expected a perfect square >= 1 (1, 4, 9, ..., 256, ...), got {n_lens!r}")
    N = int(n_lens)
    if not spec.lens:
        raise ConfigError("lens: the interleaved generator needs the lens dimension (lens=True), got False")
    if S >= N and S % N:
        raise ConfigError(f"spp: with spp >= n_lens the interleaved generator needs n_lens | spp, got spp={S}, n_lens={N}")
    B = 1
    while B * B * S < N:
        B *= 2
    if P % B:
        raise ConfigError(
            f"period: the interleaved generator with n_lens={N}, spp={S} uses {B}x{B}-pixel blocks; "
            f"expected a multiple of {B}, got {P}"
        )
    n = math.isqrt(N)
    unit = np.empty((P, P, S, 5))
    _fill_xy_strata(unit, rng, *_grid_shape(S))
    cells = np.arange(N)
    lens_unit = np.stack(
        [_stratum_values(cells % n, n, rng.random(N)), _stratum_values(cells // n, n, rng.random(N))], axis=1
    )
    Q = P // B
    M = B * B * S
    full, rest = divmod(M, N)
    per_block = np.empty((Q, Q, M), dtype=np.int64)
    per_block[..., : full * N] = np.tile(cells, full)
    if rest:
        per_block[..., full * N :] = np.argsort(rng.random((Q, Q, N)), axis=-1)[..., :rest]
    per_block = rng.permuted(per_block, axis=-1)
    lens_index = _blocks_to_pixels(per_block[..., None], B, S)[..., 0].astype(np.int32)
    unit[..., 2:4] = lens_unit[lens_index]
    time_strata = rng.permuted(np.broadcast_to(np.arange(S), (P, P, S)), axis=-1)
    unit[..., 4] = _stratum_values(time_strata, S, rng.random((P, P, S)))
    return _Draw(unit, lens_unit=lens_unit, lens_index=lens_index, params={"n_lens": N, "block_px": B})


@_generator("multiview", views=2)
def _multiview(spec: _Spec, rng: np.random.Generator, views) -> _Draw:
    """Stereo and multi-view rendering ([Nilsson 2012] §8, Fig. 16): the lens is split into
    `views` equal intervals of u, and view k owns samples k*m .. (k+1)*m - 1 of every pixel
    (m = spp / views), stratified as the `stratified` generator within its interval (so u of view k
    lies in [k/V, (k+1)/V) of the unit square). Use a square lens: the views are strips of one
    oblong lens region. views=1 is an ordinary stratified table."""
    if isinstance(views, bool) or not isinstance(views, (int, np.integer)) or not 1 <= views <= 64:
        raise ConfigError(f"views: expected an integer in 1..64, got {views!r}")
    V, S = int(views), spec.spp
    if S % V:
        raise ConfigError(f"spp: the multiview generator needs spp divisible by views, got spp={S}, views={V}")
    m = S // V
    unit = np.empty((spec.period, spec.period, S, 5))
    for k in range(V):
        sub = _stratified(_Spec(name=spec.name, spp=m, period=spec.period, lens=spec.lens, time=spec.time), rng)
        part = sub.unit
        part[..., 2] = _round_down_f32((k + part[..., 2]) / V)
        unit[..., k * m:(k + 1) * m, :] = part
    return _Draw(unit, params={"views": V, "spp_per_view": m})


# ==================================================================== helpers


def _check_int(field: str, value, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise ConfigError(f"{field}: expected an integer in {lo}..{hi}, got {value!r}")
    return int(value)


def _check_bool(field: str, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ConfigError(f"{field}: expected true or false, got {value!r}")
    return bool(value)


def _readonly(a: np.ndarray | None) -> np.ndarray | None:
    if a is not None:
        a.flags.writeable = False
    return a


def _grid_shape(n: int) -> tuple[int, int]:
    """(nx, ny) with nx·ny = n, nx >= ny, as close to square as possible (8 -> (4, 2))."""
    ny = math.isqrt(n)
    while n % ny:
        ny -= 1
    return n // ny, ny


def _round_down_f32(x: np.ndarray) -> np.ndarray:
    """The largest float32 <= x (as float64), for x in [0, 1): keeps values < 1 and keeps
    floor(x·2^k) for k <= 24."""
    f = np.asarray(x).astype(np.float32)
    f = np.where(f.astype(np.float64) > x, np.nextafter(f, np.float32(-np.inf)), f)
    return f.astype(np.float64)


def _stratum_values(index: np.ndarray, n: int, jitter: np.ndarray) -> np.ndarray:
    """(index + jitter) / n, as float32-representable float64 values with floor(value·n) == index
    exactly (nudged by one float32 ulp where rounding crossed a stratum edge)."""
    index = np.asarray(index)
    value = _round_down_f32((index + jitter) / n)
    for _ in range(8):
        k = np.floor(value * n)
        low, high = k < index, k > index
        if not (low.any() or high.any()):
            return value
        f = value.astype(np.float32)
        f = np.where(low, np.nextafter(f, np.float32(np.inf)), f)
        f = np.where(high, np.nextafter(f, np.float32(-np.inf)), f)
        value = f.astype(np.float64)
    raise AssertionError("stratum rounding did not converge")  # unreachable for n <= 2^20


def _fill_xy_strata(unit: np.ndarray, rng: np.random.Generator, nx: int, ny: int) -> None:
    """Sample s of every pixel takes (x, y) stratum (s mod nx, s div nx), jittered."""
    P, _, S, _ = unit.shape
    s = np.arange(S)
    unit[..., 0] = _stratum_values(np.broadcast_to(s % nx, (P, P, S)), nx, rng.random((P, P, S)))
    unit[..., 1] = _stratum_values(np.broadcast_to(s // nx, (P, P, S)), ny, rng.random((P, P, S)))


def _blocks_to_pixels(block: np.ndarray, B: int, S: int) -> np.ndarray:
    """(Q, Q, B·B·S, C) per-block slots -> (Q·B, Q·B, S, C) per-pixel samples. Block slot
    (dy·B + dx)·S + s is sample s of pixel (bx·B + dx, by·B + dy)."""
    Q, C = block.shape[0], block.shape[-1]
    return block.reshape(Q, Q, B, B, S, C).transpose(0, 2, 1, 3, 4, 5).reshape(Q * B, Q * B, S, C)


_U32 = np.uint32


def _reverse_bits32(x: np.ndarray) -> np.ndarray:
    x = x.astype(_U32)
    x = ((x >> _U32(1)) & _U32(0x55555555)) | ((x & _U32(0x55555555)) << _U32(1))
    x = ((x >> _U32(2)) & _U32(0x33333333)) | ((x & _U32(0x33333333)) << _U32(2))
    x = ((x >> _U32(4)) & _U32(0x0F0F0F0F)) | ((x & _U32(0x0F0F0F0F)) << _U32(4))
    x = ((x >> _U32(8)) & _U32(0x00FF00FF)) | ((x & _U32(0x00FF00FF)) << _U32(8))
    return (x >> _U32(16)) | (x << _U32(16))


def _sobol_02(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The first n points of the 2D Sobol (0,2)-sequence as 32-bit fractions (uint32)."""
    i = np.arange(n, dtype=_U32)
    dim1 = _reverse_bits32(i)  # generator matrix = identity: van der Corput
    # dim 2: primitive polynomial x + 1, all m_j = 1, i.e. direction numbers
    # v_1 = 2^31, v_j = v_{j-1} xor (v_{j-1} >> 1) -- the upper-triangular Pascal matrix mod 2.
    dim2 = np.zeros(n, dtype=_U32)
    v = 1 << 31
    for j in range(max(1, int(n - 1).bit_length())):
        dim2 ^= np.where((i >> _U32(j)) & _U32(1), _U32(v), _U32(0))
        v ^= v >> 1
    return dim1, dim2


def _owen_scramble(x: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """Nested uniform (Owen) scramble of 32-bit fractions by hashing (Burley 2020). In the
    bit-reversed domain each step (adding the seed, x ^= x·even) changes bit k only as a function
    of bits < k, i.e. each digit of the fraction is permuted depending on the digits before it."""
    x = _reverse_bits32(x)
    x = x + seed.astype(_U32)
    for c in (0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6):
        x = x ^ (x * _U32(c))
    return _reverse_bits32(x)


def _u32_to_unit(x: np.ndarray) -> np.ndarray:
    """Top 24 bits of a 32-bit fraction as float64 (exactly float32, < 1, digit-preserving)."""
    return (x >> _U32(8)).astype(np.float64) * 2.0**-24


__all__ = ["SampleTable", "LENS_SHAPES", "LENS_GRID_SIZES"]


@_generator("accumulation", discrete_lens=True, passes=None)
def _accumulation(spec: _Spec, rng: np.random.Generator, passes) -> _Draw:
    """Accumulation buffering ([Toth 2008] §2.2, §8; Haeberli and Akeley 1990): N = spp
    pinhole passes, pass k at lens position k and shutter time k, the SAME for every pixel (no
    per-pixel randomisation, so the passes' ghosts stay visible). The N lens positions are
    jittered strata of a near-square grid of the unit square, the N times jittered strata of
    [0, 1) in a random order, and each pass's (x, y) offset a jittered stratum shared by all
    pixels (the per-pass anti-aliasing jitter). Sample s of every pixel is pass s and uses discrete
    lens coordinate s, so the table is interleaved (n_lens = N): `interleave` or `accumulation`
    render it one pass per lens position. ``SampleTable.accumulation(passes=N, seed=...)``;
    passes defaults to spp and must equal it when both are given."""
    S = spec.spp
    if passes is not None and (isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or passes != S):
        raise ConfigError(f"passes: expected the number of samples per pixel ({S}), got {passes!r}")
    if not spec.lens:
        raise ConfigError("lens: the accumulation generator needs the lens dimension (lens=True), got False")
    P = spec.period
    nx, ny = _grid_shape(S)
    k = np.arange(S)
    lens_unit = np.stack([_stratum_values(k % nx, nx, rng.random(S)), _stratum_values(k // nx, ny, rng.random(S))],
                         axis=1)
    order = rng.permutation(S)
    xy = np.stack([_stratum_values(order % nx, nx, rng.random(S)), _stratum_values(order // nx, ny, rng.random(S))],
                  axis=1)
    t = _stratum_values(rng.permutation(S), S, rng.random(S))
    unit = np.empty((P, P, S, 5))
    unit[..., 0:2] = xy
    unit[..., 2:4] = lens_unit
    unit[..., 4] = t
    lens_index = np.broadcast_to(k.astype(np.int32), (P, P, S)).copy()
    return _Draw(unit, lens_unit=lens_unit, lens_index=lens_index, params={"n_lens": S, "passes": S})


def _accumulation_factory(cls, passes: int | None = None, **params) -> "SampleTable":
    """Accumulation buffering: ``SampleTable.accumulation(passes=N, seed=...)`` is the
    ``accumulation`` generator with spp = N (see its documentation)."""
    if passes is not None and (isinstance(passes, bool) or not isinstance(passes, (int, np.integer))
                               or not 1 <= passes <= MAX_SPP):
        raise ConfigError(f"passes: expected an integer in 1..{MAX_SPP}, got {passes!r}")
    if passes is not None and "spp" not in params:
        params["spp"] = passes
    return cls.create("accumulation", passes=passes, **params)


_accumulation_factory.__name__ = _accumulation_factory.__qualname__ = "accumulation"
SampleTable.accumulation = classmethod(_accumulation_factory)
