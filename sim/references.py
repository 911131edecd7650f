"""The project's bibliography: every paper rast5d implements or measures against, with its short key
([Akenine-Möller 2012]) and full citation. docs/references.md is generated from it
(`python -m experiments.config.docs`); user-facing text cites a paper by its key.

The papers' own files number the five the simulator implements (000 to 004); cite() turns such a
number into the key wherever one reaches a user (sim.counter_docs(), PipelineConfig.field_docs(),
docs/config.md, docs/counters.md); the project's sources cite by key.
"""
from __future__ import annotations

import dataclasses
import re


@dataclasses.dataclass(frozen=True)
class Reference:
    key: str  # the short key, as cited: "Akenine-Möller 2012" ([Akenine-Möller 2012] in text)
    citation: str  # the full citation (Markdown)
    uses: str  # what rast5d takes from it
    number: str = ""  # the engine declarations' number (000 to 004) of the five implemented papers

    @property
    def cite(self) -> str:
        return f"[{self.key}]"

    @property
    def anchor(self) -> str:
        """The heading anchor of the entry in docs/references.md."""
        import unicodedata

        plain = unicodedata.normalize("NFKD", self.key).encode("ascii", "ignore").decode().lower()
        return re.sub(r"[^a-z0-9]+", "-", plain).strip("-")


REFERENCES: tuple[Reference, ...] = (
    Reference("Toth 2008",
              "Robert Toth and Erik Linder. *Stochastic Depth of Field using Hardware Accelerated Rasterization.* "
              "Master's thesis, Lund University, 2008 (examiner Tomas Akenine-Möller; advisors Jacob Munkberg and "
              "Jon Hasselgren).",
              "The disc-of-confusion camera model (§1.3); the bounding geometry for a conventional GPU: 2D and 3D "
              "hexagon, wedge and reduced wedge, parallel-edge and variable-radius triangles (§4, Table 1) and the "
              "adaptive choice (§4.7); the stochastic pixel-shader test (§5) and random perturbation textures "
              "(§5.3); depth culling and depth intervals (§5.4, §9.7); texture-cache effects (§9.3); stratified, "
              "permuted super-sampling (§9.4); quad waste (§9.5); triangle and strip constants (§9.6, Table 2); "
              "accumulation buffering (§2.2, §8). The `gpu_*` algorithms and `accumulation`.", "000"),
    Reference("Akenine-Möller 2012",
              "Tomas Akenine-Möller, Robert Toth, Jacob Munkberg and Jon Hasselgren. *Efficient Depth of Field "
              "Rasterization using a Tile Test based on Half-Space Culling.* Computer Graphics Forum 31(1):3–18, "
              "2012.",
              "The tile test against a defocused triangle: h_i lines (§4.2), H_j lines (§4.3), uv-boxes and the "
              "focus-plane crossing; the lens-grid sample table (§5.1, Fig. 10); BRUTEFORCE, INTERVAL, INTERLEAVE "
              "and HINTERLEAVE (§5.2, §5.3); operation counting (§6.2); the results reproduced in kind: Table 1 "
              "(ratio to the optimum), Table 2 (culling), Fig. 14–17 (operations, spp scaling, STE against "
              "[Laine 2011]), Table 3 (quad shading requests); the selective H_j oracle (Appendix A). The `tile`, "
              "`interval`, `interleave`, `hinterleave` and `bruteforce` algorithms.", "001"),
    Reference("Nilsson 2012",
              "Jim Nilsson, Petrik Clarberg, Björn Johnsson, Jacob Munkberg, Jon Hasselgren, Robert Toth, Marco "
              "Salvi and Tomas Akenine-Möller. *Design and Novel Uses of Higher-Dimensional Rasterization.* "
              "High-Performance Graphics 2012.",
              "The 5D pipeline (§2, Fig. 2): tile tests that output (û, v̂, t̂) intervals, user clip planes, the "
              "programmable sample table, standard and conservative modes, the shading cache and the depth "
              "interval ẑ (Appendix A); the uses: occlusion queries and continuous collision detection (§3), "
              "caustics (§4), sampling (§5), glossy reflections (§6), motion-blurred soft shadows (§7), stereo "
              "and multi-view (§8).", "002"),
    Reference("McGuire 2010",
              "Morgan McGuire, Eric Enderton, Peter Shirley and David Luebke. *Real-Time Stochastic Rasterization "
              "on Conventional GPU Architectures.* High Performance Graphics 2010, 173–182 (the talk's slides).",
              "(2+1)D rasterization through a geometry-shader convex hull (`gpu_convex_hull`), the z = 0 crossing "
              "by clip-and-box, MSAA integration (one shade per pixel), sample-test efficiency, stochastic "
              "transparency and stochastic shadow maps.", "003"),
    Reference("Tzeng 2012",
              "Stanley Tzeng, Anjul Patney, Andrew Davidson, Mohamed S. Ebeida, Scott A. Mitchell and John D. "
              "Owens. *High-Quality Parallel Depth-of-Field Using Line Samples.* High-Performance Graphics 2012, "
              "23–31. doi:10.2312/EGGH/HPG12/023-031.",
              "Line samples in the lens (wagon wheels), analytic coverage from the lens-space edge equations "
              "(Eq. 2), segment buffers with occlusion, merge and length heuristics (§4.1), the bias-correcting "
              "weights κ, blur-based level of detail (§4.2); its Table 1: 16 line samples against 256 point "
              "samples in the same tiled GPU renderer (GTX 580, 800 x 800). The `lines` algorithm.", "004"),
    Reference("Laine 2011",
              "Samuli Laine, Timo Aila, Tero Karras and Jaakko Lehtinen. *Clipless Dual-Space Bounds for Faster "
              "Stochastic Rasterization.* ACM Transactions on Graphics 30(4):106, 2011.",
              "Per-tile lens bounds with every sample checked against them: the `laine` and `laine5d` algorithms "
              "([Akenine-Möller 2012] §6.3, Fig. 17)."),
    Reference("Laine & Karras 2011",
              "Samuli Laine and Tero Karras. *High-Performance Software Rasterization on GPUs.* High Performance "
              "Graphics 2011, 79–88.",
              "cudaraster's sub-pixel precision (4 bits) beside which the fixed-point study is measured, and its "
              "operation counts for comparison (docs/op_costs.md)."),
    Reference("Hakura 1997",
              "Ziyad S. Hakura and Anoop Gupta. *The Design and Analysis of a Cache Architecture for Texture "
              "Mapping.* International Symposium on Computer Architecture 1997, 108–120.",
              "The texture-cache baseline: miss rate against cache size, blocked and linear texel layouts."),
    Reference("Fatahalian 2009",
              "Kayvon Fatahalian, Edward Luong, Solomon Boulos, Kurt Akeley, William R. Mark and Pat Hanrahan. "
              "*Data-Parallel Rasterization of Micropolygons with Defocus and Motion Blur.* High Performance "
              "Graphics 2009, 59–68.",
              "INTERVAL and INTERLEAVE as [Akenine-Möller 2012] describes them, and sample-test efficiency (STE)."),
    Reference("Haeberli 1990",
              "Paul Haeberli and Kurt Akeley. *The Accumulation Buffer: Hardware Support for High-Quality "
              "Rendering.* SIGGRAPH 1990, 309–318.",
              "Accumulation buffering (the `accumulation` algorithm and sample table), as [Toth 2008] compares it."),
    Reference("Andersson 2011",
              "Magnus Andersson, Jon Hasselgren and Tomas Akenine-Möller. *Depth Buffer Compression for Stochastic "
              "Motion Blur Rasterization.* High Performance Graphics 2011, 127–134.",
              "The depth compression of the memory system's `time_predictor` scheme (docs/memory.md): up to two "
              "depth layers by clustering, a time-dependent predictor per layer, delta residuals; its reported "
              "compression to 65 % of the raw size for moderate motion against 75 % for the best earlier scheme for "
              "stochastic buffers, quoted beside rast5d's ratios on the cycles page."),
    Reference("Brunhaver 2010",
              "John S. Brunhaver, Kayvon Fatahalian and Pat Hanrahan. *Hardware Implementation of Micropolygon "
              "Rasterization with Motion and Defocus Blur.* High Performance Graphics 2010, 1–9.",
              "A measured hardware point for the area proxy of the hardware page: a 45 nm micropolygon rasterizer "
              "with motion and defocus blur, 3 G micropolygons per second in 4.1 mm² and 2.9 W."),
    Reference("Mistry 2007",
              "Kaizad Mistry et al. *A 45nm Logic Technology with High-k+Metal Gate Transistors, Strained Silicon, "
              "9 Cu Interconnect Layers, 193nm Dry Patterning, and 100% Pb-free Packaging.* IEEE International "
              "Electron Devices Meeting (IEDM) 2007, 247–250.",
              "The 45 nm six-transistor SRAM cell (0.346 µm²) behind the area proxy's cache weight (docs/hardware.md)."),
    Reference("Horowitz 2014",
              "Mark Horowitz. *Computing's Energy Problem (and what we can do about it).* IEEE International "
              "Solid-State Circuits Conference (ISSCC) 2014, 10–14.",
              "The energy table (sim/energy.py, docs/energy.md): pJ per arithmetic operation, per SRAM access and "
              "per DRAM access at 45 nm, and the 32-bit adder and multiplier areas behind the area proxy (docs/hardware.md)."),
)

BY_NUMBER = {r.number: r for r in REFERENCES if r.number}
# A paper by its number, or by the name of its text file (the number, an underscore, 16 hex digits, .txt)
_NUMBERED = re.compile(r"(?<![\w.,\-])(00[0-4])(?:_[0-9a-f]{16}(?:\.txt)?)?(?![\w.]|-\d)")


def cite(text: str) -> str:
    """text with every paper number (000 to 004, as the engine's declarations write them) replaced by the
    paper's key: '001 §6.2' -> '[Akenine-Möller 2012] §6.2'."""
    return _NUMBERED.sub(lambda m: BY_NUMBER[m.group(1)].cite, text)


def markdown() -> str:
    """docs/references.md."""
    lines = ["# References", "",
             "The papers rast5d implements or measures against. Every page, document and message cites a paper "
             "by the short key in brackets, [Akenine-Möller 2012] §5.1 for a section, and lists its figures beside "
             "ours as published. Generated from `sim/references.py` (`python -m experiments.config.docs`).", ""]
    for r in REFERENCES:
        lines += [f"## [{r.key}]", "", r.citation, "", f"What rast5d takes from it: {r.uses}", ""]
    return "\n".join(lines)


__all__ = ["REFERENCES", "Reference", "cite", "markdown"]
